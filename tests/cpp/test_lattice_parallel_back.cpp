// The parallel engine running back (timewarp.hpp Config::back, parallel_run.hpp
// run_parallel_back): an LP in run_back's reversed frame undoes its back steps exactly (each by
// its forward collision computed again, the rare log's redraws and groups kept aside); K LPs
// running back commit the sequential run_back's state bit for bit at every tick they stop at, for
// K = 1 to 8, 2D and 3D, walls, bounce walls and periodic, exact and specular, in round-robin,
// fuzzed (random order, random delays) and threaded schedules; run_parallel_back reaches
// run_back's state at a collision count (chunks, the sequential tail, or forward again past the
// count), at a tick, and at the start, where it is the forward run's first state bit for bit; a
// Ctrl-C ends it at a whole tick of the sequential run back.
#include <cstdint>
#include <cstdio>
#include <functional>
#include <limits>
#include <vector>

#include "check.hpp"
#include "lattice_gas_util.hpp"
#include "revcol/lattice/engine.hpp"
#include "revcol/lattice/parallel_run.hpp"
#include "revcol/lattice/timewarp.hpp"

using namespace revcol::lattice;
namespace en = revcol::engine;
using revcol::Mode;
using lattice_test::EngineOf;

namespace {

constexpr std::uint64_t kThreads = ~std::uint64_t{0};  // a schedule: two worker threads

// the forward-frame state of a snapshot a reversed engine took (its clock and velocities negated)
template <std::size_t D>
SnapshotN<D> forward_frame(SnapshotN<D> s) {
  s.clock = -s.clock;
  for (auto& v : s.v) v = neg(v);
  return s;
}

// One LP holding every particle runs back `span` ticks, then rolls back half way and to its
// start: each state is the sequential run_back's (and the start's) bit for bit, the rare log and
// the groups included (the back run took some of each back: the undo restored them).
template <std::size_t D>
void check_undo(EngineOf<D> e, std::uint64_t forward, int max_redraws, const char* what) {
  e.max_redraws = max_redraws;  // (-1: every collision a group)
  e.run(forward, tick_limit - 1);
  const SnapshotN<D> end = e.snapshot();
  EngineOf<D> lp(end, operator_for(end.units, end.law), 0, {0}, -1.0, true);  // (an LP of a run back)
  LpNotes notes;
  notes.after = [](void*) {};
  lp.lp_begin(std::vector<std::uint8_t>(end.x.size(), 1), &notes);
  const SnapshotN<D> start = lp.snapshot();
  const std::int64_t span = (end.clock - end.origin) * 3 / 4, mid = start.clock + span / 2;
  const auto before = [&](std::int64_t t) {  // every event after tick t undone, the clock at t
    lp.rollback_before(t + 1, std::numeric_limits<std::int32_t>::min(), std::numeric_limits<std::int32_t>::min());
  };
  lp.lp_run(EventKey::tick_start(start.clock + span + 1), ~std::size_t{0});
  const SnapshotN<D> far = lp.snapshot();  // (at its last event's tick, every event there done)
  EngineOf<D> ref(end, operator_for(end.units, end.law));
  ref.run_back(0, -far.clock);
  CHECK(same_state(forward_frame(far), ref.snapshot()));
  before(mid);
  EngineOf<D> ref2(end, operator_for(end.units, end.law));
  ref2.run_back(0, -mid);
  CHECK(same_state(forward_frame(lp.snapshot()), ref2.snapshot()));
  before(start.clock);
  const bool same = same_state(lp.snapshot(), start);
  std::printf("  %s: %llu collisions back; log %zu -> %zu, groups %zu -> %zu; undone to the start: %s\n", what,
              static_cast<unsigned long long>(end.collisions - far.collisions), end.log.size(), far.log.size(), end.groups.size(),
              far.groups.size(), same ? "same" : "DIFFERS");
  CHECK(same);
  // back steps that read the rare log were undone
  // (specular: drawn fallbacks, logged, are rarer than these runs; their undo is the exact mode's)
  CHECK(far.groups.size() < end.groups.size());
  CHECK(max_redraws < 0 || end.mode == Mode::specular || far.log.size() < end.log.size());
}

// K LPs running back from a forward run's end commit run_back's state at three ticks.
template <std::size_t D>
void check_back(EngineOf<D> e, int axis, const std::vector<int>& ks, const std::vector<std::uint64_t>& fuzz, std::uint64_t forward,
                const char* what) {
  e.run(forward, tick_limit - 1);
  const SnapshotN<D> end = e.snapshot();
  std::vector<SnapshotN<D>> want;
  std::vector<std::int64_t> ticks;
  EngineOf<D> ref(end, operator_for(end.units, end.law));
  for (int k = 1; k <= 3; ++k) {
    ticks.push_back(end.clock - (end.clock - end.origin) * k / 4);
    ref.run_back(0, ticks.back());
    want.push_back(ref.snapshot());
  }
  for (int K : ks)
    for (std::uint64_t f : fuzz) {
      if (f == kThreads && K == 1) continue;
      typename TimeWarp<EngineOf<D>>::Config c;
      c.lps = K;
      c.axis = axis;
      c.back = true;
      c.fuzz = f == kThreads ? 0 : f % 1000;
      c.workers = f == kThreads ? std::min(K, 2) : 1;
      c.lazy = f < 1000;  // (a fuzz seed from 1000 up: aggressive cancellation)
      c.batch = 8;
      TimeWarp<EngineOf<D>> tw(end, c);
      bool same = true;
      for (std::size_t s = 0; s < want.size(); ++s) {
        tw.run_until(-ticks[s]);
        const SnapshotN<D> got = tw.snapshot();  // (and a field's walls' momentum, given back as run_back gives it)
        same = same_state(got, want[s]) && got.counters.field_wall_impulse == want[s].counters.field_wall_impulse && same;
      }
      const TimeWarpStats st = tw.stats();
      std::printf("  %s, K = %d, %s: %llu collisions back; events %llu, rollbacks %llu (%llu undone), messages %llu, anti %llu, "
                  "confirmed %llu: same as run_back: %s\n",
                  what, K, f == kThreads ? "2 threads" : f == 0 ? "round robin" : f < 1000 ? "fuzzed" : "fuzzed, aggressive",
                  static_cast<unsigned long long>(end.collisions - want.back().collisions), static_cast<unsigned long long>(st.events),
                  static_cast<unsigned long long>(st.rollbacks), static_cast<unsigned long long>(st.undone),
                  static_cast<unsigned long long>(st.messages), static_cast<unsigned long long>(st.anti),
                  static_cast<unsigned long long>(st.confirmed), same ? "yes" : "NO");
      CHECK(same);
      if (K > 1 && f != 0) CHECK(st.messages > 0);
    }
}

template <std::size_t D>
typename TimeWarp<EngineOf<D>>::Config config(int k, int w) {
  return lattice_test::run_config<typename TimeWarp<EngineOf<D>>::Config>(k, w);
}

// run_parallel_back against run_back: to counts (chunks and the tail; bias > 1: past the count and
// forward again), to a tick, and to the start, which is the forward run's first state.
template <std::size_t D>
void check_counts(EngineOf<D> e, int k, int w, double bias, const char* what) {
  const SnapshotN<D> s0 = e.snapshot();
  e.run(90000, tick_limit - 1);
  const SnapshotN<D> end = e.snapshot();
  {  // the whole way back in one call: the start (a chunk past a count of 0 goes to the start's tick)
    EngineOf<D> whole(end, operator_for(end.units, end.law));
    const ParallelReport r = run_parallel_back(whole, 0, whole.origin(), config<D>(k, w), {}, 0, bias);
    CHECK(same_state(whole.snapshot(), s0) && r.collisions == end.collisions && r.sequential == 0);
  }
  EngineOf<D> ref(end, operator_for(end.units, end.law));
  std::uint64_t parallel = 0, overshoot = 0;
  for (const std::uint64_t to : {std::uint64_t{60000}, std::uint64_t{57000}, std::uint64_t{20000}}) {
    ref.run_back(to, ref.origin());
    const ParallelReport r = run_parallel_back(e, to, e.origin(), config<D>(k, w), {}, 0, bias);
    CHECK(e.collisions() == to && r.parallel + r.sequential == r.collisions && !r.stopped);
    CHECK(same_state(e.snapshot(), ref.snapshot()));
    parallel += r.parallel;
    overshoot += r.overshoot;
  }
  const std::int64_t t = e.clock() - (e.clock() - e.origin()) / 3;  // to a tick
  ref.run_back(0, t);
  const ParallelReport r = run_parallel_back(e, 0, t, config<D>(k, w));
  CHECK(r.sequential == 0 && r.chunks == 1 && e.clock() == t);
  CHECK(same_state(e.snapshot(), ref.snapshot()));
  run_parallel_back(e, 0, e.origin(), config<D>(k, w));  // to the start
  const bool start = same_state(e.snapshot(), s0);
  std::printf("  %s, K = %d, %d worker(s), bias %.2f: %llu collisions back in parallel, %llu past the count (forward again); "
              "back at the start: %s\n", what, k, w, bias, static_cast<unsigned long long>(parallel),
              static_cast<unsigned long long>(overshoot), start ? "same" : "DIFFERS");
  CHECK(start);
  CHECK(parallel > 40000);
  if (bias > 1.0) CHECK(overshoot > 0);  // the forward-again path was taken
}

}  // namespace

TEST_CASE("an LP running back undoes its back steps exactly, the rare log and groups included") {
  using B = en::Boundary;
  check_undo<2>(lattice_test::make_gas<2>(1000, 0.7, B::wall, 91, 16), 40000, 256, "2D 0.7 walls");
  check_undo<2>(lattice_test::make_gas<2>(1000, 0.5, B::bounce, 94, 16), 5000, -1, "2D 0.5 bounce walls, every collision a group");
  check_undo<3>(lattice_test::make_gas<3>(1000, 0.45, B::periodic, 92, 16), 40000, 256, "3D 0.45 periodic");
  check_undo<3>(lattice_test::make_gas<3>(1000, 0.3, B::wall, 95, 16), 5000, -1, "3D 0.3 walls, every collision a group");
  check_undo<2>(lattice_test::make_gas<2>(1000, 0.7, B::wall, 93, 16, Mode::specular), 60000, 256, "2D 0.7 walls specular");
  check_undo<2>(lattice_test::make_gas<2>(1000, 0.6, B::periodic, 191, 16, Mode::exact, -2.0), 40000, 256, "2D 0.6 channel, g = -2");
  check_undo<3>(lattice_test::make_gas<3>(1000, 0.45, B::wall, 195, 16, Mode::exact, -1.0), 40000, 256, "3D 0.45 walls, g = -1");
  check_undo<3>(lattice_test::make_gas<3>(1000, 0.4, B::periodic, 196, 16, Mode::specular, -2.0), 40000, 256, "3D 0.4 slab specular, g = -2");
}

TEST_CASE("K LPs running back commit run_back's state bit for bit (2D)") {
  using B = en::Boundary;
  check_back<2>(lattice_test::make_gas<2>(400, 0.4, B::periodic, 71, 16), 0, {1, 2, 3, 4, 8}, {0, 5, 1006, kThreads}, 6000, "2D 0.4 periodic");
  check_back<2>(lattice_test::make_gas<2>(1000, 0.6, B::wall, 73, 16), 1, {2, 3, 8}, {0, 8, kThreads}, 9000, "2D 0.6 walls");
  check_back<2>(lattice_test::make_gas<2>(600, 0.4, B::periodic, 74, 16, Mode::specular), 0, {2, 4}, {0, 9}, 6000, "2D 0.4 periodic specular");
}

TEST_CASE("K LPs running back commit run_back's state bit for bit (3D)") {
  using B = en::Boundary;
  check_back<3>(lattice_test::make_gas<3>(1000, 0.3, B::periodic, 75, 16), 2, {1, 2, 4, 8}, {0, 1010, kThreads}, 9000, "3D 0.3 periodic");
  check_back<3>(lattice_test::make_gas<3>(1000, 0.35, B::bounce, 76, 16), 0, {2, 3}, {11, kThreads}, 9000, "3D 0.35 bounce walls");
  check_back<3>(lattice_test::make_gas<3>(600, 0.25, B::wall, 77, 16, Mode::specular), 1, {2}, {12}, 6000, "3D 0.25 walls specular");
}

TEST_CASE("K LPs running back commit run_back's state bit for bit in a field") {
  using B = en::Boundary;
  check_back<2>(lattice_test::make_gas<2>(600, 0.4, B::periodic, 171, 16, Mode::exact, -2.0), 0, {2, 3, 8}, {0, 5, kThreads}, 6000,
                "2D 0.4 channel, g = -2");
  check_back<3>(lattice_test::make_gas<3>(1000, 0.3, B::wall, 175, 16, Mode::exact, -1.0), 0, {2, 4}, {0, kThreads}, 9000, "3D 0.3 walls, g = -1");
}

TEST_CASE("run_parallel_back reaches run_back's state at a count, at a tick and at the start") {
  using B = en::Boundary;
  check_counts<2>(lattice_test::make_gas<2>(2000, 0.4, B::periodic, 81, 16), 2, 2, 1.0, "2D 0.4 periodic");
  check_counts<2>(lattice_test::make_gas<2>(2000, 0.4, B::wall, 82, 16), 3, 1, 1.2, "2D 0.4 walls");
  check_counts<3>(lattice_test::make_gas<3>(2000, 0.3, B::periodic, 83, 16), 2, 2, 1.2, "3D 0.3 periodic");
  check_counts<3>(lattice_test::make_gas<3>(2000, 0.35, B::bounce, 86, 16), 4, 2, 1.0, "3D 0.35 bounce walls");
}

TEST_CASE("a Ctrl-C ends a parallel run back at a whole tick of the sequential run back") {
  auto e = lattice_test::make_gas<2>(2000, 0.4, en::Boundary::periodic, 84, 16);
  e.run(150000, tick_limit - 1);
  const SnapshotN<2> end = e.snapshot();
  int polls = 0;
  const std::function<bool()> poll = [&] { return ++polls < 40; };
  const ParallelReport r = run_parallel_back(e, 0, e.origin(), config<2>(2, 2), poll);
  CHECK(r.stopped && e.collisions() > 0);
  EngineOf<2> ref(end, operator_for(end.units, end.law));
  ref.run_back(0, e.clock());  // the state run_back(to_tick = that tick) has
  CHECK(same_state(e.snapshot(), ref.snapshot()));
}

int main() { return check::run_all(); }
