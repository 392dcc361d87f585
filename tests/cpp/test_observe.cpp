// The observer (revcol/engine/observe.hpp): constructed motions with answers worked out by
// hand (a 1D head-on pair, a rod between walls, a free flight across periodic images, a
// cradle), the virial balance of a closed gas, that observing changes no trajectory,
// forward-only observation, and validation.
#include <cmath>
#include <limits>
#include <cstdint>
#include <memory>
#include <vector>

#include "check.hpp"
#include "revcol/engine/engine.hpp"
#include "revcol/engine/init.hpp"
#include "revcol/engine/observe.hpp"
#include "revcol/error.hpp"

using namespace revcol;
using namespace revcol::engine;

namespace {

constexpr std::uint64_t kAll = ~std::uint64_t{0};
constexpr double kInfinity = std::numeric_limits<double>::infinity();

Config walled(int d, double L, Mode mode = Mode::specular) {
  Config c;
  c.dim = d;
  c.boundary = {Boundary::wall, Boundary::wall, Boundary::wall};
  c.box = {L, L, L};
  c.mode = mode;
  return c;
}

bool same(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }
bool same(const Estimate& a, const Estimate& b) { return same(a.value, b.value) && same(a.error, b.error); }
bool same(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t k = 0; k < a.size(); ++k)
    if (!same(a[k], b[k])) return false;
  return true;
}
bool same(const Profile& a, const Profile& b) {
  return same(a.edges, b.edges) && same(a.value, b.value) && same(a.error, b.error);
}

// Every result of two observations, bit for bit.
bool same(const Observation& a, const Observation& b) {
  bool ok = a.dim == b.dim && a.n == b.n && same(a.t_start, b.t_start) && same(a.t_end, b.t_end) &&
            a.blocks == b.blocks && same(a.block_time, b.block_time) && a.pair_collisions == b.pair_collisions &&
            a.group_collisions == b.group_collisions && a.particle_collisions == b.particle_collisions &&
            a.wall_reflections == b.wall_reflections;
  for (const auto m : {&Observation::temperature, &Observation::pressure_virial, &Observation::compressibility,
                       &Observation::collision_rate, &Observation::mean_free_time, &Observation::mean_free_path,
                       &Observation::virial_balance})
    ok = ok && same(a.*m, b.*m);
  for (int k = 0; k < 3; ++k) ok = ok && same(a.pressure_wall[k], b.pressure_wall[k]);
  for (const auto m : {&Observation::slab_density, &Observation::slab_temperature, &Observation::speed,
                       &Observation::pair_distance})
    ok = ok && same(a.*m, b.*m);
  return ok && same(a.msd_time, b.msd_time) && same(a.msd, b.msd) && same(a.vacf, b.vacf) &&
         a.helfand_components == b.helfand_components && same(a.helfand, b.helfand);
}

}  // namespace

TEST_CASE("1D head-on pair: virial, Z, collision rate and pair distances by hand") {
  // rods at 2 and 5 closing at speed 2: contact at t = 1, r = x_a - x_b = -1, dp_a = -2
  auto s = make_simulation(walled(1, 10.0), {2.0, 5.0}, {1.0, -1.0});
  ObserveConfig oc;
  oc.pair_bins = 50;
  oc.pair_rmax = 5.0;
  oc.speed_bins = 4;
  oc.speed_max = 2.0;
  s->observe(oc);
  s->run(kAll, 0.5);  // before the collision: |r| runs 3 -> 2, uniformly
  Observation o = s->observer()->results();
  for (int k = 20; k < 30; ++k) CHECK_NEAR(o.pair_distance.value[k], 1.0, 1e-12);
  CHECK_NEAR(o.pair_distance.value[19] + o.pair_distance.value[30], 0.0, 1e-12);
  CHECK_NEAR(o.speed.value[2], 2.0, 1e-12);  // every speed is 1: bin [1, 1.5) holds it all, density 1 / 0.5
  s->run(kAll, 1.5);
  o = s->observer()->results();
  CHECK(o.pair_collisions == 1);
  CHECK(o.particle_collisions == 2);
  CHECK_NEAR(o.t_end - o.t_start, 1.5, 1e-15);
  CHECK_NEAR(o.temperature.value, 1.0, 1e-12);                  // K2 = 2 x 1.5, T = K2 / (d N tau)
  CHECK_NEAR(o.compressibility.value, 1.0 + 2.0 / 3.0, 1e-12);  // 1 + W / K2, W = 2
  CHECK_NEAR(o.pressure_virial.value, 5.0 / 15.0, 1e-12);       // (K2 + W) / (d V tau)
  CHECK_NEAR(o.collision_rate.value, 2.0 / 3.0, 1e-12);
  CHECK_NEAR(o.mean_free_time.value, 1.5, 1e-12);
  CHECK_NEAR(o.mean_free_path.value, 1.5, 1e-12);  // 3 units flown over 2 particle collisions
}

TEST_CASE("a rod between walls: wall pressure, slab occupancy, speeds") {
  // walls for the centre at 0.5 and 3.5; from 2 to the right: reflections at 1.5, 4.5, 7.5, 10.5
  auto s = make_simulation(walled(1, 4.0), {2.0}, {1.0});
  ObserveConfig oc;
  oc.slabs = 4;
  s->observe(oc);
  s->run(kAll, 12.0);  // two full periods
  const Observation o = s->observer()->results();
  CHECK(o.wall_reflections == 4);
  CHECK_NEAR(o.pressure_wall[0].value, 8.0 / (2.0 * 12.0), 1e-12);
  const double expect[4] = {1.0 / 6, 1.0 / 3, 1.0 / 3, 1.0 / 6};  // the centre never reaches [0, 0.5)
  for (int k = 0; k < 4; ++k) {
    CHECK_NEAR(o.slab_density.value[k], expect[k], 1e-12);
    CHECK_NEAR(o.slab_temperature.value[k], 1.0, 1e-12);
  }
  CHECK_NEAR(o.virial_balance.value, 0.0, 1e-12);  // whole periods: K2 + W_wall = 0
}

TEST_CASE("species by hand: a head-on pair of two sizes, partial pressures, temperatures, MSD; resumed") {
  // 1D, walls at 0 and 10; a (radius 1/4) at 1 moving +1, b (radius 1/2) at 3 moving -1: they
  // touch at 2 - 2t = 3/4, t = 5/8, and swap velocities; r . dp_a = (-3/4)(-2) = 3/2, half to each
  ObserveConfig oc;
  oc.block_time = 0.5;
  Observer o(oc, 1, {1.0, 3.0}, {1.0, -1.0}, 0.0, {10.0, 1.0, 1.0}, {true, false, false}, 1.0);
  o.set_species({0, 1}, {0.25, 0.5});
  const double xa = 1.625, xb = 2.375, va = -1.0, vb = 1.0;
  o.pair_at(0.625, 0, 1, &xa, &xb, &va, &vb);
  std::vector<double> reals;
  std::vector<std::uint64_t> counts;
  o.save(reals, counts);
  o.sync(1.0);
  const Observation r = o.results();
  CHECK(r.species_count == (std::vector<std::size_t>{1, 1}));
  CHECK(same(r.species_diameter, {0.5, 1.0}));
  for (int s = 0; s < 2; ++s) {
    CHECK_NEAR(r.species_temperature[s].value, 1.0, 1e-15);
    CHECK_NEAR(r.species_pressure[s].value, (1.0 + 0.75) / 10.0, 1e-15);
  }
  CHECK_NEAR(r.pressure_virial.value, 0.35, 1e-15);
  // block ends 0.5 (each moved 1/2) and 1 (each 1/4 from its start)
  CHECK(same(r.species_msd, {0.25, 0.25, 0.0625, 0.0625}));
  // resumed from the snapshot taken after the collision: the same results, bit for bit
  Observer back(reals, counts, 1, {va, vb}, 0.625, {10.0, 1.0, 1.0}, {true, false, false}, 1.0);
  back.set_species({0, 1}, {0.25, 0.5});
  back.sync(1.0);
  const Observation q = back.results();
  CHECK(same(q, r));
  CHECK(same(q.species_msd, r.species_msd));
  for (int s = 0; s < 2; ++s)
    CHECK(same(q.species_pressure[s], r.species_pressure[s]) && same(q.species_temperature[s], r.species_temperature[s]));
  // bad species: named, and a snapshot's species count must match
  Observer fresh(oc, 1, {1.0, 3.0}, {1.0, -1.0}, 0.0, {10.0, 1.0, 1.0}, {true, false, false}, 1.0);
  CHECK_THROWS_AS(fresh.set_species({0}, {0.25}), InvalidArgument);
  CHECK_THROWS_AS(fresh.set_species({0, 2}, {0.25, 0.5}), InvalidArgument);  // species 1 empty
  CHECK_THROWS_AS(fresh.set_species({0, -1}, {0.25, 0.5}), InvalidArgument);
  CHECK_THROWS_AS(fresh.set_species({0, 1}, {0.25, 0.6}), InvalidArgument);  // above D / 2
  CHECK_THROWS_AS(fresh.set_species({0, 1}, {0.0, 0.5}), InvalidArgument);
  Observer other(reals, counts, 1, {va, vb}, 0.625, {10.0, 1.0, 1.0}, {true, false, false}, 1.0);
  CHECK_THROWS_AS(other.set_species({0, 0}, {0.5, 0.5}), InvalidArgument);  // one species, the snapshot kept two
  CHECK_THROWS_AS(o.set_species({0, 1}, {0.25, 0.5}), InvalidArgument);     // after events
  // one species keeps none of it
  Observer one(oc, 1, {1.0, 3.0}, {1.0, -1.0}, 0.0, {10.0, 1.0, 1.0}, {true, false, false}, 1.0);
  one.sync(1.0);
  CHECK(one.results().species_count.empty() && one.results().species_msd.empty());
}

TEST_CASE("species: a group's virial shares about its centroid, whatever the origin") {
  // a 1D cradle of three (species 0, 1, 1) meets at t = 1 at x = 3, 4, 5 (or the same 10 to the
  // right): velocities 1, 0, -1 -> -1, 0, 1. Shares (x_u - 4) . Delta p_u: 2 to species 0, 0 + 2
  // to species 1 (their sum, 4, is the group's virial); K2 per species 2 over tau = 2, V = 10
  for (const double shift : {0.0, 10.0}) {
    ObserveConfig oc;
    oc.block_time = 100.0;
    Observer o(oc, 1, {2.0 + shift, 4.0 + shift, 6.0 + shift}, {1.0, 0.0, -1.0}, 0.0, {10.0, 1.0, 1.0},
               {false, false, false}, 1.0);
    o.set_species({0, 1, 1}, {0.5, 0.5, 0.5});
    const int ids[3] = {0, 1, 2};
    const double x[3] = {3.0 + shift, 4.0 + shift, 5.0 + shift}, v[3] = {-1.0, 0.0, 1.0};
    o.group(1.0, 3, ids, x, v);
    o.sync(2.0);
    const Observation r = o.results();
    CHECK_NEAR(r.species_pressure[0].value, (2.0 + 2.0) / 20.0, 1e-15);
    CHECK_NEAR(r.species_pressure[1].value, (2.0 + 2.0) / 20.0, 1e-15);
    CHECK_NEAR(r.pressure_virial.value, (4.0 + 4.0) / 20.0, 1e-15);
  }
}

TEST_CASE("periodic free flight: unwrapped mean squared displacement, blocks of equal time") {
  Config c;
  c.dim = 2;
  c.box = {3.0, 3.0, 1.0};
  auto s = make_simulation(c, {1.0, 1.0}, {1.0, 0.5});
  ObserveConfig oc;
  oc.block_time = 2.0;
  oc.slabs = 4;  // along x, across the periodic images: 14 whole crossings fill them evenly
  s->observe(oc);
  s->run(kAll, 42.0);
  const Observation o = s->observer()->results();
  REQUIRE(o.msd.size() == 21);
  for (std::size_t k = 0; k < o.msd.size(); ++k) {
    CHECK_NEAR(o.msd_time[k], 2.0 * (k + 1), 1e-12);
    CHECK_NEAR(o.msd[k], 1.25 * o.msd_time[k] * o.msd_time[k], 1e-9);
    CHECK_NEAR(o.helfand[k], 0.5 * o.msd_time[k], 1e-12);  // I_xy = integral of v_x v_y: no collisions
  }
  CHECK(o.helfand_components == 1 && o.helfand.size() == 21);
  CHECK(o.blocks == 21);  // min_blocks 16: 21 complete blocks stay as they are
  CHECK_NEAR(o.temperature.error, 0.0, 1e-15);
  for (int k = 0; k < 4; ++k) CHECK_NEAR(o.slab_density.value[k], 1.0 / 9.0, 1e-12);
}

TEST_CASE("a 1D cradle: a group's virial sums x . dp over its members") {
  auto s = make_simulation(walled(1, 10.0, Mode::exact), {2.0, 4.0, 6.0}, {1.0, 0.0, -1.0});
  s->observe(ObserveConfig{});
  s->run(kAll, 1.5);  // both contacts close at t = 1 (x = 3, 4, 5): one group of three
  const Observation o = s->observer()->results();
  REQUIRE(o.group_collisions == 1);
  CHECK(o.particle_collisions == 3);
  const auto v = s->velocities();
  const double pre[3] = {1.0, 0.0, -1.0}, x[3] = {3.0, 4.0, 5.0};
  double w = 0.0, k2 = 2.0 * 1.0;  // K2 before: 2 per unit time
  double k2_after = 0.0;
  for (int u = 0; u < 3; ++u) {
    w += x[u] * (v[u] - pre[u]);
    k2_after += v[u] * v[u];
  }
  k2 = k2 * 1.0 + k2_after * 0.5;
  CHECK(w > 0.0);
  CHECK_NEAR(o.compressibility.value, 1.0 + w / k2, 1e-9);
}

TEST_CASE("a refused group's wall reflections are not observed: impulses are those that happened") {
  // A rigid train (particles 1..4, touching, speed -2) catches particle 0 (speed -1) at t = 1,
  // when 0 is 2^-34 short of the left wall (within group_tol): the contacts make a chain of
  // five, four contacts, which ExactCollision refuses (at most 3). The group reflected 0 off
  // the wall (W1) and undid it; the pair that follows does it for real. Until nothing has
  // reached the right wall, every impulse is on the left wall and positive, so their sum is
  // the momentum gained: sum |dp| = P(t) - P(0) (a counted-twice W1 adds 2 |dv| = 4).
  const double e = std::ldexp(1.0, -34);
  Config c = walled(1, 10.0, Mode::exact);
  c.force_group_search = true;
  auto s = make_simulation(c, {1.5 + e, 3.5 + e, 4.5 + e, 5.5 + e, 6.5 + e}, {-1.0, -2.0, -2.0, -2.0, -2.0});
  const double p0 = s->diagnostics().momentum[0];
  s->observe(ObserveConfig{});
  s->run(kAll, 1.25);
  const Observation o = s->observer()->results();
  const Diagnostics d = s->diagnostics();
  REQUIRE(d.counters.group_fallbacks >= 1);
  for (double x : s->positions()) REQUIRE(x < 9.0);  // nothing near the right wall yet
  const double tau = o.t_end - o.t_start;
  const double impulse = o.pressure_wall[0].value * 2.0 * tau;  // P_wall = sum |dp| / (2 tau A), A = 1
  CHECK(d.momentum[0] - p0 > 0.0);
  CHECK_NEAR(impulse, d.momentum[0] - p0, 1e-12);
  // (the refused W1 and its undoing add opposite virials x dv, so only the impulse shows it)
  // the engine's counter counts the reflections that happened, as the observer does (the
  // refused W1 and its undoing are not events; they once counted twice)
  CHECK(o.wall_reflections >= 1);
  CHECK(d.counters.wall_events == o.wall_reflections);
}

TEST_CASE("a closed 2D gas: K2 + W + W_wall -> 0; temperature from the energy; walls share the pressure") {
  Config c = walled(2, 1.0, Mode::exact);
  const InitialState st = random_state(c, 200, 0.3, 5);
  auto s = make_simulation(st.config, st.x, st.v);
  s->run(4000, kInfinity);
  // G = sum x . v: between events dG/dt = sum v^2, at an event G jumps by x . dv, so over the
  // observation K2 + W + W_wall = G(end) - G(start) exactly (the balance is a boundary term,
  // G bounded in a closed box, not noise that averages out)
  const auto G = [&] {
    const std::vector<double> x = s->positions(), v = s->velocities();
    double g = 0.0;
    for (std::size_t k = 0; k < x.size(); ++k) g += x[k] * v[k];
    return g;
  };
  const double g0 = G();
  ObserveConfig oc;
  oc.slabs = 5;
  s->observe(oc);
  s->run(100000, kInfinity);
  const Observation o = s->observer()->results();
  const Diagnostics d = s->diagnostics();
  CHECK_NEAR(o.temperature.value, d.energy / 200.0, 1e-9 * d.energy / 200.0);  // T = 2E / (d N)
  const double k2 = o.temperature.value * 2.0 * 200.0 * (o.t_end - o.t_start);  // K2 = d N T tau
  const double dg = G() - g0;
  std::printf("  virial balance %.3e +- %.3e (blocks %d): K2 + W + W_wall = %.6g, G(end) - G(start) = %.6g\n",
              o.virial_balance.value, o.virial_balance.error, o.blocks, o.virial_balance.value * k2, dg);
  CHECK_NEAR(o.virial_balance.value * k2, dg, 1e-12 * k2);
  // and the balance is bounded as a boundary term must be: |G| <= sum |x| |v| <= L sqrt(d)
  // sqrt(N sum v^2) with x in [0, L]^d, sum v^2 = 2E, so |balance| <= 2 |G|max / K2
  const double L = st.config.box[0], sv2 = 2.0 * d.energy;
  const double bound = 2.0 * L * std::sqrt(2.0) * std::sqrt(200.0 * sv2) / k2;
  std::printf("  |balance| bound %.3g (K2 %.6g, difference %.3g)\n", bound, k2, o.virial_balance.value * k2 - dg);
  CHECK(std::fabs(o.virial_balance.value) <= bound);
  CHECK(o.blocks >= 16 && o.blocks < 32);
  // the two axes' wall pressures agree within their errors (isotropy)
  const double dp = o.pressure_wall[0].value - o.pressure_wall[1].value;
  CHECK(std::fabs(dp) < 4.0 * std::hypot(o.pressure_wall[0].error, o.pressure_wall[1].error));
  CHECK(o.pressure_wall[0].error > 0.0);
  for (int k = 0; k < 5; ++k) CHECK(std::fabs(o.slab_temperature.value[k] / o.temperature.value - 1.0) < 0.05);
}

TEST_CASE("observing changes no trajectory; run_back ends the observation; nothing observed when off") {
  Config c;
  c.dim = 2;
  const InitialState st = random_state(c, 300, 0.4, 9);
  auto a = make_simulation(st.config, st.x, st.v);
  auto b = make_simulation(st.config, st.x, st.v);
  CHECK(a->observer() == nullptr);
  CHECK(!a->observing());
  ObserveConfig oc;
  oc.speed_bins = 20;
  oc.slabs = 3;
  b->observe(oc);
  CHECK(b->observing());
  a->run(3000, kInfinity);
  b->run(3000, kInfinity);
  CHECK(a->positions() == b->positions());
  CHECK(a->velocities() == b->velocities());
  const Observation before = b->observer()->results();
  b->run_back(1000, 0.0);
  CHECK(!b->observing());
  b->run(1000, kInfinity);
  const Observation after = b->observer()->results();
  CHECK(after.t_end == before.t_end);
  CHECK(after.particle_collisions == before.particle_collisions);
  CHECK(after.pressure_virial.value == before.pressure_virial.value);
}

TEST_CASE("snapshots keep a running observation: a resumed run's results equal an uninterrupted one's, bit for bit") {
  auto check = [](const Config& c0, std::size_t n, double phi, const ObserveConfig& oc, std::uint64_t first,
                  std::uint64_t second) {
    const InitialState st = random_state(c0, n, phi, 4);
    auto a = make_simulation(st.config, st.x, st.v);
    a->run(first, kInfinity);
    a->observe(oc);
    a->run(first, kInfinity);
    const Snapshot snap = a->snapshot();
    REQUIRE(!snap.observer.empty());
    a->run(second, kInfinity);
    const Observation ra = a->observer()->results();
    auto b = restore_simulation(snap);
    REQUIRE(b->observing());
    b->run(second, kInfinity);
    const Observation rb = b->observer()->results();
    CHECK(ra.particle_collisions > 0);
    CHECK(same(ra, rb));
    CHECK(a->positions() == b->positions());
    return ra;
  };
  ObserveConfig full;
  full.slabs = 6;
  full.speed_bins = 30;
  full.block_time = 0.002;  // past 256 blocks: the merges go on across the snapshot
  const Observation o = check(walled(2, 1.0, Mode::exact), 150, 0.35, full, 3000, 5000);
  CHECK(o.blocks >= 16);
  Config per;
  per.dim = 3;
  check(per, 200, 0.3, ObserveConfig{}, 2000, 2000);
  ObserveConfig pairs;
  pairs.pair_bins = 40;
  pairs.pair_rmax = 2.0;
  check(walled(2, 2.5, Mode::exact), 3, 0.2, pairs, 500, 700);
}

TEST_CASE("the pair hook's fast path and its general path give the same results, bit for bit") {
  // The collision record sends every pair collision down pair_general (block ends, slab
  // crossings and pair distances do so otherwise); the record adds nothing to the results.
  auto check = [](const Config& c0, std::size_t n, double phi, ObserveConfig oc) {
    const InitialState st = random_state(c0, n, phi, 6);
    auto fast = make_simulation(st.config, st.x, st.v);
    auto general = make_simulation(st.config, st.x, st.v);
    fast->observe(oc);
    oc.collision_record = true;
    general->observe(oc);
    fast->run(6000, kInfinity);
    general->run(6000, kInfinity);
    const Observation a = fast->observer()->results(), b = general->observer()->results();
    CHECK(fast->observer()->collision_record().empty());
    CHECK(general->observer()->collision_record().size() ==
          static_cast<std::size_t>(2 * c0.dim) * b.pair_collisions);
    CHECK(a.pair_collisions > 1000);
    CHECK(a.blocks >= 16);
    CHECK(same(a, b));
  };
  ObserveConfig oc;
  oc.slabs = 5;
  oc.speed_bins = 25;
  oc.speed_max = 2.0;  // speeds beyond it: the overflow bin, in neither path's results
  oc.block_time = 0.01;
  for (int d = 1; d <= 3; ++d) {
    oc.slab_axis = d - 1;
    check(walled(d, 1.0, Mode::exact), d == 1 ? 40 : d == 2 ? 150 : 256, 0.3, oc);
    Config per;
    per.dim = d;
    per.mode = Mode::exact;
    check(per, d == 1 ? 40 : d == 2 ? 150 : 256, 0.3, oc);
  }
}

TEST_CASE("snapshot observer data: none (old snapshots) resumes nothing; bad data is a named error") {
  Config c = walled(2, 1.0, Mode::exact);
  const InitialState st = random_state(c, 60, 0.3, 3);
  auto s = make_simulation(st.config, st.x, st.v);
  ObserveConfig oc;
  oc.slabs = 3;
  s->observe(oc);
  s->run(1000, kInfinity);
  const Snapshot good = s->snapshot();
  Snapshot old = good;
  old.observer.clear();
  old.observer_counts.clear();
  auto r = restore_simulation(old);
  CHECK(r->observer() == nullptr);
  CHECK(!r->observing());
  s->stop_observing();
  CHECK(s->snapshot().observer.empty());  // a stopped observation is not kept
  auto bad = [&](auto spoil) {
    Snapshot b = good;
    spoil(b);
    CHECK_THROWS_AS(restore_simulation(b), InvalidArgument);
  };
  bad([](Snapshot& b) { b.observer.pop_back(); });
  bad([](Snapshot& b) { b.observer.push_back(0.0); });
  bad([](Snapshot& b) { b.observer_counts.pop_back(); });
  bad([](Snapshot& b) { b.observer.clear(); });  // counts without the observer
  bad([](Snapshot& b) { b.observer.back() = std::nan(""); });
  bad([](Snapshot& b) { b.observer[1] = 61.0; });    // another n
  bad([](Snapshot& b) { b.observer[3] = 1.0; });     // min_blocks < 2
  bad([](Snapshot& b) { b.observer[5] = 2.5; });     // slabs not whole
  bad([](Snapshot& b) { b.observer[12] = 1e9; });    // last update after the clock
  bad([](Snapshot& b) { b.observer[18 + 2] += 1.0; });  // particle 0's velocity is not the particle's
  bad([](Snapshot& b) { b.observer[14] = 300.0; });  // more blocks than are ever kept
}

TEST_CASE("validation: a bad config throws InvalidArgument and keeps the running observation") {
  Config c;
  c.dim = 2;
  const InitialState st = random_state(c, 50, 0.3, 2);
  auto s = make_simulation(st.config, st.x, st.v);
  s->observe(ObserveConfig{});
  const Observer* first = s->observer();
  auto bad = [&](auto set) {
    ObserveConfig oc;
    set(oc);
    CHECK_THROWS_AS(s->observe(oc), InvalidArgument);
    CHECK(s->observer() == first);
    CHECK(s->observing());
  };
  bad([](ObserveConfig& o) { o.block_time = -1.0; });
  bad([](ObserveConfig& o) { o.min_blocks = 1; });
  bad([](ObserveConfig& o) { o.slabs = -2; });
  bad([](ObserveConfig& o) {
    o.slabs = 4;
    o.slab_axis = 2;
  });
  bad([](ObserveConfig& o) { o.speed_bins = -1; });
  bad([](ObserveConfig& o) { o.speed_max = std::nan(""); });
  bad([](ObserveConfig& o) { o.pair_bins = 10; });  // no pair_rmax
  bad([](ObserveConfig& o) {  // pair distances need walls on every axis: this box is periodic
    o.pair_bins = 10;
    o.pair_rmax = 2.0;
  });
}

CHECK_MAIN()
