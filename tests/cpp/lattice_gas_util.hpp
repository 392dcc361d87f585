// A lattice gas for the engine tests (test_lattice_local.cpp, test_lattice_specular_engine.cpp,
// test_lattice_rollback.cpp): the engine of a dimension, a random start with one boundary kind on
// every axis, and a check that a call is refused with a given message; run_config, the parallel
// engine's settings for a run_parallel(_back) (test_lattice_parallel_run.cpp, _back.cpp).
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <string>
#include <type_traits>

#include "revcol/lattice/engine.hpp"

namespace lattice_test {

/// The lattice engine of dimension D (2: disks, 3: spheres).
template <std::size_t D>
using EngineOf = std::conditional_t<D == 2, revcol::lattice::LatticeEngine, revcol::lattice::LatticeEngine3D>;

/// N particles at packing fraction phi, `kind` on every axis, the random start of `seed`, in `mode`.
template <std::size_t D>
EngineOf<D> make_gas(std::size_t n, double phi, revcol::engine::Boundary kind, std::uint32_t seed,
                     int tick_bits = revcol::lattice::default_tick_bits, revcol::Mode mode = revcol::Mode::exact) {
  namespace la = revcol::lattice;
  la::LatticeConfigN<D> c;
  c.tick_bits = tick_bits;
  for (std::size_t k = 0; k < D; ++k) {
    c.wall[k] = revcol::engine::has_walls(kind);
    c.bounce[k] = kind == revcol::engine::Boundary::bounce;
  }
  c.seed = seed;
  const la::LatticeStartN<D> s = la::random_start(c, n, phi, seed);
  return {s.units, s.x, s.v, seed, la::operator_for(s.units), 0, mode};
}

/// The parallel engine's settings (TimeWarp<E>::Config) for a run on k LPs and w workers, short batches.
template <class Config>
Config run_config(int k, int w) {
  Config c;
  c.lps = k;
  c.workers = w;
  c.batch = 16;
  return c;
}

/// True when f() throws an exception whose message contains `what` (another message is printed).
template <class F>
bool refused(F&& f, const std::string& what) {
  try {
    f();
  } catch (const std::exception& e) {
    if (std::string(e.what()).find(what) != std::string::npos) return true;
    std::printf("    unexpected message: %s\n", e.what());
  }
  return false;
}

}  // namespace lattice_test
