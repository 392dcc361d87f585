// The engine's limits, in one place: what a configuration and a random start may ask for.
// The engine's validation, the random start (engine/init.hpp) and, through the binding
// (revcol._core.engine_limits), the Python scene reader all read them from here, so a scene
// is refused for exactly the reasons the engine would refuse it.
//
// Geometry. Particles are spheres of diameter D; the box is [0, L_k] per axis, each axis
// walled or periodic. A walled axis needs L_k > D (a particle fits between its walls). A
// periodic axis needs floor(L_k / D) >= 3: with at least three diameters per period, and a
// neighbour-list shell of at least 0.45 D, each listed neighbour has a unique nearest image.
// Packing fraction phi = N v_D / prod L_k with v_D the particle's volume: D (1D), pi D^2 / 4
// (2D), pi D^3 / 6 (3D).
//
// Random starts. Random sequential addition (RSA) jams near phi 0.75 (1D), 0.547 (2D),
// 0.38 (3D) and slows down well before: "auto" uses it up to kRsaFraction and a jittered
// lattice above (square in 1D/2D, face-centred cubic in 3D, whose close packing is 0.74).
// kMaxFraction is the highest phi the start accepts: the lattice's spacing must exceed D.
// A particle starts at least kWallMargin D / 2 inside the wall contact (centre in
// [D/2 (1 + m), L - D/2 (1 + m)]): touching a wall at t0 is an event at t0, which a
// reversed run cannot tell from a departure.
//
// Collisions. Paper mode has pair operators in 1D (the exchange) and 2D (Procedures 1-2);
// its 3D pair operator is not a bijection, so the engine refuses paper mode in 3D.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "revcol/fixed_point.hpp"

namespace revcol::engine::limits {

/// Pi, to double precision.
inline constexpr double kPi = 3.141592653589793238462643383279502884;
/// Smallest and largest dimension d.
inline constexpr int kMinDim = 1, kMaxDim = 3;
/// Least number of whole diameters along a periodic axis (floor(L / D) >= this).
inline constexpr int kMinPeriodicCells = 3;
/// Smallest and largest K, exact mode's bits per chart coordinate (FixedPoint's).
inline constexpr int kMinBits = FixedPoint::min_bits, kMaxBits = FixedPoint::max_bits;
/// A mixture's sizes: the smallest diameter at least the largest / kMaxSizeRatio (the lists,
/// sized by the largest, would list ratio^d small particles per small one).
inline constexpr double kMaxSizeRatio = 16.0;
/// Masses: the largest at most kMaxMassRatio times the smallest (a pair's centre-of-mass
/// transform rounds its light member's velocity by about the ratio times the unit round-off).
inline constexpr double kMaxMassRatio = 1e6;
/// group_tol must lie in [0, kMaxGroupTol).
inline constexpr double kMaxGroupTol = 1e-3;
/// Seeds (and generator keys) are 32-bit: seed <= kMaxSeed.
inline constexpr std::uint64_t kMaxSeed = 0xFFFFFFFFull;
/// Relative margin kept from a wall at the start (centre >= D/2 (1 + kWallMargin) inside).
inline constexpr double kWallMargin = 2e-6;
/// Two particles of a start are at least D (1 + kMinGap) apart (RSA); a lattice's spacing at least D (1 + kLatticeGap).
inline constexpr double kMinGap = 1e-12, kLatticeGap = 1e-9;

/// Largest packing fraction the random start accepts in d dimensions (1..3).
constexpr double max_fraction(int d) { return d == 1 ? 0.95 : d == 2 ? 0.75 : 0.70; }

/// Largest packing fraction a relaxed random start (init "relax", and a mixture's "auto" past the
/// crystal of its largest) is asked for, from the particles' own volumes (1..3): a little above
/// the jamming of random packings of binary and modestly polydisperse gases (0.64-0.66 in 3D,
/// 0.84-0.86 in 2D), so a start between jamming and this bound fails by the relaxation's own
/// tests (init_relax.cpp), and one above it at once.
constexpr double max_relax_fraction(int d) { return d == 1 ? 0.95 : d == 2 ? 0.88 : 0.68; }
/// The relaxation's budget: FIRE steps before a relaxed start gives up (init_relax.hpp).
inline constexpr long kRelaxSteps = 20000;

/// Largest packing fraction at which "auto" starts by random sequential addition (1..3).
constexpr double rsa_fraction(int d) { return d == 1 ? 0.3 : d == 2 ? 0.35 : 0.2; }

/// The volume (length in 1D, area in 2D) of one particle of diameter D in d dimensions.
constexpr double particle_volume(int d, double D) {
  return d == 1 ? D : d == 2 ? kPi * D * D / 4.0 : kPi * D * D * D / 6.0;
}

/// Largest N in d dimensions: a neighbour-list entry packs an id and its image code (2 bits
/// per axis) in 32 bits (revcol/engine/neighbours.hpp), so ids stay below 2^(32 - 2d):
/// N <= 2^30 (1D), 2^28 (2D), 2^26 = 67 108 864 (3D; ~20 GB of engine at ~290 bytes each).
constexpr std::uint64_t max_particles(int d) { return std::uint64_t{1} << (32 - 2 * d); }
/// The error for N > max_particles(d): one wording wherever N is checked.
inline std::string too_many_particles(int d, std::uint64_t n) {
  return "too many particles in " + std::to_string(d) + "D (N must be at most " + std::to_string(max_particles(d)) +
         ", got " + std::to_string(n) + ")";
}

/// Largest box length in diameters per axis: cell and list indices stay within int, and a
/// position keeps ~1e-7 D of resolution (issue 17: L / D past int made the cell count overflow).
inline constexpr double kMaxBoxDiameters = 1073741824.0;  // 2^30
/// True when an axis of length L is at most kMaxBoxDiameters diameters D long.
constexpr bool box_ratio_fits(double L, double D) { return L / D <= kMaxBoxDiameters; }

/// Most cells of an exact search grid over n particles (the random start's placement grid,
/// the overlap check): max(8 n, 2^18). A sparse box takes wider cells instead, so memory stays
/// O(N) at any density (issue 59: N = 10 at phi 1e-7 took 1.8 GB of empty placement cells).
/// Which pairs these searches find does not depend on the cell width.
constexpr double max_cells(std::size_t n) { return std::max(8.0 * static_cast<double>(n), 262144.0); }
/// Most cells of the neighbour lists' grid over n particles: max(64 n, 2^18). Its cells also
/// order the particles' storage and the scans, so the cap sits far below any density in use
/// (it first binds below phi ~ 1e-3 in 2D, 5e-4 in 3D at the widest shells): every such gas
/// keeps the grid it had.
constexpr double max_list_cells(std::size_t n) { return std::max(64.0 * static_cast<double>(n), 262144.0); }

/// Cells per axis (into nc[0..d)) of a grid of cells at least w wide over box lengths L[0..d):
/// floor(L_k / w) (at least 1), exactly as before while their product is at most cap (one of
/// the two above); past it the axes take fewer, wider cells until it is (never fewer than
/// min(floor(L_k / w), 3), so an axis with 3 or more cells keeps 3: a neighbouring cell's
/// image stays unique). Fewer cells of an axis only widen them, so the 3^d cells around a
/// point still hold everything within w of it: a search over them finds the same pairs.
inline void capped_cell_counts(int d, const double* L, double w, double cap, int* nc) {
  double c[3] = {1, 1, 1}, least[3] = {1, 1, 1};
  double total = 1.0;
  for (int k = 0; k < d; ++k) {
    c[k] = std::max(1.0, std::floor(L[k] / w));
    least[k] = std::min(c[k], 3.0);
    total *= c[k];
  }
  if (total > cap) {
    const double f = std::pow(total / cap, 1.0 / d);
    total = 1.0;
    for (int k = 0; k < d; ++k) {
      c[k] = std::max(least[k], std::floor(c[k] / f));
      total *= c[k];
    }
    while (total > cap) {  // rounding or an axis held at its least: halve the axis with the most
      int m = 0;
      for (int k = 1; k < d; ++k) m = c[k] > c[m] ? k : m;
      const double h = std::max(least[m], std::floor(c[m] / 2.0));
      total = total / c[m] * h;
      c[m] = h;
    }
  }
  for (int k = 0; k < d; ++k) nc[k] = static_cast<int>(c[k]);
}

/// Largest |clock| in units of D / v_max: past it the clock's ulp (2^-52 |t|) exceeds 1e-6 of
/// the time a particle takes to cross its own diameter, and events begin to share one clock
/// value (issue 17: a start time of 1e16 never returned). Round trips degrade well before:
/// the position error grows like ulp(t) v / D (a start at t = 1e6 D / v gave 2e-8).
inline constexpr double kMaxClockFlights = 4.5e9;
/// True when a clock t resolves flight times D / vmax (|t| <= kMaxClockFlights D / vmax).
inline bool clock_fits(double t, double D, double vmax) {
  return vmax <= 0.0 || (t < 0.0 ? -t : t) * vmax <= kMaxClockFlights * D;
}

/// Speeds a gas may start with (issue 17): the largest |velocity component| v_max must be at
/// least kMinGasSpeed and sqrt(N d) v_max (a bound on every speed the gas can ever reach, from
/// its energy) at most the operators' kMaxSpeed (2^450). Below 2^-420, a colliding pair's
/// relative speed could fall under the operators' 2^-480 (two distinct components >= 2^-420
/// differ by at least 2^-472); a gas at 1e-161 hung, one at 1e154 overflowed.
inline constexpr double kMinGasSpeed = 0x1.0p-420;  // about 3.7e-127
/// Largest v_max for N particles in d dimensions: 2^450 / sqrt(N d).
inline double max_gas_speed(double n, int d) { return 0x1.0p+450 / std::sqrt(n * d); }

/// True when a walled axis of length L holds a particle of diameter D (L > D).
constexpr bool wall_axis_fits(double L, double D) { return L > D; }

/// True when a periodic axis of length L is long enough for the neighbour lists (floor(L / D) >= 3).
constexpr bool periodic_axis_fits(double L, double D) {
  return L / D >= static_cast<double>(kMinPeriodicCells);  // floor(x) >= 3 iff x >= 3
}

/// True when paper mode has an (invertible) pair operator in d dimensions: 1D and 2D.
constexpr bool paper_mode_allowed(int d) { return d == 1 || d == 2; }

}  // namespace revcol::engine::limits
