// Paper-mode collision of 3 particles in 1 dimension (Perumalla & Protopopescu 2013, §4.4):
// Procedures 3 (forward) and 4 (reverse), one random number per collision.
//
// Canonical assignation (§4.4.4): a, b, c are the velocities of the left, centre and right
// particles (by position; ids do not matter in 1D). Dynamics: a + b + c = alpha,
// a^2 + b^2 + c^2 = delta. V-to-Phi / Phi-to-V (eq. 3sphere-1dim-geometry), lambda =
// sqrt2 sqrt(delta - alpha^2/3):
//     a = alpha/3 + lambda/2 (cos phi + sin phi / sqrt3),  b = alpha/3 + lambda/2 (-cos phi + sin phi / sqrt3),
//     c = alpha/3 - lambda/2 (2 / sqrt3) sin phi,
//     tan phi = sqrt3 (b-bar - sqrt2 alpha/3) / a-bar = ((a - c) + (b - c)) / sqrt6 / ((a - b) / sqrt2)
// (computed with atan2 and from differences, never from alpha: DESIGN.md §4). In the
// orthonormal Jacobi coordinates x = ((a-b)/sqrt2, (a+b-2c)/sqrt6) of the relative velocities,
// x = (lambda/sqrt2)(cos phi, sin phi): phi is the angle on a ROUND circle, so "uniform on the
// permitted arc" means uniform in phi. Then a - b = lambda cos phi, b - c = lambda cos(phi -
// 2pi/3), c - a = lambda cos(phi + 2pi/3). Pre (both contacts approach: a' > b' > c'):
// phi' in R1 = (pi/6, pi/2); post (a < b < c): phi in S1 = (7pi/6, 3pi/2). The six arcs
// R1, S3, R2, S1, R3, S2 of width pi/3 (the text says 2pi/3: a typo) tile the circle; in an
// R region two of the three cosines are positive, in an S region one.
// G-to-Psi: psi = L^-1(G L(2 pi)) by ellipse arc length (ellipse_arc.hpp: three methods).
// Procedure 3: phi = phi' + psi; Step 2: if more than one cosine is positive (R), + pi;
// Step 3a: if cos phi > 0, - 2pi/3; Step 3b: else if cos(phi - 2pi/3) > 0, + 2pi/3.
// Every step moves phi by a multiple of pi/3 and lands in S1, so the whole forward step is
// phi = 7pi/6 + ((phi' + psi - 7pi/6) mod pi/3): a rotation of an arc of length pi/3. It is
// a bijection R1 -> S1 for each psi, and uniform on S1 exactly when psi mod pi/3 is; the
// arc-length psi is not uniform, so the output is not quite (measured: docs/paper-findings.md).
// Procedure 4 (reverse) as printed, Step 2: "if more than one of cos phi1, cos(phi1 -
// 2pi/3), cos(phi1 + 2pi/3) is positive, phi1' -= pi". It tests the POST angle phi1, which is
// in S1 and never has two positive cosines, so the printed reverse never undoes Step 2 (it
// fails whenever the forward added pi, about half the collisions); and its condition is the
// forward's R test, while the text beside it says the candidate must be remapped when it
// falls in S1, S2 or S3. Fixed (default): test the CANDIDATE phi1' for an S region (more
// than one cosine negative). printed_reverse = true keeps the printed test, to measure it.
// Steps 3a/3b of the reverse are right as printed (cos phi1' < 0: - 2pi/3; else
// cos(phi1' - 2pi/3) < 0: + 2pi/3).
// Cosine tolerance (§5.1): "a tolerance of +-1e-8 around zero was employed when determining
// whether any given cosine value can be considered zero or positive": a cosine counts as
// positive when > cos_tol and negative when < -cos_tol. Inside the bands |cos| <= cos_tol
// (about 2e-8 of the circle) the forward can leave S1 by up to cos_tol: measured in the docs.
#pragma once
#include <array>
#include <cmath>
#include <string>

#include "revcol/collide/common.hpp"
#include "revcol/collide/ellipse_arc.hpp"
#include "revcol/collide/paper_common.hpp"

namespace revcol {

/// Paper-mode collision of 3 particles in 1D (Procedures 3 and 4), one random number.
class Triple1DPaper {
 public:
  static constexpr int dim = 1;        ///< spatial dimension d
  static constexpr int particles = 3;  ///< particles n
  static constexpr int draws = 1;      ///< random numbers per collision, d_n = nd - d - 1
  using State = paper::Triple<1>;          ///< velocities by particle id
  using Geometry = std::array<double, 3>;  ///< positions by particle id (their order matters)
  using Inv = Invariants<1>;               ///< held momentum and energy
  using Draws = std::array<double, 1>;     ///< G
  static constexpr double paper_cos_tol = 1e-8;  ///< the paper's cosine tolerance (§5.1)

  /// arc: how psi is computed; cos_tol: the cosine tolerance; printed_reverse: the printed
  /// Step 2 of Procedure 4; angle: which angle psi is (ellipse_arc.hpp).
  explicit Triple1DPaper(paper::ArcMethod arc = paper::ArcMethod::simpson,
                         double cos_tol = paper_cos_tol, bool printed_reverse = false,
                         paper::ArcAngle angle = paper::ArcAngle::parametric)
      : arc_(arc, angle), tol_(cos_tol), printed_(printed_reverse) {
    require(std::isfinite(cos_tol) && cos_tol >= 0.0 && cos_tol < 0.5,
            "cosine tolerance must be in [0, 0.5)");
  }

  const paper::EllipseArc& arc() const { return arc_; }  ///< the G-to-Psi sampler
  double cos_tol() const { return tol_; }                ///< the cosine tolerance
  bool printed_reverse() const { return printed_; }      ///< the printed reverse Step 2?

  /// Procedure 3: pre -> post with g in [0,1]. Throws InvalidArgument before changing anything.
  State forward(const State& pre, const Geometry& x, const Draws& g, RareLog& /*log*/,
                const Inv* inv = nullptr) const {
    const Parts s = parts(pre, x, inv, /*post=*/false, g);
    return build(s, forward_angle(s.phi, arc_.psi(g[0])));
  }

  /// Procedure 4 (Step 2 fixed unless printed_reverse): post -> pre with the g forward used.
  State reverse(const State& post, const Geometry& x, const Draws& g, RareLog& /*log*/,
                const Inv* inv = nullptr) const {
    const Parts s = parts(post, x, inv, /*post=*/true, g);
    return build(s, reverse_angle(s.phi, arc_.psi(g[0])));
  }

  /// Procedure 3 on the angles: phi' in R1 and psi -> phi in S1.
  double forward_angle(double phi_pre, double psi) const {
    double phi = paper::wrap(phi_pre + psi);                      // Step 1
    if (positives(phi) >= 2) phi = paper::wrap(phi + paper::kPi);  // Step 2: R -> S
    if (std::cos(phi) > tol_) phi = paper::wrap(phi - k2Pi3);       // Step 3a: S2 -> S1
    else if (std::cos(phi - k2Pi3) > tol_) phi = paper::wrap(phi + k2Pi3);  // Step 3b: S3 -> S1
    return phi;
  }
  /// Procedure 4 on the angles: phi in S1 and psi -> phi' in R1.
  double reverse_angle(double phi_post, double psi) const {
    double phi = paper::wrap(phi_post - psi);  // Step 1: the candidate
    // Step 2. Printed: tests the post angle with the forward's R test (never true on S1).
    // Fixed: the candidate in an S region (two cosines negative) goes back to R by -pi.
    const bool step2 = printed_ ? positives(phi_post) >= 2 : negatives(phi) >= 2;
    if (step2) phi = paper::wrap(phi - paper::kPi);
    if (std::cos(phi) < -tol_) phi = paper::wrap(phi - k2Pi3);               // Step 3a: R2 -> R1
    else if (std::cos(phi - k2Pi3) < -tol_) phi = paper::wrap(phi + k2Pi3);  // Step 3b: R3 -> R1
    return phi;
  }

  /// Throws InvalidArgument unless `pre` is a valid pre-collision state (a' > b' > c').
  void check_pre(const State& pre, const Geometry& x, const Inv* inv = nullptr) const {
    parts(pre, x, inv, false, Draws{0.5});
  }
  /// Throws InvalidArgument unless `post` is a valid post-collision state (a < b < c).
  void check_post(const State& post, const Geometry& x, const Inv* inv = nullptr) const {
    parts(post, x, inv, true, Draws{0.5});
  }
  /// Whether reversing `post` pops the log: never.
  bool logs(const State&, const Geometry&) const { return false; }

  /// V-to-Phi: phi in [0, 2 pi) of the velocities, with the particles ordered by position.
  static double angle(const State& v, const Geometry& x) {
    const Order o = order(x);
    return angle_of(v[o.l][0], v[o.c][0], v[o.r][0]);
  }

 private:
  static constexpr double k2Pi3 = 2.0 * paper::kPi / 3.0;
  static constexpr double kSqrt2 = 1.41421356237309504880168872420969808;
  static constexpr double kSqrt3 = 1.73205080756887729352744634150587237;
  static constexpr double kSqrt6 = 2.44948974278317809819728407470589139;

  struct Order { int l, c, r; };
  struct Parts {
    Order o;
    double phi;     // V-to-Phi of the input
    double lambda;  // sqrt2 |x|
    double mean;    // alpha / 3
  };

  int positives(double phi) const {
    return (std::cos(phi) > tol_) + (std::cos(phi - k2Pi3) > tol_) + (std::cos(phi + k2Pi3) > tol_);
  }
  int negatives(double phi) const {
    return (std::cos(phi) < -tol_) + (std::cos(phi - k2Pi3) < -tol_) + (std::cos(phi + k2Pi3) < -tol_);
  }

  static double angle_of(double a, double b, double c) {
    return paper::wrap(std::atan2(((a - c) + (b - c)) / kSqrt6, (a - b) / kSqrt2));
  }

  static Order order(const Geometry& x) {
    require(std::isfinite(x[0]) && std::isfinite(x[1]) && std::isfinite(x[2]),
            "positions must be finite");
    require(x[0] != x[1] && x[1] != x[2] && x[0] != x[2],
            "positions must be distinct (three particles in a row)");
    int l = 0, c = 1, r = 2;
    auto swap_if = [&](int& p, int& q) { if (x[p] > x[q]) std::swap(p, q); };
    swap_if(l, c);
    swap_if(c, r);
    swap_if(l, c);
    return {l, c, r};
  }

  Parts parts(const State& v, const Geometry& x, const Inv* inv, bool post, const Draws& g) const {
    paper::require_finite(v);
    paper::require_speed_range(v);
    require(g[0] >= 0.0 && g[0] <= 1.0, "random number must be in [0,1]");
    Parts s;
    s.o = order(x);
    const double a = v[s.o.l][0], b = v[s.o.c][0], c = v[s.o.r][0];
    const double ab = a - b, bc = b - c;
    if (post)
      require(ab < 0.0 && bc < 0.0, [&] {
        return "post-collision state does not separate at both contacts (left - centre " +
               std::to_string(ab) + ", centre - right " + std::to_string(bc) + "; both must be < 0)";
      });
    else
      require(ab > 0.0 && bc > 0.0, [&] {
        return "pre-collision state is not approaching at both contacts (left - centre " +
               std::to_string(ab) + ", centre - right " + std::to_string(bc) + "; both must be > 0)";
      });
    const double x1 = ab / kSqrt2, x2 = ((a - c) + bc) / kSqrt6;
    const double rho = std::hypot(x1, x2);
    require(std::isfinite(rho), "velocities too large (relative speed overflows)");
    s.phi = paper::wrap(std::atan2(x2, x1));
    if (inv) {
      s.lambda = kSqrt2 * paper::checked_radius(*inv, rho);
      s.mean = inv->momentum[0] / 3.0;
    } else {
      s.lambda = kSqrt2 * rho;
      s.mean = (a + b + c) / 3.0;
    }
    return s;
  }

  static State build(const Parts& s, double phi) {
    const double h = 0.5 * s.lambda, cp = std::cos(phi), sp = std::sin(phi) / kSqrt3;
    State out;
    out[s.o.l][0] = s.mean + h * (cp + sp);
    out[s.o.c][0] = s.mean + h * (-cp + sp);
    out[s.o.r][0] = s.mean - h * (2.0 * sp);
    return out;
  }

  paper::EllipseArc arc_;
  double tol_;
  bool printed_;
};

}  // namespace revcol
