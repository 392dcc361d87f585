// The lattice engine's pair collisions: the forward acceptance test, the rare log, and the
// reverse, which reads the log and steps the stream back.
//
// Forward acceptance (LATTICE.md §4): a candidate post state is redrawn (the drawing stream steps on)
// when the operator refuses it, when a post centre is outside the walls or faster than vmax, when it
// overlaps a third body at tick a, or when its new lines overlap a third body at tick a-1 (a false tie:
// the reverse would meet that body first). The rare log holds the redraw count under the drawer's
// key (its id, its collision count after); the reverse reads and erases it. Detected and resolved
// by the rule, counted: three bodies within one tick (a third body's line overlapping a pre line at
// tick a: the pre line belongs to the past of the reverse; group.hpp) and a wall and a body within
// one tick (a collision right after a reflection on the same tick). Not resolved, an error naming it
// (never a silent approximation): a reflected line whose tick a-1 point overlaps a body (the reverse
// would meet the body first), and a collision out of redraws whose group has no post state either.
// Part of BasicEngine (revcol/lattice/engine_core.hpp, which declares it and explains the
// design); included by engine_impl.hpp, which the instantiating sources include.
#pragma once
#include <algorithm>
#include <stdexcept>
#include <string>

#include "revcol/lattice/engine_core.hpp"

namespace revcol::lattice {

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::inconsistent(const std::string& what, int i, int j) const {
  throw std::logic_error("lattice engine: inconsistent state (a damaged or edited checkpoint, or a bug): " + what +
                         ", undoing collision " + std::to_string(ncoll_) + " of particles " + std::to_string(gid(i)) +
                         " and " + std::to_string(gid(j)));
}

// why the candidate post state (positions at a, velocities) of i, j must be redrawn; 0 if none.
// The same scan flags `multi` when a pre line (pre_a: i's and j's pre lines at tick a) overlaps
// a third body at a: complete whenever 0 is returned (every neighbour was looked at).
template <class Op, class Bits, class Queue>
auto BasicEngine<Op, Bits, Queue>::post_reason(int i, int j, const Vec& xi, const Vec& xj, const Vec& vi, const Vec& vj, std::int64_t a, const Vec (&pre_a)[2], bool& multi) const -> int {
  if (sh_ != 0) [[unlikely]] return post_reason_t<true>(i, j, xi, xj, vi, vj, a, pre_a, multi);
  if (gax_ >= 0 && direct_) [[unlikely]] return post_reason_t<false, true>(i, j, xi, xj, vi, vj, a, pre_a, multi);
  return post_reason_t<false>(i, j, xi, xj, vi, vj, a, pre_a, multi);
}

// (Sheared: every distance through the nearest moving image at its tick, shear.hpp; Fall: the
// lists' double filter follows the partners' fall in a field)
template <class Op, class Bits, class Queue>
template <bool Sheared, bool Fall>
auto BasicEngine<Op, Bits, Queue>::post_reason_t(int i, int j, const Vec& xi, const Vec& xj, const Vec& vi, const Vec& vj, std::int64_t a, const Vec (&pre_a)[2], bool& multi) const -> int {
  auto dist = [&](const Vec& x, const Vec& y, std::int64_t t) { return Sheared ? diff_at(x, y, t) : diff(x, y); };
  auto meet = [&](const Vec& x, const Vec& y, int p, int q, std::int64_t t) { return norm2(dist(x, y, t)) < sig2(p, q); };
  for (std::size_t k = 0; k < D; ++k) {
    for (const Vec* vv : {&vi, &vj})
      if ((*vv)[k] > u_.vmax || (*vv)[k] < -u_.vmax) return redraw_outside;
    if (!u_.wall[k]) continue;
    if (xi[k] < lo_of(i) || xi[k] > hi_of(i, static_cast<int>(k))) return redraw_outside;
    if (xj[k] < lo_of(j) || xj[k] > hi_of(j, static_cast<int>(k))) return redraw_outside;
  }
  if (gax_ >= 0) [[unlikely]] {  // (vi, vj: the tick's moves; a field's velocities at a are the moves plus h)
    for (const Vec* vv : {&vi, &vj})
      if ((*vv)[gax_] + hg_ > u_.vmax || (*vv)[gax_] + hg_ < -u_.vmax) return redraw_outside;
  }
  int why = 0;
  multi = false;
  for (int s = 0; s < 2 && why == 0; ++s) {
    const Vec& x = s == 0 ? xi : xj;
    const Vec& v = s == 0 ? vi : vj;
    const int o = s == 0 ? i : j;  // whose post point
    const Vec ghost = Sheared ? back_at(x, v, a - 1) : wrapped(sub(x, v));
    auto third = [&](int q) {
      if (why != 0 || q == i || q == j) return;
      const Vec qa = pos(q, a);
      // exit (measure before changing): farther than sigma + 4 vmax, none of the three can hold
      // (the ghost and the pre point are within 2 vmax of x, q moves at most vmax per tick)
      const Vec d = dist(x, qa, a);
      double dd = static_cast<double>(d[0]) * d[0];
      for (std::size_t k = 1; k < D; ++k) dd += static_cast<double>(d[k]) * d[k];
      if (dd > far2_) return;
      if (meet(x, qa, o, q, a)) why = redraw_overlap_after;
      else if (meet(ghost, gax_ >= 0 || Sheared ? pos(q, a - 1) : wrapped(sub(qa, ln_[q].v)), o, q, a - 1)) why = redraw_ghost_tie;
      if (meet(pre_a[s], qa, o, q, a)) multi = true;  // complete: pre_a[s] is within 2 vmax of x
    };
    if (direct_) {  // the owner's list (x is within 2 vmax of its line), far ones dropped in double
      const std::array<double, D> ax = unwrapped_about(o, x);
      const int* ids = nl_.ids(o);
      const std::uint8_t* codes = nl_.codes(o);
      for (int e = 0, ne = nl_.size(o); e < ne; ++e) __builtin_prefetch(&lnd_[static_cast<std::size_t>(ids[e])]);
      for (int e = 0, ne = nl_.size(o); e < ne && why == 0; ++e) {
        const LineD& dq = lnd_[static_cast<std::size_t>(ids[e])];
        const double dt = static_cast<double>(a - dq.ta);
        const double* sh = shift_[codes[e]].data();
        double dd = 0.0;
        for (std::size_t k = 0; k < D; ++k) {
          double r = ((ax[k] - dq.a[k]) - sh[k]) - dq.v[k] * dt;
          if (Fall && static_cast<int>(k) == gax_) r -= hgd_ * dt * dt;  // q's fall since its anchor
          dd += r * r;
        }
        if (dd <= far2_ * (1.0 + 1e-6)) third(ids[e]);
      }
    } else if (lists_) {
      nl_.for_each(s == 0 ? i : j, third);
    } else if (Sheared) {
      grid_.for_neighbours_sheared(grid_.cell_id(x), third);
    } else {
      grid_.for_neighbours(grid_.cell_id(x), third);
    }
  }
  return why;
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::apply(int i, int j, const Vec& xi, const Vec& xj, const Vec& vi, const Vec& vj, std::int64_t a) {
  ln_[i].x = xi;
  ln_[j].x = xj;
  ln_[i].v = vi;
  ln_[j].v = vj;
  if (gax_ >= 0) [[unlikely]] {  // (vi, vj: the moves of the tick into a; a field's velocities at a are the moves plus h)
    ln_[i].v[gax_] += hg_;
    ln_[j].v[gax_] += hg_;
  }
  ln_[i].ta = ln_[j].ta = a;
  sync(i);
  sync(j);
  ++slot_[static_cast<std::size_t>(i)].ver;
  ++slot_[static_cast<std::size_t>(j)].ver;
  ++cnt_.collisions;
  predict(i, a);
  predict(j, a);
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::collide_forward(int i, int j, std::int64_t a) {
  if (mode_ == Mode::specular) {
    collide_specular(i, j, a);
    return;
  }
  journal(i);
  journal(j);
  if (wall_tick_[i] == a || wall_tick_[j] == a) ++cnt_.wall_body;
  collide_drawn(i, j, a, false);
}

// The randomized operator with redraws (exact mode; in specular mode the fallback of a refused
// post state, `fallback`: its log entry is written even with no redraw, which tells the
// reverse that this collision drew). Returns false only for a fallback whose group is
// impossible too (nothing changed); exact mode's group failure throws.
template <class Op, class Bits, class Queue>
bool BasicEngine<Op, Bits, Queue>::collide_drawn(int i, int j, std::int64_t a, bool fallback) {
  const Vec pre_a[2] = {pos(i, a), pos(j, a)};
  bool multi = false;
  const std::uint64_t ctr0 = own_[i].ctr;
  std::array<std::uint64_t, 8> reasons{};
  // the operator runs in coordinates centred on x_j (it is translation equivariant), so its
  // values stay within a few sigma of 0 whatever the box
  // (shear: i's image nearest j, -n boxes up, moving n s slower; shear.hpp)
  std::int64_t n;
  const Vec xj = pos(j, a - 1), xi = diff_at(pos(i, a - 1), xj, a - 1, n), zero{};
  Vec ui = move_of(i, a);  // the tick's moves (field.hpp)
  const Vec uj = move_of(j, a);
  ui[0] -= n * sh_;
  Vec xi2, xj2, vi2, vj2;
  Bits out;
  std::optional<Op> opm;
  const Op& op = op_of(i, j, opm);
  std::uint32_t redraws = 0;
  for (;;) {
    if (static_cast<std::int64_t>(redraws) > max_redraws) return group_collide(i, j, a, ctr0, reasons, !fallback);
    const std::uint64_t g = draw48(static_cast<std::uint32_t>(gid(i)), seed_, own_[i].ctr++);
    const auto rf = op.pair_forward(xi, zero, ui, uj, g, own_[i].X, xi2, xj2, vi2, vj2, out);
    int why = static_cast<int>(rf);
    if (why == 0) {
      xi2 = shifted_at(xj, xi2, a, vi2);
      xj2 = shifted_at(xj, xj2, a, vj2);
      why = post_reason(i, j, xi2, xj2, vi2, vj2, a, pre_a, multi);
    }
    if (why == 0) break;
    ++cnt_.redraws[std::min(why, 7)];
    ++reasons[std::min(why, 7)];
    ++redraws;
  }
  if (multi) ++cnt_.multi_body;
  if (redraws > 0 || fallback) [[unlikely]] {
    const LogKey key{static_cast<std::uint32_t>(gid(i)), own_[i].pc + 1};
    log_.emplace(key, redraws);
    if (!undo_epoch_.empty()) undo_log_.push_back(key);
    ++cnt_.log_entries;
  }
  if (fallback) ++cnt_.drawn_fallbacks;
  own_[i].X = std::move(out);
  ++own_[i].pc;
  ++own_[j].pc;
  ++ncoll_;
  if (trace != nullptr) trace->push_back({a, gid(i), gid(j)});
  if (obs_ || events || seen_) [[unlikely]] note_pair(a, i, j, xi2, xj2, plus_h(vi2), plus_h(vj2));
  apply(i, j, xi2, xj2, vi2, vj2, a);
  return true;
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::collide_back(int i, int j, std::int64_t a) {
  // i's last collision (forward) is the one undone here: its key is (i, i's count)
  const LogKey key{static_cast<std::uint32_t>(gid(i)), own_[i].pc};
  if (!groups_.empty()) [[unlikely]] {
    if (const auto it = groups_.find(key); it != groups_.end()) {
      const std::shared_ptr<Group> g = it->second;  // (group_back erases its keys)
      group_back(i, j, a, *g);
      return;
    }
  }
  const auto logged = log_.empty() ? log_.end() : log_.find(key);
  if (mode_ == Mode::specular && logged == log_.end()) {  // (a log entry: a drawn fallback)
    back_specular(i, j, a);
    return;
  }
  std::int64_t n;
  const Vec xj = pos(j, a - 1), xi = diff_at(pos(i, a - 1), xj, a - 1, n), zero{};
  const std::uint32_t redraws = logged != log_.end() ? logged->second : 0;
  if (own_[i].ctr < 1 + static_cast<std::uint64_t>(redraws)) inconsistent("particle " + std::to_string(gid(i)) + "'s stream would step back past draw 0", i, j);
  const std::uint64_t g = draw48(static_cast<std::uint32_t>(gid(i)), seed_, own_[i].ctr - 1);
  Vec xi0, xj0, vi0, vj0;
  if (own_[i].pc == 0 || own_[j].pc == 0) inconsistent("a collision count would step back past 0", i, j);
  std::optional<Op> opm;
  Vec ui = neg(move_of(i, a));
  ui[0] += n * sh_;  // (shear: the image's velocity, negated)
  op_of(i, j, opm).pair_reverse(xi, zero, ui, neg(move_of(j, a)), g, own_[i].X, xi0, xj0, vi0, vj0);
  vi0 = neg(vi0), vj0 = neg(vj0);  // (this frame's velocities)
  xi0 = shifted_at(xj, xi0, a, vi0);
  xj0 = shifted_at(xj, xj0, a, vj0);
  own_[i].ctr -= 1 + redraws;
  if (logged != log_.end()) log_.erase(logged);
  --own_[i].pc;
  --own_[j].pc;
  --ncoll_;
  apply(i, j, xi0, xj0, vi0, vj0, a);
}

// Specular mode (specular.hpp): one deterministic post state. When the map refuses it or it
// fails the acceptance test (a third body at a, a false tie at a-1, a wall, vmax) no redraw
// exists: the collision goes to the group rule (a log entry, its reason counted in redraws),
// except a post centre beyond a wall (a wall, the pair and the wall again within one tick),
// which the group rule cannot always take back: that one is drawn by the randomized operator
// with the particle's stream and X (collide_drawn, logged; counted in drawn_fallbacks). Either
// rule is the other's fallback; only both failing is an error.
template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::collide_specular(int i, int j, std::int64_t a) {
  journal(i);
  journal(j);
  if (wall_tick_[i] == a || wall_tick_[j] == a) ++cnt_.wall_body;
  const Vec pre_a[2] = {pos(i, a), pos(j, a)};
  std::int64_t n;
  const Vec xj = pos(j, a - 1), xi = diff_at(pos(i, a - 1), xj, a - 1, n), zero{};
  Vec xi2, xj2, vi2, vj2;
  SpecularTrace tr;
  bool multi = false;
  std::optional<Specular> spm;
  Vec ui = move_of(i, a);
  ui[0] -= n * sh_;  // (shear: i's image nearest j; shear.hpp)
  int why = static_cast<int>(spec_of(i, j, spm).pair_map(xi, zero, ui, move_of(j, a), xi2, xj2, vi2, vj2, &tr));
  if (why == 0) {
    xi2 = shifted_at(xj, xi2, a, vi2);
    xj2 = shifted_at(xj, xj2, a, vj2);
    why = post_reason(i, j, xi2, xj2, vi2, vj2, a, pre_a, multi);
  }
  if (why != 0) {
    std::array<std::uint64_t, 8> reasons{};
    ++reasons[std::min(why, 7)];
    ++cnt_.redraws[std::min(why, 7)];
    if (why == redraw_outside) {
      if (!collide_drawn(i, j, a, true)) group_collide(i, j, a, own_[i].ctr, reasons, true);
    } else if (!group_collide(i, j, a, own_[i].ctr, reasons, false)) {
      collide_drawn(i, j, a, true) || group_collide(i, j, a, own_[i].ctr, reasons, true);
    }
    return;
  }
  if (multi) ++cnt_.multi_body;
  if (tr.backscatter) ++cnt_.backscatters;
  ++own_[i].pc;
  ++own_[j].pc;
  ++ncoll_;
  if (trace != nullptr) trace->push_back({a, gid(i), gid(j)});
  if (obs_ || events || seen_) [[unlikely]] note_pair(a, i, j, xi2, xj2, plus_h(vi2), plus_h(vj2));
  apply(i, j, xi2, xj2, vi2, vj2, a);
}

// The reverse of a specular collision: the map's exact inverse on the negated lines.
template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::back_specular(int i, int j, std::int64_t a) {
  std::int64_t n;
  const Vec xj = pos(j, a - 1), xi = diff_at(pos(i, a - 1), xj, a - 1, n), zero{};
  Vec xi0, xj0, vi0, vj0;
  std::optional<Specular> spm;
  Vec ui = neg(move_of(i, a));
  ui[0] += n * sh_;  // (shear: the image's velocity, negated)
  if (spec_of(i, j, spm).pair_unmap(xi, zero, ui, neg(move_of(j, a)), xi0, xj0, vi0, vj0) != Refusal::none)
    inconsistent("the specular map refuses the post state it is to take back", i, j);
  if (own_[i].pc == 0 || own_[j].pc == 0) inconsistent("a collision count would step back past 0", i, j);
  vi0 = neg(vi0), vj0 = neg(vj0);  // (this frame's velocities)
  xi0 = shifted_at(xj, xi0, a, vi0);
  xj0 = shifted_at(xj, xj0, a, vj0);
  --own_[i].pc;
  --own_[j].pc;
  --ncoll_;
  apply(i, j, xi0, xj0, vi0, vj0, a);
}

}  // namespace revcol::lattice
