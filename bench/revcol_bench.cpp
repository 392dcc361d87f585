// revcol-bench: the standalone benchmark binary. Never a unit test: it measures, it does not
// judge. Each benchmark runs `--repeats` times; the JSON/CSV carries every repeat and the
// median. Run side by side in one invocation when comparing: the machines are shared.
//
//   revcol-bench --list
//   revcol-bench [--bench NAME_OR_PREFIX ...] [--repeats R] [--collisions N] [--json F] [--csv F]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench.hpp"
#include "revcol/rng/clcg4.hpp"
#include "revcol/rng/philox.hpp"
#include "revcol/studies/verify.hpp"

namespace revcol::bench {
namespace {

using Clock = std::chrono::steady_clock;

std::vector<Metric> verify_metrics(const revcol::VerifyConfig& c) {
  const revcol::VerifyResult r = revcol::verify(c);
  if (!r.passed) {
    std::fprintf(stderr, "warning: %s did not pass its round trip\n", revcol::to_json(r).c_str());
  }
  return {{"forward_per_s", r.forward_per_s},
          {"reverse_per_s", r.reverse_per_s},
          {"max_rel_error", r.max_rel_error},
          {"bit_exact", r.bit_exact ? 1.0 : 0.0},
          {"log_bytes", static_cast<double>(r.log_bytes)}};
}

template <class Gen>
std::vector<Metric> rng_metrics(Gen gen, std::uint64_t n) {
  double sink = 0.0;
  auto t0 = Clock::now();
  for (std::uint64_t k = 0; k < n; ++k) sink += gen.next();
  const double fwd = std::chrono::duration<double>(Clock::now() - t0).count();
  t0 = Clock::now();
  for (std::uint64_t k = 0; k < n; ++k) sink -= gen.prev();
  const double rev = std::chrono::duration<double>(Clock::now() - t0).count();
  volatile double keep = sink;  // keeps the loops from being optimized away
  (void)keep;
  return {{"next_per_s", n / fwd}, {"prev_per_s", n / rev}};
}

}  // namespace

void add_pair_benches(std::vector<Bench>& out) {
  for (const char* rng : {"clcg4", "philox"}) {
    for (const char* variant : {"exact-flux", "exact-uniform", "paper"}) {
      const std::string v = variant, g = rng;
      out.push_back({"pair2d/" + v + "/" + g, "collisions/s", [v, g](std::uint64_t n) {
                       revcol::VerifyConfig c;
                       c.case_name = "pair2d";
                       c.mode = v == "paper" ? revcol::Mode::paper : revcol::Mode::exact;
                       c.law = v == "exact-uniform" ? revcol::Law::uniform : revcol::Law::flux;
                       c.rng = g;
                       c.collisions = n;
                       return verify_metrics(c);
                     }});
    }
  }
  out.push_back({"pair1d/clcg4", "collisions/s", [](std::uint64_t n) {
                   revcol::VerifyConfig c;
                   c.case_name = "pair1d";
                   c.collisions = n;
                   return verify_metrics(c);
                 }});
  out.push_back({"rng/clcg4", "draws/s",
                 [](std::uint64_t n) { return rng_metrics(revcol::rng::CLCG4(0), n); }});
  out.push_back({"rng/philox", "draws/s",
                 [](std::uint64_t n) { return rng_metrics(revcol::rng::Philox({0, 0}, 0), n); }});
}

}  // namespace revcol::bench

namespace {
using revcol::bench::Bench;
using revcol::bench::Metric;

std::vector<Bench> all_benches() {
  std::vector<Bench> out;
  revcol::bench::add_pair_benches(out);
  revcol::bench::add_exact_benches(out);
  revcol::bench::add_paper_benches(out);
  revcol::bench::add_statesave_benches(out);
  revcol::bench::add_pair3d_benches(out);
  revcol::bench::add_floor_benches(out);
  revcol::bench::add_engine_benches(out);
  revcol::bench::add_skip_benches(out);
  revcol::bench::add_lattice_op_benches(out);
  revcol::bench::add_lattice_op3_benches(out);
  revcol::bench::add_lattice_benches(out);
  revcol::bench::add_rollback_benches(out);
  revcol::bench::add_slabs_benches(out);
  revcol::bench::add_parallel_benches(out);
  revcol::bench::add_tradeoff_benches(out);
  return out;
}

int usage(int code) {
  std::fprintf(code ? stderr : stdout,
               "usage: revcol-bench [--list] [--bench NAME_OR_PREFIX]... [--repeats R]\n"
               "                    [--collisions N] [--json FILE] [--csv FILE]\n");
  return code;
}

// A count: digits, or an exact integer in float notation (1e7, 2.5e6); anything else (a trailing
// word, a fraction, a sign) throws. std::stoull alone read "1.2e7" as 1.
std::uint64_t parse_count(const std::string& s) {
  std::size_t used = 0;
  if (s.find_first_not_of("0123456789") == std::string::npos && !s.empty()) {
    const std::uint64_t n = std::stoull(s, &used);
    if (used == s.size()) return n;
  } else if (!s.empty() && s[0] != '-' && s[0] != '+') {
    const double d = std::stod(s, &used);
    if (used == s.size() && d >= 0.0 && d < 1.8e19 && d == std::floor(d)) return static_cast<std::uint64_t>(d);
  }
  throw std::invalid_argument("not a count: " + s);
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> selected;
  int repeats = 5;
  std::uint64_t n = 1000000;
  std::string json_path, csv_path;
  bool list = false;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    auto value = [&]() -> std::string {
      if (a + 1 >= argc) {
        std::fprintf(stderr, "revcol-bench: %s needs a value\n", arg.c_str());
        std::exit(2);
      }
      return argv[++a];
    };
    try {
      if (arg == "--list") list = true;
      else if (arg == "--bench") selected.push_back(value());
      else if (arg == "--repeats") {
        const std::uint64_t r = parse_count(value());
        if (r > 1000000) throw std::invalid_argument("too many repeats");
        repeats = static_cast<int>(r);
      }
      else if (arg == "--collisions") n = parse_count(value());
      else if (arg == "--json") json_path = value();
      else if (arg == "--csv") csv_path = value();
      else if (arg == "-h" || arg == "--help") return usage(0);
      else {
        std::fprintf(stderr, "revcol-bench: unknown argument %s\n", arg.c_str());
        return usage(2);
      }
    } catch (const std::exception&) {
      std::fprintf(stderr, "revcol-bench: bad value %s for %s (a count: 1000000 or 1e6)\n", argv[a], arg.c_str());
      return 2;
    }
  }
  if (repeats < 1 || n < 1) {
    std::fprintf(stderr, "revcol-bench: --repeats and --collisions must be >= 1\n");
    return 2;
  }
  const std::vector<Bench> benches = all_benches();
  if (list) {
    for (const Bench& b : benches) std::printf("%s\t%s\n", b.name.c_str(), b.unit.c_str());
    return 0;
  }
  std::vector<const Bench*> run;
  for (const Bench& b : benches) {
    bool take = selected.empty();
    for (const std::string& s : selected) take = take || b.name.rfind(s, 0) == 0;
    if (take) run.push_back(&b);
  }
  if (run.empty()) {
    std::fprintf(stderr, "revcol-bench: no benchmark matches; see --list\n");
    return 2;
  }
  std::string json = "{\"collisions\": " + std::to_string(n) +
                     ", \"repeats\": " + std::to_string(repeats) +
                     ", \"isa\": \"" REVCOL_ISA_NAME "\", \"results\": [";
  std::string csv = "bench,metric,median,repeats\n";
  bool first = true;
  for (const Bench* b : run) {
    std::vector<std::vector<Metric>> reps;
    for (int r = 0; r < repeats; ++r) reps.push_back(b->run(n));
    for (std::size_t m = 0; m < reps[0].size(); ++m) {
      std::vector<double> vals;
      for (const auto& rep : reps) vals.push_back(rep[m].value);
      const double med = revcol::bench::median(vals);
      std::printf("%-28s %-16s %14.6g\n", b->name.c_str(), reps[0][m].name.c_str(), med);
      std::string list_s;
      for (std::size_t k = 0; k < vals.size(); ++k) {
        char buf[40];
        std::snprintf(buf, sizeof buf, "%s%.9g", k ? ", " : "", vals[k]);
        list_s += buf;
      }
      char medbuf[40];
      std::snprintf(medbuf, sizeof medbuf, "%.9g", med);
      json += std::string(first ? "" : ", ") + "{\"bench\": \"" + b->name + "\", \"metric\": \"" +
              reps[0][m].name + "\", \"median\": " + medbuf + ", \"values\": [" + list_s + "]}";
      csv += b->name + "," + reps[0][m].name + "," + medbuf + ",\"" + list_s + "\"\n";
      first = false;
    }
  }
  json += "]}\n";
  if (!json_path.empty()) std::ofstream(json_path) << json;
  if (!csv_path.empty()) std::ofstream(csv_path) << csv;
  return 0;
}
