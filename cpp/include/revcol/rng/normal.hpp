// A small deterministic normal generator for test states and studies: splitmix64 and
// Box-Muller (no <random>, whose distributions differ between standard libraries, so the same
// seed gives the same numbers on every platform). Not a reversible stream: the collisions'
// numbers come from Philox or CLCG4.
#pragma once
#include <cmath>
#include <cstdint>

namespace revcol::rng {

/// Normal deviates from a 64-bit state (splitmix64 words, Box-Muller).
struct SplitMixNormal {
  std::uint64_t s;  ///< the state; any value
  /// The next splitmix64 word.
  std::uint64_t bits() {
    std::uint64_t z = (s += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  /// Uniform in (0, 1): 53 bits at the cell centre.
  double uniform() { return (static_cast<double>(bits() >> 11) + 0.5) * 0x1.0p-53; }
  /// A standard normal deviate.
  double operator()() { return std::sqrt(-2.0 * std::log(uniform())) * std::cos(kTwoPi * uniform()); }
  /// 2 pi as a double (exactly twice the double nearest pi).
  static constexpr double kTwoPi = 6.283185307179586476925286766559005768;
};

}  // namespace revcol::rng
