// Cumulative distributions of cos^A(t) sin^B(t) with integer exponents, and their inverses:
// every one-dimensional law of the exact chart (DESIGN.md §3) is one of them.
//   eta in [0, pi/2], density ~ cos^A sin^B with A = m - 1 (+1 for the flux law), B = f - 1:
//       sin^2(eta) ~ Beta(f/2, m/2) (uniform) or Beta(f/2, (m+1)/2) (flux)
//   signed eta in (-pi/2, pi/2) when f = 1, density ~ cos^A
//   a hyperspherical angle phi in [0, pi] of the free part, density ~ sin^p
// J(A, B; x) = int_0^x cos^A sin^B is evaluated by the reduction formulas
//   J(A,B) = (-sin^{B-1} cos^{A+1} + (B-1) J(A,B-2)) / (A+B)     (B >= 2)
//   J(A,B) = ( sin^{B+1} cos^{A-1} + (A-1) J(A-2,B)) / (A+B)     (A >= 2)
// down to J(0,0) = x, J(1,0) = sin x, J(0,1) = 2 sin^2(x/2), J(1,1) = sin^2(x)/2. Each term is
// a product of bounded factors, so the CDF has an *absolute* error of a few ulp everywhere,
// which is what a chart coordinate needs (a cell is 2^-K wide); no 1 - F cancellation
// arises because the upper half of a [0, pi] law is evaluated from its far end.
// Inverses: closed forms where they exist, else safeguarded Newton on the bracket until the
// CDF matches to a few ulp (GSL's incomplete beta is not needed for integer exponents).
#pragma once
#include <cmath>
#include <limits>

namespace revcol::trig {

inline constexpr double kPi = 3.141592653589793238462643383279502884;

/// int_0^x cos^A sin^B given s = sin x, c = cos x, h = sin^2(x/2), x.
inline double integral(int A, int B, double x, double s, double c, double h) {
  if (A >= 2) {
    return (std::pow(s, B + 1) * std::pow(c, A - 1) + (A - 1) * integral(A - 2, B, x, s, c, h)) /
           (A + B);
  }
  if (B >= 2) {
    return (-std::pow(s, B - 1) * std::pow(c, A + 1) + (B - 1) * integral(A, B - 2, x, s, c, h)) /
           (A + B);
  }
  if (A == 0 && B == 0) return x;
  if (A == 1 && B == 0) return s;
  if (A == 0 && B == 1) return 2.0 * h;
  return 0.5 * s * s;  // A == 1, B == 1
}

/// int_0^{pi/2} cos^A sin^B, from exact endpoint values.
inline double total(int A, int B) { return integral(A, B, 0.5 * kPi, 1.0, 0.0, 0.5); }

/// The law with density cos^A sin^B / total on [0, pi/2].
class QuarterLaw {
 public:
  /// Exponents A, B >= 0.
  QuarterLaw(int A = 0, int B = 0) : A_(A), B_(B), norm_(total(A, B)) {
    // the density's maximum, cos^A sin^B at tan^2 = B/A, for the conditioning bound
    double peak;
    if (A == 0 && B == 0) peak = 1.0;
    else if (A == 0) peak = 1.0;
    else if (B == 0) peak = 1.0;
    else {
      const double t = std::atan(std::sqrt(static_cast<double>(B) / A));
      peak = std::pow(std::cos(t), A) * std::pow(std::sin(t), B);
    }
    max_density_ = peak / norm_;
  }
  int A() const { return A_; }  ///< cosine exponent
  int B() const { return B_; }  ///< sine exponent
  /// Largest density value (a bound on dF/dx).
  double max_density() const { return max_density_; }

  /// F(x) for x in [0, pi/2].
  double cdf(double x) const {
    const double s = std::sin(x), c = std::cos(x), hs = std::sin(0.5 * x);
    return integral(A_, B_, x, s, c, hs * hs) / norm_;
  }
  /// F(x) from x's sine and cosine (x = atan2(s, c) with s, c >= 0, s^2 + c^2 = 1).
  double cdf_sc(double s, double c) const {
    const double x = std::atan2(s, c);
    // sin^2(x/2) = (1 - c)/2 = s^2 / (2 (1 + c)): no cancellation
    const double h = s * s / (2.0 * (1.0 + c));
    return integral(A_, B_, x, s, c, h) / norm_;
  }
  /// x in [0, pi/2] with F(x) = u (u in [0, 1]).
  double inverse(double u) const {
    if (!(u > 0.0)) return 0.0;
    if (u >= 1.0) return 0.5 * kPi;
    if (A_ == 0 && B_ == 0) return u * 0.5 * kPi;
    if (A_ == 1 && B_ == 0) return std::asin(u);
    if (A_ == 0 && B_ == 1) return 2.0 * std::asin(std::sqrt(0.5 * u));
    if (A_ == 1 && B_ == 1) return std::asin(std::sqrt(u));
    return newton(u);
  }

 private:
  double newton(double u) const {
    double lo = 0.0, hi = 0.5 * kPi;
    double x = u * hi;  // start inside the bracket
    for (int it = 0; it < 200; ++it) {
      const double f = cdf(x) - u;
      if (f == 0.0) return x;
      if (f < 0.0) lo = x; else hi = x;
      const double dens = std::pow(std::cos(x), A_) * std::pow(std::sin(x), B_) / norm_;
      double next = dens > 0.0 ? x - f / dens : 0.5 * (lo + hi);
      if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
      if (next == x || hi - lo <= 4.0 * std::numeric_limits<double>::epsilon() * hi) return next;
      if (std::fabs(next - x) <= 1e-17 + 1e-16 * x) {
        // converged in x; F matches to a few ulp
        return next;
      }
      x = next;
    }
    return x;
  }

  int A_, B_;
  double norm_;
  double max_density_;
};

/// The law with density ~ sin^p on [0, pi] (a hyperspherical angle), p >= 0.
class HalfLaw {
 public:
  /// Exponent p >= 0.
  explicit HalfLaw(int p = 0) : q_(0, p) {}
  /// Largest density value on [0, pi].
  double max_density() const { return 0.5 * q_.max_density(); }
  /// F(phi) from phi's sine s >= 0 and cosine c (phi = atan2(s, c)).
  double cdf_sc(double s, double c) const {
    // the upper half from its far end: F(phi) = 1 - F(pi - phi)
    if (c >= 0.0) return 0.5 * q_.cdf_sc(s, c);
    return 1.0 - 0.5 * q_.cdf_sc(s, -c);
  }
  /// phi in [0, pi] with F(phi) = u, as (sin phi, cos phi) for accuracy at both ends.
  void inverse_sc(double u, double& s, double& c) const {
    if (u <= 0.5) {
      const double x = q_.inverse(2.0 * u);
      s = std::sin(x);
      c = std::cos(x);
    } else {
      const double x = q_.inverse(2.0 * (1.0 - u));  // 1 - u exact: u is a cell centre
      s = std::sin(x);
      c = -std::cos(x);
    }
  }

 private:
  QuarterLaw q_;
};

/// The law with density ~ cos^a on (-pi/2, pi/2) (the signed angle when f = 1).
class SignedLaw {
 public:
  /// Exponent a >= 0.
  explicit SignedLaw(int a = 0) : q_(a, 0) {}
  /// Largest density value.
  double max_density() const { return 0.5 * q_.max_density(); }
  /// F(eta) from eta's cosine c >= 0 and sine s (eta = atan2(s, c)).
  double cdf_sc(double s, double c) const {
    const double half = 0.5 * q_.cdf_sc(std::fabs(s), c);
    return s < 0.0 ? 0.5 - half : 0.5 + half;
  }
  /// eta with F(eta) = u, as (sin eta, cos eta).
  void inverse_sc(double u, double& s, double& c) const {
    const double x = q_.inverse(std::fabs(2.0 * u - 1.0));  // exact: u is a cell centre
    s = u < 0.5 ? -std::sin(x) : std::sin(x);
    c = std::cos(x);
  }

 private:
  QuarterLaw q_;
};

}  // namespace revcol::trig
