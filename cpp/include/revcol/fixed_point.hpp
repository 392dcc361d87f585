// K-bit fixed-point chart coordinates (DESIGN.md §4).
//
// A chart coordinate c in [0,1) is stored as the integer U = floor(c 2^K); a random number
// G in (0,1) as floor(G 2^K). The torus shift u = u' + G (mod 1) is then exact integer
// arithmetic, U = (U' + G) mod 2^K, and so is its inverse. A coordinate is decoded at the
// centre of its cell, c = (U + 1/2) 2^-K: a decoded point is never on a cell edge, and it
// re-encodes to the same integer whenever the chart's round-trip error is below half a cell.
#pragma once
#include <cmath>
#include <cstdint>
#include <string>

#include "revcol/error.hpp"

namespace revcol {

/// The number of bits of each fixed-point chart coordinate.
class FixedPoint {
 public:
  /// Smallest and largest supported K (K + 1 <= 53 keeps every cell centre exact in a double).
  static constexpr int min_bits = 8, max_bits = 52, default_bits = 40;

  /// K bits per coordinate; throws InvalidArgument outside [min_bits, max_bits].
  explicit FixedPoint(int bits = default_bits) : bits_(bits) {
    require(bits >= min_bits && bits <= max_bits, [&] { return std::string("bits must be in [" + std::to_string(min_bits) + ", " + std::to_string(max_bits) +
                "], got " + std::to_string(bits)); });
    cells_ = std::ldexp(1.0, bits);
    inv_cells_ = std::ldexp(1.0, -bits);
    half_cells_ = std::ldexp(1.0, bits - 1);
    half_inv_cells_ = std::ldexp(1.0, -bits - 1);
    const int e = bits + 1 + (bits + 1) % 2;  // K + 1 rounded up to even
    root_f_ = std::ldexp(1.0, e - bits - 1);
    root_g_ = std::ldexp(1.0, -e / 2);
    mask_ = (std::uint64_t{1} << bits) - 1;
  }
  /// K.
  int bits() const { return bits_; }
  /// 2^K as a double.
  double cells() const { return cells_; }
  /// Cell of c in [0,1]: floor(c 2^K), clamped to [0, 2^K - 1] (c = 1 can come from rounding).
  std::uint64_t encode(double c) const {
    // Without branches (the operators encode two to four coordinates per collision): clamp
    // s to [0, 2^62] first, a NaN to 0 (a comparison with a NaN is false; validation rules
    // NaNs out earlier anyway). floor(s) for s >= 0 is then the conversion's truncation: the
    // same bits, without floor's rounding-mode sequence (baseline x86-64 has no roundsd).
    // 0 <= s <= 2^62 fits a signed 64-bit integer, whose conversion is one instruction; the
    // unsigned one is a branch and a fix-up on baseline x86-64 (no AVX-512). Every c maps
    // where the branchy form (0 below the cells, mask_ above) mapped it.
    return encode_scaled(c * cells_);
  }
  /// Cell of (1 + y) / 2 for y in [-1, 1]: encode(0.5 + 0.5 * y) bit for bit, one product
  /// shorter (the scale by 2^K is exact, so it commutes with the sum's rounding:
  /// 2^K fl(1/2 + y/2) = fl(2^(K-1) + 2^(K-1) y)). The 2D flux chart's coordinate.
  /// For |y| <= 2 (a NaN goes to cell 0): 2^(K-1) (1 + y) < 2^62 needs no upper clamp.
  std::uint64_t encode_half(double y) const {
    double s = half_cells_ + half_cells_ * y;
    s = s > 0.0 ? s : 0.0;
    const auto u = static_cast<std::uint64_t>(static_cast<std::int64_t>(s));
    return u > mask_ ? mask_ : u;
  }
  /// 2 U + 1 - 2^K: 2 decode(U) - 1 is exactly this times 2^-K (the centre of cell U mapped
  /// to [-1, 1]; |.| <= 2^K <= 2^52, so its conversion to double is exact too).
  std::int64_t centered(std::uint64_t u) const {
    return static_cast<std::int64_t>(2 * u + 1) - static_cast<std::int64_t>(mask_ + 1);
  }
  /// 2^-K.
  double inv_cells() const { return inv_cells_; }
  /// Position of c inside its cell, in [0,1): 1/2 at the centre. Used to detect round-trip error.
  double offset_in_cell(double c) const {
    const double s = c * cells_;
    return s - std::floor(s);
  }
  /// Centre of cell U: (U + 1/2) 2^-K, exact in double (a product by 2^-K: the quotient's
  /// bits, without a division on the operators' hot path).
  /// U < 2^52 converts exactly through a signed integer (one instruction, as in encode).
  double decode(std::uint64_t u) const {
    return (static_cast<double>(static_cast<std::int64_t>(u)) + 0.5) * inv_cells_;
  }
  /// sqrt(c) and sqrt(1 - c) for the centre c of cell U: bit for bit std::sqrt(decode(U)) and
  /// std::sqrt(1 - decode(U)), one conversion from the integers. c = (2U + 1) 2^-(K+1) and
  /// 1 - c = (2^(K+1) - 2U - 1) 2^-(K+1) have exact integer numerators below 2^53; times
  /// root_f_ (1 or 2: the exponent made even, -2j) they stay exact, and the square root of
  /// x 2^-2j is sqrt(x) 2^-j, exactly (root_g_ = 2^-j).
  void roots(std::uint64_t u, double& s, double& c) const {
    const std::uint64_t m = 2 * u + 1;
    s = std::sqrt(static_cast<double>(static_cast<std::int64_t>(m)) * root_f_) * root_g_;
    c = std::sqrt(static_cast<double>(static_cast<std::int64_t>((mask_ + 1) * 2 - m)) * root_f_) * root_g_;
  }
  /// The centre c of cell U as the nearest quarter q/4 plus a remainder r in [-1/8, 1/8]:
  /// q = floor(4c + 1/2) = (4U + 2 + 2^(K-1)) >> K and r = c - q/4 = (2U + 1 - q 2^(K-1))
  /// 2^-(K+1), exact (trig::sincos_turns(c)'s reduction, which is exact for cell centres, in
  /// integers: trig::sincos_quarters(q, r) gives sincos_turns(decode(U))'s bits).
  struct Quarters {
    std::int64_t q;  ///< the nearest quarter (0..4)
    double r;        ///< c - q/4
  };
  Quarters quarters(std::uint64_t u) const {
    const std::uint64_t q = (4 * u + 2 + (mask_ + 1) / 2) >> bits_;
    const auto m = static_cast<std::int64_t>(2 * u + 1) - static_cast<std::int64_t>(q << (bits_ - 1));
    return {static_cast<std::int64_t>(q), static_cast<double>(m) * half_inv_cells_};
  }
  /// A random number G in [0, 1] as a K-bit shift: encode(g) bit for bit, without its clamps,
  /// which cannot act on g in [0, 1] (every caller validates g first; outside, the result is
  /// unspecified).
  std::uint64_t shift(double g) const {
    const auto u = static_cast<std::uint64_t>(static_cast<std::int64_t>(g * cells_));
    return u > mask_ ? mask_ : u;
  }
  /// (U + G) mod 2^K.
  std::uint64_t add(std::uint64_t u, std::uint64_t g) const { return (u + g) & mask_; }
  /// (U - G) mod 2^K.
  std::uint64_t sub(std::uint64_t u, std::uint64_t g) const { return (u - g) & mask_; }

 private:
  // floor(s) clamped to [0, 2^K - 1], for s = c 2^K
  std::uint64_t encode_scaled(double s) const {
    s = s > 0.0 ? s : 0.0;
    s = s < 0x1.0p+62 ? s : 0x1.0p+62;
    const auto u = static_cast<std::uint64_t>(static_cast<std::int64_t>(s));
    return u > mask_ ? mask_ : u;
  }

  int bits_;
  double cells_, inv_cells_, half_cells_, half_inv_cells_;  // 2^K, 2^-K, 2^(K-1), 2^-(K+1)
  double root_f_, root_g_;  // roots(): 2^(e-K-1) and 2^(-e/2), e = K + 1 rounded up to even
  std::uint64_t mask_;
};

}  // namespace revcol
