// The parallel lattice engine (timewarp.hpp): K logical processes on slabs, optimistic, rolled
// back by reverse computation, commit the sequential engine's state bit for bit at every tick it
// is asked to stop at, for K = 1 to 8, 2D and 3D, walls and periodic, in a round-robin schedule
// and in random schedules with random message delays; a state that no schedule may change; an
// observation running through the parallel run is the sequential run's bit for bit (threads: with
// more LPs than threads too, where LPs sharing a thread run in key order among themselves).
#include <cstdio>
#include <algorithm>
#include <cstdlib>
#include <set>
#include <vector>

#include "check.hpp"
#include "lattice_gas_util.hpp"
#include "revcol/lattice/engine.hpp"
#include "revcol/lattice/timewarp.hpp"

using namespace revcol::lattice;
namespace en = revcol::engine;
using revcol::Mode;

namespace {

using lattice_test::EngineOf;

constexpr std::uint64_t kThreads = ~std::uint64_t{0};  // a schedule: two worker threads

// collisions per stop, from the environment for longer runs
std::uint64_t scaled(std::uint64_t n) {
  const char* s = std::getenv("REVCOL_TIMEWARP_SCALE");
  return s == nullptr ? n : n * std::strtoull(s, nullptr, 10);
}

template <std::size_t D>
void check_parallel(EngineOf<D> e, int axis, const std::vector<int>& ks, const std::vector<std::uint64_t>& fuzz,
                    std::uint64_t per_stop, const char* what, double shell = -1.0, bool observe = false) {
  e.run(e.size(), tick_limit - 1);
  if (observe) {  // a running observation: the parallel engine's, fed its committed events, is the sequential one's
    en::ObserveConfig oc;
    oc.slabs = 4;
    oc.speed_bins = 16;
    oc.collision_record = true;
    e.observe(oc);
  }
  const SnapshotN<D> s0 = e.snapshot();
  // the sequential engine's state at three stops (every event at or before each stop's tick)
  EngineOf<D> ref(s0, operator_for(s0.units, s0.law));
  ref.sync_after_run = false;  // (the parallel engine's observation is not synced at a stop)
  std::vector<std::array<std::int64_t, 3>> rtrace;
  ref.trace = &rtrace;
  std::vector<SnapshotN<D>> want;
  for (int k = 0; k < 3; ++k) {
    ref.run(per_stop, tick_limit - 1);
    ref.run(~std::uint64_t{0}, ref.clock());
    want.push_back(ref.snapshot());
  }
  for (int K : ks)
    for (std::uint64_t f : fuzz) {
      typename TimeWarp<EngineOf<D>>::Config c;
      c.lps = K;
      c.axis = axis;
      c.fuzz = f == kThreads ? 0 : f % 1000;
      c.workers = f == kThreads ? std::min(K, 2) : 1;
      c.lazy = f < 1000;  // (a fuzz seed from 1000 up: aggressive cancellation)
      c.batch = 8;
      c.shell = shell;  // the LPs' search: -1 the sequential engine's automatic one (3D lists, 2D cells)
      if (f == kThreads && K == 1) continue;
      if (const char* d = std::getenv("TW_DELAY")) c.max_delay = std::atoi(d);
      if (const char* d = std::getenv("TW_GVT")) c.gvt_every = std::strtoull(d, nullptr, 10);
      TimeWarp<EngineOf<D>> tw(s0, c);
      CHECK((tw.engine(0).neighbour_search() == 0) == (shell == 0.0 || (shell < 0.0 && D == 2)));
      std::vector<std::vector<std::array<std::int64_t, 3>>> traces(static_cast<std::size_t>(K));
      for (int m = 0; m < K; ++m) tw.engine(m).trace = &traces[static_cast<std::size_t>(m)];
      bool same = true;
      for (const auto& w : want) {
        tw.run_until(w.clock);
        const SnapshotN<D> got = tw.snapshot();
        const bool eq = same_state(got, w) && got.observer == w.observer && got.observer_counts == w.observer_counts &&
                        got.counters.field_wall_impulse == w.counters.field_wall_impulse;  // (a field's walls' momentum)
        CHECK(!observe || got.observer.size() > 100);
        if (!eq) {
          const SnapshotN<D>& g = got;
          std::printf("    differs at tick %lld: collisions %llu / %llu, log %zu / %zu, groups %zu / %zu\n", static_cast<long long>(w.clock),
                      (unsigned long long)g.collisions, (unsigned long long)w.collisions, g.log.size(), w.log.size(), g.groups.size(), w.groups.size());
          std::set<std::array<std::int64_t, 3>> have;
          for (const auto& t : traces) have.insert(t.begin(), t.end());
          int miss = 0;
          for (const auto& t : rtrace)
            if (t[0] <= w.clock && !have.count(t) && miss++ < 5) {
              std::printf("      missing collision tick %lld (%lld, %lld); in LPs:", (long long)t[0], (long long)t[1], (long long)t[2]);
              for (int m = 0; m < K; ++m) std::printf(" LP%d holds %d/%d region %d/%d", m, (int)tw.engine(m).held((int)t[1]), (int)tw.engine(m).held((int)t[2]),
                                                      tw.engine(m).region((int)t[1]), tw.engine(m).region((int)t[2]));
              std::printf("\n");
            }
          int shown = 0;
          for (std::size_t p = 0; p < g.x.size() && shown < 5; ++p)
            if (g.x[p] != w.x[p] || g.v[p] != w.v[p] || g.streams[p] != w.streams[p] || g.particle_collisions[p] != w.particle_collisions[p]) {
              ++shown;
              std::printf("      particle %zu: x %lld/%lld v %lld/%lld ctr %llu/%llu pc %llu/%llu\n", p, (long long)g.x[p][0], (long long)w.x[p][0],
                          (long long)g.v[p][0], (long long)w.v[p][0], (unsigned long long)g.streams[p], (unsigned long long)w.streams[p],
                          (unsigned long long)g.particle_collisions[p], (unsigned long long)w.particle_collisions[p]);
            }
        }
        same = same && eq;
      }
      const TimeWarpStats& st = tw.stats();
      std::printf("  %s (%s), K = %d, %s: %llu collisions; events %llu, rollbacks %llu (%llu undone), messages %llu, anti %llu, "
                  "confirmed %llu, written %llu, blocked %llu: same as sequential: %s\n",
                  what, tw.engine(0).neighbour_search() == 0 ? "cells" : "lists", K, f == kThreads ? "2 threads" : f == 0 ? "round robin" : f < 1000 ? "fuzzed" : "fuzzed, aggressive", static_cast<unsigned long long>(want.back().collisions - s0.collisions),
                  static_cast<unsigned long long>(st.events), static_cast<unsigned long long>(st.rollbacks),
                  static_cast<unsigned long long>(st.undone), static_cast<unsigned long long>(st.messages),
                  static_cast<unsigned long long>(st.anti), static_cast<unsigned long long>(st.confirmed),
                  static_cast<unsigned long long>(st.written), static_cast<unsigned long long>(st.blocked), same ? "yes" : "NO");
      CHECK(same);
    }
}

}  // namespace

// (REVCOL_TIMEWARP_SCALE=s runs s times the collisions: the long form of the same test)
TEST_CASE("the parallel engine commits the sequential state bit for bit (2D)") {
  using B = en::Boundary;
  check_parallel<2>(lattice_test::make_gas<2>(400, 0.4, B::periodic, 71, 16), 0, {1, 2, 3, 4, 8}, {0, 5, 1006, kThreads}, scaled(2000),
                    "2D 0.4 periodic");
  check_parallel<2>(lattice_test::make_gas<2>(400, 0.4, B::periodic, 71, 16), 0, {1, 3, 8}, {5, 1006, kThreads}, scaled(2000),
                    "2D 0.4 periodic, observed", -1.0, true);
  check_parallel<2>(lattice_test::make_gas<2>(1000, 0.6, B::wall, 73, 16), 1, {2, 3, 8}, {0, 8, kThreads}, scaled(3000), "2D 0.6 walls");
  check_parallel<2>(lattice_test::make_gas<2>(1000, 0.6, B::wall, 73, 16), 1, {3}, {8, kThreads}, scaled(3000), "2D 0.6 walls, observed", -1.0,
                    true);
  check_parallel<2>(lattice_test::make_gas<2>(600, 0.4, B::periodic, 74, 16, Mode::specular), 0, {2, 4}, {0, 9}, scaled(2000),
                    "2D 0.4 periodic specular");
  check_parallel<2>(lattice_test::make_gas<2>(1000, 0.5, B::periodic, 78, 16), 0, {2, 4}, {0, 13, kThreads}, scaled(2000), "2D 0.5 periodic",
                    0.6);
}

TEST_CASE("the parallel engine commits the sequential state bit for bit (3D)") {
  using B = en::Boundary;
  check_parallel<3>(lattice_test::make_gas<3>(1000, 0.3, B::periodic, 75, 16), 2, {1, 2, 4, 8}, {0, 1010, kThreads}, scaled(3000),
                    "3D 0.3 periodic");
  check_parallel<3>(lattice_test::make_gas<3>(1000, 0.3, B::periodic, 75, 16), 2, {2, 3}, {14, kThreads}, scaled(3000), "3D 0.3 periodic", 0.0);
  check_parallel<3>(lattice_test::make_gas<3>(1000, 0.35, B::bounce, 76, 16), 0, {2, 3}, {11, kThreads}, scaled(3000), "3D 0.35 bounce walls");
  check_parallel<3>(lattice_test::make_gas<3>(1000, 0.35, B::bounce, 76, 16), 0, {3}, {11, kThreads}, scaled(3000), "3D 0.35 bounce walls, observed",
                    -1.0, true);
  check_parallel<3>(lattice_test::make_gas<3>(600, 0.25, B::wall, 77, 16, Mode::specular), 1, {2}, {12}, scaled(2000), "3D 0.25 walls specular");
}

TEST_CASE("the parallel engine commits the sequential state bit for bit in a field (cut across it)") {
  using B = en::Boundary;
  check_parallel<2>(lattice_test::make_gas<2>(600, 0.4, B::periodic, 171, 16, Mode::exact, -2.0), 0, {1, 2, 3, 8}, {0, 5, 1006, kThreads},
                    scaled(2000), "2D 0.4 channel, g = -2");
  check_parallel<2>(lattice_test::make_gas<2>(600, 0.4, B::periodic, 171, 16, Mode::exact, -2.0), 0, {3}, {5, kThreads}, scaled(2000),
                    "2D 0.4 channel, g = -2, observed", -1.0, true);
  check_parallel<3>(lattice_test::make_gas<3>(1000, 0.3, B::wall, 175, 16, Mode::exact, -1.0), 0, {2, 4}, {0, 1010, kThreads}, scaled(3000),
                    "3D 0.3 walls, g = -1");
  check_parallel<3>(lattice_test::make_gas<3>(1000, 0.3, B::periodic, 176, 16, Mode::specular, -2.0), 1, {2, 3}, {14, kThreads}, scaled(3000),
                    "3D 0.3 slab specular, g = -2", 0.0);
  // along the field: refused by name, nothing built
  auto e = lattice_test::make_gas<2>(200, 0.3, B::periodic, 172, 16, Mode::exact, -2.0);
  typename TimeWarp<EngineOf<2>>::Config c;
  c.lps = 2;
  c.axis = 1;
  CHECK(lattice_test::refused([&] { TimeWarp<EngineOf<2>> tw(e.snapshot(), c); }, "cut across the field"));
}

// the threaded schedule caps a turn by the other LPs on its worker: share_of must name the
// very items run_workers gives that worker
TEST_CASE("share_of gives each item the share of the worker that runs it") {
  for (int w = 1; w <= 4; ++w)
    for (int k = w; k <= 9; ++k) {
      std::vector<int> seen(static_cast<std::size_t>(k), 0);
      std::vector<std::pair<int, int>> shares;
      for (int me = 0; me < w; ++me) shares.push_back({me * k / w, (me + 1) * k / w});  // run_workers' shares
      for (int i = 0; i < k; ++i) {
        const std::pair<int, int> s = share_of(i, w, k);
        CHECK(s.first <= i && i < s.second);
        CHECK(std::find(shares.begin(), shares.end(), s) != shares.end());
        for (int j = s.first; j < s.second; ++j) ++seen[static_cast<std::size_t>(j)];
      }
      for (int i = 0; i < k; ++i) {  // every item in one share, counted once per member of it
        const std::pair<int, int> s = share_of(i, w, k);
        CHECK(seen[static_cast<std::size_t>(i)] == s.second - s.first);
      }
    }
}

int main() { return check::run_all(); }
