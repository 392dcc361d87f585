// The engine in 2D: EngineImpl<2, Op> for every pair operator of engine_operators.hpp.
#include "engine_build.hpp"

namespace revcol::engine::detail {
template std::unique_ptr<Simulation> make_engine<2>(const Config&, const std::vector<double>&,
                                                      const std::vector<double>&, double);
template std::unique_ptr<Simulation> restore_engine<2>(const Snapshot&);
}  // namespace revcol::engine::detail
