// The observer on a lattice gas in a field (engine hooks -> Observer::set_field): an observed run
// is the unobserved run bit for bit and still reverses; a checkpoint mid-observation resumes to
// the same observation, bit for bit; its temperature is the frames' kinetic energy integrated over
// time, its slabs hold every particle at every instant, and the column is denser below; a
// mixture's species sums add up to the gas's.
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

// N particles at packing fraction phi, walls on every axis (bounce-back on the field's if asked),
// gravity g along the last axis
template <std::size_t D>
LatticeStartN<D> fallen(std::size_t n, double phi, double g, std::uint32_t seed, bool bounce = false) {
  LatticeConfigN<D> c;
  c.wall = filled<D>(true);
  c.bounce[D - 1] = bounce;
  c.gravity[D - 1] = g;
  c.seed = seed;
  return random_start(c, n, phi, seed);
}

en::ObserveConfig profile_config(std::size_t D) { return observe_test::config(0.0, 10, static_cast<int>(D) - 1, 40); }

using observe_test::saved;

// sum |v|^2 / 2 in float units
template <std::size_t D>
double kinetic(const SnapshotN<D>& s) {
  const double speed = s.units.length_unit / s.units.tick;
  return 0.5 * static_cast<double>(kinetic2(s.v)) * speed * speed;
}

template <std::size_t D>
void observed(const LatticeStartN<D>& st, Mode mode, std::uint32_t seed, const char* what) {
  EngineOf<D> a = lattice_test::engine_of<D>(st, seed, mode), b = lattice_test::engine_of<D>(st, seed, mode);
  const SnapshotN<D> s0 = a.snapshot();
  a.run(3000, tick_limit - 1);
  b.run(3000, tick_limit - 1);
  a.observe(profile_config(D));
  // frames every 100 collisions: the kinetic energy integrated over time (trapezoids)
  const SnapshotN<D> f0 = a.snapshot();
  double kin = 0.0, t_prev = static_cast<double>(f0.clock) * f0.units.tick, k_prev = kinetic(f0);
  SnapshotN<D> mid;
  for (int f = 0; f < 120; ++f) {
    a.run(100, tick_limit - 1);
    const SnapshotN<D> s = a.snapshot();
    const double t = static_cast<double>(s.clock) * s.units.tick, k = kinetic(s);
    kin += 0.5 * (k + k_prev) * (t - t_prev);
    t_prev = t;
    k_prev = k;
    if (f == 59) mid = s;  // with the running observation
  }
  b.run(12000, tick_limit - 1);
  CHECK(same_state(a.snapshot(), b.snapshot()));
  // resumed from the checkpoint: the same observation, to the bit
  EngineOf<D> r(mid, operator_for(mid.units));
  for (int f = 60; f < 120; ++f) r.run(100, tick_limit - 1);  // (its syncs where a's were)
  {
    const auto x = saved(*r.observer()), y = saved(*a.observer());
    CHECK(x == y);
    if (x != y && std::getenv("REVCOL_TEST_VERBOSE")) {
      std::printf("  sizes %zu %zu\n", x.size(), y.size());
      int shown = 0;
      for (std::size_t q = 0; q < std::min(x.size(), y.size()) && shown < 8; ++q)
        if (x[q] != y[q]) std::printf("  [%zu] %.17g vs %.17g\n", q, x[q], y[q]), ++shown;
    }
  }
  const en::Observation o = a.observer()->results();
  const double n = static_cast<double>(st.x.size()), tau = o.t_end - o.t_start;
  const double T_frames = kin / tau / (n * D / 2.0);
  double total = 0.0;  // the slabs' densities times their volumes: N at every instant
  double V = 1.0;
  for (std::size_t k = 0; k < D; ++k) V *= static_cast<double>(st.units.L[k]) * st.units.length_unit;
  for (double q : o.slab_density.value) total += q * V / 10.0;
  if (std::getenv("REVCOL_TEST_VERBOSE"))
    std::printf("  %s: T observed %.8g frames %.8g (%.2g); slabs hold %.12g of %g; bottom %.4g top %.4g; P_wall %.5g\n", what,
                o.temperature.value, T_frames, o.temperature.value / T_frames - 1.0, total, n, o.slab_density.value[0],
                o.slab_density.value[9], o.pressure_wall[D - 1].value);
  // (the frames sample a kinetic energy that moves between them with the potential: measured 1.6e-6 to 5.5e-6)
  CHECK(std::fabs(o.temperature.value / T_frames - 1.0) < 1e-4);
  CHECK(std::fabs(total / n - 1.0) < 1e-12);
  CHECK(o.slab_density.value[0] > o.slab_density.value[9]);  // denser below
  CHECK(o.pressure_wall[D - 1].value > 0.0);
  // and back to the start, bit for bit (run_back ends the observation)
  a.run_back(0, s0.origin);
  CHECK(same_state(a.snapshot(), s0));
  CHECK(!a.observing());
}

}  // namespace

TEST_CASE("an observed gas in a field is the unobserved one, resumes bit for bit, reverses; its temperature the frames'") {
  observed<2>(fallen<2>(400, 0.3, -0.2, 3), Mode::exact, 3, "2D exact g -0.2");
  observed<2>(fallen<2>(400, 0.3, -0.2, 4, true), Mode::specular, 4, "2D specular, bounce-back walls");
  observed<3>(fallen<3>(500, 0.2, -0.2, 5), Mode::exact, 5, "3D exact g -0.2");
}

TEST_CASE("a binary mixture in a field observed: the species' temperatures add up to the gas's") {
  LatticeConfigN<2> c;
  c.wall = filled<2>(true);
  c.gravity[1] = -0.2;
  c.seed = 8;
  for (int q = 0; q < 300; ++q) c.diameters.push_back(q % 2 ? 1.4 : 1.0);
  const LatticeStartN<2> st = random_start(c, 300, 0.3, 8);
  EngineOf<2> e = lattice_test::engine_of<2>(st, 8, Mode::exact);
  e.run(3000, tick_limit - 1);
  e.observe(profile_config(2));
  e.run(8000, tick_limit - 1);
  const en::Observation o = e.observer()->results();
  CHECK(o.species_count.size() == 2);
  double t = 0.0, p = 0.0;
  for (std::size_t u = 0; u < 2; ++u) {
    t += static_cast<double>(o.species_count[u]) * o.species_temperature[u].value;
    p += o.species_pressure[u].value;
  }
  CHECK(std::fabs(t / 300.0 / o.temperature.value - 1.0) < 1e-9);
  CHECK(std::fabs(p / o.pressure_virial.value - 1.0) < 1e-9);
}

CHECK_MAIN()
