// Collision of 2 particles in 1 dimension (paper §4.1): no free parameter. Momentum and
// energy leave two solutions, the pre state and the exchange of the two velocities; the
// post-collision geometry picks the exchange. It draws no random number, is its own
// inverse, and is exact in floating point (a swap conserves momentum and energy bit for bit).
#pragma once
#include <cmath>

#include "revcol/collide/common.hpp"
#include "revcol/collide/pair.hpp"

namespace revcol {

/// Pair collision in 1D: deterministic velocity exchange.
class Pair1D {
 public:
  static constexpr int dim = 1;        ///< spatial dimension d
  static constexpr int particles = 2;  ///< particles n
  static constexpr int draws = 0;      ///< random numbers per collision, d_n = 0

  /// Pre -> post. normal: the sign of x_i - x_j (any non-zero finite number).
  PairV<1> forward(const PairV<1>& pre, double normal) const {
    check(pre, normal, -1.0);
    return swap(pre);
  }
  /// Post -> pre.
  PairV<1> reverse(const PairV<1>& post, double normal) const {
    check(post, normal, +1.0);
    return swap(post);
  }

 private:
  static PairV<1> swap(const PairV<1>& v) { return PairV<1>{v.j, v.i}; }
  static void check(const PairV<1>& v, double normal, double sign) {
    require_finite(v);
    require(std::isfinite(normal) && normal != 0.0, "contact normal is zero or not finite");
    const double p = (normal > 0 ? 1.0 : -1.0) * (v.i[0] - v.j[0]);
    require(p != 0.0, "zero relative speed: the particles cannot collide");
    if (sign < 0)
      require(p < 0.0, "pre-collision state is not approaching along the contact normal");
    else
      require(p > 0.0, "post-collision state does not separate along the contact normal");
  }
};

}  // namespace revcol
