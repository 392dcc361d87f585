// Tests of the deterministic specular lattice map (revcol/lattice/specular.hpp): on every pre
// state of a small disk and sphere, the map is a bijection onto valid post states with T R T R = 1;
// the velocity map is an involution, odd and parity-keeping; at the engine's scale it is the
// reflection about the contact normal to a few units, keeps the momentum exactly and the energy
// to the rounding, and turns back in place at a rate of order 2^-T.
#include <cmath>
#include <cstdio>
#include <numbers>
#include <set>
#include <tuple>

#include "check.hpp"
#include "lattice_test_util.hpp"
#include "revcol/error.hpp"
#include "revcol/lattice/specular.hpp"
#include "revcol/lattice/state.hpp"

using namespace revcol::lattice;
using revcol::InvalidArgument;

namespace {

using lattice_test::Rng;

template <std::size_t D>
i128 n2(const VecN<D>& v) {
  i128 s = 0;
  for (i64 c : v) s += static_cast<i128>(c) * c;
  return s;
}
template <std::size_t D>
VecN<D> add(const VecN<D>& a, const VecN<D>& b) {
  VecN<D> o;
  for (std::size_t k = 0; k < D; ++k) o[k] = a[k] + b[k];
  return o;
}

// Every pre state (q, w) of the box |q| <= R, |w| <= K: post valid, unmap exact, T R T R = 1,
// no two pre states with one post state. Returns {pre states, backscatters}.
template <std::size_t D, class Op>
std::pair<long, long> exhaustive(const Op& op, i64 R, i64 K) {
  const i128 s2 = static_cast<i128>(op.sigma()) * op.sigma();
  std::set<std::pair<VecN<D>, VecN<D>>> seen;
  long n = 0, back = 0, bad = 0;
  VecN<D> q{}, w{};
  auto each = [&](auto&& self, std::size_t k) -> void {
    if (k == 2 * D) {
      if (n2(q) < s2 || n2(add(q, w)) >= s2) return;
      VecN<D> q2, w2, q3, w3, q4, w4;
      SpecularTrace tr;
      if (op.map(q, w, q2, w2, &tr) != Refusal::none) return;
      ++n;
      back += tr.backscatter ? 1 : 0;
      const bool post_ok = n2(q2) >= s2 && n2(sub(q2, w2)) < s2;
      const bool inv = op.unmap(q2, w2, q3, w3) == Refusal::none && q3 == q && w3 == w;
      const bool trtr = op.map(q2, neg(w2), q4, w4) == Refusal::none && q4 == q && w4 == neg(w);
      const bool fresh = seen.insert({q2, w2}).second;
      if (!(post_ok && inv && trtr && fresh) && ++bad <= 5) std::fprintf(stderr, "bad state %ld\n", n);
      return;
    }
    const bool pos = k < D;
    const i64 lim = pos ? R : K;
    for (i64 c = -lim; c <= lim; ++c) {
      (pos ? q[k] : w[k - D]) = c;
      self(self, k + 1);
    }
  };
  each(each, 0);
  CHECK(bad == 0);
  return {n, back};
}

// A pre state at the engine's scale: contact normal n, relative speed |w| ~ 2^30, phase tau.
template <std::size_t D>
bool realistic(Rng& r, i64 sigma, double speed, VecN<D>& q, VecN<D>& w, std::array<double, D>& n) {
  double nn = 0, ww = 0, wn = 0;
  std::array<double, D> wd;
  for (std::size_t k = 0; k < D; ++k) {
    n[k] = r.uni() * 2 - 1;
    wd[k] = r.uni() * 2 - 1;
    nn += n[k] * n[k];
  }
  for (std::size_t k = 0; k < D; ++k) n[k] /= std::sqrt(nn);
  for (std::size_t k = 0; k < D; ++k) wn += wd[k] * n[k];
  if (wn > 0)
    for (std::size_t k = 0; k < D; ++k) wd[k] = -wd[k];
  for (std::size_t k = 0; k < D; ++k) ww += wd[k] * wd[k];
  const double tau = r.uni();
  for (std::size_t k = 0; k < D; ++k) {
    w[k] = std::llround(wd[k] / std::sqrt(ww) * speed);
    q[k] = std::llround(n[k] * static_cast<double>(sigma) - tau * static_cast<double>(w[k]));
  }
  const i128 s2 = static_cast<i128>(sigma) * sigma;
  return n2(q) >= s2 && n2(add(q, w)) < s2;
}

// At the engine's scale: the post velocity is the reflection of w about the contact normal to
// within a few units per component plus |w| |dn| (the column's normal is within |w| / sigma of
// the contact's), the momentum (pair level) is exact, |w|^2 moves by the rounding only.
template <std::size_t D, class Op>
void engine_scale(const Op& op, int samples, long& backscatters) {
  Rng r(7 + D);
  const i64 sigma = op.sigma();
  const double speed = std::ldexp(1.0, 30);
  int tried = 0;
  double worst_dir = 0, worst_e = 0;
  for (int s = 0; s < samples;) {
    VecN<D> q, w, q2, w2;
    std::array<double, D> n;
    if (++tried > 10 * samples) break;
    if (!realistic<D>(r, sigma, speed, q, w, n)) continue;
    ++s;
    SpecularTrace tr;
    REQUIRE(op.map(q, w, q2, w2, &tr) == Refusal::none);
    if (tr.backscatter) {
      ++backscatters;
      CHECK(w2 == neg(w));
      continue;
    }
    double wn = 0;
    for (std::size_t k = 0; k < D; ++k) wn += static_cast<double>(w[k]) * n[k];
    double dev = 0;
    for (std::size_t k = 0; k < D; ++k) {
      const double ref = static_cast<double>(w[k]) - 2 * wn * n[k];
      dev = std::max(dev, std::fabs(static_cast<double>(w2[k]) - ref));
    }
    worst_dir = std::max(worst_dir, dev / speed);
    const double de = std::fabs(static_cast<double>(n2(w2) - n2(w))) / static_cast<double>(n2(w));
    worst_e = std::max(worst_e, de);
    for (std::size_t k = 0; k < D; ++k) CHECK(((w2[k] - w[k]) & 1) == 0);  // parity kept
  }
  CHECK(tried <= 10 * samples);
  // direction: the column normal is within |w| / sigma = 2^30 / sigma of the true one
  const double tol_dir = 4.0 * speed / static_cast<double>(sigma) + 16.0 / speed;
  CHECK(worst_dir < tol_dir);
  CHECK(worst_e < 16.0 / speed);  // |w|^2 moves by a few units of |w|: relative ~ 2^-28
  std::printf("  D=%zu sigma=2^%.0f: worst direction error %.3g (tol %.3g), worst |dE/E| %.3g, backscatters %ld/%d\n", D,
              std::log2(static_cast<double>(sigma)), worst_dir, tol_dir, worst_e, backscatters, samples);
}

}  // namespace

TEST_CASE("2D: every pre state of a small disk maps to a distinct valid post state, T R T R = 1") {
  const LatticeSpecular2D op(24);
  const auto [n, back] = exhaustive<2>(op, 31, 6);
  std::printf("  2D sigma 24: %ld pre states, %ld backscatters\n", n, back);
  CHECK(n > 10000);
  CHECK(back > 0);      // the small disk's curvature makes the turn-back case occur: it is exercised
  CHECK(back < n / 4);  // a disk of 24 units and |w| up to 8: the curvature across a tick is large
}

TEST_CASE("3D: every pre state of a small sphere maps to a distinct valid post state, T R T R = 1") {
  const LatticeSpecular3D op(9);
  const auto [n, back] = exhaustive<3>(op, 12, 3);
  std::printf("  3D sigma 9: %ld pre states, %ld backscatters\n", n, back);
  CHECK(n > 10000);
  CHECK(back > 0);
  CHECK(back < n / 3);  // a sphere of 9 units and |w| up to 5
}

TEST_CASE("the velocity map is an involution, odd and parity-keeping (2D and 3D, large vectors)") {
  Rng r(3);
  const i64 sigma = i64{1} << 54;
  const LatticeSpecular2D op2(sigma);
  const LatticeSpecular3D op3(sigma);
  for (int s = 0; s < 20000; ++s) {
    const i64 xc = r.range(-(sigma >> 1), sigma >> 1), yc = r.range(-(sigma >> 1), sigma >> 1);
    const Vec2 w2{r.range(-(i64{1} << 58), i64{1} << 58), r.range(-(i64{1} << 58), i64{1} << 58)};
    const Vec2 v2 = op2.reflect({xc}, w2);
    CHECK(op2.reflect({xc}, v2) == w2);
    CHECK(op2.reflect({xc}, neg(w2)) == neg(v2));
    CHECK(((v2[0] - w2[0]) & 1) == 0 && ((v2[1] - w2[1]) & 1) == 0);
    const Vec3 w3{r.range(-(i64{1} << 57), i64{1} << 57), r.range(-(i64{1} << 57), i64{1} << 57), r.range(-(i64{1} << 57), i64{1} << 57)};
    const Vec3 v3 = op3.reflect({xc, yc}, w3);
    CHECK(op3.reflect({xc, yc}, v3) == w3);
    CHECK(op3.reflect({xc, yc}, neg(w3)) == neg(v3));
    CHECK(((v3[0] - w3[0]) & 1) == 0 && ((v3[1] - w3[1]) & 1) == 0 && ((v3[2] - w3[2]) & 1) == 0);
  }
  // the pole: (0, 0) column reflects z exactly
  CHECK(op3.reflect({0, 0}, Vec3{5, -7, 11}) == (Vec3{5, -7, -11}));
  CHECK(op2.reflect({0}, Vec2{5, 11}) == (Vec2{5, -11}));
}

TEST_CASE("at the engine's scale: the reflection about the contact normal, energy to the rounding") {
  for (int S : {52, 56, 60}) {
    long b2 = 0, b3 = 0;
    engine_scale<2>(LatticeSpecular2D(i64{1} << S), 20000, b2);
    engine_scale<3>(LatticeSpecular3D(i64{1} << S), 20000, b3);
    // turn-backs: the curvature across a tick, ~ |w| / sigma = 2^(30 - S) per collision
    CHECK(b2 <= 2 && b3 <= 2);
  }
}

TEST_CASE("pair level: momentum exact, exact inverse, refusals symmetric") {
  Rng r(11);
  const i64 sigma = i64{1} << 54;
  const LatticeSpecular2D op2(sigma);
  const LatticeSpecular3D op3(sigma);
  int done = 0;
  for (int s = 0; s < 20000; ++s) {
    Vec3 q, w;
    std::array<double, 3> n;
    if (!realistic<3>(r, sigma, std::ldexp(1.0, 31), q, w, n)) continue;
    const Vec3 vj{r.range(-(1 << 30), 1 << 30), r.range(-(1 << 30), 1 << 30), r.range(-(1 << 30), 1 << 30)};
    const Vec3 vi = add(vj, w), xj{r.range(0, i64{1} << 60), 3, -5}, xi = add(xj, q);
    Vec3 xi2, xj2, vi2, vj2, xi0, xj0, vi0, vj0;
    REQUIRE(op3.pair_map(xi, xj, vi, vj, xi2, xj2, vi2, vj2) == Refusal::none);
    for (int k = 0; k < 3; ++k) CHECK(vi2[k] + vj2[k] == vi[k] + vj[k]);
    REQUIRE(op3.pair_unmap(xi2, xj2, vi2, vj2, xi0, xj0, vi0, vj0) == Refusal::none);
    CHECK(xi0 == xi && xj0 == xj && vi0 == vi && vj0 == vj);
    Vec2 q2, w2;
    std::array<double, 2> n2d;
    if (!realistic<2>(r, sigma, std::ldexp(1.0, 31), q2, w2, n2d)) continue;
    const Vec2 vj_{vj[0], vj[1]}, vi_ = add(vj_, w2), xj_{xj[0], xj[1]}, xi_ = add(xj_, q2);
    Vec2 a, b, c, d, e, f, g, h;
    REQUIRE(op2.pair_map(xi_, xj_, vi_, vj_, a, b, c, d) == Refusal::none);
    CHECK(c[0] + d[0] == vi_[0] + vj_[0] && c[1] + d[1] == vi_[1] + vj_[1]);
    REQUIRE(op2.pair_unmap(a, b, c, d, e, f, g, h) == Refusal::none);
    CHECK(e == xi_ && f == xj_ && g == vi_ && h == vj_);
    ++done;
  }
  CHECK(done > 1000);
  // coinciding centres at a: no face, refused; velocities beyond 2^59 refused by require
  Vec2 a, b, c, d;
  CHECK(op2.map(Vec2{sigma, 0}, Vec2{-sigma, 0}, a, b) == Refusal::out_of_domain);
  CHECK_THROWS_AS(op2.pair_map(Vec2{sigma, 0}, Vec2{}, Vec2{i64{1} << 59, 0}, Vec2{}, a, b, c, d), InvalidArgument);
  CHECK_THROWS_AS(LatticeSpecular2D(1), InvalidArgument);
  CHECK_THROWS_AS(LatticeSpecular3D((i64{1} << 60) + 1), InvalidArgument);
}

CHECK_MAIN()
