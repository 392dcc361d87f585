// Integer geometry of the lattice engine in D = 2 or 3 dimensions (LATTICE.md §1-2).
//
// Lengths are integers in lattice units (sigma = 2^S of them per diameter), time is an integer
// tick count, velocities are lattice units per tick. Free flight x(t) = x_a + v (t - t_a) is then
// exact and the same whether computed from either end of a segment, so every event decision
// reads identical geometry forward and backward.
//
// Bounds (enforced by the units, units.hpp): a box length L < 2^63 - 2^56 lattice units, so a
// wrapped position is in [0, L), a minimum-image difference in [-L/2, L/2] (|r| < 2^62), and
// |r|^2 + |r'|^2 < 2^125 fits an unsigned 128-bit integer; |v| <= 2^53 per axis, so v * dt with |dt| < 2^62 is below
// 2^115 in 128 bits. A pair overlaps at a tick when |r|^2 < sigma^2 (strictly: touching is outside).
// In 3D the squares of three components are summed: the box limit is 2^62 lattice units per axis
// (units.hpp: max_box_of<3>), so every difference, a wall axis's included (no minimum image there),
// is below 2^62 and |r|^2 < 3 * 2^124 < 2^126 fits a signed 128-bit integer with room for the
// sum of two such norms (< 2^127); |r . w| < 3 * 2^116 and |w|^2 < 3 * 2^108 as in 2D.
//
// The first overlap tick of a pair (first_overlap) is decided exactly: with r the relative vector
// at the search's first tick and w the relative velocity, f(tau) = |r + w tau|^2 - sigma^2 is a convex
// quadratic in tau. Double precision gives only a first guess of the root; the answer is then decided by
// evaluating the exact integer predicate f(tau) < 0 at the guess and its neighbours (a bisection on
// integers when the guess is off, as near grazing). The full discriminant B^2 - A C (~2^230) is never
// formed in integers.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>

#include "revcol/lattice/int128.hpp"

namespace revcol::lattice {

/// An integer vector in D dimensions (a lattice position, velocity or relative vector).
template <std::size_t D>
using VecN = std::array<std::int64_t, D>;
/// A 2D integer vector.
using Vec2 = VecN<2>;
/// A 3D integer vector.
using Vec3 = VecN<3>;

/// x mod L in [0, L) for L > 0 (x any 128-bit value).
inline std::int64_t wrap(i128 x, std::int64_t L) noexcept {
  if (x >= 0 && x < L) return static_cast<std::int64_t>(x);
  i128 r = x % L;
  if (r < 0) r += L;
  return static_cast<std::int64_t>(r);
}

/// The minimum image of a difference d in (-L, L): r = d mod L, minus L when r >= (L + 1) / 2
/// (so |result| <= L/2). The same integer function in both directions of time.
inline std::int64_t min_image(std::int64_t d, std::int64_t L) noexcept {
  // = (d mod L) - (L if that is >= (L + 1) / 2), written with branches that a near pair never
  // takes (measure before changing: the scans call it three times per candidate)
  const std::int64_t hu = (L + 1) / 2;
  return d >= hu ? d - L : d < hu - L ? d + L : d;
}

/// s^2 in 128 bits for a contact distance s >= 0 (a mixture's pair: the sum of two radii).
inline u128 contact2(std::int64_t s) noexcept { return static_cast<u128>(s) * static_cast<u128>(s); }

/// |r|^2 in 128 bits (|r_k| < 2^62).
inline u128 norm2(std::int64_t rx, std::int64_t ry) noexcept {
  const u128 ax = static_cast<u128>(rx < 0 ? -static_cast<i128>(rx) : static_cast<i128>(rx));
  const u128 ay = static_cast<u128>(ry < 0 ? -static_cast<i128>(ry) : static_cast<i128>(ry));
  return ax * ax + ay * ay;
}
/// |r|^2 in 128 bits for any D (|r_k| < 2^62; in 3D the sum is below 2^126). Exact; the same
/// value as norm2(rx, ry) in 2D.
template <std::size_t D>
inline u128 norm2(const VecN<D>& r) noexcept {
  if constexpr (D == 2) {
    return norm2(r[0], r[1]);  // the 2D engine's code as it was (measure before changing)
  } else {
    u128 s = 0;
    for (std::size_t k = 0; k < D; ++k) {
      const u128 a = static_cast<u128>(r[k] < 0 ? -static_cast<i128>(r[k]) : static_cast<i128>(r[k]));
      s += a * a;
    }
    return s;
  }
}
/// The dot product r . w in 128 bits (|r_k| < 2^62, |w_k| < 2^54).
template <std::size_t D>
inline i128 dot(const VecN<D>& r, const VecN<D>& w) noexcept {
  i128 s = static_cast<i128>(r[0]) * w[0];
  for (std::size_t k = 1; k < D; ++k) s += static_cast<i128>(r[k]) * w[k];
  return s;
}

/// True when the relative vector r + w tau is strictly inside the contact circle: |.|^2 < sigma2.
/// Exact; components beyond 2^61 count as outside (sigma < 2^61).
bool overlaps_at(const Vec2& r, const Vec2& w, std::int64_t tau, u128 sigma2) noexcept;
/// The same in 3D: |r + w tau|^2 < sigma2, exact.
bool overlaps_at(const Vec3& r, const Vec3& w, std::int64_t tau, u128 sigma2) noexcept;

/// The smallest integer tau >= 0 with |r + w tau|^2 < sigma2, or -1 if there is none. Exact
/// (see the header comment); |r_k| < 2^62, |w_k| < 2^54.
std::int64_t first_overlap(const Vec2& r, const Vec2& w, u128 sigma2) noexcept;
/// The same in 3D (the same method: a double guess decided by the exact predicate).
std::int64_t first_overlap(const Vec3& r, const Vec3& w, u128 sigma2) noexcept;
/// first_overlap(r, w, sigma2) with the caller's double guess of the entry root: t = max(1,
/// ceil(guess)) is the answer when f(t) < sigma2 <= f(t - 1) (f convex: its inside ticks form an
/// interval, so none lies before t - 1), decided by two exact predicates; otherwise (a wrong or
/// non-finite guess, a pair inside at 0 or never inside) the full search. The same result for
/// every guess.
std::int64_t first_overlap(const Vec3& r, const Vec3& w, u128 sigma2, double guess) noexcept;

}  // namespace revcol::lattice
