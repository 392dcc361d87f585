// A lattice gas for the engine tests (test_lattice_local.cpp, test_lattice_specular_engine.cpp,
// test_lattice_rollback.cpp): the engine of a dimension, a random start with one boundary kind on
// every axis, and a check that a call is refused with a given message; run_config, the parallel
// engine's settings for a run_parallel(_back) (test_lattice_parallel_run.cpp, _back.cpp);
// check_replays, the end of a gas's round trip (test_lattice_field.cpp, test_lattice_shear.cpp);
// sheared_start, a sheared gas's start.
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "revcol/lattice/engine.hpp"

namespace lattice_test {

/// The lattice engine of dimension D (2: disks, 3: spheres).
template <std::size_t D>
using EngineOf = std::conditional_t<D == 2, revcol::lattice::LatticeEngine, revcol::lattice::LatticeEngine3D>;

/// N particles at packing fraction phi sheared at `rate` (3D: walls across z if asked; a mixture's
/// diameters), the random start of `seed` (test_lattice_shear.cpp, test_lattice_shear_observe.cpp).
template <std::size_t D>
revcol::lattice::LatticeStartN<D> sheared_start(std::size_t n, double phi, double rate, std::uint32_t seed,
                                                bool walls = false, std::vector<double> diameters = {}) {
  revcol::lattice::LatticeConfigN<D> c;
  c.seed = seed;
  c.diameters = std::move(diameters);
  c.shear_rate = rate;
  if constexpr (D == 3) c.wall[2] = walls;
  return revcol::lattice::random_start(c, n, phi, seed);
}

/// N particles at packing fraction phi, `kind` on every axis, the random start of `seed`, in `mode`.
template <std::size_t D>
EngineOf<D> make_gas(std::size_t n, double phi, revcol::engine::Boundary kind, std::uint32_t seed,
                     int tick_bits = revcol::lattice::default_tick_bits, revcol::Mode mode = revcol::Mode::exact,
                     double gravity = 0.0) {
  namespace la = revcol::lattice;
  la::LatticeConfigN<D> c;
  c.tick_bits = tick_bits;
  for (std::size_t k = 0; k < D; ++k) {
    c.wall[k] = revcol::engine::has_walls(kind);
    c.bounce[k] = kind == revcol::engine::Boundary::bounce;
  }
  if (gravity != 0.0) {  // a field along the last axis, walled (specular walls in a periodic box)
    c.gravity[D - 1] = gravity;
    c.wall[D - 1] = true;
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

/// The engine of a quantized start (a mixture's radii too), in `mode`, its streams keyed by `seed`.
template <std::size_t D>
EngineOf<D> engine_of(const revcol::lattice::LatticeStartN<D>& s, std::uint32_t seed, revcol::Mode mode) {
  const auto op = revcol::lattice::operator_for(s.units);
  if (s.radius.empty()) return {s.units, s.x, s.v, seed, op, 0, mode};
  return {s.units, s.x, s.v, s.radius, seed, op, 0, mode};
}

/// What a gas under shear (`sheared`) or in a field along `field_axis` refuses by name
/// (InvalidArgument), its state untouched: under shear neighbour lists, the rollback journal and
/// regions (the parallel engine); in a field regions along the field (its slabs cut across it).
/// (Both are observed; a field takes lists, the journal and regions on another axis.)
template <class Engine>
void check_refusals(Engine& e, bool sheared, int field_axis = -1) {
  const auto before = e.snapshot();
  if (sheared) CHECK_THROWS_AS(e.set_list_shell(1.0), revcol::InvalidArgument);
  if (sheared) CHECK_THROWS_AS(e.keep_journal(true), revcol::InvalidArgument);
  CHECK_THROWS_AS(e.set_regions(sheared ? 0 : field_axis, {0}), revcol::InvalidArgument);
  CHECK(revcol::lattice::same_state(e.snapshot(), before));
}

/// The end of a gas's round trip: engine `e` ran `collisions` forward from s0 through s1 (after
/// half of them) to s2. The same run with every candidate pair sent to the exact search (no double
/// filter; `fresh()` gives a new engine at s0) and the run from the checkpoint s1 end on s2; e run
/// back reaches s1, then s0, bit for bit. (CHECK: include check.hpp first.)
template <class Engine, class Fresh, class Snap>
void check_replays(Engine& e, Fresh fresh, const Snap& s0, const Snap& s1, const Snap& s2, std::uint64_t collisions) {
  namespace la = revcol::lattice;
  {
    Engine x = fresh();
    x.exhaustive_search = true;
    x.run(collisions, la::tick_limit - 1);
    CHECK(la::same_state(x.snapshot(), s2));
  }
  {
    Engine r(s1, la::operator_for(s1.units));
    r.run(collisions - collisions / 2, la::tick_limit - 1);
    CHECK(la::same_state(r.snapshot(), s2));
  }
  e.run_back(collisions / 2, s0.origin);
  CHECK(la::same_state(e.snapshot(), s1));
  e.run_back(0, s0.origin);
  CHECK(la::same_state(e.snapshot(), s0));
}

}  // namespace lattice_test
