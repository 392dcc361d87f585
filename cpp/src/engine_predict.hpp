// EngineImpl's prediction (declared in engine_impl.hpp): a particle's earliest event, its
// second earliest collision time and whether a neighbour touches it (the group gate), as a
// template on whether the gas is a mixture (each pair's contact distance) and whether a field
// bends the flights (docs/engine.md, "A uniform field"); a wall on a field's axis; the list
// renewal event and its centre's move. Private to cpp/src, included after engine_impl.hpp.
#pragma once

#include "engine_impl.hpp"

namespace revcol::engine::detail {

template <int Dim, PairOperator Op>
template <bool Mixed, bool Field>
inline void EngineImpl<Dim, Op>::predict_sized(int i) {
  Ev best;
  const double ti = p_[i].t;
  const double r_own = Mixed ? rad_[static_cast<std::size_t>(i)] : Boundaries<Dim>::kOwn;  // the walls' radius
  for (int k = 0; k < (walled_ ? Dim : 0); ++k) {  // a periodic box: no wall to test
    if (Field && g_[k] != 0.0) {  // a parabola: the first of the floor and the ceiling
      field_wall(i, k, r_own, best);
      continue;
    }
    const double vk = p_[i].v[k];
    if (vk == 0.0 || !box_.walls(k)) continue;
    const int up = vk > 0.0 ? 1 : 0;
    bool wall_ok = true;
    if (rev_ && box_.touches_ahead(k, p_[i].x[k] + vk * (clock_ - ti), up, r_own)) {
      // touching and approaching in a reversed run at the instant of a logged collision
      // of i: a reflection of its W2 is undone now; any other touched wall waits for the
      // collision. With no such collision (m < 0) the wall is met on its own, as forward
      // (the second wall of an exact corner)
      const long m = wall_entry(i);
      wall_ok = m < 0 || w2_covers(m, wall_mask(i, k, clock_));
    }
    if (wall_ok) {
      double t = Kin::plane_time(p_[i], k, box_.wall_at(k, up, r_own));
      if (t < clock_) t = clock_;
      if (earlier(t, kWall, 2 * k + up, best)) best = Ev{t, kWall, 2 * k + up, 0};
    }
  }
  if (adjacent()) {
    // 1D: no renewal; on a periodic axis the wrap, kWrap D past either end of the box
    const double vk = p_[i].v[0];
    if (box_.periodic(0) && vk != 0.0) {
      const double edge = vk > 0.0 ? box_.length(0) + wrap_ : -wrap_;
      double t = Kin::plane_time(p_[i], 0, edge);
      if (t < clock_) t = clock_;
      if (earlier(t, kRenew, 0, best)) best = Ev{t, kRenew, 0, 0};
    }
  } else {
    double tau;
    if (Field ? Kin::renewal_time(p_[i], nl_.centre(i), renew_h_, gn_, tau)
              : Kin::renewal_time(p_[i], nl_.centre(i), renew_h2_, tau)) {
      double t = ti + tau;
      if (t < clock_) t = clock_;
      if (earlier(t, kRenew, 0, best)) best = Ev{t, kRenew, 0, 0};
    }
  }
  double first = kInf, second = kInf;  // the two earliest collision times (the group gate)
  bool touch = false;
  const Particle<Dim>& pi = p_[i];
  double limit = prune_limit(best.t);
  const auto record = [&](int j, double t) {  // a hit: the gate's two earliest, and the best
    if (t < clock_) t = clock_;
    if (t < first) {
      second = first;
      first = t;
    } else if (t < second) {
      second = t;
    }
    // (t, kind, partner's id): ids, not slots, so that the choice does not depend on storage
    if (t < best.t || (t == best.t && (kColl < best.kind || (kColl == best.kind && bk_[j].id < bk_[best.partner].id)))) {
      best = Ev{t, kColl, j, p_[j].stamp};
      limit = prune_limit(best.t);
    }
  };
  const auto touched = [&](int j) {  // j within the contact tolerance: the group gate
    touch = true;
    bk_[j].touching = 1;
  };
  [[maybe_unused]] const double ri = r_own;
  const double tol_scale = 2.0 * cfg_.group_tol;  // (a mixture's: contact_tol(s2) = tol_scale s2)
  const auto s2_of = [&](int j) {
    if constexpr (Mixed) {
      const double s = ri + rad_[static_cast<std::size_t>(j)];
      return s * s;
    } else {
      (void)j;
      return sigma2_;
    }
  };
  const auto tol_of = [&](double s2) {
    if constexpr (Mixed) return tol_scale * s2;
    else {
      (void)s2;
      return contact_tol_;
    }
  };
  const auto one = [&](int j, const Vec& sh) {
    double t;
    bool tj = false;
    const double s2 = s2_of(j);
    const bool hit = Kin::template pair_time<Field>(pi, p_[j], sh, s2, tol_of(s2), t, tj, limit, g_.data());
    if (tj) touched(j);
    if (hit) record(j, t);
  };
  // two list entries per step in two-lane vectors, with pair_time's bits lane by lane; the
  // second lane's limit test is redone when the first lane's hit lowered the limit, so the
  // scan decides exactly as one entry at a time would
  const auto two = [&](int j0, const Vec& s0, int j1, const Vec& s1) {
    typename Kin::Pair2 q;
    const double s20 = s2_of(j0), s21 = s2_of(j1);
    Kin::template pair_test2<Field>(pi, p_[j0], p_[j1], s0, s1, s20, s21, tol_of(s20), tol_of(s21), limit, q,
                                    g_.data());
    if (q.touching[0]) touched(j0);
    if (q.hit[0]) record(j0, q.finish(0));
    if (q.touching[1]) touched(j1);
    if (q.still_hit(1, limit)) record(j1, q.finish(1));
  };
  nl_.for_neighbour_pairs(i, two, one, [&](int j) { __builtin_prefetch(&p_[j]); });
  Book& bi = bk_[i];
  bi.ev = best;
  // a second time beyond the final limit is one the scan kept only because it came before
  // the best: which such times it kept depends on the list's order, and no decision reads
  // them (the gate's window lies inside the limit), so they all read +inf and the stored
  // state does not depend on that order (nor on where particles are stored)
  bi.second = second <= limit ? second : kInf;
  bi.touching = touch ? 1 : 0;
}

template <int Dim, PairOperator Op>
void EngineImpl<Dim, Op>::field_wall(int i, int k, double r_own, Ev& best) {
  double tau;
  int up;
  if (!Kin::wall_time(p_[i], k, g_[k], box_.wall_at(k, 0, r_own), box_.wall_at(k, 1, r_own), tau, up)) return;
  if (rev_) {
    const double vk = vel_at(i, k, clock_);
    const int ahead = vk > 0.0 ? 1 : 0;
    if (vk != 0.0 && box_.touches_ahead(k, pos_at(i, k, clock_), ahead, r_own)) {
      const long m = wall_entry(i);
      if (!(m < 0 || w2_covers(m, wall_mask(i, k, clock_)))) return;
    }
  }
  double t = p_[i].t + tau;
  if (t < clock_) t = clock_;
  if (earlier(t, kWall, 2 * k + up, best)) best = Ev{t, kWall, 2 * k + up, 0};
}

// The list renewal: the centre moves to where i is now (wrapped into the box on periodic
// axes, moving the stored position by L: its line, and so every prediction, is unchanged),
// i's list is rebuilt (in 1D, the images of the rods beside it recoded: this is then the
// wrap) and i is predicted again. Nothing physical changes: no stamp.
template <int Dim, PairOperator Op>
inline void EngineImpl<Dim, Op>::renew_event(int i, const Ev& e) {
  if (field_) {  // a parabola's renewal time is bounded from its anchor: anchor it at e.t (the
                 // same path, so no stamp changes and every prediction with i stands)
    const std::uint64_t stamp = p_[i].stamp;
    Kin::advance(p_[i], e.t, g_.data());
    p_[i].stamp = stamp;
  }
  move_centre(i, e.t);
  if (adjacent()) nl_.recode_beside(i, [&](int j) { return pos_at(j, 0, clock_); });
  else nl_.renew(i);
  ++counters_.list_renewals;
  repredict(i);
}

// i's centre to where i is at t; on a periodic axis a position outside the box is first
// moved by L (its line, and so every prediction, is unchanged).
template <int Dim, PairOperator Op>
inline void EngineImpl<Dim, Op>::move_centre(int i, double t) {
  const double dt = t - p_[i].t;
  double* c = nl_.centre(i);
  for (int k = 0; k < Dim; ++k) {
    if (field_ && g_[k] != 0.0) {  // a walled axis: no wrap
      c[k] = pos_at(i, k, t);
      continue;
    }
    double ck = p_[i].x[k] + p_[i].v[k] * dt;
    if (box_.wrap(k, p_[i].x[k], ck)) ck = p_[i].x[k] + p_[i].v[k] * dt;
    c[k] = ck;
  }
}

}  // namespace revcol::engine::detail
