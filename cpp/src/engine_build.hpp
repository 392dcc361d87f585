// make_engine<Dim> / restore_engine<Dim>: EngineImpl<Dim, Op> for the operator that
// engine_operators.hpp chooses. Private to cpp/src: each engine_<d>d.cpp includes this and
// instantiates it for its dimension (one file per dimension, compiled in parallel).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "engine_check.hpp"
#include "engine_collide.hpp"
#include "engine_impl.hpp"
#include "engine_predict.hpp"
#include "engine_state.hpp"
#include "engine_operators.hpp"

namespace revcol::engine::detail {

template <int Dim>
std::unique_ptr<Simulation> make_engine(const Config& c, const std::vector<double>& x, const std::vector<double>& v,
                                        double t0) {
  return with_operator<Dim>(c, [&](auto op) -> std::unique_ptr<Simulation> {
    return std::make_unique<EngineImpl<Dim, decltype(op)>>(c, x, v, t0, std::move(op));
  });
}

template <int Dim>
std::unique_ptr<Simulation> restore_engine(const Snapshot& s) {
  return with_operator<Dim>(s.config, [&](auto op) -> std::unique_ptr<Simulation> {
    auto e = std::make_unique<EngineImpl<Dim, decltype(op)>>(s, std::move(op));
    // the saved schedule and list centres are trusted (bit for bit resumption): they must fit
    // the particles (issue 59: a forged one ran on and passed particles through each other)
    const std::string fault = e->fault();
    require(fault.empty(), [&] { return "snapshot: the schedule (ev_t, ev_kind, ev_partner, ev_stamp, centre) does not fit "
                                        "the particles (x, v, t_local): " + fault; });
    return e;
  });
}

}  // namespace revcol::engine::detail
