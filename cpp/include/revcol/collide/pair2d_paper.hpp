// Paper-mode collision of 2 particles in 2 dimensions: the paper's Procedures 1 and 2
// (Perumalla & Protopopescu 2013, §4.2).
//
// V-to-Phi: phi1 = atan2(v_iy - v_jy, v_ix - v_jx), the angle of the relative velocity (the
// paper's (a - alpha/2, c - beta/2) = w/2). Phi-to-V: a = alpha/2 + R cos phi1,
// b = alpha/2 - R cos phi1, c = beta/2 + R sin phi1, d = beta/2 - R sin phi1 with
// R = sqrt(2 delta - alpha^2 - beta^2) / 2. G-to-Psi: psi = 2 pi G.
// Procedure 1 (forward): phi1 = phi1' + psi (mod 2pi); if the post state approaches
// (r . (cos phi1, sin phi1) < 0) add pi.
// Procedure 2 (reverse): phi1' = phi1 - psi (mod 2pi); if the *candidate pre* state
// separates, subtract pi. The printed Procedure 2 tests the post angle phi1 instead, which
// for any valid post state always separates, so it would always subtract pi and fail
// whenever the forward step did not add it (about half the collisions). We test the
// candidate, as the paper's own proof (§4.2, "R_pi violates CS(phi1') < 0") requires;
// `printed_reverse = true` keeps the printed test so the failure can be measured.
// The output is uniform on the permitted half circle: phi1' + psi is uniform on the
// circle, and the pi fold maps it onto the half circle two-to-one.
#pragma once
#include <array>
#include <cmath>

#include "revcol/collide/common.hpp"
#include "revcol/collide/pair.hpp"

namespace revcol {

/// Paper-mode pair collision in 2D (Procedures 1 and 2), one random number per collision.
class Pair2DPaper {
 public:
  static constexpr int dim = 2;        ///< spatial dimension d
  static constexpr int particles = 2;  ///< particles n
  static constexpr int draws = 1;      ///< random numbers per collision

  /// printed_reverse = true reproduces the printed Procedure 2 (tests the post angle).
  explicit Pair2DPaper(bool printed_reverse = false) : printed_(printed_reverse) {}

  /// Whether this operator reproduces the printed (faulty) Procedure 2.
  bool printed_reverse() const { return printed_; }

  /// Procedure 1: pre -> post with g in [0,1]; held invariants optional. The log is part
  /// of the common operator signature; this operator never needs it.
  PairV<2> forward(const PairV<2>& pre, const std::array<double, 2>& normal, double g,
                   RareLog& /*log*/, const Invariants<2>* inv = nullptr) const {
    const Frame2 f(normal);
    const Parts s = parts(pre, f, inv, /*post=*/false, g);
    double phi = wrap(s.phi + kTwoPi * g);
    if (f.a[0] * std::cos(phi) + f.a[1] * std::sin(phi) < 0.0) phi = wrap(phi + kPi);
    return build(s, phi);
  }

  /// Procedure 2 (candidate test fixed): post -> pre with the g forward used.
  PairV<2> reverse(const PairV<2>& post, const std::array<double, 2>& normal, double g,
                   RareLog& /*log*/, const Invariants<2>* inv = nullptr) const {
    const Frame2 f(normal);
    const Parts s = parts(post, f, inv, /*post=*/true, g);
    double phi_pre = wrap(s.phi - kTwoPi * g);
    const double tested = printed_ ? s.phi : phi_pre;  // the fix: test the candidate
    if (f.a[0] * std::cos(tested) + f.a[1] * std::sin(tested) > 0.0)
      phi_pre = wrap(phi_pre - kPi);
    return build(s, phi_pre);
  }

  /// Throws InvalidArgument unless `pre` is a valid pre-collision state.
  void check_pre(const PairV<2>& pre, const std::array<double, 2>& normal,
                 const Invariants<2>* inv = nullptr) const {
    parts(pre, Frame2(normal), inv, false, 0.5);
  }
  /// Throws InvalidArgument unless `post` is a valid post-collision state.
  void check_post(const PairV<2>& post, const std::array<double, 2>& normal,
                  const Invariants<2>* inv = nullptr) const {
    parts(post, Frame2(normal), inv, true, 0.5);
  }
  /// Whether reversing `post` pops the log: never in this operator.
  bool logs(const PairV<2>&, const std::array<double, 2>&) const { return false; }

  /// V-to-Phi: the angle of the relative velocity in [0, 2pi).
  static double angle(const PairV<2>& v) {
    return wrap(std::atan2(v.i[1] - v.j[1], v.i[0] - v.j[0]));
  }

 private:
  static constexpr double kPi = 3.141592653589793238462643383279502884;
  static constexpr double kTwoPi = 2.0 * kPi;

  struct Parts {
    double phi;    // V-to-Phi of the input
    double R;      // radius of the circle (|w| / 2)
    double cm[2];  // alpha/2, beta/2
  };

  static double wrap(double x) {
    double r = std::fmod(x, kTwoPi);
    if (r < 0.0) r += kTwoPi;
    if (r >= kTwoPi) r -= kTwoPi;  // fmod of a tiny negative plus 2pi can round to 2pi
    return r;
  }

  Parts parts(const PairV<2>& v, const Frame2& f, const Invariants<2>* inv, bool post,
              double g) const {
    require_finite(v);
    require(g >= 0.0 && g <= 1.0, "random number must be in [0,1]");
    const std::array<double, 2> w = relative(v);
    require_speed_range(v, w);
    const double norm = std::sqrt(w[0] * w[0] + w[1] * w[1]);
    const double p = f.normal_part(w);
    if (post)
      require(p > 0.0, [&] { return std::string("post-collision state does not separate along the contact normal "
                       "(normal relative velocity " + std::to_string(p) + " <= 0)"); });
    else
      require(p < 0.0, [&] { return std::string("pre-collision state is not approaching along the contact normal "
                       "(normal relative velocity " + std::to_string(p) + " >= 0)"); });
    Parts s;
    s.phi = wrap(std::atan2(w[1], w[0]));
    if (inv) {
      s.R = 0.5 * checked_relative_speed(*inv, norm);
      s.cm[0] = 0.5 * inv->momentum[0];
      s.cm[1] = 0.5 * inv->momentum[1];
    } else {
      s.R = 0.5 * norm;
      s.cm[0] = 0.5 * (v.i[0] + v.j[0]);
      s.cm[1] = 0.5 * (v.i[1] + v.j[1]);
    }
    return s;
  }

  static PairV<2> build(const Parts& s, double phi) {
    const double hx = s.R * std::cos(phi), hy = s.R * std::sin(phi);
    PairV<2> out;
    out.i = {s.cm[0] + hx, s.cm[1] + hy};
    out.j = {s.cm[0] - hx, s.cm[1] - hy};
    return out;
  }

  bool printed_;
};

}  // namespace revcol
