// A uniform field on the lattice (gravity along one walled axis), exactly.
//
// Kinematics. With acceleration g (even, lattice units per tick^2) along axis k and h = g / 2, a
// line anchored at tick t_a with point x and velocity v is at x + v n + h n^2 after n ticks, with
// velocity v + 2 h n: every point is an integer, energy |v|^2 - 2 g x is the same at every tick,
// and the relative line of two particles is straight (the field cancels), so a pair's
// first-overlap search is unchanged. Reading the line with n -> -n and v -> -v gives the same
// points, so the reverse still only negates velocities. A tick's move is its mid velocity
// u = v + h (the velocity at its start plus h): the pair operator, the specular map, the group
// rule and the wall mirror take the mid velocities of the transition a-1 -> a and give the mid
// velocities after; the velocity at a is the post mid plus h. Read back (velocities at a
// negated), the mid of that transition is minus the post mid: the reverse sees the forward's
// own step negated, as without a field.
//
// Event times. Wall and cell crossings on the field's axis are first integer ticks n >= 1 at
// which a quadratic leaves an interval, found from an exact integer square root of the
// discriminant (128 bits: |v| <= vmax <= 2^52, |h| <= 2^35, |x| < 2^62) and checked by exact
// evaluation at the tick, never from a double root alone.
#pragma once
#include <cstdint>

#include "revcol/lattice/int128.hpp"

namespace revcol::lattice {

/// x + v n + h n^2 in 128-bit modular arithmetic (exact whenever the true value fits int128, as
/// it does for every n the engine asks: n is below the line's next event).
inline i128 field_point(std::int64_t x, std::int64_t v, std::int64_t h, std::int64_t n) noexcept {
  const u128 N = static_cast<u128>(static_cast<i128>(n));
  return static_cast<i128>(static_cast<u128>(static_cast<i128>(x)) + static_cast<u128>(static_cast<i128>(v)) * N +
                           static_cast<u128>(static_cast<i128>(h)) * N * N);
}

/// The first integer n >= 1 with A n^2 + B n + C < 0, or -1 if none; C >= 0 (not below at n = 0).
/// The root comes from an exact integer square root; each candidate is evaluated exactly.
inline std::int64_t first_negative(i128 A, i128 B, i128 C) noexcept {
  auto q = [&](i128 n) { return (A * n + B) * n + C; };
  if (A == 0) {  // a line: B n + C < 0 first at floor(C / -B) + 1
    if (B >= 0) return -1;
    return static_cast<std::int64_t>(C / -B + 1);
  }
  const i128 disc = B * B - 4 * A * C;
  if (A > 0) {  // convex: negative only between the roots, if any integer lies between them
    if (B >= 0 || disc <= 0) return -1;
    const i128 s = static_cast<i128>(isqrt(static_cast<u128>(disc)));
    // the lower root is (-B - sqrt(disc)) / 2A >= (-B - s - 1) / 2A: start at or before it
    i128 n = (-B - s - 1) / (2 * A);
    if (n < 1) n = 1;
    for (int step = 0; step < 8; ++step, ++n) {
      if (q(n) < 0) return static_cast<std::int64_t>(n);
      if (2 * A * n + B >= 0) return -1;  // past the vertex, still not below: the dip holds no tick
    }
    return -1;  // (unreachable: the start is within a tick or two of the root)
  }
  // concave: negative beyond the upper root (B + sqrt(disc)) / 2|A|, which is >= 0 since C >= 0
  const i128 a = -A;
  const i128 s = static_cast<i128>(isqrt(static_cast<u128>(disc)));
  i128 n = (B + s) / (2 * a);
  if (n < 1) n = 1;
  while (q(n) >= 0) ++n;  // at most two steps from the floor of the root
  return static_cast<std::int64_t>(n);
}

/// Ticks from an anchor (x, v) until x + v n + h n^2 is first beyond [lo, hi] (n >= 1); -1 if
/// never. An anchor already beyond that arrived there moving out (its last tick's move v - h
/// points out) gives 0: its reflection belongs to this very tick (cell_grid.hpp, wall_ticks).
inline std::int64_t field_wall_ticks(std::int64_t x, std::int64_t v, std::int64_t h, std::int64_t lo, std::int64_t hi) noexcept {
  if (x < lo && v - h < 0) return 0;
  if (x > hi && v - h > 0) return 0;
  std::int64_t best = -1;
  if (x >= lo) best = first_negative(h, v, static_cast<i128>(x) - lo);  // x + v n + h n^2 < lo
  if (x <= hi) {
    const std::int64_t up = first_negative(-static_cast<i128>(h), -static_cast<i128>(v), static_cast<i128>(hi) - x);  // > hi
    if (up >= 0 && (best < 0 || up < best)) best = up;
  }
  return best;
}

/// Ticks from an anchor (x, v) in [b0, b1) until x + v n + h n^2 is first outside it; a side
/// that is a wall (lo_wall, hi_wall) is left to the wall's event. -1 if never.
inline std::int64_t field_exit_ticks(std::int64_t x, std::int64_t v, std::int64_t h, std::int64_t b0, std::int64_t b1,
                                     bool lo_wall, bool hi_wall) noexcept {
  std::int64_t best = -1;
  if (!lo_wall) best = first_negative(h, v, static_cast<i128>(x) - b0);  // < b0
  if (!hi_wall) {
    const std::int64_t up = first_negative(-static_cast<i128>(h), -static_cast<i128>(v), static_cast<i128>(b1) - 1 - x);  // >= b1
    if (up >= 0 && (best < 0 || up < best)) best = up;
  }
  return best;
}

}  // namespace revcol::lattice
