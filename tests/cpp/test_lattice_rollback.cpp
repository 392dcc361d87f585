// Rollback (rollback.hpp): with the journal kept, the latest events are undone one by one in the
// forward frame, and the state is bit for bit the one the forward run had at the target
// (collision count or tick), in every mode the lattice has: 2D and 3D, periodic, specular and
// bounce-back walls, exact and specular collisions, the cell grid and neighbour lists, forced
// groups (resolved and bounced), and in a field (a field's wall momentum taken off too). Checked three ways: rollbacks to stored forward states and a run
// on that rejoins the forward run; the rollback check of ROSS (each collision done, undone,
// compared, done again); and a fuzz of random runs, rollbacks and commits against the forward
// run's state hash at every collision count. Bad requests are refused with the state unchanged.
#include <array>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "check.hpp"
#include "lattice_gas_util.hpp"
#include "revcol/lattice/engine.hpp"

using namespace revcol::lattice;
namespace en = revcol::engine;
using revcol::Mode;

namespace {

using lattice_test::EngineOf;
using lattice_test::refused;

// FNV-1a over the state same_state compares (clock, collisions, x, v, streams, counts, X, log, groups)
template <std::size_t D>
std::uint64_t state_hash(const SnapshotN<D>& s) {
  std::uint64_t h = 1469598103934665603ULL;
  auto mix = [&](std::uint64_t w) {
    for (int b = 0; b < 8; ++b) h = (h ^ ((w >> (8 * b)) & 0xffU)) * 1099511628211ULL;
  };
  mix(static_cast<std::uint64_t>(s.clock));
  mix(s.collisions);
  for (std::size_t p = 0; p < s.x.size(); ++p)
    for (std::size_t k = 0; k < D; ++k) {
      mix(static_cast<std::uint64_t>(s.x[p][k]));
      mix(static_cast<std::uint64_t>(s.v[p][k]));
    }
  for (auto w : s.streams) mix(w);
  for (auto w : s.particle_collisions) mix(w);
  for (auto w : s.bits) mix(w);
  for (auto w : s.bits_size) mix(w);
  for (const LogEntry& e : s.log) {
    mix(e.particle);
    mix(e.count);
    mix(e.redraws);
  }
  for (const auto& g : s.groups) {
    mix(static_cast<std::uint64_t>(g.drawer));
    mix(g.draws);
    for (int m : g.members) mix(static_cast<std::uint64_t>(m));
    for (auto c : g.counts) mix(c);
    for (const auto& v : g.pre_v)
      for (auto c : v) mix(static_cast<std::uint64_t>(c));
  }
  return h;
}

struct Scene {
  const char* what;
  std::size_t n;
  double phi;
  en::Boundary kind;
  Mode mode;
  double shell;     // < 0: the engine's choice; 0: cells; > 0: lists
  int max_redraws;  // -1: every collision a group
  bool resolve;     // groups resolve (else bounce)
  double gravity = 0.0;  // a field along the last axis (walled), kT / sigma
};

template <std::size_t D>
EngineOf<D> make(const Scene& sc, std::uint32_t seed) {
  auto e = lattice_test::make_gas<D>(sc.n, sc.phi, sc.kind, seed, 16, sc.mode, sc.gravity);
  if (sc.shell >= 0.0) e.set_list_shell(sc.shell);
  e.max_redraws = sc.max_redraws;
  e.group_resolve = sc.resolve;
  return e;
}

template <std::size_t D>
void check_scene(const Scene& sc, std::uint64_t total, std::uint32_t seed) {
  // the forward run's state (hash) after every collision, and whole snapshots at a few counts
  auto r = make<D>(sc, seed);
  // (and a field's wall momentum, a counter, not state: a rollback takes off what it undoes)
  std::vector<std::uint64_t> ref{state_hash(r.snapshot())};
  std::vector<std::array<std::uint64_t, 4>> ref_imp{r.counters().field_wall_impulse};
  std::vector<SnapshotN<D>> snaps{r.snapshot()};
  const std::uint64_t every = total / 6;
  for (std::uint64_t c = 1; c <= total; ++c) {
    r.run(1, tick_limit - 1);
    const auto s = r.snapshot();
    ref.push_back(state_hash(s));
    ref_imp.push_back(r.counters().field_wall_impulse);
    if (c % every == 0) snaps.push_back(s);
  }
  const auto cnt = r.counters();
  const SnapshotN<D> end = r.snapshot();
  if (sc.gravity != 0.0) CHECK(ref_imp.back() != ref_imp.front());

  // 1. rollbacks to stored states, latest first, then a run on that rejoins the forward run
  auto e = make<D>(sc, seed);
  e.keep_journal(true);
  e.run(total, tick_limit - 1);
  CHECK(same_state(e.snapshot(), end));
  bool all = true;
  for (std::size_t k = snaps.size(); k-- > 0;) {
    e.rollback(snaps[k].collisions);
    all = all && same_state(e.snapshot(), snaps[k]) && e.counters().field_wall_impulse == ref_imp[snaps[k].collisions];
  }
  CHECK(all);
  e.run(total, tick_limit - 1);
  CHECK(same_state(e.snapshot(), end));

  // 2. rollback to ticks: the state run(until = tick) has
  int ticks_ok = 0, ticks = 0;
  for (std::size_t k = snaps.size() - 1; k >= 1; --k) {
    const std::int64_t t = (snaps[k].clock + snaps[k - 1].clock) / 2;
    auto f = make<D>(sc, seed);
    f.run(total, t);
    e.rollback_to_tick(t);
    ++ticks;
    if (same_state(e.snapshot(), f.snapshot())) ++ticks_ok;
  }
  CHECK(ticks_ok == ticks);

  // 3. ROSS's rollback check: every collision done, undone (compared), done again (compared);
  // 4. a fuzz of runs, rollbacks and commits (the journal's start moves up), against the hashes;
  // both with rollback by reverse computation and by state saving (SS1, SS2)
  int ross_bad = 0, fuzz_bad = 0, rollbacks = 0, commits = 0;
  const std::uint64_t ross = std::min<std::uint64_t>(total, 600);
  for (const Rollback how : {Rollback::reverse, Rollback::save_all, Rollback::save_changes}) {
    auto c = make<D>(sc, seed);
    c.keep_journal(true, how);
    for (std::uint64_t k = 1; k <= ross; ++k) {
      c.run(1, tick_limit - 1);
      c.rollback(k - 1);
      if (state_hash(c.snapshot()) != ref[k - 1] || c.counters().field_wall_impulse != ref_imp[k - 1]) ++ross_bad;
      c.run(1, tick_limit - 1);
      if (state_hash(c.snapshot()) != ref[k] || c.counters().field_wall_impulse != ref_imp[k]) ++ross_bad;
    }
    auto z = make<D>(sc, seed);
    z.keep_journal(true, how);
    std::mt19937_64 rng(seed * 7919ULL + 1);
    for (int step = 0; step < 400; ++step) {
      const std::uint64_t now = z.collisions();
      const int op = static_cast<int>(rng() % 8);
      if (op < 4 && now < total) {
        z.run(1 + rng() % std::min<std::uint64_t>(60, total - now), tick_limit - 1);
      } else if (op < 7) {
        const std::uint64_t lo = z.journal_start();
        z.rollback(lo + rng() % (now - lo + 1));
        ++rollbacks;
      } else {
        const std::uint64_t lo = z.journal_start();
        z.commit(lo + rng() % (now - lo + 1) / 2);
        ++commits;
      }
      if (state_hash(z.snapshot()) != ref[z.collisions()] || z.counters().field_wall_impulse != ref_imp[z.collisions()]) ++fuzz_bad;
    }
    z.run(total - z.collisions(), tick_limit - 1);
    if (!same_state(z.snapshot(), end)) ++fuzz_bad;
  }
  CHECK(ross_bad == 0);
  CHECK(fuzz_bad == 0);
  std::printf("  %s: %llu collisions (%llu walls, %llu groups, %llu of them with a reflection, %llu log entries); %zu rollbacks to states, %d to ticks, "
              "%llu done-undone-redone, fuzz %d rollbacks %d commits (RC, SS1, SS2): %s\n",
              sc.what, static_cast<unsigned long long>(total), static_cast<unsigned long long>(cnt.walls),
              static_cast<unsigned long long>(cnt.group_resolves + cnt.group_bounces),
              static_cast<unsigned long long>(cnt.wall_groups), static_cast<unsigned long long>(cnt.log_entries), snaps.size(), ticks, static_cast<unsigned long long>(ross),
              rollbacks, commits, all && ticks_ok == ticks && ross_bad == 0 && fuzz_bad == 0 ? "bit for bit" : "DIFFERENT");
}

// rollback_before the key of collision n + 1, (tick, 2 + its drawer, its drawer), for n through the
// run, latest first: the collision count is n, and a run on rejoins the forward run's hashes;
// rollback_before (t, 0, 0) is the state run(until = t - 1) has
template <std::size_t D>
void check_keys(const Scene& sc, std::uint64_t total) {
  auto r = make<D>(sc, 51);
  std::vector<std::array<std::int64_t, 3>> trace;
  r.trace = &trace;
  std::vector<std::uint64_t> ref{state_hash(r.snapshot())};
  for (std::uint64_t c = 1; c <= total; ++c) {
    r.run(1, tick_limit - 1);
    ref.push_back(state_hash(r.snapshot()));
  }
  auto e = make<D>(sc, 51);
  e.keep_journal(true);
  e.run(total, tick_limit - 1);
  int bad = 0, tried = 0;
  for (std::uint64_t n = total - 1; n >= 100; n -= 97) {
    const auto& k = trace[n];  // collision n + 1: (tick, i, j), i the smaller id
    e.rollback_before(k[0], static_cast<std::int32_t>(2 + k[1]), static_cast<std::int32_t>(k[1]));
    ++tried;
    if (e.collisions() != n) ++bad;
    e.run(1, tick_limit - 1);  // that collision again, and the run rejoins
    if (state_hash(e.snapshot()) != ref[n + 1]) ++bad;
    e.rollback(n);
    if (state_hash(e.snapshot()) != ref[n]) ++bad;
  }
  // (t, 0, 0): the state run(until = t - 1) has
  const std::int64_t t = trace[total / 3][0];
  auto f = make<D>(sc, 51);
  f.run(total, t - 1);
  e.run(total - e.collisions(), tick_limit - 1);
  e.rollback_before(t, 0, 0);
  if (!same_state(e.snapshot(), f.snapshot())) ++bad;
  e.run(total - e.collisions(), tick_limit - 1);
  if (state_hash(e.snapshot()) != ref[total]) ++bad;
  std::printf("  %s: %d rollbacks before a collision's key, one before a tick: %s\n", sc.what, tried, bad == 0 ? "bit for bit" : "DIFFERENT");
  CHECK(bad == 0);
}

}  // namespace

TEST_CASE("2D rollback is exact: periodic, walls, bounce back; exact and specular; cells and lists") {
  using B = en::Boundary;
  check_scene<2>({"2D 0.5 periodic exact cells", 300, 0.5, B::periodic, Mode::exact, -1.0, 256, true}, 2400, 11);
  check_scene<2>({"2D 0.6 walls exact", 300, 0.6, B::wall, Mode::exact, -1.0, 256, true}, 2400, 12);
  check_scene<2>({"2D 0.5 bounce-back walls exact", 250, 0.5, B::bounce, Mode::exact, -1.0, 256, true}, 2000, 13);
  check_scene<2>({"2D 0.5 walls specular", 300, 0.5, B::wall, Mode::specular, -1.0, 256, true}, 2400, 14);
  check_scene<2>({"2D 0.4 periodic exact lists", 300, 0.4, B::periodic, Mode::exact, 0.6, 256, true}, 2000, 15);
  check_scene<2>({"2D 0.4 walls forced groups (resolve)", 150, 0.4, B::wall, Mode::exact, -1.0, -1, true}, 900, 16);
  check_scene<2>({"2D 0.4 periodic forced groups (bounce)", 150, 0.4, B::periodic, Mode::exact, -1.0, -1, false}, 900, 17);
  check_scene<2>({"2D 0.7 walls exact", 400, 0.7, B::wall, Mode::exact, -1.0, 256, true}, 3000, 18);
  check_scene<2>({"2D 0.7 bounce-back walls specular", 400, 0.7, B::bounce, Mode::specular, -1.0, 256, true}, 3000, 19);
}

TEST_CASE("3D rollback is exact: periodic, walls, bounce back; exact and specular; lists and cells") {
  using B = en::Boundary;
  check_scene<3>({"3D 0.4 periodic exact lists", 300, 0.4, B::periodic, Mode::exact, -1.0, 256, true}, 2400, 21);
  check_scene<3>({"3D 0.4 walls exact", 300, 0.4, B::wall, Mode::exact, -1.0, 256, true}, 2400, 22);
  check_scene<3>({"3D 0.4 bounce-back walls specular", 250, 0.4, B::bounce, Mode::specular, -1.0, 256, true}, 2000, 23);
  check_scene<3>({"3D 0.3 walls exact cells", 250, 0.3, B::wall, Mode::exact, 0.0, 256, true}, 2000, 24);
  check_scene<3>({"3D 0.3 walls forced groups", 150, 0.3, B::wall, Mode::exact, -1.0, -1, true}, 700, 25);
  check_scene<3>({"3D 0.45 periodic exact", 300, 0.45, B::periodic, Mode::exact, -1.0, 256, true}, 3000, 26);
  check_scene<3>({"3D 0.4 walls specular", 300, 0.4, B::wall, Mode::specular, -1.0, 256, true}, 3000, 27);
}

TEST_CASE("rollback in a field is exact: 2D and 3D, walls and slabs, exact and specular, bounce back, cells and lists, groups") {
  using B = en::Boundary;
  check_scene<2>({"2D 0.4 channel g=-2 exact cells", 300, 0.4, B::periodic, Mode::exact, -1.0, 256, true, -2.0}, 2400, 31);
  check_scene<2>({"2D 0.5 walls g=-1 specular lists", 300, 0.5, B::wall, Mode::specular, 0.4, 256, true, -1.0}, 2400, 32);
  check_scene<2>({"2D 0.4 bounce-back walls g=+2", 250, 0.4, B::bounce, Mode::exact, -1.0, 256, true, 2.0}, 2000, 33);
  check_scene<2>({"2D 0.4 walls g=-2 forced groups (resolve)", 150, 0.4, B::wall, Mode::exact, -1.0, -1, true, -2.0}, 900, 34);
  check_scene<2>({"2D 0.4 channel g=-2 forced groups (bounce)", 150, 0.4, B::periodic, Mode::exact, -1.0, -1, false, -2.0}, 900, 35);
  check_scene<3>({"3D 0.3 slab g=-2 exact lists", 300, 0.3, B::periodic, Mode::exact, -1.0, 256, true, -2.0}, 2400, 36);
  check_scene<3>({"3D 0.3 walls g=-1 exact cells", 250, 0.3, B::wall, Mode::exact, 0.0, 256, true, -1.0}, 2000, 37);
  check_scene<3>({"3D 0.4 walls g=-1 specular", 300, 0.4, B::wall, Mode::specular, -1.0, 256, true, -1.0}, 2400, 38);
  check_scene<3>({"3D 0.3 walls g=-2 forced groups", 150, 0.3, B::wall, Mode::exact, -1.0, -1, true, -2.0}, 700, 39);
}

TEST_CASE("3D walls: collisions right after a reflection on one tick roll back exactly (also in a field)") {
  // (test_lattice_engine3d.cpp: ~ every 30 000 collisions at N = 256, 0.45, walls, T = 16)
  for (const double g : {0.0, -2.0}) {
  auto e = lattice_test::make_gas<3>(256, 0.45, en::Boundary::wall, 1, 16, Mode::exact, g);
  auto f = lattice_test::make_gas<3>(256, 0.45, en::Boundary::wall, 1, 16, Mode::exact, g);  // forward only, lazily behind
  e.keep_journal(true);
  int seen = 0, bad = 0;
  for (std::uint64_t k = 1; k <= 100000; ++k) {
    const std::uint64_t before = e.counters().wall_body;
    e.run(1, tick_limit - 1);
    if (e.counters().wall_body == before) {
      if (k % 1000 == 0) e.commit(k - 1000);
      continue;
    }
    // undo it (the state before it as the forward run had it), back 200 more, then on again
    ++seen;
    const auto after = e.snapshot();
    e.rollback(k - 1);
    f.run(k - 1 - f.collisions(), tick_limit - 1);
    if (!same_state(e.snapshot(), f.snapshot())) ++bad;
    const std::uint64_t back = std::max<std::uint64_t>(e.journal_start(), k > 201 ? k - 201 : 0);
    e.rollback(back);
    e.run(k - back, tick_limit - 1);
    if (!same_state(e.snapshot(), after)) ++bad;
  }
  std::printf("  N = 256, 0.45, walls, g = %g: %d collisions right after a reflection in 10^5 (%llu groups with one), rolled back and redone: %s\n", g,
              seen, static_cast<unsigned long long>(e.counters().wall_groups), bad == 0 ? "bit for bit" : "DIFFERENT");
  CHECK(seen >= 2);
  CHECK(bad == 0);
  }
}

TEST_CASE("rollback before a key (a straggler's): the events before it kept, a run on rejoins the forward run") {
  using B = en::Boundary;
  for (const Scene& sc : {Scene{"2D 0.6 walls", 300, 0.6, B::wall, Mode::exact, -1.0, 256, true},
                          Scene{"3D 0.4 periodic", 300, 0.4, B::periodic, Mode::exact, -1.0, 256, true},
                          Scene{"2D 0.4 forced groups", 150, 0.4, B::wall, Mode::exact, -1.0, -1, true}}) {
    if (std::string(sc.what).rfind("3D", 0) == 0) check_keys<3>(sc, 1500);
    else check_keys<2>(sc, 1500);
  }
}

TEST_CASE("rollback refuses what it can not do, the state unchanged") {
  auto e = lattice_test::make_gas<2>(200, 0.5, en::Boundary::wall, 31, 16);
  e.run(300, tick_limit - 1);
  const auto s = e.snapshot();
  CHECK(refused([&] { e.rollback(100); }, "keeps no journal"));
  CHECK(refused([&] { e.rollback_to_tick(0); }, "keeps no journal"));
  CHECK(same_state(e.snapshot(), s));
  e.keep_journal(true);
  CHECK(e.journal_start() == 300);
  e.run(200, tick_limit - 1);
  const auto s2 = e.snapshot();
  CHECK(refused([&] { e.rollback(299); }, "[journal_start, collisions] = [300, 500]"));
  CHECK(refused([&] { e.rollback(501); }, "[journal_start, collisions] = [300, 500]"));
  CHECK(refused([&] { e.rollback_to_tick(s.clock - 1); }, "journal_start_tick"));
  CHECK(refused([&] { e.rollback_to_tick(s2.clock + 1); }, "journal_start_tick"));
  CHECK(refused([&] { e.commit(299); }, "lattice commit"));
  CHECK(refused([&] { e.rollback_before(s.clock, 0, 0); }, "must come after the journal's start"));
  CHECK(same_state(e.snapshot(), s2));
  e.commit(400);
  CHECK(e.journal_start() == 400);
  CHECK(refused([&] { e.rollback(399); }, "[journal_start, collisions] = [400, 500]"));
  e.rollback(400);
  CHECK(e.collisions() == 400);
  // an engine error mid-run restores the state and restarts the journal there
  e.throw_at_collision = 450;
  CHECK(refused([&] { e.run(100, tick_limit - 1); }, "test hook"));
  CHECK(e.collisions() == 400);
  CHECK(e.journal_start() == 400);
  e.throw_at_collision = 0;
  // a run back restarts the journal at the state it leaves
  e.run(50, tick_limit - 1);
  e.run_back(350, e.origin());
  CHECK(e.journal_start() == 350);
  CHECK(e.journal_size() == 0);
  CHECK(refused([&] { e.rollback(349); }, "[journal_start, collisions] = [350, 350]"));
}
int main() { return check::run_all(); }
