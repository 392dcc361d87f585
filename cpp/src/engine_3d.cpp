// The engine in 3D: EngineImpl<3, Op> for every pair operator of engine_operators.hpp.
#include "engine_build.hpp"

namespace revcol::engine::detail {
template std::unique_ptr<Simulation> make_engine<3>(const Config&, const std::vector<double>&,
                                                      const std::vector<double>&, double);
template std::unique_ptr<Simulation> restore_engine<3>(const Snapshot&);
}  // namespace revcol::engine::detail
