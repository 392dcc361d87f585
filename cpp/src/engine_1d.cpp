// The engine in 1D, for every pair operator of engine_operators.hpp (one instantiation of
// EngineImpl<1, Op> each; a file per dimension so that they compile in parallel).
#include "engine_collide.hpp"
#include "engine_impl.hpp"
#include "engine_operators.hpp"

namespace revcol::engine::detail {

template <>
std::unique_ptr<Simulation> make_engine<1>(const Config& c, const std::vector<double>& x,
                                             const std::vector<double>& v, double t0) {
  return with_operator<1>(c, [&](auto op) -> std::unique_ptr<Simulation> {
    return std::make_unique<EngineImpl<1, decltype(op)>>(c, x, v, t0, std::move(op));
  });
}

template <>
std::unique_ptr<Simulation> restore_engine<1>(const Snapshot& s) {
  return with_operator<1>(s.config, [&](auto op) -> std::unique_ptr<Simulation> {
    return std::make_unique<EngineImpl<1, decltype(op)>>(s, std::move(op));
  });
}

}  // namespace revcol::engine::detail
