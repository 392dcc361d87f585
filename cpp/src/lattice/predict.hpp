// The lattice engine's prediction: a particle's earliest event (neutral crossing or list
// renewal, wall, collision with a neighbour), the double-precision filter in front of the exact
// first-overlap search, and the slot order that makes the search never decide a collision.
// Part of BasicEngine (revcol/lattice/engine_core.hpp, which declares it and explains the
// design); included by engine_impl.hpp, which the instantiating sources include.
#pragma once
#include <cmath>
#include <limits>
#include <tuple>

#include "revcol/lattice/engine_core.hpp"

namespace revcol::lattice {

// ---- geometry of the lines ----
template <class Op, class Bits, class Queue>
[[gnu::always_inline]] inline auto BasicEngine<Op, Bits, Queue>::pos(int p, std::int64_t t) const noexcept -> Vec {
  Vec out;
  const std::int64_t dt = t - ln_[p].ta;
  for (std::size_t k = 0; k < D; ++k) {
    std::int64_t m, y;
    // fast path (measure before changing): the displacement fits int64 and at most one wrap
    // (axk_: 0 periodic, 1 walls, 2 walls and the field, 3 the sheared gradient, read in one test)
    if (!__builtin_mul_overflow(ln_[p].v[k], dt, &m) && !__builtin_add_overflow(ln_[p].x[k], m, &y)) {
      if (axk_[k] != 0) {
        out[k] = axk_[k] == 1 ? y : axk_[k] == 2 ? field_at(p, k, dt) : sheared_at(p, t, out);
        continue;
      }
      if (y >= u_.L[k]) y -= u_.L[k];
      else if (y < 0) y += u_.L[k];
      if (y >= 0 && y < u_.L[k]) {
        out[k] = y;
        continue;
      }
    }
    const i128 z = static_cast<i128>(ln_[p].x[k]) + static_cast<i128>(ln_[p].v[k]) * dt;
    out[k] = axk_[k] == 2 ? field_at(p, k, dt) : axk_[k] == 3 ? sheared_at(p, t, out) : u_.wall[k] ? static_cast<std::int64_t>(z) : wrap(z, u_.L[k]);
  }
  return out;
}

// ---- line helpers (declared in engine_core.hpp) ----
// origin + d, wrapped on periodic axes (128-bit sum: no overflow whatever the box)
template <class Op, class Bits, class Queue>
inline auto BasicEngine<Op, Bits, Queue>::shifted(const Vec& origin, const Vec& d) const noexcept -> Vec {
  Vec o;
  for (std::size_t k = 0; k < D; ++k) {
    const i128 y = static_cast<i128>(origin[k]) + d[k];
    o[k] = u_.wall[k] ? static_cast<std::int64_t>(y) : wrap(y, u_.L[k]);
  }
  return o;
}

template <class Op, class Bits, class Queue>
inline auto BasicEngine<Op, Bits, Queue>::wrapped(const Vec& x) const noexcept -> Vec {
  Vec o = x;
  for (std::size_t k = 0; k < D; ++k)
    if (!u_.wall[k]) o[k] = wrap(x[k], u_.L[k]);
  return o;
}

// the prediction's double mirror of p's line, after every change of ln_[p]
template <class Op, class Bits, class Queue>
[[gnu::always_inline]] inline void BasicEngine<Op, Bits, Queue>::sync(int p) noexcept {
  LineD& d = lnd_[static_cast<std::size_t>(p)];
  const Line& l = ln_[static_cast<std::size_t>(p)];
  if (lists_) {
    d.a = unwrapped_about(p, l.x);
  } else {
    for (std::size_t k = 0; k < D; ++k) d.a[k] = static_cast<double>(l.x[k]);
  }
  for (std::size_t k = 0; k < D; ++k) d.v[k] = static_cast<double>(l.v[k]);
  d.ta = l.ta;
}

template <class Op, class Bits, class Queue>
inline std::int64_t BasicEngine<Op, Bits, Queue>::ups(int p, std::int64_t t) const noexcept {
  return floor_div128(static_cast<i128>(ln_[p].x[1]) + static_cast<i128>(ln_[p].v[1]) * (t - ln_[p].ta), u_.L[1]);
}

// ---- a uniform field (field.hpp) ----
// the parabola's point on the field's axis k, dt ticks from p's anchor (walled: no wrap), exact in 128 bits
template <class Op, class Bits, class Queue>
[[gnu::noinline]] std::int64_t BasicEngine<Op, Bits, Queue>::field_at(int p, std::size_t k, std::int64_t dt) const noexcept {
  return static_cast<std::int64_t>(field_point(ln_[p].x[k], ln_[p].v[k], hg_, dt));
}

template <class Op, class Bits, class Queue>
inline auto BasicEngine<Op, Bits, Queue>::vel(int p, std::int64_t t) const noexcept -> Vec {
  Vec v = ln_[p].v;
  if (!moving_) [[likely]] return v;
  if (gax_ >= 0)
    v[gax_] = static_cast<std::int64_t>(static_cast<std::uint64_t>(v[gax_]) + 2 * static_cast<std::uint64_t>(hg_) * static_cast<std::uint64_t>(t - ln_[p].ta));
  if (sh_ != 0) v[0] -= ups(p, t) * sh_;  // (shear: the jumps of its crossings)
  return v;
}

template <class Op, class Bits, class Queue>
inline auto BasicEngine<Op, Bits, Queue>::move_of(int p, std::int64_t a) const noexcept -> Vec {
  if (!moving_) [[likely]] return ln_[p].v;
  return plus_h(vel(p, a - 1));  // (shear: the velocity of its point at a-1, past a crossing at a)
}

template <class Op, class Bits, class Queue>
inline auto BasicEngine<Op, Bits, Queue>::plus_h(Vec v) const noexcept -> Vec {
  if (gax_ >= 0) [[unlikely]] v[gax_] += hg_;
  return v;
}

template <class Op, class Bits, class Queue>
inline auto BasicEngine<Op, Bits, Queue>::minus_h(Vec v) const noexcept -> Vec {
  if (gax_ >= 0) [[unlikely]] v[gax_] -= hg_;
  return v;
}

// ---- Lees-Edwards shear (shear.hpp) ----
template <class Op, class Bits, class Queue>
inline auto BasicEngine<Op, Bits, Queue>::diff_at(const Vec& a, const Vec& b, std::int64_t t, std::int64_t& n) const noexcept -> Vec {
  n = 0;
  if (sh_ == 0) [[likely]] return diff(a, b);
  return sheared_diff<D>(a, b, u_.L, u_.wall, delta(t), n);  // (a template of shear.hpp: out of line)
}

template <class Op, class Bits, class Queue>
inline auto BasicEngine<Op, Bits, Queue>::diff_at(const Vec& a, const Vec& b, std::int64_t t) const noexcept -> Vec {
  std::int64_t n;
  return diff_at(a, b, t, n);
}

template <class Op, class Bits, class Queue>
inline auto BasicEngine<Op, Bits, Queue>::shifted_at(const Vec& origin, const Vec& d, std::int64_t t, Vec& v) const noexcept -> Vec {
  if (sh_ == 0) [[likely]] return shifted(origin, d);
  return sheared_shift(origin, d, t, v);
}

template <class Op, class Bits, class Queue>
auto BasicEngine<Op, Bits, Queue>::sheared_shift(const Vec& origin, const Vec& d, std::int64_t t, Vec& v) const noexcept -> Vec {
  Vec o = shifted(origin, d);
  const std::int64_t m = floor_div128(static_cast<i128>(origin[1]) + d[1], u_.L[1]);
  if (m != 0) {
    o[0] = wrap(static_cast<i128>(o[0]) - static_cast<i128>(m) * delta(t), u_.L[0]);
    v[0] -= m * sh_;
  }
  return o;
}

template <class Op, class Bits, class Queue>
inline auto BasicEngine<Op, Bits, Queue>::back_at(const Vec& x, const Vec& v, std::int64_t t) const noexcept -> Vec {
  if (sh_ == 0) [[likely]] return wrapped(sub(x, v));
  Vec w = v;
  return shifted_at(x, neg(v), t, w);
}

template <class Op, class Bits, class Queue>
std::int64_t BasicEngine<Op, Bits, Queue>::sheared_at(int p, std::int64_t t, Vec& out) const noexcept {
  const i128 z = static_cast<i128>(ln_[p].x[1]) + static_cast<i128>(ln_[p].v[1]) * (t - ln_[p].ta);
  const std::int64_t m = floor_div128(z, u_.L[1]);  // across the gradient faces m times: the images' offset along the flow
  if (m != 0) out[0] = wrap(static_cast<i128>(out[0]) - static_cast<i128>(m) * delta(t), u_.L[0]);
  return static_cast<std::int64_t>(z - static_cast<i128>(m) * u_.L[1]);
}

// The first tick after lo at which floor(s t / W) changes, W the narrowest cell along the flow:
// between two such ticks the images across the gradient faces move by less than a cell, so a
// crossing pair's nearest image at a prediction is the one it can meet (a neutral event of the
// particles next to a gradient face; shear.hpp, cell_grid.hpp).
template <class Op, class Bits, class Queue>
std::int64_t BasicEngine<Op, Bits, Queue>::next_offset(std::int64_t lo) const noexcept {
  const std::int64_t W = u_.L[0] / grid_.count(0);
  if (sh_ > 0) {
    const i128 k = floor_div128(static_cast<i128>(sh_) * lo, W);
    return floor_div128((k + 1) * W + sh_ - 1, sh_);
  }
  const std::int64_t s = -sh_;
  const i128 j = -static_cast<i128>(floor_div128(-static_cast<i128>(s) * lo, W));  // ceil(s lo / W)
  return floor_div128(j * W, s) + 1;
}

// A position x (wrapped) unwrapped about p's list centre: c_p + min_image(x - c_p), in
// (-L/2, 3L/2), as doubles (two roundings, each within 2^10 lattice units: no integer sum,
// which could overflow a 2D box near 2^63). In exact arithmetic, two of them less the pair's
// image shift (neighbour_lists.hpp) are the minimum-image difference of the two positions.
template <class Op, class Bits, class Queue>
inline std::array<double, BasicEngine<Op, Bits, Queue>::D> BasicEngine<Op, Bits, Queue>::unwrapped_about(int p, const Vec& x) const noexcept {
  std::array<double, D> a{};
  const Vec& c = nl_.centre(p);
  for (std::size_t k = 0; k < D; ++k)
    a[k] = u_.wall[k] ? static_cast<double>(x[k])
                      : static_cast<double>(c[k]) + static_cast<double>(min_image(x[k] - c[k], u_.L[k]));
  return a;
}

// Ticks from the anchor to the first at which the line's centre is in the next slab along the
// regions' axis (set_regions), or -1 (still, or no face ahead before a wall).
template <class Op, class Bits, class Queue>
auto BasicEngine<Op, Bits, Queue>::region_ticks(const Line& l) const noexcept -> std::int64_t {
  const auto k = static_cast<std::size_t>(rax_);
  const std::int64_t x = l.x[k], v = l.v[k];
  if (v == 0) return -1;
  const bool wrap_axis = !u_.wall[k];
  if (v > 0) {  // the first face above x: x + v t >= F
    const auto it = std::upper_bound(faces_.begin(), faces_.end(), x);
    if (it == faces_.end() && !wrap_axis) return -1;
    const i128 f = it != faces_.end() ? i128{*it} : i128{faces_.front()} + u_.L[k];
    return static_cast<std::int64_t>((f - x + v - 1) / v);
  }
  // the slab's lower face: x + v t < F
  auto it = std::upper_bound(faces_.begin(), faces_.end(), x);
  if (it == faces_.begin() && !wrap_axis) return -1;
  const i128 f = it != faces_.begin() ? i128{*(it - 1)} : i128{faces_.back()} - u_.L[k];
  return static_cast<std::int64_t>((i128{x} - f) / -v + 1);
}

// ---- prediction ----
template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::reanchor(int p, std::int64_t t) {
  if (moving_) [[unlikely]] reanchor_moving(p, t);
  else ln_[p].x = pos(p, t);
  ln_[p].ta = t;
  if (lists_) {  // a post point outside the ball (a collision moves it by ~vmax): renew now
    if (!nl_.inside(p, ln_[p].x)) nl_.renew(p, ln_[p].x);
    sync(p);
    return;
  }
  const int id = grid_.cell_id(ln_[p].x);
  if (grid_.cell_of_particle(p) != id) {
    grid_.remove(p);
    grid_.insert(p, id);
  }
}

// a field's or shear's line re-anchored at t: its point and its velocity there (read before the
// anchor moves: shear counts the old line's crossings)
template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::reanchor_moving(int p, std::int64_t t) {
  const Vec v = vel(p, t);
  ln_[p].x = pos(p, t);
  ln_[p].v = v;
  if (sh_ != 0 && (v[0] > u_.vmax || v[0] < -u_.vmax))
    throw std::runtime_error("lattice engine: shear has heated the gas beyond the lattice's speed limit vmax (particle " + std::to_string(gid(p)) +
                             ", tick " + std::to_string(t) + "): the run stops here");
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::schedule(int p, Type type, std::int64_t t, std::int32_t kind, int partner) {
  Slot& b = slot_[static_cast<std::size_t>(p)];
  b.type = type;
  b.partner = partner;
  b.vself = b.ver;
  b.vpart = partner >= 0 ? slot_[static_cast<std::size_t>(partner)].ver : 0;
  if (type == none) queue_.erase(p);
  else if (gid_.empty()) queue_.set(p, t, kind);
  else queue_.set(p, t, kind, gid(p));  // ties by particle id
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::predict(int p, std::int64_t lo) {
  reanchor(p, lo);
  Best b;
  std::array<int, D> c{};
  if (lists_) {  // the renewal: when the line leaves the ball about p's list centre
    const std::int64_t dt = nl_.exit_ticks(p, ln_[p].x, ln_[p].v);
    if (dt > 0) b.offer(lo + dt, 0, cross, -1, -1);
  } else {
    c = grid_.coords(grid_.cell_of_particle(p));
  }
  if (rax_ >= 0) {  // slabs: the neutral event of entering the next one, and a change at lo
    const std::int64_t dr = region_ticks(ln_[p]);
    if (dr > 0) b.offer(lo + dr, 0, cross, -1, -1);
    const int r = region_of(ln_[p].x);
    if (r != region_[static_cast<std::size_t>(p)]) {
      if (migrations != nullptr && !unwinding_) migrations->push_back({lo, gid(p), region_[static_cast<std::size_t>(p)], r});
      region_[static_cast<std::size_t>(p)] = r;
    }
  }
  if (sh_ != 0 && !lists_ && (c[1] == 0 || c[1] + 1 == grid_.count(1))) [[unlikely]]
    b.offer(next_offset(lo), 0, cross, -1, -1);  // next to a gradient face: the images move on (shear.hpp)
  for (std::size_t k = 0; k < D; ++k) {
    if (static_cast<int>(k) == gax_) [[unlikely]] {  // the field's axis: quadratic times (lists: their cube's, above)
      const int kk = static_cast<int>(k);
      if (!lists_) {
        const int ck = c[k], nc = grid_.count(kk);
        const std::int64_t dt = field_exit_ticks(ln_[p].x[k], ln_[p].v[k], hg_, grid_.boundary(kk, ck), grid_.boundary(kk, ck + 1), ck == 0, ck + 1 == nc);
        if (dt > 0) b.offer(lo + dt, 0, cross, -1, -1);
      }
      const std::int64_t dw = field_wall_ticks(ln_[p].x[k], ln_[p].v[k], hg_, lo_of(p), hi_of(p, kk));
      if (dw >= 0) b.offer(lo + dw, wall_kind(), wall, -1, -1);
      continue;
    }
    if (!lists_) {
      const std::int64_t dt = grid_.exit_ticks(static_cast<int>(k), c[k], ln_[p].x[k], ln_[p].v[k]);
      if (dt > 0) b.offer(lo + dt, 0, cross, -1, -1);
    }
    if (u_.wall[k]) {
      const std::int64_t dw = wall_ticks(ln_[p].x[k], ln_[p].v[k], lo_of(p), hi_of(p, static_cast<int>(k)));
      if (dw >= 0) b.offer(lo + dw, wall_kind(), wall, -1, -1);
    }
  }
  if (moving_) [[unlikely]] {  // (Field: curved lines or moving images)
    if (sz_.mixed()) scan<true, true>(p, lo, b);
    else scan<false, true>(p, lo, b);
  } else if (sz_.mixed()) {
    scan<true, false>(p, lo, b);
  } else {
    scan<false, false>(p, lo, b);
  }
  schedule(p, b.type, b.t, b.k, b.q);
  if (b.type == coll) {  // write it into the partner's slot when before the event there
    // in offer's order (tick, kind, other particle): with (tick, kind) alone, a tie (two pairs of
    // one particle at one tick and one kind, i.e. the same lower index) went to whichever
    // prediction wrote the slot first, so the search's neutral events (crossings or renewals,
    // which re-predict) could choose the partner; measured once in 6.6 x 10^6 collisions
    const Slot& sq = slot_[static_cast<std::size_t>(b.q)];
    if (!queue_.scheduled(b.q) ||
        std::make_tuple(b.t, b.k, gid(p)) < std::make_tuple(queue_.time(b.q), queue_.kind(b.q), sq.partner >= 0 ? gid(sq.partner) : -1)) {
      schedule(b.q, coll, b.t, b.k, p);
    }
  }
}

// p's candidate partners (its list, or its 3^D cells) into b.
template <class Op, class Bits, class Queue>
template <bool Mixed, bool Field>
inline void BasicEngine<Op, Bits, Queue>::scan(int p, std::int64_t lo, Best& b) {
  // The candidates. A double-precision filter drops the pairs that cannot collide, or not
  // before the best event so far; the others get the exact search (measure before changing).
  // Rounding: a position is within 2^10 lattice units of its double (|x| < 2^63; an unwrapped
  // anchor, two such roundings) and sigma >= 2^40 (units.hpp), so r is within ~2^-27 sigma of
  // the exact relative vector and |r|^2, the closest approach and |r + w t|^2 within ~2^-26
  // (|r|^2 + sigma^2): the margins below are 1e-6 of that (~2^-20), so a filtered pair is one
  // whose every integer tick is provably outside.
  // The image is the exact search's unless |r_k| is within rounding of L_k / 2 (edge: no filter).
  const Line& lp = ln_[p];
  constexpr double never = std::numeric_limits<double>::infinity();
  double tb = b.type != none ? static_cast<double>(b.t - lo) : never;  // the best so far, ticks from lo
  auto exact = [&](int q, double guess) {
    // (a field: q's velocity at lo, p is anchored there; shear: q's nearest image, n boxes up)
    std::int64_t n = 0;
    const Vec r = Field ? diff_at(lp.x, pos(q, lo), lo, n) : diff(lp.x, pos(q, lo));
    Vec w = Field ? sub(lp.v, vel(q, lo)) : sub(lp.v, ln_[q].v);
    if (Field) w[0] -= n * sh_;
    std::int64_t tau;
    if constexpr (D == 3) {
      tau = first_overlap(r, w, Mixed ? sig2(p, q) : sigma2_, guess);
    } else {
      (void)guess;
      tau = first_overlap(r, w, Mixed ? sig2(p, q) : sigma2_);
    }
    if (tau >= 0) {
      b.offer(lo + tau, coll_kind(p, q), coll, q, gid(q));
      tb = static_cast<double>(b.t - lo);
    }
  };
  // the filter's tests on r, w (doubles) for the contact distance s2 (squared): true when the
  // pair surely has no overlap tick <= t
  auto beyond = [&](double rr, double bb, double aa, double t, double s2) {
    // never inside: the smallest |r + w t|^2 over t >= 0 (rr - bb^2 / aa when approaching, here
    // times aa: no division on the loop's path; its rounding, ~4u rr aa by Cauchy-Schwarz, is far
    // inside the margin) is beyond sigma^2
    const double lim = s2 + 1e-6 * (rr + s2);
    if (bb >= 0.0 ? rr > lim : rr * aa - bb * bb > lim * aa) return true;
    // not up to t: f(t) = |r + w t|^2 is still falling at t and outside there
    return t != never && -bb >= aa * t && rr + t * (2.0 * bb + aa * t) > s2 + 1e-6 * (rr + aa * t * t + s2);
  };
  // a mixture's contact distance squared, in double (the radii are the lines' doubles; within
  // the filter's margin of the exact sum); one diameter: sigma^2
  const double rp = Mixed ? lnd_[static_cast<std::size_t>(p)].r : 0.0;
  auto s2d = [&](int q) {
    if constexpr (!Mixed) {
      (void)q;
      return sigma2d_;
    } else {
      const double s = rp + lnd_[static_cast<std::size_t>(q)].r;
      return s * s;
    }
  };
  if (direct_ && !exhaustive_search) {
    // lists on a box wide enough: r = (a_p - a_q - s) - v_q (lo - t_q), with a the anchors
    // unwrapped about their list centres and s the entry's image shift: no image to find
    // (a and s are exact integers rounded once, as the positions of the other path)
    const LineD& dp = lnd_[static_cast<std::size_t>(p)];
    const int* ids = nl_.ids(p);
    const std::uint8_t* codes = nl_.codes(p);
    // every partner's line requested first: the filter's branches are unpredictable, and a
    // mispredicted one would otherwise serialize the cache misses (as the float engine does)
    for (int e = 0, ne = nl_.size(p); e < ne; ++e) __builtin_prefetch(&lnd_[static_cast<std::size_t>(ids[e])]);
    for (int e = 0, ne = nl_.size(p); e < ne; ++e) {
      const int q = ids[e];
      const LineD& dq = lnd_[static_cast<std::size_t>(q)];
      const double dtq = static_cast<double>(lo - dq.ta);
      const double* sh = shift_[codes[e]].data();
      double rr = 0.0, bb = 0.0, aa = 0.0;
      for (std::size_t k = 0; k < D; ++k) {
        double r = ((dp.a[k] - dq.a[k]) - sh[k]) - dq.v[k] * dtq;
        double w = dp.v[k] - dq.v[k];
        if (Field && static_cast<int>(k) == gax_) {  // q's fall since its anchor
          r -= hgd_ * dtq * dtq;
          w -= 2.0 * hgd_ * dtq;
        }
        rr += r * r;
        bb += r * w;
        aa += w * w;
      }
      const double s2 = s2d(q);
      if (beyond(rr, bb, aa, tb, s2)) continue;
      // the entry root of aa t^2 + 2 bb t + rr - sigma^2 from these doubles: first_overlap's
      // first guess (its exact predicates decide; any guess gives the same answer)
      const double c0 = rr - s2;
      exact(q, c0 / (std::sqrt(std::max(0.0, bb * bb - aa * c0)) - bb));
    }
  } else if (!lists_ && shifted_ && !exhaustive_search) {
    // cells, >= 5 on every periodic axis: each neighbouring cell's image is known, so r is the
    // exact integer difference to that image, rounded once, less the partner's travel (no image
    // to find and no edge: every candidate is within two cells, nearer than L / 2)
    grid_.for_neighbours_shifted(grid_.cell_of_particle(p), [&](int q, const Vec& s) {
      if (q == p) return;
      const Line& lq = ln_[q];
      const double dtq = static_cast<double>(lo - lq.ta);
      double rr = 0.0, bb = 0.0, aa = 0.0;
      for (std::size_t k = 0; k < D; ++k) {
        // (x_p - x_q) + s: the difference is in (-L, L) and a shift only ever brings it nearer 0
        // (+L for a partner near L seen from near 0), so no sum passes 2^63 however large L is
        double r = static_cast<double>((lp.x[k] - lq.x[k]) + s[k]) - static_cast<double>(lq.v[k]) * dtq;
        double w = static_cast<double>(lp.v[k] - lq.v[k]);
        if (Field && static_cast<int>(k) == gax_) {  // q's fall since its anchor
          r -= hgd_ * dtq * dtq;
          w -= 2.0 * hgd_ * dtq;
        }
        rr += r * r;
        bb += r * w;
        aa += w * w;
      }
      if (!beyond(rr, bb, aa, tb, s2d(q))) exact(q, std::numeric_limits<double>::quiet_NaN());
    });
  } else {
    std::array<double, D> xp{};
    for (std::size_t k = 0; k < D; ++k) xp[k] = static_cast<double>(lp.x[k]);
    // shear: the images' offset at lo and their speed (shear.hpp)
    const double deltad = Field && sh_ != 0 ? static_cast<double>(delta(lo)) : 0.0, shd = Field ? static_cast<double>(sh_) : 0.0;
    near(p, [&](int q) {
      if (q == p) return;
      const Line& lq = ln_[q];
      if (!exhaustive_search) {
        const double dtq = static_cast<double>(lo - lq.ta);
        double rr = 0.0, bb = 0.0, aa = 0.0;
        bool edge = false;
        double s0 = 0.0, sw = 0.0;  // shear: q's image across the gradient faces nearest p, n boxes up
        if (Field && sh_ != 0) {
          const double m = ((xp[1] - static_cast<double>(lq.x[1])) - static_cast<double>(lq.v[1]) * dtq) * invL_[1];
          const double n = static_cast<double>(static_cast<std::int64_t>(m + (m >= 0.0 ? 0.5 : -0.5)));
          s0 = n * deltad;
          sw = n * shd;
        }
        for (std::size_t k = 0; k < D; ++k) {
          double r = (xp[k] - static_cast<double>(lq.x[k])) - static_cast<double>(lq.v[k]) * dtq;
          if (Field && static_cast<int>(k) == gax_) r -= hgd_ * dtq * dtq;  // q's fall since its anchor
          if (Field && k == 0) r -= s0;
          if (!u_.wall[k]) {  // the nearest image (an inline rounding: libm's is a call)
            const double m = r * invL_[k];
            r -= Ld_[k] * static_cast<double>(static_cast<std::int64_t>(m + (m >= 0.0 ? 0.5 : -0.5)));
            edge = edge || std::fabs(r) > edge_[k];
          }
          double w = static_cast<double>(lp.v[k] - lq.v[k]);
          if (Field && static_cast<int>(k) == gax_) w -= 2.0 * hgd_ * dtq;
          if (Field && k == 0) w -= sw;
          rr += r * r;
          bb += r * w;
          aa += w * w;
        }
        if (!edge && beyond(rr, bb, aa, tb, s2d(q))) return;
      }
      exact(q, std::numeric_limits<double>::quiet_NaN());
    });
  }
}

}  // namespace revcol::lattice
