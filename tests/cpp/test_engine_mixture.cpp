// The float engine's mixtures (Config::diameters, Config::masses): a mixture of one size is
// the one-size gas bit for bit; pairs meet at their own contact distance (D_a + D_b) / 2 and
// walls at each particle's own radius; binary gases run forward and back to round-off within
// the horizon, conserve, never overlap at their own contact distances; a 1D cradle of three
// lengths is one group; checkpoints resume bit for bit in any storage order; bad sizes are
// refused by name; the observer keeps the species. Masses: unit (or any common) masses are the
// massless gas bit for bit, a head-on pair of masses 1 and 3 leaves as the textbook says, a
// gas of two masses conserves sum m v and sum m v^2 / 2 and returns within the horizon, a group
// of unequal masses falls back to pairs, bad masses are refused by name.
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "check.hpp"
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

Config config(int d, Boundary b) {
  Config c;
  c.dim = d;
  c.boundary = {b, b, b};
  return c;
}

// Alternating sizes 1 and 1 / ratio (id even: large).
std::vector<double> binary(std::size_t n, double ratio) {
  std::vector<double> d(n);
  for (std::size_t i = 0; i < n; ++i) d[i] = i % 2 == 0 ? 1.0 : 1.0 / ratio;
  return d;
}

bool same_state(const Simulation& a, const Simulation& b) {
  const Snapshot p = a.snapshot(), q = b.snapshot();
  return p.x == q.x && p.v == q.v && p.t_local == q.t_local && p.ev_t == q.ev_t && p.rng == q.rng &&
         p.time == q.time && p.ncoll == q.ncoll;
}


double max_error(const std::vector<double>& a, const std::vector<double>& b) {
  double e = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) e = std::fmax(e, std::fabs(a[i] - b[i]));
  return e;
}

}  // namespace

TEST_CASE("a mixture of one size is the one-size gas, bit for bit (1D, 2D, 3D; walls and periodic)") {
  struct Case {
    int d;
    Boundary b;
    double phi;
    int resort;
  };
  for (const Case k : {Case{1, Boundary::wall, 0.5, -1}, Case{1, Boundary::periodic, 0.5, -1},
                       Case{2, Boundary::periodic, 0.5, 1}, Case{2, Boundary::wall, 0.4, -1},
                       Case{3, Boundary::periodic, 0.4, -1}, Case{3, Boundary::bounce, 0.3, 1}}) {
    Config c = config(k.d, k.b);
    c.resort = k.resort;
    const InitialState st = random_state(c, 300, k.phi, 5);
    Config m = st.config;
    m.diameters.assign(300, st.config.diameter);
    auto one = make_simulation(st.config, st.x, st.v);
    auto mix = make_simulation(m, st.x, st.v);
    one->run(3000, kInf);
    mix->run(3000, kInf);
    CHECK(same_state(*one, *mix));
    one->run_back(kAll, 0.0);
    mix->run_back(kAll, 0.0);
    CHECK(same_state(*one, *mix));
  }
}

TEST_CASE("a pair meets at its own contact distance, and a wall at the particle's own radius") {
  // 2D periodic: a disk of diameter 1 and one of 0.5 head on, 3 apart: contact at 0.75, t = 1.125
  Config c = config(2, Boundary::periodic);
  c.box = {10, 10, 1};
  c.diameter = 1.0;
  c.diameters = {1.0, 0.5};
  auto s = make_simulation(c, {2, 5, 5, 5}, {1, 0, -1, 0});
  CHECK(s->run(kAll, 1.1249).collisions == 0);
  CHECK(s->run(kAll, 1.1251).collisions == 1);
  // walls: the small disk (radius 0.25) starts 1 from its contact plane x = 0.25, speed 1;
  // with the largest radius it would reflect at t = 0.75
  Config w = config(2, Boundary::wall);
  w.box = {10, 10, 1};
  w.diameter = 1.0;
  w.diameters = {0.5, 1.0};
  auto b = make_simulation(w, {1.25, 5, 8, 8}, {-1, 0, 0, 0.1});
  b->run(kAll, 0.999);
  CHECK(b->velocities()[0] == -1.0);
  b->run(kAll, 1.5);
  CHECK(b->velocities()[0] == 1.0);
  CHECK(std::fabs(b->positions()[0] - 0.75) < 1e-12);
}

TEST_CASE("binary mixtures (size ratio 1.4): forward and back within the horizon, conserved, never overlapping") {
  struct Case {
    int d;
    Boundary b;
    double phi;
  };
  for (const Case k : {Case{2, Boundary::periodic, 0.5}, Case{2, Boundary::wall, 0.5}, Case{3, Boundary::periodic, 0.4},
                       Case{3, Boundary::wall, 0.3}, Case{1, Boundary::periodic, 0.5}}) {
    Config c = config(k.d, k.b);
    c.diameters = binary(400, 1.4);
    const InitialState st = random_state(c, 400, k.phi, 7);
    CHECK(st.config.diameter == 1.0);
    auto s = make_simulation(st.config, st.x, st.v);
    const auto x0 = s->positions(), v0 = s->velocities();
    s->run(400, kInf);  // one collision per particle: within the round-off horizon
    CHECK(s->fault().empty());
    s->run_back(kAll, 0.0);
    CHECK(s->diagnostics().net_collisions == 0);
    CHECK(max_error(s->positions(), x0) < 1e-9 * st.config.box[0]);
    CHECK(max_error(s->velocities(), v0) < 1e-9);
    // 20 collisions per particle: conserved to round-off, no pair closer than its contact
    s->run(8000, kInf);
    const std::string f = s->fault();
    CHECK(f.empty());
    if (!f.empty()) std::fprintf(stderr, "    %s\n", f.c_str());
    CHECK(std::fabs(s->diagnostics().energy_drift) < 1e-12);
    std::printf("  %dD %s: groups %llu, walls %llu\n", k.d, to_string(k.b),
                static_cast<unsigned long long>(s->diagnostics().counters.group_collisions),
                static_cast<unsigned long long>(s->diagnostics().counters.wall_events));
  }
}

TEST_CASE("a 1D cradle of three lengths at rest, hit by a fourth: one group, reversed") {
  Config c = config(1, Boundary::wall);
  c.box = {30, 1, 1};
  c.diameter = 1.0;
  c.diameters = {1.0, 0.5, 0.75, 1.0};
  // contacts at (1 + 0.5) / 2, (0.5 + 0.75) / 2 and (0.75 + 1) / 2: 10, 10.625, 11.5
  auto s = make_simulation(c, {5.0, 10.0, 10.625, 11.5}, {1.0, 0.0, 0.0, 0.0});
  const auto x0 = s->positions(), v0 = s->velocities();
  s->run(kAll, 6.0);
  const Counters f = s->diagnostics().counters;
  CHECK(f.group_collisions == 1);
  CHECK(f.group_particles == 4);
  s->run_back(kAll, 0.0);
  CHECK(max_error(s->positions(), x0) < 1e-9);
  CHECK(max_error(s->velocities(), v0) < 1e-9);
}

TEST_CASE("a mixture's checkpoint resumes bit for bit, in any storage order") {
  for (int d : {2, 3}) {
    Config c = config(d, Boundary::periodic);
    c.diameters = binary(500, 1.4);
    const InitialState st = random_state(c, 500, d == 2 ? 0.5 : 0.4, 11);
    auto a = make_simulation(st.config, st.x, st.v);
    auto b = make_simulation(st.config, st.x, st.v);
    a->run(3000, kInf);
    b->run(1300, kInf);
    auto r = restore_simulation(b->snapshot());
    r->run(1700, kInf);
    CHECK(same_state(*a, *r));
    Config sorted = st.config;
    sorted.resort = 1;  // the storage re-sorted after every renewal per particle (the radii move with it)
    auto q = make_simulation(sorted, st.x, st.v);
    q->run(3000, kInf);
    CHECK(q->positions() == a->positions());
    CHECK(q->velocities() == a->velocities());
    CHECK(q->diagnostics().storage_resorts > 0);
  }
}

TEST_CASE("bad sizes are refused by name, nothing built") {
  Config c = config(2, Boundary::wall);
  c.box = {10, 10, 1};
  c.diameter = 1.0;
  const std::vector<double> x = {2, 2, 5, 5}, v = {1, 0, -1, 0};
  c.diameters = {1.0};
  CHECK(refused([&] { make_simulation(c, x, v); }, "one entry per particle (2)"));
  c.diameters = {0.5, 0.8};
  CHECK(refused([&] { make_simulation(c, x, v); }, "must be the largest of the diameters"));
  c.diameters = {1.0, 0.05};
  CHECK(refused([&] { make_simulation(c, x, v); }, "more than 16 times smaller"));
  c.diameters = {1.0, NAN};
  CHECK(refused([&] { make_simulation(c, x, v); }, "diameter of particle 1 must be finite"));
  // overlap at the pair's own contact distance 0.75; 0.8 apart is allowed (under the largest D)
  c.diameters = {1.0, 0.5};
  CHECK(refused([&] { make_simulation(c, {2, 2, 2.7, 2}, v); }, "contact distance 0.75"));
  CHECK(make_simulation(c, {2, 2, 2.8, 2}, v) != nullptr);
  // walls: the small one's centre at least its own radius 0.25 inside
  CHECK(make_simulation(c, {2, 2, 0.3, 5}, v) != nullptr);
  CHECK(refused([&] { make_simulation(c, {2, 2, 0.2, 5}, v); }, "outside the box"));
  // a snapshot whose sizes were damaged
  auto s = make_simulation(c, x, v);
  Snapshot snap = s->snapshot();
  snap.config.diameters = {1.0, 0.5, 0.5};
  CHECK(refused([&] { restore_simulation(snap); }, "snapshot: diameters"));
  snap.config.diameters = {0.9, 0.5};
  CHECK(refused([&] { restore_simulation(snap); }, "snapshot: diameter must be the largest"));
}

TEST_CASE("the observer keeps a mixture's species (by size, ascending)") {
  Config c = config(3, Boundary::periodic);
  c.diameters = binary(400, 1.4);
  const InitialState st = random_state(c, 400, 0.3, 13);
  auto s = make_simulation(st.config, st.x, st.v);
  s->observe(ObserveConfig{});
  s->run(20000, kInf);
  const Observation o = s->observer()->results();
  REQUIRE(o.species_count.size() == 2);
  CHECK(o.species_count[0] == 200 && o.species_count[1] == 200);
  CHECK(std::fabs(o.species_diameter[0] - 1.0 / 1.4) < 1e-15 && o.species_diameter[1] == 1.0);
  double sum = 0.0;
  for (const Estimate& p : o.species_pressure) sum += p.value;
  CHECK(std::fabs(sum - o.pressure_virial.value) < 1e-9 * o.pressure_virial.value);
  // a resumed observation keeps them
  auto r = restore_simulation(s->snapshot());
  r->run(1000, kInf);
  s->run(1000, kInf);
  CHECK(r->observer()->results().species_temperature[0].value == s->observer()->results().species_temperature[0].value);
}

TEST_CASE("unit or common masses are the massless gas, bit for bit") {
  for (int d : {2, 3}) {
    Config c = config(d, d == 2 ? Boundary::periodic : Boundary::wall);
    const InitialState st = random_state(c, 300, 0.4, 3);
    auto plain = make_simulation(st.config, st.x, st.v);
    Config one = st.config, two = st.config;
    one.masses.assign(300, 1.0);
    two.masses.assign(300, 2.0);
    auto a = make_simulation(one, st.x, st.v), b = make_simulation(two, st.x, st.v);
    for (auto* s : {plain.get(), a.get(), b.get()}) s->run(3000, kInf);
    CHECK(same_state(*plain, *a));
    CHECK(plain->positions() == b->positions() && plain->velocities() == b->velocities());
    CHECK(b->diagnostics().energy == 2.0 * plain->diagnostics().energy);
  }
}

TEST_CASE("a head-on pair of masses 1 and 3 leaves with the textbook's velocities") {
  // v1' = (m1 - m2) / M v1 = -v1 / 2, v2' = 2 m1 / M v1 = v1 / 2 (1D exact mode; 2D specular)
  Config c = config(1, Boundary::wall);
  c.box = {20, 1, 1};
  c.masses = {1.0, 3.0};
  auto s = make_simulation(c, {2.0, 5.0}, {1.0, 0.0});
  s->run(kAll, 2.5);
  CHECK(s->velocities() == std::vector<double>({-0.5, 0.5}));
  Config p = config(2, Boundary::wall);
  p.box = {20, 20, 1};
  p.mode = Mode::specular;
  p.masses = {1.0, 3.0};
  auto q = make_simulation(p, {2.0, 5.0, 5.0, 5.0}, {1.0, 0.0, 0.0, 0.0});
  q->run(kAll, 2.5);
  const auto v = q->velocities();
  CHECK(std::fabs(v[0] + 0.5) < 1e-15 && std::fabs(v[2] - 0.5) < 1e-15 && v[1] == 0.0 && v[3] == 0.0);
}

TEST_CASE("a gas of two masses (1 and 4): momentum and energy kept, back within the horizon") {
  for (int d : {1, 2, 3}) {
    Config c = config(d, d == 1 ? Boundary::periodic : d == 2 ? Boundary::periodic : Boundary::wall);
    c.masses.resize(400);
    for (std::size_t i = 0; i < 400; ++i) c.masses[i] = i % 2 == 0 ? 1.0 : 4.0;
    c.diameters = d == 3 ? binary(400, 1.4) : std::vector<double>{};  // sizes and masses together in 3D
    const InitialState st = random_state(c, 400, d == 3 ? 0.3 : 0.5, 5);
    auto s = make_simulation(st.config, st.x, st.v);
    const auto x0 = s->positions(), v0 = s->velocities();
    const Diagnostics g0 = s->diagnostics();
    if (d < 3)  // the start's centre of mass is at rest
      for (int k = 0; k < d; ++k) CHECK(std::fabs(g0.momentum[k]) < 1e-12 * std::sqrt(2.0 * g0.energy * 1000.0));
    s->run(400, kInf);
    s->run_back(kAll, 0.0);
    CHECK(max_error(s->positions(), x0) < 1e-9 * st.config.box[0]);
    CHECK(max_error(s->velocities(), v0) < 1e-9);
    s->run(8000, kInf);
    const Diagnostics g = s->diagnostics();
    CHECK(s->fault().empty());
    CHECK(std::fabs(g.energy_drift) < 1e-12);
    if (d < 3) CHECK(g.momentum_drift < 1e-12);  // (walls in 3D: not conserved)
  }
}

TEST_CASE("a group of unequal masses falls back to pairs: conserving, and the trace reports its reversal") {
  // Newton's cradle of masses 1, 2, 2: the group operator collides equal masses only, so the
  // contact is two pairs in id order, 0-1 then 1-2 (the textbook's sequential limit: -1/3, 0,
  // 2/3). Reversed, both contacts meet at one instant again and the queue undoes 0-1 first, so
  // the instant does not retrace: the collision trace says so (a random gas has no such
  // instants; docs/mixtures.md).
  Config c = config(1, Boundary::wall);
  c.box = {30, 1, 1};
  c.masses = {1.0, 2.0, 2.0};
  auto s = make_simulation(c, {5.0, 10.0, 11.0}, {1.0, 0.0, 0.0});
  const auto x0 = s->positions(), v0 = s->velocities();
  s->run(kAll, 6.0);
  const Counters f = s->diagnostics().counters;
  CHECK(f.group_collisions == 0);
  CHECK(f.group_fallbacks >= 1);
  CHECK(std::fabs(s->diagnostics().energy_drift) < 1e-15);
  const auto v = s->velocities();
  CHECK(std::fabs(v[0] + 1.0 / 3.0) < 1e-15 && v[1] == 0.0 && std::fabs(v[2] - 2.0 / 3.0) < 1e-15);
  s->run_back(kAll, 0.0);
  CHECK(s->diagnostics().divergence != Divergence::none);
  (void)x0;
  (void)v0;
}

TEST_CASE("masses: checkpoints resume bit for bit, the observer weighs them, bad masses are refused by name") {
  Config c = config(2, Boundary::wall);
  c.masses.resize(300);
  for (std::size_t i = 0; i < 300; ++i) c.masses[i] = i % 3 == 0 ? 5.0 : 1.0;
  const InitialState st = random_state(c, 300, 0.3, 9);
  auto a = make_simulation(st.config, st.x, st.v);
  a->observe(ObserveConfig{});
  a->run(2000, kInf);
  auto r = restore_simulation(a->snapshot());
  a->run(3000, kInf);
  r->run(3000, kInf);
  CHECK(same_state(*a, *r));
  const Observation o = a->observer()->results(), q = r->observer()->results();
  CHECK(o.temperature.value == q.temperature.value && o.pressure_virial.value == q.pressure_virial.value);
  REQUIRE(o.species_mass.size() == 2);
  CHECK(o.species_mass[0] == 1.0 && o.species_mass[1] == 5.0 && o.species_count[0] == 200);
  CHECK(std::fabs(o.temperature.value - 1.0) < 0.05);  // sum m v^2 / (d N): the start's kT = 1
  Config bad = config(2, Boundary::wall);
  bad.box = {10, 10, 1};
  const std::vector<double> x = {2, 2, 5, 5}, v = {1, 0, -1, 0};
  bad.masses = {1.0};
  CHECK(refused([&] { make_simulation(bad, x, v); }, "masses must have one entry per particle (2)"));
  bad.masses = {1.0, 0.0};
  CHECK(refused([&] { make_simulation(bad, x, v); }, "mass of particle 1 must be finite and > 0"));
  bad.masses = {1.0, 2e6};
  CHECK(refused([&] { make_simulation(bad, x, v); }, "ratio"));
  bad.masses = {1.0, 2.0};
  bad.mode = Mode::paper;
  CHECK(refused([&] { make_simulation(bad, x, v); }, "paper mode collides equal masses only"));
  Snapshot snap = a->snapshot();
  snap.config.masses.pop_back();
  CHECK(refused([&] { restore_simulation(snap); }, "snapshot: masses"));
}

// ---- a uniform field (Config::gravity) ----

TEST_CASE("gravity: a lone disk bounces on the floor on its exact parabola, forward and back") {
  // g = -2 along y, floor contact at y = 0.5: from y = 4.5 at rest it lands at t = 2 (speed 4)
  // and rises back to 4.5 at t = 4; in x it flies at 0.25 on a periodic axis
  Config c = config(2, Boundary::wall);
  c.boundary = {Boundary::periodic, Boundary::wall, Boundary::periodic};
  c.box = {10, 10, 1};
  c.gravity = {0.0, -2.0, 0.0};
  auto s = make_simulation(c, {1.0, 4.5, 8.0, 8.0}, {0.25, 0.0, 0.0, 0.0});
  s->run(kAll, 1.0);
  CHECK(std::fabs(s->positions()[1] - 3.5) < 1e-12 && std::fabs(s->velocities()[1] + 2.0) < 1e-12);
  s->run(kAll, 3.0);  // bounced at t = 2: rising at 2 from 0.5, at t = 3 y = 0.5 + 4 - 1 = 3.5
  CHECK(std::fabs(s->positions()[1] - 3.5) < 1e-12 && std::fabs(s->velocities()[1] - 2.0) < 1e-12);
  CHECK(s->diagnostics().counters.wall_events == 2);  // (the other disk, dropped from 8, lands at t = sqrt(7.5))
  CHECK(std::fabs(s->diagnostics().energy_drift) < 1e-15);
  s->run(kAll, 4.0);
  CHECK(std::fabs(s->positions()[1] - 4.5) < 1e-12 && std::fabs(s->velocities()[1]) < 1e-12);
  s->run_back(kAll, 0.0);
  CHECK(std::fabs(s->positions()[1] - 4.5) < 1e-12 && std::fabs(s->positions()[0] - 1.0) < 1e-12);
}

TEST_CASE("gravity: gases keep kinetic plus potential energy and return within the horizon") {
  for (int d : {1, 2, 3}) {
    Config c = config(d, Boundary::periodic);
    c.boundary[static_cast<std::size_t>(d - 1)] = d == 3 ? Boundary::bounce : Boundary::wall;  // the field's axis
    c.gravity[static_cast<std::size_t>(d - 1)] = d == 2 ? -0.5 : 0.3;                         // down; up in 1D and 3D
    if (d == 2) c.diameters = binary(400, 1.4);
    const InitialState st = random_state(c, 400, 0.3, 7);
    auto s = make_simulation(st.config, st.x, st.v);
    const auto x0 = s->positions(), v0 = s->velocities();
    CHECK(s->diagnostics().potential > 0.0);
    s->run(400, kInf);
    CHECK(s->fault().empty());
    s->run_back(kAll, 0.0);
    CHECK(s->diagnostics().divergence == Divergence::none);
    for (std::size_t q = 0; q < x0.size(); ++q) {  // periodic images folded
      const double L = st.config.box[q % static_cast<std::size_t>(d)], e = std::fabs(s->positions()[q] - x0[q]);
      CHECK(std::fmin(e, std::fabs(e - L)) < 1e-9 * L);
    }
    CHECK(max_error(s->velocities(), v0) < 1e-9);
    s->run(20000, kInf);
    const std::string f = s->fault();
    CHECK(f.empty());
    if (!f.empty()) std::fprintf(stderr, "    %s\n", f.c_str());
    CHECK(std::fabs(s->diagnostics().energy_drift) < 1e-12);
    auto r = restore_simulation(s->snapshot());  // and a checkpoint resumes bit for bit
    s->run(3000, kInf);
    r->run(3000, kInf);
    CHECK(same_state(*s, *r));
  }
}

TEST_CASE("gravity: refused by name on a periodic axis (observed: test_float_field_observe.cpp)") {
  Config c = config(2, Boundary::periodic);
  c.box = {10, 10, 1};
  c.gravity = {0.0, -1.0, 0.0};
  CHECK(refused([&] { make_simulation(c, {2, 2, 5, 5}, {1, 0, -1, 0}); }, "gravity along axis 1 needs walls"));
  c.boundary[1] = Boundary::wall;
  c.gravity[1] = NAN;
  CHECK(refused([&] { make_simulation(c, {2, 2, 5, 5}, {1, 0, -1, 0}); }, "gravity must be finite"));
}

int main() { return check::run_all(); }
