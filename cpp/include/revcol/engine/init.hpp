// Random initial states for the engine, in any box: N spheres of diameter D placed without
// overlap in [0, L_k] per axis (each axis walled or periodic), velocities drawn at random.
//
// Positions. Random sequential addition ("rsa"): uniform candidates, rejected when closer
// than D (1 + 1e-12) to a placed particle (a cell grid of about D per axis finds the
// neighbours, periodic images included), up to 1000 N + 100000 tries. Or a jittered crystal
// ("crystal"; "lattice" is its old name, still read): m_k sites per axis (square in 1D/2D;
// face-centred cubic in 3D, 4 sites per cell) until the sites hold N: a cube takes the same
// m on every axis, any other box refines one axis at a time, the one whose refined spacing
// (hi_k - lo_k) / (m_k + 1) is the widest (so the smallest spacing of the counts that hold N is the largest). Sites sit at
// the cell centres of [lo_k, hi_k] (lo, hi: the centre range, D/2 (1 + 2e-6) inside a wall,
// [0, L) on a periodic axis); N of them are chosen at random and each is moved by up to
// j = 0.49 (s - D) / sqrt(d) per axis, s the nearest-site distance (the smallest spacing a1;
// in 3D min(a1, |(a1, a2)| / 2) over the two smallest), so any two particles stay
// s - 2 sqrt(d) j = s - 0.98 (s - D) > D apart. "auto" picks rsa when the packing fraction
// is at most limits::rsa_fraction(d), and tries the other placement when the first fails.
//
// Velocities. Gaussian components with the mean removed (zero momentum; not for N = 1),
// scaled to the kinetic energy asked (<= 0: N d / 2, that is kT = 1 at unit mass); or, with
// equal_speeds, unit vectors in random directions scaled alike (momentum not enforced).
//
// Draws. Philox streams keyed {0xFFFFFF00, seed} (positions) and {0xFFFFFF01, seed}
// (velocities), never a stream the engine's collisions use: the same seed and box give
// the same bits. random_state (below: the cubic box of a packing fraction) is this
// start in its cube.
#pragma once
#include <cstdint>
#include <string>

#include "revcol/engine/engine.hpp"
#include "revcol/interrupt.hpp"

namespace revcol::engine {

/// A random initial state: box of side L with n particles at packing fraction phi
/// (phi = n v_D / L^d), placed by random sequential addition ("rsa"), or on a crystal
/// (square in 1D/2D, face-centred cubic in 3D) with random displacements ("crystal"; "auto"
/// picks rsa for phi <= 0.3 (1D), 0.35 (2D), 0.2 (3D), else crystal), velocities Gaussian with zero total momentum scaled to
/// kinetic energy `energy` (<= 0: n d / 2, that is kT = 1), or, with equal_speeds, all of
/// the same speed in random directions (then zero momentum is not enforced).
struct InitialState {
  Config config;          ///< config with its box set
  std::vector<double> x;  ///< n x dim
  std::vector<double> v;  ///< n x dim
};
/// The volume (length in 1D, area in 2D) of one particle of diameter D in d dimensions:
/// packing fraction = n particle_volume(d, D) / box volume.
double particle_volume(int d, double D);

/// See InitialState. A mixture (config.diameters, one per particle; config.diameter is then
/// set to the largest): the cube whose packing fraction, from the particles' own volumes, is
/// phi, every particle placed as one of the largest (so each pair starts at least the largest
/// diameter apart, and phi is bounded by the largest ones' crystal).
/// `interrupt`: polled during a relaxed start (every few steps); when it says stop the start
/// throws revcol::Interrupted (the bindings pass Ctrl-C).
InitialState random_state(Config config, std::size_t n, double phi, std::uint64_t seed,
                          double energy = 0.0, const std::string& init = "auto",
                          bool equal_speeds = false, const InterruptCheck& interrupt = {});


/// How a random start places particles: automatic, random sequential addition, or a jittered
/// crystal (square in 1D/2D, face-centred cubic in 3D).
enum class Placement { automatic, rsa, crystal, relax };

/// Parses "auto" / "rsa" / "crystal" ("lattice": the crystal's old name, still read; the word
/// names the integer engine now); throws InvalidArgument otherwise.
Placement parse_placement(const std::string& s);

/// The packing fraction of n particles in config's box: n particle_volume / prod L_k.
double box_fraction(const Config& config, std::size_t n);

/// A random start of n particles in config's box (config.box and config.boundary per axis,
/// config.diameter): see the header comment. Throws InvalidArgument naming the problem
/// (N = 0, a bad box or diameter, a packing fraction above limits::max_fraction, N not
/// fitting on the crystal, a seed of 2^32 or more) and draws nothing then.
InitialState random_start(const Config& config, std::size_t n, std::uint64_t seed, double energy = 0.0,
                          const std::string& init = "auto", bool equal_speeds = false,
                          const InterruptCheck& interrupt = {});

}  // namespace revcol::engine
