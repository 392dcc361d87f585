// Event-chain Monte Carlo (revcol/studies/ecmc.hpp): its pressure against the exact finite-N answers
// (rods on a ring, two disks, two spheres), no overlaps in dense gases, determinism, errors
// that change nothing, and an interrupt between chains; mixtures: the same exact answers with
// sizes (rods of two lengths, two spheres of two diameters), a mixture of one size that is the
// one-size chain bit for bit, dense binary gases that never overlap at their own contact
// distances, and bad diameters refused by name.
#include "revcol/studies/ecmc.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <string>
#include <tuple>
#include <vector>

#include "check.hpp"
#include "revcol/engine/engine.hpp"
#include "revcol/engine/init.hpp"
#include "revcol/error.hpp"

using revcol::InvalidArgument;
using revcol::ecmc::EventChain;

namespace {

constexpr double kPi = 3.141592653589793238462643383279502884;

struct Estimate {
  double z, error;
};

/// Z over `blocks` blocks of `chains` chains each: the mean and its standard error.
Estimate blocks_of(EventChain& s, int blocks, std::uint64_t chains, double ell) {
  std::vector<double> z;
  for (int b = 0; b < blocks; ++b) z.push_back(s.run(chains, ell).compressibility());
  const double mean = std::accumulate(z.begin(), z.end(), 0.0) / blocks;
  double var = 0;
  for (const double v : z) var += (v - mean) * (v - mean);
  return {mean, std::sqrt(var / (blocks - 1) / blocks)};
}

/// A random start of n spheres at packing fraction phi in a periodic cube (the engine's).
EventChain start(int d, std::size_t n, double phi, std::uint64_t seed) {
  revcol::engine::Config c;
  c.dim = d;
  for (int k = 0; k < d; ++k) c.boundary[k] = revcol::engine::Boundary::periodic;
  const auto s = revcol::engine::random_state(c, n, phi, seed);
  return EventChain(std::vector<double>(s.config.box.begin(), s.config.box.begin() + d), s.x, 1.0, seed);
}

/// The engine's random start of n spheres of diameter 1 at packing fraction phi (periodic),
/// every other sphere then shrunk to 1 / ratio: a binary 1:1 mixture.
struct Binary {
  std::vector<double> box, x, diameters;
};
Binary binary(int d, std::size_t n, double phi, double ratio, std::uint64_t seed) {
  revcol::engine::Config c;
  c.dim = d;
  for (int k = 0; k < d; ++k) c.boundary[k] = revcol::engine::Boundary::periodic;
  const auto s = revcol::engine::random_state(c, n, phi, seed);
  Binary b{std::vector<double>(s.config.box.begin(), s.config.box.begin() + d), s.x, std::vector<double>(n, 1.0)};
  for (std::size_t i = 1; i < n; i += 2) b.diameters[i] = 1.0 / ratio;
  return b;
}

double sphere_volume(int d, double r) { return d == 1 ? 2 * r : d == 2 ? kPi * r * r : 4.0 / 3.0 * kPi * r * r * r; }

}  // namespace

// N rods on a ring of length L: Z = L (L - N D)^(N-1), beta P = 1/L + (N-1)/(L - N D).
TEST_CASE("rods on a ring: the exact finite-N pressure of Tonks' gas") {
  const int n = 10;
  const double L = 20.0;
  std::vector<double> x;
  for (int i = 0; i < n; ++i) x.push_back(2.0 * i + 0.5);
  EventChain s({L}, x, 1.0, 7);
  s.run(2000, 5.0);  // forget the lattice
  const Estimate e = blocks_of(s, 40, 5000, 5.0);
  const double exact = (L / n) * (1.0 / L + (n - 1) / (L - n));  // 1.9
  CHECK(e.error < 0.003);  // the test can fail: the estimate is sharp
  CHECK(std::fabs(e.z - exact) < 4.0 * e.error);
  CHECK(s.min_distance() >= 1.0 - 1e-9);
}

// Two spheres in a periodic box whose sides all exceed 2 D: Z = V (V - v_ex).
TEST_CASE("two disks and two spheres: Z = V (V - v_ex) gives the exact pressure") {
  struct Case {
    std::vector<double> box, x;
    double v_ex;
  };
  const Case cases[] = {{{3.0, 3.0}, {0.5, 0.5, 2.0, 1.7}, kPi},
                        {{3.0, 4.5}, {0.5, 0.5, 2.0, 3.1}, kPi},
                        {{3.0, 3.0, 3.0}, {0.5, 0.5, 0.5, 2.0, 1.7, 2.2}, 4.0 * kPi / 3.0}};
  for (const Case& c : cases) {
    EventChain s(c.box, c.x, 1.0, 3);
    s.run(1000, 1.0);
    const Estimate e = blocks_of(s, 40, 10000, 1.0);
    double V = 1.0;
    for (const double L : c.box) V *= L;
    const double exact = 0.5 * (1.0 + V / (V - c.v_ex));
    CHECK(e.error < 0.002);
    CHECK(std::fabs(e.z - exact) < 4.0 * e.error);
  }
}

TEST_CASE("dense gases: no pair overlaps after many chains, every sphere still in its box") {
  for (const auto& [d, n, phi] : {std::tuple{2, 400, 0.7}, std::tuple{3, 256, 0.45}, std::tuple{1, 50, 0.8}}) {
    EventChain s = start(d, static_cast<std::size_t>(n), phi, 11);
    const auto sums = s.run(20000, 0.5 * s.box()[0]);
    CHECK(sums.lifts > 20000u);
    CHECK(sums.crossings > 0u);
    CHECK(s.min_distance() >= 1.0 - 1e-9);
    const auto& x = s.positions();
    for (std::size_t i = 0; i < x.size(); ++i) CHECK(x[i] >= 0.0 && x[i] < s.box()[i % d]);
    CHECK(std::fabs(s.packing_fraction() - phi) < 1e-12);
  }
}

TEST_CASE("a cell of more than 8 spheres (a body-centred cube) widens every cell's slots") {
  // box 4 D: 3 cells of 4/3 D per axis; 8 spheres on the corners of a cube of side 1.31 D and
  // one at its centre (1.13 D from each corner), all in cell (0, 0, 0)
  std::vector<double> x;
  for (int c = 0; c < 8; ++c)
    for (int a = 0; a < 3; ++a) x.push_back((c >> a & 1) ? 1.32 : 0.01);
  for (int a = 0; a < 3; ++a) x.push_back(0.665);
  x.insert(x.end(), {2.7, 2.7, 2.7});
  EventChain s({4.0, 4.0, 4.0}, x, 1.0, 8);
  CHECK(s.min_distance() >= 1.0);
  const auto sums = s.run(3000, 2.0);
  CHECK(sums.lifts > 0u && sums.crossings > 0u);
  CHECK(s.min_distance() >= 1.0 - 1e-9);
  CHECK(s.positions().size() == x.size());
}

TEST_CASE("the same seed gives the same bits; another seed another chain") {
  EventChain a = start(2, 200, 0.5, 5), b = start(2, 200, 0.5, 5);
  const auto sa = a.run(3000, 4.0), sb = b.run(3000, 4.0);
  CHECK(a.positions() == b.positions());
  CHECK(sa.lift_dx == sb.lift_dx);
  CHECK(sa.lifts == sb.lifts);
  revcol::engine::Config c;
  c.dim = 2;
  c.boundary[0] = c.boundary[1] = revcol::engine::Boundary::periodic;
  const auto st = revcol::engine::random_state(c, 200, 0.5, 5);
  EventChain other({st.config.box[0], st.config.box[1]}, st.x, 1.0, 6);
  other.run(3000, 4.0);
  CHECK(other.positions() != a.positions());
}

TEST_CASE("bad input names the problem and changes nothing") {
  using revcol::InvalidArgument;
  CHECK_THROWS_AS(EventChain({}, {}, 1.0, 1), InvalidArgument);
  CHECK_THROWS_AS(EventChain({3, 3, 3, 3}, {}, 1.0, 1), InvalidArgument);
  CHECK_THROWS_AS(EventChain({2.5, 3.0}, {0.5, 0.5}, 1.0, 1), InvalidArgument);             // < 3 D
  CHECK_THROWS_AS(EventChain({3.0, 3.0}, {0.5, 0.5, 1.2, 0.5}, 1.0, 1), InvalidArgument);   // overlap
  CHECK_THROWS_AS(EventChain({3.0, 3.0}, {0.5, 0.5, 2.9, 0.5}, 1.0, 1), InvalidArgument);   // overlap across the wrap
  CHECK_THROWS_AS(EventChain({3.0, 3.0}, {0.5, 3.0}, 1.0, 1), InvalidArgument);             // outside [0, L)
  CHECK_THROWS_AS(EventChain({3.0, 3.0}, {0.5, NAN}, 1.0, 1), InvalidArgument);
  CHECK_THROWS_AS(EventChain({3.0, 3.0}, {0.5, 0.5, 1.0}, 1.0, 1), InvalidArgument);        // not n x d
  CHECK_THROWS_AS(EventChain({3.0, 3.0}, {0.5, 0.5}, 0.0, 1), InvalidArgument);
  CHECK_THROWS_AS(EventChain({3.0, 3.0}, {0.5, 0.5}, 1.0, std::uint64_t{1} << 32), InvalidArgument);
  CHECK_THROWS_AS(EventChain({300.0, 300.0, 300.0}, {0.5, 0.5, 0.5}, 1.0, 1), InvalidArgument);  // 2.7e7 cells
  EventChain s = start(2, 50, 0.3, 2);
  const auto before = s.positions();
  CHECK_THROWS_AS(s.run(10, 0.0), InvalidArgument);
  CHECK_THROWS_AS(s.run(10, INFINITY), InvalidArgument);
  CHECK_THROWS_AS(s.run(10, -1.0), InvalidArgument);
  CHECK(s.positions() == before);
  CHECK(s.totals().chains == 0u);
}

TEST_CASE("an interrupt stops between chains: totals count whole chains") {
  EventChain s = start(2, 100, 0.5, 4);
  int calls = 0;
  const revcol::InterruptCheck stop = [&] { return ++calls >= 3; };
  CHECK_THROWS_AS(s.run(100000, 3.0, stop), revcol::Interrupted);
  CHECK(s.totals().chains == 3u * 256u - 1u);
  const double mean = s.totals().displacement / static_cast<double>(s.totals().chains);
  CHECK(mean > 2.8 && mean < 3.2);  // lengths uniform in [1.5, 4.5]
  CHECK(s.min_distance() >= 1.0 - 1e-9);
  // the run goes on from there as from any other state
  EventChain t = start(2, 100, 0.5, 4);
  t.run(3u * 256u - 1u, 3.0);
  CHECK(t.positions() == s.positions());
}

// ---- mixtures (the diameters constructor) ----

// Rods of lengths d_i on a ring of length L (their order fixed): Z = L (L - sum d)^(N-1).
TEST_CASE("rods of two lengths on a ring: Tonks' exact pressure with the rods' total length") {
  const int n = 10;
  const double L = 20.0;
  std::vector<double> x, d;
  for (int i = 0; i < n; ++i) {
    x.push_back(2.0 * i + 0.5);
    d.push_back(i % 2 ? 0.6 : 1.0);
  }
  EventChain s({L}, x, d, 7);
  CHECK(s.diameter() == 1.0);
  CHECK(s.radii().size() == static_cast<std::size_t>(n));
  CHECK(std::fabs(s.packing_fraction() - 8.0 / L) < 1e-15);
  s.run(2000, 5.0);
  const Estimate e = blocks_of(s, 40, 5000, 5.0);
  const double exact = (L / n) * (1.0 / L + (n - 1) / (L - 8.0));  // 1.6
  CHECK(e.error < 0.003);
  CHECK(std::fabs(e.z - exact) < 4.0 * e.error);
  // one size would give 1.9: the test tells the sizes apart by 100 of its errors
  CHECK(std::fabs(e.z - 1.9) > 50.0 * e.error);
  CHECK(s.min_distance() >= 1.0 - 1e-9);
}

// Two spheres of diameters 1 and 1/2: Z = V (V - v_ex), v_ex a sphere of radius 3/4.
TEST_CASE("two spheres of two sizes: Z = V (V - v_ex) at their contact distance") {
  struct Case {
    std::vector<double> box, x;
    int d;
  };
  const Case cases[] = {{{3.0, 3.0}, {0.5, 0.5, 2.0, 1.7}, 2}, {{3.0, 3.0, 3.0}, {0.5, 0.5, 0.5, 2.0, 1.7, 2.2}, 3}};
  const std::vector<double> sizes{1.0, 0.5};
  for (const Case& c : cases) {
    EventChain s(c.box, c.x, sizes, 3);
    s.run(1000, 1.0);
    const Estimate e = blocks_of(s, 40, 10000, 1.0);
    double V = 1.0;
    for (const double L : c.box) V *= L;
    const double exact = 0.5 * (1.0 + V / (V - sphere_volume(c.d, 0.75)));
    CHECK(e.error < 0.002);
    CHECK(std::fabs(e.z - exact) < 4.0 * e.error);
    CHECK(std::fabs(s.packing_fraction() - (sphere_volume(c.d, 0.5) + sphere_volume(c.d, 0.25)) / V) < 1e-15);
  }
}

TEST_CASE("a mixture of one size is the one-size chain bit for bit") {
  for (const int d : {1, 2, 3}) {
    const Binary b = binary(d, 200, d == 1 ? 0.6 : 0.45, 1.0, 9);
    EventChain one(b.box, b.x, 1.0, 4), mix(b.box, b.x, b.diameters, 4);
    const auto s1 = one.run(2000, 3.0), s2 = mix.run(2000, 3.0);
    CHECK(s1.lifts > 1000u);
    CHECK(one.positions() == mix.positions());
    CHECK(s1.lift_dx == s2.lift_dx);
    CHECK(s1.crossings == s2.crossings);
    CHECK(one.min_distance() == mix.min_distance());
  }
}

TEST_CASE("dense binary gases: no pair closer than its own contact distance, every sphere in its box") {
  for (const auto& [d, n, phi] : {std::tuple{2, 400, 0.75}, std::tuple{3, 256, 0.5}, std::tuple{1, 50, 0.8}}) {
    const Binary b = binary(d, static_cast<std::size_t>(n), phi, 1.4, 11);
    EventChain s(b.box, b.x, b.diameters, 11);
    const auto sums = s.run(20000, 0.5 * s.box()[0]);
    CHECK(sums.lifts > 20000u);
    CHECK(s.min_distance() >= 1.0 - 1e-9);
    const auto& x = s.positions();
    for (std::size_t i = 0; i < x.size(); ++i) CHECK(x[i] >= 0.0 && x[i] < s.box()[i % d]);
    double v = 0;
    for (const double di : b.diameters) v += sphere_volume(d, 0.5 * di);
    double V = 1;
    for (const double L : b.box) V *= L;
    CHECK(std::fabs(s.packing_fraction() - v / V) < 1e-12);
  }
  // the small spheres do come within a large pair's contact distance of each other: the
  // contact distance is the pair's own, not the largest
  const Binary b = binary(2, 400, 0.75, 1.4, 12);
  EventChain s(b.box, b.x, b.diameters, 12);
  s.run(20000, 5.0);
  double closest_small = 1e9;
  const auto& x = s.positions();
  for (std::size_t i = 1; i < 400; i += 2)
    for (std::size_t j = i + 2; j < 400; j += 2) {
      double r2 = 0;
      for (int k = 0; k < 2; ++k) {
        double r = x[2 * j + k] - x[2 * i + k];
        r -= b.box[k] * std::round(r / b.box[k]);
        r2 += r * r;
      }
      closest_small = std::min(closest_small, std::sqrt(r2));
    }
  CHECK(closest_small < 0.9);
  CHECK(closest_small >= 1.0 / 1.4 * (1.0 - 1e-9));
}

TEST_CASE("bad diameters are refused by name") {
  const std::vector<double> box{3.0, 3.0}, x{0.5, 0.5, 2.0, 1.7};
  auto refuses = [&](std::vector<double> b, std::vector<double> xs, std::vector<double> d, const char* what) {
    try {
      EventChain s(std::move(b), std::move(xs), d, 1);
      return false;
    } catch (const InvalidArgument& e) {
      return std::string(e.what()).find(what) != std::string::npos;
    }
  };
  CHECK(refuses(box, x, {1.0, 0.0}, "diameters must be positive and finite"));
  CHECK(refuses(box, x, {1.0, NAN}, "diameter 1 is nan"));
  CHECK(refuses(box, x, {1.0, -0.5}, "positive"));
  CHECK(refuses(box, x, {1.0, 0.05}, "more than 16 times smaller"));
  CHECK(refuses(box, x, {1.0}, "one diameter per sphere"));
  CHECK(refuses(box, x, {1.0, 1.0, 1.0}, "one diameter per sphere"));
  CHECK(refuses({3.0, 3.0}, {0.5, 0.5, 1.2, 0.5}, {1.0, 0.5}, "overlap"));  // 0.7 < 0.75
  CHECK(refuses({2.5, 2.5}, x, {1.0, 0.5}, "at least 3 diameters"));       // 3 D of the largest
  // 0.55 apart is fine for two small spheres
  EventChain ok({3.0, 3.0}, {0.5, 0.5, 1.05, 0.5}, {0.5, 0.5}, 1);
  CHECK(std::fabs(ok.min_distance() - 0.55 / 0.5) < 1e-12);
}

CHECK_MAIN()
