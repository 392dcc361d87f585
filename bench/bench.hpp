// Shared types of the revcol-bench binary. Each family of benchmarks lives in its own
// bench/<family>_bench.cpp and appends to the list in add_<family>_benches().
#pragma once
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "revcol/error.hpp"

namespace revcol::bench {

/// One measured number of a benchmark run.
struct Metric {
  std::string name;  ///< e.g. forward_per_s
  double value;      ///< its value
};

/// A benchmark: run(n) does n units of work (collisions, draws, ...) and reports metrics.
struct Bench {
  std::string name;  ///< family/variant/..., selected by prefix with --bench
  std::string unit;  ///< what the main metric counts
  std::function<std::vector<Metric>(std::uint64_t n)> run;
};

void add_pair_benches(std::vector<Bench>& out);       ///< revcol_bench.cpp: pair1d, pair2d, rng
void add_exact_benches(std::vector<Bench>& out);      ///< exact_bench.cpp: the general exact operator
void add_paper_benches(std::vector<Bench>& out);      ///< paper_bench.cpp: paper-mode 3D pair, triples
void add_statesave_benches(std::vector<Bench>& out);  ///< statesave_bench.cpp: SS1/SS2/RC study
void add_pair3d_benches(std::vector<Bench>& out);     ///< pair3d_bench.cpp: the fast exact 3D pair operator
void add_floor_benches(std::vector<Bench>& out);      ///< floor_bench.cpp: exact-flux pair operators against their bare floor
void add_engine_benches(std::vector<Bench>& out);     ///< engine_bench.cpp: the event-driven engine
void add_skip_benches(std::vector<Bench>& out);       ///< skip_bench.cpp: what a pair-only scene does not pay for
void add_lattice_op_benches(std::vector<Bench>& out);  ///< lattice_op_bench.cpp: the exact lattice pair operator
void add_lattice_op3_benches(std::vector<Bench>& out); ///< lattice_op3_bench.cpp: the 3D lattice pair operator, its design study
void add_lattice_benches(std::vector<Bench>& out);     ///< lattice_engine_bench.cpp: the 2D lattice engine
void add_rollback_benches(std::vector<Bench>& out);    ///< lattice_rollback_bench.cpp: the lattice engine's journal and rollback
void add_slabs_benches(std::vector<Bench>& out);       ///< lattice_slabs_bench.cpp: what K slabs would ask of a parallel run
void add_parallel_benches(std::vector<Bench>& out);    ///< lattice_parallel_bench.cpp: the parallel lattice engine against the sequential one
void add_tradeoff_benches(std::vector<Bench>& out);    ///< tradeoff_bench.cpp: run time against error per operator and knob

/// Seconds of the steady clock since t0.
inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// Median of a non-empty list (the mean of the middle two for an even count).
inline double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

/// Applies the environment variable `var`'s comma-separated key=value list: set(key, value)
/// for each entry (it returns false for an unknown key). A malformed entry, an unknown key
/// (`known` lists them) or a value set() cannot parse (std::stoi and the like throw) raises
/// InvalidArgument naming the variable and the entry.
template <class Set>
void apply_settings(const char* var, const char* known, Set&& set) {
  const char* env = std::getenv(var);
  if (env == nullptr) return;
  const std::string all = env, name = var;
  std::size_t at = 0;
  while (at < all.size()) {
    std::size_t end = all.find(',', at);
    if (end == std::string::npos) end = all.size();
    const std::string item = all.substr(at, end - at);
    at = end + 1;
    if (item.empty()) continue;
    const std::size_t eq = item.find('=');
    if (eq == std::string::npos) throw InvalidArgument(name + ": expected key=value, got '" + item + "'");
    const std::string key = item.substr(0, eq), value = item.substr(eq + 1);
    bool known_key = false;
    try {
      known_key = set(key, value);
    } catch (const std::logic_error& e) {  // stoi/stod failures and InvalidArgument
      if (dynamic_cast<const InvalidArgument*>(&e)) throw;
      throw InvalidArgument(name + ": bad value for " + key + ": '" + value + "'");
    }
    if (!known_key) throw InvalidArgument(name + ": unknown key '" + key + "' (known: " + known + ")");
  }
}

}  // namespace revcol::bench
