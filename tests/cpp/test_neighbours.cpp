// Neighbour lists (revcol/engine/neighbours.hpp): built from random centres and renewed
// after moves, they hold exactly the pairs whose centres are within D + shell (nearest
// image across periodic axes), symmetric with mirrored image codes, checked against a
// brute-force count written here; the 1D rods-beside mode lists the two neighbours.
#include "revcol/engine/neighbours.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <type_traits>
#include <vector>

#include "check.hpp"
#include "revcol/engine/limits.hpp"

using namespace revcol::engine;

namespace {

template <int Dim>
Config box_config(Boundary b0, Boundary b1, Boundary b2, double L) {
  Config c;
  c.dim = Dim;
  c.boundary = {b0, b1, b2};
  c.box = {L, L, L};
  return c;
}

// Number of j != i within reach of i by brute force, nearest image on periodic axes.
template <int Dim>
int brute_count(const Config& c, const std::vector<double>& x, int i, double reach) {
  const int n = static_cast<int>(x.size() / Dim);
  int m = 0;
  for (int j = 0; j < n; ++j) {
    if (j == i) continue;
    double d2 = 0.0;
    for (int k = 0; k < Dim; ++k) {
      double d = x[i * Dim + k] - x[j * Dim + k];
      if (c.boundary[k] == Boundary::periodic) d -= c.box[k] * std::round(d / c.box[k]);
      d2 += d * d;
    }
    if (d2 < reach * reach) ++m;
  }
  return m;
}

// L = 12: 7 cells per axis, so a renewal takes each candidate's image code from its cell
// (scan_cells<true>); L = 4.5: 2 cells, the general nearest-image path.
template <int Dim>
void check_gas(Boundary b0, Boundary b1, Boundary b2, std::uint32_t seed, double L = 12.0) {
  const double reach = 1.6;
  const Config c = box_config<Dim>(b0, b1, b2, L);
  const Boundaries<Dim> box(c);
  const int n = L < 6.0 ? (Dim == 3 ? 12 : 6) : (Dim == 3 ? 400 : 150);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, L);
  std::vector<double> x(n * Dim);
  for (double& q : x) q = u(rng);
  NeighbourLists<Dim> nl;
  nl.setup(n, box, reach, false);
  nl.set_centres(x);
  nl.build([](int) { return 0.0; });
  CHECK(nl.valid());
  for (int i = 0; i < n; ++i) CHECK(nl.count(i) == brute_count<Dim>(c, x, i, reach));
  // move a third of the centres a little (some across a periodic edge) and renew them
  std::normal_distribution<double> step(0.0, 0.7);
  for (int i = 0; i < n; i += 3) {
    double* ci = nl.centre(i);
    for (int k = 0; k < Dim; ++k) {
      double q = ci[k] + step(rng);
      if (c.boundary[k] == Boundary::periodic) q -= L * std::floor(q / L);
      else q = std::fmin(std::fmax(q, 0.0), L);
      ci[k] = q;
      x[i * Dim + k] = q;
    }
    nl.renew(i);
  }
  CHECK(nl.valid());
  for (int i = 0; i < n; ++i) CHECK(nl.count(i) == brute_count<Dim>(c, x, i, reach));
  // pair_shift gives the nearest image: |x_a - x_b - s| is the brute-force distance
  for (int a = 0; a < n; a += 7)
    for (int b = a + 1; b < n; b += 11) {
      const auto s = nl.pair_shift(a, b);
      for (int k = 0; k < Dim; ++k) {
        const double d = x[a * Dim + k] - x[b * Dim + k] - s[k];
        if (c.boundary[k] == Boundary::periodic) CHECK(std::fabs(d) <= 0.5 * L + 1e-12);
        else CHECK(s[k] == 0.0);
      }
    }
}

}  // namespace

TEST_CASE("2D: lists equal the brute-force neighbourhoods, periodic, walls and mixed, after renewals") {
  for (std::uint32_t seed = 1; seed <= 3; ++seed) {
    check_gas<2>(Boundary::periodic, Boundary::periodic, Boundary::periodic, seed);
    check_gas<2>(Boundary::wall, Boundary::wall, Boundary::wall, seed);
    check_gas<2>(Boundary::wall, Boundary::periodic, Boundary::wall, seed);
  }
}

TEST_CASE("3D: lists equal the brute-force neighbourhoods, periodic, walls and mixed, after renewals") {
  check_gas<3>(Boundary::periodic, Boundary::periodic, Boundary::periodic, 4);
  check_gas<3>(Boundary::wall, Boundary::wall, Boundary::wall, 5);
  check_gas<3>(Boundary::periodic, Boundary::wall, Boundary::periodic, 6);
}

TEST_CASE("a periodic axis of 2 cells: renewals find the nearest image without the cells' codes") {
  for (std::uint32_t seed = 7; seed <= 9; ++seed) {
    check_gas<2>(Boundary::periodic, Boundary::periodic, Boundary::periodic, seed, 4.5);
    check_gas<2>(Boundary::periodic, Boundary::wall, Boundary::periodic, seed, 4.5);
    check_gas<3>(Boundary::periodic, Boundary::periodic, Boundary::periodic, seed, 4.5);
  }
}

// A renewal skips the cells out of reach of the centre (scan_cells), from the gaps between
// the centre and the cell faces. The tightest case: j just across a cell corner, edge or face
// from i (one ulp past the grid point q, on the far side from i) and i at reach (1 - 1e-9)
// from q. j's cell then comes within 1.6e-9 of being out of reach, so a cull that
// overestimated a gap by 1e-6 would drop the pair (checked by hand: this test then fails).
TEST_CASE("3D: renewals skip no cell that holds a centre within reach (pairs across cell corners, edges, faces)") {
  const double L = 12.0, reach = 1.6, cw = L / 7.0;  // 7 cells per axis
  for (Boundary b : {Boundary::periodic, Boundary::wall}) {
    const Config c = box_config<3>(b, b, b, L);
    const Boundaries<3> box(c);
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int trial = 0; trial < 300; ++trial) {
      const int axes = 1 + trial % 3;  // q on a face (1 axis on the grid), an edge (2), a corner (3)
      double q[3], dir[3], sgn[3], dn = 0.0;
      for (int k = 0; k < 3; ++k) {
        const bool on_grid = k < axes;
        q[k] = on_grid ? (1 + std::floor(u(rng) * 6)) * cw : cw + u(rng) * 5 * cw;
        dir[k] = on_grid ? 0.2 + u(rng) : 0.0;
        sgn[k] = u(rng) < 0.5 ? -1.0 : 1.0;
        dn += dir[k] * dir[k];
      }
      dn = std::sqrt(dn);
      const double r = reach * (1.0 - 1e-9);
      std::vector<double> x(6);
      for (int k = 0; k < 3; ++k) {
        x[k] = q[k] - sgn[k] * r * dir[k] / dn;  // i
        x[3 + k] = k < axes ? std::nextafter(q[k], q[k] + sgn[k]) : q[k];  // j, across q from i
      }
      NeighbourLists<3> nl;
      nl.setup(2, box, reach, false);
      nl.set_centres(x);
      nl.build([](int) { return 0.0; });
      CHECK(nl.count(0) == 1);
      nl.renew(0);  // the renewal's (coded) scan, from each side
      nl.renew(1);
      CHECK(nl.valid());
      CHECK(nl.count(0) == 1);
      CHECK(nl.count(1) == 1);
    }
  }
}

// Centres crowd into two cells (dozens to a cell, and long lists) and go back where
// they were, by renewals: the lists stay exact and the store does not grow from one cycle to
// the next. (Written for the cell blocks tried in session 22, which chained blocks in a
// crowded cell and reused the freed ones; it holds for any cell store.)
template <int Dim>
void check_crowding(Boundary b, std::uint32_t seed) {
  const double L = 12.0, reach = 1.6, cw = L / 7.0;  // 7 cells per axis
  const Config c = box_config<Dim>(b, b, b, L);
  const Boundaries<Dim> box(c);
  const int n = Dim == 3 ? 300 : 120;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> x(n * Dim);
  for (double& q : x) q = u(rng) * L;
  NeighbourLists<Dim> nl;
  nl.setup(n, box, reach, false);
  nl.set_centres(x);
  nl.build([](int) { return 0.0; });
  CHECK(nl.valid());
  // each centre's place in the crowd: in cell 3 (4 on the last axis for odd i)
  const std::vector<double> x0 = x;
  std::vector<double> xc(n * Dim);
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < Dim; ++k) xc[i * Dim + k] = (k == Dim - 1 && i % 2 ? 4.0 : 3.0) * cw + u(rng) * cw * 0.999;
  const auto move = [&](int i, bool crowd) {
    double* ci = nl.centre(i);
    for (int k = 0; k < Dim; ++k) {
      const double q = crowd ? xc[i * Dim + k] : x0[i * Dim + k];
      ci[k] = q;
      x[i * Dim + k] = q;
    }
    nl.renew(i);
  };
  // a third of the centres crowds into two cells and goes back where it was, in one order
  // each cycle: every cycle passes through the same states, so it needs no more store than
  // the first
  std::vector<int> crowd(n);
  for (int i = 0; i < n; ++i) crowd[i] = i;
  std::shuffle(crowd.begin(), crowd.end(), rng);
  crowd.resize(n / 3);
  std::size_t bytes_after_first = 0;
  for (int cycle = 0; cycle < 4; ++cycle) {
    for (int i : crowd) move(i, true);
    CHECK(nl.valid());
    for (int i = 0; i < n; ++i) CHECK(nl.count(i) == brute_count<Dim>(c, x, i, reach));
    for (int i : crowd) move(i, false);
    CHECK(nl.valid());
    for (int i = 0; i < n; ++i) CHECK(nl.count(i) == brute_count<Dim>(c, x, i, reach));
    if (cycle == 0) bytes_after_first = nl.memory_bytes();
    else CHECK(nl.memory_bytes() == bytes_after_first);
  }
}

TEST_CASE("crowded cells: lists stay exact as dozens of centres crowd into two cells and leave (2D and 3D)") {
  check_crowding<2>(Boundary::periodic, 21);
  check_crowding<2>(Boundary::wall, 22);
  check_crowding<3>(Boundary::periodic, 23);
  check_crowding<3>(Boundary::wall, 24);
}

TEST_CASE("image codes mirror: near(i, j) and near(j, i) agree, codes 1 <-> 2") {
  const Config c = box_config<2>(Boundary::periodic, Boundary::periodic, Boundary::periodic, 10.0);
  NeighbourLists<2> nl;
  nl.setup(2, Boundaries<2>(c), 1.5, false);
  nl.set_centres({0.2, 5.0, 9.9, 5.3});  // across the x edge
  nl.build([](int) { return 0.0; });
  unsigned cij, cji;
  CHECK(nl.near(0, 1, cij));
  CHECK(nl.near(1, 0, cji));
  CHECK(cij == 2u);  // x_1 - L is 1's image next to 0
  CHECK(cji == NeighbourLists<2>::mirror(cij));
  CHECK(nl.shift_of(cij)[0] == -10.0);
  CHECK(nl.count(0) == 1 && nl.count(1) == 1);
}

TEST_CASE("1D rods beside each other: walls (ends listed once) and a ring (wrap codes)") {
  for (Boundary b : {Boundary::wall, Boundary::periodic}) {
    const Config c = box_config<1>(b, b, b, 20.0);
    const std::vector<double> x = {7.0, 1.0, 15.0, 11.0};  // order 1, 0, 3, 2
    NeighbourLists<1> nl;
    nl.setup(4, Boundaries<1>(c), 2.0, true);
    CHECK(nl.adjacent());
    nl.set_centres(x);
    nl.build([&](int j) { return x[j]; });
    CHECK(nl.valid());
    const bool ring = b == Boundary::periodic;
    CHECK(nl.count(1) == (ring ? 2 : 1));
    CHECK(nl.count(0) == 2);
    CHECK(nl.count(2) == (ring ? 2 : 1));
    if (ring) CHECK(nl.pair_shift(1, 2)[0] == -20.0);  // 2 sits left of 1 across the end: x_2 - L
  }
}

CHECK_MAIN()

// Issue 59: a sparse box's grid is capped at limits::max_list_cells(n) cells (wider cells), and
// below the cap it is floor(L / reach) per axis as before. The lists stay exact: centres in a
// cluster that straddles the periodic corner of a box of 10^5 (2D) and 10^4 (3D) reaches.
TEST_CASE("sparse boxes: the grid is capped, unchanged below the cap, and the lists stay exact") {
  int nc[3];
  const double below[2] = {800.0, 800.0};  // 500^2 = 250 000 cells <= 2^18: unchanged
  limits::capped_cell_counts(2, below, 1.6, limits::max_list_cells(10), nc);
  CHECK(nc[0] == 500 && nc[1] == 500);
  const double thin[3] = {1e9, 5.0, 3.0};  // the short axes keep their 3 and 1 cells
  limits::capped_cell_counts(3, thin, 1.6, limits::max_list_cells(10), nc);
  CHECK(nc[1] == 3 && nc[2] == 1 && nc[0] >= 1 && 3.0 * nc[0] <= limits::max_list_cells(10));
  CHECK(thin[0] / nc[0] >= 1.6);
  auto sparse = [&](auto dim_tag, double L, Boundary b) {
    constexpr int Dim = decltype(dim_tag)::value;
    const double reach = 1.6;
    const Config c = box_config<Dim>(b, b, b, L);
    const Boundaries<Dim> box(c);
    const int n = Dim == 3 ? 300 : 120;
    std::mt19937_64 rng(13);
    std::uniform_real_distribution<double> u(-4.0, 4.0);
    std::vector<double> x(n * Dim);
    for (double& q : x) {
      q = u(rng);
      if (b == Boundary::periodic) q -= L * std::floor(q / L);  // around the corner 0 = L
      else q = std::fabs(q);
    }
    NeighbourLists<Dim> nl;
    nl.setup(n, box, reach, false);
    CHECK(static_cast<double>(nl.cell_count()) <= limits::max_list_cells(n));
    nl.set_centres(x);
    nl.build([](int) { return 0.0; });
    CHECK(nl.valid());
    int pairs = 0;
    for (int i = 0; i < n; ++i) {
      CHECK(nl.count(i) == brute_count<Dim>(c, x, i, reach));
      pairs += nl.count(i);
    }
    CHECK(pairs > n);  // a crowded cluster: the check has pairs to find
  };
  for (Boundary b : {Boundary::periodic, Boundary::wall}) {
    sparse(std::integral_constant<int, 2>{}, 1.6e5, b);
    sparse(std::integral_constant<int, 3>{}, 1.6e4, b);
  }
}
