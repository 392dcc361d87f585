// Paper-mode collision of 3 particles in 2 dimensions (Perumalla & Protopopescu 2013, §4.5):
// canonical configurations C1-C4 reached by rotation, hyper-ellipsoid sampling (Procedure 5,
// calotte.hpp), Procedures 6 and 7, exactly d_n = 3 random numbers per collision.
//
// Canonical configuration (§4.5.1), from the positions alone. The horizontal pair is "the
// two particles whose identifiers are smaller than that of the third", the smaller id P1 on
// the left, P2 on the right. When those two do not touch (a chain whose middle particle has
// the largest id, a case the paper does not cover) we take the contact pair with the smallest
// ids, which is the paper's pair whenever the paper's pair touches. C1/C2: all three touch,
// P3 on one side or the other; C3: P3 touches P2 only; C4: P3 touches P1 only.
// Orientation. The printed contact vectors of C1 (r21 = (D, 0), r32 = (-D/2, sqrt3 D/2),
// r13 = (-D/2, -sqrt3 D/2)) follow §2's convention (r_ji from j to i, post constraint
// r_ji.(V_i - V_j) > 0, which is separation) only if the x axis points from P2 to P1: the
// paper's picture (P1 left, P2 right, P3 above) with both axes reversed. We use that frame,
// x = (x_P1 - x_P2)/D and y = x rotated by +90 degrees, so that every printed range is
// physically right: post phi1 in [0, pi/2) is a - b > 0, P1 and P2 separating. (With x from
// P1 to P2, as the picture suggests, every printed "post" range would be an approaching one.)
// C1 is then P3 on the -y side, i.e. above in the paper's picture. C2 by symmetry: no rotation
// maps C2 onto C1 with the ids fixed, so C2 is C1 seen in a mirror, y -> -y (the frame matrix
// has det -1). C3: theta = angle of x_P3 - x_P2 in the frame, in (pi/3, 5 pi/3), contact
// normal r32 = -(cos theta, sin theta) as printed; C4: theta = angle of x_P3 - x_P1, in
// (-2pi/3, 2pi/3), normal r13 = (cos theta, sin theta) ("K3 instead of K2"). Velocities are
// rotated into the frame with an Eigen matrix and rotated back after the collision.
//
// V-to-Phi / Phi-to-V (eq. 3sphere-2dim-ellipsoid-space): with P1 = (a, d), P2 = (b, e),
// P3 = (c, f) in the frame and x = ((a-b)/sqrt2, (d-e)/sqrt2, (a+b-2c)/sqrt6, (d+e-2f)/sqrt6)
// (orthonormal Jacobi coordinates; |x| = lambda/sqrt2),
//     x / |x| = (cos phi1, sin phi1 cos phi2, sin phi1 sin phi2 cos phi3, sin phi1 sin phi2 sin phi3):
// the phi's are the hyperspherical angles of a ROUND 3-sphere. We compute them with atan2
// (the printed phi3 = asin(...) cannot tell phi3 from pi - phi3: half of [0, 2pi) is lost);
// phi2 = phi3 = 0 at phi1 in {0, pi} and phi3 = 0 at phi2 in {0, pi}, as printed.
// Each contact (i, j) with unit normal n (from j to i) must separate after the collision,
// n.(V_i - V_j) > 0. K1 is cos phi1 > 0; any other contact reads
//     sqrt3 sin phi1 sin phi2 cos(phi3 - c) < p cos phi1 + q sin phi1 cos phi2
// (c, p, q from n: L1 and L2 of C1 and the gamma inequality of C3 are instances).
//
// Procedure 6 (forward), as printed:
//   phi1 = (phi1' - pi/2 + psi1) mod pi/2
//   phi2 = (phi2' + psi2) mod pi;  if phi2 < phi2l or phi2u < phi2: phi2 = (phi2 + phi2l + pi - phi2u) mod pi
//   phi3 = (phi3' + psi3) mod 2pi; if phi3 < phi3l: phi3 += phi3l; else if phi3 > phi3u: phi3 += 2pi - phi3u (mod 2pi)
// with the bounds of phi2 from phi1 and of phi3 from (phi1, phi2). Procedure 7 (reverse)
// undoes each line with the bounds recomputed from the post angles, testing the candidate.
// Bounds: C1 (and C2): phi2l, phi2u by the printed closed forms (r = cot phi1 / sqrt3); C3/C4:
// the printed conditions ("if mu - nu >= 0 or mu + nu <= 0, phi2 is unconstrained"; the upper
// bound from sin phi2 = mu + nu cos phi2) contradict the inequality they come from, so we
// compute the interval where gamma > -1 (mu + nu cos phi2 + sin phi2 > 0) exactly. phi3: the
// paper writes the permitted phi3 as one interval [phi3l, phi3u] inside [0, 2 pi); we take the
// smallest such interval containing every permitted phi3 (no restriction when the permitted
// set wraps through 0, which in C1 is most of the time: its excluded arcs are centred at
// 4pi/3 and 5pi/3).
//
// NOT A BIJECTION and NOT SOUND as printed (measured in docs/paper-findings.md): the folds of
// phi2 and phi3 map the excluded part onto part of the permitted part (two-to-one), the
// "phi3 > phi3u" fold lands below phi3l, the pre ranges of phi2' and phi3' are never used,
// and in C3/C4 part of phi1's range [0, pi/2) has no permitted (phi2, phi3) at all, so the
// forward step can produce a post state that does not separate. Kept as printed.
#pragma once
#include <array>
#include <cmath>
#include <string>

#include "revcol/eigen.hpp"

#include "revcol/collide/calotte.hpp"
#include "revcol/collide/common.hpp"
#include "revcol/collide/paper_common.hpp"

namespace revcol::paper {

/// The paper's canonical configurations of 3 disks in contact (§4.5.1).
enum class Config { c1, c2, c3, c4 };
/// "C1" .. "C4".
const char* to_string(Config c);

/// Positions of three disks by particle id (index 0 = the smallest id).
using Positions2 = std::array<std::array<double, 2>, 3>;

/// The canonical frame and constraints of a 3-disk contact, decided by the positions alone.
struct Canonical {
  Config config = Config::c1;     ///< which configuration
  std::array<int, 3> id{};        ///< the ids of P1, P2, P3
  Eigen::Matrix2d R;              ///< world -> frame: v_frame = R v (rows x, +-y; det -1 for C2)
  double theta = 0.0;             ///< C3: angle of P3 - P2; C4: angle of P3 - P1 (frame); else 0
  int contacts = 0;               ///< 2 or 3
  std::array<std::array<int, 2>, 3> role{};  ///< contact k is between roles (i, j), normal j -> i
  std::array<Eigen::Vector2d, 3> normal;     ///< unit normal of contact k in the frame
  std::array<double, 3> centre{}, p{}, q{};  ///< contact k >= 1: c, p, q of its phi3 inequality
};

/// The canonical frame of positions x: contacts are the pairs within (1 + tol) of the
/// smallest distance (the diameter); needs two or three. Throws InvalidArgument otherwise.
Canonical canonical(const Positions2& x, double tol = 1e-9);

}  // namespace revcol::paper

namespace revcol {

/// Paper-mode collision of 3 particles in 2D (§4.5, Procedures 5-7), three random numbers.
class Triple2DPaper {
 public:
  static constexpr int dim = 2;        ///< spatial dimension d
  static constexpr int particles = 3;  ///< particles n
  static constexpr int draws = 3;      ///< random numbers per collision, d_n = nd - d - 1
  using State = paper::Triple<2>;       ///< velocities by particle id
  using Geometry = paper::Positions2;   ///< positions by particle id
  using Inv = Invariants<2>;            ///< held momentum and energy (world frame)
  using Draws = std::array<double, 3>;  ///< (G1, G2, G3)
  using Angles = std::array<double, 3>; ///< (phi1, phi2, phi3)
  /// A closed interval [lo, hi].
  struct Bounds { double lo, hi; };

  /// Fetches the calotte tables (built on the first construction).
  Triple2DPaper() = default;

  /// Procedure 6: pre -> post with g in [0,1]^3 (the post may fail to separate: see above).
  State forward(const State& pre, const Geometry& x, const Draws& g, RareLog& /*log*/,
                const Inv* inv = nullptr) const {
    const paper::Canonical cf = paper::canonical(x);
    const Parts s = parts(pre, cf, inv, /*post=*/false, g);
    return build(cf, s, forward_angles(cf, s.phi, sampler_.psi(g)));
  }
  /// Procedure 7: post -> pre with the g forward used.
  State reverse(const State& post, const Geometry& x, const Draws& g, RareLog& /*log*/,
                const Inv* inv = nullptr) const {
    const paper::Canonical cf = paper::canonical(x);
    const Parts s = parts(post, cf, inv, /*post=*/true, g);
    return build(cf, s, reverse_angles(cf, s.phi, sampler_.psi(g)));
  }

  /// Procedure 6 on the angles.
  Angles forward_angles(const paper::Canonical& cf, const Angles& pre, const Draws& psi) const {
    using paper::kPi;
    Angles a;
    a[0] = paper::wrap(pre[0] - 0.5 * kPi + psi[0], 0.5 * kPi);
    a[1] = paper::wrap(pre[1] + psi[1], kPi);
    const Bounds b2 = bounds2(cf, a[0]);
    if (a[1] < b2.lo || b2.hi < a[1]) a[1] = paper::wrap(a[1] + (b2.lo + kPi - b2.hi), kPi);
    const Bounds b3 = bounds3(cf, a[0], a[1]);
    a[2] = paper::wrap(pre[2] + psi[2]);
    if (a[2] < b3.lo) a[2] = paper::wrap(a[2] + b3.lo);
    else if (a[2] > b3.hi) a[2] = paper::wrap(a[2] + (paper::kTwoPi - b3.hi));
    return a;
  }
  /// Procedure 7 on the angles (bounds recomputed from the post angles).
  Angles reverse_angles(const paper::Canonical& cf, const Angles& post, const Draws& psi) const {
    using paper::kPi;
    const Bounds b2 = bounds2(cf, post[0]);
    const Bounds b3 = bounds3(cf, post[0], post[1]);
    Angles a;
    a[0] = 0.5 * kPi + paper::wrap(post[0] - psi[0], 0.5 * kPi);
    a[1] = paper::wrap(post[1] - psi[1], kPi);
    if (a[1] < b2.lo || b2.hi < a[1]) a[1] = paper::wrap(a[1] - (b2.lo + kPi - b2.hi), kPi);
    a[2] = paper::wrap(post[2] - psi[2]);
    if (a[2] < b3.lo) a[2] = paper::wrap(a[2] - b3.lo);
    else if (a[2] > b3.hi) a[2] = paper::wrap(a[2] - (paper::kTwoPi - b3.hi));
    return a;
  }

  /// Bounds of the post phi2 given phi1 ([0, 0] at phi1 = 0; [0, pi] when none is permitted).
  static Bounds bounds2(const paper::Canonical& cf, double phi1);
  /// Bounds of the post phi3 given (phi1, phi2): the smallest interval of [0, 2 pi) holding
  /// every permitted phi3 ([0, 0] at a pole; [0, 2 pi] when none or all are permitted).
  static Bounds bounds3(const paper::Canonical& cf, double phi1, double phi2);

  /// Throws InvalidArgument unless `pre` approaches at every contact.
  void check_pre(const State& pre, const Geometry& x, const Inv* inv = nullptr) const {
    parts(pre, paper::canonical(x), inv, false, Draws{0.5, 0.5, 0.5});
  }
  /// Throws InvalidArgument unless `post` separates at every contact.
  void check_post(const State& post, const Geometry& x, const Inv* inv = nullptr) const {
    parts(post, paper::canonical(x), inv, true, Draws{0.5, 0.5, 0.5});
  }
  /// Whether reversing `post` pops the log: never.
  bool logs(const State&, const Geometry&) const { return false; }

  /// V-to-Phi in the canonical frame: (phi1 in [0, pi], phi2 in [0, pi], phi3 in [0, 2 pi)).
  static Angles angles(const State& v, const Geometry& x) {
    const paper::Canonical cf = paper::canonical(x);
    return angles_of(jacobi(frame_velocities(cf, v)));
  }
  /// Normal relative velocities n_k.(V_i - V_j) of each contact (all > 0: separating).
  static std::array<double, 3> normal_speeds(const State& v, const paper::Canonical& cf);
  /// The sampler of Procedure 5.
  const paper::HyperEllipsoidSampler& sampler() const { return sampler_; }

 private:
  static constexpr double kSqrt2 = 1.41421356237309504880168872420969808;
  static constexpr double kSqrt6 = 2.44948974278317809819728407470589139;

  using Frame3 = std::array<Eigen::Vector2d, 3>;  // velocities of P1, P2, P3 in the frame
  struct Parts {
    Angles phi;            // V-to-Phi of the input
    double rho;            // |x|
    Eigen::Vector2d mean;  // M / 3 in the frame
  };

  static Frame3 frame_velocities(const paper::Canonical& cf, const State& v) {
    Frame3 f;
    for (int r = 0; r < 3; ++r) f[r] = cf.R * Eigen::Vector2d(v[cf.id[r]][0], v[cf.id[r]][1]);
    return f;
  }
  static Eigen::Vector4d jacobi(const Frame3& f) {
    return {(f[0].x() - f[1].x()) / kSqrt2, (f[0].y() - f[1].y()) / kSqrt2,
            ((f[0].x() - f[2].x()) + (f[1].x() - f[2].x())) / kSqrt6,
            ((f[0].y() - f[2].y()) + (f[1].y() - f[2].y())) / kSqrt6};
  }
  static Angles angles_of(const Eigen::Vector4d& x) {
    const double r34 = std::hypot(x[2], x[3]);
    const double r234 = std::hypot(x[1], r34);
    Angles a;
    a[0] = std::atan2(r234, x[0]);
    a[1] = r234 == 0.0 ? 0.0 : std::atan2(r34, x[1]);
    a[2] = (r234 == 0.0 || r34 == 0.0) ? 0.0 : paper::wrap(std::atan2(x[3], x[2]));
    return a;
  }

  Parts parts(const State& v, const paper::Canonical& cf, const Inv* inv, bool post,
              const Draws& g) const;
  static State build(const paper::Canonical& cf, const Parts& s, const Angles& phi);

  paper::HyperEllipsoidSampler sampler_;
};

}  // namespace revcol
