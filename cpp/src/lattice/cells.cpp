// Direction cells, the flux-law table and the lifting rotation (revcol/lattice/cells.hpp).
// Everything that decides a cell is integer arithmetic on compile-time tables; angles in double
// (atan2_guess, cells.hpp) are only first guesses that an exact comparison corrects.
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "revcol/error.hpp"
#include "revcol/lattice/cells.hpp"

namespace revcol::lattice {
namespace {

constexpr i128 kOne = static_cast<i128>(1) << kFixBits;   // 1.0 in 62-bit fixed point
constexpr i128 kHalf = static_cast<i128>(1) << (kFixBits - 1);
// round(2*pi * 2^100) (tests/reference/lattice_cells.py recomputes it with Machin's formula).
constexpr i128 kTwoPiFx100 = (static_cast<i128>(0x6487ed5110ULL) << 64) | static_cast<i128>(0xb4611a62633145c0ULL);
constexpr std::int64_t kOctant = 1LL << 18;    // pi/4 at half-cell resolution (2^21 per turn)
constexpr std::int64_t kQuadrant = 1LL << 19;  // pi/2 at half-cell resolution
constexpr std::int64_t kHalfMask = (1LL << 21) - 1;
constexpr int kFineBits = 9;                   // fine table: 2^9 half-cells
constexpr std::int64_t kFine = 1LL << kFineBits;
constexpr std::int64_t kCoarse = kOctant / kFine;  // 512 coarse steps (+1 entry for pi/4)

// 2*pi*h/2^21 in 62-bit fixed point, rounded (h <= 2^18).
constexpr i128 angle_fx(std::int64_t h) {
  return (static_cast<i128>(h) * kTwoPiFx100 + (static_cast<i128>(1) << 58)) >> 59;
}

// (cos a, sin a) * 2^62 for 0 <= a <= pi/4 * 2^62: Taylor series, every term rounded to
// nearest (all terms non-negative, so the rounding is the same in any language).
constexpr IVec sincos_fx(i128 a) {
  const i128 x2 = (a * a + kHalf) >> kFixBits;
  i128 c = kOne, s = a, tc = kOne, ts = a;
  for (int n = 1; tc != 0 || ts != 0; ++n) {
    const i128 dc = static_cast<i128>(2 * n - 1) * (2 * n);
    const i128 ds = static_cast<i128>(2 * n) * (2 * n + 1);
    tc = (((tc * x2 + kHalf) >> kFixBits) + dc / 2) / dc;
    ts = (((ts * x2 + kHalf) >> kFixBits) + ds / 2) / ds;
    c += (n & 1) ? -tc : tc;
    s += (n & 1) ? -ts : ts;
  }
  return {static_cast<i64>(c), static_cast<i64>(s)};
}

// floor(sqrt(n)) by Newton's method (compile time only).
constexpr u128 isqrt_newton(u128 n) {
  u128 x = n, y = (x + 1) / 2;
  while (y < x) {
    x = y;
    y = (x + n / x) / 2;
  }
  return x;
}

struct Tables {
  std::array<IVec, kCoarse + 1> coarse{};  // angle i * 2^9 half-cells, i = 0..512
  std::array<IVec, kFine> fine{};          // angle j half-cells, j = 0..511
};

constexpr Tables make_tables() {
  Tables t;
  for (std::int64_t i = 0; i < kCoarse; ++i) t.coarse[i] = sincos_fx(angle_fx(i * kFine));
  const i64 diag = static_cast<i64>(isqrt_newton(static_cast<u128>(1) << (2 * kFixBits - 1)));
  t.coarse[kCoarse] = {diag, diag};  // exactly on the diagonal: the octant symmetry is exact
  for (std::int64_t j = 0; j < kFine; ++j) t.fine[j] = sincos_fx(angle_fx(j));
  return t;
}

constexpr Tables kTables = make_tables();

// B(h) for 0 <= h <= 2^18: coarse (x) fine, a complex product rounded to nearest.
inline IVec boundary_octant(std::int64_t h) {
  const IVec& a = kTables.coarse[h >> kFineBits];
  const std::int64_t j = h & (kFine - 1);
  if (j == 0) return a;
  const IVec& b = kTables.fine[j];
  const i128 x = static_cast<i128>(a.x) * b.x - static_cast<i128>(a.y) * b.y;
  const i128 y = static_cast<i128>(a.y) * b.x + static_cast<i128>(a.x) * b.y;
  return {static_cast<i64>((x + kHalf) >> kFixBits), static_cast<i64>((y + kHalf) >> kFixBits)};
}

// n / d for a quotient below 2^64 (n >> 64 < d): one divq on x86-64.
inline std::uint64_t div_word(u128 n, std::uint64_t d) {
#if defined(__x86_64__)
  std::uint64_t q, r;
  __asm__("divq %4" : "=a"(q), "=d"(r) : "a"(static_cast<std::uint64_t>(n)), "d"(static_cast<std::uint64_t>(n >> 64)), "rm"(d) : "cc");
  return q;
#else
  return static_cast<std::uint64_t>(n / d);
#endif
}

constexpr double kCellsPerRadian = static_cast<double>(kCells) / (2.0 * std::numbers::pi);

inline i128 cross(const IVec& b, i64 wx, i64 wy) {
  return static_cast<i128>(b.x) * wy - static_cast<i128>(b.y) * wx;
}

}  // namespace

IVec boundary(std::int64_t h) {
  h &= kHalfMask;
  const std::int64_t r = h & (kQuadrant - 1);
  IVec b;
  if (r <= kOctant) {
    b = boundary_octant(r);
  } else {
    const IVec m = boundary_octant(kQuadrant - r);
    b = {m.y, m.x};
  }
  return rot90(b, static_cast<int>(h >> 19));
}

namespace {

// Component `y` (false: x) of the octant vector, as boundary_octant computes it (2 products).
inline i64 octant_component(std::int64_t h, bool y) {
  const IVec& a = kTables.coarse[h >> kFineBits];
  const std::int64_t j = h & (kFine - 1);
  if (j == 0) return y ? a.y : a.x;
  const IVec& b = kTables.fine[j];
  const i128 v = y ? static_cast<i128>(a.y) * b.x + static_cast<i128>(a.x) * b.y
                   : static_cast<i128>(a.x) * b.x - static_cast<i128>(a.y) * b.y;
  return static_cast<i64>((v + kHalf) >> kFixBits);
}

// One component of B(h), the same bits as boundary(h) (half the products).
inline i64 boundary_component(std::int64_t h, bool y) {
  h &= kHalfMask;
  const int q = static_cast<int>(h >> 19);
  const std::int64_t r = h & (kQuadrant - 1);
  // rot90 by q: x <- (x, -y, -x, y)[q], y <- (y, x, -y, -x)[q] of the quadrant vector
  const bool take_y = y ? (q & 1) == 0 : (q & 1) == 1;
  const bool negate = y ? q >= 2 : (q == 1 || q == 2);
  const i64 c = r <= kOctant ? octant_component(r, take_y) : octant_component(kQuadrant - r, !take_y);
  return negate ? -c : c;
}

}  // namespace

i64 boundary_x(std::int64_t h) { return boundary_component(h, false); }
i64 boundary_y(std::int64_t h) { return boundary_component(h, true); }

std::int64_t dir_cell(i64 wx, i64 wy) {
  require(wx != 0 || wy != 0, "dir_cell: the zero vector has no direction");
  constexpr std::int64_t mask = kCells - 1;
  const double a = atan2_guess(static_cast<double>(wy), static_cast<double>(wx));
  std::int64_t k = static_cast<std::int64_t>(std::floor(a * kCellsPerRadian)) & mask;
  while (cross(boundary(2 * k), wx, wy) < 0) k = (k - 1) & mask;
  while (cross(boundary(2 * k + 2), wx, wy) >= 0) k = (k + 1) & mask;
  return k;
}

std::int64_t half_cell(i64 wx, i64 wy) {
  require(wx != 0 || wy != 0, "half_cell: the zero vector has no direction");
  constexpr std::int64_t mask = 2 * kCells - 1;
  const double a = atan2_guess(static_cast<double>(wy), static_cast<double>(wx));
  std::int64_t h = static_cast<std::int64_t>(std::floor(a * (2.0 * kCellsPerRadian))) & mask;
  while (cross(boundary(h), wx, wy) < 0) h = (h - 1) & mask;
  while (cross(boundary(h + 1), wx, wy) >= 0) h = (h + 1) & mask;
  return h;
}

std::int64_t coarse_cell(i64 wx, i64 wy, int shift, IVec& b0, IVec& b1) {
  require(wx != 0 || wy != 0, "coarse_cell: the zero vector has no direction");
  const std::int64_t mask = (kCells >> shift) - 1;
  const double a = atan2_guess(static_cast<double>(wy), static_cast<double>(wx));
  std::int64_t k = static_cast<std::int64_t>(std::floor(a * kCellsPerRadian * (1.0 / static_cast<double>(1LL << shift)))) & mask;
  b0 = boundary((2 * k) << shift);
  b1 = boundary((2 * k + 2) << shift);
  while (cross(b0, wx, wy) < 0) {
    k = (k - 1) & mask;
    b1 = b0;
    b0 = boundary((2 * k) << shift);
  }
  while (cross(b1, wx, wy) >= 0) {
    k = (k + 1) & mask;
    b0 = b1;
    b1 = boundary((2 * k + 2) << shift);
  }
  return k;
}

bool in_cell(i64 wx, i64 wy, std::int64_t k) {
  return cross(boundary(2 * k), wx, wy) >= 0 && cross(boundary(2 * k + 2), wx, wy) < 0;
}

bool in_coarse_cell(i64 wx, i64 wy, std::int64_t k, int shift) {
  return cross(boundary((2 * k) << shift), wx, wy) >= 0 && cross(boundary((2 * k + 2) << shift), wx, wy) < 0;
}

std::int64_t normal_cell(i64 xc, i64 sigma) { return normal_cell(xc, sigma, 0); }

std::int64_t normal_cell(i64 xc, i64 sigma, int shift) {
  require(sigma >= 1 && xc > -sigma && xc < sigma, "normal_cell: needs |xc| < sigma");
  require(shift >= 0 && shift <= kCellBits - 4, "normal_cell: shift must be in [0, 16]");
  // the guess: acos(u) = atan2(sqrt(1 - u^2), u) in [0, pi], rounded (any guess gives the same k)
  const double u = static_cast<double>(xc) / static_cast<double>(sigma);
  const double phi = atan2_guess(std::sqrt(std::max(0.0, 1.0 - u * u)), u);
  std::int64_t k = static_cast<std::int64_t>(phi * kCellsPerRadian * (1.0 / static_cast<double>(1LL << shift)) + 0.5);
  const i128 lhs = static_cast<i128>(xc) << kFixBits;
  // the coarse half-cell point h is the fine half-cell point h 2^shift
  auto bound = [&](std::int64_t h) { return static_cast<i128>(sigma) * boundary_x(h << shift); };
  // phi in [theta(2k-1), theta(2k+1)) <=> sigma*B(2k+1).x < xc*2^62 <= sigma*B(2k-1).x
  while (lhs > bound(2 * k - 1)) --k;
  while (lhs <= bound(2 * k + 1)) ++k;
  return k;
}

RotCoef rot_coef(std::int64_t k) {
  k &= kCells - 1;
  const std::int64_t qt = (k + kCells / 8) >> 18;  // nearest quarter turn, 0..4
  const std::int64_t r = k - qt * kQuarterTurn;   // residual in [-ND/8, ND/8)
  const IVec b = boundary(2 * r);
  // mag = round(|S| 2^62 / (2^62 + C)): a 124-bit numerator over a 64-bit divisor whose quotient
  // (< 2^61) fits a word, so one hardware division (libgcc's 128-bit division costs more)
  const u64 den = static_cast<u64>(kOne + b.x);  // 2^62 + cos(a) 2^62 < 2^64
  const u128 num = (static_cast<u128>(b.y < 0 ? -static_cast<i128>(b.y) : static_cast<i128>(b.y)) << kFixBits) + den / 2;
  const i64 mag = static_cast<i64>(div_word(num, den));
  return {static_cast<int>(qt & 3), b.y >= 0 ? -mag : mag, b.y};
}

std::uint64_t flux_cum(std::int64_t a) {
  const i64 y = boundary_y(2 * (a - kQuarterTurn));
  return static_cast<std::uint64_t>((1LL << 47) + ((y + (1LL << 14)) >> 15));
}

std::int64_t flux_decode(std::uint64_t s, std::uint64_t& cum, std::uint64_t& freq) {
  constexpr std::int64_t n = kHalfTurn;  // relative cells 0..2^19-1
  const double u = static_cast<double>(s) / static_cast<double>(1ULL << 47) - 1.0;
  const double uc = u < -1.0 ? -1.0 : (u > 1.0 ? 1.0 : u);
  const double th = atan2_guess(uc, std::sqrt(1.0 - uc * uc));  // asin(u), a guess
  std::int64_t b = static_cast<std::int64_t>(std::floor(th * kCellsPerRadian)) + kQuarterTurn;
  b = b < 0 ? 0 : (b >= n ? n - 1 : b);
  std::uint64_t lo = flux_cum(b);
  while (lo > s) lo = flux_cum(--b);  // cum(0) = 0 <= s stops it
  std::uint64_t hi = flux_cum(b + 1);
  while (hi <= s) {                    // cum(2^19) = 2^48 > s stops it
    lo = hi;
    hi = flux_cum(++b + 1);
  }
  cum = lo;
  freq = hi - lo;
  return b;
}

}  // namespace revcol::lattice
