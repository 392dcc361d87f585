// Tests of the lattice engine's neighbour lists (lattice/neighbour_lists.hpp) and of the engine's
// neighbour search: the lists against brute force after random renewals (complete, symmetric,
// their image codes exact and mirrored), the ball's renewal tick against brute force (never late, rarely
// early), and the engine with lists (several shells, both prediction paths) against the cell
// grid with every candidate sent to the exact search: the same collisions (trace), the same
// state bit for bit, in 2D and 3D, periodic, walled, dense with redraws and with groups forced,
// and in a field (whose renewals leave a cube inside the ball at an exact tick, also brute-forced).
#include <cmath>
#include <cstdio>
#include <random>
#include <set>
#include <string>

#include "check.hpp"
#include "revcol/lattice/engine.hpp"

using namespace revcol::lattice;

namespace {

// |a - b|^2 exactly (minimum image on periodic axes), as a long double for the band test
template <std::size_t D>
long double dist2(const UnitsN<D>& u, const VecN<D>& a, const VecN<D>& b) {
  long double s = 0.0L;
  for (std::size_t k = 0; k < D; ++k) {
    const std::int64_t d = u.wall[k] ? a[k] - b[k] : min_image(a[k] - b[k], u.L[k]);
    s += static_cast<long double>(d) * static_cast<long double>(d);
  }
  return s;
}

template <std::size_t D>
UnitsN<D> box_units(std::array<bool, D> wall, double length_sigma, int S) {
  UnitsN<D> u;
  u.S = S;
  u.sigma = std::int64_t{1} << S;
  u.vmax = std::int64_t{1} << (S - 8);
  for (std::size_t k = 0; k < D; ++k) {
    u.L[k] = static_cast<std::int64_t>(length_sigma * static_cast<double>(u.sigma));
    u.wall[k] = wall[k];
  }
  return u;
}

// every list against brute force: complete outside a rounding band about R, symmetric, the
// codes the exact images of the centres' minimum-image differences, mirrored on the other list
template <std::size_t D>
void check_lists(const UnitsN<D>& u, const NeighbourListsN<D>& nl, const std::vector<VecN<D>>& c, const char* what) {
  const long double R2 = static_cast<long double>(nl.reach()) * static_cast<long double>(nl.reach());
  int bad = 0;
  for (std::size_t p = 0; p < c.size(); ++p) {
    std::set<int> listed;
    const int* ids = nl.ids(static_cast<int>(p));
    const std::uint8_t* codes = nl.codes(static_cast<int>(p));
    for (int e = 0; e < nl.size(static_cast<int>(p)); ++e) {
      const int q = ids[e];
      if (!listed.insert(q).second || q == static_cast<int>(p)) ++bad;  // no duplicates, not itself
      // the code's shift s: c_p - c_q - s is the exact minimum image (the raw difference on walls)
      for (std::size_t k = 0; k < D; ++k) {
        const std::int64_t raw = c[p][k] - c[q][k];
        const std::int64_t d = u.wall[k] ? raw : min_image(raw, u.L[k]);
        const unsigned ck = (codes[e] >> (2 * k)) & 3u;
        const std::int64_t s = ck == 1 ? u.L[k] : ck == 2 ? -u.L[k] : 0;
        if (ck == 3 || raw - s != d) ++bad;
      }
      // symmetric: p on q's list, with the mirrored code
      int back = 0;
      const int* qids = nl.ids(q);
      for (int f = 0; f < nl.size(q); ++f)
        if (qids[f] == static_cast<int>(p)) {
          ++back;
          if (nl.codes(q)[f] != NeighbourListsN<D>::mirror(codes[e])) ++bad;
        }
      if (back != 1) ++bad;
    }
    for (std::size_t q = 0; q < c.size(); ++q) {
      if (q == p) continue;
      const long double d2 = dist2(u, c[p], c[q]);
      const bool in = listed.count(static_cast<int>(q)) > 0;
      if (d2 < R2 * (1.0L - 1e-12L) && !in) ++bad;   // missing
      if (d2 > R2 * (1.0L + 1e-12L) && in) ++bad;    // listed too far
    }
  }
  if (bad != 0) std::fprintf(stderr, "%s: %d list defects\n", what, bad);
  CHECK(bad == 0);
}

// the coded scan's lists are the minimum-image scan's: the same entries with the same codes
template <std::size_t D>
void same_lists(const NeighbourListsN<D>& a, const NeighbourListsN<D>& b, std::size_t n, const char* what) {
  int bad = 0;
  for (std::size_t p = 0; p < n; ++p) {
    std::set<std::pair<int, int>> ea, eb;
    for (int e = 0; e < a.size(static_cast<int>(p)); ++e) ea.insert({a.ids(static_cast<int>(p))[e], a.codes(static_cast<int>(p))[e]});
    for (int e = 0; e < b.size(static_cast<int>(p)); ++e) eb.insert({b.ids(static_cast<int>(p))[e], b.codes(static_cast<int>(p))[e]});
    bad += ea != eb ? 1 : 0;
  }
  if (bad != 0) std::fprintf(stderr, "%s: %d lists differ between the two scans\n", what, bad);
  CHECK(bad == 0);
}

template <std::size_t D>
void lists_case(std::array<bool, D> wall, double length, std::size_t n, double shell, std::uint64_t seed, bool coded,
                const char* what, int S = 50) {
  const UnitsN<D> u = box_units<D>(wall, length, S);
  std::mt19937_64 rng(seed);
  std::vector<VecN<D>> c(n);
  for (auto& x : c)
    for (std::size_t k = 0; k < D; ++k)
      x[k] = u.wall[k] ? u.sigma / 2 + static_cast<std::int64_t>(rng() % static_cast<std::uint64_t>(u.L[k] - u.sigma))
                       : static_cast<std::int64_t>(rng() % static_cast<std::uint64_t>(u.L[k]));
  NeighbourListsN<D> nl, plain;  // plain: the minimum-image scan of every candidate
  const std::int64_t h = static_cast<std::int64_t>(shell * 0.5 * static_cast<double>(u.sigma));
  nl.build(u, h, c);
  plain.use_minimum_image_scan();
  plain.build(u, h, c);
  CHECK(nl.reach() == u.sigma + 2 * h + 8 * u.vmax + 8);
  CHECK(nl.coded() == coded && !plain.coded());
  check_lists(u, nl, c, what);
  same_lists(nl, plain, c.size(), what);
  // random renewals: a centre moves by up to a diameter (wrapped, inside the walls)
  std::uniform_real_distribution<double> step(-1.0, 1.0);
  for (int round = 0; round < 3; ++round) {
    for (std::size_t m = 0; m < n; ++m) {
      const int p = static_cast<int>(rng() % n);
      for (std::size_t k = 0; k < D; ++k) {
        // in 128 bits: a centre near L plus a diameter can pass 2^63 in the largest box
        const i128 y = static_cast<i128>(c[p][k]) + static_cast<std::int64_t>(step(rng) * static_cast<double>(u.sigma));
        if (u.wall[k]) c[p][k] = static_cast<std::int64_t>(std::clamp<i128>(y, u.sigma / 2, u.L[k] - u.sigma / 2));
        else c[p][k] = wrap(y, u.L[k]);
      }
      nl.renew(p, c[p]);
      plain.renew(p, c[p]);
    }
    check_lists(u, nl, c, what);
    same_lists(nl, plain, c.size(), what);
  }
}

}  // namespace

// for_neighbours_within against for_neighbours: every member closer than r (in double, from the
// exact nearest-image differences) is visited, in the same order, and the skipped cells held
// nothing closer than r; periodic, walled and mixed boxes, small ones where every cell is a neighbour
template <std::size_t D>
void check_within(std::array<bool, D> wall, double length_sigma, int n, std::uint64_t seed) {
  const UnitsN<D> u = box_units<D>(wall, length_sigma, 40);
  const std::int64_t reach = u.sigma + 2 * (u.sigma / 3) + 8 * u.vmax + 8;
  CellGridN<D> g;
  g.build(u, static_cast<std::size_t>(n), (reach + 1) / 2, 2);
  std::mt19937_64 rng(seed);
  std::vector<VecN<D>> x(static_cast<std::size_t>(n));
  for (int p = 0; p < n; ++p) {
    for (std::size_t k = 0; k < D; ++k) x[p][k] = static_cast<std::int64_t>(rng() % static_cast<std::uint64_t>(u.L[k]));
    g.insert(p, g.cell_id(x[p]));
  }
  const double r = static_cast<double>(reach), r2 = r * r;
  int bad = 0, seen = 0, fewer = 0;
  for (int p = 0; p < n; ++p) {
    auto close = [&](int q) {
      double dd = 0.0;
      for (std::size_t k = 0; k < D; ++k) {
        const double d = static_cast<double>(u.wall[k] ? x[p][k] - x[q][k] : min_image(x[p][k] - x[q][k], u.L[k]));
        dd += d * d;
      }
      return dd < r2;
    };
    std::vector<int> all, within, all_close;
    g.for_neighbours(g.cell_of_particle(p), [&](int q) { all.push_back(q); });
    g.for_neighbours_within(g.cell_of_particle(p), x[p], r, [&](int q) { within.push_back(q); });
    for (int q : all)
      if (close(q)) all_close.push_back(q);
    std::vector<int> within_close;
    for (int q : within)
      if (close(q)) within_close.push_back(q);
    if (within_close != all_close) ++bad;
    // and nothing closer than r outside the neighbour cells either (brute force)
    int brute = 0;
    for (int q = 0; q < n; ++q) brute += close(q) ? 1 : 0;
    if (brute != static_cast<int>(all_close.size())) ++bad;
    seen += static_cast<int>(all_close.size());
    fewer += within.size() < all.size() ? 1 : 0;
  }
  CHECK(bad == 0);
  CHECK(seen > n);  // the test saw neighbours
  if (length_sigma > 12.0) CHECK(fewer > n / 2);  // and skipped cells (in boxes of more than 5 cells a side)
}

TEST_CASE("cell grid: for_neighbours_within visits what for_neighbours keeps within r, in order, and skips cells") {
  check_within<3>({false, false, false}, 20.0, 3000, 1);
  check_within<3>({true, true, true}, 20.0, 3000, 2);
  check_within<3>({true, false, true}, 16.0, 2000, 3);
  check_within<3>({false, false, false}, 6.0, 300, 4);  // every cell a neighbour
  check_within<2>({false, false}, 40.0, 3000, 5);
  check_within<2>({true, false}, 30.0, 2000, 6);
}

TEST_CASE("min_image: (d mod L) folded at (L + 1) / 2, every d in (-L, L) of small L, the edges of large L") {
  auto reference = [](std::int64_t d, std::int64_t L) {
    i128 r = static_cast<i128>(d) % L;
    if (r < 0) r += L;
    return static_cast<std::int64_t>(r >= (L + 1) / 2 ? r - L : r);
  };
  int bad = 0;
  for (std::int64_t L = 1; L <= 40; ++L)
    for (std::int64_t d = -L + 1; d < L; ++d) bad += min_image(d, L) != reference(d, L);
  for (std::int64_t L : {(std::int64_t{1} << 62) - 1, std::int64_t{1} << 62, max_box - 1, max_box})
    for (std::int64_t d : {-L + 1, -L / 2 - 1, -L / 2, -L / 2 + 1, std::int64_t{-1}, std::int64_t{0}, std::int64_t{1}, L / 2 - 1, L / 2,
                           L / 2 + 1, (L + 1) / 2, L - 1})
      bad += min_image(d, L) != reference(d, L);
  CHECK(bad == 0);
}

TEST_CASE("neighbour lists: complete, symmetric and with exact image codes, built and after random renewals") {
  lists_case<3>({false, false, false}, 9.0, 400, 0.3, 1, true, "3D periodic, shell 0.3");
  lists_case<3>({true, true, true}, 8.0, 300, 0.8, 2, true, "3D walls, shell 0.8");
  lists_case<3>({false, true, false}, 3.0, 40, 2.0, 3, false, "3D small periodic box, shell 2 (every cell a neighbour)");
  lists_case<3>({false, false, true}, 7.0, 300, 0.2, 6, true, "3D, 5 cells on the periodic axes, shell 0.2");
  lists_case<3>({false, false, false}, 16.0, 1500, 1.0, 7, true, "3D periodic, shell 1");
  lists_case<2>({false, false}, 20.0, 400, 0.5, 4, true, "2D periodic, shell 0.5");
  lists_case<2>({true, false}, 15.0, 300, 0.1, 5, true, "2D slab, shell 0.1");
  lists_case<2>({false, false}, 4.5, 12, 0.4, 8, false, "2D small periodic box (every cell a neighbour)");
  // a box near the coordinates' limit (L = 15.5 x 2^59 ~ 0.97 x 2^63, 5 cells a side): a centre
  // of the first cell plus L would pass 2^63
  lists_case<3>({false, false, false}, 15.5, 200, 2.0, 9, true, "3D periodic, L ~ 0.97 x 2^63", 59);
}

TEST_CASE("neighbour lists: the renewal tick is never late and rarely early (brute force over the ticks)") {
  const UnitsN<3> u = box_units<3>({false, false, false}, 10.0, 50);
  std::mt19937_64 rng(11);
  const std::int64_t h = u.sigma / 8;
  std::vector<VecN<3>> c(1, VecN<3>{u.L[0] / 2, u.L[1] / 2, u.L[2] / 2});
  NeighbourListsN<3> nl;
  nl.build(u, h, c);
  auto inside_at = [&](const VecN<3>& x, const VecN<3>& v, std::int64_t t) {
    VecN<3> y;
    for (int k = 0; k < 3; ++k) y[k] = x[k] + v[k] * t;
    return nl.inside(0, y);
  };
  int late = 0, early = 0, cases = 0;
  std::uniform_int_distribution<std::int64_t> off(-h / 2, h / 2);
  for (int m = 0; m < 2000; ++m) {
    // speeds of 1..2^k units per tick: exits after ~10^2..10^5 ticks, brute-forced
    const int bits = 1 + static_cast<int>(rng() % 10);
    VecN<3> x{}, v{};
    for (int k = 0; k < 3; ++k) {
      x[k] = c[0][k] + off(rng);
      v[k] = static_cast<std::int64_t>(rng() % (std::uint64_t{1} << bits)) - (std::int64_t{1} << (bits - 1));
    }
    if (!nl.inside(0, x)) continue;
    // scale v so that the exit is within 10^5 ticks
    std::int64_t vm = std::max({std::abs(v[0]), std::abs(v[1]), std::abs(v[2])});
    if (vm == 0) {
      CHECK(nl.exit_ticks(0, x, v) == -1);
      continue;
    }
    const std::int64_t scale = std::max<std::int64_t>(1, h / (vm * 20000));
    for (int k = 0; k < 3; ++k) v[k] *= scale;
    const std::int64_t tau = nl.exit_ticks(0, x, v);
    std::int64_t first_out = 0;
    while (inside_at(x, v, first_out)) ++first_out;
    ++cases;
    if (tau < 1 || tau > first_out) ++late;           // inside on [0, tau - 1] is required
    if (tau < first_out - 2 - first_out / 1000000) ++early;  // the double root is good to ~1e-9
  }
  std::printf("  %d lines: %d late, %d early by more than 2 ticks\n", cases, late, early);
  CHECK(cases > 1000);
  CHECK(late == 0);
  CHECK(early == 0);
}

TEST_CASE("neighbour lists in a field: the cube's renewal tick is the exact first tick out (brute force over the ticks)") {
  for (const int axis : {2, 0}) {
    UnitsN<3> u = box_units<3>({true, true, true}, 10.0, 50);
    NeighbourListsN<3> nl;
    const std::int64_t h = u.sigma / 8, half_g = -(std::int64_t{1} << 20);  // a field along `axis`
    nl.set_field(axis, half_g);
    std::vector<VecN<3>> c(1, VecN<3>{u.L[0] / 2, u.L[1] / 2, u.L[2] / 2});
    nl.build(u, h, c);
    // the cube's half-width w: the largest with 3 w^2 <= h^2 (inside the ball), read off inside()
    std::int64_t w = 0;
    for (std::int64_t step = h; step > 0; step /= 2)
      while (nl.inside(0, VecN<3>{c[0][0] + w + step, c[0][1], c[0][2]})) w += step;
    CHECK(static_cast<long double>(3) * w * w <= static_cast<long double>(h) * h);
    CHECK(static_cast<long double>(3) * (w + 1) * (w + 1) > static_cast<long double>(h) * h);
    CHECK(nl.inside(0, VecN<3>{c[0][0] + w, c[0][1] - w, c[0][2] + w}));    // a corner of the cube: in
    CHECK(!nl.inside(0, VecN<3>{c[0][0], c[0][1] - w - 1, c[0][2]}));       // past a face: out
    std::mt19937_64 rng(13);
    std::uniform_int_distribution<std::int64_t> off(-w, w);
    int cases = 0, wrong = 0;
    for (int m = 0; m < 1500; ++m) {
      const int bits = 1 + static_cast<int>(rng() % 22);  // speeds of 1 .. 2^21 units per tick
      VecN<3> x{}, v{};
      for (int k = 0; k < 3; ++k) {
        x[k] = c[0][k] + off(rng);
        v[k] = static_cast<std::int64_t>(rng() % (std::uint64_t{1} << bits)) - (std::int64_t{1} << (bits - 1));
      }
      if (m % 5 == 0) v = {0, 0, 0};  // still: the field alone moves it out
      auto at = [&](std::int64_t t) {
        VecN<3> y;
        for (int k = 0; k < 3; ++k) y[k] = x[k] + v[k] * t + (k == axis ? half_g * t * t : 0);
        return y;
      };
      const std::int64_t tau = nl.exit_ticks(0, x, v);
      std::int64_t first_out = 1;
      while (nl.inside(0, at(first_out))) ++first_out;
      ++cases;
      if (tau != first_out) ++wrong;
    }
    std::printf("  field along axis %d: %d lines, %d renewal ticks not the first tick out\n", axis, cases, wrong);
    CHECK(cases == 1500);
    CHECK(wrong == 0);
  }
}

namespace {

template <std::size_t D>
struct Gas {
  const char* what;
  std::size_t n;
  double phi;
  std::array<bool, D> wall;
  int tick_bits;
  std::uint64_t collisions;
  bool groups;  // every collision a group collision (max_redraws = -1)
  int shifted = -1;  // 1 / 0: the cell grid knows / does not know each neighbouring cell's image (-1: either)
  double gravity = 0.0;  // a field along the last axis (walled), in kT / sigma; 0: none
};

// the reference: the cell grid, every candidate to the exact search
template <std::size_t D, class Engine>
void run_equivalence(const Gas<D>& g) {
  LatticeConfigN<D> cfg;
  cfg.wall = g.wall;
  cfg.seed = 7;
  if (g.tick_bits != 0) cfg.tick_bits = g.tick_bits;
  cfg.gravity[D - 1] = g.gravity;
  const LatticeStartN<D> st = random_start(cfg, g.n, g.phi, 7);
  CHECK((st.units.gravity[D - 1] != 0) == (g.gravity != 0.0));
  if (g.shifted >= 0) {  // the engine's cell grid (shell 0): the image-known filter, or the per-pair image
    CellGridN<D> grid;
    grid.build(st.units, g.n);
    CHECK(grid.shifted() == (g.shifted == 1));
  }
  auto make = [&](double shell, bool exhaustive) {
    Engine e(st.units, st.x, st.v, 7, operator_for(st.units));
    e.set_list_shell(shell);
    e.exhaustive_search = exhaustive;
    if (g.groups) e.max_redraws = -1;
    return e;
  };
  std::vector<std::array<std::int64_t, 3>> ref_trace;
  Engine ref = make(0.0, true);
  ref.trace = &ref_trace;
  const SnapshotN<D> s0 = ref.snapshot();
  CHECK(ref.neighbour_search() == 0);
  ref.run(g.collisions, tick_limit - 1);
  const SnapshotN<D> s1 = ref.snapshot();
  std::set<int> paths;
  for (double shell : {0.0, 0.02, 0.3, -1.0, 2.0}) {
    Engine e = make(shell, false);
    std::vector<std::array<std::int64_t, 3>> trace;
    e.trace = &trace;
    paths.insert(e.neighbour_search());
    e.run(g.collisions / 3, tick_limit - 1);  // a stop and a restart on the way
    e.run(g.collisions - g.collisions / 3, tick_limit - 1);
    const bool same = trace == ref_trace && same_state(e.snapshot(), s1);
    if (!same) std::fprintf(stderr, "%s, shell %.2f (search %d): differs from the exhaustive cell search\n", g.what, shell, e.neighbour_search());
    CHECK(same);
    e.run_back(0, e.origin());
    CHECK(same_state(e.snapshot(), s0));
    if (shell == 0.3 || shell == 2.0) {
      std::printf("  %s, shell %.2f: search %d, %llu neutral events for %llu collisions (both ways)\n", g.what, shell,
                  e.neighbour_search(), static_cast<unsigned long long>(e.counters().crossings),
                  static_cast<unsigned long long>(e.counters().collisions));
    }
  }
  CHECK(paths.count(1) + paths.count(2) >= 1);
}

}  // namespace

TEST_CASE("3D engine: lists (shells 0.02 .. 2, both paths) find exactly the exhaustive cell search's collisions, bit for bit") {
  const std::array<bool, 3> per{false, false, false}, walls{true, true, true}, slab{false, false, true};
  for (const Gas<3>& g : {Gas<3>{"N=1000 phi=0.3 periodic", 1000, 0.3, per, 0, 20000, false},
                          Gas<3>{"N=64 phi=0.1 periodic (short box)", 64, 0.1, per, 0, 5000, false, 1},
                          Gas<3>{"N=80 phi=0.4 periodic (every cell a neighbour)", 80, 0.4, per, 0, 3000, false, 0},
                          Gas<3>{"N=500 phi=0.45 walls", 500, 0.45, walls, 0, 15000, false},
                          Gas<3>{"N=500 phi=0.45 slab, T=16 (redraws)", 500, 0.45, slab, 16, 15000, false},
                          Gas<3>{"N=200 phi=0.3 walls, groups forced", 200, 0.3, walls, 0, 2000, true}})
    run_equivalence<3, LatticeEngine3D>(g);
}

TEST_CASE("3D and 2D engines in a field: lists (the cube's renewals) find exactly the exhaustive cell search's collisions, bit for bit") {
  const std::array<bool, 3> walls{true, true, true}, slab{false, false, true};
  for (const Gas<3>& g : {Gas<3>{"3D N=1000 phi=0.3 walls, g=-1", 1000, 0.3, walls, 0, 20000, false, -1, -1.0},
                          Gas<3>{"3D N=500 phi=0.45 slab, g=-3, T=16 (redraws)", 500, 0.45, slab, 16, 15000, false, -1, -3.0},
                          Gas<3>{"3D N=80 phi=0.4 slab, g=-2 (every cell a neighbour)", 80, 0.4, slab, 0, 3000, false, 0, -2.0},
                          Gas<3>{"3D N=200 phi=0.3 walls, g=+1, groups forced", 200, 0.3, walls, 0, 2000, true, -1, 1.0},
                          Gas<3>{"3D N=400 phi=0.2 slab, g=-20, T=16 (coarse ticks: redraws)", 400, 0.2, slab, 16, 15000, false, -1, -20.0}})
    run_equivalence<3, LatticeEngine3D>(g);
  const std::array<bool, 2> channel{false, true};
  run_equivalence<2, LatticeEngine>(Gas<2>{"2D N=600 phi=0.5 channel, g=-2", 600, 0.5, channel, 0, 10000, false, 1, -2.0});
}

TEST_CASE("2D engine: lists find exactly the exhaustive cell search's collisions, bit for bit") {
  const std::array<bool, 2> per{false, false}, walls{true, true};
  const std::array<bool, 2> channel{false, true};
  for (const Gas<2>& g : {Gas<2>{"2D N=1000 phi=0.5 periodic", 1000, 0.5, per, 0, 20000, false, 1},
                          Gas<2>{"2D N=400 phi=0.3 walls, T=16", 400, 0.3, walls, 16, 10000, false, 1},
                          Gas<2>{"2D N=300 phi=0.6 channel", 300, 0.6, channel, 0, 10000, false, 1},
                          Gas<2>{"2D N=14 phi=0.5 periodic (every cell a neighbour)", 14, 0.5, per, 0, 3000, false, 0}})
    run_equivalence<2, LatticeEngine>(g);
}

TEST_CASE("a same-tick tie of two partners with one lower index goes to the smaller partner, whatever order the predictions came in") {
  // 2D, walls, sigma 2^44. Particle 0 rests at the centre; 2 comes at it from x = H along
  // y = c + 0.7 sigma; 1 starts a little inside x = H moving out along y = c - 0.35 sigma,
  // reflects, and comes back behind 2, by so much that both pairs first overlap at one tick
  // (found below): the same lower index 0, so the same (tick, kind). 0 is far from both at
  // first; 2, ahead, finds it first (a cell crossing or list renewal brings 0 into its search)
  // and writes 0's slot; 1 finds the tie later. A slot write compared on (tick, kind) alone
  // kept 2 (the first writer); a particle's own prediction orders (tick, kind, other) and would
  // choose 1, and so must the write, or the search's re-predictions (which differ between the
  // cell grid and the lists) would decide the trajectory.
  const UnitsN<2> u = box_units<2>({true, true}, 20.0, 44);
  const std::int64_t sg = u.sigma, H = u.L[0] - sg / 2, c = 10 * sg, speed = u.vmax / 2;
  const std::int64_t d2 = sg / 10 * 7, d1 = sg / 100 * 35;
  const u128 s2 = static_cast<u128>(sg) * static_cast<u128>(sg);
  const std::int64_t t2 = first_overlap(VecN<2>{H - c, d2}, VecN<2>{-speed, 0}, s2);
  // 1 starts at H - e moving out, reflects at tick e / speed + 1 onto x = H + 1 + e - speed t;
  // e from the contact distances, then stepped until its first overlap tick is t2
  auto t1_of = [&](std::int64_t e) {
    const std::int64_t w = e / speed + 1;  // the reflection tick
    return w + first_overlap(VecN<2>{H + 1 + e - speed * w - c, -d1}, VecN<2>{-speed, 0}, s2);
  };
  std::int64_t e = static_cast<std::int64_t>((std::sqrt(1.0 - 0.35 * 0.35) - std::sqrt(1.0 - 0.7 * 0.7)) * static_cast<double>(sg));
  for (int k = 0; k < 64 && t1_of(e) != t2; ++k) e += t1_of(e) < t2 ? speed / 2 : -speed / 3;
  CHECK(t1_of(e) == t2);
  CHECK(e > 50 * speed);  // 1 lags by tens of ticks: 2 finds 0 first
  const std::vector<VecN<2>> x{{c, c}, {H - e, c - d1}, {H, c + d2}};
  const std::vector<VecN<2>> v{{0, 0}, {speed, 0}, {-speed, 0}};
  for (double shell : {0.0, -1.0, 0.3}) {
    LatticeEngine e2(u, x, v, 5, operator_for(u));
    e2.set_list_shell(shell);
    std::vector<std::array<std::int64_t, 3>> trace;
    e2.trace = &trace;
    const Snapshot s0 = e2.snapshot();
    e2.run(1, tick_limit - 1);
    CHECK(trace.size() == 1);
    if (trace.size() != 1) continue;
    if (trace[0][2] != 1) std::fprintf(stderr, "shell %.1f: 0 met %lld at tick %lld\n", shell, (long long)trace[0][2], (long long)trace[0][0]);
    CHECK(trace[0][0] == t2);
    CHECK(trace[0][1] == 0);
    CHECK(trace[0][2] == 1);
    e2.run(10, tick_limit - 1);
    e2.run_back(0, e2.origin());
    CHECK(same_state(e2.snapshot(), s0));
  }
}

TEST_CASE("2D walls: a collision right after a reflection on one tick (built); back to the tick before equals forward there") {
  // The 2D form of test_lattice_engine3d's case, built rather than found. Particle 0 runs at
  // (u, -u) and reflects on the wall x = H at tick 4 (half a step from it at tick 3); 1 rests
  // below and to the left, its distance at tick 3 just over sigma, so the pair overlaps at tick
  // 4: the reflection comes first, then the collision. Here a neutral event of 0 (a cell crossing
  // or a renewal, kind 0) also falls on tick 4 and re-anchors 0 beyond the wall before its
  // reflection (kind 1): wall_ticks once gave 1 tick from there, so the forward collided 0
  // unreflected (no wall counted) and the trajectory hung on where the search's neutral events
  // fell. And the reverse restores 0's reflected line, whose point at tick 3 is beyond the wall:
  // it was reflected a tick late, so run_back to tick 3 held a centre beyond the wall.
  const UnitsN<2> u = box_units<2>({true, true}, 20.0, 44);
  const std::int64_t sg = u.sigma, H = u.L[0] - sg / 2, c = 10 * sg, w = u.vmax / 4;
  const std::int64_t dx = sg / 10;
  auto dist2 = [](std::int64_t a, std::int64_t b) { return static_cast<u128>(a) * static_cast<u128>(a) + static_cast<u128>(b) * static_cast<u128>(b); };
  const u128 s2 = dist2(sg, 0);
  std::int64_t D = static_cast<std::int64_t>(std::sqrt(static_cast<double>(sg) * static_cast<double>(sg) - static_cast<double>(dx) * static_cast<double>(dx)));
  while (dist2(dx, D) < s2) ++D;  // at tick 3 the pair is just apart
  const std::vector<VecN<2>> x{{H - 3 * w - w / 2, c + 3 * w}, {H - w / 2 - dx, c - D}};
  const std::vector<VecN<2>> v{{w, -w}, {0, 0}};
  // tick 3: 0 at (H - w/2, c), apart; reflected at tick 4: (H + 1 - w/2, c - w), inside
  CHECK(dist2(dx + 1, D - w) < s2);
  for (double shell : {0.0, -1.0}) {
    LatticeEngine e(u, x, v, 9, operator_for(u));
    e.set_list_shell(shell);
    const Snapshot s0 = e.snapshot();
    e.run(1, tick_limit - 1);
    CHECK(e.clock() == 4);
    CHECK(e.counters().walls == 1);
    CHECK(e.counters().wall_body >= 1);
    const Snapshot s1 = e.snapshot();
    LatticeEngine f(s0, operator_for(u));
    f.run(UINT64_MAX, 3);
    const Snapshot f3 = f.snapshot();
    e.run_back(0, 3);
    const Snapshot b3 = e.snapshot();
    CHECK(b3.x[0][0] <= H);
    CHECK(same_state(b3, f3));
    e.run_back(0, e.origin());
    CHECK(same_state(e.snapshot(), s0));
    e.run(1, tick_limit - 1);
    CHECK(same_state(e.snapshot(), s1));
  }
}

TEST_CASE("engine: the list shell is checked, and changing it keeps the state") {
  LatticeConfigN<3> cfg;
  const LatticeStartN<3> st = random_start(cfg, 100, 0.3, 3);
  LatticeEngine3D e(st.units, st.x, st.v, 3, operator_for(st.units));
  CHECK(e.neighbour_search() != 0);  // 3D: lists by default
  CHECK(e.list_shell() > 0.0);
  e.run(500, tick_limit - 1);
  const Snapshot3 s = e.snapshot();
  for (double bad : {0.01, 2.5, std::nan("")}) {
    bool refused = false;
    try {
      e.set_list_shell(bad);
    } catch (const revcol::InvalidArgument& ex) {
      refused = std::string(ex.what()).find("list shell") != std::string::npos;
    }
    CHECK(refused);
    CHECK(same_state(e.snapshot(), s));
  }
  e.set_list_shell(0.0);
  CHECK(e.neighbour_search() == 0);
  CHECK(same_state(e.snapshot(), s));
  const LatticeStartN<2> st2 = random_start(LatticeConfigN<2>{}, 100, 0.3, 3);
  LatticeEngine e2(st2.units, st2.x, st2.v, 3, operator_for(st2.units));
  CHECK(e2.neighbour_search() == 0);  // 2D: the cell grid by default
}

int main() { return check::run_all(); }
