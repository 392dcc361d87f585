// Random-number stream policies for reversible collisions (paper section "Random Number
// Generation", \label{sec:rngstreams}). Every collision of n particles in d dimensions
// draws exactly d_n numbers, unconditionally, so its reversal undoes exactly d_n draws
// (k = d_n - 1 down to 0) and the streams return to their pre-collision positions.
// Three ways to assign draws to streams:
//   single        one generator for the whole system (needs a long period);
//   per_particle  one generator per particle id 0..N-1; a collision draws from the stream
//                 of the smallest particle id taking part;
//   per_draw      d_n generators; the k-th number of every collision comes from stream k.
// A seed picks a disjoint family of `count` generators (count = 1, N or d_n):
//   CLCG4   generator i is stream  seed * count + i   (streams are 2^72 draws apart);
//   Philox  generator i has key    {i, seed}          (independent counter spaces).
// Add a generator type by specializing generator_traits<Gen>.
#pragma once
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "revcol/error.hpp"
#include "revcol/rng/clcg4.hpp"
#include "revcol/rng/philox.hpp"

namespace revcol::rng {

/// How the draws of collisions are assigned to generators (paper section 4.6).
enum class StreamPolicy { single, per_particle, per_draw };

/// "single", "per_particle" or "per_draw".
constexpr std::string_view to_string(StreamPolicy p) noexcept {
  switch (p) {
    case StreamPolicy::single: return "single";
    case StreamPolicy::per_particle: return "per_particle";
    case StreamPolicy::per_draw: return "per_draw";
  }
  return "?";
}

/// Parses "single", "per_particle" or "per_draw"; throws InvalidArgument otherwise.
inline StreamPolicy stream_policy_from_string(std::string_view name) {
  if (name == "single") return StreamPolicy::single;
  if (name == "per_particle") return StreamPolicy::per_particle;
  if (name == "per_draw") return StreamPolicy::per_draw;
  throw InvalidArgument("unknown stream policy '" + std::string(name) +
                        "' (expected single, per_particle or per_draw)");
}

/// How to build generator i of the family chosen by `seed` (count generators in all).
template <class Gen>
struct generator_traits;  // specialize: static Gen make(i, seed, count); static std::vector<Gen> family(seed, count)

/// CLCG4: generator i of family `seed` is stream seed * count + i.
template <>
struct generator_traits<CLCG4> {
  /// The stream index seed * count + i; throws InvalidArgument on 64-bit overflow.
  static std::uint64_t stream_index(std::uint64_t i, std::uint64_t seed, std::uint64_t count) {
    require(count == 0 || seed <= (std::numeric_limits<std::uint64_t>::max() - i) / count,
            "CLCG4 stream index seed * count + i overflows 64 bits");
    return seed * count + i;
  }
  /// Generator i of family `seed`.
  static CLCG4 make(std::uint64_t i, std::uint64_t seed, std::uint64_t count) {
    return CLCG4(stream_index(i, seed, count));
  }
  /// All count generators of family `seed`: one modular power, then one jump per stream.
  static std::vector<CLCG4> family(std::uint64_t seed, std::uint64_t count) {
    std::vector<CLCG4> out;
    if (count == 0) return out;
    out.reserve(count);
    out.push_back(make(0, seed, count));
    (void)stream_index(count - 1, seed, count);  // the last index must not overflow either
    CLCG4::State s = out.back().state();
    for (std::uint64_t i = 1; i < count; ++i) {
      for (int j = 0; j < 4; ++j) s[j] = clcg4_detail::mulmod(s[j], CLCG4::stream_jump[j], CLCG4::modulus[j]);
      CLCG4 g;
      g.set_state(s);
      out.push_back(g);
    }
    return out;
  }
};

/// Philox: generator i of family `seed` has key {i, seed}, counter 0.
template <>
struct generator_traits<Philox> {
  /// Generator i of family `seed`; both must fit in 32 bits (else InvalidArgument).
  static Philox make(std::uint64_t i, std::uint64_t seed, std::uint64_t /*count*/) {
    require(i <= std::numeric_limits<std::uint32_t>::max(), "Philox stream index must be < 2^32");
    require(seed <= std::numeric_limits<std::uint32_t>::max(), "Philox seed must be < 2^32");
    return Philox({static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(seed)}, 0);
  }
  /// All count generators of family `seed`.
  static std::vector<Philox> family(std::uint64_t seed, std::uint64_t count) {
    std::vector<Philox> out;
    if (count == 0) return out;
    (void)make(count - 1, seed, count);  // validate once
    out.reserve(count);
    for (std::uint64_t i = 0; i < count; ++i) out.push_back(make(i, seed, count));
    return out;
  }
};

/// Generator i of the family chosen by `seed`, in a policy with `count` generators.
template <class Gen>
Gen make_generator(std::uint64_t i, std::uint64_t seed, std::uint64_t count) {
  return generator_traits<Gen>::make(i, seed, count);
}

/// The generators of one stream policy, addressed by (smallest particle id, draw index k).
template <class Gen>
class Streams {
 public:
  /// Builds the family `seed`: 1 generator (single), n_particles (per_particle) or
  /// draws_per_collision (per_draw). draws_per_collision = d_n >= 0.
  Streams(StreamPolicy policy, std::uint64_t seed, std::size_t n_particles, int draws_per_collision)
      : policy_(policy), seed_(seed), n_particles_(n_particles), draws_(draws_per_collision) {
    require(draws_per_collision >= 0, "draws_per_collision must be >= 0");
    require(policy == StreamPolicy::single || policy == StreamPolicy::per_particle ||
                policy == StreamPolicy::per_draw,
            "unknown stream policy");
    const std::size_t count = policy == StreamPolicy::single         ? 1
                              : policy == StreamPolicy::per_particle ? n_particles
                                                                     : static_cast<std::size_t>(draws_per_collision);
    gens_ = generator_traits<Gen>::family(seed, count);
  }

  /// Index of the generator that serves draw k of a collision with this smallest particle
  /// id; throws InvalidArgument if k is outside [0, d_n) or (per_particle) the id >= N.
  std::size_t stream_index(std::size_t min_particle_id, int k) const {
    if (k < 0 || k >= draws_) [[unlikely]] detail::fail("Streams: draw index k outside [0, draws_per_collision)");
    switch (policy_) {
      case StreamPolicy::single: return 0;
      case StreamPolicy::per_particle:
        if (min_particle_id >= n_particles_) [[unlikely]] detail::fail("Streams: particle id outside [0, n_particles)");
        return min_particle_id;
      case StreamPolicy::per_draw: return static_cast<std::size_t>(k);
    }
    return 0;
  }

  /// The k-th draw (k = 0..d_n-1) of a collision whose smallest particle id is min_particle_id.
  double next(std::size_t min_particle_id, int k) { return gens_[stream_index(min_particle_id, k)].next(); }

  /// Undoes that draw and returns its value (callers undo k = d_n-1 down to 0).
  double prev(std::size_t min_particle_id, int k) { return gens_[stream_index(min_particle_id, k)].prev(); }

  /// The policy.
  StreamPolicy policy() const noexcept { return policy_; }
  /// The seed (which disjoint family).
  std::uint64_t seed() const noexcept { return seed_; }
  /// Number of particles given at construction.
  std::size_t n_particles() const noexcept { return n_particles_; }
  /// d_n, the draws per collision.
  int draws_per_collision() const noexcept { return draws_; }
  /// Number of generators.
  std::size_t size() const noexcept { return gens_.size(); }
  /// Generator i (0 <= i < size()).
  Gen& generator(std::size_t i) {
    if (i >= gens_.size()) [[unlikely]] detail::fail("Streams: generator index outside [0, size())");
    return gens_[i];
  }
  /// Generator i (0 <= i < size()).
  const Gen& generator(std::size_t i) const {
    if (i >= gens_.size()) [[unlikely]] detail::fail("Streams: generator index outside [0, size())");
    return gens_[i];
  }

 private:
  StreamPolicy policy_;
  std::uint64_t seed_;
  std::size_t n_particles_;
  int draws_;
  std::vector<Gen> gens_;
};

}  // namespace revcol::rng
