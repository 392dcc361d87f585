// The rollback family of revcol-bench: what the lattice engine's journal and rollback
// (rollback.hpp) cost, the two halves of a Time Warp logical process's rollback, by reverse
// computation (RC) and by the paper's two kinds of state saving (SS1: each touched particle's
// whole record before every event; SS2: only the lines and X an event changes).
// From a gas warmed up by a collision per particle, twice in turn (A RC SS1 SS2 A RC SS1 SS2):
//   A   run(n) forward without the journal;
//   RC, SS1, SS2  run(n) forward keeping the journal so, then undo all n collisions: the first
//       quarter one collision per rollback, the second 100 per rollback, the rest in one.
// Metrics (medians of the two turns): forward_per_s (A); per variant v in rc, ss1, ss2:
// forward_v_per_s, undo_v_per_s_L1, undo_v_per_s_L100, undo_v_per_s_bulk (collisions undone
// per second at each rollback length) and journal_v_bytes_per_collision (the journal's memory
// after the forward run); bit_exact (1 when every variant's forward state equals A's and its
// rollbacks end at the start state, bit for bit); events_per_collision; n, phi.
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
  const la::Rollback hows[3] = {la::Rollback::reverse, la::Rollback::save_all, la::Rollback::save_changes};
  const char* names[3] = {"rc", "ss1", "ss2"};
  std::vector<double> fwd, events, fwdj[3], l1[3], l100[3], bulk[3], bytes[3];
  bool exact = true;
  for (int turn = 0; turn < 2; ++turn) {
    // A: forward, no journal
    e.keep_journal(false);
    e.restore(s0);
    auto t0 = clock::now();
    const std::uint64_t done = e.run(nc, la::tick_limit - 1);
    fwd.push_back(static_cast<double>(done) / seconds_since(t0));
    const la::SnapshotN<D> s1 = e.snapshot();
    for (int v = 0; v < 3; ++v) {
      // forward with the journal, then undo it all
      e.restore(s0);
      e.keep_journal(true, hows[v]);
      const std::uint64_t ev0 = e.counters().events;
      t0 = clock::now();
      e.run(nc, la::tick_limit - 1);
      fwdj[v].push_back(static_cast<double>(done) / seconds_since(t0));
      if (v == 0) events.push_back(static_cast<double>(e.counters().events - ev0) / static_cast<double>(done));
      bytes[v].push_back(static_cast<double>(e.journal_bytes()) / static_cast<double>(done));
      exact = exact && la::same_state(e.snapshot(), s1);
      const std::uint64_t top = e.collisions(), q = done / 4;
      auto undo = [&](std::uint64_t to, std::uint64_t step) {
        const std::uint64_t from = e.collisions();
        const auto u0 = clock::now();
        while (e.collisions() > to) e.rollback(e.collisions() - std::min(step, e.collisions() - to));
        return static_cast<double>(from - to) / seconds_since(u0);
      };
      l1[v].push_back(undo(top - q, 1));
      l100[v].push_back(undo(top - 2 * q, 100));
      bulk[v].push_back(undo(s0.collisions, done));
      exact = exact && la::same_state(e.snapshot(), s0);
    }
  }
  std::vector<Metric> out{{"forward_per_s", median(fwd)}};
  for (int v = 0; v < 3; ++v) {
    const std::string n = names[v];
    out.push_back({"forward_" + n + "_per_s", median(fwdj[v])});
    out.push_back({"undo_" + n + "_per_s_L1", median(l1[v])});
    out.push_back({"undo_" + n + "_per_s_L100", median(l100[v])});
    out.push_back({"undo_" + n + "_per_s_bulk", median(bulk[v])});
    out.push_back({"journal_" + n + "_bytes_per_collision", median(bytes[v])});
  }
  out.push_back({"events_per_collision", median(events)});
  out.push_back({"bit_exact", exact ? 1.0 : 0.0});
  out.push_back({"n", static_cast<double>(c.n)});
  out.push_back({"phi", c.phi});
  return out;
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
