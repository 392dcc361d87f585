// Units of the lattice engine (D = 2 or 3 dimensions), chosen once from the box and the particles,
// and the one-time quantization of a float state (LATTICE.md §1, §6). Every function is the same
// for D = 2 and D = 3 (templates on the dimension, instantiated for both); the 2D names (Units,
// Quantized, choose_units) are the dimension-2 instances, unchanged.
//
// Length: sigma = 2^S lattice units per diameter D. choose_units takes the largest S <= 60 with
// every box length below 2^61 lattice units; any box below max_box (~2^63) is valid (minimum-image
// differences are then below 2^62 and their squares fit 128-bit integers, geometry.hpp). S < 40 (a box longer than 2^22 diameters) is refused: the
// velocity resolution would fall below ~2^20 units.
// Velocity: the root-mean-square speed v_rms of the float state is mapped to 2^(S-T) units per
// tick, so a tick moves a typical particle 2^-T sigma; T = tick_bits, 16..26 allowed. One tick is
// then D 2^-T / v_rms in the float state's time unit. A finer tick (larger T) makes third bodies
// within one tick, and so redraws and group collisions, rarer at the cost of fewer bits of
// velocity resolution (2^(S-T) units for v_rms), which makes the pair operator's read-back
// redraws (~ cells / |w|) and the energy random walk (~2^-(S-T) per collision) larger. The
// automatic tick (the default) balances the two: T = clamp(S - 30, 16, 24) (and at least
// 9 + ceil(log2(N) / 2), so that sqrt(N) v_rms <= vmax / 2 for a huge gas), so v_rms is 2^30
// units per tick wherever the box allows (docs/lattice.md "Choosing the tick and the cells", measured). The
// prototype's T = 20 is what units written before the automatic choice carry. N is bounded by
// 2^(2 (T - 8)) (vmax below). Speeds are bounded by vmax = 2^(S-8) units per
// tick per axis (1/256 sigma per tick): a relative move per tick below sigma/128, which the cell
// grid (cell_grid.hpp) relies on. Because no particle can be faster than sqrt(total kinetic energy),
// a state with sqrt(sum |v|^2) > vmax is refused (N > ~2^24 at the default scale).
// 3D: the same rules per axis, except the box limit: every box length below max_box_of<3> = 2^62
// lattice units, so that a difference on a wall axis (no minimum image) is below 2^62 and the
// squares of three components sum below 3 * 2^124 < 2^126 (geometry.hpp). choose_units keeps
// every length below 2^61 in both dimensions, so the units it picks are not affected.
// Ticks: the clock and per-particle anchor ticks are int64; every event tick is kept below
// tick_limit = 2^61 (about 2^41 mean free times of a typical particle); a run that would pass it
// stops with an error, nothing changed past the last event.
#pragma once
#include <cstddef>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "revcol/engine/boundary_kind.hpp"
#include "revcol/lattice/geometry.hpp"
#include "revcol/lattice/shear.hpp"

namespace revcol::lattice {

/// Largest allowed clock or event tick (both directions): |t| < 2^61.
inline constexpr std::int64_t tick_limit = std::int64_t{1} << 61;
/// Events between two polls of a run's stop request (Ctrl-C through the binding).
inline constexpr std::uint32_t kPollEvents = 1u << 14;
/// Largest allowed box length in lattice units in D dimensions: in 2D positions, their
/// differences and a position plus or minus a velocity stay inside int64; in 3D also the sum of
/// three squared differences stays below 2^126 (see the header comment).
template <std::size_t Dim>
inline constexpr std::int64_t max_box_of = Dim == 2 ? INT64_MAX - (std::int64_t{1} << 56) : std::int64_t{1} << 62;
/// Largest allowed box length of the 2D lattice.
inline constexpr std::int64_t max_box = max_box_of<2>;

/// The lattice's units and box in Dim dimensions: what integer state means physically.
template <std::size_t Dim>
struct UnitsN {
  int S = 60;                                ///< sigma = 2^S lattice units per diameter
  std::int64_t sigma = std::int64_t{1} << 60;  ///< lattice units per diameter
  std::array<std::int64_t, Dim> L{};         ///< box lengths in lattice units, per axis
  std::array<bool, Dim> wall{};              ///< per axis: flat walls at 0 and L (else periodic)
  std::array<bool, Dim> bounce{};            ///< per walled axis: bounce-back walls (v -> -v), else specular
  std::int64_t vmax = std::int64_t{1} << 52;  ///< largest |v| per axis, units per tick
  double length_unit = 0.0;                  ///< float length of one lattice unit (D / sigma)
  double tick = 0.0;                         ///< float time of one tick
  int tick_bits = 20;                        ///< T: a particle of rms speed moves 2^-T sigma per tick
  int cell_bits = 20;                        ///< the pair operator's 2^cell_bits direction cells per turn
  /// A uniform field: per axis the acceleration in lattice units per tick^2, even (so that a
  /// line's point x + v n + (g/2) n^2 is an integer at every tick), |g| <= max_gravity, on at
  /// most one axis, a walled one (every particle falls toward one of its walls). Zero: none.
  std::array<std::int64_t, Dim> gravity{};
  /// Lees-Edwards shear (shear.hpp): the images of the box above it (axis 1 + L_1) move along
  /// axis 0 at `shear` lattice units per tick, offset by delta(t) = shear t mod L_0 at tick t, and
  /// those below at -shear; axes 0 and 1 periodic, |shear| <= vmax / 4. Zero: none.
  std::int64_t shear = 0;
};
/// The offset delta(t) = shear t mod L_0 of the images above the box at tick t (Lees-Edwards).
template <std::size_t Dim>
std::int64_t shear_offset(const UnitsN<Dim>& u, std::int64_t t) noexcept {
  return wrap(static_cast<i128>(u.shear) * t, u.L[0]);
}
/// Largest |gravity| in lattice units per tick^2: 2^36 (the potential sum 2 |g| x over 2^24
/// particles stays inside 128 bits; the default units put g = 1 sigma / tau^2 near 2^12).
inline constexpr std::int64_t max_gravity = std::int64_t{1} << 36;
/// The axis of a field (-1: none).
template <std::size_t Dim>
int field_axis(const UnitsN<Dim>& u) noexcept {
  for (std::size_t k = 0; k < Dim; ++k)
    if (u.gravity[k] != 0) return static_cast<int>(k);
  return -1;
}
/// The boundary kind of axis k (engine/boundary_kind.hpp): periodic, wall or bounce.
template <std::size_t Dim>
engine::Boundary boundary_of(const UnitsN<Dim>& u, std::size_t k) noexcept {
  return !u.wall[k] ? engine::Boundary::periodic : u.bounce[k] ? engine::Boundary::bounce : engine::Boundary::wall;
}
/// Sets axis k of the units to a boundary kind (its walls and bounce flags).
template <std::size_t Dim>
void set_boundary(UnitsN<Dim>& u, std::size_t k, engine::Boundary b) noexcept {
  u.wall[k] = engine::has_walls(b);
  u.bounce[k] = b == engine::Boundary::bounce;
}
/// The 2D units.
using Units = UnitsN<2>;
/// The 3D units.
using Units3 = UnitsN<3>;

/// Allowed range of tick_bits; the tick of units written before the automatic choice (20).
inline constexpr int min_tick_bits = 16, max_tick_bits = 26, legacy_tick_bits = 20;
/// tick_bits = auto_tick_bits asks choose_units for T = clamp(S - velocity_bits, 16, 24).
inline constexpr int auto_tick_bits = 0, default_tick_bits = auto_tick_bits;
/// The velocity resolution the automatic tick aims at: v_rms = 2^velocity_bits units per tick.
inline constexpr int velocity_bits = 30;
/// Default and allowed range of cell_bits (pair2d.hpp; 20 is the prototype's resolution).
inline constexpr int default_cell_bits = 16, min_units_cell_bits = 12, max_units_cell_bits = 20;

/// Checks a Units value (box lengths, sigma, vmax); throws InvalidArgument naming the problem.
template <std::size_t Dim>
void validate(const UnitsN<Dim>& u);

/// Units for a float box of lengths box (per axis) and diameter D holding n particles (0: not
/// known) whose root-mean-square speed is v_rms; throws InvalidArgument if the lattice cannot
/// hold it. The automatic tick is also at least 9 + ceil(log2(n) / 2), so that the total
/// kinetic energy fits vmax with a bit to spare (sqrt(n) v_rms <= vmax / 2).
template <std::size_t Dim>
UnitsN<Dim> choose_units_d(const std::array<double, Dim>& box, double D, double v_rms, const std::array<bool, Dim>& wall,
                           int tick_bits = default_tick_bits, int cell_bits = default_cell_bits, std::size_t n = 0);
/// choose_units_d in 2D.
inline Units choose_units(const std::array<double, 2>& box, double D, double v_rms, const std::array<bool, 2>& wall,
                          int tick_bits = default_tick_bits, int cell_bits = default_cell_bits, std::size_t n = 0) {
  return choose_units_d<2>(box, D, v_rms, wall, tick_bits, cell_bits, n);
}
/// choose_units_d in 3D.
inline Units3 choose_units3(const std::array<double, 3>& box, double D, double v_rms, const std::array<bool, 3>& wall,
                            int tick_bits = default_tick_bits, int cell_bits = default_cell_bits, std::size_t n = 0) {
  return choose_units_d<3>(box, D, v_rms, wall, tick_bits, cell_bits, n);
}

/// A float state quantized to the lattice: integer positions and velocities, and the errors.
template <std::size_t Dim>
struct QuantizedN {
  std::vector<VecN<Dim>> x;         ///< positions, wrapped into [0, L) (periodic) or clamped inside walls
  std::vector<VecN<Dim>> v;         ///< velocities
  double max_position_error = 0.0;  ///< max |x_float - x_lattice * length_unit| / D
  double max_velocity_error = 0.0;  ///< max |v_float - v_lattice * length_unit / tick| / v_rms
};
/// A quantized 2D state.
using Quantized = QuantizedN<2>;

/// Quantizes n x Dim float positions and velocities (row-major) once. Refuses (InvalidArgument) a
/// speed beyond vmax, a position outside the walls, or a pair overlapping after quantization
/// (a mixture: with the given radii, validate_state).
template <std::size_t Dim>
QuantizedN<Dim> quantize(const UnitsN<Dim>& u, const std::vector<double>& x, const std::vector<double>& v,
                         const std::vector<std::int64_t>& radius = {});

/// Checks an integer state: positions inside [0, L) (and inside the walls), |v| <= vmax per axis,
/// sqrt(sum |v|^2) <= vmax, and no pair overlapping (|r|^2 < sigma^2); throws InvalidArgument
/// naming the first problem. O(N) with a hash grid. `pending` (a snapshot's state): a pair that
/// overlaps but was apart one tick earlier (x - v) is a collision pending at the clock (a run
/// stops after a collision, other collisions of that tick still to come) and is accepted.
/// `radius` (a mixture, validate_radii): per particle its radius, a pair overlapping when
/// |r| < r_i + r_j and a particle its radius from a wall; empty: every diameter sigma.
/// `clock`: the tick of the state (shear: the images across the gradient faces are offset by
/// shear_offset(u, clock)).
template <std::size_t Dim>
void validate_state(const UnitsN<Dim>& u, const std::vector<VecN<Dim>>& x, const std::vector<VecN<Dim>>& v,
                    bool pending = false, const std::vector<std::int64_t>& radius = {}, std::int64_t clock = 0);

/// The smallest radius a mixture may hold: sigma / 32 (sigma = 2^S, the largest diameter), so
/// diameters are within a ratio of 16 and a relative move per tick (below sigma / 128 per axis)
/// stays well inside the smallest contact distance.
template <std::size_t Dim>
constexpr std::int64_t min_radius(const UnitsN<Dim>& u) noexcept { return u.sigma / 32; }
/// Checks a mixture's radii (empty: one diameter, nothing to check): one per particle, each in
/// [min_radius, sigma / 2]; throws InvalidArgument naming the first problem.
template <std::size_t Dim>
void validate_radii(const UnitsN<Dim>& u, const std::vector<std::int64_t>& radius, std::size_t n);

/// Kinetic energy sum |v|^2 in 128 bits (lattice units).
template <std::size_t Dim>
u128 kinetic2(const std::vector<VecN<Dim>>& v) noexcept;
/// Twice the energy in lattice units, 128 bits: sum |v|^2 plus, in a field, 2 |g| times each
/// centre's distance from the wall plane the field pulls toward (0 or L; the potential, >= 0).
/// Without a field it is kinetic2. Saturates at 2^128 - 1 (only a state far beyond vmax).
template <std::size_t Dim>
u128 energy2(const UnitsN<Dim>& u, const std::vector<VecN<Dim>>& x, const std::vector<VecN<Dim>>& v) noexcept;

}  // namespace revcol::lattice
