// Philox4x32-10: the counter-based generator of J. K. Salmon, M. A. Moraes, R. O. Dror and
// D. E. Shaw, "Parallel random numbers: as easy as 1, 2, 3", SC'11 (Random123). Known
// answers: /work/shared/reference/rng-vectors.md (Random123's kat_vectors lines).
//
// A block is a bijection of a 128-bit counter c = (c0, c1, c2, c3) under a 64-bit key
// k = (k0, k1): ten rounds of
//   (hi0, lo0) = M0 * c0,  (hi1, lo1) = M1 * c2     (32 x 32 -> 64-bit products)
//   c <- (hi1 ^ c1 ^ k0,  lo1,  hi0 ^ c3 ^ k1,  lo0)
// with the key bumped by the Weyl constants (k0 += W0, k1 += W1, mod 2^32) between rounds;
// M0 = 0xD2511F53, M1 = 0xCD9E8D57, W0 = 0x9E3779B9, W1 = 0xBB67AE85.
//
// Draw k of a generator with key `key` is a pure function of (key, k): the block
//   (w0, w1, w2, w3) = philox4x32_10((lo32(k), hi32(k), 0, 0), key),
// 53 bits B = (w0 << 21) ^ (w1 >> 11) (all of w0, the top 21 bits of w1), and
//   u = (B + 1/2) 2^-53      evaluated in double: (double(B) + 0.5) * 0x1p-53.
// For B < 2^52 this is exact. Above, B + 1/2 needs 54 bits and rounds to even: B = 2j - 1
// and B = 2j both give u = 2j 2^-53 (a 2^-52 grid there, the mean preserved), and the one
// pattern B = 2^53 - 1 would round to exactly 1.0: it is returned as 1 - 2^-53 instead, so
// u is strictly inside (0, 1) always. Reversal is a counter decrement: prev() recomputes the undone draw.
#pragma once
#include <algorithm>
#include <array>
#include <cstdint>

#include "revcol/error.hpp"

namespace revcol::rng {

namespace detail {
/// Throws InvalidArgument(msg). Out of line of the hot paths: a `require(cond, "literal")`
/// there would build a std::string on every call, taken or not (measured: 3x slower).
[[noreturn]] inline void fail(const char* msg) { throw InvalidArgument(msg); }
}  // namespace detail

/// Random123 Philox4x32-10: one 128-bit block from a 4-word counter and a 2-word key.
constexpr std::array<std::uint32_t, 4> philox4x32_10(std::array<std::uint32_t, 4> counter,
                                                     std::array<std::uint32_t, 2> key) noexcept {
  constexpr std::uint64_t M0 = 0xD2511F53U, M1 = 0xCD9E8D57U;
  constexpr std::uint32_t W0 = 0x9E3779B9U, W1 = 0xBB67AE85U;
  std::array<std::uint32_t, 4> c = counter;
  std::uint32_t k0 = key[0], k1 = key[1];
  for (int round = 0; round < 10; ++round) {
    if (round > 0) {
      k0 += W0;
      k1 += W1;
    }
    const std::uint64_t p0 = M0 * c[0];
    const std::uint64_t p1 = M1 * c[2];
    c = {static_cast<std::uint32_t>(p1 >> 32) ^ c[1] ^ k0, static_cast<std::uint32_t>(p1),
         static_cast<std::uint32_t>(p0 >> 32) ^ c[3] ^ k1, static_cast<std::uint32_t>(p0)};
  }
  return c;
}

/// Counter-based Philox4x32-10 stream: draw k is a pure function of (key, k).
class Philox {
 public:
  /// The 64-bit key (k0, k1): which stream.
  using Key = std::array<std::uint32_t, 2>;
  /// Doubles consumed per next(): one (a trait the stream layer reads).
  static constexpr int draws_per_next = 1;

  /// A stream with this key, positioned so that the next draw is draw `counter`.
  explicit Philox(Key key = {0, 0}, std::uint64_t counter = 0) noexcept : key_(key), counter_(counter) {}

  /// Returns draw at(counter) and advances the counter (modulo 2^64).
  double next() noexcept { return at(counter_++); }

  /// Steps the counter back and returns that draw, i.e. the value the last next() returned;
  /// throws InvalidArgument (nothing changed) at counter 0.
  double prev() {
    if (counter_ == 0) [[unlikely]] detail::fail("Philox: cannot step back before draw 0");
    --counter_;
    return at(counter_);
  }

  /// Draw k in (0, 1): (B + 1/2) 2^-53 from the 53 bits B of block (lo32(k), hi32(k), 0, 0).
  double at(std::uint64_t k) const noexcept {
    const auto w = philox4x32_10({static_cast<std::uint32_t>(k), static_cast<std::uint32_t>(k >> 32), 0U, 0U}, key_);
    return to_open_unit((std::uint64_t{w[0]} << 21) ^ (w[1] >> 11));
  }

  /// (B + 1/2) 2^-53 for 53 bits B, in double, capped at 1 - 2^-53 (see the header comment).
  static constexpr double to_open_unit(std::uint64_t bits53) noexcept {
    return std::min((static_cast<double>(bits53) + 0.5) * 0x1p-53, 0x1.fffffffffffffp-1);
  }

  /// Index of the next draw.
  std::uint64_t counter() const noexcept { return counter_; }
  /// Repositions the stream: the next draw is draw `counter`.
  void set_counter(std::uint64_t counter) noexcept { counter_ = counter; }
  /// The key.
  Key key() const noexcept { return key_; }

  /// Same key and counter.
  friend bool operator==(const Philox& a, const Philox& b) noexcept {
    return a.key_ == b.key_ && a.counter_ == b.counter_;
  }

 private:
  Key key_;
  std::uint64_t counter_;
};

}  // namespace revcol::rng
