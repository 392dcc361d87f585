// The paper's 3-particle 2D operator: canonical frames and the bounds of Procedures 6/7
// (see triple2d_paper.hpp for the maths and the choices made where the text is ambiguous).
#include "revcol/collide/triple2d_paper.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace revcol::paper {
namespace {

constexpr double kSqrt3 = 1.73205080756887729352744634150587237;

double dist(const Positions2& x, int i, int j) {
  return std::hypot(x[i][0] - x[j][0], x[i][1] - x[j][1]);
}

// Contact k between roles (i, j) with unit normal n (from j to i) separates iff
//   sqrt3 s1 s2 cos(phi3 - c) < p c1 + q s1 c2   (derivation in the header):
// (P2, P3):  c = angle(-n), (p, q) = -n;      (P3, P1):  c = angle(n), (p, q) = -n.
void set_phi3_form(Canonical& cf, int k) {
  const Eigen::Vector2d& n = cf.normal[k];
  const bool p2p3 = cf.role[k][0] == 1;  // (P2, P3) or (P3, P1)
  cf.centre[k] = wrap(p2p3 ? std::atan2(-n.y(), -n.x()) : std::atan2(n.y(), n.x()));
  cf.p[k] = -n.x();
  cf.q[k] = -n.y();
}

}  // namespace

const char* to_string(Config c) {
  switch (c) {
    case Config::c1: return "C1";
    case Config::c2: return "C2";
    case Config::c3: return "C3";
    case Config::c4: return "C4";
  }
  return "?";
}

Canonical canonical(const Positions2& x, double tol) {
  for (const auto& p : x)
    require(std::isfinite(p[0]) && std::isfinite(p[1]), "positions must be finite");
  const double d01 = dist(x, 0, 1), d12 = dist(x, 1, 2), d02 = dist(x, 0, 2);
  const double dmin = std::min({d01, d12, d02});
  require(dmin > 0.0, "positions must be distinct");
  const double lim = dmin * (1.0 + tol);
  const bool c01 = d01 <= lim, c12 = d12 <= lim, c02 = d02 <= lim;
  require(c01 + c12 + c02 >= 2, [&] {
    return "three disks in a collision need at least two contacts at one common distance "
           "(distances " + std::to_string(d01) + ", " + std::to_string(d12) + ", " +
           std::to_string(d02) + " for pairs (0,1), (1,2), (0,2))";
  });
  Canonical cf;
  // the horizontal pair: the contact pair with the smallest ids, P1 = its smaller id
  if (c01) cf.id = {0, 1, 2};
  else cf.id = {0, 2, 1};  // (0,1) apart: the contacts are (0,2) and (1,2)
  const auto& X1 = x[cf.id[0]];
  const auto& X2 = x[cf.id[1]];
  const auto& X3 = x[cf.id[2]];
  const double D = dist(x, cf.id[0], cf.id[1]);
  const Eigen::Vector2d ex((X1[0] - X2[0]) / D, (X1[1] - X2[1]) / D);  // from P2 to P1
  const Eigen::Vector2d ey(-ex.y(), ex.x());
  const Eigen::Vector2d r23(X3[0] - X2[0], X3[1] - X2[1]);  // P3 - P2 (world)
  const bool p3p2 = dist(x, cf.id[2], cf.id[1]) <= lim, p3p1 = dist(x, cf.id[2], cf.id[0]) <= lim;
  cf.role[0] = {0, 1};
  cf.normal[0] = Eigen::Vector2d(1.0, 0.0);
  double side = 1.0;
  if (p3p2 && p3p1) {
    // C1: P3 on the -y side; C2 (+y) is C1 in a mirror, y -> -y
    cf.config = ey.dot(r23) < 0.0 ? Config::c1 : Config::c2;
    side = cf.config == Config::c1 ? 1.0 : -1.0;
    cf.contacts = 3;
    cf.role[1] = {1, 2};
    cf.normal[1] = Eigen::Vector2d(-0.5, 0.5 * kSqrt3);  // r32, from P3 to P2
    cf.role[2] = {2, 0};
    cf.normal[2] = Eigen::Vector2d(-0.5, -0.5 * kSqrt3);  // r13, from P1 to P3
  } else if (p3p2) {
    cf.config = Config::c3;
    cf.contacts = 2;
    cf.theta = wrap(std::atan2(ey.dot(r23), ex.dot(r23)));
    require(cf.theta > kPi / 3.0 && cf.theta < 5.0 * kPi / 3.0,
            "C3 needs P3 at an angle in (pi/3, 5pi/3) from P2");
    cf.role[1] = {1, 2};
    cf.normal[1] = Eigen::Vector2d(-std::cos(cf.theta), -std::sin(cf.theta));  // r32
  } else {
    cf.config = Config::c4;
    cf.contacts = 2;
    const Eigen::Vector2d r13(X3[0] - X1[0], X3[1] - X1[1]);
    cf.theta = std::atan2(ey.dot(r13), ex.dot(r13));
    require(std::fabs(cf.theta) < 2.0 * kPi / 3.0,
            "C4 needs P3 at an angle in (-2pi/3, 2pi/3) from P1");
    cf.role[1] = {2, 0};
    cf.normal[1] = Eigen::Vector2d(std::cos(cf.theta), std::sin(cf.theta));  // r13
  }
  cf.R << ex.x(), ex.y(), side * ey.x(), side * ey.y();
  for (int k = 1; k < cf.contacts; ++k) set_phi3_form(cf, k);
  return cf;
}

}  // namespace revcol::paper

namespace revcol {

using paper::kPi;
using paper::kTwoPi;
namespace {
constexpr double kSqrt3 = 1.73205080756887729352744634150587237;
}  // namespace

Triple2DPaper::Bounds Triple2DPaper::bounds2(const paper::Canonical& cf, double phi1) {
  const double s1 = std::sin(phi1), c1 = std::cos(phi1);
  if (phi1 == 0.0 || s1 == 0.0) return {0.0, 0.0};  // the paper's [0, 0] at phi1 = 0
  if (cf.contacts == 3) {
    // C1 (C2 in its mirror), the printed closed forms
    if (phi1 <= kPi / 6.0) return {0.0, kPi};
    const double r = c1 / (kSqrt3 * s1);  // cot(phi1) / sqrt3
    const double root = std::sqrt(5.0 - r * r);
    return {2.0 * std::atan((-2.0 + root) / (1.0 + r)), 2.0 * std::atan((2.0 + root) / (1.0 - r))};
  }
  // C3/C4: permitted phi2 where gamma > -1: mu + nu cos phi2 + sin phi2 > 0, a sinusoid
  // mu + R cos(phi2 - phi*) with R = sqrt(1 + nu^2), phi* = atan2(1, nu) in (0, pi).
  const double mu = cf.p[1] * c1 / (kSqrt3 * s1), nu = cf.q[1] / kSqrt3;
  const double R = std::hypot(1.0, nu), star = std::atan2(1.0, nu), c = -mu / R;
  if (c <= -1.0) return {0.0, kPi};  // all permitted
  if (c >= 1.0) return {0.0, kPi};   // none permitted: nothing to fold to
  const double w = std::acos(c);
  return {std::max(0.0, star - w), std::min(kPi, star + w)};
}

Triple2DPaper::Bounds Triple2DPaper::bounds3(const paper::Canonical& cf, double phi1, double phi2) {
  const double s1 = std::sin(phi1), c1 = std::cos(phi1), s2 = std::sin(phi2), c2 = std::cos(phi2);
  const double sigma = kSqrt3 * s1 * s2;
  if (phi1 == 0.0 || phi2 == 0.0 || phi2 == kPi || sigma == 0.0) return {0.0, 0.0};  // as printed
  // excluded arcs [start, start + width] (mod 2 pi), one per contact beyond K1
  double start[2], width[2];
  int arcs = 0;
  for (int k = 1; k < cf.contacts; ++k) {
    const double R = (cf.p[k] * c1 + cf.q[k] * s1 * c2) / sigma;
    if (R >= 1.0) continue;                     // this contact permits every phi3
    if (R <= -1.0) return {0.0, kTwoPi};        // none permitted: nothing to fold to
    const double w = std::acos(R);
    start[arcs] = paper::wrap(cf.centre[k] - w);
    width[arcs] = 2.0 * w;
    ++arcs;
  }
  auto inside = [&](double t, int a) { return paper::wrap(t - start[a]) <= width[a]; };
  bool zero_excluded = false;
  for (int a = 0; a < arcs; ++a) zero_excluded = zero_excluded || inside(0.0, a);
  if (!zero_excluded) return {0.0, kTwoPi};  // the permitted set wraps through 0 (or is all)
  // walk up from 0 and down from 2 pi through the excluded arcs that cover 0
  double lo = 0.0, hi = kTwoPi;
  for (int pass = 0; pass < 2 * arcs; ++pass) {
    for (int a = 0; a < arcs; ++a) {
      if (lo < kTwoPi && inside(lo, a)) lo += width[a] - paper::wrap(lo - start[a]);
      if (hi > 0.0 && inside(hi, a)) hi -= paper::wrap(hi - start[a]);
    }
  }
  if (!(lo < hi)) return {0.0, kTwoPi};  // the arcs cover the circle: none permitted
  return {lo, hi};
}

std::array<double, 3> Triple2DPaper::normal_speeds(const State& v, const paper::Canonical& cf) {
  const Frame3 f = frame_velocities(cf, v);
  std::array<double, 3> out{0.0, 0.0, 0.0};
  for (int k = 0; k < cf.contacts; ++k)
    out[k] = cf.normal[k].dot(f[cf.role[k][0]] - f[cf.role[k][1]]);
  return out;
}

Triple2DPaper::Parts Triple2DPaper::parts(const State& v, const paper::Canonical& cf,
                                          const Inv* inv, bool post, const Draws& g) const {
  paper::require_finite(v);
  paper::require_speed_range(v);
  require(g[0] >= 0.0 && g[0] <= 1.0 && g[1] >= 0.0 && g[1] <= 1.0 && g[2] >= 0.0 && g[2] <= 1.0,
          "random numbers must be in [0,1]");
  const Frame3 f = frame_velocities(cf, v);
  for (int k = 0; k < cf.contacts; ++k) {
    const double s = cf.normal[k].dot(f[cf.role[k][0]] - f[cf.role[k][1]]);
    const int i = cf.id[cf.role[k][0]], j = cf.id[cf.role[k][1]];
    if (post)
      require(s > 0.0, [&] {
        return "post-collision state does not separate at contact (" + std::to_string(i) + ", " +
               std::to_string(j) + ") (normal relative velocity " + std::to_string(s) + " <= 0)";
      });
    else
      require(s < 0.0, [&] {
        return "pre-collision state is not approaching at contact (" + std::to_string(i) + ", " +
               std::to_string(j) + ") (normal relative velocity " + std::to_string(s) + " >= 0)";
      });
  }
  const Eigen::Vector4d x = jacobi(f);
  const double rho = x.norm();
  require(std::isfinite(rho), "velocities too large (relative speed overflows)");
  require(rho > 0.0, "zero relative speed: the particles cannot collide");
  Parts s;
  s.phi = angles_of(x);
  if (inv) {
    s.rho = paper::checked_radius(*inv, rho);
    s.mean = cf.R * Eigen::Vector2d(inv->momentum[0], inv->momentum[1]) / 3.0;
  } else {
    s.rho = rho;
    s.mean = (f[0] + f[1] + f[2]) / 3.0;
  }
  return s;
}

Triple2DPaper::State Triple2DPaper::build(const paper::Canonical& cf, const Parts& s,
                                          const Angles& phi) {
  const double s1 = std::sin(phi[0]), s2 = std::sin(phi[1]);
  const Eigen::Vector4d x = s.rho * Eigen::Vector4d(std::cos(phi[0]), s1 * std::cos(phi[1]),
                                                    s1 * s2 * std::cos(phi[2]), s1 * s2 * std::sin(phi[2]));
  const Eigen::Vector2d d12(x[0] / kSqrt2, x[1] / kSqrt2), d3(x[2] / kSqrt6, x[3] / kSqrt6);
  const Frame3 f = {s.mean + d12 + d3, s.mean - d12 + d3, s.mean - 2.0 * d3};
  State out;
  for (int r = 0; r < 3; ++r) {
    const Eigen::Vector2d w = cf.R.transpose() * f[r];  // back to the world frame
    out[cf.id[r]] = {w.x(), w.y()};
  }
  return out;
}

}  // namespace revcol
