// The engine in 1D: EngineImpl<1, Op> for every pair operator of engine_operators.hpp.
#include "engine_build.hpp"

namespace revcol::engine::detail {
template std::unique_ptr<Simulation> make_engine<1>(const Config&, const std::vector<double>&,
                                                      const std::vector<double>&, double);
template std::unique_ptr<Simulation> restore_engine<1>(const Snapshot&);
}  // namespace revcol::engine::detail
