// A run of a sequential lattice engine's state on the parallel engine (timewarp.hpp): what
// LatticeSimulation(workers=K).run and `revcol run --workers K` call. The engine ends in the
// state its own run(collisions, until) would reach, bit for bit.
//
// Time Warp runs to a tick; a stop at a collision count is reached in three steps: a probe of a
// few thousand collisions on the sequential engine measures ticks per collision, the parallel
// engine runs to a tick estimated to fall just short of the count (up to two more, nearer ticks
// from the rate the last chunk measured), and the sequential engine runs the last few thousand
// collisions, or back the few a chunk ran past the count (its run_back is exact). Short runs (at
// most `small` collisions, default max(8192, N/4): building K views costs more than they save)
// stay sequential, and the report says how many collisions each engine ran. run_parallel_back is
// the same for a run back (the LPs in run_back's reversed frame).
#pragma once
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <exception>
#include <functional>
#include <limits>
#include <memory>

#include "revcol/error.hpp"
#include "revcol/lattice/timewarp.hpp"

namespace revcol::lattice {

/// What run_parallel (or run_parallel_back) did.
struct ParallelReport {
  std::uint64_t collisions = 0;  ///< collisions done (committed) in all
  std::uint64_t parallel = 0;    ///< of them, committed by the parallel engine
  std::uint64_t sequential = 0;  ///< of them, run by the sequential engine (probe and tail)
  std::uint64_t overshoot = 0;   ///< collisions a chunk ran past the stop: run back sequentially (observed: the chunk discarded, run again sequentially; a run back: forward again)
  int chunks = 0;                ///< parallel runs to a tick
  bool stopped = false;          ///< Ctrl-C: the state is the run's at a whole tick before the stop
  TimeWarpStats stats{};         ///< the parallel engine's counts
  double build_s = 0.0;          ///< seconds: building the K views
  double parallel_s = 0.0;       ///< seconds: the parallel engine's runs
  double assemble_s = 0.0;       ///< seconds: assembling the committed state and restoring the engine
  double sequential_s = 0.0;     ///< seconds: the sequential probe, tail or run back (a run back: its tail, or forward again)
};

/// Runs engine e forward, as e.run(collisions, until) does (bit for bit the same state), on K
/// logical processes (config c). An engine error leaves e's state as it was; Ctrl-C (poll()
/// false) leaves it at a whole tick the run passed. A running observation sees the committed
/// events (lp_seen.hpp) and is synced once, at the end: the observation is e.run's bit for bit
/// (a chunk that ran past the count is then discarded and its rest run sequentially, since an
/// observation cannot run back). `small`: runs of at most that many
/// collisions stay sequential (0: max(8192, N/4)); `bias` (tests): scales the chunks' ticks (> 1
/// runs past the count, which the sequential engine then runs back).
template <class Engine>
ParallelReport run_parallel(Engine& e, std::uint64_t collisions, std::int64_t until, const typename TimeWarp<Engine>::Config& c,
                            const std::function<bool()>& poll = {}, std::uint64_t small = 0, double bias = 1.0) {
  require(until >= e.clock(), "lattice run: the end tick is before the clock");
  require(until < tick_limit, "lattice run: the end tick is beyond the tick limit 2^61");
  constexpr std::uint64_t all = std::numeric_limits<std::uint64_t>::max();
  constexpr std::uint64_t probe = 4096, tail = 4096;
  if (small == 0) small = std::max<std::uint64_t>(probe + tail, e.size() / 4);
  ParallelReport r;
  if (collisions == 0) return r;
  struct Synced {  // the run's parts observed as one run: its observation synced once, at its end
    Engine& e;
    bool was;
    ~Synced() {
      e.sync_after_run = was;
      if (was && std::uncaught_exceptions() == 0) e.sync_observation();
    }
  } synced{e, e.sync_after_run};
  e.sync_after_run = false;
  const bool observed = e.observing();
  const std::uint64_t c0 = e.collisions();
  const std::uint64_t target = collisions >= all - c0 ? all : c0 + collisions;
  const bool by_count = target != all;
  using clock_type = std::chrono::steady_clock;
  const auto since = [](clock_type::time_point t0) { return std::chrono::duration<double>(clock_type::now() - t0).count(); };
  const auto sequential = [&](std::uint64_t n) {
    const auto t0 = clock_type::now();
    const std::uint64_t did = e.run(n, until, poll);
    r.sequential_s += since(t0);
    r.sequential += did;
    r.collisions += did;
    r.stopped = did < n && e.clock() < until;  // (a run short of n ends at until, or at a Ctrl-C)
    return did;
  };
  if (by_count && collisions <= small) {
    sequential(collisions);
    return r;
  }
  const typename Engine::Snapshot start = e.snapshot();
  try {
    double per = 0.0;  // ticks per collision
    if (by_count) {
      const std::int64_t t0 = e.clock();
      const std::uint64_t did = sequential(probe);
      if (did < probe) return r;  // the run reached until (or a Ctrl-C)
      per = static_cast<double>(e.clock() - t0) / static_cast<double>(did);
    }
    auto t0 = clock_type::now();
    typename TimeWarp<Engine>::Config cs = c;
    if (cs.shell < 0.0) cs.shell = e.list_shell();  // the LPs search as e does (cells or its lists)
    typename Engine::Snapshot s, before = e.snapshot();  // before: the state before the chunk (an observed run's)
    e.release();  // (the state is the LPs' until the run ends: the engine's memory meanwhile)
    auto tw = std::make_unique<TimeWarp<Engine>>(before, cs);
    if (!observed) before = {};
    r.build_s = since(t0);
    for (std::int64_t clock = e.clock(); r.chunks < 3;) {
      const std::uint64_t had = e.collisions() + r.parallel;
      std::int64_t t = until;
      if (by_count) {
        if (had + tail >= target) break;  // (at or past the count: the tail, or back)
        const double left = static_cast<double>(target - had);
        // short of the count (running past it costs a run back, two rebuilds of the search; short
        // of it, a cheap further chunk or tail): the probe's rate is good to 1/64 in a steady
        // state, but a gas still relaxing changes its rate by several per cent over a run, so the
        // first chunk aims at 85%, the next at 97% of the rest at the rate the last chunk measured
        const double aim = r.chunks == 0 ? 0.85 * left : 0.97 * left - 4.0 * std::sqrt(left);
        const double ticks = std::max(1.0, std::floor(aim * per * bias));
        if (ticks < static_cast<double>(until - clock)) t = clock + static_cast<std::int64_t>(ticks);
      }
      if (observed && r.chunks > 0) before = s;
      t0 = clock_type::now();
      const bool whole = tw->run_until(t, poll);
      r.parallel_s += since(t0);
      t0 = clock_type::now();
      s = tw->snapshot();
      r.assemble_s += since(t0);
      ++r.chunks;
      const std::uint64_t did = s.collisions - had;
      r.parallel += did;
      if (did > 0) per = static_cast<double>(s.clock - clock) / static_cast<double>(did);
      clock = s.clock;
      if (!whole) r.stopped = true;
      if (observed && by_count && s.collisions >= target) {  // at or past the count: discarded (see above)
        r.overshoot = s.collisions - target;
        r.parallel -= did;
        s = std::move(before);
        break;
      }
      if (!whole || t == until || !by_count) break;
    }
    r.stats = tw->stats();
    t0 = clock_type::now();
    if (r.chunks == 0) s = tw->snapshot();  // (no chunk ran: the state it was built from)
    tw.reset();  // (its K views' memory, before the engine rebuilds its own)
    e.restore(s);
    r.assemble_s += since(t0);
    r.collisions += r.parallel;
    if (r.stopped || !by_count) return r;
    // the chunk ran past the count, or reached it on a tick after its collision's: back, exactly,
    // to right after it (run_back stops before the collision it would take back next)
    if (e.collisions() > target || (e.collisions() == target && r.chunks > 0 && r.parallel > 0)) {
      r.overshoot = e.collisions() - target;
      r.collisions -= r.overshoot;
      r.parallel -= r.overshoot;
      t0 = clock_type::now();
      e.run_back(target, e.origin(), poll);
      r.sequential_s += since(t0);
      r.stopped = e.collisions() > target;
    } else if (e.collisions() < target && e.clock() < until) {
      sequential(target - e.collisions());
    }
    return r;
  } catch (...) {
    e.restore(start);
    throw;
  }
}

/// Runs engine e back, as e.run_back(to_collisions, to_tick) does (bit for bit the same state),
/// on K logical processes in run_back's reversed frame (TimeWarp's Config::back; a straggler is
/// rolled back by computing the back steps' forward collisions again, whatever c.how). The
/// parallel engine runs back to a tick: chunks to ticks estimated from the run's mean ticks per
/// collision, the first at 85% of the collisions to undo, the next just past the count (by 3% of
/// the rest and four standard errors, at the rate the last chunk measured); then the sequential
/// engine runs forward again, exactly, the few a chunk took back past the count (a sequential
/// tail back would cost two rebuilds of the search, its frame flipped and back; it runs only
/// when three chunks fell short, or one landed on the count on a later tick than its collision's).
/// Runs back of at most `small` collisions (0: max(8192, N/4)) stay sequential. An engine error
/// leaves e's state as it was; Ctrl-C leaves it at a whole tick the run passed. Ends a running
/// observation (as run_back does). `bias` (tests): scales the chunks' ticks (> 1 runs past the
/// count).
template <class Engine>
ParallelReport run_parallel_back(Engine& e, std::uint64_t to_collisions, std::int64_t to_tick, const typename TimeWarp<Engine>::Config& c,
                                 const std::function<bool()>& poll = {}, std::uint64_t small = 0, double bias = 1.0) {
  require(to_collisions <= e.collisions(), "lattice run_back: the target collision count is ahead of the state");
  require(to_tick >= e.origin() && to_tick <= e.clock(), "lattice run_back: the target tick must be in [origin, clock]");
  if (small == 0) small = std::max<std::uint64_t>(8192, e.size() / 4);
  ParallelReport r;
  e.stop_observing();  // observation is forward only
  using clock_type = std::chrono::steady_clock;
  const auto since = [](clock_type::time_point t0) { return std::chrono::duration<double>(clock_type::now() - t0).count(); };
  const auto sequential = [&] {
    const auto t0 = clock_type::now();
    const std::uint64_t had = e.collisions();
    e.run_back(to_collisions, to_tick, poll);
    r.sequential_s += since(t0);
    r.sequential += had - e.collisions();
    r.collisions += had - e.collisions();
    r.stopped = e.collisions() > to_collisions && e.clock() > to_tick;
  };
  const std::uint64_t c0 = e.collisions();
  if (c0 - to_collisions <= small || e.clock() == to_tick) {
    sequential();
    return r;
  }
  const typename Engine::Snapshot start = e.snapshot();
  try {
    // ticks per collision: the run's mean since its origin (then the last chunk's)
    double per = static_cast<double>(e.clock() - e.origin()) / static_cast<double>(c0);
    auto t0 = clock_type::now();
    typename TimeWarp<Engine>::Config cs = c;
    if (cs.shell < 0.0) cs.shell = e.list_shell();
    cs.back = true;
    cs.how = Rollback::reverse;
    e.release();  // (the state is the LPs' until the run ends: the engine's memory meanwhile)
    auto tw = std::make_unique<TimeWarp<Engine>>(start, cs);
    r.build_s = since(t0);
    typename Engine::Snapshot s;
    for (std::int64_t clock = e.clock(); r.chunks < 3;) {
      const std::uint64_t had = c0 - r.parallel;
      if (had <= to_collisions) break;  // (at or past the count)
      const double left = static_cast<double>(had - to_collisions);
      const double aim = r.chunks == 0 ? 0.85 * left : 1.03 * left + 4.0 * std::sqrt(left) + 16.0;
      const double ticks = std::max(1.0, std::floor(aim * per * bias));
      // (past a count of 0 is the start: to_tick, where run_back ends with no collision left)
      const bool start = r.chunks > 0 && to_collisions == 0;
      const std::int64_t to = ticks < static_cast<double>(clock - to_tick) && !start ? clock - static_cast<std::int64_t>(ticks) : to_tick;
      t0 = clock_type::now();
      const bool whole = tw->run_until(-to, poll);  // (the reversed frame's tick)
      r.parallel_s += since(t0);
      t0 = clock_type::now();
      s = tw->snapshot();
      r.assemble_s += since(t0);
      ++r.chunks;
      const std::uint64_t did = had - s.collisions;
      r.parallel += did;
      if (did > 0) per = static_cast<double>(clock - s.clock) / static_cast<double>(did);
      clock = s.clock;
      if (!whole) r.stopped = true;
      if (!whole || to == to_tick) break;
    }
    r.stats = tw->stats();
    t0 = clock_type::now();
    tw.reset();
    e.restore(r.chunks > 0 ? s : start);
    r.assemble_s += since(t0);
    r.collisions += r.parallel;
    if (r.stopped) return r;
    if (e.collisions() < to_collisions) {  // a chunk ran back past the count: forward, exactly, to right after it
      r.overshoot = to_collisions - e.collisions();
      r.collisions -= r.overshoot;
      r.parallel -= r.overshoot;
      t0 = clock_type::now();
      e.run(r.overshoot, start.clock, poll);
      r.sequential_s += since(t0);
      r.stopped = e.collisions() < to_collisions;
    } else if (e.collisions() >= to_collisions && e.clock() > to_tick) {
      // (at the count but on a later tick than its collision's, or short of it: run_back goes on
      // to the next collision it would take back, or to the tick)
      sequential();
    }
    return r;
  } catch (...) {
    e.restore(start);
    throw;
  }
}

}  // namespace revcol::lattice
