// Benchmarks of the general exact operator: every named case through verify() (the paper's
// illustration: forward then reverse with the generator stepping back), flux law, CLCG4.
// Reports collisions/s each way, the round trip's error, and the rare log's size.
#include "bench.hpp"
#include "revcol/collide/cases.hpp"
#include "revcol/studies/verify.hpp"

namespace revcol::bench {

void add_exact_benches(std::vector<Bench>& out) {
  for (const NamedCase& c : named_cases()) {
    if (c.name == "pair1d" || c.name == "pair2d") continue;  // fast paths: revcol_bench.cpp
    for (const char* law : {"flux", "uniform"}) {
      const std::string name = c.name, lw = law;
      out.push_back({"exact/" + name + "/" + lw, "collisions/s", [name, lw](std::uint64_t n) {
                       VerifyConfig cfg;
                       cfg.case_name = name;
                       cfg.mode = Mode::exact;
                       cfg.law = parse_law(lw);
                       cfg.collisions = n;
                       const VerifyResult r = verify(cfg);
                       return std::vector<Metric>{
                           {"forward_per_s", r.forward_per_s},
                           {"reverse_per_s", r.reverse_per_s},
                           {"passed", r.passed ? 1.0 : 0.0},
                           {"max_rel_error", r.max_rel_error},
                           {"log_bytes", static_cast<double>(r.log_bytes)},
                           {"log_bytes_per_collision", static_cast<double>(r.log_bytes) /
                                                           static_cast<double>(n)}};
                     }});
    }
  }
}

}  // namespace revcol::bench
