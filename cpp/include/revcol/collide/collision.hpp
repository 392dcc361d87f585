// The exact operator with its own rare log, over batches of collisions of one geometry: what
// the Python API holds. A batch is validated whole before anything changes (batch.hpp's rule).
#pragma once
#include <cstddef>
#include <string>
#include <vector>

#include "revcol/collide/exact.hpp"

namespace revcol {

/// ExactCollision + RareLog, batched. Velocities: B x n x d; draws: B x d_n; held: B or none.
class Collision {
 public:
  /// Wraps an operator (a geometry).
  explicit Collision(ExactCollision op) : op_(std::move(op)) {}
  const ExactCollision& op() const { return op_; }  ///< the operator
  RareLog& log() { return log_; }                   ///< the rare log
  const RareLog& log() const { return log_; }       ///< the rare log

  /// Forward over entries 0..B-1 with draws g (B x d_n).
  void forward(const double* v, std::size_t B, const double* g, double* out,
               const Held* held = nullptr) {
    const std::size_t nd = op_.particles() * op_.dim(), k = op_.draws();
    check_pre(v, B, held);
    for (std::size_t b = 0; b < B * k; ++b)
      require(g[b] >= 0.0 && g[b] <= 1.0, "random numbers must be in [0,1]");
    for (std::size_t b = 0; b < B; ++b)
      op_.forward(v + b * nd, g + b * k, out + b * nd, log_, held ? held + b : nullptr);
  }
  /// Reverse over entries B-1..0 with the draws forward used.
  void reverse(const double* v, std::size_t B, const double* g, double* out,
               const Held* held = nullptr) {
    const std::size_t nd = op_.particles() * op_.dim(), k = op_.draws();
    check_post(v, B, held);
    for (std::size_t b = 0; b < B * k; ++b)
      require(g[b] >= 0.0 && g[b] <= 1.0, "random numbers must be in [0,1]");
    for (std::size_t b = B; b-- > 0;)
      op_.reverse(v + b * nd, g + b * k, out + b * nd, log_, held ? held + b : nullptr);
  }
  /// Forward drawing d_n numbers per entry from gen (entry order) after validating all.
  template <class Gen>
  void forward(const double* v, std::size_t B, Gen& gen, double* out, const Held* held = nullptr) {
    check_pre(v, B, held);
    std::vector<double> g(B * op_.draws());
    for (double& x : g) x = gen.next();
    forward(v, B, g.data(), out, held);
  }
  /// Reverse stepping gen back (last entry, last draw first) after validating all.
  template <class Gen>
  void reverse(const double* v, std::size_t B, Gen& gen, double* out, const Held* held = nullptr) {
    check_post(v, B, held);
    std::vector<double> g(B * op_.draws());
    for (std::size_t x = g.size(); x-- > 0;) g[x] = gen.prev();
    reverse(v, B, g.data(), out, held);
  }

 private:
  void check_pre(const double* v, std::size_t B, const Held* held) const {
    const std::size_t nd = op_.particles() * op_.dim();
    for (std::size_t b = 0; b < B; ++b) {
      try {
        op_.check_pre(v + b * nd, held ? held + b : nullptr);
      } catch (const InvalidArgument& e) {
        throw InvalidArgument("entry " + std::to_string(b) + ": " + e.what());
      }
    }
  }
  void check_post(const double* v, std::size_t B, const Held* held) const {
    const std::size_t nd = op_.particles() * op_.dim();
    std::size_t pops = 0;
    for (std::size_t b = 0; b < B; ++b) {
      try {
        op_.check_post(v + b * nd, held ? held + b : nullptr);
      } catch (const InvalidArgument& e) {
        throw InvalidArgument("entry " + std::to_string(b) + ": " + e.what());
      }
      if (op_.logs(v + b * nd)) pops += op_.draws();
    }
    require(pops <= log_.size(), [&] {
      return "rare log holds " + std::to_string(log_.size()) + " cells but this batch needs " +
             std::to_string(pops);
    });
  }

  ExactCollision op_;
  RareLog log_;
};

}  // namespace revcol
