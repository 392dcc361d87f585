// CLCG4: the reversible combined multiplicative linear congruential generator of
// P. L'Ecuyer and T. H. Andres, "A random number generator based on the combination of
// four LCGs", Mathematics and Computers in Simulation 44 (1997) 99-107, in the variant
// shipped by the ROSS simulator and used by the paper (section "Random Number Generation",
// \label{sec:rngstreams}). Known answers: /work/shared/reference/rng-vectors.md.
//
// Four components j = 0..3, each a multiplicative LCG modulo a prime m_j < 2^31:
//   forward   s_j <- a_j s_j mod m_j
//   backward  s_j <- b_j s_j mod m_j,   b_j = a_j^{-1} mod m_j
// and after each forward step the output
//   u = (s_0/m_0 - s_1/m_1 + s_2/m_2 - s_3/m_3) mod 1
// evaluated in double precision, term by term in that order, with a wrap after each of
// the last three terms (after s_1: u < 0 -> u += 1; after s_2: u >= 1 -> u -= 1; after s_3:
// u < 0 -> u += 1). "s_j/m_j" is evaluated as s_j * (1.0/m_j) with the reciprocal rounded
// to double once (the published code multiplies by 4.65661287524579692e-10 etc., which are
// exactly those rounded reciprocals); a true division differs in the last bit for some
// draws and does not reproduce the known-answer vectors. The output lies in [0, 1]: the
// rounding of the final "+1" can give exactly 1.0 (or 0.0) with probability ~2^-53.
//
// Streams: stream k starts at seed_j * a_j^(k 2^72) mod m_j, substream s of it at
// (start) * (a_j^(2^41))^s; the period of the combination is about 2^121, so streams are
// disjoint for k < 2^49. Reversal (the paper's RNG^-1): prev() returns the value the last
// next() returned, then steps every component back, so next(); prev(); is the identity.
//
// Hot path (measure before changing): the forward products a_j s_j < 2^49 are reduced with
// the pseudo-Mersenne identity 2^31 = c_j (mod m_j), m_j = 2^31 - c_j, c_j in {1, 105, 225,
// 325}: x = hi 2^31 + lo = hi c_j + lo (mod m_j), one fold and one conditional subtract
// (measured ~15% faster than `% m`). The backward products b_j s_j < 2^62 use `% m_j` by a
// constant, which the compiler turns into a multiply-high (measured ~15% faster than two
// folds). The output's wraps are branch-free (~2x faster than branches).
#pragma once
#include <array>
#include <bit>
#include <cstdint>

namespace revcol::rng {

namespace clcg4_detail {

/// (x * y) mod m for x, y < 2^32, m < 2^32; for set-up code, not the hot path.
constexpr std::uint32_t mulmod(std::uint64_t x, std::uint64_t y, std::uint64_t m) noexcept {
  return static_cast<std::uint32_t>((x % m) * (y % m) % m);
}

/// base^e mod m by binary exponentiation (64-bit products, m < 2^32).
constexpr std::uint32_t powmod(std::uint64_t base, std::uint64_t e, std::uint64_t m) noexcept {
  std::uint64_t result = 1 % m;
  std::uint64_t b = base % m;
  while (e != 0) {
    if (e & 1U) result = result * b % m;
    b = b * b % m;
    e >>= 1U;
  }
  return static_cast<std::uint32_t>(result);
}

/// base^(2^k) mod m: k successive squarings.
constexpr std::uint32_t pow_pow2(std::uint64_t base, int k, std::uint64_t m) noexcept {
  std::uint64_t b = base % m;
  for (int i = 0; i < k; ++i) b = b * b % m;
  return static_cast<std::uint32_t>(b);
}

/// x mod (2^31 - C) for x < 2^49 and 0 < C < 2^9: fold the bits above 2^31 down once
/// (2^31 = C mod m), giving < 2^31 + 2^27 < 2 m, then subtract m at most once.
template <std::uint64_t C>
constexpr std::uint32_t reduce(std::uint64_t x) noexcept {
  static_assert(C > 0 && C < 512);
  constexpr std::uint64_t m = (std::uint64_t{1} << 31) - C;
  constexpr std::uint64_t mask = (std::uint64_t{1} << 31) - 1;
  x = (x & mask) + (x >> 31) * C;
  return static_cast<std::uint32_t>(x >= m ? x - m : x);
}

}  // namespace clcg4_detail

/// L'Ecuyer-Andres CLCG4 with exact reversal; u in [0, 1] per rng-vectors.md.
class CLCG4 {
 public:
  /// The four component states s_j, each in [1, m_j - 1].
  using State = std::array<std::uint32_t, 4>;

  /// Moduli m_j = 2^31 - c_j (primes).
  static constexpr State modulus = {2147483647U, 2147483543U, 2147483423U, 2147483323U};
  /// Multipliers a_j.
  static constexpr State multiplier = {45991U, 207707U, 138556U, 49689U};
  /// Inverse multipliers b_j = a_j^-1 mod m_j (the backward step).
  static constexpr State inverse_multiplier = {1441196816U, 1463744518U, 499766181U, 660421676U};
  /// Start of stream 0 (L'Ecuyer-Andres default seed).
  static constexpr State default_seed = {11111111U, 22222222U, 33333333U, 44444444U};
  /// a_j^(2^72) mod m_j: the jump from the start of stream k to stream k + 1.
  static constexpr State stream_jump = {
      clcg4_detail::pow_pow2(45991U, 72, 2147483647U), clcg4_detail::pow_pow2(207707U, 72, 2147483543U),
      clcg4_detail::pow_pow2(138556U, 72, 2147483423U), clcg4_detail::pow_pow2(49689U, 72, 2147483323U)};
  /// a_j^(2^41) mod m_j: the jump from substream s to substream s + 1.
  static constexpr State substream_jump = {
      clcg4_detail::pow_pow2(45991U, 41, 2147483647U), clcg4_detail::pow_pow2(207707U, 41, 2147483543U),
      clcg4_detail::pow_pow2(138556U, 41, 2147483423U), clcg4_detail::pow_pow2(49689U, 41, 2147483323U)};
  /// Doubles consumed per next(): one (a trait the stream layer reads).
  static constexpr int draws_per_next = 1;

  /// Start of substream `substream` of stream `stream`: s_j = seed_j a_j^(stream 2^72 + substream 2^41) mod m_j.
  explicit CLCG4(std::uint64_t stream = 0, std::uint64_t substream = 0) noexcept {
    for (int j = 0; j < 4; ++j) {
      const std::uint64_t m = modulus[j];
      const std::uint32_t to_stream = clcg4_detail::powmod(stream_jump[j], stream, m);
      const std::uint32_t to_sub = clcg4_detail::powmod(substream_jump[j], substream, m);
      s_[j] = clcg4_detail::mulmod(clcg4_detail::mulmod(default_seed[j], to_stream, m), to_sub, m);
    }
  }

  /// Steps every component forward (s_j <- a_j s_j mod m_j) and returns the output u.
  double next() noexcept {
    s_[0] = clcg4_detail::reduce<1>(std::uint64_t{multiplier[0]} * s_[0]);
    s_[1] = clcg4_detail::reduce<105>(std::uint64_t{multiplier[1]} * s_[1]);
    s_[2] = clcg4_detail::reduce<225>(std::uint64_t{multiplier[2]} * s_[2]);
    s_[3] = clcg4_detail::reduce<325>(std::uint64_t{multiplier[3]} * s_[3]);
    return output(s_);
  }

  /// Returns the value the last next() returned (the output of the current state), then
  /// steps every component back (s_j <- b_j s_j mod m_j): next(); prev(); is the identity.
  double prev() noexcept {
    const double u = output(s_);
    s_[0] = static_cast<std::uint32_t>(std::uint64_t{inverse_multiplier[0]} * s_[0] % modulus[0]);
    s_[1] = static_cast<std::uint32_t>(std::uint64_t{inverse_multiplier[1]} * s_[1] % modulus[1]);
    s_[2] = static_cast<std::uint32_t>(std::uint64_t{inverse_multiplier[2]} * s_[2] % modulus[2]);
    s_[3] = static_cast<std::uint32_t>(std::uint64_t{inverse_multiplier[3]} * s_[3] % modulus[3]);
    return u;
  }

  /// The output u of a state (the value next() returns after arriving at it).
  static double output(const State& s) noexcept {
    // The wraps add +-1 or an exact 0.0 (u is never -0.0: every term is > 0 and x - x is
    // +0.0), which is the specification's conditional add, bit for bit, but compiles to a
    // compare-and-mask instead of a branch the CPU mispredicts half the time (measured:
    // ~2x faster). -ffp-contract=off keeps the products and sums separately rounded.
    double u = static_cast<double>(s[0]) * inv_m0;
    u -= static_cast<double>(s[1]) * inv_m1;
    u += one_if(u < 0.0);
    u += static_cast<double>(s[2]) * inv_m2;
    u -= one_if(u >= 1.0);
    u -= static_cast<double>(s[3]) * inv_m3;
    u += one_if(u < 0.0);
    return u;
  }

  /// The current state (s_0, s_1, s_2, s_3).
  State state() const noexcept { return s_; }

  /// Sets the state; throws InvalidArgument naming the component unless every s_j is in
  /// [1, m_j - 1], in which case nothing is changed.
  void set_state(const State& s);

  /// True when every s_j is in [1, m_j - 1].
  static bool valid_state(const State& s) noexcept {
    for (int j = 0; j < 4; ++j)
      if (s[j] < 1 || s[j] >= modulus[j]) return false;
    return true;
  }

  /// Equal states (hence equal futures and pasts).
  friend bool operator==(const CLCG4& a, const CLCG4& b) noexcept { return a.s_ == b.s_; }

 private:
  // 1.0 / m_j rounded once to double; they equal the published constants.
  static constexpr double inv_m0 = 1.0 / 2147483647.0;
  static constexpr double inv_m1 = 1.0 / 2147483543.0;
  static constexpr double inv_m2 = 1.0 / 2147483423.0;
  static constexpr double inv_m3 = 1.0 / 2147483323.0;
  static_assert(inv_m0 == 4.65661287524579692e-10 && inv_m1 == 4.65661310075985993e-10 &&
                inv_m2 == 4.65661336096842131e-10 && inv_m3 == 4.65661357780891134e-10);

  // 1.0 if c else 0.0, by masking the bits of 1.0 (no branch).
  static double one_if(bool c) noexcept {
    return std::bit_cast<double>(std::bit_cast<std::uint64_t>(1.0) & (std::uint64_t{0} - std::uint64_t{c}));
  }

  State s_{};
};

// The reduction constants c_j = 2^31 - m_j used by next().
static_assert(CLCG4::modulus[0] == (1U << 31) - 1 && CLCG4::modulus[1] == (1U << 31) - 105 &&
              CLCG4::modulus[2] == (1U << 31) - 225 && CLCG4::modulus[3] == (1U << 31) - 325);
static_assert(clcg4_detail::mulmod(45991U, 1441196816U, 2147483647U) == 1 &&
              clcg4_detail::mulmod(207707U, 1463744518U, 2147483543U) == 1 &&
              clcg4_detail::mulmod(138556U, 499766181U, 2147483423U) == 1 &&
              clcg4_detail::mulmod(49689U, 660421676U, 2147483323U) == 1);

}  // namespace revcol::rng
