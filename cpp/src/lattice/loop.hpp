// The lattice engine's event loop: run and run_back, the loop over the queue, and the wall
// reflection (a mirror on the transition into the first tick beyond the wall).
// Part of BasicEngine (revcol/lattice/engine_core.hpp, which declares it and explains the
// design); included by engine_impl.hpp, which the instantiating sources include.
//
// Event rule. Invariant: no pair overlaps at any integer tick, and every centre is inside [h, H] on
// wall axes (a mixture: [r_p, L - r_p], sizes.hpp). A pair collides on the transition a-1 -> a
// where a is the first tick at which its incoming lines overlap; a wall reflects on the transition into the first tick beyond it
// (cell_grid.hpp; a line anchored beyond a wall, by a neutral event of the reflection's tick or,
// in the reverse, by the undo of a collision that came right after a reflection on the same
// tick, reflects on that tick); a cell crossing is neutral. One event per particle in the queue (its earliest:
// crossing, wall, or collision with a neighbour); a collision found by p with q is also written into
// q's slot when it is earlier there, so a pair's collision sits in both slots; an event whose versions
// are stale is recomputed when it comes up.
//
// Neighbour search (set_list_shell): cells or neighbour lists, behind a double filter; neither
// changes which collisions happen (predict.hpp; docs/lattice.md "Finding the next event").
// Order within a tick (queue key (tick, kind, id)): forward, crossings (kind 0), walls (1), then
// collisions by pair index lo = min(i, j) ascending (kind 2 + lo); reverse, crossings, collisions by
// lo descending (kind 1 + (N - 1 - lo)), then walls (kind N + 1). So the reverse undoes each tick's
// state changes in exactly the opposite order: the bits-back X and the streams are stacks.
//
// Reverse (the prototype's engine.py): negate velocities, anchor ticks and the clock, run the same
// search, apply v -> -reverse(-v) at each collision with the streams stepping back, negate again.
#pragma once
#include <algorithm>
#include <stdexcept>
#include <string>

#include "revcol/lattice/engine_core.hpp"

namespace revcol::lattice {

template <class Op, class Bits, class Queue>
auto BasicEngine<Op, Bits, Queue>::run(std::uint64_t collisions, std::int64_t until, const std::function<bool()>& poll) -> std::uint64_t {
  require(until >= clock_, "lattice run: the end tick is before the clock");
  require(until < tick_limit, "lattice run: the end tick is beyond the tick limit 2^61");
  if (collisions == 0) return 0;
  // an engine error mid-run leaves the state as it was: an undo journal of the particles the
  // run changes (O(changes), so that run(collisions=1) stays O(1) at any N)
  begin_undo();
  try {
    const std::uint64_t done = loop(collisions, until, false, 0, poll);
    if (obs_ && sync_after_run) obs_->sync(time_of(clock_));
    return done;
  } catch (...) {
    undo();
    // the observer has seen events the undo took back: the observation ends, discarded
    observer_.reset();
    obs_ = nullptr;
    throw;
  }
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::run_back(std::uint64_t to_collisions, std::int64_t to_tick, const std::function<bool()>& poll) {
  require(to_collisions <= ncoll_, "lattice run_back: the target collision count is ahead of the state");
  require(to_tick >= origin_ && to_tick <= clock_, "lattice run_back: the target tick must be in [origin, clock]");
  stop_observing();  // observation is forward only (revcol/engine/observe.hpp)
  const Snapshot before = snapshot();  // an engine error mid-run leaves the state as it was
  flip();
  try {
    loop(0, -to_tick, true, to_collisions, poll);
  } catch (...) {
    restore(before);
    throw;
  }
  flip();
}

template <class Op, class Bits, class Queue>
auto BasicEngine<Op, Bits, Queue>::loop(std::uint64_t want, std::int64_t until, bool back, std::uint64_t target, const std::function<bool()>& poll) -> std::uint64_t {
  std::uint64_t done = 0;
  std::uint32_t since_poll = 0;
  for (;;) {
    if (lp_ != nullptr) [[unlikely]] {  // a logical process's run (lp_run): its hook, its stop
      if (lp_stepped_) {
        lp_stepped_ = false;
        clock_ = lp_->key.t;
        ++lp_->done;
        lp_->in_after = true;
        lp_->after(lp_->ctx);
        lp_->in_after = false;
      }
      const int q = queue_.top();
      if (q < 0 || lp_->done >= lp_->max || !(EventKey{queue_.time(q), queue_.kind(q), gid(q)} < lp_->stop)) return done;
      begin_undo();  // (an engine error in the event undoes it: lp_run)
      lp_->marks = {jdone_.size(), jwall_.size(), jss1_.size(), jss2_.size(), jss2x_.size(), jlp_.size(), jback_.size()};
    }
    const int p = queue_.top();
    if (poll && ++since_poll == kPollEvents && p >= 0) {
      // Ctrl-C: end at the tick before the next event, as run(until = that tick) would
      since_poll = 0;
      if (!poll()) until = std::max(clock_, std::min(until, queue_.time(p) - 1));
    }
    if (p < 0 || queue_.time(p) > until) {
      clock_ = until;
      return done;
    }
    const std::int64_t t = queue_.time(p);
    // the periodic re-sort, between two ticks (every event before t done, none at t yet)
    if (resort_at_ != 0 && cnt_.crossings >= resort_at_ && t > last_key_.first && !jon_) [[unlikely]] {
      resort(t);
      continue;
    }
    ++cnt_.events;
    const bool journal = jon_ && (!back || lp_ != nullptr);  // (an LP running back journals its back steps)
    if (lp_ != nullptr) [[unlikely]] {
      lp_stepped_ = true;
      lp_->key = EventKey{t, queue_.kind(p), gid(p)};
      lp_->type = valid(p) ? static_cast<LpNotes::Type>(slot_[static_cast<std::size_t>(p)].type) : LpNotes::none;
    }
    if (!valid(p)) {
      ++cnt_.stale;
      if (journal) jdone_.push_back(Done{t, queue_.kind(p), p, -1, none, 0, 0});
      predict(p, t);
      continue;
    }
    const Slot& sp = slot_[static_cast<std::size_t>(p)];
    if (sp.type == cross) {
      ++cnt_.crossings;
      if (journal) jdone_.push_back(Done{t, queue_.kind(p), p, -1, cross, 0, 0});
      if (lists_) nl_.renew(p, pos(p, t));
      predict(p, t);
      continue;
    }
    const std::int32_t kind = queue_.kind(p);
    check_order(t, kind);
    if (sp.type == wall) {
      if (journal) {
        jkept_ = 0;
        if (jhow_ != Rollback::reverse) save_state(p);
        jwall_.push_back(WallDone{wall_tick_[p], pre_wall_[p], impulse_here(p)});
        jdone_.push_back(Done{t, kind, p, -1, wall, 0, jkept_});
      }
      reflect(p, t);
      continue;
    }
    // the pair's drawer i: the smaller particle id
    const bool first = gid(p) < gid(sp.partner);
    const int i = first ? p : sp.partner, j = first ? sp.partner : p;
    if (throw_at_collision != 0 && (back ? ncoll_ : ncoll_ + 1) == throw_at_collision)
      throw std::runtime_error("lattice engine: test hook at collision " + std::to_string(throw_at_collision));
    if (back) {
      if (ncoll_ == target && lp_ == nullptr) {
        clock_ = t - 1;
        return done;
      }
      std::uint8_t side = 0;
      if (lp_ != nullptr) [[unlikely]] {
        lp_note(i, j);  // (before: a group's entry goes with its back step)
        if (journal) side = note_back(i);
      }
      collide_back(i, j, t);
      if (journal) jdone_.push_back(Done{t, kind, i, j, coll, static_cast<std::uint8_t>(side | (p == j ? 4u : 0u)), 0});
    } else {
      unreflected_ = 0;
      jkept_ = 0;
      if (journal && jhow_ != Rollback::reverse) {
        save_state(i, true);
        save_state(j);
      }
      collide_forward(i, j, t);
      if (journal) jdone_.push_back(Done{t, kind, i, j, coll, static_cast<std::uint8_t>(unreflected_ | (p == j ? 4u : 0u)), jkept_});
      if (lp_ != nullptr) [[unlikely]] lp_note(i, j);
    }
    ++done;
    if (!back && done == want) {
      clock_ = t;
      return done;
    }
  }
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::check_order(std::int64_t t, std::int32_t k) {
  if (std::make_pair(t, k) < last_key_)
    throw std::logic_error(std::string(reversed_ ? "lattice engine: inconsistent state (a damaged or edited checkpoint, or a bug): events out of order: (tick "
                                                   : "lattice engine: events out of order (a bug): (tick ") + std::to_string(t) + ", kind " +
                           std::to_string(k) + ") after (tick " + std::to_string(last_key_.first) + ", kind " +
                           std::to_string(last_key_.second) + "), collision " + std::to_string(ncoll_));
  last_key_ = {t, k};
}

// ---- walls ----
// The reflection on the transition a-1 -> a of a line whose point at a is beyond the walls of
// the axes C. Specular (every axis of C specular): on each axis of C the integer mirror of the
// pre phase (wall_mirror, its own inverse) and v_k -> -v_k; the other axes fly on. Bounce back
// (an axis of C bounces, engine::Boundary::bounce): the mirror on each axis of C, every other
// axis stalls at its a-1 point, v -> -v. Reversed (velocity v again from the post point), the
// line is beyond exactly the walls of C at the next tick (mirror(x) + v is beyond iff x was
// inside; a stalled axis is back at its forward a point, inside), so the reverse applies the
// same rule and mirror(mirror(x)) = x, the stall and -(-v) restore the pre state exactly.
template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::reflect(int p, std::int64_t a) {
  journal(p);
  const Vec x0 = pos(p, a - 1), v0 = vel(p, a - 1);
  // the mirror takes the tick's move (a field: the mid velocity v + h) and gives the move after,
  // whose point at a-1 is x - move (the ghost); the velocity at a is that move plus h
  Vec x = x0, v = plus_h(v0);
  const Vec old_line_at_a = pos(p, a);
  const unsigned axes = reflection(p, x, v, a);
  const Vec ghost = back_at(x, v, a - 1);
  v = plus_h(v);
  if (gax_ >= 0 && (axes >> gax_ & 1u) && impulse_here(p)) [[unlikely]] field_impulse(v0[gax_], v[gax_], reversed_);
  near(p, [&](int q) {
    if (q == p) return;
    // the forward's guard (its reverse would meet q first); the reverse replays the forward, and
    // its ghost is the forward's pre-wall line at a, beyond the wall (right after a collision
    // undone on this tick, a body may well overlap it there)
    if (!reversed_ && overlap_at(ghost, pos(q, a - 1), p, q, a - 1)) {
      throw std::runtime_error("lattice engine: a wall and a body within one tick that the rule cannot resolve (particle " +
                               std::to_string(p) + ", tick " + std::to_string(a) + "); not supported yet");
    }
    if (overlap_at(old_line_at_a, pos(q, a), p, q, a)) ++cnt_.wall_body;
  });
  if (!reversed_ && (obs_ || events || seen_)) [[unlikely]] note_wall(a, p, x, v, axes);
  pre_wall_[p] = Line{x0, v0, a - 1};  // a group collision at a may take it back
  ln_[p].x = x;
  ln_[p].v = v;
  ln_[p].ta = a;
  sync(p);
  ++slot_[static_cast<std::size_t>(p)].ver;
  wall_tick_[p] = a;
  ++cnt_.walls;
  predict(p, a);
}

// Whether a reflection of p adds to the field's wall momentum: always, but in an LP of the parallel
// engine only for a particle in a region it owns (the authority: each reflection counted once).
template <class Op, class Bits, class Queue>
bool BasicEngine<Op, Bits, Queue>::impulse_here(int p) const noexcept {
  return lp_ == nullptr || lp_->mine == nullptr || (*lp_->mine)[static_cast<std::size_t>(region_[static_cast<std::size_t>(p)])] != 0;
}

// A reflection on the field's axis: |v_after - v_before| to the wall met (the lower one when the
// velocity before points down, in either frame), added forward and taken off (`off`) in reverse
// and by a rollback. (A group that takes a reflection of its tick in, counted in wall_groups, keeps
// it counted.)
template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::field_impulse(std::int64_t before, std::int64_t after, bool off) noexcept {
  const std::int64_t d = after - before;
  const u128 m = static_cast<u128>(d < 0 ? -d : d);
  const bool lower = before < 0;
  auto& w = cnt_.field_wall_impulse;
  const std::size_t at = lower ? 0 : 2;
  u128 sum = (static_cast<u128>(w[at + 1]) << 64) | w[at];
  sum = off ? sum - m : sum + m;
  w[at] = static_cast<std::uint64_t>(sum);
  w[at + 1] = static_cast<std::uint64_t>(sum >> 64);
}

template <class Op, class Bits, class Queue>
unsigned BasicEngine<Op, Bits, Queue>::reflection(int p, Vec& x, Vec& v, std::int64_t a) const noexcept {
  unsigned axes = 0;  // the walls it meets
  bool whole = false;  // one of them bounces back
  for (std::size_t k = 0; k < D; ++k)
    if (u_.wall[k] && (x[k] + v[k] < lo_of(p) || x[k] + v[k] > hi_of(p, static_cast<int>(k)))) {
      axes |= 1u << k;
      whole = whole || u_.bounce[k];
    }
  const Vec v0 = v;
  Vec d{};  // the move of the axes that fly on (shear: shifted_at below, across a gradient face)
  for (std::size_t k = 0; k < D; ++k) {
    if (axes >> k & 1u) wall_mirror(x[k], v[k], lo_of(p), hi_of(p, static_cast<int>(k)));
    else if (!whole) d[k] = v[k];  // a bounce back: the other axes stall at their a-1 point
  }
  if (whole) v = neg(v0);
  x = shifted_at(x, d, a, v);
  return axes;
}

}  // namespace revcol::lattice
