// "Skip what a scene doesn't need", measured. A 2D pair-only gas (the default scene: N =
// 1000 disks, area fraction 0.3, walls, exact mode, flux law) against the same gas with the
// 3-particle machinery forced on, and the one-time cost of the paper-mode tables that only
// a scene with paper-mode triples builds.
//
//   skip/gas2d-pairs          start-up and per-collision cost of the pair-only scene
//   skip/gas2d-forced-groups   the same scene with the group search run at every collision
//                              (Config::force_group_search: what an engine without the
//                              gate would pay; the result is the same gas, no group forms)
//   skip/paper-tables          building the three lazily built GSL tables (calotte areas
//                              H4, H3 of the 2D triple, ellipse-arc inverse of the 1D triple)
//
// Metrics: startup_ms (make_simulation: validation, cell list, first event predictions),
// forward_ns_per_collision, reverse_ns_per_collision, paper_tables_built (the process's
// count after the run: 0 means the pair scene built none), groups_searched (forced
// scene), build_ms_calotte_h4, build_ms_calotte_h3, build_ms_ellipse_table. Tables are
// built once per process: run skip/paper-tables with --repeats 1 in a fresh process.
#include <chrono>
#include <cstdint>
#include <limits>

#include "bench.hpp"
#include "revcol/collide/calotte.hpp"
#include "revcol/collide/ellipse_arc.hpp"
#include "revcol/collide/tables.hpp"
#include "revcol/engine/engine.hpp"
#include "revcol/engine/init.hpp"

namespace revcol::bench {
namespace {

namespace en = revcol::engine;
using Clock = std::chrono::steady_clock;

std::vector<Metric> pair_scene(std::uint64_t n, bool force_groups) {
  en::Config c;
  c.dim = 2;
  c.boundary = {en::Boundary::wall, en::Boundary::wall, en::Boundary::wall};
  c.force_group_search = force_groups;
  const en::InitialState st = en::random_state(c, 1000, 0.3, 1);
  const auto t0 = Clock::now();
  auto sim = en::make_simulation(st.config, st.x, st.v);
  const double startup = seconds_since(t0);
  const auto t1 = Clock::now();
  const en::RunResult f = sim->run(n, std::numeric_limits<double>::infinity());
  const double fwd = seconds_since(t1);
  const auto t2 = Clock::now();
  const en::RunResult r = sim->run_back(f.collisions, -std::numeric_limits<double>::infinity());
  const double rev = seconds_since(t2);
  const en::Diagnostics d = sim->diagnostics();
  return {{"startup_ms", 1e3 * startup},
          {"forward_ns_per_collision", 1e9 * fwd / static_cast<double>(f.collisions)},
          {"reverse_ns_per_collision", 1e9 * rev / static_cast<double>(r.collisions)},
          {"paper_tables_built", static_cast<double>(paper::tables_built())},
          {"group_collisions", static_cast<double>(d.counters.group_collisions)}};
}

}  // namespace

void add_skip_benches(std::vector<Bench>& out) {
  out.push_back({"skip/gas2d-pairs", "collisions", [](std::uint64_t n) { return pair_scene(n, false); }});
  out.push_back({"skip/gas2d-forced-groups", "collisions", [](std::uint64_t n) { return pair_scene(n, true); }});
  out.push_back({"skip/paper-tables", "tables", [](std::uint64_t) {
                   const int before = paper::tables_built();
                   auto t0 = Clock::now();
                   (void)paper::CalotteTable::h4();
                   const double h4 = seconds_since(t0);
                   t0 = Clock::now();
                   (void)paper::CalotteTable::h3();
                   const double h3 = seconds_since(t0);
                   t0 = Clock::now();
                   const paper::EllipseArc arc(paper::ArcMethod::table);
                   const double el = seconds_since(t0);
                   return std::vector<Metric>{{"build_ms_calotte_h4", 1e3 * h4},
                                              {"build_ms_calotte_h3", 1e3 * h3},
                                              {"build_ms_ellipse_table", 1e3 * el},
                                              {"tables_built_before", static_cast<double>(before)},
                                              {"paper_tables_built", static_cast<double>(paper::tables_built())}};
                 }});
}

}  // namespace revcol::bench
