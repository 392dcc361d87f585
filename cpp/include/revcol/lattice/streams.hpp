// Each lattice particle's own random stream and initial bits-back integer (ARCHITECTURE.md,
// "Per-particle state"): Philox4x32-10 keyed by {particle id, seed}, so a particle's draws do
// not depend on where it is stored or which other particles exist.
#pragma once
#include <cstdint>
#include <vector>

#include "revcol/rng/philox.hpp"

namespace revcol::lattice {

/// The 48-bit draw k of particle p's stream: Philox4x32-10 block (lo32(k), hi32(k), 0, 0) under
/// key {p, seed}, bits w0 (32) and the top 16 of w1.
inline std::uint64_t draw48(std::uint32_t p, std::uint32_t seed, std::uint64_t k) noexcept {
  const auto w = rng::philox4x32_10({static_cast<std::uint32_t>(k), static_cast<std::uint32_t>(k >> 32), 0U, 0U}, {p, seed});
  return (std::uint64_t{w[0]} << 16) | (w[1] >> 16);
}
/// The 128 initial bits of particle p's X: Philox4x32-10 block (0, 0, 1, 0) under key {p, seed}
/// (no draw48 block has a nonzero third word), top bit set (exactly 128 bits).
std::vector<std::uint64_t> initial_bits(std::uint32_t p, std::uint32_t seed);

}  // namespace revcol::lattice
