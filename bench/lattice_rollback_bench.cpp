// The rollback family of revcol-bench: what the lattice engine's journal and rollback
// (rollback.hpp) cost, the two halves of a Time Warp logical process's reverse computation.
// From a gas warmed up by a collision per particle, twice in turn (A B A B):
//   A  run(n) forward without the journal;
//   B  run(n) forward keeping the journal, then undo all n collisions: the first quarter one
//      collision per rollback, the second 100 per rollback, the rest in one, back to the start.
// Metrics (medians of the two turns): forward_per_s (A), forward_journal_per_s (B), and the
// collisions undone per second at each rollback length (undo_per_s_L1, undo_per_s_L100,
// undo_per_s_bulk); journal_bytes_per_collision; bit_exact (1 when B's forward state equals A's
// and the rollbacks end at the start state, bit for bit); events_per_collision; n, phi.
//
//   revcol-bench --bench rollback/ --collisions 1000000
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <string>
#include <type_traits>
#include <vector>

#include "bench.hpp"
#include "revcol/lattice/engine.hpp"

namespace revcol::bench {
namespace {

namespace la = revcol::lattice;

template <std::size_t D>
using EngineOf = std::conditional_t<D == 2, la::LatticeEngine, la::LatticeEngine3D>;

struct RollbackCase {
  std::size_t n;
  double phi;
  bool walls;
};

template <std::size_t D>
std::vector<Metric> run_rollback(const RollbackCase& c, std::uint64_t nc) {
  la::LatticeConfigN<D> cfg;
  cfg.wall = la::filled<D>(c.walls);
  cfg.seed = 1;
  const la::LatticeStartN<D> st = la::random_start(cfg, c.n, c.phi, 1, D == 2 && c.phi > 0.35 ? "crystal" : "auto");
  EngineOf<D> e(st.units, st.x, st.v, cfg.seed, la::operator_for(st.units));
  e.run(c.n, la::tick_limit - 1);  // warm up
  const la::SnapshotN<D> s0 = e.snapshot();
  using clock = std::chrono::steady_clock;
  std::vector<double> fwd, fwdj, l1, l100, bulk, bytes, events;
  bool exact = true;
  for (int turn = 0; turn < 2; ++turn) {
    // A: forward, no journal
    e.keep_journal(false);
    e.restore(s0);
    auto t0 = clock::now();
    const std::uint64_t done = e.run(nc, la::tick_limit - 1);
    fwd.push_back(static_cast<double>(done) / seconds_since(t0));
    const la::SnapshotN<D> s1 = e.snapshot();
    // B: forward with the journal, then undo it all
    e.restore(s0);
    e.keep_journal(true);
    const std::uint64_t ev0 = e.counters().events;
    t0 = clock::now();
    e.run(nc, la::tick_limit - 1);
    fwdj.push_back(static_cast<double>(done) / seconds_since(t0));
    events.push_back(static_cast<double>(e.counters().events - ev0) / static_cast<double>(done));
    bytes.push_back(static_cast<double>(e.journal_size()) * 24.0 / static_cast<double>(done));
    exact = exact && la::same_state(e.snapshot(), s1);
    const std::uint64_t top = e.collisions(), q = done / 4;
    auto undo = [&](std::uint64_t to, std::uint64_t step) {
      const std::uint64_t from = e.collisions();
      const auto u0 = clock::now();
      while (e.collisions() > to) e.rollback(e.collisions() - std::min(step, e.collisions() - to));
      return static_cast<double>(from - to) / seconds_since(u0);
    };
    l1.push_back(undo(top - q, 1));
    l100.push_back(undo(top - 2 * q, 100));
    bulk.push_back(undo(s0.collisions, done));
    exact = exact && la::same_state(e.snapshot(), s0);
  }
  return {{"forward_per_s", median(fwd)},
          {"forward_journal_per_s", median(fwdj)},
          {"undo_per_s_L1", median(l1)},
          {"undo_per_s_L100", median(l100)},
          {"undo_per_s_bulk", median(bulk)},
          {"journal_bytes_per_collision", median(bytes)},
          {"events_per_collision", median(events)},
          {"bit_exact", exact ? 1.0 : 0.0},
          {"n", static_cast<double>(c.n)},
          {"phi", c.phi}};
}

}  // namespace

void add_rollback_benches(std::vector<Bench>& out) {
  struct Named {
    const char* name;
    int dim;
    RollbackCase c;
  };
  static const Named named[] = {{"rollback/d2/n10000/phi0.5", 2, {10000, 0.5, false}},
                                {"rollback/d2/n1000000/phi0.5", 2, {1000000, 0.5, false}},
                                {"rollback/d2/walls/n10000/phi0.5", 2, {10000, 0.5, true}},
                                {"rollback/d3/n10000/phi0.3", 3, {10000, 0.3, false}},
                                {"rollback/d3/n1000000/phi0.3", 3, {1000000, 0.3, false}}};
  for (const Named& m : named) {
    const RollbackCase c = m.c;
    const int dim = m.dim;
    out.push_back({m.name, "collisions/s", [c, dim](std::uint64_t k) { return dim == 3 ? run_rollback<3>(c, k) : run_rollback<2>(c, k); }});
  }
}

}  // namespace revcol::bench
