// The relaxed random start (engine/init.hpp, init "relax"; cpp/src/init_relax.cpp): uniform
// centres, the overlaps relaxed away. Every pair ends at least its contact distance times
// (1 + kRelaxGap) apart and every centre in its range inside the walls, at the packing fraction
// asked for; the same seed gives the same bits; a mixture's "auto" start is unchanged where the
// largest size's placement fits and relaxed past it; the float engine runs a dense mixture from
// it; a start at or past jamming, or above the bound, is refused by name.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "check.hpp"
#include "init_relax.hpp"
#include "revcol/engine/engine.hpp"
#include "revcol/engine/init.hpp"
#include "revcol/engine/limits.hpp"
#include "revcol/error.hpp"
#include "revcol/rng/philox.hpp"

using namespace revcol;
using namespace revcol::engine;
using check::refused;

namespace {

Config config(int d, Boundary b, Boundary last) {
  Config c;
  c.dim = d;
  c.boundary = {b, b, b};
  c.boundary[d - 1] = last;
  return c;
}

std::vector<double> binary(std::size_t n, double ratio) {
  std::vector<double> d(n, 1.0);
  for (std::size_t i = 1; i < n; i += 2) d[i] = 1.0 / ratio;
  return d;
}

std::vector<double> gaussian(std::size_t n, double width, std::uint32_t seed) {
  rng::Philox g({0x5151u, seed}, 0);
  std::vector<double> d(n);
  for (double& x : d) {
    double z;
    do {
      z = std::sqrt(-2.0 * std::log(g.next())) * std::cos(2.0 * limits::kPi * g.next());
    } while (std::fabs(z) > 3.0);
    x = 1.0 + width * z;
  }
  return d;
}

// The smallest pair distance over its contact distance (nearest images), and whether every
// centre is inside its range (walls: its radius (1 + kWallMargin) in; periodic: [0, L)).
struct Shape {
  double min_ratio = 1e300;   // over pairs: distance / contact distance
  double wall_ratio = 1e300;  // over centres and walls: distance to the wall / radius
  bool inside = true;
};
Shape shape(const InitialState& s) {
  const Config& c = s.config;
  const int d = c.dim;
  const std::size_t n = s.x.size() / d;
  auto diam = [&](std::size_t i) { return c.diameters.empty() ? c.diameter : c.diameters[i]; };
  Shape out;
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < d; ++k) {
      const double p = s.x[i * d + k], L = c.box[k], r = 0.5 * diam(i) * (1.0 + limits::kWallMargin);
      out.inside = out.inside && (has_walls(c.boundary[k]) ? p >= r && p <= L - r : p >= 0.0 && p < L);
      if (has_walls(c.boundary[k])) out.wall_ratio = std::min(out.wall_ratio, std::min(p, L - p) / (0.5 * diam(i)));
    }
    for (std::size_t j = 0; j < i; ++j) {
      double r2 = 0.0;
      for (int k = 0; k < d; ++k) {
        double u = std::fabs(s.x[i * d + k] - s.x[j * d + k]);
        if (!has_walls(c.boundary[k])) u = std::min(u, c.box[k] - u);
        r2 += u * u;
      }
      out.min_ratio = std::min(out.min_ratio, std::sqrt(r2) / (0.5 * (diam(i) + diam(j))));
    }
  }
  return out;
}

double own_fraction(const InitialState& s) {
  const Config& c = s.config;
  double vol = 1.0, own = 0.0;
  for (int k = 0; k < c.dim; ++k) vol *= c.box[k];
  const std::size_t n = s.x.size() / c.dim;
  for (std::size_t i = 0; i < n; ++i) own += particle_volume(c.dim, c.diameters.empty() ? c.diameter : c.diameters[i]);
  return own / vol;
}

// rounding of the test's sqrt and division: the bound holds to a few ulps
constexpr double kGapBound = 1.0 + detail::kRelaxGap - 1e-13;

}  // namespace

TEST_CASE("relaxed starts of dense mixtures: no pair within its contact distance (1 + 1e-3), nor a wall") {
  struct Case {
    int d;
    Boundary last;
    double phi;
    std::vector<double> diam;
    const char* what;
  };
  const std::vector<Case> cases = {
      {2, Boundary::periodic, 0.80, binary(500, 1.4), "2D binary 0.80"},
      {2, Boundary::wall, 0.78, binary(500, 1.4), "2D binary 0.78, walls on y"},
      {3, Boundary::periodic, 0.58, binary(500, 1.4), "3D binary 0.58"},
      {3, Boundary::bounce, 0.56, binary(500, 1.4), "3D binary 0.56, bounce walls on z"},
      {3, Boundary::periodic, 0.60, gaussian(500, 0.1, 3), "3D polydisperse (10%) 0.60"},
      {1, Boundary::wall, 0.9, binary(100, 2.0), "1D binary 0.9, walls"},
  };
  for (const Case& k : cases) {
    Config c = config(k.d, Boundary::periodic, k.last);
    c.diameters = k.diam;
    const InitialState s = random_state(c, k.diam.size(), k.phi, 11, 0.0, "relax");
    const Shape sh = shape(s);
    std::printf("  %s: smallest distance / contact - 1 = %.3g\n", k.what, sh.min_ratio - 1.0);
    CHECK(sh.min_ratio >= kGapBound);
    CHECK(sh.inside);
    CHECK(sh.wall_ratio >= kGapBound);  // (1e300 without walls)
    CHECK_NEAR(own_fraction(s), k.phi, 1e-12);
    // "auto" goes the same way once the largest size's placement no longer fits
    const InitialState a = random_state(c, k.diam.size(), k.phi, 11, 0.0, "auto");
    CHECK(a.x == s.x);
    CHECK(a.v == s.v);
  }
}

TEST_CASE("same seed, same bits; another seed, another start; one size relaxes too") {
  Config c = config(3, Boundary::periodic, Boundary::periodic);
  c.diameters = binary(300, 1.4);
  const InitialState a = random_state(c, 300, 0.58, 7, 0.0, "relax"), b = random_state(c, 300, 0.58, 7, 0.0, "relax");
  const InitialState o = random_state(c, 300, 0.58, 8, 0.0, "relax");
  CHECK(a.x == b.x);
  CHECK(a.v == b.v);
  CHECK(a.x != o.x);
  Config one = config(3, Boundary::periodic, Boundary::wall);
  const InitialState m = random_state(one, 400, 0.55, 3, 0.0, "relax");
  CHECK(shape(m).min_ratio >= kGapBound);
  CHECK(shape(m).inside);
  CHECK(m.x != random_state(one, 400, 0.55, 3, 0.0, "crystal").x);  // not the crystal
}

TEST_CASE("a mixture's automatic start is unchanged where the largest size's placement fits") {
  for (const double phi : {0.1, 0.35}) {  // rsa, then the crystal, as the largest (0.15 and 0.51 so)
    Config c = config(3, Boundary::periodic, Boundary::periodic);
    c.diameters = binary(300, 1.4);
    const InitialState a = random_state(c, 300, phi, 5);
    const InitialState r = random_state(c, 300, phi, 5, 0.0, phi < 0.2 ? "rsa" : "crystal");
    CHECK(a.x == r.x);
    CHECK(a.x != random_state(c, 300, phi, 5, 0.0, "relax").x);
    CHECK(shape(a).min_ratio * 1.4 >= 1.0);  // as the largest: every pair a large diameter apart
  }
}

TEST_CASE("two centres on top of each other part to their contact distance") {
  detail::RelaxBox box;
  box.d = 2;
  box.L[0] = box.L[1] = 4.0;
  std::vector<double> x = {2.0, 2.0, 2.0, 2.0 + 1e-3, 1.0, 3.9};  // 0 and 1 almost coincide, 2 overlaps 0 across no face
  const std::vector<double> diam = {1.0, 0.5, 1.0};
  const detail::RelaxResult r = detail::relax_overlaps(box, diam, x, 1000);
  REQUIRE(r.done);
  auto dist = [&](int i, int j) {
    double r2 = 0.0;
    for (int k = 0; k < 2; ++k) {
      double u = std::fabs(x[2 * i + k] - x[2 * j + k]);
      u = std::min(u, 4.0 - u);
      r2 += u * u;
    }
    return std::sqrt(r2);
  };
  CHECK(dist(0, 1) >= 0.75 * kGapBound);
  CHECK(dist(0, 2) >= 1.0 * kGapBound);
  CHECK(dist(1, 2) >= 0.75 * kGapBound);
  // the pushes stop once every pair is apart: nothing moved far (no pair was more than a diameter in)
  CHECK(std::fabs(x[0] - 2.0) < 1.0);
}

TEST_CASE("the float engine runs a dense mixture from a relaxed start, energy and momentum kept") {
  Config c = config(3, Boundary::periodic, Boundary::periodic);
  c.diameters = binary(400, 1.4);
  const InitialState s = random_state(c, 400, 0.58, 9);
  auto sim = make_simulation(s.config, s.x, s.v);
  const RunResult r = sim->run(20000, std::numeric_limits<double>::infinity());
  CHECK(r.collisions == 20000);
  const Diagnostics g = sim->diagnostics();
  CHECK(std::fabs(g.energy_drift) < 1e-12);
  std::printf("  3D binary 0.58, 20000 collisions: energy drift %.2e\n", g.energy_drift);
}

TEST_CASE("a start at or past jamming, or above the bound, is refused by name") {
  Config c = config(3, Boundary::periodic, Boundary::periodic);
  c.diameters = binary(200, 1.4);
  CHECK(refused([&] { random_state(c, 200, 0.67, 3, 0.0, "relax"); }, "jamming"));
  CHECK(refused([&] { random_state(c, 200, 0.67, 3); }, "did not relax away"));
  CHECK(refused([&] { random_state(c, 200, 0.70, 3); }, "above what a relaxed random start reaches (0.68 in 3D)"));
  CHECK(refused([&] { random_state(c, 200, 0.4, 3, 0.0, "relaxed"); }, "init must be 'auto', 'rsa', 'crystal' or 'relax'"));
  Config bad = c;
  bad.diameters.pop_back();
  CHECK(refused([&] { random_state(bad, 200, 0.4, 3, 0.0, "relax"); }, "one entry per particle"));
  Config one = config(3, Boundary::periodic, Boundary::periodic);
  CHECK(refused([&] { random_state(one, 200, 0.72, 3, 0.0, "relax"); }, "above what the initialiser reaches"));
  // in a given box: a mixture's own diameters reach random_start
  Config box = config(2, Boundary::periodic, Boundary::periodic);
  box.box = {20.0, 20.0, 1.0};
  box.diameters = binary(400, 1.4);
  box.diameter = 1.0;
  const InitialState s = random_start(box, 400, 4);  // 0.77 of the box at own sizes: relaxed
  CHECK(shape(s).min_ratio >= kGapBound);
}

CHECK_MAIN()
