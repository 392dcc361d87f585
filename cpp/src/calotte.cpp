// Calotte-area tables of the paper's Procedure 5 (see calotte.hpp for the maths).
#include "revcol/collide/calotte.hpp"
#include "revcol/collide/tables.hpp"

#include <gsl/gsl_integration.h>

#include <algorithm>
#include <cmath>
#include <memory>

namespace revcol::paper {
namespace {

constexpr double kPi = 3.141592653589793238462643383279502884;

struct GlTable {
  gsl_integration_glfixed_table* t;
  explicit GlTable(std::size_t n) : t(gsl_integration_glfixed_table_alloc(n)) {
    require(t != nullptr, "GSL could not allocate a Gauss-Legendre table");
  }
  ~GlTable() { gsl_integration_glfixed_table_free(t); }
  GlTable(const GlTable&) = delete;
  GlTable& operator=(const GlTable&) = delete;
};

// I(t) = int_0^pi sin s sqrt(1 + 2 sin^2 t sin^2 s) ds (GSL Gauss-Legendre, 2 x 64 nodes:
// the integrand is analytic within 0.65 of the real axis, so this is exact to rounding).
double inner_h4(double t, const GlTable& gl) {
  struct P { double a; };
  P p{2.0 * std::sin(t) * std::sin(t)};
  gsl_function f;
  f.function = [](double s, void* params) {
    const double a = static_cast<P*>(params)->a, ss = std::sin(s);
    return ss * std::sqrt(1.0 + a * ss * ss);
  };
  f.params = &p;
  return gsl_integration_glfixed(&f, 0.0, 0.5 * kPi, gl.t) +
         gsl_integration_glfixed(&f, 0.5 * kPi, kPi, gl.t);
}

// The cap density (unnormalized) of each shape at latitude t.
double cap_density(int s, double t, const GlTable& inner) {
  const double st = std::sin(t);
  if (s == 3) return st * std::sqrt(1.0 + 2.0 * st * st);
  return st * st * inner_h4(t, inner);
}

// int_a^b cap_density by GSL Gauss-Legendre with `nodes` points per panel.
double cap_integral(int s, double a, double b, int panels, const GlTable& outer, const GlTable& inner) {
  struct P { int s; const GlTable* inner; };
  P p{s, &inner};
  gsl_function f;
  f.function = [](double t, void* params) {
    const P* q = static_cast<P*>(params);
    return cap_density(q->s, t, *q->inner);
  };
  f.params = &p;
  double sum = 0.0;
  const double h = (b - a) / panels;
  for (int k = 0; k < panels; ++k) sum += gsl_integration_glfixed(&f, a + k * h, a + (k + 1) * h, outer.t);
  return sum;
}

}  // namespace

CalotteTable::CalotteTable(int s, int n, int nodes) : s_(s), n_(n), nodes_(nodes), F_(n + 1), dF_(n + 1) {
  detail::note_table_built();
  const GlTable outer(static_cast<std::size_t>(nodes)), inner(64);
  const double h = kPi / n_;
  F_[0] = 0.0;
  for (int k = 1; k <= n_; ++k)
    F_[k] = F_[k - 1] + cap_integral(s, (k - 1) * h, k * h, 1, outer, inner);
  total_ = F_[n_];
  for (int k = 0; k <= n_; ++k) {
    F_[k] /= total_;
    dF_[k] = cap_density(s, k * h, inner) / total_;
  }
  F_[n_] = 1.0;
}

CalotteTable CalotteTable::build(int s, int n, int nodes) {
  require(s == 3 || s == 4, "calotte tables exist for s = 3 and s = 4");
  require(n >= 16 && n <= (1 << 20), "the calotte table's cells must be in [16, 2^20]");
  require(nodes >= 1 && nodes <= 64, "the calotte quadrature's nodes per cell must be in [1, 64]");
  return CalotteTable(s, n, nodes);
}

const CalotteTable& CalotteTable::h4() {
  static const CalotteTable t(4, cells, quadrature_nodes);  // built once, on first use, thread-safe
  return t;
}
const CalotteTable& CalotteTable::h3() {
  static const CalotteTable t(3, cells, quadrature_nodes);
  return t;
}

double CalotteTable::hermite(int k, double u) const {
  const double h = kPi / n_, u2 = u * u, u3 = u2 * u;
  return (2 * u3 - 3 * u2 + 1) * F_[k] + (u3 - 2 * u2 + u) * h * dF_[k] +
         (-2 * u3 + 3 * u2) * F_[k + 1] + (u3 - u2) * h * dF_[k + 1];
}

double CalotteTable::fraction(double psi) const {
  require(psi >= 0.0 && psi <= kPi, "latitude must be in [0, pi]");
  const double x = psi / kPi * n_;
  const int k = std::min(static_cast<int>(x), n_ - 1);
  return hermite(k, x - k);
}

double CalotteTable::inverse(double g) const {
  require(g >= 0.0 && g <= 1.0, "random number must be in [0,1]");
  // Both shapes are symmetric under x_1 -> -x_1: F(pi - psi) = 1 - F(psi). Near the far pole
  // F^-1 is a cube root of 1 - g, which g itself cannot carry; 1 - g is exact for g >= 1/2.
  if (g > 0.5) return kPi - inverse(1.0 - g);
  if (g == 0.0) return 0.0;
  // the cell: F_k <= g < F_{k+1}
  const auto it = std::upper_bound(F_.begin(), F_.end(), g);
  int k = static_cast<int>(it - F_.begin()) - 1;
  k = std::clamp(k, 0, n_ - 1);
  // bisection on the (monotone) Hermite cubic of that cell
  double lo = 0.0, hi = 1.0;
  for (int it2 = 0; it2 < 64 && hi - lo > 1e-16; ++it2) {
    const double mid = 0.5 * (lo + hi);
    if (hermite(k, mid) < g) lo = mid; else hi = mid;
  }
  return (k + 0.5 * (lo + hi)) * (kPi / n_);
}

double CalotteTable::density(double psi) const {
  const GlTable inner(64);
  return cap_density(s_, psi, inner) / total_;
}

double CalotteTable::fraction_direct(int s, double psi) {
  require(s == 3 || s == 4, "calotte tables exist for s = 3 and s = 4");
  require(psi >= 0.0 && psi <= kPi, "latitude must be in [0, pi]");
  const GlTable outer(20), inner(64);
  const double part = cap_integral(s, 0.0, psi, 64, outer, inner);
  const double whole = cap_integral(s, 0.0, kPi, 64, outer, inner);
  return part / whole;
}

}  // namespace revcol::paper
