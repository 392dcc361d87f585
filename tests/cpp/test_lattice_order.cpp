// The order in which an engine stores its particles changes nothing (engine_core.hpp: local
// index and particle id): every key, draw, tie, log entry and output is by particle id, so an
// engine holding its particles in a random order runs the same collisions with the same bits,
// forward, back and rolled back (the parallel engine's logical processes hold theirs so).
#include <algorithm>
#include <cstdio>
#include <numeric>
#include <random>
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

template <std::size_t D>
void check_order(EngineOf<D> e, std::uint64_t collisions, std::uint32_t seed, const char* what, int max_redraws = 256) {
  e.max_redraws = max_redraws;
  e.run(e.size(), tick_limit - 1);  // not the start: streams, X and the log under way
  const SnapshotN<D> s0 = e.snapshot();
  std::vector<std::uint32_t> order(s0.x.size());
  std::iota(order.begin(), order.end(), 0U);
  std::mt19937 rng(seed);
  std::shuffle(order.begin(), order.end(), rng);
  EngineOf<D> a(s0, operator_for(s0.units, s0.law)), b(s0, operator_for(s0.units, s0.law), order);
  for (auto* x : {&a, &b}) x->max_redraws = max_redraws;
  CHECK(same_state(b.snapshot(), s0));
  std::vector<std::array<std::int64_t, 3>> ta, tb;
  std::vector<EventRecordN<D>> ea, eb;
  a.trace = &ta;
  b.trace = &tb;
  a.events = &ea;
  b.events = &eb;
  b.keep_journal(true);
  a.run(collisions, tick_limit - 1);
  b.run(collisions, tick_limit - 1);
  bool events_same = ea.size() == eb.size();
  for (std::size_t k = 0; events_same && k < ea.size(); ++k)
    events_same = ea[k].ids == eb[k].ids && ea[k].x == eb[k].x && ea[k].v_after == eb[k].v_after && ea[k].v_before == eb[k].v_before;
  const bool fwd = same_state(a.snapshot(), b.snapshot()) && ta == tb && events_same;
  if (!fwd) {
    std::size_t k = 0;
    while (k < std::min(ta.size(), tb.size()) && ta[k] == tb[k]) ++k;
    std::printf("    state %d trace %d (first difference at %zu of %zu/%zu) events %d (%zu/%zu)\n", same_state(a.snapshot(), b.snapshot()),
                ta == tb, k, ta.size(), tb.size(), events_same, ea.size(), eb.size());
    if (k < ta.size() && k < tb.size())
      std::printf("    a: %lld %lld %lld  b: %lld %lld %lld\n", (long long)ta[k][0], (long long)ta[k][1], (long long)ta[k][2], (long long)tb[k][0], (long long)tb[k][1], (long long)tb[k][2]);
    for (std::size_t q = 0; q < std::min(ea.size(), eb.size()); ++q)
      if (!(ea[q].ids == eb[q].ids && ea[q].x == eb[q].x && ea[q].v_after == eb[q].v_after && ea[q].v_before == eb[q].v_before)) {
        std::printf("    event %zu differs: kind %d/%d tick %lld/%lld ids %d/%d\n", q, ea[q].kind, eb[q].kind, (long long)ea[q].tick, (long long)eb[q].tick, ea[q].ids[0], eb[q].ids[0]);
        break;
      }
  }
  CHECK(fwd);
  for (int p : {0, static_cast<int>(s0.x.size()) - 1}) {
    CHECK(a.bits(p).words() == b.bits(p).words());
    CHECK(a.particle_collisions(p) == b.particle_collisions(p));
  }
  // rolled back half way, on again, and back to the start
  const SnapshotN<D> end = a.snapshot();
  b.rollback(s0.collisions + collisions / 2);
  b.run(collisions - collisions / 2, tick_limit - 1);
  const bool redo = same_state(b.snapshot(), end);
  CHECK(redo);
  a.run_back(s0.collisions, s0.clock);
  b.run_back(s0.collisions, s0.clock);
  const bool back = same_state(a.snapshot(), s0) && same_state(b.snapshot(), s0);
  CHECK(back);
  std::printf("  %s: %llu collisions (%llu groups, %zu log entries), particles shuffled: forward %s, rolled back and on %s, "
              "back %s\n",
              what, static_cast<unsigned long long>(collisions),
              static_cast<unsigned long long>(a.counters().group_resolves + a.counters().group_bounces), end.log.size(),
              fwd ? "same" : "DIFFERENT", redo ? "same" : "DIFFERENT", back ? "same" : "DIFFERENT");
}

}  // namespace

TEST_CASE("an engine's particle order changes nothing: the same collisions, the same bits, forward, back, rolled back") {
  using B = en::Boundary;
  check_order<2>(lattice_test::make_gas<2>(300, 0.6, B::wall, 41, 16), 4000, 1, "2D 0.6 walls exact");
  check_order<2>(lattice_test::make_gas<2>(300, 0.5, B::periodic, 42, 16, Mode::specular), 4000, 2, "2D 0.5 periodic specular");
  check_order<2>(lattice_test::make_gas<2>(150, 0.4, B::wall, 43, 16), 800, 3, "2D 0.4 walls, every collision a group", -1);
  check_order<3>(lattice_test::make_gas<3>(300, 0.4, B::periodic, 44, 16), 4000, 4, "3D 0.4 periodic exact (lists)");
  check_order<3>(lattice_test::make_gas<3>(250, 0.3, B::bounce, 45, 16), 3000, 5, "3D 0.3 bounce-back walls exact");
  check_order<3>(lattice_test::make_gas<3>(150, 0.3, B::periodic, 46, 16), 600, 6, "3D 0.3 periodic, every collision a group", -1);
}

namespace {

// The periodic re-sort (engine_core.hpp set_resort, state.hpp resort), forced every neutral
// event per particle, against an engine that never re-sorts: the same collisions, event records,
// observation and bits forward and back; an engine error mid-run undone (the undo journal
// follows its particles); none while a journal is kept.
template <std::size_t D>
void check_resort(EngineOf<D> e, std::uint64_t collisions, const char* what, int max_redraws = 256) {
  e.max_redraws = max_redraws;
  e.run(e.size(), tick_limit - 1);
  const SnapshotN<D> s0 = e.snapshot();
  EngineOf<D> a(s0, operator_for(s0.units, s0.law)), b(s0, operator_for(s0.units, s0.law));
  for (auto* x : {&a, &b}) x->max_redraws = max_redraws;
  a.set_resort(0);
  b.set_resort(1);
  std::vector<std::array<std::int64_t, 3>> ta, tb;
  a.trace = &ta;
  b.trace = &tb;
  // an error part way: the run is undone, whatever the re-sorts moved
  b.throw_at_collision = s0.collisions + collisions * 9 / 10;
  CHECK(refused([&] { b.run(collisions, tick_limit - 1); }, "test hook"));
  const std::uint64_t tried = b.resorts();
  CHECK(tried > 0);
  CHECK(same_state(b.snapshot(), s0));
  b.throw_at_collision = 0;
  tb.clear();
  std::vector<EventRecordN<D>> ea, eb;
  a.events = &ea;
  b.events = &eb;
  en::ObserveConfig oc;
  oc.speed_bins = 20;
  oc.slabs = 4;
  a.observe(oc);
  b.observe(oc);
  a.run(collisions, tick_limit - 1);
  b.run(collisions, tick_limit - 1);
  bool events_same = ea.size() == eb.size() && !ea.empty();
  for (std::size_t k = 0; events_same && k < ea.size(); ++k)
    events_same = ea[k].ids == eb[k].ids && ea[k].x == eb[k].x && ea[k].v_after == eb[k].v_after && ea[k].v_before == eb[k].v_before;
  const SnapshotN<D> sa = a.snapshot(), sb = b.snapshot();
  const bool fwd = same_state(sa, sb) && ta == tb && events_same && !sa.observer.empty() && sa.observer == sb.observer;
  a.events = b.events = nullptr;
  CHECK(fwd);
  const std::uint64_t forward_sorts = b.resorts() - tried;
  CHECK(forward_sorts > 0);
  a.run_back(s0.collisions, s0.clock);
  b.run_back(s0.collisions, s0.clock);
  const bool back = same_state(a.snapshot(), s0) && same_state(b.snapshot(), s0);
  CHECK(back);
  CHECK(b.resorts() > tried + forward_sorts);
  CHECK(a.resorts() == 0);
  // a kept journal holds local indices: no re-sort while it is kept
  const std::uint64_t before = b.resorts();
  b.keep_journal(true);
  b.run(collisions, tick_limit - 1);
  CHECK(b.resorts() == before);
  std::printf("  %s: %llu collisions, %llu re-sorts forward and %llu back: forward %s, back %s\n", what,
              static_cast<unsigned long long>(collisions), static_cast<unsigned long long>(forward_sorts),
              static_cast<unsigned long long>(before - tried - forward_sorts), fwd ? "same" : "DIFFERENT",
              back ? "same" : "DIFFERENT");
}

}  // namespace

TEST_CASE("the periodic re-sort of the storage changes nothing: the same collisions, the same bits, forward and back") {
  using B = en::Boundary;
  check_resort<2>(lattice_test::make_gas<2>(300, 0.6, B::wall, 51, 16), 8000, "2D 0.6 walls exact (cells)");
  check_resort<2>(lattice_test::make_gas<2>(300, 0.5, B::periodic, 52, 16, Mode::specular), 4000, "2D 0.5 periodic specular");
  check_resort<3>(lattice_test::make_gas<3>(300, 0.4, B::periodic, 54, 16), 12000, "3D 0.4 periodic exact (lists)");
  check_resort<3>(lattice_test::make_gas<3>(250, 0.3, B::bounce, 55, 16), 6000, "3D 0.3 bounce-back walls exact");
  check_resort<3>(lattice_test::make_gas<3>(150, 0.3, B::periodic, 56, 16), 1200, "3D 0.3 periodic, every collision a group", -1);
}

TEST_CASE("a re-sort setting below -1 is refused") {
  auto e = lattice_test::make_gas<2>(50, 0.3, en::Boundary::periodic, 8, 16);
  CHECK(refused([&] { e.set_resort(-2); }, "resort must be >= -1"));
  CHECK(e.resort_every() == 0);  // automatic: none below 32 768 particles
}

TEST_CASE("an order that is not a permutation is refused, the state unchanged") {
  auto e = lattice_test::make_gas<2>(50, 0.3, en::Boundary::periodic, 7, 16);
  e.run(100, tick_limit - 1);
  const Snapshot s = e.snapshot();
  std::vector<std::uint32_t> bad(50, 0);
  CHECK(refused([&] { e.restore(s, bad); }, "a permutation of [0, N)"));
  bad.resize(49);
  CHECK(refused([&] { e.restore(s, bad); }, "a permutation of [0, N)"));
  std::iota(bad.begin(), bad.end(), 1U);
  bad.push_back(50);
  CHECK(refused([&] { e.restore(s, bad); }, "a permutation of [0, N)"));
  CHECK(same_state(e.snapshot(), s));
  CHECK(refused([&] { (void)e.bits(50); }, "no such particle id"));
}

int main() { return check::run_all(); }
