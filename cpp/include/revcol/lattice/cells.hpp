// Direction cells, the flux-law table and the lifting rotation of the lattice pair operator
// (LATTICE.md §3.2-3.3, docs/lattice.md "Cells").
//
// Cells. The circle is cut into ND = 2^20 cells of equal angle 2*pi/ND. Their boundaries are
// integer vectors B(h) at the half-cell resolution 2^21 per turn (cell boundary k is B(2k),
// half-cell points B(2k+1)), with |B| ~= 2^62:
//   * 0 <= h <= 2^18 (the first octant): B(h) = (cos, sin)(2*pi*h/2^21) * 2^62, built from two
//     compact tables (coarse steps of 2^9 half-cells x fine steps), each entry computed once,
//     at compile time, by a Taylor series in 62-bit fixed point from a 103-bit constant 2*pi
//     (integer arithmetic only: the same bits on every machine). B(2^18) is set exactly on the
//     diagonal (x = y = floor(2^61.5)).
//   * the rest by exact lattice symmetries: B(2^19 - h) = swap(B(h)) and B(h + 2^19) = B(h)
//     rotated by a quarter turn. So the cells are exactly symmetric under the 8 lattice
//     symmetries: cell(rot90(w)) = cell(w) + ND/4, cell(-w) = cell(w) + ND/2.
// The cell of an integer vector w != 0 is the k with cross(B(2k), w) >= 0 > cross(B(2k+2), w),
// decided exactly with 128-bit products; atan2 in single precision gives only the first guess (a wrong guess
// costs a step, never a different answer). This is the integer "pseudo-angle" of LATTICE.md §6:
// portable and deterministic, no libm value ever decides a cell.
//
// Normal cell. In the face frame (the inside point in the upper sector) the contact normal
// of column xc is n = (xc, sqrt(sigma^2 - xc^2)), angle phi = acos(xc/sigma) in (pi/4, 3pi/4).
// Its cell is phi rounded to the nearest cell: the k with
// sigma*B(2k+1).x < xc*2^62 <= sigma*B(2k-1).x (exact).
//
// Flux table. Relative cells a in [0, 2^19) stand for the direction j = a - ND/4 about the
// normal; the flux law F(theta) = (1 + sin theta)/2 gives the cumulative frequency
//   cum(a) = 2^47 + round(B(2j).y / 2^15)   (cum(0) = 0, cum(2^19) = 2^48, f(a) = cum(a+1) - cum(a)),
// computed on the fly (no 4 MB table): every f >= 1 (the smallest is ~2^11, test_lattice_pair2d
// checks all 2^19). Decoding s in [0, 2^48) guesses b from asin and corrects it exactly.
// The uniform law: cum(a) = a * 2^29.
//
// Lifting rotation by k cells: qt = nearest quarter turn, residual r = k - qt*ND/4 in
// [-ND/8, ND/8), angle a = 2*pi*r/ND; S = B(2r).y = sin(a)*2^62, P = -round(S*2^62/(2^62 +
// B(2r).x)) = -tan(a/2)*2^62. The rotation is rot90^qt, then x += round(P y / 2^62);
// y += round(S x / 2^62); x += round(P y / 2^62) (round: (v + 2^61) >> 62). Each shear is
// undone exactly by subtracting the same rounded term, so rotate_inv(rotate(w, k), k) == w
// for every w (the rotation is a bijection of Z^2, close to the true rotation within ~1 unit).
#pragma once
#include <cmath>
#include <cstdint>
#include <numbers>

#include "revcol/lattice/int128.hpp"

namespace revcol::lattice {

inline constexpr int kCellBits = 20;                 ///< 2^20 direction cells per turn
inline constexpr std::int64_t kCells = 1LL << kCellBits;  ///< ND
inline constexpr std::int64_t kHalfTurn = kCells >> 1;    ///< ND/2
inline constexpr std::int64_t kQuarterTurn = kCells >> 2; ///< ND/4
inline constexpr int kFixBits = 62;                  ///< fixed-point bits of B and of P, S
inline constexpr int kRansBits = 48;                 ///< frequency total 2^48

/// An integer vector (x, y).
struct IVec {
  i64 x;  ///< first component
  i64 y;  ///< second component
  friend bool operator==(const IVec&, const IVec&) = default;
};

/// (x, y) turned by k quarter turns counter-clockwise (k taken mod 4, negative allowed).
inline IVec rot90(IVec v, int k) {
  switch (k & 3) {
    case 0: return v;
    case 1: return {-v.y, v.x};
    case 2: return {-v.x, -v.y};
    default: return {v.y, -v.x};
  }
}

/// atan2(y, x) within 2.5e-7 rad for (x, y) != 0, a first guess only (a cell is 6e-6 rad): an odd
/// polynomial of degree 13 in t = min / max on [0, 1] (fitted for this purpose), then the octant.
/// The exact comparisons that follow it correct any guess (its rounding changes the number of
/// correction steps, never a cell), so no libm value decides anything; about a fifth of the
/// instructions of libm's atan2f, and it stands in for acos and asin too (atan2 of the two legs).
inline double atan2_guess(double y, double x) {
  const double ax = std::fabs(x), ay = std::fabs(y);
  const bool steep = ay > ax;
  const double t = steep ? ax / ay : ay / ax;
  const double t2 = t * t;
  double p = 0.0068117926046103588;
  p = p * t2 - 0.03360421913636702;
  p = p * t2 + 0.079623671866918211;
  p = p * t2 - 0.13233342169370219;
  p = p * t2 + 0.19807815630014494;
  p = p * t2 - 0.33317368071638948;
  p = p * t2 + 0.99999611156190982;
  double a = t * p;
  if (steep) a = std::numbers::pi / 2 - a;
  if (x < 0) a = std::numbers::pi - a;
  return y < 0 ? -a : a;
}

/// The boundary vector B(h) at half-cell resolution (h taken mod 2^21), |B| ~= 2^62.
IVec boundary(std::int64_t h);
/// B(h).x with half the work (the same bits).
i64 boundary_x(std::int64_t h);
/// B(h).y with half the work (the same bits).
i64 boundary_y(std::int64_t h);
/// The direction cell in [0, ND) of w != 0 (exact; see above).
std::int64_t dir_cell(i64 wx, i64 wy);
/// The half-cell h in [0, 2^21) of w != 0: cross(B(h), w) >= 0 > cross(B(h + 1), w), i.e.
/// 2 dir_cell(w) + 1 when w is at or past its cell's half-cell point, else 2 dir_cell(w); two
/// boundary evaluations when the first guess is right (dir_cell and that test take three).
std::int64_t half_cell(i64 wx, i64 wy);
/// The coarse cell k = dir_cell(w) >> shift of w != 0 (ND / 2^shift cells per turn), with its
/// boundaries b0 = B((2k) << shift) and b1 = B((2k + 2) << shift) (the same bits as boundary()):
/// two boundary evaluations when the first guess is right, and the caller needs no more.
std::int64_t coarse_cell(i64 wx, i64 wy, int shift, IVec& b0, IVec& b1);
/// dir_cell(wx, wy) == k, decided by two exact cross products (w != 0, 0 <= k < ND).
bool in_cell(i64 wx, i64 wy, std::int64_t k);
/// dir_cell(wx, wy) >> shift == k: w lies in the coarse cell k of ND / 2^shift cells per turn
/// (its boundaries are the fine boundaries k 2^shift and (k+1) 2^shift); shift = 0 is in_cell.
bool in_coarse_cell(i64 wx, i64 wy, std::int64_t k, int shift);
/// The cell nearest to the normal angle acos(xc/sigma); needs |xc| < sigma, sigma <= 2^61.
std::int64_t normal_cell(i64 xc, i64 sigma);
/// The coarse cell (ND / 2^shift per turn) nearest to acos(xc/sigma); shift = 0 is normal_cell.
std::int64_t normal_cell(i64 xc, i64 sigma, int shift);

/// The lifting coefficients of a rotation by k cells.
struct RotCoef {
  int qt;     ///< quarter turns, 0..3
  i64 p;      ///< -tan(a/2) * 2^62, a the residual angle
  i64 s;      ///< sin(a) * 2^62
};
/// The coefficients for k cells (k taken mod ND).
RotCoef rot_coef(std::int64_t k);
/// One lifting shear's term: round(coef y / 2^62), rounded half up (the same term undoes it).
inline i64 shear_term(i64 coef, i64 y) {
  return static_cast<i64>((static_cast<i128>(coef) * y + (static_cast<i128>(1) << (kFixBits - 1))) >> kFixBits);
}
/// The lifting rotation with given coefficients (exact bijection of Z^2 for |x|,|y| < 2^62).
/// (Inline, as the small helpers are; boundary() stays out of line: inlined at its dozen call
/// sites it saved 0.6% of the instructions but added ~45% to callgrind's I1 misses.)
inline IVec rotate(IVec w, const RotCoef& c) {
  IVec v = rot90(w, c.qt);
  v.x += shear_term(c.p, v.y);
  v.y += shear_term(c.s, v.x);
  v.x += shear_term(c.p, v.y);
  return v;
}
/// Its exact inverse.
inline IVec rotate_inv(IVec w, const RotCoef& c) {
  IVec v = w;
  v.x -= shear_term(c.p, v.y);
  v.y -= shear_term(c.s, v.x);
  v.x -= shear_term(c.p, v.y);
  return rot90(v, -c.qt);
}

/// The flux-law cumulative frequency cum(a), 0 <= a <= 2^19 (cum(2^19) = 2^48).
std::uint64_t flux_cum(std::int64_t a);
/// The relative cell b with flux_cum(b) <= s < flux_cum(b + 1), for s < 2^48; writes
/// cum = flux_cum(b) and freq = flux_cum(b + 1) - flux_cum(b).
std::int64_t flux_decode(std::uint64_t s, std::uint64_t& cum, std::uint64_t& freq);
/// As above, without the frequencies.
inline std::int64_t flux_decode(std::uint64_t s) {
  std::uint64_t c, f;
  return flux_decode(s, c, f);
}

}  // namespace revcol::lattice
