// G-to-Psi of the paper for 3 particles in 1 dimension (Perumalla & Protopopescu 2013,
// §4.4 "Sampling the Circumference of the Ellipse"): a point uniform in arc length on the
// ellipse (x/d_x)^2 + (y/d_y)^2 = 1, with exactly one random number,
//     psi = L^-1(G L(2 pi)),   L(psi) = arc length from (d_x, 0) counter-clockwise,
// for the paper's ellipse d_y = d_x / sqrt(3) (eq. 3sphere-1dim-ellipse). d_x scales out, so
// psi depends on G alone (aspect q = d_y / d_x fixed).
//
// Which angle is psi? The text is ambiguous. Its footnote says the angle "is in fact the
// parameter in the representation of the point on the ellipse, and not the geometrical
// angle", but the definition of L that follows ends the arc at (r cos psi, r sin psi) with
// r^2 = d_x^2 d_y^2 / (d_y^2 cos^2 + d_x^2 sin^2): the polar (geometrical) angle. We take
// the PARAMETRIC angle t (the point (d_x cos t, d_y sin t)) by default: psi is added to
// phi_1, which the paper defines as the parameter of the same ellipse (a-bar = d_x cos phi_1,
// b-bar - sqrt2 alpha/3 = d_y sin phi_1), so only the parametric reading adds like to like,
// and the footnote says so explicitly. ArcAngle::polar gives the other reading (the polar
// angle of the same point), for measurement: docs/paper-findings.md compares both.
// Either way the POINT is uniform in arc length on the paper's ellipse, which is not the
// uniform (microcanonical) measure on velocities: the ellipse is the round circle of the
// relative velocities seen in non-orthonormal coordinates (DESIGN.md §3), and phi_1 itself
// is the uniform angle on that circle.
//
// With t the parametric angle, dL/dt = d_x sqrt(1 - k^2 cos^2 t), k^2 = 1 - q^2, so
//     L(t) / d_x = E(t - pi/2 | k) + E(k)                (incomplete elliptic integral, 2nd kind)
//     L(2 pi) / d_x = 4 E(k) = pi (1 + q) sum_n binom(1/2, n)^2 h^n,  h = ((1-q)/(1+q))^2
// (the series is the paper's). Three ways to invert, selectable (all deterministic: the
// same G gives the same psi in forward and reverse, which is all reversal needs):
//   simpson   the paper's: bisection on [0, 2 pi] starting at pi, L by adaptive Simpson
//             (Richardson-corrected, tolerance 1e-9 per step), stopping when the bracket is
//             below 1e-9 (the paper's "precision of 1e-9 in the computation of angles"; the
//             tolerance is a constructor argument, for measuring it: docs/tradeoff.md);
//             L(lower) is carried so each step integrates only the new half bracket.
//             Error <= 1e-9 (measured: 4e-10).
//   elliptic  GSL's incomplete elliptic integral of the second kind, in Carlson's form with
//             GSL's R_F and R_D (gsl_sf_ellint_E itself is wrong by up to 6e-9 near
//             amplitudes +-pi/2: see ellipse_arc.cpp), and safeguarded Newton (dL/dt >= q > 0). ~1e-15.
//   table     psi(G) tabulated once on first use (4096 cells by default, cubic Hermite with the exact
//             slope dpsi/dG = L(2 pi) / L'(psi)); nodes from the elliptic method. ~1e-13.
// Measured errors and times: docs/paper-findings.md and `revcol-bench --bench paper/arc`.
#pragma once
#include <cmath>
#include <memory>
#include <string>

#include "revcol/error.hpp"

namespace revcol::paper {

/// How psi = L^-1(G L(2 pi)) is computed.
enum class ArcMethod { simpson, elliptic, table };
/// Which angle psi is: the ellipse's parameter (default) or the polar angle of the point.
enum class ArcAngle { parametric, polar };

/// "simpson" / "elliptic" / "table".
const char* to_string(ArcMethod m);
/// "parametric" / "polar".
const char* to_string(ArcAngle a);
/// Parses an ArcMethod; throws InvalidArgument naming the allowed values.
ArcMethod parse_arc_method(const std::string& s);
/// Parses an ArcAngle; throws InvalidArgument naming the allowed values.
ArcAngle parse_arc_angle(const std::string& s);

/// The paper's aspect ratio d_y / d_x = 1 / sqrt(3) (3 particles, 1D).
inline constexpr double kPaperAspect = 0.57735026918962576450914878050195746;

/// Uniform arc-length sampling of an ellipse with aspect q = d_y / d_x (0 < q <= 1).
class EllipseArc {
 public:
  /// Default bracket width at which the paper's bisection stops (its angle precision).
  static constexpr double simpson_tolerance = 1e-9;
  /// Default cells of the table method.
  static constexpr int table_cells = 4096;

  /// A sampler; the table method exists for the paper's aspect only (its table is built
  /// once, on the first construction that asks for it). Throws InvalidArgument otherwise.
  explicit EllipseArc(ArcMethod method = ArcMethod::simpson,
                      ArcAngle angle = ArcAngle::parametric, double aspect = kPaperAspect);
  /// As above with the simpson method's tolerance (bracket width and Simpson tolerance per
  /// step, in [1e-14, 1e-2]) and the table method's cells (in [16, 2^20]; a table of other
  /// than table_cells cells is built for this sampler, the default one is shared). The
  /// defaults give the same bits as the constructor above. For measuring the knobs
  /// (`revcol-bench --bench tradeoff/arc`).
  EllipseArc(ArcMethod method, ArcAngle angle, double aspect, double tolerance, int cells);

  ArcMethod method() const { return method_; }  ///< the method
  ArcAngle angle() const { return angle_; }     ///< the angle convention
  double aspect() const { return q_; }          ///< q = d_y / d_x
  double tolerance() const { return tol_; }     ///< the simpson method's tolerance
  int cells() const { return cells_; }          ///< the table method's cells

  /// G-to-Psi: g in [0, 1] -> psi in [0, 2 pi] (the chosen angle of the point at arc
  /// length g L(2 pi)). Throws InvalidArgument unless 0 <= g <= 1.
  double psi(double g) const {
    require(g >= 0.0 && g <= 1.0, "random number must be in [0,1]");
    const double t = parametric(g);
    return angle_ == ArcAngle::parametric ? t : polar_of(t);
  }
  /// The parametric angle t of the point at arc length g L(2 pi), by the chosen method.
  double parametric(double g) const;

  /// L(t) / d_x by this sampler's method (simpson: adaptive Simpson; else GSL).
  double arc(double t) const;
  /// L(2 pi) / d_x: the paper's series (simpson) or 4 E(k) from GSL.
  double perimeter() const { return perimeter_; }
  /// dL/dt / d_x = sqrt(sin^2 t + q^2 cos^2 t) = sqrt(q^2 + k^2 sin^2 t).
  double speed(double t) const {
    const double s = std::sin(t);
    return std::sqrt(q_ * q_ + k_ * k_ * (s * s));
  }
  /// The polar angle in [0, 2 pi) of the point with parametric angle t.
  double polar_of(double t) const;

  /// High-precision reference for the parametric angle (long double Gauss-Legendre arc
  /// length and Newton's method; independent of GSL and of the table). Slow.
  static long double reference_parametric(long double g, long double aspect);

 private:
  struct Table;
  static const Table& paper_table();
  static std::shared_ptr<const Table> build_table(int cells);
  double simpson_parametric(double g) const;
  double elliptic_parametric(double g) const;
  double table_parametric(double g) const;
  double simpson_arc(double a, double b, double tol) const;
  double ellint_e(double phi) const;

  ArcMethod method_;
  ArcAngle angle_;
  double q_, k_;
  double perimeter_;
  double tol_ = simpson_tolerance;
  int cells_ = table_cells;
  const Table* table_ = nullptr;
  std::shared_ptr<const Table> own_table_;  // a table of other than table_cells cells
};

}  // namespace revcol::paper
