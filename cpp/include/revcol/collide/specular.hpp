// The specular (deterministic) elastic collision of two equal spheres: the component of the
// relative velocity along the contact normal changes sign, the tangential part and the
// centre-of-mass velocity stay. With r the normal (from j to i, any length) and
// w = v_i - v_j, f = (r.w) / (r.r):
//     v_i' = v_i - f r,   v_j' = v_j + f r.
// No random number (draws = 0): the classical hard-sphere gas, a baseline for benchmarks
// (the cost of the event search alone) and for physics checks (equilibrium properties of
// the randomized operators must match it). The map is an involution, so reverse is the same
// formula on the post state; reversal is exact to round-off (f is recomputed from the post
// state, ~1 ulp), within the same chaotic horizon as every other operator.
//
// It is also the engine's fallback when a reversed collision is refused beyond the horizon
// (EngineImpl::collide), which reflects specularly drawing nothing.
#pragma once
#include <array>

#include "revcol/collide/common.hpp"
#include "revcol/collide/pair.hpp"

namespace revcol {

/// Specular reflection of a pair in d = 1, 2, 3 (a PairOperator, collide/operator.hpp).
template <int Dim>
struct Specular {
  static constexpr int dim = Dim;                       ///< d
  static constexpr int draws = 0;                       ///< deterministic
  static constexpr bool needs_exact_pre_log = false;    ///< no chart
  static constexpr bool quantizes = false;              ///< double precision throughout
  static constexpr const char* name = "specular";       ///< Mode::specular

  /// The reflection itself (no checks): v_i - f r, v_j + f r, f = r.w / r.r.
  static PairV<Dim> reflect(const PairV<Dim>& in, const std::array<double, Dim>& r) {
    double rr = 0.0, rw = 0.0;
    for (int k = 0; k < Dim; ++k) {
      rr += r[k] * r[k];
      rw += r[k] * (in.i[k] - in.j[k]);
    }
    const double f = rw / rr;
    PairV<Dim> out = in;
    for (int k = 0; k < Dim; ++k) {
      out.i[k] -= f * r[k];
      out.j[k] += f * r[k];
    }
    return out;
  }
  /// Pre -> post; throws InvalidArgument unless the pair approaches along r.
  PairV<Dim> forward(const PairV<Dim>& pre, const std::array<double, Dim>& r, const double*, RareLog&) const {
    check(pre, r, -1.0);
    return reflect(pre, r);
  }
  /// Post -> pre; throws InvalidArgument unless the pair separates along r.
  PairV<Dim> reverse(const PairV<Dim>& post, const std::array<double, Dim>& r, const double*, RareLog&) const {
    check(post, r, +1.0);
    return reflect(post, r);
  }

 private:
  static void check(const PairV<Dim>& v, const std::array<double, Dim>& r, double sign) {
    require_finite(v);
    double rr = 0.0, rw = 0.0;
    for (int k = 0; k < Dim; ++k) {
      require(std::isfinite(r[k]), "contact normal must be finite");
      rr += r[k] * r[k];
      rw += r[k] * (v.i[k] - v.j[k]);
    }
    require(rr > 0.0, "contact normal is zero");
    if (sign < 0)
      require(rw < 0.0, "pre-collision state is not approaching along the contact normal");
    else
      require(rw > 0.0, "post-collision state does not separate along the contact normal");
  }
};

}  // namespace revcol
