// Helpers shared by the lattice operator tests (test_lattice_pair2d.cpp, test_lattice_pair3d.cpp):
// a seeded generator with 48-bit draws, a random bits-back integer of a given size, and the
// Kolmogorov-Smirnov p-value.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "revcol/error.hpp"
#include "revcol/lattice/bitsback.hpp"
#include "revcol/lattice/pair2d.hpp"

namespace lattice_test {

/// A seeded 64-bit Mersenne twister with the draws the tests need.
struct Rng {
  std::mt19937_64 gen;  ///< the generator
  explicit Rng(std::uint64_t seed) : gen(seed) {}
  double uni() { return std::uniform_real_distribution<double>(0.0, 1.0)(gen); }  ///< uniform [0, 1)
  std::uint64_t draw() { return gen() >> 16; }  ///< a 48-bit G
  /// A uniform integer in [lo, hi] (hi >= lo).
  std::int64_t range(std::int64_t lo, std::int64_t hi) {
    return lo + static_cast<std::int64_t>(gen() % static_cast<std::uint64_t>(hi - lo + 1));
  }
};

/// The rows of tests/data/lattice/<name> (known answers), split into words; '#' lines skipped.
inline std::vector<std::vector<std::string>> load(const char* name) {
  const std::string src = __FILE__;
  std::ifstream in(src.substr(0, src.rfind('/')) + "/../data/lattice/" + name);
  std::vector<std::vector<std::string>> out;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream words(line);
    out.emplace_back(std::istream_iterator<std::string>(words), std::istream_iterator<std::string>());
  }
  return out;
}

/// A random X of exactly `bits` bits.
inline revcol::lattice::BitsBack random_bits(std::mt19937_64& rng, int bits) {
  std::vector<std::uint64_t> w(static_cast<std::size_t>((bits + 63) / 64));
  for (auto& x : w) x = rng();
  w.back() |= 1ULL << ((bits - 1) % 64);
  if (bits % 64) w.back() &= (1ULL << (bits % 64)) - 1;
  return revcol::lattice::BitsBack(w);
}

/// The bit lengths of a snapshot's per-particle X, summed.
template <class Snapshot>
std::size_t total_bits(const Snapshot& s) {
  std::size_t b = 0;
  for (const auto& w : bits_per_particle(s)) b += revcol::lattice::BitsBack(w).bit_length();  // (by ADL: lattice/state.hpp)
  return b;
}

/// Kolmogorov's limiting p-value of the KS statistic d over n samples (Stephens' correction).
inline double ks_pvalue(double d, std::size_t n) {
  const double sn = std::sqrt(static_cast<double>(n));
  const double lam = (sn + 0.12 + 0.11 / sn) * d;
  double p = 0.0;
  for (int k = 1; k <= 100; ++k) p += 2.0 * ((k & 1) ? 1.0 : -1.0) * std::exp(-2.0 * k * k * lam * lam);
  return std::clamp(p, 0.0, 1.0);
}

}  // namespace lattice_test

namespace lattice_test {

/// What a chain of collisions of one fixed pre state did to X and how often it was refused.
struct ChainStats {
  long refusals = 0;       ///< draws the operator refused
  int bad = 0;             ///< spot-checked reverses that did not restore the pre state and X
  double bits_start = 0;   ///< X's size before
  double bits_min = 1e300; ///< X's smallest size after a collision
  double bits_max = 0;     ///< X's largest size after a collision
  double bits_end = 0;     ///< X's size after
};

/// n accepted collisions of one fixed pre state (q, w) through op.forward, X chained from a
/// random 256-bit start; every 997th draw's reverse is checked; post(w2) sees each post velocity.
template <class Op, class V, class Post>
ChainStats fixed_pre_chain(const Op& op, const V& q, const V& w, long n, Rng& rng, Post post) {
  ChainStats out;
  revcol::lattice::BitsBack X = random_bits(rng.gen, 256), X2;
  out.bits_start = static_cast<double>(X.bit_length());
  for (long k = 0, done = 0; done < n; ++k) {
    V q2, w2;
    const std::uint64_t g = rng.draw();
    if (op.forward(q, w, g, X, q2, w2, X2) != revcol::lattice::Refusal::none) {
      ++out.refusals;
      continue;
    }
    if (k % 997 == 0) {
      revcol::lattice::BitsBack Xb = X2;
      V qb, wb;
      op.reverse(q2, w2, g, Xb, qb, wb);
      if (!(qb == q && wb == w && Xb == X)) ++out.bad;
    }
    std::swap(X, X2);
    const double bits = static_cast<double>(X.bit_length());
    out.bits_min = std::min(out.bits_min, bits);
    out.bits_max = std::max(out.bits_max, bits);
    post(w2);
    ++done;
  }
  out.bits_end = static_cast<double>(X.bit_length());
  return out;
}

}  // namespace lattice_test

namespace lattice_test {

/// Reverse of a post state no forward produced, from a tiny X (pops may fail): 1 when it
/// answers, 0 when it throws InvalidArgument leaving X as it was, -1 when a throw changed X.
template <class Op, class V>
int reverse_or_clean_throw(const Op& op, const V& q2, const V& w2, Rng& rng) {
  revcol::lattice::BitsBack W(std::vector<std::uint64_t>{rng.gen() % 7});
  const revcol::lattice::BitsBack W0 = W;
  V a, b;
  try {
    op.reverse(q2, w2, rng.draw(), W, a, b);
    return 1;
  } catch (const revcol::InvalidArgument&) {
    return W == W0 ? 0 : -1;
  }
}

}  // namespace lattice_test
