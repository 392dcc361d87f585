// The observer in a uniform field (Observer::set_field, cpp/src/observe_field.cpp), on
// constructed parabolic flights with answers worked out here: the kinetic integral, the slabs'
// occupancy across the turning point, the MSD and the VACF at block ends, the distance and the
// speed histogram, an event between two flights that changes no velocity (no impulse: the
// velocities were followed along the parabolas), a wall reflection's impulse, a snapshot resumed
// to the same bits, and the refusals.
#include <cmath>
#include <vector>

#include "check.hpp"
#include "observe_util.hpp"
#include "revcol/engine/observe.hpp"
#include "revcol/error.hpp"

using namespace revcol;
using namespace revcol::engine;

namespace {

constexpr double kG = -1.0, kL = 10.0;  // the field along axis 1 of a 10 x 10 box with walls

double rel(double a, double b) { return std::fabs(a - b) / std::fabs(b); }

struct Flight {
  double x0[2], v[2];
  double x(double t) const { return x0[0] + v[0] * t; }
  double y(double t) const { return x0[1] + v[1] * t + 0.5 * kG * t * t; }
  double vy(double t) const { return v[1] + kG * t; }
  double k2(double t) const { return v[0] * v[0] * t + (std::pow(vy(0.0), 3) - std::pow(vy(t), 3)) / (3.0 * -kG); }
  double dist(double t) const {  // Simpson, 2e5 steps
    const int n = 200000;
    const double h = t / n;
    double s = 0.0;
    for (int k = 0; k <= n; ++k) s += std::hypot(v[0], vy(k * h)) * (k == 0 || k == n ? 1.0 : (k % 2 ? 4.0 : 2.0)) * h / 3.0;
    return s;
  }
};

}  // namespace

TEST_CASE("parabolic flights: the kinetic integral, slabs across the turning point, MSD, VACF, distance, speeds exact") {
  // p0 rises to 3.125 at t = 1.5 and is in [3, 4) for t in [1, 2]; p1 falls from 7 (at rest along y)
  const std::vector<Flight> f{{{3.0, 2.0}, {0.5, 1.5}}, {{6.0, 7.0}, {0.3, 0.0}}};
  const auto [x, v] = observe_test::starts(f, 2);
  const ObserveConfig c = observe_test::config(1.0, 10, 1, 30, 3.0);
  Observer o(c, 2, x, v, 0.0, {kL, kL, 1.0}, {true, true, false}, 1.0);
  o.set_field(1, kG);
  // an event at t = 0.8 between the two that changes no velocity: no impulse
  const double te = 0.8, t2 = 2.5;
  const double xa[2] = {f[0].x(te), f[0].y(te)}, xb[2] = {f[1].x(te), f[1].y(te)};
  const double va[2] = {f[0].v[0], f[0].vy(te)}, vb[2] = {f[1].v[0], f[1].vy(te)};
  o.pair_at(te, 0, 1, xa, xb, va, vb);
  o.sync(t2);
  const Observation r = o.results();
  CHECK(rel(r.temperature.value, (f[0].k2(t2) + f[1].k2(t2)) / (2.0 * 2.0 * t2)) < 1e-12);
  CHECK(std::fabs(r.compressibility.value - 1.0) < 1e-12);
  CHECK(rel(r.mean_free_path.value, (f[0].dist(t2) + f[1].dist(t2)) / 2.0) < 1e-10);
  // slabs of width 1: p0 spends [1, 2] in [3, 4) and the rest in [2, 3); p1 crosses 6, 5 and 4 at
  // sqrt(2), 2 and sqrt(6)
  std::vector<double> occ(10, 0.0);
  occ[3] += 1.0;
  occ[2] += 1.5;
  occ[6] += std::sqrt(2.0);
  occ[5] += 2.0 - std::sqrt(2.0);
  occ[4] += std::sqrt(6.0) - 2.0;
  occ[3] += t2 - std::sqrt(6.0);
  for (int s = 0; s < 10; ++s) CHECK(std::fabs(r.slab_density.value[s] - occ[s] / (t2 * kL * kL / 10.0)) < 1e-12);
  // the slab temperature of [3, 4): p0 over [1, 2] and p1 over [sqrt 6, 2.5]
  const double t3 = std::sqrt(6.0);
  const double k2_3 = (f[0].k2(2.0) - f[0].k2(1.0)) + (f[1].k2(t2) - f[1].k2(t3));
  CHECK(rel(r.slab_temperature.value[3], k2_3 / (2.0 * (1.0 + t2 - t3))) < 1e-12);
  // MSD and VACF at the block ends t = 1, 2
  CHECK(r.msd_time.size() == 2);
  for (int b = 0; b < 2; ++b) {
    const double t = b + 1.0;
    double msd = 0.0, vacf = 0.0;
    for (const Flight& q : f) {
      msd += std::pow(q.x(t) - q.x0[0], 2) + std::pow(q.y(t) - q.x0[1], 2);
      vacf += q.v[0] * q.v[0] + q.v[1] * q.vy(t);
    }
    CHECK(std::fabs(r.msd[b] - msd / 2.0) < 1e-12);
    CHECK(std::fabs(r.vacf[b] - vacf / 2.0) < 1e-12);
  }
  // the Helfand moment: the integral of sum v_x v_y
  double hxy = 0.0;
  for (const Flight& q : f) hxy += q.v[0] * (q.v[1] * 2.0 + 0.5 * kG * 4.0);
  CHECK(std::fabs(r.helfand[1] - hxy) < 1e-12);
  // the speed histogram: a density, its mean the distance over N tau
  const auto [norm, mean] = observe_test::speed_moments(r, c);
  CHECK(std::fabs(norm - 1.0) < 1e-12);
  CHECK(std::fabs(mean - (f[0].dist(t2) + f[1].dist(t2)) / (2.0 * t2)) < 0.5 * c.speed_max / c.speed_bins);
}

TEST_CASE("a wall reflection in a field, and a snapshot resumed to the same bits") {
  // p0 falls from 2 at rest along y: it meets the floor's contact plane 0.5 at t = sqrt(3)
  const std::vector<double> x{4.0, 2.0, 7.0, 6.0}, v{0.2, 0.0, -0.1, 0.4};
  Observer o(observe_test::config(0.5, 4, 1, 8), 2, x, v, 0.0, {kL, kL, 1.0}, {true, true, false}, 1.0);
  o.set_field(1, kG);
  const double tw = std::sqrt(3.0);
  const double xw[2] = {4.0 + 0.2 * tw, 0.5}, vw[2] = {0.2, -kG * tw};  // reflected: up
  o.wall_at(tw, 0, xw, vw, 2u);
  o.sync(2.2);
  std::vector<double> reals;
  std::vector<std::uint64_t> counts;
  o.save(reals, counts);
  // the particles' velocities now (2.2): p0 rising since tw, p1 falling since 0
  const std::vector<double> vnow{0.2, vw[1] + kG * (2.2 - tw), -0.1, 0.4 + kG * 2.2};
  Observer back(reals, counts, 2, vnow, 2.2, {kL, kL, 1.0}, {true, true, false}, 1.0);
  CHECK(back.saved_field_axis() == 1);
  CHECK_THROWS_AS(Observer(reals, counts, 2, vnow, 2.2, {kL, kL, 1.0}, {true, true, false}, 1.0).set_field(1, 2 * kG),
                  InvalidArgument);
  back.set_field(1, kG);
  o.sync(3.1);
  back.sync(3.1);
  CHECK(observe_test::saved(o) == observe_test::saved(back));
  const Observation r = o.results();
  CHECK(rel(r.pressure_wall[1].value, 2.0 * -kG * tw / (2.0 * 3.1 * kL)) < 1e-12);  // |Delta p| = 2 |g| tw
  // a velocity that is not the particle's at the snapshot's clock is refused
  std::vector<double> wrong = vnow;
  wrong[1] += 1e-3;
  CHECK_THROWS_AS(Observer(reals, counts, 2, wrong, 2.2, {kL, kL, 1.0}, {true, true, false}, 1.0), InvalidArgument);
}

TEST_CASE("field refusals: a periodic axis, a bad value, after an event; masses and sizes after it") {
  const std::vector<double> x{1.0, 1.0, 5.0, 5.0}, v{0.3, 0.1, -0.3, -0.1};
  Observer periodic(ObserveConfig{}, 2, x, v, 0.0, {kL, kL, 1.0}, {true, false, false}, 1.0);
  CHECK_THROWS_AS(periodic.set_field(1, kG), InvalidArgument);
  Observer fine(ObserveConfig{}, 2, x, v, 0.0, {kL, kL, 1.0}, {true, true, false}, 1.0);
  CHECK_THROWS_AS(fine.set_field(1, 0.0), InvalidArgument);
  CHECK_THROWS_AS(fine.set_field(2, kG), InvalidArgument);
  CHECK_THROWS_AS(fine.set_field(1, std::nan("")), InvalidArgument);
  CHECK_THROWS_AS(fine.set_shear(0.1), InvalidArgument);  // (walls on axis 1 anyway)
  Observer late(ObserveConfig{}, 2, x, v, 0.0, {kL, kL, 1.0}, {true, true, false}, 1.0);
  const double xa[2] = {1.3, 1.1}, xb[2] = {4.7, 4.9};
  late.pair_at(1.0, 0, 1, xa, xb, v.data(), v.data() + 2);
  CHECK_THROWS_AS(late.set_field(1, kG), InvalidArgument);
  ObserveConfig pc;  // pair distances take a field (test_float_field_observe.cpp has a worked pair)
  pc.pair_bins = 10;
  pc.pair_rmax = 5.0;
  Observer pairs(pc, 2, x, v, 0.0, {kL, kL, 1.0}, {true, true, false}, 1.0);
  pairs.set_field(1, kG);
  // the field's running sums are weighted by the masses and kept per species: both come first
  CHECK_THROWS_AS(pairs.set_masses({1.0, 2.0}), InvalidArgument);
  CHECK_THROWS_AS(pairs.set_sizes({0.5, 0.3}), InvalidArgument);
}

CHECK_MAIN()
