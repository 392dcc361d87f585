// The exact operator with its own rare log, over batches of collisions of one geometry: what
// the Python API holds. Batches run through batch.hpp's one template (validate every entry,
// then draw, then apply), through the adapter ExactEntries for ExactCollision's flat arrays.
#pragma once
#include <cstddef>
#include <utility>

#include "revcol/collide/batch.hpp"
#include "revcol/collide/exact.hpp"

namespace revcol {

namespace batch {
/// B entries of ExactCollision: velocities B x n x d in, results B x n x d out, held or none.
class ExactEntries {
 public:
  /// The operator, B inputs at v, B outputs at out, null or B held invariants.
  ExactEntries(const ExactCollision& op, const double* v, std::size_t B, double* out, const Held* held)
      : op_(op), v_(v), out_(out), B_(B), nd_(static_cast<std::size_t>(op.particles() * op.dim())), held_(held) {}
  std::size_t size() const { return B_; }                                        ///< B
  std::size_t draws() const { return static_cast<std::size_t>(op_.draws()); }   ///< d_n
  /// Throws InvalidArgument unless entry b is a valid pre (forward) or post (reverse) state.
  void check(std::size_t b, Dir dir) const {
    if (dir == Dir::forward) op_.check_pre(v_ + b * nd_, held(b));
    else op_.check_post(v_ + b * nd_, held(b));
  }
  /// Log entries (cells, d_n per logged collision) reversing entry b pops.
  std::size_t pops(std::size_t b) const { return op_.logs(v_ + b * nd_) ? draws() : 0; }
  /// Entry b through the operator with draws g[0..d_n).
  void apply(std::size_t b, const double* g, RareLog& log, Dir dir) {
    if (dir == Dir::forward) op_.forward(v_ + b * nd_, g, out_ + b * nd_, log, held(b));
    else op_.reverse(v_ + b * nd_, g, out_ + b * nd_, log, held(b));
  }

 private:
  const Held* held(std::size_t b) const { return held_ ? held_ + b : nullptr; }
  const ExactCollision& op_;
  const double* v_;
  double* out_;
  std::size_t B_, nd_;
  const Held* held_;
};
}  // namespace batch

/// ExactCollision + RareLog, batched. Velocities: B x n x d; draws: B x d_n; held: B or none.
class Collision {
 public:
  /// Wraps an operator (a geometry).
  explicit Collision(ExactCollision op) : op_(std::move(op)) {}
  const ExactCollision& op() const { return op_; }  ///< the operator
  RareLog& log() { return log_; }                   ///< the rare log
  const RareLog& log() const { return log_; }       ///< the rare log

  /// Forward over entries 0..B-1 with draws g (B x d_n).
  void forward(const double* v, std::size_t B, const double* g, double* out, const Held* held = nullptr) {
    batch::ExactEntries a(op_, v, B, out, held);
    batch::run(a, g, log_, batch::Dir::forward);
  }
  /// Reverse over entries B-1..0 with the draws forward used.
  void reverse(const double* v, std::size_t B, const double* g, double* out, const Held* held = nullptr) {
    batch::ExactEntries a(op_, v, B, out, held);
    batch::run(a, g, log_, batch::Dir::reverse);
  }
  /// Forward drawing d_n numbers per entry from gen (entry order) after validating all.
  template <batch::Generator Gen>
  void forward(const double* v, std::size_t B, Gen& gen, double* out, const Held* held = nullptr) {
    batch::ExactEntries a(op_, v, B, out, held);
    batch::run(a, gen, log_, batch::Dir::forward);
  }
  /// Reverse stepping gen back (last entry, last draw first) after validating all.
  template <batch::Generator Gen>
  void reverse(const double* v, std::size_t B, Gen& gen, double* out, const Held* held = nullptr) {
    batch::ExactEntries a(op_, v, B, out, held);
    batch::run(a, gen, log_, batch::Dir::reverse);
  }

 private:
  ExactCollision op_;
  RareLog log_;
};

}  // namespace revcol
