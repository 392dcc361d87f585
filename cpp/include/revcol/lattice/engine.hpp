// The 2D lattice engine: a randomized hard-disk gas reversed bit for bit, for any number of
// collisions, with memory that does not grow with them (LATTICE.md; issue 13).
//
// An integer state (units.hpp: sigma = 2^S lattice units per diameter, a tick moving a typical
// particle 2^-20 sigma), exact event search on integer ticks with a cell grid and flat walls
// (cell_grid.hpp, geometry.hpp), the exact pair operator LatticePair2D with per-particle Philox
// streams and the bits-back integer X (pair2d.hpp, bitsback.hpp), a forward acceptance test with
// redraws and a rare log (engine_core.hpp). Reverse: run_back to any earlier collision count or tick.
//
// Float states (Simulation.random-like starts) are quantized once (units.hpp: quantize); the round
// trip is exact from the quantized state on, and the quantization error is reported.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "revcol/collide/common.hpp"
#include "revcol/lattice/bitsback.hpp"
#include "revcol/lattice/engine_core.hpp"
#include "revcol/lattice/pair2d.hpp"

namespace revcol::lattice {

/// The lattice engine with the exact pair operator.
using LatticeEngine = BasicEngine<LatticePair2D, BitsBack>;
extern template class BasicEngine<LatticePair2D, BitsBack>;

/// How to make a lattice simulation from a float start.
struct LatticeConfig {
  std::array<double, 2> box{1.0, 1.0};     ///< box lengths (float units)
  std::array<bool, 2> wall{false, false};  ///< per axis: walls (else periodic)
  double diameter = 1.0;                   ///< D
  Law law = Law::flux;                     ///< the operator's post-direction law
  std::uint32_t seed = 1;                  ///< stream seed (Philox key {particle, seed}) and X's first bits
  int tick_bits = default_tick_bits;       ///< a particle of rms speed moves 2^-tick_bits D per tick (units.hpp)
  int cell_bits = default_cell_bits;       ///< the pair operator's 2^cell_bits direction cells per turn (pair2d.hpp)
};

/// A quantized start and what the quantization cost.
struct LatticeStart {
  Units units;                      ///< the chosen units
  std::vector<Vec2> x;              ///< integer positions
  std::vector<Vec2> v;              ///< integer velocities
  double max_position_error = 0.0;  ///< max |x_float - x_lattice| / D
  double max_velocity_error = 0.0;  ///< max |v_float - v_lattice| / v_rms
};

/// Units chosen from the box and the velocities' rms speed, then one quantization of n x 2 float
/// positions and velocities (row-major). Throws InvalidArgument (a box or speed range the lattice
/// cannot hold, an overlap after quantization).
LatticeStart quantize_start(const LatticeConfig& c, const std::vector<double>& x, const std::vector<double>& v);

/// A random start as the float engine's engine::random_state (2D, n disks at area fraction phi in
/// the square box it chooses, Gaussian velocities with zero momentum, kT = 1, init "auto", "rsa" or
/// "lattice"), quantized once.
LatticeStart random_start(const LatticeConfig& c, std::size_t n, double phi, std::uint64_t seed,
                          const std::string& init = "auto");

/// Diagnostics of a lattice state (all exact integers converted only for reporting).
struct Diagnostics {
  double energy_drift = 0.0;               ///< (E - E0) / E0, E = sum |v|^2 in lattice units
  double energy_drift_units = 0.0;         ///< E - E0 in lattice units^2 / tick^2
  std::array<double, 2> momentum_drift{};  ///< P - P0 per axis, lattice units per tick
  std::size_t bits_length = 0;             ///< bit length of X
  std::size_t log_entries = 0;             ///< rare-log entries held
  std::uint64_t collisions = 0;            ///< collisions since the start
  std::int64_t clock = 0;                  ///< the tick
  double time = 0.0;                       ///< clock * tick (float units), from the origin
  std::size_t memory_bytes = 0;            ///< engine memory
};
/// Diagnostics of an engine.
Diagnostics diagnostics(const LatticeEngine& e);

/// The pair operator the units ask for (their sigma and cell_bits) with the given law.
inline LatticePair2D operator_for(const Units& u, Law law = Law::flux) { return LatticePair2D(u.sigma, law, u.cell_bits); }

/// The same snapshot from the engine (a convenience for bindings).
inline Snapshot snapshot_of(const LatticeEngine& e) { return e.snapshot(); }

}  // namespace revcol::lattice
