// The observer on the float engine's gas in a field (EngineImpl::describe_particles ->
// Observer::set_field): two disks dropped on a floor give the worked kinetic integral and floor
// impulse; an observed gas (1D, 2D binary, 3D of two masses with bounce walls; the field down or
// up) is the unobserved one bit for bit, its temperature is the frames' kinetic energy integrated over time,
// its slabs hold every particle and the column is denser at the floor, its species' sums add up
// to the gas's, and a checkpoint taken mid-observation resumes to the same observation bit for
// bit; the virial with the field's term holds (unit masses and two masses); pair distances follow
// the pair's linear separation; a field along two axes is refused by name.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "check.hpp"
#include "observe_util.hpp"
#include "revcol/engine/engine.hpp"
#include "revcol/engine/init.hpp"
#include "revcol/engine/observe.hpp"
#include "revcol/error.hpp"

using namespace revcol;
using namespace revcol::engine;

using check::refused;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr std::uint64_t kAll = std::numeric_limits<std::uint64_t>::max();

bool close_to(double a, double b, double rel) {
  const bool ok = std::fabs(a - b) <= rel * std::fabs(b);
  if (!ok) std::fprintf(stderr, "    %.17g vs %.17g (rel %.3g)\n", a, b, std::fabs(a - b) / std::fabs(b));
  return ok;
}

double kinetic(const Simulation& s, const std::vector<double>& mass) {
  const std::vector<double> v = s.velocities();
  const auto d = static_cast<std::size_t>(s.config().dim);
  double k = 0.0;
  for (std::size_t q = 0; q < v.size(); ++q) k += 0.5 * (mass.empty() ? 1.0 : mass[q / d]) * v[q] * v[q];
  return k;
}

}  // namespace

TEST_CASE("two disks dropped on a floor: the worked kinetic integral and floor impulse") {
  // g = -2 along y, floor contact at y = 0.5. A from y = 4.5 at rest (flying at 0.25 in x) lands
  // at t = 2 with speed 4 and is back at 4.5 at t = 4; B from y = 8 lands at tb = sqrt(7.5) with
  // speed 2 tb. Over [0, 4]: integral of sum v^2 = 64/3 + 0.25 (A) + 4 tb^3 / 3 + 4 (tb^3 -
  // (2 tb - 4)^3) / 3 (B); the floor takes |Delta p| = 8 + 4 tb
  Config c;
  c.dim = 2;
  c.boundary = {Boundary::periodic, Boundary::wall, Boundary::periodic};
  c.box = {10, 10, 1};
  c.gravity = {0.0, -2.0, 0.0};
  auto s = make_simulation(c, {1.0, 4.5, 8.0, 8.0}, {0.25, 0.0, 0.0, 0.0});
  ObserveConfig oc = observe_test::config(10.0, 5, 1, 8, 8.0);
  s->observe(oc);
  s->run(kAll, 4.0);
  const Observation r = s->observer()->results();
  const double tb = std::sqrt(7.5), k2 = 64.0 / 3.0 + 0.25 + 4.0 * tb * tb * tb / 3.0 +
                                         4.0 * (tb * tb * tb - std::pow(2.0 * tb - 4.0, 3)) / 3.0;
  CHECK(close_to(r.t_end - r.t_start, 4.0, 1e-15) && r.wall_reflections == 2);
  CHECK(close_to(r.temperature.value, k2 / (2.0 * 2.0 * 4.0), 1e-12));
  CHECK(close_to(r.pressure_wall[1].value, (8.0 + 4.0 * tb) / (2.0 * 4.0 * 10.0), 1e-12));
  CHECK(r.pressure_wall[0].value != r.pressure_wall[0].value || r.pressure_wall[0].value == 0.0);  // periodic: none
  // the slabs hold both disks all the time; the speeds' histogram integrates to 1
  double held = 0.0;
  for (double q : r.slab_density.value) held += q * 100.0 / 5.0;
  CHECK(close_to(held, 2.0, 1e-12));
  CHECK(close_to(observe_test::speed_moments(r, oc).first, 1.0, 1e-12));
  // the observer's parabolas are the engine's: its unwrapped centres at the end are the engine's
  const std::vector<double> x = s->positions(), u = s->observer()->unwrapped(4.0);
  for (std::size_t q = 0; q < x.size(); ++q) CHECK(std::fabs(x[q] - u[q]) < 1e-12);
}

TEST_CASE("an observed gas in a field: the unobserved run's bits, the frames' temperature, its profile, resumed") {
  for (int d : {1, 2, 3}) {
    Config c;
    c.dim = d;
    c.boundary = {Boundary::periodic, Boundary::periodic, Boundary::periodic};
    const auto f = static_cast<std::size_t>(d - 1);
    c.boundary[f] = d == 3 ? Boundary::bounce : Boundary::wall;  // the field's axis
    c.gravity[f] = d == 2 ? -0.5 : 0.3;                          // down; up in 1D and 3D
    if (d == 2)
      for (std::size_t i = 0; i < 400; ++i) c.diameters.push_back(i % 2 == 0 ? 1.0 : 1.0 / 1.4);
    if (d == 3)
      for (std::size_t i = 0; i < 400; ++i) c.masses.push_back(i % 2 == 0 ? 1.0 : 4.0);
    const InitialState st = random_state(c, 400, 0.3, 11);
    const std::vector<double>& mass = st.config.masses;
    auto a = make_simulation(st.config, st.x, st.v), b = make_simulation(st.config, st.x, st.v);
    a->run(3000, kInf);
    b->run(3000, kInf);
    ObserveConfig oc = observe_test::config(0.0, 10, d - 1, 40);
    a->observe(oc);
    // frames every 20 collisions: the kinetic energy integrated over time (trapezoids)
    double kin = 0.0, t_prev = a->time(), k_prev = kinetic(*a, mass);
    Snapshot mid;
    for (int q = 0; q < 600; ++q) {
      a->run(20, kInf);
      b->run(20, kInf);
      const double t = a->time(), k = kinetic(*a, mass);
      kin += 0.5 * (k + k_prev) * (t - t_prev);
      t_prev = t;
      k_prev = k;
      if (q == 300) mid = a->snapshot();
    }
    CHECK(a->fault().empty());
    CHECK(a->positions() == b->positions() && a->velocities() == b->velocities());  // observing moves no bit
    {  // the observer's parabolas are the engine's: its unwrapped centres, folded, are the engine's
      const std::vector<double> x = a->positions(), u = a->observer()->unwrapped(a->time());
      double worst = 0.0;
      for (std::size_t q = 0; q < x.size(); ++q) {
        const double L = st.config.box[q % static_cast<std::size_t>(d)], e = u[q] - x[q];
        worst = std::fmax(worst, std::fabs(e - L * std::nearbyint(e / L)));
      }
      CHECK(worst < 1e-9);
    }
    const Observation r = a->observer()->results();
    const double n = 400.0;
    // the temperature is the kinetic energy the particles have, averaged over the time
    // (trapezoids between frames 20 collisions apart err by ~1e-7 here)
    CHECK(close_to(r.temperature.value, 2.0 * kin / (d * n * (r.t_end - r.t_start)), 1e-5));
    double held = 0.0, vol = 1.0;
    for (int k = 0; k < d; ++k) vol *= st.config.box[static_cast<std::size_t>(k)];
    for (double q : r.slab_density.value) held += q * vol / 10.0;
    CHECK(close_to(held, n, 1e-9));                        // every particle in a slab at every instant
    const double floor = c.gravity[f] < 0.0 ? r.slab_density.value.front() : r.slab_density.value.back();
    const double ceiling = c.gravity[f] < 0.0 ? r.slab_density.value.back() : r.slab_density.value.front();
    CHECK(floor > ceiling);                                // denser where the field pulls
    if (d >= 2) {  // the species' (by size; by mass) temperatures, weighted by their counts, are the gas's
      CHECK(r.species_temperature.size() == 2);
      double sum = 0.0;
      for (std::size_t u = 0; u < 2; ++u) sum += r.species_temperature[u].value * static_cast<double>(r.species_count[u]);
      CHECK(close_to(sum / n, r.temperature.value, 1e-12));
    }
    // resumed from the checkpoint mid-observation: the same observation, bit for bit
    auto m = restore_simulation(mid);
    CHECK(m->observing());
    for (int q = 301; q < 600; ++q) m->run(20, kInf);  // in the same calls (each run's end closes every flight)
    CHECK(m->positions() == a->positions());
    CHECK(observe_test::saved(*m->observer()) == observe_test::saved(*a->observer()));
    // and it goes back as the unobserved run does, bit for bit
    a->run_back(kAll, 0.0);
    b->run_back(kAll, 0.0);
    CHECK(!a->observing());
    CHECK(a->positions() == b->positions() && a->velocities() == b->velocities());
  }
}

TEST_CASE("the virial in a field: G(t1) - G(t0) = K2 + W + W_wall + g integral of sum m x_f (1D two masses, 2D binary)") {
  // G = sum m x . v changes at m v^2 + m g x_f between events and by x . Delta p at each: its
  // change over the observation is the observer's kinetic integral, pair and wall virials, and
  // the field's term, which frames every 20 collisions integrate (trapezoids, ~1e-7 here)
  for (int d : {1, 2}) {
    Config c;
    c.dim = d;
    c.boundary = {Boundary::wall, Boundary::wall, Boundary::wall};  // no images: x . v is one number
    const auto f = static_cast<std::size_t>(d - 1);
    c.gravity[f] = d == 2 ? -0.5 : 0.3;
    if (d == 2)
      for (std::size_t i = 0; i < 300; ++i) c.diameters.push_back(i % 2 == 0 ? 1.0 : 1.0 / 1.4);
    else
      for (std::size_t i = 0; i < 300; ++i) c.masses.push_back(i % 3 == 0 ? 2.5 : 1.0);
    const InitialState st = random_state(c, 300, 0.3, 5);
    auto m_of = [&](std::size_t q) { return st.config.masses.empty() ? 1.0 : st.config.masses[q / static_cast<std::size_t>(d)]; };
    auto s = make_simulation(st.config, st.x, st.v);
    s->run(2000, kInf);
    s->observe(observe_test::config(0.0, 0, 0, 0));
    auto g_of = [&] {
      const std::vector<double> x = s->positions(), v = s->velocities();
      double g = 0.0, h = 0.0;
      for (std::size_t q = 0; q < x.size(); ++q) g += m_of(q) * x[q] * v[q];
      for (std::size_t q = f; q < x.size(); q += static_cast<std::size_t>(d)) h += m_of(q) * x[q];
      return std::pair<double, double>{g, h};
    };
    auto [g0, h_prev] = g_of();
    double t_prev = s->time(), field = 0.0;
    for (int q = 0; q < 400; ++q) {
      s->run(20, kInf);
      const auto [g1, h] = g_of();
      field += c.gravity[f] * 0.5 * (h + h_prev) * (s->time() - t_prev);
      h_prev = h;
      t_prev = s->time();
      if (q == 399) g0 = g1 - g0;  // G(t1) - G(t0)
    }
    const Observation r = s->observer()->results();
    const double k2 = r.temperature.value * d * 300.0 * (r.t_end - r.t_start);
    const double sum = r.virial_balance.value * k2 + field;  // K2 + W + W_wall + the field's term
    std::fprintf(stderr, "    d = %d: (K2 + W + W_wall + field - Delta G) / K2 = %.3g\n", d, (sum - g0) / k2);
    CHECK(std::fabs(sum - g0) < 1e-5 * k2);
    CHECK(std::fabs(r.virial_balance.value - 1.0) > 1e-2);  // the field's term is not small: the check bites
  }
}

TEST_CASE("pair distances in a field: two disks dropped side by side, one landing first") {
  // g = -1 along y, walls all round (pair distances need them). A from (2, 5), B from (5, 7), at
  // rest but for 0.25 along x each (a gas at rest is refused): they fall alike, |r| = sqrt(13), until A lands at t = 3 (speed 3); B lands at sqrt(13).
  // Over [3, 3.5] r_y = -2 + 6 s (s = t - 3): the rate is the velocities' difference at one
  // instant (3 - (-3)), not the segments' (B's is still its start's, 0). Observed over [0, 3.5]
  Config c;
  c.dim = 2;
  c.boundary = {Boundary::wall, Boundary::wall, Boundary::wall};
  c.box = {10, 10, 1};
  c.gravity = {0.0, -1.0, 0.0};
  auto s = make_simulation(c, {2.0, 5.0, 5.0, 7.0}, {0.25, 0.0, 0.25, 0.0});  // (r_x = -3 throughout)
  ObserveConfig oc;
  oc.block_time = 10.0;
  oc.pair_bins = 50;
  oc.pair_rmax = 5.0;
  s->observe(oc);
  s->run(kAll, 3.5);
  const Observation r = s->observer()->results();
  CHECK(r.wall_reflections == 1 && r.pair_collisions == 0);
  // the time |r| < R over [3, 3.5]: |u| < sqrt(R^2 - 9) for u = -2 + 6 s in [-2, 1]
  auto below = [](double R) {
    const double q = R > 3.0 ? std::sqrt(R * R - 9.0) : 0.0;
    return std::max(0.0, std::min(q, 1.0) - std::max(-q, -2.0)) / 6.0;
  };
  double worst = 0.0;
  for (int k = 0; k < 50; ++k) {
    const double lo = 0.1 * k, hi = 0.1 * (k + 1);
    double t = below(hi) - below(lo);
    if (std::sqrt(13.0) >= lo && std::sqrt(13.0) < hi) t += 3.0;  // [0, 3] at sqrt(13)
    worst = std::fmax(worst, std::fabs(r.pair_distance.value[static_cast<std::size_t>(k)] - t / (3.5 * 0.1)));
  }
  CHECK(worst < 1e-9);
}

TEST_CASE("a field is observed along one axis; else refused by name, nothing changed") {
  Config c;
  c.dim = 2;
  c.boundary = {Boundary::wall, Boundary::wall, Boundary::periodic};
  c.box = {10, 10, 1};
  c.gravity = {-1.0, -1.0, 0.0};
  auto s = make_simulation(c, {2, 2, 5, 5}, {1, 0, -1, 0});
  CHECK(refused([&] { s->observe(ObserveConfig{}); }, "a field along more than one axis is not observed"));
  CHECK(!s->observing());
}

int main() { return check::run_all(); }
