// Exact integer helpers of the lattice engine (docs/lattice.md): 128-bit types, the exact
// integer square root of an unsigned 128-bit value, and Python's floor semantics.
//
// The lattice bijection reads every geometric decision from integers, so these must be exact,
// not approximately right: isqrt(n) is floor(sqrt(n)) for every n < 2^128 (a double-precision
// guess, one residual correction, then +-1 steps decided by exact 128-bit products), and
// floor_div / floor_mod round toward minus infinity as Python's // and % do (C++'s / and %
// truncate toward zero). A right shift of a negative signed value is an arithmetic shift in
// C++20, i.e. floor(a / 2^k), the same as Python's >>.
#pragma once
#include <cmath>
#include <cstdint>
#include <limits>

namespace revcol::lattice {

using i64 = std::int64_t;              ///< a lattice coordinate or velocity component
using u64 = std::uint64_t;             ///< an unsigned machine word
using i128 = __int128;                 ///< products of two coordinates
using u128 = unsigned __int128;        ///< squares up to 2^128 - 1

/// An approximation of n as a double (two word conversions; only ever a first guess).
inline double approx_double(u128 n) {
  return static_cast<double>(static_cast<u64>(n >> 64)) * 0x1p64 + static_cast<double>(static_cast<u64>(n));
}
/// static_cast<double>(n), the same bits, without the library call (~40 instructions) when one
/// word of n is zero, as for sigma^2 = 2^(2S): a power-of-two scaling commutes with the rounding.
inline double to_double(u128 n) {
  const u64 hi = static_cast<u64>(n >> 64), lo = static_cast<u64>(n);
  if (hi == 0) return static_cast<double>(lo);
  if (lo == 0) return static_cast<double>(hi) * 0x1p64;
  return static_cast<double>(n);
}
/// An approximation of a signed n as a double (only ever a first guess).
inline double approx_double(i128 n) {
  return static_cast<double>(static_cast<std::int64_t>(n >> 64)) * 0x1p64 + static_cast<double>(static_cast<u64>(n));
}

/// floor(sqrt(n)), exact for every unsigned 128-bit n.
inline u64 isqrt(u128 n) {
  if (n == 0) return 0;
  constexpr u64 kMax = std::numeric_limits<u64>::max();
  const double d = std::sqrt(approx_double(n));
  u64 r = d >= 18446744073709551615.0 ? kMax : static_cast<u64>(d);
  if (r == 0) r = 1;
  // The guess is within ~2^-51 r of the root: one correction from the exact residual
  // e = n - r^2 (small, so the wrapped unsigned difference read as signed is exact).
  const i128 e = static_cast<i128>(n - static_cast<u128>(r) * r);
  const double step = std::floor(approx_double(e) / (2.0 * static_cast<double>(r)));
  i128 rr = static_cast<i128>(r) + static_cast<std::int64_t>(step);
  if (rr < 1) rr = 1;
  if (rr > static_cast<i128>(kMax)) rr = static_cast<i128>(kMax);
  r = static_cast<u64>(rr);
  // Exact +-1 steps: r^2 <= n < (r+1)^2.
  while (static_cast<u128>(r) * r > n) --r;
  while (r < kMax && static_cast<u128>(r + 1) * (r + 1) <= n) ++r;
  return r;
}

/// The smallest z >= 0 with z^2 >= n (ceil(sqrt(n))), exact.
inline u64 isqrt_ceil(u128 n) { return n == 0 ? 0 : isqrt(n - 1) + 1; }

/// floor(a / b) for b != 0, as Python's a // b.
inline i64 floor_div(i64 a, i64 b) {
  const i64 q = a / b;
  return (a % b != 0 && ((a < 0) != (b < 0))) ? q - 1 : q;
}

/// a - b * floor(a / b) for b != 0 (sign of b), as Python's a % b.
inline i64 floor_mod(i64 a, i64 b) {
  const i64 r = a % b;
  return (r != 0 && ((r < 0) != (b < 0))) ? r + b : r;
}

/// floor(a / 2^k) for 0 <= k < 128, as Python's a >> k (C++20: arithmetic shift).
inline i128 floor_shift(i128 a, int k) { return a >> k; }

}  // namespace revcol::lattice
