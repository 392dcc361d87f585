// Lees-Edwards shear on the lattice (UnitsN::shear), exactly.
//
// Images. Axis 0 is the flow, axis 1 the gradient, both periodic. The copy of the box n boxes up
// the gradient axis (+ n L_1) is shifted along the flow by n delta(t), delta(t) = s t mod L_0,
// and moves n s faster along it (s = UnitsN::shear, lattice units per tick; the shear rate is
// s / L_1 per tick). A particle's image there is at (x_0 + n delta(t), x_1 + n L_1, ...) with
// velocity (v_0 + n s, v_1, ...). delta(t) grows by exactly s per tick, so the image of a line is
// a line: a pair's relative motion stays straight across the gradient faces, and its first
// overlap is the same exact search on the image's relative vector.
//
// Crossing a gradient face. A line that leaves the box through the upper face (x_1 >= L_1) at
// tick t comes back through the lower one as its image n = -1: x_0 - delta(t), v_0 - s; through
// the lower face the other way. Because delta is linear in t, a line anchored at t_a whose
// unwrapped point x_1 + v_1 (t - t_a) is m boxes up is at (x_0 + v_0 (t - t_a) - m delta(t),
// x_1 + v_1 (t - t_a) - m L_1) with velocity v_0 - m s at tick t, whatever t (before or after its
// anchor): the engine reads every point so (pos, vel) and re-anchors the line at its crossing.
//
// Time reversal negates velocities and the clock; the images' offset at a physical time must
// stay the same, so the reversed frame runs with -s (-s times -t is s t): the reverse is the
// forward search in that frame, as without shear. Energy is not conserved: the boundary does
// work (viscous heating, E grows as eta gamma^2 V t); momentum is conserved by collisions (in the
// frame of either particle) and changes by -+ s at each face crossing.
#pragma once
#include <cstdint>

#include "revcol/lattice/geometry.hpp"
#include "revcol/lattice/int128.hpp"

namespace revcol::lattice {

/// floor(z / L) for L > 0, any 128-bit z.
inline std::int64_t floor_div128(i128 z, std::int64_t L) noexcept {
  return static_cast<std::int64_t>(z >= 0 ? z / L : -((-z + L - 1) / L));
}

/// The minimum image a - b of two positions in the box at offset delta = delta(t), and n, the
/// image of b it is taken to (b's image n boxes up the gradient axis: 0 or +-1). `wall` per axis.
template <std::size_t D>
[[gnu::noinline]] VecN<D> sheared_diff(const VecN<D>& a, const VecN<D>& b, const std::array<std::int64_t, D>& L, const std::array<bool, D>& wall,
                     std::int64_t delta, std::int64_t& n) noexcept {
  VecN<D> r;
  for (std::size_t k = 0; k < D; ++k) r[k] = wall[k] ? a[k] - b[k] : min_image(a[k] - b[k], L[k]);
  n = (a[1] - b[1] - r[1]) / L[1];
  if (n != 0) r[0] = min_image(wrap(static_cast<i128>(a[0]) - b[0] - static_cast<i128>(n) * delta, L[0]), L[0]);
  return r;
}

}  // namespace revcol::lattice
