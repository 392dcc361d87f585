// trig_cdf.hpp: the CDFs of cos^A sin^B on [0, pi/2] (QuarterLaw), of sin^p on [0, pi]
// (HalfLaw) and of cos^a on (-pi/2, pi/2) (SignedLaw), and their inverses. Each CDF is
// checked against an independent quadrature (composite Gauss-Legendre in long double on
// many panels), at its endpoints, for monotonicity, and each inverse by the round trip
// F(F^-1(u)) = u to a few ulp in u (the accuracy a K-bit chart needs) and F^-1(F(x)) = x
// where the density is not small.
#include "revcol/collide/trig_cdf.hpp"

#include <cmath>
#include <random>

#include "check.hpp"

using namespace revcol::trig;

namespace {

// int_a^b cos^A sin^B by 5-point Gauss-Legendre on 400 panels, in long double (error of
// order (h/2)^10 max|f^(10)| < 1e-19 here, far below the few ulp checked).
long double quad(int A, int B, long double a, long double b) {
  static const long double x5[5] = {0.0L, -0.5384693101056830910363144L, 0.5384693101056830910363144L,
                                    -0.9061798459386639927976269L, 0.9061798459386639927976269L};
  static const long double w5[5] = {0.5688888888888888888888889L, 0.4786286704993664680412915L,
                                    0.4786286704993664680412915L, 0.2369268850561890875142640L,
                                    0.2369268850561890875142640L};
  const int panels = 400;
  const long double h = (b - a) / panels;
  long double sum = 0.0L;
  for (int p = 0; p < panels; ++p) {
    const long double mid = a + (p + 0.5L) * h;
    for (int k = 0; k < 5; ++k) {
      const long double t = mid + 0.5L * h * x5[k];
      sum += w5[k] * std::pow(std::cos(t), A) * std::pow(std::sin(t), B);
    }
  }
  return 0.5L * h * sum;
}

constexpr double kEps = 2.220446049250313e-16;

}  // namespace

TEST_CASE("QuarterLaw: endpoints, monotone, equal to quadrature") {
  for (int A = 0; A <= 6; ++A)
    for (int B = 0; B <= 6; ++B) {
      const QuarterLaw law(A, B);
      const long double norm = quad(A, B, 0.0L, 0.5L * kPi);
      CHECK(std::fabs(total(A, B) - norm) <= 8 * kEps * norm);
      CHECK(law.cdf(0.0) == 0.0);
      CHECK(std::fabs(law.cdf(0.5 * kPi) - 1.0) <= 4 * kEps);
      double prev = 0.0;
      for (int k = 1; k <= 200; ++k) {
        const double x = 0.5 * kPi * k / 200.0;
        const double F = law.cdf(x);
        CHECK(F >= prev);  // monotone
        prev = F;
        if (k % 20 == 0) {
          const long double ref = quad(A, B, 0.0L, x) / norm;
          CHECK(std::fabs(F - static_cast<double>(ref)) <= 8 * kEps);  // absolute, a few ulp
          // cdf_sc from the sine and cosine agrees with cdf(x)
          CHECK(std::fabs(law.cdf_sc(std::sin(x), std::cos(x)) - F) <= 4 * kEps);
        }
      }
      // the density bound holds on the grid
      for (int k = 0; k <= 100; ++k) {
        const double x = 0.5 * kPi * k / 100.0;
        const double dens = std::pow(std::cos(x), A) * std::pow(std::sin(x), B) / total(A, B);
        CHECK(dens <= law.max_density() * (1 + 1e-12));
      }
    }
}

TEST_CASE("QuarterLaw: inverse round trips, endpoints and out-of-range u") {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unif(0.0, 1.0);
  for (int A = 0; A <= 6; ++A)
    for (int B = 0; B <= 6; ++B) {
      const QuarterLaw law(A, B);
      CHECK(law.inverse(0.0) == 0.0);
      CHECK(law.inverse(-0.25) == 0.0);
      CHECK(law.inverse(1.0) == 0.5 * kPi);
      CHECK(law.inverse(1.5) == 0.5 * kPi);
      double prev = 0.0;
      for (int t = 0; t < 400; ++t) {
        const double u = t < 200 ? (t + 0.5) / 200.0 : unif(rng);
        const double x = law.inverse(u);
        CHECK(x >= 0.0);
        CHECK(x <= 0.5 * kPi);
        CHECK(std::fabs(law.cdf(x) - u) <= 16 * kEps);  // F(F^-1(u)) = u
        if (t < 200) {
          CHECK(x >= prev);  // the inverse is monotone too
          prev = x;
        }
        // F^-1(F(x)) = x where the density is not small (error ~ eps / density)
        const double dens = std::pow(std::cos(x), A) * std::pow(std::sin(x), B) / total(A, B);
        if (dens > 1e-3) CHECK(std::fabs(law.inverse(law.cdf(x)) - x) <= 64 * kEps / dens);
      }
      // near the ends, at a chart's cell width
      for (double u : {std::ldexp(1.0, -41), 1.0 - std::ldexp(1.0, -41)})
        CHECK(std::fabs(law.cdf(law.inverse(u)) - u) <= 16 * kEps);
    }
}

TEST_CASE("HalfLaw (sin^p on [0, pi]): endpoints, symmetry, quadrature, inverse") {
  for (int p = 0; p <= 6; ++p) {
    const HalfLaw law(p);
    const long double norm = quad(0, p, 0.0L, kPi);
    CHECK(law.cdf_sc(0.0, 1.0) == 0.0);
    CHECK(std::fabs(law.cdf_sc(0.0, -1.0) - 1.0) <= 4 * kEps);
    CHECK(std::fabs(law.cdf_sc(1.0, 0.0) - 0.5) <= 4 * kEps);
    double prev = 0.0;
    for (int k = 1; k < 100; ++k) {
      const double phi = kPi * k / 100.0;
      const double s = std::sin(phi), c = std::cos(phi);
      const double F = law.cdf_sc(s, c);
      CHECK(F >= prev);
      prev = F;
      CHECK(std::fabs(F - static_cast<double>(quad(0, p, 0.0L, phi) / norm)) <= 8 * kEps);
      CHECK(std::fabs(law.cdf_sc(s, -c) - (1.0 - F)) <= 8 * kEps);  // F(pi - phi) = 1 - F(phi)
    }
    for (int t = 0; t < 200; ++t) {
      const double u = (t + 0.5) / 200.0;
      double s = 0, c = 0;
      law.inverse_sc(u, s, c);
      CHECK(s >= 0.0);
      CHECK(std::fabs(s * s + c * c - 1.0) <= 4 * kEps);
      CHECK(std::fabs(law.cdf_sc(s, c) - u) <= 16 * kEps);
      CHECK((u < 0.5) == (c > 0.0));
    }
    const double dens_max = std::pow(1.0, p) / static_cast<double>(norm);
    CHECK(std::fabs(law.max_density() - dens_max) <= 1e-12 * dens_max);
  }
}

TEST_CASE("SignedLaw (cos^a on (-pi/2, pi/2)): centre, symmetry, quadrature, inverse") {
  for (int a = 0; a <= 6; ++a) {
    const SignedLaw law(a);
    const long double norm = quad(a, 0, -0.5L * kPi, 0.5L * kPi);
    CHECK(law.cdf_sc(0.0, 1.0) == 0.5);
    CHECK(std::fabs(law.cdf_sc(-1.0, 0.0)) <= 4 * kEps);
    CHECK(std::fabs(law.cdf_sc(1.0, 0.0) - 1.0) <= 4 * kEps);
    double prev = 0.0;
    for (int k = -49; k < 50; ++k) {
      const double eta = kPi * k / 100.0;
      const double s = std::sin(eta), c = std::cos(eta);
      const double F = law.cdf_sc(s, c);
      CHECK(F >= prev);
      prev = F;
      CHECK(std::fabs(F - static_cast<double>(quad(a, 0, -0.5L * kPi, eta) / norm)) <= 8 * kEps);
      CHECK(std::fabs(law.cdf_sc(-s, c) - (1.0 - F)) <= 8 * kEps);
    }
    for (int t = 0; t < 200; ++t) {
      const double u = (t + 0.5) / 200.0;
      double s = 0, c = 0;
      law.inverse_sc(u, s, c);
      CHECK(c >= 0.0);
      CHECK((u < 0.5) == (s < 0.0));
      CHECK(std::fabs(law.cdf_sc(s, c) - u) <= 16 * kEps);
    }
  }
}

CHECK_MAIN()
