// The arc-length sampler of the paper's §4.4 (see ellipse_arc.hpp for the maths).
#include "revcol/collide/ellipse_arc.hpp"
#include "revcol/collide/tables.hpp"

#include <gsl/gsl_mode.h>
#include <gsl/gsl_sf_ellint.h>  // gsl_sf_ellint_Ecomp, _RF, _RD

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <vector>

namespace revcol::paper {
namespace {

constexpr double kPi = 3.141592653589793238462643383279502884;
constexpr double kTwoPi = 2.0 * kPi;

double wrap2pi(double x) {
  double r = std::fmod(x, kTwoPi);
  if (r < 0.0) r += kTwoPi;
  if (r >= kTwoPi) r -= kTwoPi;
  return r;
}

// The paper's series for the perimeter: pi (1 + q) sum binom(1/2, n)^2 h^n (d_x = 1).
double series_perimeter(double q) {
  const double h = ((1.0 - q) / (1.0 + q)) * ((1.0 - q) / (1.0 + q));
  double binom = 1.0, hn = 1.0, sum = 0.0;
  for (int n = 0; n < 2000; ++n) {
    const double term = binom * binom * hn;
    sum += term;
    if (term <= 1e-18 * sum) break;
    binom *= (0.5 - n) / (n + 1.0);  // binom(1/2, n+1) from binom(1/2, n)
    hn *= h;
  }
  return kPi * (1.0 + q) * sum;
}

// Gauss-Legendre nodes and weights on [-1, 1] in long double (Newton on P_n).
template <int N>
struct GaussLegendre {
  std::array<long double, N> x{}, w{};
  GaussLegendre() {
    const long double pi = 3.141592653589793238462643383279502884L;
    for (int i = 0; i < N; ++i) {
      long double z = std::cos(pi * (i + 0.75L) / (N + 0.5L)), dp = 0.0L;
      for (int it = 0; it < 100; ++it) {
        long double p0 = 1.0L, p1 = z;
        for (int k = 2; k <= N; ++k) {
          const long double p2 = ((2.0L * k - 1.0L) * z * p1 - (k - 1.0L) * p0) / k;
          p0 = p1;
          p1 = p2;
        }
        dp = N * (z * p1 - p0) / (z * z - 1.0L);
        const long double dz = p1 / dp;
        z -= dz;
        if (std::fabs(dz) < 1e-21L) break;
      }
      x[i] = z;
      w[i] = 2.0L / ((1.0L - z * z) * dp * dp);
    }
  }
};

long double ref_speed(long double t, long double q) {
  const long double s = std::sin(t), c = std::cos(t);
  return std::sqrt(s * s + q * q * c * c);
}

long double ref_arc(long double t, long double q) {
  static const GaussLegendre<20> gl;
  const long double pi = 3.141592653589793238462643383279502884L;
  const int panels = std::max(1, static_cast<int>(std::ceil(t / (pi / 32.0L))));
  const long double h = t / panels;
  long double sum = 0.0L;
  for (int p = 0; p < panels; ++p) {
    const long double mid = (p + 0.5L) * h;
    for (int i = 0; i < 20; ++i) sum += gl.w[i] * ref_speed(mid + 0.5L * h * gl.x[i], q);
  }
  return 0.5L * h * sum;
}

}  // namespace

const char* to_string(ArcMethod m) {
  switch (m) {
    case ArcMethod::simpson: return "simpson";
    case ArcMethod::elliptic: return "elliptic";
    case ArcMethod::table: return "table";
  }
  return "?";
}
const char* to_string(ArcAngle a) { return a == ArcAngle::parametric ? "parametric" : "polar"; }

ArcMethod parse_arc_method(const std::string& s) {
  if (s == "simpson") return ArcMethod::simpson;
  if (s == "elliptic") return ArcMethod::elliptic;
  if (s == "table") return ArcMethod::table;
  throw InvalidArgument("arc must be 'simpson', 'elliptic' or 'table', got '" + s + "'");
}
ArcAngle parse_arc_angle(const std::string& s) {
  if (s == "parametric") return ArcAngle::parametric;
  if (s == "polar") return ArcAngle::polar;
  throw InvalidArgument("angle must be 'parametric' or 'polar', got '" + s + "'");
}

struct EllipseArc::Table {
  double perimeter;
  std::vector<double> t, slope;  // t(G_k) and dt/dG at G_k = k / cells
};

std::shared_ptr<const EllipseArc::Table> EllipseArc::build_table(int cells) {
  detail::note_table_built();
  const EllipseArc ell(ArcMethod::elliptic, ArcAngle::parametric, kPaperAspect);
  auto tb = std::make_shared<Table>();
  tb->perimeter = ell.perimeter();
  tb->t.resize(cells + 1);
  tb->slope.resize(cells + 1);
  for (int k = 0; k <= cells; ++k) {
    const double g = static_cast<double>(k) / cells;
    tb->t[k] = k == cells ? kTwoPi : ell.parametric(g);
    tb->slope[k] = tb->perimeter / ell.speed(tb->t[k]);
  }
  return tb;
}

const EllipseArc::Table& EllipseArc::paper_table() {
  // Built once, on first use, thread-safe (a function-local static).
  static const std::shared_ptr<const Table> table = build_table(table_cells);
  return *table;
}

EllipseArc::EllipseArc(ArcMethod method, ArcAngle angle, double aspect)
    : EllipseArc(method, angle, aspect, simpson_tolerance, table_cells) {}

EllipseArc::EllipseArc(ArcMethod method, ArcAngle angle, double aspect, double tolerance, int cells)
    : method_(method), angle_(angle), q_(aspect), tol_(tolerance), cells_(cells) {
  require(std::isfinite(aspect) && aspect > 0.0 && aspect <= 1.0,
          "ellipse aspect d_y / d_x must be in (0, 1]");
  require(std::isfinite(tolerance) && tolerance >= 1e-14 && tolerance <= 1e-2,
          "the simpson tolerance must be in [1e-14, 1e-2]");
  require(cells >= 16 && cells <= (1 << 20), "the table's cells must be in [16, 2^20]");
  k_ = std::sqrt((1.0 - q_) * (1.0 + q_));
  if (method_ == ArcMethod::simpson) {
    perimeter_ = series_perimeter(q_);
  } else {
    perimeter_ = 4.0 * gsl_sf_ellint_Ecomp(k_, GSL_PREC_DOUBLE);
  }
  if (method_ == ArcMethod::table) {
    require(q_ == kPaperAspect, "the table method exists for the paper's ellipse only (aspect 1/sqrt(3))");
    if (cells_ == table_cells) {
      table_ = &paper_table();
    } else {
      own_table_ = build_table(cells_);
      table_ = own_table_.get();
    }
  }
}

double EllipseArc::parametric(double g) const {
  require(g >= 0.0 && g <= 1.0, "random number must be in [0,1]");
  switch (method_) {
    case ArcMethod::simpson: return simpson_parametric(g);
    case ArcMethod::elliptic: return elliptic_parametric(g);
    case ArcMethod::table: return table_parametric(g);
  }
  return 0.0;
}

// E(phi | k) for any amplitude: reduce to r in [-pi/2, pi/2] (E(r + n pi) = 2 n E(k) + E(r)),
// then Carlson's form with GSL's R_F and R_D,
//     E(r) = sin r R_F(cos^2 r, 1 - k^2 sin^2 r, 1) - k^2/3 sin^3 r R_D(cos^2 r, 1 - k^2 sin^2 r, 1).
// This is how gsl_sf_ellint_E computes it, except that GSL forms cos^2 r as 1 - sin^2 r, which
// cancels near r = +-pi/2: there gsl_sf_ellint_E is wrong by up to 6e-9 (it returns E(k)
// exactly for pi/2 - r < 1e-8; measured), i.e. near t = 0, pi, 2 pi of the arc. We compute
// cos^2 r and 1 - k^2 sin^2 r = q^2 + k^2 cos^2 r directly.
double EllipseArc::ellint_e(double phi) const {
  const double nc = std::floor(phi / kPi + 0.5);
  const double r = phi - nc * kPi;
  const double s = std::sin(r), c = std::cos(r), c2 = c * c;
  const double y = q_ * q_ + k_ * k_ * c2;
  const double val = s * gsl_sf_ellint_RF(c2, y, 1.0, GSL_PREC_DOUBLE) -
                     (k_ * k_ / 3.0) * s * s * s * gsl_sf_ellint_RD(c2, y, 1.0, GSL_PREC_DOUBLE);
  return 0.5 * nc * perimeter_ + val;
}

double EllipseArc::arc(double t) const {
  if (method_ == ArcMethod::simpson) return t >= 0 ? simpson_arc(0.0, t, 1e-12) : -simpson_arc(t, 0.0, 1e-12);
  // L(t) = E(t - pi/2 | k) + E(k)
  return ellint_e(t - 0.5 * kPi) + 0.25 * perimeter_;
}

double EllipseArc::polar_of(double t) const {
  return wrap2pi(std::atan2(q_ * std::sin(t), std::cos(t)));
}

// Adaptive Simpson on [a, b] to absolute tolerance tol (Richardson-corrected, depth <= 40).
double EllipseArc::simpson_arc(double a, double b, double tol) const {
  struct Seg { double a, b, fa, fm, fb, whole, tol; int depth; };
  auto panel = [](double a_, double b_, double fa, double fm, double fb) {
    return (b_ - a_) / 6.0 * (fa + 4.0 * fm + fb);
  };
  const double fa = speed(a), fb = speed(b), fm = speed(0.5 * (a + b));
  // explicit stack (deterministic order: left before right)
  Seg stack[64];
  int top = 0;
  stack[top++] = {a, b, fa, fm, fb, panel(a, b, fa, fm, fb), tol, 40};
  double sum = 0.0;
  while (top > 0) {
    const Seg s = stack[--top];
    const double m = 0.5 * (s.a + s.b);
    const double flm = speed(0.5 * (s.a + m)), frm = speed(0.5 * (m + s.b));
    const double left = panel(s.a, m, s.fa, flm, s.fm), right = panel(m, s.b, s.fm, frm, s.fb);
    const double delta = left + right - s.whole;
    if (s.depth <= 0 || std::fabs(delta) <= 15.0 * s.tol || top >= 62) {
      sum += left + right + delta / 15.0;
    } else {
      stack[top++] = {m, s.b, s.fm, frm, s.fb, right, 0.5 * s.tol, s.depth - 1};
      stack[top++] = {s.a, m, s.fa, flm, s.fm, left, 0.5 * s.tol, s.depth - 1};
    }
  }
  return sum;
}

// The paper's bisection: lower bound 0, upper bound 2 pi, first guess pi; move the bound
// on the side of the target to the guess until the bracket is below 1e-9. L(lower) is
// carried, so each step integrates only [lower, guess]. Per step the adaptive Simpson
// tolerance is 1e-9; its Richardson-corrected sums are far more accurate than that bound
// (measured against the reference: the arc error adds at most 2e-11 to the angle, whose
// error, 4e-10 at most, is the half bracket). Measure before changing: a tolerance of
// 1e-12 costs 5 times as much for no gain in the angle.
double EllipseArc::simpson_parametric(double g) const {
  const double target = g * perimeter_;
  double lo = 0.0, hi = kTwoPi, arc_lo = 0.0;
  while (hi - lo > tol_) {
    const double mid = 0.5 * (lo + hi);
    const double arc_mid = arc_lo + simpson_arc(lo, mid, tol_);
    if (arc_mid < target) {
      lo = mid;
      arc_lo = arc_mid;
    } else {
      hi = mid;
    }
  }
  return 0.5 * (lo + hi);
}

// Newton's method on L(t) = target with GSL's E, kept inside a shrinking bracket.
double EllipseArc::elliptic_parametric(double g) const {
  const double target = g * perimeter_;
  double lo = 0.0, hi = kTwoPi, t = kTwoPi * g;
  for (int it = 0; it < 100; ++it) {
    const double f = arc(t) - target;
    if (f == 0.0) return t;
    if (f < 0.0) lo = t; else hi = t;
    double next = t - f / speed(t);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    if (std::fabs(next - t) <= 4e-16 * std::fmax(1.0, t) || hi - lo <= 4e-16 * std::fmax(1.0, t))
      return next;
    t = next;
  }
  return t;
}

double EllipseArc::table_parametric(double g) const {
  const Table& tb = *table_;
  const double x = g * cells_;
  const int k = std::min(static_cast<int>(x), cells_ - 1);
  const double u = x - k, h = 1.0 / cells_;
  const double u2 = u * u, u3 = u2 * u;
  const double h00 = 2 * u3 - 3 * u2 + 1, h10 = u3 - 2 * u2 + u, h01 = -2 * u3 + 3 * u2, h11 = u3 - u2;
  return h00 * tb.t[k] + h10 * h * tb.slope[k] + h01 * tb.t[k + 1] + h11 * h * tb.slope[k + 1];
}

long double EllipseArc::reference_parametric(long double g, long double q) {
  const long double pi = 3.141592653589793238462643383279502884L;
  const long double perimeter = 4.0L * ref_arc(0.5L * pi, q);
  const long double target = g * perimeter;
  long double lo = 0.0L, hi = 2.0L * pi, t = 2.0L * pi * g;
  for (int it = 0; it < 200; ++it) {
    const long double f = ref_arc(t, q) - target;
    if (f == 0.0L) return t;
    if (f < 0.0L) lo = t; else hi = t;
    long double next = t - f / ref_speed(t, q);
    if (!(next > lo && next < hi)) next = 0.5L * (lo + hi);
    if (std::fabs(next - t) <= 1e-19L * (1.0L + t)) return next;
    t = next;
  }
  return t;
}

}  // namespace revcol::paper
