// The observer under Lees-Edwards shear (Observer::set_shear, cpp/src/observe_shear.cpp), on
// constructed motions with answers worked out here: free flights that cross a gradient face
// (the box's velocity jumps, the observer's unwrapped flight does not), the peculiar kinetic
// integral and the kinetic shear stress as exact polynomials, the distance flown and the speed
// histogram of a peculiar speed that changes along a flight, the slabs' box-frame velocity
// profile, the collision record, a wall on z in 3D, a snapshot resumed to the same bits, and the
// refusals.
#include <cmath>
#include <vector>

#include "check.hpp"
#include "observe_util.hpp"
#include "revcol/engine/observe.hpp"
#include "revcol/error.hpp"

using namespace revcol;
using namespace revcol::engine;

namespace {

constexpr double kRate = 0.1, kL0 = 12.0, kL1 = 10.0, kU = kRate * kL1;  // the image one box up: kU faster

double rel(double a, double b) { return std::fabs(a - b) / std::fabs(b); }

// One particle's flight, unwrapped: x(t) = x0 + v (t - t0)
struct Flight {
  double x0[3], v[3], t0;
  double y(double t) const { return x0[1] + v[1] * (t - t0); }
  double ux(double t) const { return v[0] - kRate * (y(t) - 0.5 * kL1); }
};

// int_ta^tb of |u|^2, u_x v_y and |u| (Simpson, 2e5 steps: the last to 1e-12) for one flight
struct Integrals {
  double k2 = 0.0, xy = 0.0, xz = 0.0, dist = 0.0;
};
Integrals integrate(const Flight& f, double ta, double tb) {
  Integrals out;
  const double a = f.ux(ta), b = kRate * f.v[1], T = tb - ta, p2 = f.v[1] * f.v[1] + f.v[2] * f.v[2];
  out.k2 = a * a * T - a * b * T * T + b * b * T * T * T / 3.0 + p2 * T;  // u_x = a - b (t - ta)
  out.xy = f.v[1] * (a * T - 0.5 * b * T * T);
  out.xz = f.v[2] * (a * T - 0.5 * b * T * T);
  const int n = 200000;
  const double h = T / n;
  for (int k = 0; k <= n; ++k) {
    const double ux = a - b * (k * h), s = std::sqrt(ux * ux + p2);
    out.dist += s * (k == 0 || k == n ? 1.0 : (k % 2 ? 4.0 : 2.0)) * h / 3.0;
  }
  return out;
}

// the box point and velocity of an unwrapped point (m boxes up: less m (offset, L1), v less m U)
void to_box(const Flight& f, double t, double* x, double* v, int dim) {
  double y = f.y(t);
  const double m = std::floor(y / kL1);
  x[1] = y - m * kL1;
  x[0] = f.x0[0] + f.v[0] * (t - f.t0) - m * std::fmod(kU * t, kL0);
  x[0] -= kL0 * std::floor(x[0] / kL0);
  v[0] = f.v[0] - m * kU;
  v[1] = f.v[1];
  if (dim == 3) {
    x[2] = f.x0[2] + f.v[2] * (t - f.t0);
    v[2] = f.v[2];
  }
}

}  // namespace

TEST_CASE("sheared free flights: a face crossed, the peculiar kinetic integral, stress, distance, speeds and slabs exact") {
  // p0 crosses the upper face at t = 1.25; p1 drifts down; p2 flies along the flow (v_y = 0)
  std::vector<Flight> f{{{3.0, 9.0, 0.0}, {0.5, 0.8, 0.0}, 0.0}, {{6.0, 2.0, 0.0}, {-0.3, -0.2, 0.0}, 0.0},
                        {{9.0, 5.0, 0.0}, {0.2, 0.0, 0.0}, 0.0}};
  std::vector<double> x, v;
  for (const Flight& q : f) x.insert(x.end(), {q.x0[0], q.x0[1]}), v.insert(v.end(), {q.v[0], q.v[1]});
  ObserveConfig c = observe_test::config(100.0, 5, 1, 40, 4.0);
  c.collision_record = true;
  Observer o(c, 2, x, v, 0.0, {kL0, kL1, 1.0}, {false, false, false}, 1.0);
  o.set_shear(kRate);
  // a "collision" of p0 and p1 at t = 3 that changes no velocity: the box's positions and
  // velocities (p0 one box up: its box velocity jumped by -U) must give no impulse
  const double t1 = 3.0, t2 = 5.0;
  double xa[2], xb[2], va[2], vb[2];
  to_box(f[0], t1, xa, va, 2);
  to_box(f[1], t1, xb, vb, 2);
  CHECK(va[0] == f[0].v[0] - kU);
  o.pair_at(t1, 0, 1, xa, xb, va, vb);
  // the record: in the box both are at y = 1.4 (one image row), r = (-3.6, 0), w the box's v_a - v_b
  const std::vector<double>& rec = o.collision_record();
  CHECK(rec.size() == 4);
  CHECK(std::fabs(rec[0] + 1.0) < 1e-12 && std::fabs(rec[1]) < 1e-12);
  CHECK(std::fabs(rec[2] - (-0.2)) < 1e-12 && std::fabs(rec[3] - 1.0) < 1e-12);
  o.sync(t2);
  const Observation r = o.results();
  Integrals tot;
  for (const Flight& q : f) {
    const Integrals s = integrate(q, 0.0, t2);
    tot.k2 += s.k2;
    tot.xy += s.xy;
    tot.dist += s.dist;
  }
  const double V = kL0 * kL1;
  CHECK(r.shear_rate == kRate);
  CHECK(rel(r.temperature.value, tot.k2 / (2.0 * 3.0 * t2)) < 1e-12);
  CHECK(std::fabs(r.compressibility.value - 1.0) < 1e-12);  // no impulse: the images were found
  CHECK(rel(r.shear_stress.value, tot.xy / (V * t2)) < 1e-12);
  CHECK(rel(r.viscosity.value, -tot.xy / (V * t2 * kRate)) < 1e-12);
  CHECK(rel(r.mean_free_path.value, tot.dist / 2.0) < 1e-10);  // two particle collisions
  // unwrapped through the face: p0 flew on as one line
  const std::vector<double> un = o.unwrapped(t2);
  CHECK(std::fabs(un[0] - (3.0 + 0.5 * t2)) < 1e-12);
  CHECK(std::fabs(un[1] - (9.0 + 0.8 * t2)) < 1e-12);
  // the speed histogram: a density of the peculiar speed, its mean the distance over N tau
  const auto [norm, mean] = observe_test::speed_moments(r, c);
  CHECK(std::fabs(norm - 1.0) < 1e-12);
  CHECK(std::fabs(mean - tot.dist / (3.0 * t2)) < 0.5 * c.speed_max / c.speed_bins);
  // slabs: occupancy and the box-frame flow velocity per slab, sampled finely
  std::vector<double> occ(5, 0.0), vx(5, 0.0);
  const int n = 500000;
  for (int k = 0; k < n; ++k) {
    const double t = (k + 0.5) * t2 / n;
    for (const Flight& q : f) {
      double xb2[2], vb2[2];
      to_box(q, t, xb2, vb2, 2);
      const auto s = static_cast<std::size_t>(xb2[1] / 2.0);
      occ[s] += 1.0;
      vx[s] += vb2[0];
    }
  }
  for (std::size_t s = 0; s < 5; ++s) {
    CHECK(std::fabs(r.slab_density.value[s] - occ[s] / n / (V / 5.0)) < 1e-4);
    if (occ[s] > 0) CHECK(std::fabs(r.slab_velocity.value[s] - vx[s] / occ[s]) < 1e-4);
  }
  // p0's stretch in the lowest slab after its crossing moves at its box velocity 0.5 - U
  CHECK(r.slab_velocity.value[0] < 0.0);
}

TEST_CASE("sheared 3D flights with a wall on z: the xz and yz stresses, the wall impulse, and a snapshot resumed to the same bits") {
  std::vector<Flight> f{{{2.0, 8.5, 2.0}, {0.4, 0.9, -0.5}, 0.0}, {{7.0, 3.0, 6.0}, {-0.2, 0.3, 0.25}, 0.0}};
  const auto [x, v] = observe_test::starts(f, 3);
  const ObserveConfig c = observe_test::config(1.0, 0, 0, 0);
  const std::array<double, 3> box{kL0, kL1, 8.0};
  const std::array<bool, 3> walls{false, false, true};
  Observer o(c, 3, x, v, 0.0, box, walls, 1.0);
  o.set_shear(kRate);
  // p0 meets the lower wall (contact plane z = 0.5) at t = 3, having crossed the upper face at
  // t = 5/3: the hook gets its box point and velocity with v_z reversed
  const double tw = 3.0, t2 = 4.5;
  double xw[3], vw[3];
  to_box(f[0], tw, xw, vw, 3);
  CHECK(std::fabs(xw[2] - 0.5) < 1e-12);
  vw[2] = -vw[2];
  o.wall_at(tw, 0, xw, vw, 4u);
  // an interrupted copy: saved at 3.7, resumed with the box's velocities, both run to t2
  o.sync(3.7);
  std::vector<double> reals;
  std::vector<std::uint64_t> counts;
  o.save(reals, counts);
  std::vector<double> vbox;
  for (const Flight& q : f) {
    Flight g = q;
    if (&q == &f[0]) g = Flight{{f[0].x0[0] + f[0].v[0] * tw, f[0].y(tw), 0.5}, {f[0].v[0], f[0].v[1], 0.5}, tw};
    double xb[3], vb[3];
    to_box(g, 3.7, xb, vb, 3);
    vbox.insert(vbox.end(), vb, vb + 3);
  }
  Observer back(reals, counts, 3, vbox, 3.7, box, walls, 1.0);
  CHECK(back.saved_shear() == kRate);
  CHECK_THROWS_AS(Observer(reals, counts, 3, vbox, 3.7, box, walls, 1.0).set_shear(2 * kRate), InvalidArgument);
  back.set_shear(kRate);
  o.sync(t2);
  back.sync(t2);
  CHECK(observe_test::saved(o) == observe_test::saved(back));
  const Observation r = o.results();
  Flight after{{f[0].x0[0] + f[0].v[0] * tw, f[0].y(tw), 0.5}, {f[0].v[0], f[0].v[1], 0.5}, tw};
  Integrals a = integrate(f[0], 0.0, tw), b = integrate(after, tw, t2), q = integrate(f[1], 0.0, t2);
  const double V = kL0 * kL1 * 8.0, k2 = a.k2 + b.k2 + q.k2;
  CHECK(rel(r.temperature.value, k2 / (3.0 * 2.0 * t2)) < 1e-12);
  CHECK(rel(r.shear_stress.value, (a.xy + b.xy + q.xy) / (V * t2)) < 1e-12);
  // the Helfand record at the block ends: xz integrates u_x v_z (v_z reversed at the wall),
  // yz v_y v_z; at t = 4: p0 flew 3 before the wall and 1 after it
  CHECK(r.helfand_components == 3 && r.msd_time.size() == 4);
  const Integrals a4 = integrate(after, tw, 4.0), q4 = integrate(f[1], 0.0, 4.0);
  CHECK(std::fabs(r.helfand[3 * 3 + 1] - (a.xz + a4.xz + q4.xz)) < 1e-12);
  CHECK(std::fabs(r.helfand[3 * 3 + 2] - (0.9 * -0.5 * 3.0 + 0.9 * 0.5 * 1.0 + 0.3 * 0.25 * 4.0)) < 1e-12);
  CHECK(rel(r.pressure_wall[2].value, 1.0 / (2.0 * t2 * kL0 * kL1)) < 1e-12);  // |Delta p_z| = 1
}

TEST_CASE("shear refusals: walls on the flow or gradient axis, slabs across another axis, after an event") {
  const std::vector<double> x{1.0, 1.0, 5.0, 5.0}, v{0.3, 0.1, -0.3, -0.1};
  Observer walled(ObserveConfig{}, 2, x, v, 0.0, {kL0, kL1, 1.0}, {false, true, false}, 1.0);
  CHECK_THROWS_AS(walled.set_shear(kRate), InvalidArgument);
  ObserveConfig c;
  c.slabs = 4;
  c.slab_axis = 0;
  Observer across(c, 2, x, v, 0.0, {kL0, kL1, 1.0}, {false, false, false}, 1.0);
  CHECK_THROWS_AS(across.set_shear(kRate), InvalidArgument);
  Observer late(ObserveConfig{}, 2, x, v, 0.0, {kL0, kL1, 1.0}, {false, false, false}, 1.0);
  const double xa[2] = {1.3, 1.1}, xb[2] = {4.7, 4.9};
  late.pair_at(1.0, 0, 1, xa, xb, v.data(), v.data() + 2);
  CHECK_THROWS_AS(late.set_shear(kRate), InvalidArgument);
  Observer fine(ObserveConfig{}, 2, x, v, 0.0, {kL0, kL1, 1.0}, {false, false, false}, 1.0);
  CHECK_THROWS_AS(fine.set_shear(std::nan("")), InvalidArgument);
  CHECK_THROWS_AS(fine.set_shear(0.0), InvalidArgument);
}

CHECK_MAIN()
