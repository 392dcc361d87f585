// run_parallel (parallel_run.hpp): a sequential engine's run on the parallel engine ends in the
// state e.run(collisions, until) reaches, bit for bit: at a collision count (a probe, chunks to
// estimated ticks, the sequential tail), past it and back (a biased estimate), at a tick, and
// as short runs that stay sequential; a running observation is the run's bit for bit (past the
// count, the chunk discarded); a Ctrl-C ends at a whole tick of the run; a bad configuration
// found after the probe leaves the state and its observation as they were.
#include <cstdint>
#include <cstdio>
#include <functional>
#include <stdexcept>

#include "check.hpp"
#include "lattice_gas_util.hpp"
#include "revcol/error.hpp"
#include "revcol/lattice/engine.hpp"
#include "revcol/lattice/parallel_run.hpp"

using namespace revcol::lattice;
namespace en = revcol::engine;

namespace {

using lattice_test::EngineOf;

template <std::size_t D>
typename TimeWarp<EngineOf<D>>::Config config(int k, int w) {
  return lattice_test::run_config<typename TimeWarp<EngineOf<D>>::Config>(k, w);
}

template <std::size_t D>
void check_counts(EngineOf<D> start, int k, int w, double bias, const char* what, bool observe = false) {
  if (observe) {
    en::ObserveConfig oc;
    oc.slabs = 3;
    oc.collision_record = true;
    start.observe(oc);
  }
  const SnapshotN<D> s0 = start.snapshot();
  EngineOf<D> ref(s0, operator_for(s0.units, s0.law)), e(s0, operator_for(s0.units, s0.law));
  std::uint64_t parallel = 0, overshoot = 0;
  for (const std::uint64_t n : {std::uint64_t{30000}, std::uint64_t{3000}, std::uint64_t{50000}}) {
    ref.run(n, tick_limit - 1);
    const ParallelReport r = run_parallel(e, n, tick_limit - 1, config<D>(k, w), {}, 0, bias);
    CHECK(r.collisions == n);
    CHECK(r.parallel + r.sequential == n);
    CHECK(!r.stopped);
    CHECK(same_state(e.snapshot(), ref.snapshot()));
    CHECK(e.snapshot().observer == ref.snapshot().observer && e.observing() == observe);
    parallel += r.parallel;
    overshoot += r.overshoot;
  }
  // to a tick
  const std::int64_t t = e.clock() + (e.clock() - s0.clock) / 4;
  ref.run(~std::uint64_t{0}, t);
  const ParallelReport r = run_parallel(e, ~std::uint64_t{0}, t, config<D>(k, w));
  CHECK(r.sequential == 0 && r.chunks == 1 && e.clock() == t);
  CHECK(same_state(e.snapshot(), ref.snapshot()));
  CHECK(e.snapshot().observer == ref.snapshot().observer);
  std::printf("  %s, K = %d, %d worker(s), bias %.2f: %llu collisions in parallel, %llu run past the count (back, or observed: discarded)\n", what, k, w, bias,
              static_cast<unsigned long long>(parallel), static_cast<unsigned long long>(overshoot));
  // (observed, a chunk past the count is discarded: at this bias every first chunk is)
  CHECK(observe && bias > 1.0 ? parallel == 0 : parallel > 40000);
  if (bias > 1.0) CHECK(overshoot > 0);  // the run-back path was taken
  // a collision count the tick stops first: the clock at the tick, as run's
  ref.run(1000000, ref.clock() + 10);
  run_parallel(e, 1000000, e.clock() + 10, config<D>(k, w));
  CHECK(same_state(e.snapshot(), ref.snapshot()));
}

}  // namespace

TEST_CASE("run_parallel reaches the sequential run's state at a count and at a tick") {
  using B = en::Boundary;
  check_counts<2>(lattice_test::make_gas<2>(2000, 0.4, B::periodic, 81, 16), 2, 2, 1.0, "2D 0.4 periodic");
  check_counts<2>(lattice_test::make_gas<2>(2000, 0.4, B::wall, 82, 16), 3, 1, 1.2, "2D 0.4 walls");
  check_counts<3>(lattice_test::make_gas<3>(2000, 0.3, B::periodic, 83, 16), 2, 2, 1.2, "3D 0.3 periodic");
  check_counts<2>(lattice_test::make_gas<2>(2000, 0.4, B::periodic, 81, 16), 2, 2, 1.0, "2D 0.4 periodic, observed", true);
  check_counts<2>(lattice_test::make_gas<2>(2000, 0.4, B::wall, 82, 16), 3, 1, 1.2, "2D 0.4 walls, observed", true);
  check_counts<3>(lattice_test::make_gas<3>(2000, 0.35, B::bounce, 86, 16), 2, 2, 1.0, "3D 0.35 bounce walls, observed", true);
}

TEST_CASE("a Ctrl-C ends a parallel run at a whole tick of the sequential run") {
  auto e = lattice_test::make_gas<2>(2000, 0.4, en::Boundary::periodic, 84, 16);
  const SnapshotN<2> s0 = e.snapshot();
  int polls = 0;
  const std::function<bool()> poll = [&] { return ++polls < 40; };
  const ParallelReport r = run_parallel(e, 200000, tick_limit - 1, config<2>(2, 2), poll);
  CHECK(r.stopped);
  CHECK(r.collisions < 200000);
  EngineOf<2> ref(s0, operator_for(s0.units, s0.law));
  ref.run(~std::uint64_t{0}, e.clock());  // the state run(until = that tick) has
  CHECK(same_state(e.snapshot(), ref.snapshot()));
}

TEST_CASE("a configuration refused after the probe leaves the state and its observation") {
  auto e = lattice_test::make_gas<2>(2000, 0.4, en::Boundary::periodic, 85, 16);
  e.run(5000, tick_limit - 1);
  e.observe(en::ObserveConfig{});
  e.run(5000, tick_limit - 1);
  const SnapshotN<2> s0 = e.snapshot();
  bool refused = false;
  try {
    run_parallel(e, 50000, tick_limit - 1, config<2>(2, 3));  // more workers than LPs: TimeWarp refuses
  } catch (const revcol::InvalidArgument&) {
    refused = true;
  }
  CHECK(refused && e.observing() && e.sync_after_run);
  CHECK(same_state(e.snapshot(), s0) && e.snapshot().observer == s0.observer);
}

int main() { return check::run_all(); }
