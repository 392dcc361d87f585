#include "revcol/collide/ellipse_arc.hpp"

#include <cmath>
#include <vector>

#include "check.hpp"

using namespace revcol;
using namespace revcol::paper;

namespace {
constexpr double kPi = 3.141592653589793238462643383279502884;

// fixed G in (0, 1) and their long double references (slow: computed once)
const std::vector<std::pair<double, long double>>& refs() {
  static const std::vector<std::pair<double, long double>> r = [] {
    std::vector<std::pair<double, long double>> out;
    for (int k = 0; k < 400; ++k) {
      const double g = (k + 0.37) / 400.0;
      out.emplace_back(g, EllipseArc::reference_parametric(g, kPaperAspect));
    }
    for (double g : {1e-12, 1e-6, 0.25, 0.5, 0.75, 1.0 - 1e-9})
      out.emplace_back(g, EllipseArc::reference_parametric(g, kPaperAspect));
    return out;
  }();
  return r;
}
}  // namespace

TEST_CASE("the three arc-length methods agree with the reference within their tolerances") {
  struct M { ArcMethod m; double tol; };
  for (const M& m : {M{ArcMethod::simpson, 1e-9}, M{ArcMethod::elliptic, 1e-13}, M{ArcMethod::table, 1e-12}}) {
    const EllipseArc ell(m.m);
    long double worst = 0.0L;
    for (const auto& [g, ref] : refs())
      worst = std::max(worst, std::fabs(static_cast<long double>(ell.parametric(g)) - ref));
    CHECK(worst <= m.tol);
  }
  // and with each other
  const EllipseArc s(ArcMethod::simpson), e(ArcMethod::elliptic), t(ArcMethod::table);
  for (int k = 0; k <= 1000; ++k) {
    const double g = k / 1000.0;
    CHECK_NEAR(s.psi(g), e.psi(g), 1e-9);
    CHECK_NEAR(t.psi(g), e.psi(g), 1e-12);
  }
}

TEST_CASE("the reference itself: quarter points and the paper's perimeter series") {
  const long double pi = 3.141592653589793238462643383279502884L;
  CHECK(std::fabs(EllipseArc::reference_parametric(0.25L, kPaperAspect) - 0.5L * pi) < 1e-17L);
  CHECK(std::fabs(EllipseArc::reference_parametric(0.5L, kPaperAspect) - pi) < 1e-17L);
  // a circle: arc length is the angle
  CHECK(std::fabs(EllipseArc::reference_parametric(0.3L, 1.0L) - 0.6L * pi) < 1e-17L);
  const EllipseArc s(ArcMethod::simpson), e(ArcMethod::elliptic);
  CHECK_NEAR(s.perimeter(), e.perimeter(), 1e-14);  // series vs 4 E(k)
  CHECK_NEAR(s.arc(1.234), e.arc(1.234), 1e-12);    // adaptive Simpson vs GSL E(phi, k)
  CHECK_NEAR(e.arc(2.0 * kPi), e.perimeter(), 1e-14);
  CHECK_NEAR(e.arc(kPi + 0.3) - e.arc(kPi), e.arc(0.3), 1e-14);  // the amplitude reduction
  // near amplitude pi/2 (t near 0, pi, 2 pi): L(t) ~ q t, where gsl_sf_ellint_E cancels
  for (double d : {1e-10, 1e-8, 1e-6})
    CHECK(std::fabs(e.arc(d) - kPaperAspect * d) <= 1e-15);
}

TEST_CASE("endpoints, monotonicity, symmetry") {
  for (ArcMethod m : {ArcMethod::simpson, ArcMethod::elliptic, ArcMethod::table}) {
    const EllipseArc ell(m);
    CHECK(std::fabs(ell.psi(0.0)) <= 1e-9);
    CHECK(std::fabs(ell.psi(1.0) - 2.0 * kPi) <= 1e-9);
    CHECK_NEAR(ell.psi(0.25), 0.5 * kPi, 1e-9);
    CHECK_NEAR(ell.psi(0.5), kPi, 1e-9);
    double prev = -1.0;
    for (int k = 0; k <= 2000; ++k) {
      const double p = ell.psi(k / 2000.0);
      CHECK(p >= prev);
      prev = p;
    }
    // the ellipse is symmetric: psi(1 - g) = 2 pi - psi(g)
    for (double g : {0.01, 0.2, 0.33, 0.49})
      CHECK_NEAR(ell.psi(1.0 - g), 2.0 * kPi - ell.psi(g), m == ArcMethod::simpson ? 2e-9 : 1e-12);
  }
}

TEST_CASE("arc length is uniform in G: equal steps of G give equal arcs") {
  const EllipseArc e(ArcMethod::elliptic);
  for (int k = 0; k < 100; ++k) {
    const double a = e.arc(e.parametric(k / 100.0)), b = e.arc(e.parametric((k + 1) / 100.0));
    CHECK_NEAR(b - a, e.perimeter() / 100.0, 1e-13);
  }
}

TEST_CASE("the polar reading is the polar angle of the same point") {
  const EllipseArc par(ArcMethod::elliptic, ArcAngle::parametric), pol(ArcMethod::elliptic, ArcAngle::polar);
  for (int k = 1; k < 100; ++k) {
    const double g = k / 100.0, t = par.psi(g), th = pol.psi(g);
    const double x = std::cos(t), y = kPaperAspect * std::sin(t);  // the point (d_x = 1)
    CHECK_NEAR(std::atan2(y, x), std::atan2(std::sin(th), std::cos(th)), 1e-14);
  }
  // they differ away from the axes: the two readings are different samplers
  CHECK(std::fabs(par.psi(0.1) - pol.psi(0.1)) > 0.1);
}

TEST_CASE("validation") {
  const EllipseArc e(ArcMethod::elliptic);
  CHECK_THROWS_AS(e.psi(-0.1), InvalidArgument);
  CHECK_THROWS_AS(e.psi(1.5), InvalidArgument);
  CHECK_THROWS_AS(e.psi(std::nan("")), InvalidArgument);
  CHECK_THROWS_AS(EllipseArc(ArcMethod::elliptic, ArcAngle::parametric, 0.0), InvalidArgument);
  CHECK_THROWS_AS(EllipseArc(ArcMethod::elliptic, ArcAngle::parametric, 1.5), InvalidArgument);
  CHECK_THROWS_AS(EllipseArc(ArcMethod::table, ArcAngle::parametric, 0.5), InvalidArgument);
  CHECK_THROWS_AS(parse_arc_method("gauss"), InvalidArgument);
  CHECK_THROWS_AS(parse_arc_angle("geometric"), InvalidArgument);
  CHECK(parse_arc_method("table") == ArcMethod::table);
  CHECK(parse_arc_angle("polar") == ArcAngle::polar);
  // other aspects work for the two computed methods
  const EllipseArc c(ArcMethod::simpson, ArcAngle::parametric, 1.0);
  CHECK_NEAR(c.psi(0.3), 0.6 * kPi, 1e-9);
}

CHECK_MAIN()
