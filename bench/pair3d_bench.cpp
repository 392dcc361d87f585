// Benchmarks of the fast exact 3D pair operator (collide/pair3d_exact.hpp): to be filled.
#include "bench.hpp"

namespace revcol::bench {

void add_pair3d_benches(std::vector<Bench>& out) { (void)out; }

}  // namespace revcol::bench
