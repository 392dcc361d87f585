// Exact-mode collision of 2 particles in 3 dimensions: the fast path of the general exact
// operator (exact.hpp) for its "pair3d" geometry, without a QR per contact normal.
//
// Physics (DESIGN.md §3; the reference operator is pair2d_exact.hpp). Two unit masses: the
// centre-of-mass velocity M/2 and the relative speed |w| = |v_i - v_j| are conserved, the
// direction of w is free: a point on the sphere S^2 (D = 3, d_n = 2 draws). The unit contact
// normal a (from j to i) splits it: the pair separates iff a.w > 0 (P, a hemisphere: m = 1
// contact, f = 2 free dimensions) and approached iff a.w < 0 (-P). With a tangent frame
// (t1, t2) built from a alone, a point of P is
//     w = |w| (cos(eta) a + sin(eta) (cos(phi) t1 + sin(phi) t2)),  eta in [0, pi/2), phi in [0, 2 pi).
// The chart c = (c0, c1): P -> [0,1)^2 is measure-preserving for the chosen law (the general
// operator's QuarterLaw(A, 1) with A = 0 / 1, in closed form):
//   uniform (uniform area on the hemisphere):   c0 = 1 - cos(eta)
//   flux    (density ~ a.w = cos(eta)):          c0 = sin^2(eta)
//   both:                                        c1 = phi / (2 pi)
// Forward:  c' = chart(-w_pre), c = c' + g (mod 1 per coordinate), w_post = chart^-1(c).
// Reverse:  c = chart(w_post), c' = c - g, w_pre = -chart^-1(c'). A torus shift of a
// measure-preserving chart: the post state has the law exactly, whatever the pre state.
//
// The frame. t1 = e_k x a / |e_k x a| with e_k the coordinate axis least aligned with a
// (smallest |a_k|, the first one on ties), t2 = a x t1. No continuous tangent frame exists
// on the sphere of normals, so this one jumps where the two smallest |a_k| swap order (the
// switching surface: normals along an axis, or with two equal small components such as
// (1,1,1)). That is harmless here: forward and reverse receive the same normal, hence the
// same frame bit for bit; only the meaning of phi changes across the surface, and phi is
// uniform whatever its origin.
//
// Numerics (DESIGN.md §4). The coordinates are K-bit FixedPoint cells: integer shifts,
// decoding at cell centres. Small quantities are computed directly: sin^2(eta) = T/(p^2 + T)
// from the tangential part T = q1^2 + q2^2 and the normal part p (never 1 - cos^2), and
// 1 - cos(eta) = T / (N (N + p)) with N = sqrt(p^2 + T); decoding takes 1 - c0 exactly (c0
// is a cell centre) and sin(eta) = sqrt(c0 (2 - c0)) (uniform) or sqrt(c0) (flux).
// The rare log: phi cannot be recovered near the pole eta = 0 (a tangential error delta
// turns phi by delta / |w_t|), and no coordinate can when the centre of mass is fast next to
// |w|. needs_log() bounds each coordinate's recovery error from the post velocities alone
// (recovery_bound(), its derivation in the comment there) and logs when twice the bound
// reaches a quarter cell; forward pushes both pre cells, reverse pops them. At the grazing
// edge eta -> pi/2 nothing is singular (dc0/deta <= 1), and an unlogged post state is
// guaranteed to separate (its normal part exceeds the bounded error).
#pragma once
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "revcol/collide/common.hpp"
#include "revcol/collide/pair.hpp"
#include "revcol/double_double.hpp"
#include "revcol/fixed_point.hpp"
#include "revcol/trig.hpp"

namespace revcol {

/// Exact-mode pair collision in 3D: closed-form chart + K-bit torus shift, flux or uniform law.
class Pair3DExact {
 public:
  static constexpr int dim = 3;        ///< spatial dimension d
  static constexpr int particles = 2;  ///< particles n
  static constexpr int draws = 2;      ///< random numbers per collision, d_n = nd - d - 1

  /// The contact frame (a, t1, t2) in 3D, decided by the normal alone (see the header comment).
  struct Frame {
    double a[3];   ///< unit normal, from j to i
    double t1[3];  ///< unit tangent: e_axis x a, normalized
    double t2[3];  ///< a x t1
    int axis;      ///< the coordinate axis t1 is built from (smallest |a_k|, first on ties)

    /// Builds the frame from any non-zero finite normal; throws InvalidArgument otherwise.
    [[gnu::always_inline]] explicit Frame(const std::array<double, 3>& normal) {
      double x0 = normal[0], x1 = normal[1], x2 = normal[2];
      double s2 = x0 * x0 + x1 * x1 + x2 * x2;
      if (!(s2 >= 0x1.0p-900 && s2 <= 0x1.0p+900)) [[unlikely]] {
        // tiny, huge or non-finite normals (an s2 in the range proves all three finite):
        // rescale by the largest component first (cold path)
        require(std::isfinite(x0) && std::isfinite(x1) && std::isfinite(x2),
                "contact normal must be finite");
        const double m = std::fmax(std::fabs(x0), std::fmax(std::fabs(x1), std::fabs(x2)));
        require(m > 0.0, "contact normal is zero");
        x0 /= m;
        x1 /= m;
        x2 /= m;
        s2 = x0 * x0 + x1 * x1 + x2 * x2;
      }
      // one square root and one reciprocal per unit vector: two divisions instead of six
      const double rl = 1.0 / std::sqrt(s2);
      a[0] = x0 * rl;
      a[1] = x1 * rl;
      a[2] = x2 * rl;
      const double b0 = std::fabs(a[0]), b1 = std::fabs(a[1]), b2 = std::fabs(a[2]);
      axis = (b0 <= b1 && b0 <= b2) ? 0 : (b1 <= b2 ? 1 : 2);
      // e_axis x a has the other two components of a, swapped, one negated; its length is
      // sqrt(1 - a_axis^2) >= sqrt(2/3), so nothing cancels
      if (axis == 0) {
        const double r = 1.0 / std::sqrt(a[1] * a[1] + a[2] * a[2]);
        t1[0] = 0.0; t1[1] = -a[2] * r; t1[2] = a[1] * r;
      } else if (axis == 1) {
        const double r = 1.0 / std::sqrt(a[0] * a[0] + a[2] * a[2]);
        t1[0] = a[2] * r; t1[1] = 0.0; t1[2] = -a[0] * r;
      } else {
        const double r = 1.0 / std::sqrt(a[0] * a[0] + a[1] * a[1]);
        t1[0] = -a[1] * r; t1[1] = a[0] * r; t1[2] = 0.0;
      }
      t2[0] = a[1] * t1[2] - a[2] * t1[1];
      t2[1] = a[2] * t1[0] - a[0] * t1[2];
      t2[2] = a[0] * t1[1] - a[1] * t1[0];
    }
  };

  /// A relative velocity in the frame: p = w.a, q1 = w.t1, q2 = w.t2, T = q1^2 + q2^2,
  /// n2 = p^2 + T (|w|^2), and S = sum of |velocity components| (for the error bound).
  struct Proj {
    double p, q1, q2, T, n2, S;
  };

  /// An operator for the given law with K-bit chart coordinates.
  explicit Pair3DExact(Law law = Law::flux, int bits = FixedPoint::default_bits)
      : law_(law), fp_(bits), ucells_(kUnitRoundoff * fp_.cells()) {
    const double a0 = 0.125 / ucells_ - 4.0 - kErr, a1 = 0.125 / ucells_ - 8.0;
    lim0_ = a0 > 0.0 ? a0 : 0.0;
    lim1_ = a1 > 0.0 ? (kTwoPi * a1) * (kTwoPi * a1) : 0.0;
    fast0_ = 0.99 * lim0_;
    fast1_ = 0.9 * lim1_;
  }

  /// The target law.
  Law law() const { return law_; }
  /// K.
  int bits() const { return fp_.bits(); }

  /// Pre -> post with the random numbers g in [0,1] (CLCG4 can return either end). Pushes
  /// the 2 pre cells onto `log` when the post state cannot give them back (rare). With
  /// `inv`, momentum and energy come from it (held invariants) instead of the velocities.
  /// Throws InvalidArgument on bad input, before anything changes.
  PairV<3> forward(const PairV<3>& pre, const std::array<double, 3>& normal,
                   const std::array<double, 2>& g, RareLog& log,
                   const Invariants<3>* inv = nullptr) const {
    const Frame f(normal);
    const Split s = split(pre, f, inv, /*post=*/false);
    check_draws(g);
    // chart of -w_pre, which lies in P because w_pre approaches
    const std::array<std::uint64_t, 2> pre_cells = encode(-s.x.p, -s.x.q1, -s.x.q2, s.x.T);
    const std::uint64_t c0 = fp_.add(pre_cells[0], fp_.shift(g[0]));
    const std::uint64_t c1 = fp_.add(pre_cells[1], fp_.shift(g[1]));
    PairV<3> post = assemble(f, s, c0, c1, +1.0);
    if (!surely_unlogged(s, fp_.decode(c0)) && needs_log(project(post, f))) {
      log.push(pre_cells[0]);
      log.push(pre_cells[1]);
    }
    return post;
  }

  /// Post -> pre with the same random numbers g that forward used (the RNG stepped back).
  /// Pops 2 cells from `log` when the forward step pushed. Throws InvalidArgument on bad
  /// input (including a post state that does not separate, or a log too short), before
  /// anything changes.
  PairV<3> reverse(const PairV<3>& post, const std::array<double, 3>& normal,
                   const std::array<double, 2>& g, RareLog& log,
                   const Invariants<3>* inv = nullptr) const {
    const Frame f(normal);
    const Proj x = project(post, f);
    const bool logged = needs_log(x);
    const Split s = split(post, f, x, inv, /*post=*/true, logged);
    check_draws(g);
    std::uint64_t c0, c1;
    if (logged) {
      require(log.size() >= 2, "rare log is empty: this post-collision state needs the 2 logged "
                               "coordinates that were never recorded");
      c1 = log.pop();
      c0 = log.pop();
    } else {
      const std::array<std::uint64_t, 2> post_cells = encode(x.p, x.q1, x.q2, x.T);
      c0 = fp_.sub(post_cells[0], fp_.shift(g[0]));
      c1 = fp_.sub(post_cells[1], fp_.shift(g[1]));
    }
    return assemble(f, s, c0, c1, -1.0);
  }

  /// Throws InvalidArgument unless `post` is a valid post-collision state (whether the log
  /// holds what it needs is logs() against the log's size).
  void check_post(const PairV<3>& post, const std::array<double, 3>& normal,
                  const Invariants<3>* inv = nullptr) const {
    const Frame f(normal);
    const Proj x = project(post, f);
    split(post, f, x, inv, /*post=*/true, needs_log(x));
  }
  /// Whether reversing `post` pops the rare log (2 cells).
  bool logs(const PairV<3>& post, const std::array<double, 3>& normal) const {
    const Frame f(normal);
    return needs_log(project(post, f));
  }
  /// Throws InvalidArgument unless `pre` is a valid pre-collision state.
  void check_pre(const PairV<3>& pre, const std::array<double, 3>& normal,
                 const Invariants<3>* inv = nullptr) const {
    split(pre, Frame(normal), inv, /*post=*/false);
  }

  /// The pre state as reversal restores it: its chart cells decoded at the cell centres
  /// (the "first quantization"; afterwards a reversed sequence is exact bit for bit).
  PairV<3> quantize(const PairV<3>& pre, const std::array<double, 3>& normal,
                    const Invariants<3>* inv = nullptr) const {
    const Frame f(normal);
    const Split s = split(pre, f, inv, /*post=*/false);
    const std::array<std::uint64_t, 2> u = encode(-s.x.p, -s.x.q1, -s.x.q2, s.x.T);
    return assemble(f, s, u[0], u[1], -1.0);
  }

  /// The K-bit chart cells of a pre-collision state (what reversal restores exactly).
  std::array<std::uint64_t, 2> pre_cell(const PairV<3>& pre,
                                        const std::array<double, 3>& normal) const {
    const Frame f(normal);
    const Split s = split(pre, f, nullptr, /*post=*/false);
    return encode(-s.x.p, -s.x.q1, -s.x.q2, s.x.T);
  }

  /// The chart coordinates (c0, c1) in [0,1] of a state seen as a post state (the caller
  /// makes sure it separates; exposed for coverage tests). Throws on a bad normal only.
  std::array<double, 2> chart(const PairV<3>& post, const std::array<double, 3>& normal) const {
    const Proj x = project(post, Frame(normal));
    return chart(x.p, x.q1, x.q2, x.T);
  }

  /// The bound, in cells, on how far each chart coordinate of `post` can lie from the cell
  /// centre forward decoded, through the rounding of the post velocities and of the chart
  /// (the rare log fires when twice it exceeds a quarter cell). Throws on a bad normal only.
  std::array<double, 2> recovery_bound(const PairV<3>& post,
                                       const std::array<double, 3>& normal) const {
    return bound(project(post, Frame(normal)));
  }

  /// The relative velocity of `v` in the frame (no validation).
  static Proj project(const PairV<3>& v, const Frame& f) {
    const double w0 = v.i[0] - v.j[0], w1 = v.i[1] - v.j[1], w2 = v.i[2] - v.j[2];
    Proj x;
    x.p = w0 * f.a[0] + w1 * f.a[1] + w2 * f.a[2];
    x.q1 = w0 * f.t1[0] + w1 * f.t1[1] + w2 * f.t1[2];
    x.q2 = w0 * f.t2[0] + w1 * f.t2[1] + w2 * f.t2[2];
    x.T = x.q1 * x.q1 + x.q2 * x.q2;
    x.n2 = x.p * x.p + x.T;
    x.S = std::fabs(v.i[0]) + std::fabs(v.i[1]) + std::fabs(v.i[2]) + std::fabs(v.j[0]) +
          std::fabs(v.j[1]) + std::fabs(v.j[2]);
    return x;
  }

  /// Whether a post state (in the frame) is too close to rounding trouble for its cells to
  /// be recovered: the rare-log condition, from the velocities alone (both directions agree).
  bool needs_log(const Proj& x) const {
    // recovery_bound() <= 1/8 in both coordinates, solved for the velocities (no division,
    // one square root): with err = S + kErr N,
    //   u 2^K (err / N + 4) <= 1/8             <=>  S <= lim0_ N,
    //   u 2^K (err / (2 pi sqrt(T)) + 8) <= 1/8 <=>  err^2 <= lim1_ T.
    if (!(x.n2 > 0.0 && lim0_ > 0.0 && lim1_ > 0.0)) return true;  // zero or NaN norm, or K too large
    const double N = std::sqrt(x.n2);
    const double err = x.S + kErr * N;
    return !(x.S <= lim0_ * N && err * err <= lim1_ * x.T);  // also true for NaN
  }

 private:
  static constexpr double kPi = 3.141592653589793238462643383279502884;
  static constexpr double kTwoPi = 2.0 * kPi;
  static constexpr double kUnitRoundoff = std::numeric_limits<double>::epsilon() / 2;
  static constexpr double kErr = 40.0;  // the bound's multiple of |w| (see bound())

  using DD = dd::DD;

  struct Split {
    Proj x;         // the relative velocity in the frame
    DD R;           // |w|^2 to build the output with (held, or from the velocities, compensated)
    double cm[3];   // centre-of-mass velocity (held or computed)
  };

  std::array<double, 2> bound(const Proj& x) const {
    // Error budget, in units of u = 2^-53, of the relative velocity that reverse recovers
    // from the stored post velocities, against the exact direction of the decoded cell
    // centres (times |w|), in frame coordinates:
    //   - v = cm +- w/2 rounds each component by u |v|: w moves by <= u S (S = sum |v_k|;
    //     cm's own rounding cancels in the difference);
    //   - decoding: sqrt / sincos / the products of the direction: <= 3; the world vector
    //     (3 products, 2 sums) <= 3; the double-double scale hi u + lo u: 1.5;
    //   - the frame is orthonormal only to rounding, F F^T = I + E with |E| <= 24 u (a: 7,
    //     t1: 6, t2 = a x t1: 17 on the diagonal, <= 3 off it; each unit vector is scaled by
    //     a reciprocal square root, 2 u more than a division), and encode projects on the
    //     same F that decode built with;
    //   - w = v_i - v_j: 1; the three projections: 4.5.
    // Total: u (S + 37 |w|), taken as u (S + kErr N), kErr = 40. A perturbation delta of w moves eta by
    // <= delta / N, and c0 by <= delta / N (dc0/deta = sin 2eta or sin eta, <= 1), plus 4 u
    // for c0's own formula; it moves phi by <= delta / |w_t| = delta / sqrt(T), that is c1 by
    // delta / (2 pi sqrt(T)), plus 8 u for atan2_turns (< 1 u, tests/cpp/test_trig.cpp) and
    // the decoder's sincos_turns (< 1.5 u). (The tests measure actual errors against this
    // bound.) Measure before
    // changing: this runs twice per collision and decides the rare log's size.
    const double N = std::sqrt(x.n2);
    const double err = x.S + kErr * N;
    return {ucells_ * (err / N + 4.0), ucells_ * (err / (kTwoPi * std::sqrt(x.T)) + 8.0)};
  }

  // Forward's shortcut to needs_log(project(post, f)) == false, from quantities known before
  // the post state is (so the test is off the end of the operator's critical path): the post
  // state's relative speed is sqrt(R), its tangential part sqrt(R sin^2(eta)) with sin^2(eta)
  // = c0 (flux) or c0 (2 - c0) (uniform) at the decoded cell centre c0, and its sum of
  // |components| S <= 2 sum |cm_k| + 2 sum |h_k| <= 2 sum |cm_k| + sqrt(3) sqrt(R), taken as
  // B = 2 sum |cm_k| + 1.8 sqrt(R) (post = cm +- h, |h| = sqrt(R)/2), all up to the recovery
  // error that bound() derives, |delta| <= u (S + 37 |w|) per frame coordinate. True only when
  // the exact test surely finds no log (both of its conditions only tighten as S grows):
  //   - N (reverse's |w|) is within u (lim0 + 40) <= 2^-K / 8 relative of sqrt(R), so
  //     B <= 0.99 lim0 sqrt(R) gives S <= lim0 N, and err = S + 40 N <= B + 40.4 sqrt(R);
  //   - where (B + 40.4 sqrt(R))^2 <= 0.9 lim1 R sin^2, sqrt(R sin^2) >= err / sqrt(lim1),
  //     so the recovery error 2 u err moves sqrt(T) by at most 2 u sqrt(lim1) <= pi 2^-K / 2
  //     (<= 0.7% for K >= 8) of itself: T >= 0.9 R sin^2 and err^2 <= lim1 T.
  // Otherwise (rarely: near the log's own edge, and always when K is too large for any state
  // to go unlogged) the exact test decides: forward and reverse agree bit for bit either way.
  // (Saves the forward step a projection and a square root; tests/cpp/test_pair3d_exact.cpp
  // checks the implication across the edge at every K.)
  bool surely_unlogged(const Split& s, double c0) const {
    const double R = s.R.hi, rho = std::sqrt(R);
    const double B = 2.0 * (std::fabs(s.cm[0]) + std::fabs(s.cm[1]) + std::fabs(s.cm[2])) + 1.8 * rho;
    const double sin2 = law_ == Law::flux ? c0 : c0 * (2.0 - c0);
    const double err = B + (kErr + 0.4) * rho;
    return B <= fast0_ * rho && err * err <= fast1_ * (R * sin2);  // false for NaN
  }

  void check_draws(const std::array<double, 2>& g) const {
    require(g[0] >= 0.0 && g[0] <= 1.0 && g[1] >= 0.0 && g[1] <= 1.0,
            "random numbers must be in [0,1]");
  }

  // Chart coordinates of a separating relative velocity (p >= 0) in the frame.
  std::array<double, 2> chart(double p, double q1, double q2, double T) const {
    const double n2 = p * p + T;
    double c0;
    if (law_ == Law::flux) {
      c0 = T / n2;  // sin^2(eta)
    } else {
      const double N = std::sqrt(n2);
      c0 = T / (N * (N + p));  // 1 - cos(eta) = sin^2 / (1 + cos)
    }
    return {c0, trig::atan2_turns(q2, q1)};  // phi / (2 pi) in [0, 1] (trig.hpp)
  }
  std::array<std::uint64_t, 2> encode(double p, double q1, double q2, double T) const {
    const std::array<double, 2> c = chart(p, q1, q2, T);
    return {fp_.encode(c[0]), fp_.encode(c[1])};
  }

  // Validates and splits a pre (post = false: must approach) or post (must separate,
  // unless the rare log serves it) state. The relative speed must lie in [2^-500, 2^500]
  // (its square in [2^-1000, 2^1000]: a normal double whose squares neither underflow nor
  // overflow); post states get a factor 2 more room, so that every post state forward
  // produces passes.
  [[gnu::always_inline]] Split split(const PairV<3>& v, const Frame& f, const Invariants<3>* inv, bool post,
              bool logged = false) const {
    return split(v, f, project(v, f), inv, post, logged);
  }
  [[gnu::always_inline]] Split split(const PairV<3>& v, const Frame& f, const Proj& x, const Invariants<3>* inv,
              bool post, bool logged) const {
    (void)f;
    // |v| bounded so that v_i + v_j and cm +- w/2 cannot overflow
    const double smax = post ? 0x1.0p+1021 : 0x1.0p+1020;
    const double lo = post ? 0x1.0p-1001 : 0x1.0p-1000, hi = post ? 0x1.0p+1001 : 0x1.0p+1000;
    // one test on the hot path: S in range also proves every component finite (an infinity
    // makes S infinite, a NaN makes the comparison false); the cold path names the problem
    if (!(x.S <= smax && x.n2 >= lo && x.n2 <= hi)) [[unlikely]] {
      require_finite(v);
      require(x.S <= smax, "velocities too large (sum of |components| above 2^1020, about 1e307)");
      require(x.n2 > 0.0, "zero relative speed: the particles cannot collide");
      require(x.n2 >= lo, "relative speed too small (below 2^-500, about 3e-151)");
      require(x.n2 <= hi, "relative speed too large (above 2^500, about 3e150)");
    }
    if (post) {
      require(x.p > 0.0 || logged, [&] {
        return std::string("post-collision state does not separate along the contact normal "
                           "(normal relative velocity " + std::to_string(x.p) + " <= 0)");
      });
    } else {
      require(x.p < 0.0, [&] {
        return std::string("pre-collision state is not approaching along the contact normal "
                           "(normal relative velocity " + std::to_string(x.p) + " >= 0)");
      });
    }
    Split s;
    s.x = x;
    if (inv) {
      checked_relative_speed(*inv, std::sqrt(x.n2));
      s.R = {relative_speed2(*inv), 0.0};
      for (int k = 0; k < 3; ++k) s.cm[k] = 0.5 * inv->momentum[k];
    } else {
      // |w|^2 with its additions compensated, as Pair2DExact's (dd::compensated_norm2). A
      // plain double sum drifts the energy linearly when outputs are chained (3.8e-12 over
      // 1e5 collisions with a fixed normal, measured; exact.cpp found the same). Over 1e6
      // chained collisions the energy walks to ~1e-13 with fixed and random normals alike, as
      // with the exact double-double |w|^2 this replaced (6% of the forward operator, 15% of
      // the reverse).
      s.R = dd::compensated_norm2<3>(relative(v).data());
      for (int k = 0; k < 3; ++k) s.cm[k] = 0.5 * (v.i[k] + v.j[k]);
    }
    return s;
  }

  // Velocities from chart cells (U0, U1), decoded at their centres c0, c1; sign -1 gives the
  // pre state (-chart^-1). The flux law's roots and phi's reduction come straight from the
  // integers (FixedPoint::roots, quarters: the same bits as from c0 and c1, shorter).
  [[gnu::always_inline]] PairV<3> assemble(const Frame& f, const Split& s, std::uint64_t U0, std::uint64_t U1,
                                           double sign) const {
    double cn, sn;  // cos(eta), sin(eta)
    if (law_ == Law::flux) {
      fp_.roots(U0, sn, cn);  // sqrt(c0), sqrt(1 - c0)
    } else {
      const double c0 = fp_.decode(U0);  // 1 - c0 and 2 - c0 are exact (c0 is a cell centre)
      cn = 1.0 - c0;
      sn = std::sqrt(c0 * (2.0 - c0));
    }
    // sin and cos of phi = 2 pi c1 (trig.hpp), reduced to quarter turns in integers
    double sphi, cphi;
    const FixedPoint::Quarters qr = fp_.quarters(U1);
    trig::sincos_quarters(qr.q, qr.r, sphi, cphi);
    const double d1 = sn * cphi, d2 = sn * sphi;
    double u[3];  // the unit direction in the world frame (to rounding)
    for (int k = 0; k < 3; ++k) u[k] = cn * f.a[k] + d1 * f.t1[k] + d2 * f.t2[k];
    // Scale u to |w| = sqrt(R) in double-double: |u|^2 = 1 + u.E u with E = F F^T - I fixed
    // by the frame's rounding, so a plain scale by |w| would bias the energy by the same
    // u.E u every collision with this normal (a linear drift). hi u + lo u has |.|^2 = R/|u|^2
    // |u|^2 to double-double accuracy; only the final roundings remain, and they vary.
    // The scale sqrt(R / |u|^2) by its two first-order parts (dd::first_order_scale, as
    // Pair2DExact), with |u|^2 = 1 + dU (dd::compensated_norm2_minus_one). |u|^2 has its additions
    // compensated (their rounding would repeat: the sum is always ~1) but its squares rounded,
    // as |w|^2: u is a new random direction every collision, even with one normal, so those
    // roundings vary and average out. (Exact squares cost ~30 instructions a collision, 8% of
    // the operator; the drift over 2e6 chained collisions, fixed or random normals, stays the
    // same random walk, ~1e-13: tests/cpp/test_pair3d_exact.cpp bounds it at 1e5.)
    const DD sc = dd::first_order_scale(s.R, std::sqrt(s.R.hi), dd::compensated_norm2_minus_one<3>(u));
    const double hi = sign * 0.5 * sc.hi, lo = sign * 0.5 * sc.lo;  // v = cm +- w/2
    PairV<3> out;
    for (int k = 0; k < 3; ++k) {
      const double h = hi * u[k] + lo * u[k];
      out.i[k] = s.cm[k] + h;
      out.j[k] = s.cm[k] - h;
    }
    return out;
  }

  Law law_;
  FixedPoint fp_;
  double ucells_;  // u 2^K: an error of k u in a coordinate is k ucells_ cells
  double lim0_, lim1_;  // needs_log's limits (0: every state logs)
  double fast0_, fast1_;  // surely_unlogged's: 0.99 lim0_, 0.9 lim1_
};

}  // namespace revcol
