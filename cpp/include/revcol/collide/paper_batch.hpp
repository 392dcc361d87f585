// Batches of independent collisions for the paper-mode operators with several draws
// (Pair3DPaper, Triple1DPaper, Triple2DPaper), the analogue of batch.hpp: everything is
// validated before anything changes (a bad entry throws InvalidArgument naming its index,
// and no velocity, generator or log has moved). Entry b uses draws g[b][0..d_n-1]; from a
// generator they are drawn in entry order, and reverse steps back last entry, last draw first.
#pragma once
#include <cstddef>
#include <string>
#include <vector>

#include "revcol/collide/common.hpp"

namespace revcol::paper {

namespace detail {
template <class Op>
void validate(const Op& op, const typename Op::State* v, const typename Op::Geometry* x,
              std::size_t B, const typename Op::Draws* g, const typename Op::Inv* inv, bool post,
              const RareLog* log) {
  std::size_t pops = 0;
  for (std::size_t b = 0; b < B; ++b) {
    try {
      if (post) op.check_post(v[b], x[b], inv ? inv + b : nullptr);
      else op.check_pre(v[b], x[b], inv ? inv + b : nullptr);
      if (g)
        for (double gk : g[b]) require(gk >= 0.0 && gk <= 1.0, "random numbers must be in [0,1]");
    } catch (const InvalidArgument& e) {
      throw InvalidArgument("entry " + std::to_string(b) + ": " + e.what());
    }
    if (post) pops += op.logs(v[b], x[b]) ? 1 : 0;
  }
  if (log)
    require(pops <= log->size(), [&] {
      return "rare log holds " + std::to_string(log->size()) + " entries but this batch needs " +
             std::to_string(pops);
    });
}
}  // namespace detail

/// Forward over entries 0..B-1 with draws g[b]; `inv` is null or B invariants.
template <class Op>
void forward_batch(const Op& op, typename Op::State* v, const typename Op::Geometry* x,
                   std::size_t B, const typename Op::Draws* g, RareLog& log,
                   const typename Op::Inv* inv = nullptr) {
  detail::validate(op, v, x, B, g, inv, false, nullptr);
  for (std::size_t b = 0; b < B; ++b) v[b] = op.forward(v[b], x[b], g[b], log, inv ? inv + b : nullptr);
}

/// Reverse of forward_batch: entries B-1..0 with the same draws, popping the log.
template <class Op>
void reverse_batch(const Op& op, typename Op::State* v, const typename Op::Geometry* x,
                   std::size_t B, const typename Op::Draws* g, RareLog& log,
                   const typename Op::Inv* inv = nullptr) {
  detail::validate(op, v, x, B, g, inv, true, &log);
  for (std::size_t b = B; b-- > 0;) v[b] = op.reverse(v[b], x[b], g[b], log, inv ? inv + b : nullptr);
}

/// Validates, then draws B x d_n numbers from gen (entry order) and runs forward_batch.
template <class Op, class Gen>
void forward_batch(const Op& op, typename Op::State* v, const typename Op::Geometry* x,
                   std::size_t B, Gen& gen, RareLog& log, const typename Op::Inv* inv = nullptr) {
  detail::validate<Op>(op, v, x, B, nullptr, inv, false, nullptr);
  std::vector<typename Op::Draws> g(B);
  for (std::size_t b = 0; b < B; ++b)
    for (double& gk : g[b]) gk = gen.next();
  forward_batch(op, v, x, B, g.data(), log, inv);
}

/// Validates, then steps gen back B x d_n numbers (last first) and runs reverse_batch.
template <class Op, class Gen>
void reverse_batch(const Op& op, typename Op::State* v, const typename Op::Geometry* x,
                   std::size_t B, Gen& gen, RareLog& log, const typename Op::Inv* inv = nullptr) {
  detail::validate<Op>(op, v, x, B, nullptr, inv, true, &log);
  std::vector<typename Op::Draws> g(B);
  for (std::size_t b = B; b-- > 0;)
    for (std::size_t k = g[b].size(); k-- > 0;) g[b][k] = gen.prev();
  reverse_batch(op, v, x, B, g.data(), log, inv);
}

}  // namespace revcol::paper
