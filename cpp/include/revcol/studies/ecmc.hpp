// Event-chain Monte Carlo of hard spheres (Bernard, Krauth and Wilson, Phys. Rev. E 80,
// 056704, 2009): an independent sampler of the equilibrium that the engine's dynamics should
// keep, and the pressure of that equilibrium at the engine's own N and box.
//
// Mixtures. Each sphere may have its own diameter d_i (a pair touches at (d_i + d_j) / 2; the
// largest, D, sizes the cells): the uniform measure, the chains and the pressure estimator are
// the same, dx being the contact's projection for the pair's own contact distance.
//
// What it samples. N spheres of diameter D in a periodic box (d = 1, 2, 3, side L_k >= 3 D on
// every axis): the uniform measure over non-overlapping configurations, which is the
// configurational equilibrium of hard spheres at any temperature (the velocities of an
// energy-conserving gas are independent of the positions). No dynamics, no velocities: a
// different algorithm from the event-driven engine, sharing none of its code but the Philox
// generator, so agreement between the two is evidence about the engine's collision law.
//
// One chain. Pick a particle uniformly at random, an axis k (the chains cycle through the
// axes x, y, z in turn) and a length l uniform in [ell / 2, 3 ell / 2]; move the particle
// along +k until it touches another one (or until the chain has moved a total of l); then
// stop it and move the one it touched ("lift"), and so on until the chain's displacement
// adds up to l. Each chain leaves the uniform measure invariant (global balance through the
// lifts), and moves along the d axes make the chain irreducible. The length is random
// because a fixed one is not enough in 1D: there a chain only shifts gaps between rods by
// multiples of l and merges or splits them, so from a lattice start the gaps stay on a
// lattice (measured: Tonks' Z 1.45 instead of 1.90 with l = 0.5 D). At a lift from sphere i
// to sphere j, x_j - x_i along k is the contact's projection dx = sqrt(D^2 - b^2) (b: the
// perpendicular distance of the centres).
//
// The pressure. For a chain of length l the position of its last moved sphere less that of
// its first is l + sum over lifts of dx, and (Michel, Kapfer and Krauth, J. Chem. Phys. 140,
// 054116, 2014)
//     beta P V / N = 1 + < sum dx > / < l >,
// exact at finite N for the thermodynamic pressure of the canonical ensemble (beta P =
// d ln Z / d V). Checked in tests/cpp/test_ecmc.cpp against the two exact finite-N answers:
// N rods on a ring (Tonks: beta P = 1 / L + (N - 1) / (L - N D)) and two spheres in a periodic
// box (Z = V (V - v_ex), v_ex the volume of a sphere of radius D: beta P V / N = (1 + V / (V -
// v_ex)) / 2).
//
// The engine's Z. The engine's observer reports Z_md = 1 + W / (sum m v^2), its collision
// virial W over twice the kinetic energy, the temperature counted over d N degrees of freedom.
// At zero total momentum a pair's relative velocity has <(u.n)^2> = 2 k T' with T' counted over
// d (N - 1), so with the same contacts the two are related exactly by
//     Z_md - 1 = (Z_mc - 1) N / (N - 1)
// (python/revcol/ecmc.py: md_equivalent). Both tend to the same Z as N grows.
//
// Numerics. Positions are doubles wrapped into [0, L_k); each particle lives in a cell of side
// w_k = L_k / m_k >= D (m_k = floor(L_k / (D (1 + 1e-9)))), kept explicitly (never recomputed
// from a rounded position). A move never leaves the active particle's cell: its step is capped
// at the cell's face, so every sphere it can touch is in the 3^d cells around it, and at the
// face it passes to the next cell. The sphere just lifted from sits behind the new active
// sphere at contact; rounding can put it a hair ahead, so that one image (dx < D / 2) is not a
// candidate for the next move. Draws: Philox keyed {0xFFFFFF10, seed}; chain c draws 2c (its
// particle) and 2c + 1 (its length), so a run is a pure function of (state, seed, chain count).
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "revcol/interrupt.hpp"
#include "revcol/rng/philox.hpp"

namespace revcol::ecmc {

/// The sums of a run of chains: the pressure is 1 + lift_dx / displacement.
struct ChainSums {
  std::uint64_t chains = 0;    ///< chains run
  double displacement = 0.0;   ///< the chains' lengths added up
  double lift_dx = 0.0;        ///< sum of the lifts' projections dx along the chain's axis
  std::uint64_t lifts = 0;     ///< lifts (events where the active sphere passed its move on)
  std::uint64_t crossings = 0; ///< cell faces the active spheres crossed
  /// beta P V / N of these chains: 1 + lift_dx / displacement (1 when nothing ran).
  double compressibility() const { return displacement > 0 ? 1.0 + lift_dx / displacement : 1.0; }
  /// Adds another run's sums.
  ChainSums& operator+=(const ChainSums& o) {
    chains += o.chains;
    displacement += o.displacement;
    lift_dx += o.lift_dx;
    lifts += o.lifts;
    crossings += o.crossings;
    return *this;
  }
};

/// The event-chain sampler: see the header comment.
class EventChain {
 public:
  /// n = x.size() / box.size() spheres of diameter `diameter` at positions x (n x d, row-major,
  /// each coordinate in [0, L_k)) in the periodic box `box` (d = 1..3 lengths, each >= 3 D).
  /// Throws InvalidArgument naming the problem: a bad d, box, diameter or position, a pair
  /// closer than D (1 - 1e-9), a seed of 2^32 or more, more than 2^22 cells (floor(L_k / D)
  /// per axis).
  EventChain(std::vector<double> box, std::vector<double> x, double diameter, std::uint64_t seed);
  /// A mixture: sphere i has diameter diameters[i] (one per sphere, positive, finite, within a
  /// ratio of 16 of the largest, D, which sizes the cells and the box's minimum of 3 D); a pair
  /// touches at (d_i + d_j) / 2. Throws as the one-size constructor does, and on a bad diameter.
  EventChain(std::vector<double> box, std::vector<double> x, const std::vector<double>& diameters,
             std::uint64_t seed);

  /// Runs `chains` chains of mean length `ell` (> 0, finite, at most 1e6 L_max) and returns their
  /// sums (also added to totals()). The check is polled between chains; Interrupted leaves
  /// the chains that finished (a chain is never left half-run). Bad arguments throw
  /// InvalidArgument and change nothing.
  ChainSums run(std::uint64_t chains, double ell, const InterruptCheck& check = {});

  /// Dimension d.
  int dim() const { return dim_; }
  /// Number of spheres.
  std::size_t size() const { return n_; }
  /// Box lengths (d of them).
  std::vector<double> box() const { return {box_.begin(), box_.begin() + dim_}; }
  /// Diameter D (a mixture's largest).
  double diameter() const { return diameter_; }
  /// A mixture's radii, d_i / 2 by sphere; empty for one diameter.
  const std::vector<double>& radii() const { return radius_; }
  /// Positions, n x d row-major, each in [0, L_k).
  const std::vector<double>& positions() const { return x_; }
  /// Sums over every run so far.
  const ChainSums& totals() const { return totals_; }
  /// Packing fraction: the spheres' volumes over V (N v_D / V for one diameter).
  double packing_fraction() const;
  /// The smallest centre distance (nearest periodic image) divided by the pair's contact
  /// distance (D, or (d_i + d_j) / 2 in a mixture), over the pairs in neighbouring cells, which
  /// hold every pair closer than D; infinity when no pair is that near. O(N) through the cells.
  double min_distance() const;

 private:
  /// The checks and the cells, for both constructors (diameter_ already the largest diameter).
  void init(std::vector<double> box, std::vector<double> x, const std::vector<double>& diameters, std::uint64_t seed);
  template <int Dim, bool Mixed> ChainSums run_chain(double ell);  ///< one chain along axis axis_ % d
  std::size_t cell_index(const std::array<int, 3>& c) const;
  /// Calls f(j, shift) for every sphere j of the 3^Dim cells around cell c (x fastest, then y,
  /// z; each cell's members in order), shift the image shift of that cell's wrap.
  template <int Dim, class F> void for_around(const std::array<int, 3>& c, F&& f) const;
  template <int Dim> double min_distance_d() const;  ///< min_distance for this Dim

  int dim_;
  std::size_t n_;
  std::array<double, 3> box_{1.0, 1.0, 1.0};
  double diameter_;
  std::array<int, 3> m_{1, 1, 1};           ///< cells per axis
  std::array<double, 3> w_{1.0, 1.0, 1.0};  ///< cell sides
  std::vector<double> x_;                   ///< n x dim
  std::vector<double> radius_;              ///< a mixture's radii by sphere; empty for one diameter
  std::vector<std::array<int, 3>> cell_;    ///< each sphere's cell coordinates
  /// The spheres of cell c: members_[c cap_ .. c cap_ + count_[c]), in insertion order with
  /// removals filled from the back. cap_ starts at 2, 4, 8 (1D, 2D, 3D) and doubles for all
  /// cells when one is full (a cell of side < 4 D / 3 holds few centres D apart).
  std::vector<int> members_;
  std::vector<int> count_;                  ///< spheres per cell
  int cap_ = 1;                             ///< slots per cell
  std::vector<int> slot_;                   ///< each sphere's index in its cell's members
  void insert(int i, std::size_t cell);     ///< appends sphere i to cell
  void remove(int i, std::size_t cell);     ///< takes sphere i out of cell (the last member fills its slot)
  rng::Philox rng_;
  std::uint64_t axis_ = 0;                  ///< chains started: the next chain's axis is axis_ % d
  ChainSums totals_;
};

}  // namespace revcol::ecmc
