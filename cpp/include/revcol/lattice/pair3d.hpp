// The exact pair operator of the 3D lattice engine (LATTICE.md §3 and §6, docs/lattice.md "3D").
//
// The 2D operator (pair2d.hpp) keeps a direction's offset inside its cell by rotating through a
// whole number of congruent equal-angle cells. On the sphere cells are not congruent, so the 3D
// operator splits the direction about the contact normal into a polar angle theta and an
// azimuth phi, and treats them differently:
//   * theta by whole-cell lifting rotations in one integer plane, exactly as in 2D (the cells of
//     a plane are congruent), with the flux law's integer frequencies (density cos(theta) on the
//     hemisphere, i.e. sin^2(theta) uniform);
//   * phi by bits-back over the lattice points themselves: the offset across the azimuth cell is
//     an integer y on a row of the cell whose exact end points are computed, pushed as a uniform
//     index over the pre row and popped over the post row (whose length differs: it is
//     proportional to sin(theta)). A post direction therefore lies in its azimuth cell by
//     construction: no read-back refusal and no law distortion from the azimuth.
// The measured design study (docs/lattice.md "3D: the direction chart") compares this with the
// issue's other candidates.
//
// Units: positions in lattice units (sphere diameter sigma, 2 <= sigma <= 2^60), velocities in
// lattice units per tick, time in ticks. A pair collides on the transition from tick a-1 to tick
// a, where a is the first tick at which its incoming lines overlap (LATTICE.md §2).
//
// Relative operator (forward). Pre state: q = x_i - x_j at tick a-1 outside (|q|^2 >= sigma^2),
// w = v_i - v_j with p = q + w inside. Steps:
//  1. Face: the cube face of p (axis of the largest |p_k|, ties to z, then y, then x; sign of
//     p_k). The face frame is a signed cyclic permutation (a rotation) taking that axis to +z; in
//     it p = (xc, yc, pz), the column (xc, yc) is fixed and the face holds the points of the column
//     with z >= zmin = max(1, |xc| + sx, |yc| + sy), sx, sy = 1 where the frame axis has priority
//     over the face axis (strict ties).
//  2. Pre phases: the inside points of the column, z <= Zin = isqrt(sigma^2 - xc^2 - yc^2 - 1),
//     z >= zmin, whose point minus W is outside, form [lo, Zin] (exact integer square roots; not
//     an interval: out_of_domain); m = Zin - lo + 1. X <- X*m + (pz - lo).
//  3. Normal frame: the column's normal n = (xc, yc, sqrt(sigma^2 - xc^2 - yc^2)) quantized to
//     the nearest of 2^20 equal-angle cells in azimuth (Kphi, atan2(yc, xc)) and in polar angle
//     (Ktheta, asin(isqrt(xc^2 + yc^2) / sigma)), both decided exactly (cells.hpp). L is the
//     lifting rotation by -Kphi in (x, y) followed by -Ktheta in (z, x): an exact bijection of
//     Z^3 taking n to +z within a unit. u = -L(W), the reversed incoming velocity, approaching
//     when u_z > 0.
//  4. Pre chart: Phi = azimuth cell of (u_x, u_y), 2^18 per turn (phi_bits). Align: (x_a, y) =
//     the lifting rotation of (u_x, u_y) by minus the cell's centre, so x_a ~ |u_xy| and y is the
//     offset across the cell (the pole, u_xy = 0, is Phi = 0, x_a = y = 0). Polar cell a of the
//     plane vector (u_z, x_a), cells of angle D = 2 pi / 2^cell_bits CENTRED on multiples of D:
//     cell j holds [(j - 1/2) D, (j + 1/2) D), j = 0 .. Q = 2^cell_bits / 4 (cells 0 and Q are
//     half cells), so the pole is a cell's centre and a head-on pre state never rotates onto a
//     boundary (u_z <= 0: not_approaching). The row of (Phi, x_a): the integers y whose aligned
//     point rotated back lies in cell Phi, [ylo, yhi] (found exactly; the pre's y must be on it,
//     else out_of_domain; row(0, 0) = {0}). X <- X*(yhi - ylo + 1) + (y - ylo).
//  5. rANS push of the joint symbol (Phi, a): cumulative Phi*2^30 + cum(a), frequency f(a), where
//     cum is the polar law's table with total 2^30 over the Q + 1 cells: with t_j = (j - 1/2) D
//     the start of cell j, flux cum(j) = j + round((2^30 - Q - 1) sin^2 t_j), uniform (in solid
//     angle) cum(j) = j + round((2^30 - Q - 1)(1 - cos t_j)), cum(0) = 0, cum(Q + 1) = 2^30 (the
//     +j keeps every f >= 1 exactly; it moves the law by at most (Q + 1) / 2^30).
//  6. Torus shift: the low 48 bits s of X become (s + G) mod 2^48.
//  7. rANS pop of (Phi', b). Rotate (u_z, x_a) by b - a polar cells (lifting) to (u_z', x_a'); if
//     that is not in cell b (or not in the quarter plane): cell_readback. (A post at the pole
//     reads back as Phi' = 0; another Phi' there is cell_readback.) Pop the post offset over the row of (Phi', x_a')
//     (no row: empty_post), rotate it back by the centre of Phi' to (u_x', u_y'), check its cell
//     is Phi' (holes in a row, never seen; cell_readback). W2 = L^{-1}(u').
//  8. Post phase: the inside points of the column whose point plus W2 is outside form [lo2, Zin]
//     (or out_of_domain); m2 = Zin - lo2 + 1 (m2 <= 0: empty_post). Pop idx2 over m2; P2 = (xc,
//     yc, lo2 + idx2); q2 = P2 + W2, w2 = W2, turned back to the original frame.
// Why a bijection: every step is exactly invertible given what the reverse reads from the post
// state: face, column, normal and L from P2 = q2 - w2; Phi' from u' = L(w2); the aligned (x_a',
// y'), the cell b (step 7's check), the row of (Phi', x_a'), and the post phase. The reverse
// pushes idx2, the post offset and (Phi', b), shifts by -G, pops (Phi, a), rotates back, pops
// the pre offset over the row of (Phi, x_a) and the pre phase.
// Why X stays bounded under the flux law: per collision X grows by log2(m m_row / f(a)) and
// shrinks by log2(m2 m_row' / f(b)); m ~ cos(theta), m_row ~ sin(theta), f ~ sin(theta)
// cos(theta) dtheta: the two balance (measured in test_lattice_pair3d).
// Energy: the theta rotation and L move |w| by about a unit (as in 2D); re-drawing the offset
// across an azimuth cell changes |w|^2 by at most (|u_xy| dphi / 2)^2 <= 2^-32.7 |w|^2 at 2^18
// cells (dphi = 2 pi / 2^18; measured: docs/lattice.md).
//
// Refusals (the forward changes nothing and the engine redraws or logs): not_approaching and
// out_of_domain before step 5 do not depend on G (check_pre reports them); cell_readback,
// empty_post and a later out_of_domain depend on G.
//
// Pair level (S-transform, as in 2D): d = v_i - v_j, s = v_j + (d >> 1), centre c = x_j + (r
// >> 1) with r = x_i - x_j; the centre moves by s over the tick; positions modulo 2^64.
// Reversal convention: the reverse engine calls pair_reverse(x_i, x_j, -v_i, -v_j, G) exactly as
// in 2D; pair_reverse is the plain inverse of pair_forward.
#pragma once
#include <array>
#include <cstdint>
#include <optional>

#include "revcol/collide/common.hpp"
#include "revcol/lattice/bitsback.hpp"
#include "revcol/lattice/cells.hpp"
#include "revcol/lattice/int128.hpp"
#include "revcol/lattice/pair2d.hpp"

namespace revcol::lattice {

using Vec3 = std::array<std::int64_t, 3>;  ///< an integer 3D vector (x, y, z)

/// What one 3D forward did (for tests, statistics and the engine's counters).
struct Trace3 {
  int face = 0;             ///< 2 * axis + (sign < 0), axis 0..2 = x, y, z
  i64 m = 0;                ///< number of pre phases
  i64 m2 = 0;               ///< number of post phases (0 before step 8)
  i64 row = 0;              ///< pre row length (azimuth offsets)
  i64 row2 = 0;             ///< post row length (0 before step 7)
  std::int64_t phi = 0;     ///< pre azimuth cell
  std::int64_t phi2 = 0;    ///< post azimuth cell
  std::int64_t a = 0;       ///< pre polar cell
  std::int64_t b = 0;       ///< post polar cell
};

/// The exact 3D pair operator for spheres of diameter sigma lattice units.
class LatticePair3D {
 public:
  /// Throws InvalidArgument unless 2 <= sigma <= 2^60 and 12 <= cell_bits <= 20.
  explicit LatticePair3D(std::int64_t sigma, Law law = Law::flux, int cell_bits = 16);
  static constexpr int draw_bits = 48;                      ///< G is a 48-bit integer
  static constexpr int phi_bits = 18;                       ///< 2^18 azimuth cells per turn
  static constexpr int theta_total_bits = draw_bits - phi_bits;  ///< the polar table's total 2^30
  static constexpr std::int64_t max_component = 1LL << 61;  ///< |q|, |w| components must be below

  std::int64_t sigma() const { return sigma_; }  ///< sphere diameter in lattice units
  Law law() const { return law_; }               ///< flux or uniform
  int cell_bits() const { return kCellBits - shift_; }  ///< 2^cell_bits polar cells per turn
  std::int64_t polar_cells() const { return quarter_ + 1; }  ///< polar cells in [0, pi/2): 2^cell_bits / 4 + 1

  /// The G-independent refusal of a pre state (none, not_approaching or out_of_domain).
  Refusal check_pre(const Vec3& q, const Vec3& w) const;
  /// Relative pre state -> relative post state and X_out (X itself unchanged); Refusal::none or
  /// why this G must be redrawn (then X_out == X). Throws InvalidArgument on a state outside the
  /// contract (|q|^2 >= sigma^2 > |q+w|^2, components below 2^61), g >= 2^48, or X_out being X.
  Refusal forward(const Vec3& q, const Vec3& w, std::uint64_t g, const BitsBack& X, Vec3& q2, Vec3& w2,
                  BitsBack& X_out, Trace3* trace = nullptr) const;
  /// The exact inverse of an accepted forward, in place on X. Throws InvalidArgument (X
  /// unchanged) when (q2, w2, X) cannot be such an output.
  void reverse(const Vec3& q2, const Vec3& w2, std::uint64_t g, BitsBack& X, Vec3& q, Vec3& w) const;
  /// Pair level (S-transform): absolute positions at tick a-1 (xi = xj + minimum image, the
  /// caller unwraps and wraps), velocities below 2^59 per component; as forward otherwise.
  Refusal pair_forward(const Vec3& xi, const Vec3& xj, const Vec3& vi, const Vec3& vj, std::uint64_t g,
                       const BitsBack& X, Vec3& xi2, Vec3& xj2, Vec3& vi2, Vec3& vj2, BitsBack& X_out,
                       Trace3* trace = nullptr) const;
  /// Inverse of pair_forward.
  void pair_reverse(const Vec3& xi2, const Vec3& xj2, const Vec3& vi2, const Vec3& vj2, std::uint64_t g,
                    BitsBack& X, Vec3& xi, Vec3& xj, Vec3& vi, Vec3& vj) const;

  /// The polar table's cumulative frequency below cell b, b in [0, polar_cells()] (total 2^30).
  std::uint64_t cum(std::int64_t b) const;
  /// The polar cell b with cum(b) <= s < cum(b + 1), s < 2^30; writes c = cum(b), f = cum(b+1) - c.
  std::int64_t decode(std::uint64_t s, std::uint64_t& c, std::uint64_t& f) const;
  /// The row [ylo, yhi] of azimuth cell phi at aligned distance xa: the y whose aligned point
  /// (xa, y), turned back by the cell's centre, lies in the cell; nullopt when empty or ragged.
  static std::optional<std::array<i64, 2>> row(std::int64_t phi, i64 xa);
  /// The face frame of p != 0: its face index (2 * axis + (sign < 0)).
  static int face_of(const Vec3& p);
  /// v in the frame of face f (the face's axis to +z).
  static Vec3 to_face(const Vec3& v, int f);
  /// The inverse of to_face.
  static Vec3 from_face(const Vec3& v, int f);
  /// The lowest z of face f's column (xc, yc): max(1, |xc| + sx, |yc| + sy), sx, sy = 1 where
  /// the frame axis has priority over the face axis (strict ties).
  static i64 zmin_of(int face, i64 xc, i64 yc);
  /// The lowest pre phase of column (xc, yc) (face frame, z in [zmin, zin]) for inward W: the
  /// inside points whose point minus W is outside form [lo, zin] (lo = zin + 1: none); nullopt
  /// when they do not form an interval.
  static std::optional<i64> lo_pre(i128 sigma2, i64 xc, i64 yc, i64 zmin, i64 zin, const Vec3& W);

 private:
  std::int64_t sigma_;
  i128 sigma2_;
  Law law_;
  int shift_;            // polar cells are 2^shift_ of cells.hpp's 2^20 per turn
  std::int64_t quarter_; // polar cells in [0, pi/2)
};

}  // namespace revcol::lattice
