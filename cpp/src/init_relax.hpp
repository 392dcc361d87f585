// A dense random start by relaxing overlaps away (engine/init.hpp, init "relax"): the
// particles' centres drawn uniformly in the box at their own diameters, then moved until no two
// overlap. The moves minimize the harmonic overlap energy U = sum over overlapping pairs of
// (s_ij - r_ij)^2 / (2 D^2) (s_ij the pair's contact distance times 1 + kRelaxGap, D the largest
// diameter) with FIRE (Bitzek et al., PRL 97, 170201, 2006). Below jamming the minimum is U = 0,
// reached in a finite number of steps: every pair is then at least s_ij apart. This is the
// standard way to make dense amorphous packings of mixtures (the jamming protocol of O'Hern et
// al., PRE 68, 011306, 2003, stopped at U = 0), which a crystal of the largest size cannot
// hold (a 1:1 mixture of size ratio 1.4 fills at most about 0.5 of a cube as fcc of the largest).
// Walls push a centre as a pair does (at its radius), and keep it in its range (its radius
// (1 + kWallMargin) inside each wall) by projection. Deterministic: the same positions in, the same bits out.
#pragma once
#include <cstddef>
#include <vector>

#include "revcol/interrupt.hpp"

namespace revcol::engine::detail {

/// Each pair of a relaxed start is at least its contact distance times (1 + kRelaxGap) apart,
/// each centre its radius times (1 + kRelaxGap) from a wall. The relaxation leaves many pairs at
/// that gap at once, so it is kept far above what a particle moves in one lattice tick (2^-16
/// diameters at most): a gap of 1e-6 left third bodies within a tick in a dense walled 3D start
/// that the lattice engine's group rule could not resolve (measured). It adds 0.3% to the
/// packing fraction the relaxation sees in 3D, far below the spread of jamming densities.
inline constexpr double kRelaxGap = 1e-3;

/// The box as the relaxation sees it: per axis its length and whether it has walls.
struct RelaxBox {
  int d = 0;
  double L[3] = {1.0, 1.0, 1.0};
  bool wall[3] = {false, false, false};
};

/// What a relaxation did.
struct RelaxResult {
  bool done = false;     ///< every pair at least its contact distance times (1 + kRelaxGap) apart
  long steps = 0;        ///< FIRE steps taken
  double overlap = 0.0;  ///< not done: the largest overlap left, over its contact distance
};

/// Moves the centres x (n x d, each inside its range) until no pair of particles (diameters
/// `diam`, one per particle) is closer than its contact distance times (1 + kRelaxGap), or
/// max_steps FIRE steps have run, or the relaxation is jammed or stalled (then done is false and
/// x is where the steps left it). `interrupt` is polled every few steps (throws Interrupted).
RelaxResult relax_overlaps(const RelaxBox& box, const std::vector<double>& diam, std::vector<double>& x,
                           long max_steps, const InterruptCheck& interrupt = {});

}  // namespace revcol::engine::detail
