// Double-double arithmetic: a value hi + lo with |lo| <= ulp(hi)/2, from error-free
// transformations (Knuth's TwoSum, Dekker's TwoProd or one fused multiply-add), plain IEEE
// operations that -ffp-contract=off keeps exactly as written. Each transformation is exact,
// so its result is the same two numbers however it is computed: the bits are the same
// everywhere, in a baseline build and in a build for the host's FMA alike.
//
// Used where a double is not enough: the operators scale their post states to the relative
// kinetic energy. That energy is conserved, so it sits at the same place on the double grid
// collision after collision, and the rounding of a plain-double scale repeats instead of
// averaging out: a bias that grows linearly with the number of collisions (measured
// 3e-17 to 8e-17 per collision, 3e-11 after 1e6, in exact.cpp, pair2d and pair3d alike).
#pragma once
#include <cmath>

namespace revcol::dd {

/// hi + lo.
struct DD {
  double hi, lo;
};

/// a + b for |a| >= |b| (or a = 0), exactly.
inline DD quick_two_sum(double a, double b) {
  const double s = a + b;
  return {s, b - (s - a)};
}
/// a + b exactly.
inline DD two_sum(double a, double b) {
  const double s = a + b, bb = s - a;
  return {s, (a - (s - bb)) + (b - bb)};
}
/// a * b exactly by Dekker's product with Veltkamp's split: plain IEEE operations. Exact
/// unless a * b overflows or a partial result underflows, far outside the validated range.
inline DD two_prod_dekker(double a, double b) {
  constexpr double kSplit = 134217729.0;  // 2^27 + 1
  const double p = a * b;
  const double ca = kSplit * a, cb = kSplit * b;
  const double ah = ca - (ca - a), al = a - ah;
  const double bh = cb - (cb - b), bl = b - bh;
  return {p, ((ah * bh - p) + ah * bl + al * bh) + al * bl};
}
/// x * x exactly by Dekker's product: two_prod_dekker(x, x) with one split instead of two
/// and the two equal cross products as one, (xh + xh) xl. The same bits as
/// two_prod_dekker(x, x): in Dekker's product
/// every operation after the split is exact, so the sum of the cross terms is the same
/// representable number whether added as xh xl + xl xh or as 2 xh xl (xh + xh is exact,
/// and 2 xh xl has at most 53 significant bits). That holds while no partial result
/// underflows (|x| above about 2^-484, x^2 above 2^-969); below, neither form is exact and
/// their last bits may differ. tests/cpp/test_double_double.cpp compares the two bit for
/// bit.
inline DD two_square_dekker(double x) {
  constexpr double kSplit = 134217729.0;  // 2^27 + 1
  const double p = x * x;
  const double c = kSplit * x;
  const double xh = c - (c - x), xl = x - xh;
  return {p, ((xh * xh - p) + (xh + xh) * xl) + xl * xl};
}
/// Whether two_prod and two_square take the hardware fused multiply-add (a build with FMA).
#ifdef __FMA__
inline constexpr bool kFusedProducts = true;
#else
inline constexpr bool kFusedProducts = false;
#endif
/// a * b exactly. A build for a host with FMA (CMake REVCOL_ISA, __FMA__ defined) takes the
/// error from one fused multiply-add, fma(a, b, -p), two instructions instead of seventeen;
/// a baseline build takes Dekker's (no fma call: libm's software fma costs more than a pair
/// collision). Both are exact, so both give the same two numbers, hence the same bits in
/// either build, while the error term is representable: a * b above about 2^-969 (Dekker's
/// split needs the same headroom). tests/cpp/test_double_double.cpp compares them bit for bit.
inline DD two_prod(double a, double b) {
#ifdef __FMA__
  const double p = a * b;
  return {p, __builtin_fma(a, b, -p)};
#else
  return two_prod_dekker(a, b);
#endif
}
/// x * x exactly: two_prod(x, x), the same way (one fused multiply-add, or Dekker's with
/// one split).
inline DD two_square(double x) {
#ifdef __FMA__
  return two_prod(x, x);
#else
  return two_square_dekker(x);
#endif
}
/// x + y to double-double accuracy.
inline DD add(DD x, DD y) {
  const DD s = two_sum(x.hi, y.hi);
  return quick_two_sum(s.hi, s.lo + (x.lo + y.lo));
}
/// x^2 to double-double accuracy.
inline DD square(DD x) {
  const DD p = two_square(x.hi);
  return quick_two_sum(p.hi, p.lo + 2.0 * x.hi * x.lo);
}
/// a / b to double-double accuracy.
inline DD div(DD a, DD b) {
  const double q1 = a.hi / b.hi;
  const DD p = two_prod(q1, b.hi);
  const double r = ((a.hi - p.hi) - p.lo + a.lo) - q1 * b.lo;
  return quick_two_sum(q1, r / b.hi);
}
/// sqrt(x) for x > 0, to double-double accuracy.
inline DD sqrt(DD x) {
  const double r = std::sqrt(x.hi);
  const DD p = two_square(r);
  return quick_two_sum(r, ((x.hi - p.hi) - p.lo + x.lo) / (2.0 * r));
}
namespace detail {
// compensated_norm2's sum before its final QuickTwoSum: hi + lo, lo not yet normalized
template <int N>
inline DD compensated_sum_of_squares(const double* w) {
  DD s{w[0] * w[0], 0.0};
  for (int k = 1; k < N; ++k) {
    const DD t = two_sum(s.hi, w[k] * w[k]);
    s = {t.hi, s.lo + t.lo};
  }
  return s;
}
}  // namespace detail
/// |w|^2 of a short vector with its additions compensated (the squares rounded): what the
/// pair operators scale to. The rounding of a plain sum would repeat collision after
/// collision (|w| is conserved); the squares' roundings vary with the direction of w.
/// For N = 2 the sum is one TwoSum, whose result is already normalized: the final
/// QuickTwoSum would give it back bit for bit (|lo| <= ulp(hi)/2, and where that is a tie
/// the rounding had already chosen the even hi), so it is left out.
template <int N>
inline DD compensated_norm2(const double* w) {
  const DD s = detail::compensated_sum_of_squares<N>(w);
  if constexpr (N == 2) return s;
  return quick_two_sum(s.hi, s.lo);
}
/// (U.hi - 1) + U.lo for U = compensated_norm2<N>(u), bit for bit, where U.hi is in
/// [1/2, 2] (a unit vector to rounding): U.hi + U.lo is the unnormalized sum's hi + lo
/// exactly, and both hi - 1 are exact (Sterbenz), so the one rounding left sees the same
/// number. Skips the QuickTwoSum: |u|^2 - 1 of the operators' scales.
template <int N>
inline double compensated_norm2_minus_one(const double* u) {
  const DD s = detail::compensated_sum_of_squares<N>(u);
  return (s.hi - 1.0) + s.lo;
}
/// (S.hi - 1) + S.lo for S = add(x, y), bit for bit, where x.hi + y.hi rounds into
/// [1/2, 2]: add's QuickTwoSum keeps hi + lo, and both hi - 1 are exact (Sterbenz). The
/// 2D frame's |a|^2 - 1 from the squares of a unit vector's components.
inline double add_minus_one(DD x, DD y) {
  const DD s = two_sum(x.hi, y.hi);
  return (s.hi - 1.0) + (s.lo + (x.lo + y.lo));
}
/// The scale sqrt(R) / sqrt(1 + d) for R > 0 and a tiny d (a direction's |u|^2 - 1), as
/// hi + lo by its two first-order parts: sqrt(R) = rho + e / (2 rho) with rho = sqrt(R.hi)
/// (passed in) and e = R - rho^2 exactly, and 1 / sqrt(1 + d) = 1 - d / 2. What is left out
/// is of order u^2 sqrt(R); a double-double division and square root would cost 3 divisions
/// more.
inline DD first_order_scale(DD R, double rho, double d) {
  const DD rr = two_square(rho);
  const double e = ((R.hi - rr.hi) - rr.lo) + R.lo;
  return {rho, e / (2.0 * rho) - 0.5 * rho * d};
}
/// |u|^2 of a short vector, to double-double accuracy.
template <int N>
inline DD norm2(const double* u) {
  DD s{0.0, 0.0};
  for (int k = 0; k < N; ++k) s = add(s, two_square(u[k]));
  return s;
}

}  // namespace revcol::dd
