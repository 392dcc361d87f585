// The state-saving study in revcol-bench (workload and maths: revcol/studies/statesave.hpp).
//
//   statesave/<mode>/<transport>/<variant>     mode exact|paper, transport eager|lazy,
//                                               variant ss1|ss2|rc (eager), ss1|ss2|ssp|rc (lazy)
//
// --collisions is N_c. The rest comes from the environment, so that a plain revcol-bench
// run stays small (N = 1000; state saving over the budget is skipped, not attempted):
//
//   REVCOL_STATESAVE="n=1000000,seed=0,rng=clcg4,law=flux,budget=8589934592,prefault=1,mean_dt=1e-5,grazing_tol=1e-11"
//
// (every key optional; budget in bytes). revcol.statesave (revcol bench statesave) runs one
// (variant, N) per process, so that peak_rss_bytes (the process's VmHWM) is that run's.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>

#include "bench.hpp"
#include "revcol/error.hpp"
#include "revcol/studies/statesave.hpp"

namespace revcol::bench {
namespace {

namespace ss = revcol::statesave;

// REVCOL_STATESAVE's key=value list applied to c; throws InvalidArgument naming a bad entry.
void apply_environment(ss::Config& c) {
  apply_settings("REVCOL_STATESAVE", "n, seed, rng, law, bits, budget, prefault, mean_dt, grazing_tol",
                 [&](const std::string& key, const std::string& value) {
                   if (key == "n") c.particles = std::stoull(value);
                   else if (key == "seed") c.seed = std::stoull(value);
                   else if (key == "rng") c.rng = value;
                   else if (key == "law") c.law = parse_law(value);
                   else if (key == "bits") c.bits = std::stoi(value);
                   else if (key == "budget") c.budget_bytes = std::stoull(value);
                   else if (key == "prefault") c.prefault = value != "0";
                   else if (key == "mean_dt") c.mean_dt = std::stod(value);
                   else if (key == "grazing_tol") c.grazing_tol = std::stod(value);
                   else return false;
                   return true;
                 });
}

// JSON has no inf or NaN: a non-finite error (a rollback gone wrong) is reported as 1e300.
double finite(double x) { return std::isfinite(x) ? x : 1e300; }

std::vector<Metric> run_study(Mode mode, ss::Transport transport, ss::Variant variant, std::uint64_t n) {
  ss::Config c;
  c.collisions = n;
  c.mode = mode;
  c.transport = transport;
  c.variant = variant;
  ss::Result r;
  try {
    apply_environment(c);
    r = ss::run(c);
  } catch (const InvalidArgument& e) {
    std::fprintf(stderr, "revcol-bench: statesave: %s\n", e.what());
    std::exit(2);
  }
  if (!r.skipped && !r.restored) {
    std::fprintf(stderr, "warning: statesave/%s/%s/%s N=%llu did not restore the start (max rel error %.3g)%s%s\n",
                 to_string(mode), ss::to_string(transport), ss::to_string(variant),
                 static_cast<unsigned long long>(c.particles), r.max_rel_error, r.error.empty() ? "" : ": ",
                 r.error.c_str());
  }
  const double total = r.forward_s + r.rollback_s;
  auto d = [](std::uint64_t x) { return static_cast<double>(x); };
  return {{"forward_per_s", r.forward_s > 0 ? d(c.collisions) / r.forward_s : 0.0},
          {"forward_ms", 1e3 * r.forward_s},
          {"rollback_ms", 1e3 * r.rollback_s},
          {"total_ms", 1e3 * total},
          {"bytes_saved", d(r.bytes_saved)},
          {"record_bytes", d(r.record_bytes)},
          {"projected_bytes", d(r.projected_bytes)},
          {"state_bytes", d(r.state_bytes)},
          {"peak_rss_bytes", d(r.peak_rss_bytes)},
          {"rss_before_bytes", d(r.rss_before_bytes)},
          {"max_rel_error", finite(r.max_rel_error)},
          {"max_rel_error_x", finite(r.max_rel_error_x)},
          {"max_rel_error_v", finite(r.max_rel_error_v)},
          {"restored", r.restored ? 1.0 : 0.0},
          {"bit_exact", r.bit_exact ? 1.0 : 0.0},
          {"rng_restored", r.rng_restored ? 1.0 : 0.0},
          {"log_bytes", d(r.log_bytes)},
          {"rare_log_entries", d(r.rare_log_entries)},
          {"decision_log_entries", d(r.decision_log_entries)},
          {"pre_log_entries", d(r.pre_log_entries)},
          {"grazes", d(r.grazes)},
          {"draws", d(r.draws)},
          {"draws_undone", d(r.draws_undone)},
          {"skipped", r.skipped ? 1.0 : 0.0},
          {"particles", d(c.particles)}};
}

}  // namespace

void add_statesave_benches(std::vector<Bench>& out) {
  for (Mode mode : {Mode::exact, Mode::paper}) {
    for (ss::Transport t : {ss::Transport::eager, ss::Transport::lazy}) {
      for (const std::string& v : ss::variant_names(t)) {
        const ss::Variant variant = ss::parse_variant(v);
        out.push_back({std::string("statesave/") + to_string(mode) + "/" + ss::to_string(t) + "/" + v,
                       "collisions", [mode, t, variant](std::uint64_t n) { return run_study(mode, t, variant, n); }});
      }
    }
  }
}

}  // namespace revcol::bench
