// The specular (deterministic) elastic collision of two equal spheres: the component of the
// relative velocity along the contact normal changes sign, the tangential part and the
// centre-of-mass velocity stay. With r the normal (from j to i, any length) and
// w = v_i - v_j, f = (r.w) / (r.r):
//     v_i' = v_i - f r,   v_j' = v_j + f r.
// No random number. The engine's fallback when a reversed collision is refused beyond the
// horizon (EngineImpl::collide) reflects specularly, drawing nothing.
#pragma once
#include <array>

#include "revcol/collide/common.hpp"
#include "revcol/collide/pair.hpp"

namespace revcol {

/// Specular reflection of a pair in d = 1, 2, 3.
template <int Dim>
struct Specular {
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
};

}  // namespace revcol
