// A 2D pair collision operator of either mode, with its own rare log: what the Python API
// and the benchmarks hold. Batches of independent collisions; see batch.hpp for the rules
// (everything validated before anything changes).
#pragma once
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <string>

#include "revcol/collide/batch.hpp"
#include "revcol/collide/pair2d_exact.hpp"
#include "revcol/collide/pair2d_paper.hpp"

namespace revcol {

/// Pair collisions in 2D: exact mode (flux or uniform law) or paper mode.
class Pair2D {
 public:
  static constexpr int draws = 1;  ///< random numbers per collision

  /// mode, exact mode's law and K, paper mode's printed_reverse flag.
  Pair2D(Mode mode = Mode::exact, Law law = Law::flux, int bits = FixedPoint::default_bits,
         bool printed_reverse = false)
      : mode_(mode), exact_(law, bits), paper_(printed_reverse) {}

  Mode mode() const { return mode_; }                          ///< the mode
  Law law() const { return exact_.law(); }                     ///< exact mode's law
  int bits() const { return exact_.bits(); }                   ///< exact mode's K
  bool printed_reverse() const { return paper_.printed_reverse(); }  ///< paper mode flag
  RareLog& log() { return log_; }                              ///< the rare log
  const RareLog& log() const { return log_; }                  ///< the rare log

  /// Forward over B entries with given draws g[b].
  void forward(PairV<2>* v, const std::array<double, 2>* n, std::size_t B, const double* g,
               const Invariants<2>* inv = nullptr) {
    if (mode_ == Mode::exact) forward_batch(exact_, v, n, B, g, log_, inv);
    else forward_batch(paper_, v, n, B, g, log_, inv);
  }
  /// Reverse over B entries (last first) with the draws forward used.
  void reverse(PairV<2>* v, const std::array<double, 2>* n, std::size_t B, const double* g,
               const Invariants<2>* inv = nullptr) {
    if (mode_ == Mode::exact) reverse_batch(exact_, v, n, B, g, log_, inv);
    else reverse_batch(paper_, v, n, B, g, log_, inv);
  }
  /// Forward over B entries drawing from gen (entry order) after validating all.
  template <class Gen>
  void forward(PairV<2>* v, const std::array<double, 2>* n, std::size_t B, Gen& gen,
               const Invariants<2>* inv = nullptr) {
    if (mode_ == Mode::exact) forward_batch(exact_, v, n, B, gen, log_, inv);
    else forward_batch(paper_, v, n, B, gen, log_, inv);
  }
  /// Reverse over B entries stepping gen back after validating all.
  template <class Gen>
  void reverse(PairV<2>* v, const std::array<double, 2>* n, std::size_t B, Gen& gen,
               const Invariants<2>* inv = nullptr) {
    if (mode_ == Mode::exact) reverse_batch(exact_, v, n, B, gen, log_, inv);
    else reverse_batch(paper_, v, n, B, gen, log_, inv);
  }
  /// The pre state as a reversal restores it (exact: its cell centre; paper: itself).
  PairV<2> quantize(const PairV<2>& pre, const std::array<double, 2>& n,
                    const Invariants<2>* inv = nullptr) const {
    if (mode_ == Mode::exact) return exact_.quantize(pre, n, inv);
    paper_.check_pre(pre, n, inv);
    return pre;
  }
  /// Exact mode's chart coordinate of a post state, in [0, 1] (for coverage). The chart is
  /// defined on the closed half circle a.w >= 0 (a grazing state gives 0 or 1); throws
  /// InvalidArgument, naming the problem, for a velocity the operators refuse (not finite,
  /// zero or too small a relative speed) and for an approaching state (a.w < 0), where the
  /// formula would give a number outside the chart (flux: 0.5 head-on; uniform: beyond [0, 1]).
  double chart(const PairV<2>& post, const std::array<double, 2>& n) const {
    const Frame2 f(n);
    const auto w = relative(post);
    const double n2 = w[0] * w[0] + w[1] * w[1];
    const double cm[2] = {0.5 * (post.i[0] + post.j[0]), 0.5 * (post.i[1] + post.j[1])};
    require_speed_range(post, w, n2, cm);
    const double p = f.normal_part(w);
    require(p >= 0.0, [&] {
      char num[32];
      std::snprintf(num, sizeof num, "%.6g", p);
      return std::string("chart: the state approaches along the contact normal (normal relative velocity ") + num +
             " < 0): the chart is defined on post-collision states, a.w >= 0";
    });
    return exact_.chart(p, f.tangent_part(w), std::sqrt(n2));
  }

 private:
  Mode mode_;
  Pair2DExact exact_;
  Pair2DPaper paper_;
  RareLog log_;
};

}  // namespace revcol
