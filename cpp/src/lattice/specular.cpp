// The deterministic specular map of the lattice engine (revcol/lattice/specular.hpp): the lifting
// reflection, the phase bijection, and the pair level, in 2D and 3D.
#include <algorithm>

#include "revcol/error.hpp"
#include "revcol/lattice/geometry.hpp"
#include "revcol/lattice/specular.hpp"
#include "revcol/lattice/state.hpp"

namespace revcol::lattice {
namespace {

constexpr i64 kMaxQ = 1LL << 61;  // relative position components below
constexpr i64 kMaxW = 1LL << 60;  // relative velocity components below
constexpr int kFix = 62;

inline i128 sq(i64 a) { return static_cast<i128>(a) * a; }
inline bool small(i64 v, i64 bound) { return v > -bound && v < bound; }
template <std::size_t D>
bool small(const VecN<D>& v, i64 bound) {
  for (i64 c : v)
    if (!small(c, bound)) return false;
  return true;
}
// Wrapping (mod 2^64) arithmetic for positions: no signed overflow, two's complement result.
inline i64 wadd(i64 a, i64 b) { return static_cast<i64>(static_cast<std::uint64_t>(a) + static_cast<std::uint64_t>(b)); }
inline i64 wsub(i64 a, i64 b) { return static_cast<i64>(static_cast<std::uint64_t>(a) - static_cast<std::uint64_t>(b)); }

// round(|a| 2^62 / r) with a's sign, |a| <= r < 2^63
i64 fix_ratio(i64 a, i64 r) {
  const u128 n = (static_cast<u128>(a < 0 ? -static_cast<i128>(a) : static_cast<i128>(a)) << kFix) + static_cast<u128>(r) / 2;
  const i64 q = static_cast<i64>(n / static_cast<u128>(r));
  return a < 0 ? -q : q;
}
// 2 round(c y / 2^63) (half away from zero): an even shift, odd in y
inline i64 even_term(i64 c, i64 y) {
  const i128 t = static_cast<i128>(c) * y;
  const u128 mag = static_cast<u128>(t < 0 ? -t : t);
  const i64 r = static_cast<i64>((mag + (static_cast<u128>(1) << (kFix))) >> (kFix + 1));
  return t < 0 ? -2 * r : 2 * r;
}

// The relative map's phase step, shared by 2D and 3D: pre depth d in [0, m), m = m(W), m2 =
// m(W~); returns true (reflect, post depth written) or false (turn back in place).
inline bool carry_phase(i64 d, i64 m, i64 m2, i64& d2) {
  const i64 c = std::min(m, m2) - 1;
  if (d > c) return false;
  d2 = c - d;
  return true;
}

// The S-transform pair level over a relative map (2D or 3D): positions at a-1 and velocities ->
// positions at a and velocities; momentum exact when the relative map keeps each parity.
template <std::size_t D, class Map>
Refusal pair_level(const VecN<D>& xi, const VecN<D>& xj, const VecN<D>& vi, const VecN<D>& vj, VecN<D>& xi2,
                   VecN<D>& xj2, VecN<D>& vi2, VecN<D>& vj2, i64 vbound, const Map& map) {
  require(small(vi, vbound) && small(vj, vbound), "LatticeSpecular: velocity components must be below 2^59");
  VecN<D> r, c, d, s, r2, d2;
  for (std::size_t e = 0; e < D; ++e) {
    r[e] = wsub(xi[e], xj[e]);
    c[e] = wadd(xj[e], r[e] >> 1);
    d[e] = vi[e] - vj[e];
    s[e] = vj[e] + (d[e] >> 1);
  }
  const Refusal why = map(r, d, r2, d2);
  if (why != Refusal::none) return why;
  VecN<D> nvi, nvj;
  for (std::size_t e = 0; e < D; ++e) {
    nvj[e] = s[e] - (d2[e] >> 1);
    nvi[e] = nvj[e] + d2[e];
  }
  // the reverse would refuse these velocities: refuse them here (a symmetric refusal)
  if (!small(nvi, vbound) || !small(nvj, vbound)) return Refusal::out_of_domain;
  for (std::size_t e = 0; e < D; ++e) {
    xj2[e] = wsub(wadd(c[e], s[e]), r2[e] >> 1);
    xi2[e] = wadd(xj2[e], r2[e]);
  }
  vi2 = nvi;
  vj2 = nvj;
  return Refusal::none;
}

// The exact inverse of pair_level over the inverse relative map: the S-transform read from the
// post velocities (s = v_j2 + (d2 >> 1) is the forward's s), the centre moved back by s.
template <std::size_t D, class Unmap>
Refusal pair_level_back(const VecN<D>& xi2, const VecN<D>& xj2, const VecN<D>& vi2, const VecN<D>& vj2, VecN<D>& xi,
                        VecN<D>& xj, VecN<D>& vi, VecN<D>& vj, i64 vbound, const Unmap& unmap) {
  require(small(vi2, vbound) && small(vj2, vbound), "LatticeSpecular: velocity components must be below 2^59");
  VecN<D> r2, c, d2, s, r, d;
  for (std::size_t e = 0; e < D; ++e) {
    r2[e] = wsub(xi2[e], xj2[e]);
    d2[e] = vi2[e] - vj2[e];
    s[e] = vj2[e] + (d2[e] >> 1);
    c[e] = wsub(wadd(xj2[e], r2[e] >> 1), s[e]);
  }
  const Refusal why = unmap(r2, d2, r, d);
  if (why != Refusal::none) return why;
  VecN<D> nvi, nvj;
  for (std::size_t e = 0; e < D; ++e) {
    nvj[e] = s[e] - (d[e] >> 1);
    nvi[e] = nvj[e] + d[e];
  }
  if (!small(nvi, vbound) || !small(nvj, vbound)) return Refusal::out_of_domain;
  for (std::size_t e = 0; e < D; ++e) {
    xj[e] = wsub(c[e], r[e] >> 1);
    xi[e] = wadd(xj[e], r[e]);
  }
  vi = nvi;
  vj = nvj;
  return Refusal::none;
}

}  // namespace

Shear3 Shear3::of(i64 a, i64 b, i64 r) { return {fix_ratio(-a, r + b), fix_ratio(a, r)}; }

void Shear3::apply(i64& x, i64& y) const {
  x += even_term(p, y);
  y += even_term(s, x);
  x += even_term(p, y);
}

void Shear3::undo(i64& x, i64& y) const {
  x -= even_term(p, y);
  y -= even_term(s, x);
  x -= even_term(p, y);
}

template <std::size_t D>
LatticeSpecular<D>::LatticeSpecular(std::int64_t sigma) : sigma_(sigma), sigma2_(sq(sigma)) {
  require(sigma >= 2 && sigma <= (D == 2 ? (1LL << 61) : (1LL << 60)),
          D == 2 ? "LatticeSpecular2D: sigma must be in [2, 2^61] lattice units"
                 : "LatticeSpecular3D: sigma must be in [2, 2^60] lattice units");
}

// ---- 2D ----

template <>
Vec2 LatticeSpecular<2>::reflect(const Column& col, const Vec2& w) const {
  const i64 xc = col[0];
  require(small(xc, sigma_) && small(w, kMaxW), "LatticeSpecular2D::reflect: |xc| < sigma and |w| components below 2^60");
  const i64 h = static_cast<i64>(isqrt(static_cast<u128>(sigma2_ - sq(xc))));
  const Shear3 q = Shear3::of(xc, h, sigma_);  // takes (xc, h) to (0, sigma)
  i64 x = w[0], y = w[1];
  q.apply(x, y);
  y = -y;
  q.undo(x, y);
  return {x, y};
}

template <>
Refusal LatticeSpecular<2>::map(const Vec2& q, const Vec2& w, Vec2& q2, Vec2& w2, SpecularTrace* trace) const {
  require(small(q, kMaxQ) && small(w, kMaxW), "LatticeSpecular2D: |q| components must be below 2^61, |w| below 2^60");
  require(norm2(q) >= static_cast<u128>(sigma2_), "LatticeSpecular2D::map: q must be outside (|q|^2 >= sigma^2)");
  const i64 px = q[0] + w[0], py = q[1] + w[1];
  require(sq(px) + sq(py) < sigma2_, "LatticeSpecular2D::map: q + w must be inside (|q+w|^2 < sigma^2)");
  if (px == 0 && py == 0) return Refusal::out_of_domain;  // coinciding centres at a: no face
  const int f = face_of(px, py), strict = f & 1;
  const IVec P = rot90({px, py}, f), W = rot90({w[0], w[1]}, f);
  const i64 yin = static_cast<i64>(isqrt(static_cast<u128>(sigma2_ - sq(P.x) - 1)));
  const auto lo = lo_pre(sigma2_, P.x, strict, W.x, W.y);
  if (!lo) return Refusal::out_of_domain;
  const i64 m = yin - *lo + 1;
  const Vec2 V = reflect({P.x}, {W.x, W.y});
  if (!small(V, kMaxW)) return Refusal::out_of_domain;
  const auto lo2 = lo_pre(sigma2_, P.x, strict, -V[0], -V[1]);  // the phases of W~ = -V(W)
  const i64 m2 = lo2 ? std::max<i64>(0, yin - *lo2 + 1) : 0;
  i64 d2 = 0;
  const bool reflected = carry_phase(yin - P.y, m, m2, d2);
  const IVec W2 = reflected ? IVec{V[0], V[1]} : IVec{-W.x, -W.y};
  const IVec P2 = reflected ? IVec{P.x, yin - d2} : P;
  const IVec Q2 = rot90({P2.x + W2.x, P2.y + W2.y}, -f), w2f = rot90(W2, -f);
  q2 = {Q2.x, Q2.y};
  w2 = {w2f.x, w2f.y};
  if (trace) *trace = {m, m2, !reflected};
  return Refusal::none;
}

// ---- 3D ----

template <>
Vec3 LatticeSpecular<3>::reflect(const Column& col, const Vec3& w) const {
  const i64 xc = col[0], yc = col[1];
  const i128 r2 = sq(xc) + sq(yc);
  require(r2 < sigma2_ && small(w, kMaxW), "LatticeSpecular3D::reflect: |column| < sigma and |w| components below 2^60");
  // a quarter turn in (x, y) puts the column in the sector x > 0, |y| <= x (the first that does)
  int k = 0;
  IVec c{xc, yc};
  if (r2 != 0)
    for (; k < 4; ++k) {
      c = rot90({xc, yc}, k);
      if (c.x > 0 && (c.y < 0 ? -c.y : c.y) <= c.x) break;
    }
  const i64 rho = static_cast<i64>(isqrt(static_cast<u128>(r2)));
  const i64 h = static_cast<i64>(isqrt(static_cast<u128>(sigma2_ - r2)));
  // in (x, y): (c.x, c.y) -> (rho, 0), i.e. the 2D rotation taking (-c.y, c.x) to (0, rho)
  const Shear3 az = r2 != 0 ? Shear3::of(-c.y, c.x, rho) : Shear3{};
  const Shear3 po = Shear3::of(rho, h, sigma_);  // in (x, z): (rho, h) -> (0, sigma)
  IVec xy = rot90({w[0], w[1]}, k);
  i64 z = w[2];
  // az takes (a, b) = (-y, x) about; write it on (u, v) = (-y, x) and map back
  i64 u = -xy.y, v = xy.x;
  az.apply(u, v);
  i64 x = v, y = -u;
  po.apply(x, z);
  z = -z;
  po.undo(x, z);
  u = -y;
  v = x;
  az.undo(u, v);
  xy = rot90({v, -u}, -k);
  return {xy.x, xy.y, z};
}

template <>
Refusal LatticeSpecular<3>::map(const Vec3& q, const Vec3& w, Vec3& q2, Vec3& w2, SpecularTrace* trace) const {
  require(small(q, kMaxQ) && small(w, kMaxW), "LatticeSpecular3D: |q| components must be below 2^61, |w| below 2^60");
  require(norm2(q) >= static_cast<u128>(sigma2_), "LatticeSpecular3D::map: q must be outside (|q|^2 >= sigma^2)");
  const Vec3 p{q[0] + w[0], q[1] + w[1], q[2] + w[2]};
  require(norm2(p) < static_cast<u128>(sigma2_), "LatticeSpecular3D::map: q + w must be inside (|q+w|^2 < sigma^2)");
  if (p == Vec3{}) return Refusal::out_of_domain;  // coinciding centres at a: no face
  const int f = LatticePair3D::face_of(p);
  const Vec3 P = LatticePair3D::to_face(p, f), W = LatticePair3D::to_face(w, f);
  const i64 zmin = LatticePair3D::zmin_of(f, P[0], P[1]);
  const i64 zin = static_cast<i64>(isqrt(static_cast<u128>(sigma2_ - sq(P[0]) - sq(P[1]) - 1)));
  const auto lo = LatticePair3D::lo_pre(sigma2_, P[0], P[1], zmin, zin, W);
  if (!lo) return Refusal::out_of_domain;
  const i64 m = zin - *lo + 1;
  const Vec3 V = reflect({P[0], P[1]}, W);
  if (!small(V, kMaxW)) return Refusal::out_of_domain;
  const auto lo2 = LatticePair3D::lo_pre(sigma2_, P[0], P[1], zmin, zin, neg(V));
  const i64 m2 = lo2 ? std::max<i64>(0, zin - *lo2 + 1) : 0;
  i64 d2 = 0;
  const bool reflected = carry_phase(zin - P[2], m, m2, d2);
  const Vec3 W2 = reflected ? V : neg(W);
  const Vec3 P2 = reflected ? Vec3{P[0], P[1], zin - d2} : P;
  q2 = LatticePair3D::from_face({P2[0] + W2[0], P2[1] + W2[1], P2[2] + W2[2]}, f);
  w2 = LatticePair3D::from_face(W2, f);
  if (trace) *trace = {m, m2, !reflected};
  return Refusal::none;
}

// ---- both ----

template <std::size_t D>
Refusal LatticeSpecular<D>::unmap(const Vec& q2, const Vec& w2, Vec& q, Vec& w) const {
  Vec nw;
  const Refusal why = map(q2, neg(w2), q, nw);
  if (why == Refusal::none) w = neg(nw);
  return why;
}

template <std::size_t D>
Refusal LatticeSpecular<D>::pair_map(const Vec& xi, const Vec& xj, const Vec& vi, const Vec& vj, Vec& xi2, Vec& xj2,
                                     Vec& vi2, Vec& vj2, SpecularTrace* trace) const {
  return pair_level<D>(xi, xj, vi, vj, xi2, xj2, vi2, vj2, max_velocity,
                       [&](const Vec& r, const Vec& d, Vec& r2, Vec& d2) { return map(r, d, r2, d2, trace); });
}

template <std::size_t D>
Refusal LatticeSpecular<D>::pair_unmap(const Vec& xi2, const Vec& xj2, const Vec& vi2, const Vec& vj2, Vec& xi,
                                       Vec& xj, Vec& vi, Vec& vj) const {
  return pair_level_back<D>(xi2, xj2, vi2, vj2, xi, xj, vi, vj, max_velocity,
                            [&](const Vec& r2, const Vec& d2, Vec& r, Vec& d) { return unmap(r2, d2, r, d); });
}

template class LatticeSpecular<2>;
template class LatticeSpecular<3>;

}  // namespace revcol::lattice
