// Paper-mode collision of 2 particles in 3 dimensions (Perumalla & Protopopescu 2013, §4.3),
// as printed, with exactly d_n = 2 random numbers per collision (§4.6).
//
// V-to-Phi / Phi-to-V (eq. 2sphere-3dim-geometry): the point (a, c, e) = v_i lies on the
// sphere of radius R = |v_i - v_j| / 2 about the centre-of-mass velocity M/2,
//     v_i = M/2 + R (sin phi1 sin phi2, sin phi1 cos phi2, cos phi1),   v_j = M - v_i,
// phi1 in [0, pi] (polar angle from +z), phi2 in [0, 2 pi) (azimuth from +y towards +x);
// phi2 = 0 at the poles (phi1 = 0 or pi), as the paper sets it.
// G-to-Psi: (psi1, psi2) are the angles of a uniform point on the unit sphere, from two
// numbers by the inverse CDF (Marsaglia's method, which the paper cites, rejects, and a
// variable count of draws cannot be reversed, §4.6): psi1 = acos(1 - 2 G1), psi2 = 2 pi G2.
// Forward: phi1 = phi1' + psi1 (mod 2 pi), phi2 = phi2' + psi2 (mod 2 pi); if the post state
// approaches (CS(phi) = n . (sin phi1 sin phi2, sin phi1 cos phi2, cos phi1) < 0), phi1 += pi,
// which maps the point to its antipode. G2 is drawn and used even when phi1 lands on a pole
// (where phi2 does not matter): the count is 2, unconditionally.
// Reverse: (phi1, phi2) = V-to-Phi(post); phi1' = phi1 - psi1, phi2' = phi2 - psi2; if the
// candidate separates, phi1' -= pi (the analogue of Procedure 2 with its typo fixed: test the
// candidate; printed_reverse = true tests the post angle, as printed Procedure 2 does).
// Log: the paper logs phi2' "only if phi1 = 0". We decide it on the post velocities (push
// when V-to-Phi of the post state gives phi1 == 0 exactly), so forward and reverse agree bit
// for bit; phi1 = pi, which loses phi2 just the same, is not logged, as printed.
//
// NOT INVERTIBLE as printed (measured in docs/paper-findings.md): phi1' + psi1 (+ pi) is
// taken mod 2 pi, so the forward phi1 lands in (pi, 2 pi) about half the time, while V-to-Phi
// returns phi1 in [0, pi]: the reverse then sees the same point written as
// (2 pi - phi1, phi2 + pi), and subtracting (psi1, psi2) from that gives another pre state.
// No test on the post state alone can tell the two writings apart. NOT UNIFORM either: adding
// a uniform point's angles to phi' is not a rotation of the sphere, so the post law depends on
// the pre state.
#pragma once
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <string>

#include "revcol/collide/common.hpp"
#include "revcol/collide/pair.hpp"

namespace revcol {

/// Paper-mode pair collision in 3D (§4.3 as printed), two random numbers per collision.
class Pair3DPaper {
 public:
  static constexpr int dim = 3;        ///< spatial dimension d
  static constexpr int particles = 2;  ///< particles n
  static constexpr int draws = 2;      ///< random numbers per collision, d_n = nd - d - 1
  using State = PairV<3>;                  ///< velocities (i, j)
  using Geometry = std::array<double, 3>;  ///< contact normal, from j to i
  using Inv = Invariants<3>;               ///< held momentum and energy
  using Draws = std::array<double, 2>;     ///< (G1, G2)

  /// printed_reverse = true tests the post angle in the reverse (as printed Procedure 2).
  explicit Pair3DPaper(bool printed_reverse = false) : printed_(printed_reverse) {}

  /// Whether the reverse reproduces the printed (faulty) test.
  bool printed_reverse() const { return printed_; }

  /// §4.3 forward: pre -> post with g in [0,1]^2; pushes phi2' when the post is at phi1 = 0.
  PairV<3> forward(const PairV<3>& pre, const Geometry& normal, const Draws& g, RareLog& log,
                   const Inv* inv = nullptr) const {
    const Unit n = unit(normal);
    const Parts s = parts(pre, n, inv, /*post=*/false, g);
    double phi1 = wrap(s.phi1 + psi1(g[0]));
    const double phi2 = wrap(s.phi2 + psi2(g[1]));
    if (cs(n, phi1, phi2) < 0.0) phi1 = wrap(phi1 + kPi);
    const PairV<3> post = build(s, phi1, phi2);
    if (at_pole(post)) log.push(std::bit_cast<std::uint64_t>(s.phi2));
    return post;
  }

  /// §4.3 reverse (candidate test): post -> pre with the g forward used; pops at the pole.
  PairV<3> reverse(const PairV<3>& post, const Geometry& normal, const Draws& g, RareLog& log,
                   const Inv* inv = nullptr) const {
    const Unit n = unit(normal);
    const Parts s = parts(post, n, inv, /*post=*/true, g);
    double phi1 = wrap(s.phi1 - psi1(g[0]));
    const double phi2 = at_pole(post) ? std::bit_cast<double>(log.pop()) : wrap(s.phi2 - psi2(g[1]));
    const bool flip = printed_ ? cs(n, s.phi1, s.phi2) > 0.0 : cs(n, phi1, phi2) > 0.0;
    if (flip) phi1 = wrap(phi1 - kPi);
    return build(s, phi1, phi2);
  }

  /// Throws InvalidArgument unless `pre` is a valid pre-collision state.
  void check_pre(const PairV<3>& pre, const Geometry& normal, const Inv* inv = nullptr) const {
    parts(pre, unit(normal), inv, false, Draws{0.5, 0.5});
  }
  /// Throws InvalidArgument unless `post` is a valid post-collision state.
  void check_post(const PairV<3>& post, const Geometry& normal, const Inv* inv = nullptr) const {
    parts(post, unit(normal), inv, true, Draws{0.5, 0.5});
  }
  /// Whether reversing `post` pops the log (V-to-Phi gives phi1 == 0).
  bool logs(const PairV<3>& post, const Geometry&) const { return at_pole(post); }

  /// V-to-Phi: (phi1 in [0, pi], phi2 in [0, 2 pi)) of the relative velocity v_i - v_j.
  static std::array<double, 2> angles(const PairV<3>& v) {
    const std::array<double, 3> w = relative(v);
    return {std::atan2(std::hypot(w[0], w[1]), w[2]),
            (w[0] == 0.0 && w[1] == 0.0) ? 0.0 : wrap(std::atan2(w[0], w[1]))};
  }
  /// G-to-Psi: psi1 = acos(1 - 2 G1) in [0, pi] (polar angle of a uniform point).
  static double psi1(double g1) { return std::acos(1.0 - 2.0 * g1); }
  /// G-to-Psi: psi2 = 2 pi G2 (its azimuth).
  static double psi2(double g2) { return kTwoPi * g2; }

 private:
  static constexpr double kPi = 3.141592653589793238462643383279502884;
  static constexpr double kTwoPi = 2.0 * kPi;

  struct Unit { double a[3]; };
  struct Parts {
    double phi1, phi2;  // V-to-Phi of the input
    double R;           // sphere radius |w| / 2
    double cm[3];       // M / 2
  };

  static double wrap(double x) {
    double r = std::fmod(x, kTwoPi);
    if (r < 0.0) r += kTwoPi;
    if (r >= kTwoPi) r -= kTwoPi;
    return r;
  }
  static Unit unit(const Geometry& n) {
    require(std::isfinite(n[0]) && std::isfinite(n[1]) && std::isfinite(n[2]),
            "contact normal must be finite");
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    require(len > 0.0, "contact normal is zero");
    return {{n[0] / len, n[1] / len, n[2] / len}};
  }
  // CS(phi): the normal relative velocity of the point (phi1, phi2), over 2R.
  static double cs(const Unit& n, double phi1, double phi2) {
    const double s1 = std::sin(phi1);
    return n.a[0] * s1 * std::sin(phi2) + n.a[1] * s1 * std::cos(phi2) + n.a[2] * std::cos(phi1);
  }
  static bool at_pole(const PairV<3>& post) {
    const std::array<double, 3> w = relative(post);
    return w[0] == 0.0 && w[1] == 0.0 && w[2] > 0.0;  // V-to-Phi gives phi1 == 0
  }

  Parts parts(const PairV<3>& v, const Unit& n, const Inv* inv, bool post, const Draws& g) const {
    require_finite(v);
    require(g[0] >= 0.0 && g[0] <= 1.0 && g[1] >= 0.0 && g[1] <= 1.0,
            "random numbers must be in [0,1]");
    const std::array<double, 3> w = relative(v);
    require_speed_range(v, w);
    const double norm = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    const double p = n.a[0] * w[0] + n.a[1] * w[1] + n.a[2] * w[2];
    if (post)
      require(p > 0.0, [&] { return std::string("post-collision state does not separate along the contact normal "
                       "(normal relative velocity " + std::to_string(p) + " <= 0)"); });
    else
      require(p < 0.0, [&] { return std::string("pre-collision state is not approaching along the contact normal "
                       "(normal relative velocity " + std::to_string(p) + " >= 0)"); });
    Parts s;
    const std::array<double, 2> phi = angles(v);
    s.phi1 = phi[0];
    s.phi2 = phi[1];
    if (inv) {
      s.R = 0.5 * checked_relative_speed(*inv, norm);
      for (int k = 0; k < 3; ++k) s.cm[k] = 0.5 * inv->momentum[k];
    } else {
      s.R = 0.5 * norm;
      for (int k = 0; k < 3; ++k) s.cm[k] = 0.5 * (v.i[k] + v.j[k]);
    }
    return s;
  }

  static PairV<3> build(const Parts& s, double phi1, double phi2) {
    const double s1 = std::sin(phi1);
    const double h[3] = {s.R * s1 * std::sin(phi2), s.R * s1 * std::cos(phi2), s.R * std::cos(phi1)};
    PairV<3> out;
    for (int k = 0; k < 3; ++k) {
      out.i[k] = s.cm[k] + h[k];
      out.j[k] = s.cm[k] - h[k];
    }
    return out;
  }

  bool printed_;
};

}  // namespace revcol
