// One concept for the pair collision operators the engine runs, and the thin adapters that
// give every existing operator its form.
//
// A pair operator in d dimensions maps the pre-collision velocities of an approaching pair
// (contact normal r from j to i, not necessarily unit) and `draws` random numbers to the
// post-collision velocities, and back:
//     post = forward(pre, r, g, log),   pre = reverse(post, r, g, log)
// with the same g (the generator stepped back: reverse reads g[draws-1] first), so that
// reverse(forward(v)) = v to the operator's precision. g points at `draws` numbers in draw
// order. `draws` is fixed per operator: a variable count cannot be reversed (the paper
// §4.6). Both throw InvalidArgument on a state that is not theirs (a pair that does not
// approach, resp. separate), before anything changes and before the log is touched.
// The engine runs forward, or, in a reversed run (velocities negated), v -> -reverse(-v).
//
// Capability flags, read at compile time by the engine:
//   needs_exact_pre_log  the chart has singular points where a pre state's quantized cell is
//                        wide: the engine asks singular(pre, r) and, when true, quantize(pre,
//                        r) and keeps the pre state when its cell centre is off by more than
//                        1e-10 (the exact-pre log, engine/logs.hpp);
//   quantizes            reverse restores the pre state to its K-bit cell centre (exact
//                        mode), not to the last bit.
// And `name`, the Mode's name.
//
// To add an operator: write it (its own header under collide/, this form, or an adapter
// here), give it a Mode value (collide/common.hpp), and choose it in the engine's
// with_operator (cpp/src/engine_operators.hpp, the one place that names the operators);
// ARCHITECTURE.md "To add an operator".
#pragma once
#include <array>
#include <concepts>

#include "revcol/collide/common.hpp"
#include "revcol/collide/pair.hpp"
#include "revcol/collide/pair1d.hpp"
#include "revcol/collide/pair2d_exact.hpp"
#include "revcol/collide/pair2d_paper.hpp"
#include "revcol/collide/pair3d_exact.hpp"

namespace revcol {

/// What the engine asks of a pair collision operator (see above).
template <class Op>
concept PairOperator = requires(const Op& op, const PairV<Op::dim>& v, const std::array<double, Op::dim>& r,
                                const double* g, RareLog& log) {
  requires Op::dim >= 1 && Op::dim <= 3;
  requires Op::draws >= 0;
  { Op::needs_exact_pre_log } -> std::convertible_to<bool>;
  { Op::quantizes } -> std::convertible_to<bool>;
  { Op::name } -> std::convertible_to<const char*>;
  { op.forward(v, r, g, log) } -> std::same_as<PairV<Op::dim>>;
  { op.reverse(v, r, g, log) } -> std::same_as<PairV<Op::dim>>;
};

/// A pair operator whose singular pre states the engine keeps exactly (needs_exact_pre_log).
template <class Op>
concept ExactPreLogged = PairOperator<Op> && Op::needs_exact_pre_log &&
                         requires(const Op& op, const PairV<Op::dim>& v, const std::array<double, Op::dim>& r) {
                           { op.singular(v, r) } -> std::same_as<bool>;
                           { op.quantize(v, r) } -> std::same_as<PairV<Op::dim>>;
                         };

namespace ops {

/// 1D: Pair1D, the exchange of velocities (0 draws; paper and exact mode alike).
struct Exchange1D {
  static constexpr int dim = 1;                         ///< d
  static constexpr int draws = 0;                       ///< random numbers per collision
  static constexpr bool needs_exact_pre_log = false;    ///< no chart
  static constexpr bool quantizes = false;              ///< exact to the bit
  static constexpr const char* name = "exchange";       ///< what it is
  /// Pre -> post.
  PairV<1> forward(const PairV<1>& v, const std::array<double, 1>& r, const double*, RareLog&) const {
    return Pair1D{}.forward(v, r[0]);
  }
  /// Post -> pre.
  PairV<1> reverse(const PairV<1>& v, const std::array<double, 1>& r, const double*, RareLog&) const {
    return Pair1D{}.reverse(v, r[0]);
  }
};

/// 2D, one draw: the adapter of Pair2DExact and Pair2DPaper (their g is one number).
template <class P, bool Quantizes>
struct OneDraw2D {
  static constexpr int dim = 2;                         ///< d
  static constexpr int draws = 1;                       ///< random numbers per collision
  static constexpr bool needs_exact_pre_log = false;    ///< their rare logs suffice
  static constexpr bool quantizes = Quantizes;          ///< K-bit chart cells (exact) or not (paper)
  /// Pre -> post.
  PairV<2> forward(const PairV<2>& v, const std::array<double, 2>& r, const double* g, RareLog& log) const {
    return op.forward(v, r, g[0], log);
  }
  /// Post -> pre.
  PairV<2> reverse(const PairV<2>& v, const std::array<double, 2>& r, const double* g, RareLog& log) const {
    return op.reverse(v, r, g[0], log);
  }
  P op;  ///< the operator
};

/// 2D, exact mode: Pair2DExact.
struct Exact2D : OneDraw2D<Pair2DExact, true> {
  static constexpr const char* name = "exact";  ///< Mode::exact
  /// The law and K.
  Exact2D(Law law, int bits) : OneDraw2D{{Pair2DExact(law, bits)}} {}
};

/// 2D, paper mode: Pair2DPaper, Procedures 1-2 with the candidate test fixed.
struct Paper2D : OneDraw2D<Pair2DPaper, false> {
  static constexpr const char* name = "paper";  ///< Mode::paper
  /// With the candidate test fixed (not the printed one).
  Paper2D() : OneDraw2D{{Pair2DPaper(/*printed_reverse=*/false)}} {}
};

/// 3D, exact mode: Pair3DExact (2 draws); near head-on its polar chart is singular.
struct Exact3D {
  static constexpr int dim = 3;                         ///< d
  static constexpr int draws = 2;                       ///< random numbers per collision
  static constexpr bool needs_exact_pre_log = true;     ///< near head-on pre cells are wide
  static constexpr bool quantizes = true;               ///< K-bit chart cells
  static constexpr const char* name = "exact";          ///< Mode::exact
  /// The law and K.
  Exact3D(Law law, int bits) : op(law, bits) {}
  /// Pre -> post.
  PairV<3> forward(const PairV<3>& v, const std::array<double, 3>& r, const double* g, RareLog& log) const {
    return op.forward(v, r, {g[0], g[1]}, log);
  }
  /// Post -> pre.
  PairV<3> reverse(const PairV<3>& v, const std::array<double, 3>& r, const double* g, RareLog& log) const {
    return op.reverse(v, r, {g[0], g[1]}, log);
  }
  /// Near head-on (sin^2 of the angle between r and w below 1e-4, eta < ~1e-2), where the
  /// pre cell of the polar chart is wide.
  bool singular(const PairV<3>& v, const std::array<double, 3>& r) const {
    double w2 = 0.0, rr = 0.0, rw = 0.0;
    for (int k = 0; k < 3; ++k) {
      const double w = v.i[k] - v.j[k];
      w2 += w * w;
      rr += r[k] * r[k];
      rw += r[k] * w;
    }
    return w2 * rr - rw * rw < 1e-4 * w2 * rr;
  }
  /// The pre state as a reversal restores it (its cells decoded at their centres).
  PairV<3> quantize(const PairV<3>& v, const std::array<double, 3>& r) const { return op.quantize(v, r); }
  Pair3DExact op;  ///< the operator
};

static_assert(PairOperator<Exchange1D> && PairOperator<Exact2D> && PairOperator<Paper2D>);
static_assert(ExactPreLogged<Exact3D>);

}  // namespace ops
}  // namespace revcol
