// A fixed pool of random approaching pair states for the pair-operator benchmarks
// (pair3d_bench.cpp, floor_bench.cpp): the same states in every repeat and for every operator
// timed on them, as an event-driven gas hands them over.
#pragma once
#include <array>
#include <cstdint>
#include <random>
#include <vector>

#include "revcol/collide/pair.hpp"

namespace revcol::bench {

/// One pre-collision state in D dimensions: velocities, a contact normal, D - 1 draws.
template <int D>
struct PairState {
  PairV<D> pre;
  std::array<double, D> n;
  std::array<double, D - 1> g;
};

/// P states from `seed`: standard normal velocities and normal (redrawn until the pair
/// approaches along it), uniform draws.
template <int D>
std::vector<PairState<D>> approaching_pool(std::size_t P, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> N(0.0, 1.0);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::vector<PairState<D>> pool(P);
  for (PairState<D>& s : pool) {
    for (;;) {
      double p = 0.0;
      for (int k = 0; k < D; ++k) {
        s.pre.i[k] = N(rng);
        s.pre.j[k] = N(rng);
        s.n[k] = N(rng);
        p += (s.pre.i[k] - s.pre.j[k]) * s.n[k];
      }
      if (p < 0.0) break;
    }
    for (double& g : s.g) g = U(rng);
  }
  return pool;
}

}  // namespace revcol::bench
