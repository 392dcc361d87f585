// Trigonometry in turns for the exact operators' charts, from IEEE basic operations only:
// sin(2 pi c) and cos(2 pi c) of a chart coordinate c in [0, 1] (sincos_turns), and the angle
// of a vector in turns, atan2(y, x) / (2 pi) in [0, 1] (atan2_turns).
//
// Why not libm: the chart coordinate is a fraction of a turn, so the argument reduction is
// exact here (c - q/4 for the nearest quarter q/4 is a difference of nearby doubles), where
// libm first rounds 2 pi c (up to 3 u of absolute error at c ~ 1) and then reduces again.
// glibc's kernels also save and restore the floating-point environment on every call:
// callgrind counts ~315 instructions for its atan2 and sincos together, ~110 for these two.
// And libm's last bit differs between versions, which makes a trajectory depend on the
// machine's C library; these give the same bits on every IEEE double machine (compiled with
// -ffp-contract=off, as revcol is).
//
// Accuracy (tests/cpp/test_trig.cpp measures it against long double over 2e6 points): sin
// and cos within 2.5e-16 absolute over [0, 1], the angle within 2e-16 of a turn. The
// constants come from scripts/trig_coefficients.py (mpmath, 50 digits, correctly rounded).
#pragma once
#include <cmath>
#include <cstdint>

namespace revcol::trig {

namespace detail {
// Taylor coefficients (-1)^k (2 pi)^(2k+1) / (2k+1)! and (-1)^k (2 pi)^(2k) / (2k)!, each
// correctly rounded. On |r| <= 1/8 turn the first terms left out,
// of order r^19 and r^18, are below 1e-19 and 3e-18.
inline constexpr double kSin[9] = {
    0x1.921fb54442d18p+2,  -0x1.4abbce625be53p+5, 0x1.466bc6775aae2p+6,
    -0x1.32d2cce62bd86p+6, 0x1.50783487ee782p+5,  -0x1.e3074fde8871fp+3,
    0x1.e8f434d018d63p+1,  -0x1.6fadb9f155744p-1, 0x1.aaec32af93359p-4};
inline constexpr double kCos[9] = {
    0x1.0000000000000p+0, -0x1.3bd3cc9be45dep+4, 0x1.03c1f081b5ac4p+6,
    -0x1.55d3c7e3cbffap+6, 0x1.e1f506891babbp+5, -0x1.a6d1f2a204a8cp+4,
    0x1.f9d38a3763cc3p+2,  -0x1.b6e24f44b128fp+0, 0x1.20c62c2f2d7f5p-2};
// atan(i/32) / (2 pi) for i = 0..32, correctly rounded, and the Taylor coefficients of
// atan(d) / (2 pi) = d (1 - d^2/3 + d^4/5 - d^6/7 ...) / (2 pi) on |d| <= 1/64, where the
// first term left out, d^9 / (9 * 2 pi), is below 1e-18.
inline constexpr double kAtanTurns[33] = {
    0x0.0p+0,               0x1.45d7e15904628p-8, 0x1.4586a1872c4d7p-7, 0x1.e77fc4d61a048p-7,
    0x1.4444750777668p-6,   0x1.942b2da6d3f8fp-6, 0x1.e34ff3a10b9ccp-6, 0x1.18c864aaecac3p-5,
    0x1.3f670b6bdc73dp-5,   0x1.657572a8eb16dp-5, 0x1.8ae6855098eecp-5, 0x1.afaea29d43dfbp-5,
    0x1.d3c3a482f3ab5p-5,   0x1.f71cdf27e994dp-5, 0x1.0cd98d1293ee4p-4, 0x1.1dc042355a3c1p-4,
    0x1.2e4051d9df308p-4,   0x1.3e58203d3c359p-4, 0x1.4e06a7aa3c7dep-4, 0x1.5d4b6c4888c77p-4,
    0x1.6c266f6edfc1ep-4,   0x1.7a9822cde870cp-4, 0x1.88a15bbbca864p-4, 0x1.964346db496e2p-4,
    0x1.a37f5c4c419efp-4,   0x1.b05754878e5b1p-4, 0x1.bccd1dfdd0272p-4, 0x1.c8e2d3876e8e1p-4,
    0x1.d49ab3ac8b1bbp-4,   0x1.dff718c563e17p-4, 0x1.eafa71eebf23ap-4, 0x1.f5a73cca450a1p-4,
    0x1.0000000000000p-3};
inline constexpr double kAtanPoly[4] = {0x1.45f306dc9c883p-3, -0x1.b2995e7b7b604p-5,
                                        0x1.04c26be3b06cfp-5, -0x1.7483758e69c03p-6};
}  // namespace detail

inline void sincos_quarters(std::int64_t q, double r, double& s, double& co);

/// sin(2 pi c) and cos(2 pi c) for c in [0, 1] (absolute error < 2.5e-16; outside [0, 1]
/// the result is unspecified). Same bits on every IEEE double platform.
inline void sincos_turns(double c, double& s, double& co) {
  // the nearest quarter turn q/4 and the remainder r in [-1/8, 1/8] turn: 4c is exact, and
  // so is 4c - q (nearby doubles), except when 4c lies within 2^-54 below 1/2 and the +1/2
  // rounds up: then r is off by at most 2^-57, a 4e-17 error in the result
  const double c4 = 4.0 * c;
  const auto q = static_cast<std::int64_t>(c4 + 0.5);
  sincos_quarters(q, 0.25 * (c4 - static_cast<double>(q)), s, co);
}

/// sin and cos of 2 pi (q/4 + r) for an integer q and |r| <= 1/8: sincos_turns after its
/// argument reduction, for callers that have the reduction exactly at hand (Pair3DExact
/// reduces its K-bit cells in integers).
inline void sincos_quarters(std::int64_t q, double r, double& s, double& co) {
  const double z = r * r;
  using detail::kCos;
  using detail::kSin;
  double ps = kSin[8], pc = kCos[8];
  for (int k = 7; k >= 0; --k) {
    ps = kSin[k] + z * ps;
    pc = kCos[k] + z * pc;
  }
  const double sr = r * ps, cr = pc;  // sin and cos of 2 pi r
  switch (q & 3) {
    case 0: s = sr, co = cr; break;
    case 1: s = cr, co = -sr; break;
    case 2: s = -sr, co = -cr; break;
    default: s = -cr, co = sr; break;
  }
}

/// atan2(y, x) / (2 pi) wrapped into [0, 1] (1 only by rounding just below a full turn):
/// the angle of (x, y) in turns, for finite x, y below 2^1022 in size; 0 for x = y = 0 (absolute error < 2e-16
/// in turns). Same bits on every IEEE double platform.
inline double atan2_turns(double y, double x) {
  // octant: t = min / max of |x|, |y| in [0, 1]; then atan(t) = atan(c) + atan(d) with c the
  // nearest multiple of 1/32 and d = (t - c) / (1 + t c) = (num - c den) / (den + c num),
  // |d| <= 1/64 (plus rounding). c den rounds by <= u/2 den; the subtraction from num is then
  // exact (Sterbenz: num / (c den) is within 1 +- 1/2 for c >= 1/32), so d is off by <= u/2
  // absolute plus its own 1.5 u relative: below u/10 of a turn in all
  const double ax = std::fabs(x), ay = std::fabs(y);
  const bool swap = ay > ax;
  const double num = swap ? ax : ay, den = swap ? ay : ax;
  if (!(den > 0.0)) return 0.0;  // the origin (a NaN also lands here; callers exclude it)
  const double t = num / den;
  const auto i = static_cast<int>(32.0 * t + 0.5);
  const double c = 0x1.0p-5 * i;
  const double d = (num - c * den) / (den + c * num);
  const double z = d * d;
  using detail::kAtanPoly;
  const double p = d * (kAtanPoly[0] + z * (kAtanPoly[1] + z * (kAtanPoly[2] + z * kAtanPoly[3])));
  double a = detail::kAtanTurns[i] + p;  // in [0, 1/8]
  if (swap) a = 0.25 - a;
  if (x < 0.0) a = 0.5 - a;
  if (y < 0.0) a = 1.0 - a;
  return a;
}

}  // namespace revcol::trig
