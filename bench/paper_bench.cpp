#include "bench.hpp"

namespace revcol::bench {
void add_paper_benches(std::vector<Bench>& out) { (void)out; }
}  // namespace revcol::bench
