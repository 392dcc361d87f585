// The engine's choice of pair operator, made once per simulation from its dimension and
// mode (no branch on the mode per collision): the one place that names the operators.
//   1D  exchange of velocities (Pair1D), exact and paper mode alike
//   2D  Pair2DExact (exact), Pair2DPaper (paper)
//   3D  Pair3DExact (exact); paper mode is refused by the validation (engine.cpp)
//   any d  Specular (mode "specular", engine-only: deterministic, 0 draws)
// Groups of three or more always go through ExactCollision (engine_collide.hpp).
// Private to cpp/src: included by engine_<d>d.cpp.
#pragma once
#include <memory>
#include <string>

#include "revcol/collide/operator.hpp"
#include "revcol/collide/specular.hpp"
#include "revcol/engine/engine.hpp"

namespace revcol::engine::detail {

/// The engine-only modes (not parse_mode's, so that the operator-level users refuse them):
/// sets m and returns true when s names one.
inline bool engine_only_mode(const std::string& s, Mode& m) {
  if (s == "specular") {
    m = Mode::specular;
    return true;
  }
  return false;
}

/// Calls f(op) with the pair operator for c.mode in dimension Dim; returns what f returns.
template <int Dim, class F>
auto with_operator(const Config& c, F&& f) {
  if (c.mode == Mode::specular) return f(Specular<Dim>{});
  if constexpr (Dim == 1) {
    return f(ops::Exchange1D{});
  } else if constexpr (Dim == 2) {
    if (c.mode == Mode::paper) return f(ops::Paper2D{});
    return f(ops::Exact2D(c.law, c.bits));
  } else {
    return f(ops::Exact3D(c.law, c.bits));
  }
}

}  // namespace revcol::engine::detail
