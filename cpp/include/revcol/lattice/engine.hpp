// The lattice engine: a randomized hard-disk (2D) or hard-sphere (3D) gas reversed bit for bit,
// for any number of collisions, with memory that does not grow with them (LATTICE.md; issues 13, 14).
//
// An integer state (units.hpp: sigma = 2^S lattice units per diameter, a tick moving a typical
// particle 2^-T sigma), exact event search on integer ticks with a cell grid and flat walls
// (cell_grid.hpp, geometry.hpp), the exact pair operator (LatticePair2D, pair2d.hpp; LatticePair3D,
// pair3d.hpp) with per-particle Philox streams and the bits-back integer X (bitsback.hpp), a
// forward acceptance test with redraws and a rare log (engine_core.hpp). Reverse: run_back to any
// earlier collision count or tick. The 2D and 3D engines are one template (BasicEngine, the
// dimension taken from the operator); the 2D names (LatticeEngine, LatticeConfig, LatticeStart,
// Diagnostics) are the dimension-2 instances, the 3D ones carry a 3.
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
#include "revcol/lattice/pair3d.hpp"
#include "revcol/interrupt.hpp"

namespace revcol::lattice {

/// The 2D lattice engine with the exact pair operator.
using LatticeEngine = BasicEngine<LatticePair2D, BitsBack>;
extern template class BasicEngine<LatticePair2D, BitsBack>;
/// The 3D lattice engine (spheres) with the exact 3D pair operator.
using LatticeEngine3D = BasicEngine<LatticePair3D, BitsBack>;
extern template class BasicEngine<LatticePair3D, BitsBack>;

/// An array of D equal values (a default box).
template <std::size_t D, class T>
constexpr std::array<T, D> filled(T value) noexcept {
  std::array<T, D> a{};
  for (T& x : a) x = value;
  return a;
}

/// How to make a lattice simulation in D dimensions from a float start.
template <std::size_t D>
struct LatticeConfigN {
  std::array<double, D> box = filled<D>(1.0);  ///< box lengths (float units)
  std::array<bool, D> wall{};                  ///< per axis: walls (else periodic)
  std::array<bool, D> bounce{};                ///< per walled axis: bounce-back walls (v -> -v), else specular
  double diameter = 1.0;                   ///< D
  Law law = Law::flux;                     ///< the operator's post-direction law
  std::uint32_t seed = 1;                  ///< stream seed (Philox key {particle, seed}) and X's first bits
  int tick_bits = default_tick_bits;       ///< a particle of rms speed moves 2^-tick_bits D per tick (units.hpp)
  int cell_bits = default_cell_bits;       ///< the pair operator's 2^cell_bits direction (2D) or polar (3D) cells per turn
  /// A mixture (equal masses): per particle its diameter in float units (empty: every one
  /// `diameter`). The largest is the units' sigma (`diameter` is then ignored); the others are
  /// quantized to even lattice lengths, radius = round(d / (2 length_unit)), within a ratio of 16.
  std::vector<double> diameters;
  /// A uniform field: per axis the acceleration in float units (length / time^2), on at most
  /// one walled axis. It is quantized once to an even number of lattice units per tick^2
  /// (field.hpp), the rounding in LatticeStartN::gravity_error. The automatic tick is then
  /// coarsened (down to tick_bits 16) until that rounding is within 2^-8 (the largest component's); a
  /// field below 2 units at a given tick is refused.
  std::array<double, D> gravity{};
  /// Lees-Edwards shear (shear.hpp): the shear rate gamma in float units (1 / time), the flow
  /// along axis 0, the gradient along axis 1 (both periodic): the box above moves gamma L_1
  /// faster. Quantized once to an integer shear (lattice units per tick), the rounding in
  /// LatticeStartN::shear_error; random_start adds the steady profile gamma (x_1 - <x_1>) to the
  /// velocities along axis 0 (about the particles' mean height: no momentum added). Zero: none.
  double shear_rate = 0.0;
};
/// The 2D configuration.
using LatticeConfig = LatticeConfigN<2>;
/// The 3D configuration.
using LatticeConfig3 = LatticeConfigN<3>;

/// A quantized start and what the quantization cost.
template <std::size_t D>
struct LatticeStartN {
  UnitsN<D> units;                  ///< the chosen units
  std::vector<VecN<D>> x;           ///< integer positions
  std::vector<VecN<D>> v;           ///< integer velocities
  double max_position_error = 0.0;  ///< max |x_float - x_lattice| / D
  double max_velocity_error = 0.0;  ///< max |v_float - v_lattice| / v_rms
  std::vector<std::int64_t> radius;  ///< a mixture: per particle its radius in lattice units (empty: one diameter)
  double gravity_error = 0.0;        ///< a field: |g_lattice - g| / |g| after quantization (0: none)
  double shear_error = 0.0;          ///< shear: |s_lattice - s| / |s| after quantization (0: none)
};
/// A quantized 2D start.
using LatticeStart = LatticeStartN<2>;
/// A quantized 3D start.
using LatticeStart3 = LatticeStartN<3>;

/// Units chosen from the box and the velocities' rms speed, then one quantization of n x D float
/// positions and velocities (row-major). Throws InvalidArgument (a box or speed range the lattice
/// cannot hold, an overlap after quantization).
template <std::size_t D>
LatticeStartN<D> quantize_start(const LatticeConfigN<D>& c, const std::vector<double>& x, const std::vector<double>& v);

/// A random start as the float engine's engine::random_state (n disks or spheres at area or
/// volume fraction phi in the square or cubic box it chooses, Gaussian velocities with zero
/// momentum, kT = 1, init "auto", "rsa", "crystal" or "relax"; `interrupt` polled by a relaxed
/// start), quantized once.
template <std::size_t D>
LatticeStartN<D> random_start(const LatticeConfigN<D>& c, std::size_t n, double phi, std::uint64_t seed,
                              const std::string& init = "auto", const InterruptCheck& interrupt = {});

/// Diagnostics of a lattice state (all exact integers converted only for reporting).
template <std::size_t D>
struct DiagnosticsN {
  double energy_drift = 0.0;               ///< (E - E0) / E0, E = sum |v|^2 in lattice units
  double energy_drift_units = 0.0;         ///< E - E0 in lattice units^2 / tick^2
  std::array<double, D> momentum_drift{};  ///< P - P0 per axis, lattice units per tick
  std::size_t bits_length = 0;             ///< the particles' X, bit lengths summed
  std::size_t log_entries = 0;             ///< rare-log entries held
  std::uint64_t collisions = 0;            ///< collisions since the start
  std::int64_t clock = 0;                  ///< the tick
  double time = 0.0;                       ///< clock * tick (float units), from the origin
  std::size_t memory_bytes = 0;            ///< engine memory
};
/// 2D diagnostics.
using Diagnostics = DiagnosticsN<2>;
/// Diagnostics of an engine.
Diagnostics diagnostics(const LatticeEngine& e);
/// Diagnostics of a 3D engine.
DiagnosticsN<3> diagnostics(const LatticeEngine3D& e);

/// The pair operator the units ask for (their sigma and cell_bits) with the given law.
inline LatticePair2D operator_for(const Units& u, Law law = Law::flux) { return LatticePair2D(u.sigma, law, u.cell_bits); }
/// The 3D pair operator the units ask for (their sigma and 2^cell_bits polar cells per turn).
inline LatticePair3D operator_for(const Units3& u, Law law = Law::flux) { return LatticePair3D(u.sigma, law, u.cell_bits); }

/// The same snapshot from the engine (a convenience for bindings).
inline Snapshot snapshot_of(const LatticeEngine& e) { return e.snapshot(); }

}  // namespace revcol::lattice
