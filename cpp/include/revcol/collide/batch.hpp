// Batches of independent collisions, for the Python API and the benchmarks: one template
// for every operator signature.
//
// A batch is validated whole before anything changes: every entry is checked (its state,
// its draws in [0,1], and for a reverse batch that the rare log holds what the entries
// will pop); a bad entry throws InvalidArgument naming its index, and no velocity, random
// number generator or log has moved. Only then are the draws taken (from a generator: in
// entry order, d_n per entry; a reverse batch steps the generator back, last entry and
// last draw first) and the operator applied (forward: entries 0..B-1; reverse: B-1..0).
//
// The loop (batch::run) is written once, over an adapter that knows how to check and apply
// entry b of one operator signature:
//   - PairEntries<Op>: state, geometry and held invariants per entry, the draws either one
//     double (Pair2DExact, Pair2DPaper) or std::array<double, d_n> (Pair3DExact,
//     Pair3DPaper, Triple1DPaper, Triple2DPaper); the types are read off Op::forward;
//   - ExactEntries (collision.hpp): ExactCollision's flat arrays, B x n x d velocities.
// Draws are always passed flat: B x d_n doubles, entry b's at g + b d_n.
#pragma once
#include <array>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <string>
#include <type_traits>
#include <vector>

#include "revcol/collide/common.hpp"
#include "revcol/collide/pair.hpp"
#include "revcol/error.hpp"

namespace revcol {

class Pair3DExact;

namespace batch {

/// Which way a batch runs.
enum class Dir { forward, reverse };

/// A reversible generator: next() draws, prev() steps back.
template <class G>
concept Generator = requires(G& g) {
  { g.next() } -> std::convertible_to<double>;
  { g.prev() } -> std::convertible_to<double>;
};

/// What run() needs of B entries of one operator (see the header comment).
template <class A>
concept Entries = requires(A& a, const A& ca, std::size_t b, const double* g, RareLog& log) {
  { ca.size() } -> std::convertible_to<std::size_t>;   // B
  { ca.draws() } -> std::convertible_to<std::size_t>;  // d_n per entry
  ca.check(b, Dir::forward);                           // throws InvalidArgument, changes nothing
  { ca.pops(b) } -> std::convertible_to<std::size_t>;  // log entries reversing entry b pops
  a.apply(b, g, log, Dir::forward);                    // the operator on entry b, draws g[0..d_n)
};

/// Throws InvalidArgument ("entry b: ...") unless every entry (and, with `draws`, its draws)
/// is valid for `dir`, and, for a reverse batch, the log holds what the entries pop.
template <Entries A>
void check_all(const A& a, const double* g, bool draws, const RareLog& log, Dir dir) {
  const std::size_t B = a.size(), k = a.draws();
  const char* range = k == 1 ? "random number must be in [0,1]" : "random numbers must be in [0,1]";
  std::size_t pops = 0;
  for (std::size_t b = 0; b < B; ++b) {
    try {
      a.check(b, dir);
      if (draws)
        for (std::size_t j = 0; j < k; ++j) require(g[b * k + j] >= 0.0 && g[b * k + j] <= 1.0, range);
    } catch (const InvalidArgument& e) {
      throw InvalidArgument("entry " + std::to_string(b) + ": " + e.what());
    }
    if (dir == Dir::reverse) pops += a.pops(b);
  }
  if (dir == Dir::reverse)
    require(pops <= log.size(), [&] {
      return "rare log holds " + std::to_string(log.size()) + " entries but this batch needs " +
             std::to_string(pops);
    });
}

/// Applies the operator to every entry (forward 0..B-1, reverse B-1..0); draws g flat.
template <Entries A>
void apply_all(A& a, const double* g, RareLog& log, Dir dir) {
  const std::size_t B = a.size(), k = a.draws();
  if (dir == Dir::forward)
    for (std::size_t b = 0; b < B; ++b) a.apply(b, g + b * k, log, dir);
  else
    for (std::size_t b = B; b-- > 0;) a.apply(b, g + b * k, log, dir);
}

/// Validates everything, then runs the batch with the given draws (B x d_n, flat).
template <Entries A>
void run(A& a, const double* g, RareLog& log, Dir dir) {
  check_all(a, g, true, log, dir);
  apply_all(a, g, log, dir);
}

/// Validates everything (a reverse batch: also that a counter generator can step back all its
/// draws), then draws B x d_n numbers from gen (reverse: steps it back, last entry and last
/// draw first) and runs the batch.
template <Entries A, Generator Gen>
void run(A& a, Gen& gen, RareLog& log, Dir dir) {
  check_all(a, nullptr, false, log, dir);
  std::vector<double> g(a.size() * a.draws());
  if constexpr (requires { { gen.counter() } -> std::convertible_to<std::uint64_t>; })
    if (dir == Dir::reverse)  // a counter generator cannot step back before draw 0: say so first
      require(gen.counter() >= g.size(), [&] {
        return "rng counter is " + std::to_string(gen.counter()) + " but reversing this batch steps back " +
               std::to_string(g.size()) + " draws (the generator cannot go before draw 0)";
      });
  if (dir == Dir::forward)
    for (double& x : g) x = gen.next();
  else
    for (std::size_t x = g.size(); x-- > 0;) g[x] = gen.prev();
  apply_all(a, g.data(), log, dir);
}

/// The types of an operator's forward(const State&, const Geometry&, Draws, RareLog&, const Inv*).
template <class F>
struct Signature;
template <class C, class R, class S, class X, class G, class I>
struct Signature<R (C::*)(const S&, const X&, G, RareLog&, const I*) const> {
  using State = S;                          ///< velocities of one collision
  using Geometry = X;                       ///< contact normal or positions
  using Draws = std::remove_cvref_t<G>;     ///< double, or std::array<double, d_n>
  using Inv = I;                            ///< held invariants
};
/// Signature of Op::forward.
template <class Op>
using OpTypes = Signature<decltype(&Op::forward)>;

/// Log entries one logged reverse pops: one, except Pair3DExact's two cells.
template <class Op>
inline constexpr std::size_t log_entries = std::is_same_v<Op, Pair3DExact> ? 2 : 1;

/// B entries of an operator with per-entry state, geometry and held invariants.
template <class Op>
class PairEntries {
 public:
  using T = OpTypes<Op>;
  /// The operator, B states (changed in place), B geometries, null or B invariants.
  PairEntries(const Op& op, typename T::State* v, const typename T::Geometry* x, std::size_t B,
              const typename T::Inv* inv)
      : op_(op), v_(v), x_(x), B_(B), inv_(inv) {}
  std::size_t size() const { return B_; }                          ///< B
  std::size_t draws() const { return static_cast<std::size_t>(Op::draws); }  ///< d_n
  /// Throws InvalidArgument unless entry b is a valid pre (forward) or post (reverse) state.
  void check(std::size_t b, Dir dir) const {
    if (dir == Dir::forward) op_.check_pre(v_[b], x_[b], inv(b));
    else op_.check_post(v_[b], x_[b], inv(b));
  }
  /// Log entries reversing entry b pops.
  std::size_t pops(std::size_t b) const { return op_.logs(v_[b], x_[b]) ? log_entries<Op> : 0; }
  /// Entry b through the operator with draws g[0..d_n).
  void apply(std::size_t b, const double* g, RareLog& log, Dir dir) {
    typename T::Draws d;
    if constexpr (std::is_same_v<typename T::Draws, double>) d = g[0];
    else
      for (std::size_t j = 0; j < d.size(); ++j) d[j] = g[j];
    v_[b] = dir == Dir::forward ? op_.forward(v_[b], x_[b], d, log, inv(b))
                                : op_.reverse(v_[b], x_[b], d, log, inv(b));
  }

 private:
  const typename T::Inv* inv(std::size_t b) const { return inv_ ? inv_ + b : nullptr; }
  const Op& op_;
  typename T::State* v_;
  const typename T::Geometry* x_;
  std::size_t B_;
  const typename T::Inv* inv_;
};

}  // namespace batch

/// Forward over entries 0..B-1; `inv` is null or B invariants. The draws come from `src`:
/// B x d_n doubles (flat, const double*), or a generator (drawn in entry order).
template <class Op, class Src>
void forward_batch(const Op& op, typename batch::OpTypes<Op>::State* v,
                   const typename batch::OpTypes<Op>::Geometry* x, std::size_t B, Src&& src,
                   RareLog& log, const typename batch::OpTypes<Op>::Inv* inv = nullptr) {
  batch::PairEntries<Op> a(op, v, x, B, inv);
  batch::run(a, src, log, batch::Dir::forward);
}

/// Reverse of forward_batch: entries B-1..0 with the same draws (a generator steps back,
/// last entry and last draw first), popping the log.
template <class Op, class Src>
void reverse_batch(const Op& op, typename batch::OpTypes<Op>::State* v,
                   const typename batch::OpTypes<Op>::Geometry* x, std::size_t B, Src&& src,
                   RareLog& log, const typename batch::OpTypes<Op>::Inv* inv = nullptr) {
  batch::PairEntries<Op> a(op, v, x, B, inv);
  batch::run(a, src, log, batch::Dir::reverse);
}

}  // namespace revcol
