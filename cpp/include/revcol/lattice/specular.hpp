// The deterministic specular pair operator of the lattice engine (2D disks and 3D spheres): true
// hard-sphere dynamics, reversed bit for bit with no random numbers, no bits-back integer and no
// log but for the rare cases the engine resolves (docs/specular.md; engine: src/lattice/collide.hpp).
//
// The event rule is the flux law's (LATTICE.md §2): a pair collides on the transition a-1 -> a,
// the pre state being q = x_i - x_j at a-1 outside (|q|^2 >= sigma^2), w = v_i - v_j, the inside
// point p = q + w (|p|^2 < sigma^2); the post state is q2 at a outside with q2 - w2 inside. The
// map T: (q, w) -> (q2, w2) built here satisfies T R T R = identity, R: (q, w) -> (q, -w): the
// time reverse of a collision is the collision (the reverse engine applies T to the negated post
// state; pair_unmap is R T R, T's exact inverse).
//
// Relative map (face frame of p: pair2d.hpp's quarter turns in 2D, pair3d.hpp's cube faces in 3D;
// the column, xc in 2D or (xc, yc) in 3D, is the invariant both directions read):
//  1. Normal: the column's normal n = (xc, h) / sigma (3D: (xc, yc, h) / sigma), h =
//     isqrt(sigma^2 - |column|^2): the contact normal within |w| / sigma of the true one.
//  2. Velocity: V = Q^-1 F Q, Q a lifting rotation taking n to the last axis (2D: one rotation by
//     asin(xc / sigma); 3D: a quarter turn and a rotation by the azimuth in (x, y), then one by
//     the polar angle in (x, z)), F the sign flip of the last axis. Coefficients are 62-bit fixed
//     point computed from the integers of the column (the same bits in both directions). Every
//     shear adds an EVEN integer rounded half away from zero: V is an exact involution of Z^D
//     (V V = 1, Q^-1 undoes Q), odd (V(-w) = -V(w)), and keeps each component's parity, so the
//     S-transform gives post velocities whose sum is exactly the pre sum (momentum exact). V is the
//     reflection of w about the tangent plane of n to within a few lattice units (|w| ~ 2^30):
//     energy is kept to that rounding.
//  3. Phases: the inside points of the column whose point minus W is outside form [lo(W), zin]
//     (the flux operator's pre phases), m(W) of them; depth d = zin - P_z. With W~ = -V(W) (the
//     reflection about the tangent plane: an involution too) and c = min(m(W), m(W~)) - 1:
//       d <= c: w2 = V(W), post depth c - d (the sub-tick phase carried across: a contact late in
//               the tick leaves late), P2 = (column, zin - (c - d));
//       d > c:  w2 = -W, P2 = P (the pair turns back in place: a backscatter). Only when the post
//               column has fewer phases than the pre one, m(W~) < m(W), by the curvature of the
//               sphere across one tick (~ |w|^2 / sigma units out of m ~ |w|): rate about
//               2^-T per collision (T = tick_bits); counted, never silent.
//     q2 = P2 + w2. The post state has P2 inside and q2 outside by construction (P2's depth is a
//     post phase of w2), P2 in the same face and column, so the reverse reads the same normal and
//     the same pair {W, W~}; c is symmetric in the pair, so T applied to (q2, -w2) gives (q, -w).
//     The two cases fill exactly the m(W) + m(W~) post slots of the velocities V(W) and -W: T is
//     a bijection between pre and post states.
//  Refusal (out_of_domain; the engine resolves the collision as a group, counted in the rare log):
//  coinciding centres at a (p = 0: no face), pre phases not an interval, a velocity component at
//  or beyond 2^59 (pair level) or 2^60 (relative). Each refusal is symmetric: a post state T
//  writes is never refused by the reverse.
//
// Pair level: the S-transform of the flux operators (pair2d.hpp): d = v_i - v_j, s = v_j + (d >>
// 1), centre c = x_j + (r >> 1); the centre moves by s over the tick; positions modulo 2^64.
#pragma once
#include <array>
#include <cstdint>

#include "revcol/lattice/geometry.hpp"
#include "revcol/lattice/int128.hpp"
#include "revcol/lattice/pair2d.hpp"
#include "revcol/lattice/pair3d.hpp"

namespace revcol::lattice {

/// What one specular map did (tests and the engine's counters).
struct SpecularTrace {
  i64 m = 0;                 ///< pre phases m(W)
  i64 m2 = 0;                ///< phases of the reflected velocity, m(W~)
  bool backscatter = false;  ///< the pair turned back in place (d > c)
};

/// Fixed-point lifting coefficients of a rotation taking (a, b) / r to (0, 1) in a plane:
/// p = -a / (r + b), s = a / r, both times 2^62 (|a| <= r, b >= 0).
struct Shear3 {
  i64 p = 0;  ///< -tan(angle / 2) 2^62
  i64 s = 0;  ///< sin(angle) 2^62
  /// Coefficients for the normal (a, b) of length r (b = sqrt(r^2 - a^2) rounded down).
  static Shear3 of(i64 a, i64 b, i64 r);
  /// The rotation on (x, y) with even, half-away rounded shears (parity of each kept).
  void apply(i64& x, i64& y) const;
  /// Its exact inverse.
  void undo(i64& x, i64& y) const;
};

/// The deterministic specular map for disks (D = 2) or spheres (D = 3) of diameter sigma
/// lattice units.
template <std::size_t D>
class LatticeSpecular {
 public:
  using Vec = VecN<D>;                 ///< an integer vector
  using Column = std::array<i64, D - 1>;  ///< a column of the face frame: xc (2D), (xc, yc) (3D)
  /// Throws InvalidArgument unless 2 <= sigma <= 2^61 (2D) or 2^60 (3D).
  explicit LatticeSpecular(std::int64_t sigma);
  static constexpr std::int64_t max_velocity = 1LL << 59;  ///< pair level: |v| components below
  std::int64_t sigma() const { return sigma_; }             ///< diameter in lattice units

  /// V(w): w reflected about the normal of a column (face frame, |column| < sigma, |w|
  /// components below 2^60), an involution of Z^D.
  Vec reflect(const Column& c, const Vec& w) const;
  /// Relative pre state (|q|^2 >= sigma^2 > |q + w|^2, |q| components below 2^61, |w| below
  /// 2^60) -> post state; Refusal::none or out_of_domain (q2, w2 then unspecified). Throws
  /// InvalidArgument on a state outside that contract.
  Refusal map(const Vec& q, const Vec& w, Vec& q2, Vec& w2, SpecularTrace* trace = nullptr) const;
  /// The exact inverse of map (R map R): post state -> pre state.
  Refusal unmap(const Vec& q2, const Vec& w2, Vec& q, Vec& w) const;
  /// Pair level: positions at tick a-1 (xi = xj + minimum image), velocities (components below
  /// 2^59) -> positions at a and post velocities (momentum exact).
  Refusal pair_map(const Vec& xi, const Vec& xj, const Vec& vi, const Vec& vj, Vec& xi2, Vec& xj2, Vec& vi2,
                   Vec& vj2, SpecularTrace* trace = nullptr) const;
  /// Inverse of pair_map: positions at a and post velocities -> positions at a-1 and pre.
  Refusal pair_unmap(const Vec& xi2, const Vec& xj2, const Vec& vi2, const Vec& vj2, Vec& xi, Vec& xj, Vec& vi,
                     Vec& vj) const;

 private:
  std::int64_t sigma_;
  i128 sigma2_;
};
/// The 2D map (disks).
using LatticeSpecular2D = LatticeSpecular<2>;
/// The 3D map (spheres).
using LatticeSpecular3D = LatticeSpecular<3>;
// the dimension-specific parts (specular.cpp), declared before the instantiations
template <>
Vec2 LatticeSpecular<2>::reflect(const Column& c, const Vec2& w) const;
template <>
Vec3 LatticeSpecular<3>::reflect(const Column& c, const Vec3& w) const;
template <>
Refusal LatticeSpecular<2>::map(const Vec2& q, const Vec2& w, Vec2& q2, Vec2& w2, SpecularTrace* trace) const;
template <>
Refusal LatticeSpecular<3>::map(const Vec3& q, const Vec3& w, Vec3& q2, Vec3& w2, SpecularTrace* trace) const;
extern template class LatticeSpecular<2>;
extern template class LatticeSpecular<3>;

}  // namespace revcol::lattice
