// The exact pair operator of the 2D lattice engine (LATTICE.md §3, docs/lattice.md).
//
// Units: positions in lattice units (disk diameter sigma, a runtime integer 2 <= sigma <= 2^61),
// velocities in lattice units per tick, time in ticks. A pair collides on the transition from
// tick a-1 to tick a, where a is the first tick at which its incoming lines overlap.
//
// Relative operator (forward). Pre state: q = x_i - x_j at tick a-1 with |q|^2 >= sigma^2,
// w = v_i - v_j with p = q + w inside (|p|^2 < sigma^2). Steps:
//  1. Face: the quarter turn f that puts p in the upper sector (py > 0, |px| <= py; for odd f
//     strictly |px| < py). In that frame p = (xc, Py), w = (Wx, Wy); the column xc is fixed.
//  2. Phase interval: the inside points of column xc in the face, Y <= Yin = isqrt(sigma^2 -
//     xc^2 - 1), Y >= max(1, |xc| + (f odd)), whose point minus W is outside, form [lo, Yin]
//     (exact integer square roots; if they do not form an interval, or p = 0 has no face:
//     out_of_domain);
//     m = Yin - lo + 1. X <- X*m + (Py - lo).
// Direction cells: ND = 2^cell_bits equal-angle cells per turn (12..20, default 20; the engine
// takes it from its Units). A coarse cell is 2^(20 - cell_bits) of cells.hpp's cells, so it is
// decided by the same exact boundaries (coarse cell = fine cell >> shift), and its flux
// frequency is the sum of its fine cells'. Fewer cells make the step-5 read-back refusal rarer
// (it needs the lifting's ~1-unit round-off to cross a cell boundary: probability ~ ND / |W|)
// at no cost to the law (the post direction keeps the pre direction's offset in its cell).
//  3. Pre direction: jn = normal cell of column xc, jd = cell of W, jpre = ((jd - jn) mod ND)
//     - ND/2 is the cell of -W about the normal; it must lie in [-ND/4, ND/4) (else
//     not_approaching). rANS push of a = jpre + ND/4 with the law's (cum, f).
//  4. Torus shift: the low 48 bits s of X become (s + G) mod 2^48 (u_post = u_pre + G mod 1).
//  5. Post direction: rANS pop of b, jpost = b - ND/4; rotate W by k = jn + jpost - jd cells
//     with the lifting rotation (cells.hpp) to W2. If the cell of W2 is not jn + jpost (a
//     round-off of the lifting across a cell boundary): cell_readback (reported after step
//     6's out_of_domain and empty_post, the prototype's order).
//  6. Post phase: the inside points of the column whose point plus W2 is outside form
//     [lo2, Yin] (or out_of_domain); m2 = Yin - lo2 + 1 (m2 <= 0: empty_post). idx2 = X mod
//     m2, X <- X div m2, P2 = (xc, lo2 + idx2). Post state: q2 = P2 + W2, w2 = W2, turned back
//     by -f. So |q2|^2 >= sigma^2 and q2 - w2 = P2 is inside: read backwards with the
//     velocity negated it is again "outside at a, inside at a-1", the same event.
// Why a bijection: each step is exactly invertible given what the reverse can read from the
// post state (face and column from P2 = q2 - w2, jn from the column, jpost from the cell of W2,
// which step 5 guarantees), and the reverse runs the inverse steps backwards: push idx2 over
// m2, rANS push b, shift by -G, rANS pop a, rotate back by the same k, pop the pre phase.
//
// Refusals (the forward changes nothing and the engine redraws or logs): not_approaching and
// out_of_domain from step 2 do not depend on G (check_pre reports them; no redraw helps);
// cell_readback, empty_post and out_of_domain from step 6 depend on G (a redraw helps).
//
// Pair level (S-transform, LATTICE.md §3.1): d = v_i - v_j, s = v_j + (d >> 1), the centre
// c = x_j + (r >> 1) with r = x_i - x_j; the centre moves by s over the tick, d and r go
// through the relative operator: x_j' = c + s - (r' >> 1), x_i' = x_j' + r', v_j' = s -
// (d' >> 1), v_i' = v_j' + d' (>> is floor; an integer bijection for equal masses). Positions
// are computed modulo 2^64 (two's complement): the result is the unwrapped position whenever
// that fits in int64; the caller wraps into its box.
//
// Reversal convention (the prototype's engine.py): the reverse engine runs on (x, -v). At a
// collision it holds the post positions at forward tick a and the negated post velocities; it
// calls pair_reverse(x_i, x_j, -v_i, -v_j, G) (the same i, j order and the same G as the
// forward), gets the positions at forward tick a-1 and the pre velocities, and stores the
// negated pre velocities. So pair_reverse itself is the plain inverse of pair_forward.
#pragma once
#include <array>
#include <cstdint>
#include <optional>

#include "revcol/collide/common.hpp"
#include "revcol/lattice/bitsback.hpp"
#include "revcol/lattice/cells.hpp"
#include "revcol/lattice/int128.hpp"

namespace revcol::lattice {

using Vec2 = std::array<std::int64_t, 2>;  ///< an integer 2D vector (x, y)

/// Why a candidate post state must be redrawn by the engine (none: accepted by the operator).
enum class Refusal : std::uint8_t { none, cell_readback, not_approaching, empty_post, out_of_domain };
/// "none", "cell_readback", ...
const char* to_string(Refusal r);

/// The face (quarter turn 0..3) that puts p in the upper sector: 0 for py > 0, |px| <= py;
/// 1 for px > 0, |py| < px; 2 for py < 0, |px| <= -py; 3 otherwise (p != 0).
int face_of(i64 px, i64 py);
/// The lowest pre phase of column xc (face frame) for inward W, or nullopt when the pre phases
/// do not form an interval [lo, Yin]; strict = 1 for odd faces.
std::optional<i64> lo_pre(i128 sigma2, i64 xc, int strict, i64 wx, i64 wy);
/// The lowest post phase of column xc for outgoing W2, or nullopt when not an interval.
std::optional<i64> lo_post(i128 sigma2, i64 xc, int strict, i64 wx, i64 wy);

/// What one forward did (for tests, statistics and the engine's counters).
struct Trace {
  int face = 0;           ///< quarter turn of the face frame
  i64 m = 0;              ///< number of pre phases
  i64 m2 = 0;             ///< number of post phases (0 before step 6)
  std::int64_t jn = 0;    ///< normal cell
  std::int64_t jpre = 0;  ///< pre cell about the normal, [-ND/4, ND/4)
  std::int64_t jpost = 0; ///< post cell about the normal, [-ND/4, ND/4)
};

/// Allowed direction-cell resolutions: 2^cell_bits cells per turn (cells.hpp's 2^20 is the finest).
inline constexpr int min_cell_bits = 12, max_cell_bits = kCellBits;

/// The exact pair operator (LATTICE.md §3) for disks of diameter sigma lattice units.
class LatticePair2D {
 public:
  /// Throws InvalidArgument unless 2 <= sigma <= 2^61 and 12 <= cell_bits <= 20.
  explicit LatticePair2D(std::int64_t sigma, Law law = Law::flux, int cell_bits = kCellBits);
  static constexpr int draw_bits = 48;   ///< G is a 48-bit integer
  static constexpr std::int64_t max_component = 1LL << 62;  ///< |q|, |w| components must be below

  std::int64_t sigma() const { return sigma_; }  ///< disk diameter in lattice units
  Law law() const { return law_; }               ///< flux or uniform
  int cell_bits() const { return kCellBits - shift_; }  ///< 2^cell_bits direction cells per turn
  std::int64_t cells() const { return mask_ + 1; }      ///< ND, direction cells per turn

  /// The G-independent refusal of a pre state (none, not_approaching or out_of_domain): when
  /// it is not none, no redraw can help. Same input checks as forward.
  Refusal check_pre(const Vec2& q, const Vec2& w) const;
  /// Relative pre state: q = x_i - x_j at tick a-1, |q|^2 >= sigma^2; w = v_i - v_j; |q+w|^2 < sigma^2.
  /// Writes the relative post state at tick a (|q2|^2 >= sigma^2, |q2 - w2|^2 < sigma^2) and
  /// X_out; X itself is never changed. Returns Refusal::none, or why this G must be redrawn
  /// (then q2, w2 are unspecified and X_out == X). Throws InvalidArgument on a state outside
  /// the contract, on g >= 2^48 or when X_out is X.
  Refusal forward(const Vec2& q, const Vec2& w, std::uint64_t g, const BitsBack& X,
                  Vec2& q2, Vec2& w2, BitsBack& X_out, Trace* trace = nullptr) const;
  /// The exact inverse of an accepted forward: (q2, w2, g, X_out) -> (q, w, X), in place on X.
  /// Throws InvalidArgument (X unchanged) when (q2, w2, X) cannot be such an output.
  void reverse(const Vec2& q2, const Vec2& w2, std::uint64_t g, BitsBack& X, Vec2& q, Vec2& w) const;
  /// Pair level (S-transform): absolute positions at tick a-1 (xi is xj plus the minimum-image
  /// relative vector: the caller unwraps; unwrapped positions at tick a come back, the caller
  /// wraps), velocities; same contract as forward. |v| components must be below 2^61.
  Refusal pair_forward(const Vec2& xi, const Vec2& xj, const Vec2& vi, const Vec2& vj, std::uint64_t g,
                       const BitsBack& X, Vec2& xi2, Vec2& xj2, Vec2& vi2, Vec2& vj2, BitsBack& X_out,
                       Trace* trace = nullptr) const;
  /// Inverse of pair_forward: from positions at tick a and post velocities back to tick a-1 and pre.
  void pair_reverse(const Vec2& xi2, const Vec2& xj2, const Vec2& vi2, const Vec2& vj2, std::uint64_t g,
                    BitsBack& X, Vec2& xi, Vec2& xj, Vec2& vi, Vec2& vj) const;

  /// The law's cumulative frequency of relative cell a in [0, ND/2] (total 2^48).
  std::uint64_t cum(std::int64_t a) const;
  /// The relative cell b with cum(b) <= s < cum(b+1), s < 2^48.
  std::int64_t decode(std::uint64_t s) const;
  /// As decode, also writing c = cum(b) and f = cum(b+1) - cum(b).
  std::int64_t decode(std::uint64_t s, std::uint64_t& c, std::uint64_t& f) const;

 private:
  std::int64_t dir(i64 wx, i64 wy) const { return dir_cell(wx, wy) >> shift_; }  // the (coarse) cell of w
  std::int64_t sigma_;
  i128 sigma2_;
  Law law_;
  int shift_;               // cells are 2^shift_ of cells.hpp's 2^20 per turn
  std::int64_t mask_;       // ND - 1
  std::int64_t half_;       // ND / 2
  std::int64_t quarter_;    // ND / 4
  std::uint64_t ufreq_;     // the uniform law's frequency, 2^48 / (ND / 2)
};

}  // namespace revcol::lattice
