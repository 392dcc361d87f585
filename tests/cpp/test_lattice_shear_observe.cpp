// The observer on a sheared lattice gas (engine hooks -> Observer::set_shear): an observed run
// is the unobserved run bit for bit and still reverses; a checkpoint mid-observation resumes to
// the same observation, bit for bit; the observer's shear stress gives the peculiar energy the
// gas gained along its path (to 1e-6), its temperature the peculiar one of the frames, its
// velocity profile the imposed rate, and its pressure that of the same gas unsheared (pairs
// across the gradient faces through the moving images); a mixture's species add up.
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "check.hpp"
#include "lattice_gas_util.hpp"
#include "observe_util.hpp"
#include "revcol/lattice/engine.hpp"

using namespace revcol::lattice;
using lattice_test::EngineOf;
using revcol::Mode;
namespace en = revcol::engine;

namespace {

template <std::size_t D>
LatticeStartN<D> start(std::size_t n, double phi, double rate, std::uint32_t seed, bool walls = false) {
  return lattice_test::sheared_start<D>(n, phi, rate, seed, walls);
}

// the rate the engine's units run, as the observer takes it (lattice/observe.hpp)
template <std::size_t D>
double rate_of(const UnitsN<D>& u) {
  return static_cast<double>(u.shear) * (u.length_unit / u.tick) / (static_cast<double>(u.L[1]) * u.length_unit);
}

en::ObserveConfig profile_config() { return observe_test::config(0.0, 8, 1, 40); }

double rel(double a, double b) { return std::fabs(a - b) / std::fabs(b); }

using observe_test::saved;

// sum of |v|^2 / 2 in float units
template <std::size_t D>
double energy(const SnapshotN<D>& s) {
  const double speed = s.units.length_unit / s.units.tick;
  return 0.5 * static_cast<double>(energy2(s.units, s.x, s.v)) * speed * speed;
}

// the peculiar kinetic energy sum |v - rate (y - L_1 / 2) e_0|^2 / 2 of a state, float units
template <std::size_t D>
double peculiar(const SnapshotN<D>& s, double rate) {
  const double len = s.units.length_unit, speed = len / s.units.tick, half = 0.5 * static_cast<double>(s.units.L[1]) * len;
  double e = 0.0;
  for (std::size_t p = 0; p < s.x.size(); ++p)
    for (std::size_t k = 0; k < D; ++k) {
      double v = static_cast<double>(s.v[p][k]) * speed;
      if (k == 0) v -= rate * (static_cast<double>(s.x[p][1]) * len - half);
      e += 0.5 * v * v;
    }
  return e;
}

template <std::size_t D>
void observed_is_unobserved(Mode mode, std::uint32_t seed) {
  const LatticeStartN<D> st = start<D>(D == 2 ? 500 : 600, 0.4, 0.1, seed);
  EngineOf<D> a = lattice_test::engine_of<D>(st, seed, mode), b = lattice_test::engine_of<D>(st, seed, mode);
  const SnapshotN<D> s0 = a.snapshot();
  a.run(3000, tick_limit - 1);
  b.run(3000, tick_limit - 1);
  a.observe(profile_config());
  a.run(6000, tick_limit - 1);
  const SnapshotN<D> mid = a.snapshot();  // with the running observation
  a.run(6000, tick_limit - 1);
  b.run(12000, tick_limit - 1);
  CHECK(same_state(a.snapshot(), b.snapshot()));
  // resumed from the checkpoint: the same observation, to the bit
  EngineOf<D> r(mid, operator_for(mid.units));
  r.run(6000, tick_limit - 1);
  CHECK(r.observer() != nullptr && a.observer() != nullptr);
  CHECK(saved(*r.observer()) == saved(*a.observer()));
  const en::Observation o = a.observer()->results();
  CHECK(o.shear_rate == rate_of(a.units()));
  CHECK(o.pair_collisions + o.group_collisions > 0);
  CHECK(std::isfinite(o.shear_stress.value) && o.shear_stress.value < 0.0);
  // and back to the start, bit for bit (run_back ends the observation)
  a.run_back(0, s0.origin);
  CHECK(same_state(a.snapshot(), s0));
  CHECK(!a.observing());
}

}  // namespace

TEST_CASE("an observed sheared gas is the unobserved one, resumes its observation bit for bit, and reverses: 2D and 3D, exact and specular") {
  observed_is_unobserved<2>(Mode::exact, 3);
  observed_is_unobserved<2>(Mode::specular, 4);
  observed_is_unobserved<3>(Mode::exact, 5);
  observed_is_unobserved<3>(Mode::specular, 6);
}

// Observes e for `frames` x `every` collisions: the boundary's work (the energy gained) against
// the observer's stress, its temperature against the frames' peculiar energy integrated over
// time (trapezoids), the slope of its velocity profile against the rate; the observation.
template <class E>
en::Observation check_balance(E& e, int frames, std::uint64_t every, const char* what) {
  constexpr std::size_t D = E::D;
  const double q = rate_of(e.units());
  en::ObserveConfig c = profile_config();
  e.observe(c);
  const SnapshotN<D> s0 = e.snapshot();
  // (the gas heats, and its collisions come faster as it does: integrate over time)
  double pec = 0.0, t_prev = static_cast<double>(s0.clock) * s0.units.tick, e_prev = peculiar(s0, q);
  for (int f = 0; f < frames; ++f) {
    e.run(every, tick_limit - 1);
    const SnapshotN<D> s = e.snapshot();
    const double t = static_cast<double>(s.clock) * s.units.tick, en = peculiar(s, q);
    pec += 0.5 * (en + e_prev) * (t - t_prev);
    t_prev = t;
    e_prev = en;
  }
  const SnapshotN<D> s1 = e.snapshot();
  const en::Observation o = e.observer()->results();
  const double len = s0.units.length_unit;
  double V = 1.0;
  for (std::size_t k = 0; k < D; ++k) V *= static_cast<double>(s0.units.L[k]) * len;
  const double n = static_cast<double>(s0.x.size());
  const double tau = o.t_end - o.t_start, work = energy(s1) - energy(s0), from_stress = -q * V * tau * o.shear_stress.value;
  const double heat = peculiar(s1, q) - peculiar(s0, q);  // the peculiar energy gained
  const double T_frames = pec / tau / (n * D / 2.0);  // E = N d T / 2
  // the profile's slope by least squares over the slabs
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  const int ns = c.slabs;
  for (int k = 0; k < ns; ++k) {
    const double y = 0.5 * (o.slab_velocity.edges[k] + o.slab_velocity.edges[k + 1]), v = o.slab_velocity.value[k];
    sx += y, sy += v, sxx += y * y, sxy += y * v;
  }
  const double slope = (ns * sxy - sx * sy) / (ns * sxx - sx * sx);
  if (std::getenv("REVCOL_TEST_VERBOSE"))
    std::printf("  %s: peculiar heat %.10g from stress %.10g (%.3g); work %.6g (eta %.4g +- %.2g); T observed %.7g frames %.7g; slope %.5g (rate %.5g); Z %.5g +- %.2g\n",
                what, heat, from_stress, heat / from_stress - 1.0, work, o.viscosity.value, o.viscosity.error, o.temperature.value, T_frames, slope, q,
                o.compressibility.value, o.compressibility.error);
  // the peculiar energy gained is the stress's work, -gamma V P_yx tau, along the path (measured
  // 3e-8 to 1.1e-7 apart: a lattice collision moves its pair by a fraction of a tick's travel).
  // (The box frame's energy gained, `work`, differs from it by gamma sum u_x (y - L_1 / 2) +
  // gamma^2 sum (y - L_1 / 2)^2 / 2 between the ends, a fluctuation of the ends, not a drift.)
  CHECK(std::fabs(heat - from_stress) < 1e-6 * std::fabs(from_stress));
  // (the frames sample a peculiar energy that moves between them at the fluctuating rate
  // -2 gamma sum u_x v_y: measured 5e-6 apart at rate 0.1, 5e-5 in 3D, 1.4e-4 at rate 0.5)
  CHECK(std::fabs(o.temperature.value / T_frames - 1.0) < 1e-3);
  CHECK(std::fabs(slope / q - 1.0) < 0.1);
  return o;
}

TEST_CASE("the observer's shear stress is the heat the gas gained, its temperature the peculiar one, its profile the rate; its pressure the unsheared gas's") {
  const LatticeStartN<2> st = start<2>(400, 0.4, 0.1, 11);
  EngineOf<2> e = lattice_test::engine_of<2>(st, 11, Mode::specular);
  e.run(8000, tick_limit - 1);  // settle
  const en::Observation o = check_balance(e, 400, 200, "2D 0.4 specular");
  // the same gas unsheared, observed as long: the same pressure within errors and 1% (the
  // pairs across the gradient faces taken through the moving images)
  LatticeConfigN<2> plain;
  plain.seed = 11;
  const LatticeStartN<2> ps = random_start(plain, 400, 0.4, 11);
  EngineOf<2> p = lattice_test::engine_of<2>(ps, 11, Mode::specular);
  p.run(8000, tick_limit - 1);
  p.observe(en::ObserveConfig{});
  p.run(80000, tick_limit - 1);
  const en::Observation po = p.observer()->results();
  if (std::getenv("REVCOL_TEST_VERBOSE")) std::printf("  unsheared Z %.5g +- %.2g\n", po.compressibility.value, po.compressibility.error);
  CHECK(std::fabs(o.compressibility.value - po.compressibility.value) <
        3.0 * std::hypot(o.compressibility.error, po.compressibility.error) + 0.01 * po.compressibility.value);
  // 3D, exact mode
  const LatticeStartN<3> s3 = start<3>(500, 0.3, 0.1, 12);
  EngineOf<3> e3 = lattice_test::engine_of<3>(s3, 12, Mode::exact);
  e3.run(8000, tick_limit - 1);
  check_balance(e3, 200, 400, "3D 0.3 exact");
  // 3D with walls across z (the hooks' wall reflections under shear)
  const LatticeStartN<3> w3 = start<3>(500, 0.3, 0.1, 13, true);
  EngineOf<3> ew = lattice_test::engine_of<3>(w3, 13, Mode::specular);
  ew.run(8000, tick_limit - 1);
  const en::Observation ow = check_balance(ew, 200, 400, "3D 0.3 walls on z");
  CHECK(ow.wall_reflections > 0 && ow.pressure_wall[2].value > 0.0);
}

TEST_CASE("a sheared binary mixture observed: the species' peculiar temperatures and partial pressures add up") {
  std::vector<double> sizes;
  for (int q = 0; q < 400; ++q) sizes.push_back(q % 2 ? 1.4 : 1.0);
  const LatticeStartN<2> st = lattice_test::sheared_start<2>(400, 0.4, 0.2, 21, false, sizes);
  EngineOf<2> e = lattice_test::engine_of<2>(st, 21, Mode::exact);
  e.run(4000, tick_limit - 1);
  const en::Observation o = check_balance(e, 100, 200, "2D binary mixture");
  CHECK(o.species_count.size() == 2);
  double t = 0.0, p = 0.0;
  for (std::size_t u = 0; u < 2; ++u) {
    t += static_cast<double>(o.species_count[u]) * o.species_temperature[u].value;
    p += o.species_pressure[u].value;
  }
  CHECK(rel(t / 400.0, o.temperature.value) < 1e-9);
  CHECK(rel(p, o.pressure_virial.value) < 1e-9);
}

TEST_CASE("observed group collisions across the gradient faces: every collision a group, the same balance") {
  const LatticeStartN<2> st = start<2>(300, 0.5, 0.5, 51);
  EngineOf<2> e = lattice_test::engine_of<2>(st, 51, Mode::exact);
  e.max_redraws = -1;  // every collision takes the group path (group_sheared's images)
  e.run(3000, tick_limit - 1);
  const en::Observation o = check_balance(e, 200, 200, "2D groups");
  CHECK(o.group_collisions == 40000 && o.pair_collisions == 0);
}

CHECK_MAIN()
