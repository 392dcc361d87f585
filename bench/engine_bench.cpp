// Benchmarks of the event-driven engine: to be filled.
#include "bench.hpp"

namespace revcol::bench {

void add_engine_benches(std::vector<Bench>& out) { (void)out; }

}  // namespace revcol::bench
