// Exact-mode collision of 2 particles in 2 dimensions: the reference operator.
//
// Physics (DESIGN.md §3). Two unit masses collide; momentum M = v_i + v_j and energy
// E = |v_i|^2 + |v_j|^2 fix the centre-of-mass velocity M/2 and the relative speed
// |w| = |v_i - v_j| = sqrt(2E - |M|^2). What is free is the direction of w: a point on a
// circle (D = (n-1)d = 2, so d_n = 1 free parameter). The contact normal a (unit, from
// particle j to particle i) splits the circle: the pair separates after the collision iff
// a.w > 0 (the permitted set P, a half circle, m = 1 contact) and approached before it iff
// a.w < 0 (the pre set -P). With t the tangent, write a point of P as
//     w = |w| (cos(eta) a + sin(eta) t),   eta in (-pi/2, pi/2)
// (the general chart's f = 1 case: the free part z = +-1 merges with eta into this signed
// angle).
//
// The chart c: P -> [0,1) is measure-preserving for the chosen law:
//   uniform  (uniform on P, the paper's requirement):  c = eta/pi + 1/2
//   flux     (density ~ a.w = cos(eta), the time reverse of the arrival law of an
//             event-driven gas, DESIGN.md "Which law"):  c = (1 + sin(eta)) / 2
// Forward:  c' = chart(-w_pre), c = c' + G (mod 1), w_post = chart^-1(c).
// Reverse:  c = chart(w_post), c' = c - G (mod 1), w_pre = -chart^-1(c').
// Whatever c' is, c is distributed by the law (a torus shift of a uniform variable), so
// every post state is sampled exactly, with exactly one random number, and no folding.
//
// Numerics (DESIGN.md §4). c is held as a K-bit integer (FixedPoint): the shift is exact
// integer arithmetic, and decoding at a cell centre makes a post state re-encode to its own
// cell whenever the round trip through the stored velocities is accurate to half a cell.
// That accuracy is lost only when the relative speed is tiny next to the velocities
// themselves (rounding cm +- w/2 costs eps |v| in w): there the forward step pushes the pre
// cell onto the rare log and the reverse step pops it. The decision is a function of the
// post velocities alone, evaluated bit-identically in both directions.
#pragma once
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#include "revcol/collide/common.hpp"
#include "revcol/collide/pair.hpp"
#include "revcol/double_double.hpp"
#include "revcol/fixed_point.hpp"

namespace revcol {

/// Exact-mode pair collision in 2D: chart + K-bit torus shift, flux or uniform law.
class Pair2DExact {
 public:
  static constexpr int dim = 2;        ///< spatial dimension d
  static constexpr int particles = 2;  ///< particles n
  static constexpr int draws = 1;      ///< random numbers per collision, d_n = nd - d - 1

  /// An operator for the given law with K-bit chart coordinates.
  explicit Pair2DExact(Law law = Law::flux, int bits = FixedPoint::default_bits)
      : law_(law), fp_(bits) {
    const double lim = 1.0 / (8.0 * kUnitRoundoff * fp_.cells());
    log_lim2_ = lim > 10.0 ? (lim - 10.0) * (lim - 10.0) : 0.0;
    fast_lim2_ = 0.99 * log_lim2_;
  }

  /// The target law.
  Law law() const { return law_; }
  /// K.
  int bits() const { return fp_.bits(); }

  /// Pre -> post with the random number g in [0,1] (CLCG4 can return either end). Pushes onto `log` when the post state
  /// cannot give the pre cell back (rare). With `inv`, momentum and energy are taken from
  /// it (held invariants) instead of the velocities. Throws InvalidArgument on bad input,
  /// before anything changes.
  PairV<2> forward(const PairV<2>& pre, const std::array<double, 2>& normal, double g,
                   RareLog& log, const Invariants<2>* inv = nullptr) const {
    const Frame2 f(normal);
    const Split s = split(pre, f, inv, /*post=*/false);
    // chart of -w_pre, which lies in P because w_pre approaches
    const std::uint64_t cell_pre = cell(-s.p, -s.q, -s.y, s.norm);
    const std::uint64_t cell_post = fp_.add(cell_pre, shift(g));
    PairV<2> post = assemble(f, s, cell_post, +1.0);
    if (!surely_unlogged(s) && needs_log(post, f)) log.push(cell_pre);
    return post;
  }

  /// Post -> pre with the same random number g that forward used (the RNG stepped back).
  /// Pops from `log` when the forward step pushed. Throws InvalidArgument on bad input
  /// (including a post state that does not separate), before anything changes.
  PairV<2> reverse(const PairV<2>& post, const std::array<double, 2>& normal, double g,
                   RareLog& log, const Invariants<2>* inv = nullptr) const {
    const Frame2 f(normal);
    const bool logged = needs_log(post, f);
    const Split s = split(post, f, inv, /*post=*/true, logged);
    std::uint64_t cell_pre;
    if (logged) {
      cell_pre = log.pop();
    } else {
      cell_pre = fp_.sub(cell(s.p, s.q, s.y, s.norm), shift(g));
    }
    return assemble(f, s, cell_pre, -1.0);
  }

  /// Throws InvalidArgument unless `post` is a valid post-collision state (whether the log
  /// holds what it needs is logs() against the log's size).
  void check_post(const PairV<2>& post, const std::array<double, 2>& normal,
                  const Invariants<2>* inv = nullptr) const {
    const Frame2 f(normal);
    split(post, f, inv, /*post=*/true, needs_log(post, f));
  }
  /// Whether reversing `post` pops the rare log.
  bool logs(const PairV<2>& post, const std::array<double, 2>& normal) const {
    return needs_log(post, Frame2(normal));
  }
  /// Throws InvalidArgument unless `pre` is a valid pre-collision state.
  void check_pre(const PairV<2>& pre, const std::array<double, 2>& normal,
                 const Invariants<2>* inv = nullptr) const {
    split(pre, Frame2(normal), inv, /*post=*/false);
  }

  /// The pre state as reversal restores it: its chart cell decoded at the cell centre
  /// (the "first quantization"; afterwards a reversed sequence is exact bit for bit).
  PairV<2> quantize(const PairV<2>& pre, const std::array<double, 2>& normal,
                    const Invariants<2>* inv = nullptr) const {
    const Frame2 f(normal);
    const Split s = split(pre, f, inv, /*post=*/false);
    return assemble(f, s, cell(-s.p, -s.q, -s.y, s.norm), -1.0);
  }

  /// The K-bit chart cell of a pre-collision state (what reversal restores exactly).
  std::uint64_t pre_cell(const PairV<2>& pre, const std::array<double, 2>& normal) const {
    const Frame2 f(normal);
    const Split s = split(pre, f, nullptr, /*post=*/false);
    return cell(-s.p, -s.q, -s.y, s.norm);
  }

  /// The chart coordinate in [0,1] of a separating relative velocity with normal part
  /// p > 0, tangent part q and norm |w| (exposed for coverage tests; the operator's flux
  /// cells take q/|w| from the normal as given, split(), the same value to a few roundings).
  double chart(double p, double q, double norm) const {
    if (law_ == Law::uniform) return std::atan2(q, p) / kPi + 0.5;
    return 0.5 + 0.5 * (q / norm);
  }

  /// Whether a post state is too close to rounding trouble for its cell to be recovered:
  /// the rare-log condition, evaluated on the velocities alone (both directions agree).
  bool needs_log(const PairV<2>& post, const Frame2& f) const {
    (void)f;  // the bound below is rotation-invariant
    // Rounding v = cm +- w/2 to doubles moves w by up to u (|v_i| + |v_j|) per component
    // (u = 2^-53); computing w, its frame components, the chart and the decoded direction
    // add about ten more roundings relative to |w|. The chart coordinate's error is then
    // below u (S/|w| + 10) with S the sum of |components|; a cell is 2^-K, and the cell
    // round-trips when the error stays below half a cell. We log beyond a quarter cell,
    // with a factor 2 of safety on the bound. Measure before changing: this is the whole
    // cost of the rare log on the hot path.
    const double w0 = post.i[0] - post.j[0], w1 = post.i[1] - post.j[1];
    const double norm2 = w0 * w0 + w1 * w1;
    const double sum = std::fabs(post.i[0]) + std::fabs(post.i[1]) + std::fabs(post.j[0]) +
                       std::fabs(post.j[1]);
    // 2 u 2^K (sum/|w| + 10) > 1/4  <=>  sum > |w| (L - 10), L = 1 / (8 u 2^K)
    //                               <=>  sum^2 > |w|^2 (L - 10)^2  (for L > 10: K <= 46),
    // without a square root; for K >= 47 (L <= 10) every state logs.
    if (!(log_lim2_ > 0.0)) return true;
    return !(sum * sum <= norm2 * log_lim2_);  // also true for a zero (moving pair) or non-finite norm
  }

 private:
  static constexpr double kPi = 3.141592653589793238462643383279502884;
  static constexpr double kUnitRoundoff = std::numeric_limits<double>::epsilon() / 2;

  /// The relative velocity in the contact frame plus what assembling needs.
  struct Split {
    double p, q;     // w . a, w . t
    double norm;     // |w| from the velocities
    double y;        // q / |w| as the flux chart takes it: (x x w) / (|x| |w|)
    dd::DD R;        // |w|^2 to build the output with (held, or from the velocities exactly)
    double rho;      // sqrt(R.hi) (= norm when R comes from the velocities)
    double cm[2];    // centre-of-mass velocity (held or computed)
  };

  // The K-bit cell of the chart: uniform law encode(chart(p, q, norm)); flux law the cell of
  // (1 + y)/2 (FixedPoint::encode_half), y = q/|w| as split() computes it.
  std::uint64_t cell(double p, double q, double y, double norm) const {
    if (law_ == Law::uniform) return fp_.encode(chart(p, q, norm));
    return fp_.encode_half(y);
  }

  // Forward's shortcut to needs_log(post) == false, from quantities known before the post
  // state is (off the end of the critical path): post = cm +- h with |h| = sqrt(R)/2, so its
  // sum of |components| is at most 2 (|cm_0| + |cm_1|) + 2 (|h_0| + |h_1|) <= B = 2 (|cm_0| +
  // |cm_1|) + 1.5 sqrt(R) (sqrt(2) with room for roundings). Where B^2 <= 0.99 R (L - 10)^2,
  // the post state's |w|^2 is within 4 u (L + 10) <= 2^-K / 2 relative of R (twice
  // needs_log's own error budget at sum <= L |w|; <= 0.2% for K >= 8), so
  // sum^2 <= B^2 <= norm2 (L - 10)^2: needs_log is false.
  // Otherwise (rarely: a centre of mass within a factor ~2 of the log's edge, or a K too
  // large for any state to go unlogged) needs_log decides, as reverse does: both agree bit for
  // bit either way (tests/cpp/test_pair2d_exact.cpp checks the implication at every K).
  bool surely_unlogged(const Split& s) const {
    const double B = 2.0 * (std::fabs(s.cm[0]) + std::fabs(s.cm[1])) + 1.5 * s.rho;
    return B * B <= fast_lim2_ * s.R.hi;  // false for NaN and when every state logs
  }

  std::uint64_t shift(double g) const {
    require(g >= 0.0 && g <= 1.0, "random number must be in [0,1]");
    return fp_.shift(g);
  }

  // Validates and splits a pre (post = false: must approach) or post (must separate,
  // unless the rare log serves it) state.
  [[gnu::always_inline]] Split split(const PairV<2>& v, const Frame2& f, const Invariants<2>* inv, bool post,
              bool logged = false) const {
    const std::array<double, 2> w = relative(v);
    Split s;
    s.p = f.normal_part(w);
    s.q = f.tangent_part(w);
    const double n2 = w[0] * w[0] + w[1] * w[1];
    const double vcm[2] = {0.5 * (v.i[0] + v.j[0]), 0.5 * (v.i[1] + v.j[1])};
    require_speed_range(v, w, n2, vcm);  // also rejects a NaN or infinite velocity
    s.norm = std::sqrt(n2);
    // The flux chart's q / |w| straight from the normal as given, (w_1 x_0 - w_0 x_1) / (|x|
    // |w|): the frame's reciprocal and the products by a leave the operator's critical path
    // (one division after the square roots instead of two). About as many roundings of
    // order u as w . t / |w| had: inside the chart's share of needs_log()'s budget.
    s.y = law_ == Law::flux ? (w[1] * f.x[0] - w[0] * f.x[1]) / (f.len * s.norm) : 0.0;
    if (post) {
      require(s.p > 0.0 || logged, [&] { return std::string("post-collision state does not separate along the contact normal "
              "(normal relative velocity " + std::to_string(s.p) + " <= 0)"); });
    } else {
      require(s.p < 0.0, [&] { return std::string("pre-collision state is not approaching along the contact normal "
                         "(normal relative velocity " + std::to_string(s.p) + " >= 0)"); });
    }
    if (inv) {
      checked_relative_speed(*inv, s.norm);
      s.R = {relative_speed2(*inv), 0.0};
      s.rho = std::sqrt(s.R.hi);
      s.cm[0] = 0.5 * inv->momentum[0];
      s.cm[1] = 0.5 * inv->momentum[1];
    } else {
      // |w|^2 with its last addition compensated: |w| is conserved, so the rounding of that
      // sum would repeat collision after collision (see double_double.hpp); the roundings of
      // the squares vary with the direction of w and average out
      s.R = dd::compensated_norm2<2>(w.data());
      s.rho = s.norm;  // the same sum's square root
      s.cm[0] = vcm[0];
      s.cm[1] = vcm[1];
    }
    return s;
  }

  // Velocities from chart cell U, decoded at its centre c; sign -1 gives the pre state
  // (-chart^-1).
  PairV<2> assemble(const Frame2& f, const Split& s, std::uint64_t U, double sign) const {
    double cn, ct;  // unit direction in the frame: cos(eta), sin(eta)
    if (law_ == Law::uniform) {
      const double c = fp_.decode(U);
      // eta = pi (c - 1/2). With th = pi min(c, 1-c): cos(eta) = sin(th), which keeps full
      // relative precision at the grazing edges where the textbook cos(eta) would cancel, and
      // sin(eta) = -+cos(th) (one sincos; its absolute error ~1e-16 is what the chart needs).
      const double th = kPi * std::fmin(c, 1.0 - c);
      cn = std::sin(th);
      ct = c < 0.5 ? -std::cos(th) : std::cos(th);
    } else {
      // sin(eta) = 2c - 1 exactly (c is a cell centre); cos(eta) from the factored form
      // sqrt((1 - sn)(1 + sn)). Both straight from the integer cell, with the same bits:
      // sn = m 2^-K with m = 2U + 1 - 2^K, 1 -+ sn = (2^K -+ m) 2^-K, all exact (|m| <= 2^K
      // <= 2^52, 2^K -+ m <= 2^53); scaling by 2^-2K commutes with the product's rounding,
      // and by an even power of two with the square root's, so cn = sqrt((2^K - m)(2^K + m))
      // 2^-K. (Five operations shorter on the critical path than decoding c first.)
      const double m = static_cast<double>(fp_.centered(U)), k = fp_.cells();
      cn = std::sqrt((k - m) * (k + m)) * fp_.inv_cells();
      ct = m * fp_.inv_cells();
    }
    // The scale |w| / |a| to double-double accuracy, by its two systematic parts only (both
    // repeat collision after collision, so a plain scale drifts the energy linearly: 3e-12
    // after 1e5 chained collisions with one normal, measured; see test_pair2d_exact):
    //   sqrt(R) = rho + e / (2 rho), e = R - rho^2 exactly (the rounding of the sqrt);
    //   |a|^2 = 1 + da (the frame's rounding; t = (-a1, a0) has |t| = |a| and a.t = 0
    //   exactly), so the direction cn a + ct t is divided by |a| = 1 + da/2.
    // What remains varies with the direction and the cell: a random walk (~1e-16 sqrt(N)).
    // Cheaper than full double-double (which halved this operator's throughput).
    const double da = dd::add_minus_one(dd::two_square(f.a[0]), dd::two_square(f.a[1]));  // |a|^2 - 1
    const dd::DD sc = dd::first_order_scale(s.R, s.rho, da);
    const double hi = sign * 0.5 * sc.hi, lo = sign * 0.5 * sc.lo;  // half of w: v = cm +- w/2
    const double u[2] = {cn * f.a[0] + ct * f.t[0], cn * f.a[1] + ct * f.t[1]};
    const double h0 = hi * u[0] + lo * u[0];
    const double h1 = hi * u[1] + lo * u[1];
    PairV<2> out;
    out.i = {s.cm[0] + h0, s.cm[1] + h1};
    out.j = {s.cm[0] - h0, s.cm[1] - h1};
    return out;
  }

  Law law_;
  FixedPoint fp_;
  double log_lim2_;  // (L - 10)^2 of needs_log, 0 when every state logs
  double fast_lim2_;  // 0.99 log_lim2_: surely_unlogged's
};

}  // namespace revcol
