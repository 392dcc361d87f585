// Batches of independent pair collisions, for the Python API and the benchmarks. A batch is
// validated whole before anything changes: a bad entry throws InvalidArgument naming its
// index, and no velocity, random number generator or log has moved.
#pragma once
#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "revcol/collide/common.hpp"
#include "revcol/collide/pair.hpp"

namespace revcol {

/// Forward over entries 0..B-1 in order with draws g[b]; `inv` is null or B invariants.
template <class Op>
void forward_batch(const Op& op, PairV<2>* v, const std::array<double, 2>* n, std::size_t B,
                   const double* g, RareLog& log, const Invariants<2>* inv = nullptr) {
  for (std::size_t b = 0; b < B; ++b) {
    try {
      op.check_pre(v[b], n[b], inv ? inv + b : nullptr);
      require(g[b] >= 0.0 && g[b] <= 1.0, "random number must be in [0,1]");
    } catch (const InvalidArgument& e) {
      throw InvalidArgument("entry " + std::to_string(b) + ": " + e.what());
    }
  }
  for (std::size_t b = 0; b < B; ++b) v[b] = op.forward(v[b], n[b], g[b], log, inv ? inv + b : nullptr);
}

/// Reverse of forward_batch: entries B-1..0 with the same draws g[b], popping the log.
template <class Op>
void reverse_batch(const Op& op, PairV<2>* v, const std::array<double, 2>* n, std::size_t B,
                   const double* g, RareLog& log, const Invariants<2>* inv = nullptr) {
  std::size_t pops = 0;
  for (std::size_t b = 0; b < B; ++b) {
    try {
      op.check_post(v[b], n[b], inv ? inv + b : nullptr);
      require(g[b] >= 0.0 && g[b] <= 1.0, "random number must be in [0,1]");
    } catch (const InvalidArgument& e) {
      throw InvalidArgument("entry " + std::to_string(b) + ": " + e.what());
    }
    pops += op.logs(v[b], n[b]) ? 1 : 0;
  }
  require(pops <= log.size(), [&] { return std::string("rare log holds " + std::to_string(log.size()) +
                                  " entries but this batch needs " + std::to_string(pops)); });
  for (std::size_t b = B; b-- > 0;) v[b] = op.reverse(v[b], n[b], g[b], log, inv ? inv + b : nullptr);
}

/// Validates, then draws B numbers from gen (in entry order) and runs forward_batch.
template <class Op, class Gen>
void forward_batch(const Op& op, PairV<2>* v, const std::array<double, 2>* n, std::size_t B,
                   Gen& gen, RareLog& log, const Invariants<2>* inv = nullptr) {
  std::vector<double> g(B, 0.5);
  for (std::size_t b = 0; b < B; ++b) {
    try {
      op.check_pre(v[b], n[b], inv ? inv + b : nullptr);
    } catch (const InvalidArgument& e) {
      throw InvalidArgument("entry " + std::to_string(b) + ": " + e.what());
    }
  }
  for (std::size_t b = 0; b < B; ++b) g[b] = gen.next();
  forward_batch(op, v, n, B, g.data(), log, inv);
}

/// Validates, then steps gen back B numbers (last entry first) and runs reverse_batch.
template <class Op, class Gen>
void reverse_batch(const Op& op, PairV<2>* v, const std::array<double, 2>* n, std::size_t B,
                   Gen& gen, RareLog& log, const Invariants<2>* inv = nullptr) {
  std::size_t pops = 0;
  for (std::size_t b = 0; b < B; ++b) {
    try {
      op.check_post(v[b], n[b], inv ? inv + b : nullptr);
    } catch (const InvalidArgument& e) {
      throw InvalidArgument("entry " + std::to_string(b) + ": " + e.what());
    }
    pops += op.logs(v[b], n[b]) ? 1 : 0;
  }
  require(pops <= log.size(), [&] { return std::string("rare log holds " + std::to_string(log.size()) +
                                  " entries but this batch needs " + std::to_string(pops)); });
  std::vector<double> g(B);
  for (std::size_t b = B; b-- > 0;) g[b] = gen.prev();
  reverse_batch(op, v, n, B, g.data(), log, inv);
}

}  // namespace revcol
