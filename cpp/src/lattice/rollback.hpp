// The lattice engine's rollback: the latest events undone one by one in the forward frame, each
// by its own reverse computation, from the journal of queue pops (what a logical process of an
// optimistic parallel run does with a straggler; ARCHITECTURE.md "Rollback").
// Part of BasicEngine (revcol/lattice/engine_core.hpp, which declares it and explains the
// design); included by engine_impl.hpp, which the instantiating sources include.
//
// The undo of each event is the inverse of its forward map, read in the forward frame:
//   pair      pair_reverse (or, specular mode, pair_unmap) of the post points at tick a and the
//             post velocities gives the points at a-1 and the pre velocities (pair2d.hpp: the
//             plain inverse of pair_forward); the drawer's stream steps back by 1 + the rare
//             log's redraws, X takes back its bits, the log entry goes;
//   group     the members' stall points (their points at a are their a-1 points) with the
//             logged pre velocities (a resolve) or the negated ones (a bounce); the drawer's
//             stream steps back by the draws tried; a member that took in its reflection at a
//             is reflected again (the reflection's own entry undoes it next);
//   wall      the reflection map on the time-reversed post line (its point at a, -v): the
//             mirror is its own inverse (cell_grid.hpp), so it gives the point at a-1 and -v;
//             the one-tick cache it replaced (wall tick, pre-wall line) comes back from the entry;
//   neutral   (crossings, list renewals, stale recomputes) nothing physical;
//   back step (an LP running back, in the reversed frame) its forward collision computed again
//             (redo_collision).
// Then every particle the undone span touched (popped, partners, group members) is anchored
// at the new clock and predicted again, its version bumped so that any slot naming its
// undone line is stale: the queue is again one whose least event is the next one (the argument
// of the forward loop: a slot is never later than its particle's next event), so a run on from
// the rolled-back state processes the same events as the sequential run did.
#pragma once
#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>
#include <tuple>

#include "revcol/lattice/engine_core.hpp"

namespace revcol::lattice {

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::keep_journal(bool on, Rollback how) {
  require(how == Rollback::reverse || how == Rollback::save_all || how == Rollback::save_changes,
          "lattice journal: rollback by reverse computation, save_all (SS1) or save_changes (SS2)");
  require(!on || sh_ == 0, "lattice journal: not built for a sheared gas yet (rollback and the parallel engine run without shear)");
  jon_ = on;
  jhow_ = how;
  restart_journal();
}

template <class Op, class Bits, class Queue>
auto BasicEngine<Op, Bits, Queue>::journal_bytes() const noexcept -> std::size_t {
  std::size_t b = jdone_.size() * sizeof(Done) + jwall_.size() * sizeof(WallDone) + jss1_.size() * sizeof(Saved) +
                  jss2_.size() * sizeof(std::pair<int, Line>) + jss2x_.size() * sizeof(Bits) +
                  jlp_.size() * sizeof(std::pair<std::uint8_t, Record>);  // (an LP's: the states messages replaced)
  for (const Saved& s : jss1_) b += s.X.heap_bytes();
  for (const Bits& x : jss2x_) b += x.heap_bytes();
  for (const auto& w : jlp_) b += w.second.X.heap_bytes();
  for (const BackDone& x : jback_) b += sizeof(BackDone) + x.lines.size() * sizeof(Line);
  return b;
}

// State saving: p's state before the event under way (SS1 its whole record; SS2 its line, and
// the drawer's X).
template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::save_state(int p, bool drawer) {
  if (jhow_ == Rollback::save_all) {
    jss1_.push_back(Saved{p, ln_[p], pre_wall_[p], wall_tick_[p], own_[p].X, own_[p].ctr, own_[p].pc});
  } else {
    jss2_.emplace_back(p, ln_[p]);
    if (drawer) jss2x_.push_back(own_[p].X);
  }
  ++jkept_;
}

// State saving: the undo of a wall or collision entry from the states saved before it (SS1), or
// from the lines and X saved and the counters stepped back (SS2); the log entries it wrote go.
template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::restore_kept(const Done& d) {
  std::vector<int> members;  // SS2: whose counts step back
  std::uint64_t back = 0;    // SS2: the draws the drawer's stream steps back
  if (d.type == coll) {
    const int i = d.p;
    const LogKey key{static_cast<std::uint32_t>(gid(i)), own_[i].pc};
    const auto it = groups_.empty() ? groups_.end() : groups_.find(key);
    if (it != groups_.end()) {
      const std::shared_ptr<Group> g = it->second;
      for (int q : g->members) {
        members.push_back(static_cast<int>(local(q)));
        groups_.erase(LogKey{static_cast<std::uint32_t>(q), own_[members.back()].pc});
      }
      back = g->draws;
      --ngroups_;
    } else {
      members = {i, d.q};
      const auto logged = log_.find(key);
      const bool drawn = mode_ == Mode::exact || logged != log_.end();
      back = drawn ? 1 + (logged != log_.end() ? logged->second : 0) : 0;
      if (logged != log_.end()) log_.erase(logged);
    }
    --ncoll_;
    ++cnt_.collisions;
  } else {
    ++cnt_.walls;
  }
  if (jhow_ == Rollback::save_all) {
    for (int k = 0; k < d.kept; ++k) {
      const Saved& s = jss1_.back();
      ln_[s.p] = s.line;
      pre_wall_[s.p] = s.pre_wall;
      wall_tick_[s.p] = s.wall_tick;
      own_[s.p].X = s.X;
      own_[s.p].ctr = s.ctr;
      own_[s.p].pc = s.pc;
      touch(s.p);
      sync(s.p);
      jss1_.pop_back();
    }
    return;
  }
  for (int k = 0; k < d.kept; ++k) {
    const auto& [p, line] = jss2_.back();
    ln_[p] = line;
    touch(p);
    sync(p);
    jss2_.pop_back();
  }
  if (d.type != coll) return;
  own_[d.p].X = jss2x_.back();
  jss2x_.pop_back();
  own_[d.p].ctr -= back;  // (i is the drawer of a pair and of its group)
  for (int q : members) --own_[q].pc;
  for (int s = 0; s < 2; ++s)
    if (d.unreflected >> s & 1u) wall_tick_[s == 0 ? d.p : d.q] = d.t;  // the group had taken the reflection in
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::restart_journal() {
  jdone_.clear();
  jwall_.clear();
  jss1_.clear();
  jss2_.clear();
  jss2x_.clear();
  jlp_.clear();
  jback_.clear();
  j_ncoll0_ = ncoll_;
  j_clock0_ = clock_;
  j_key0_ = last_key_;
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::rollback(std::uint64_t collisions) {
  require(jon_, "lattice rollback: the engine keeps no journal (keep_journal)");
  require(collisions >= j_ncoll0_ && collisions <= ncoll_,
          "lattice rollback: the target collision count must be in [journal_start, collisions] = [" +
              std::to_string(j_ncoll0_) + ", " + std::to_string(ncoll_) + "]");
  if (collisions == ncoll_) {
    // already there unless events after the collision were processed: undo those
    if (jdone_.empty() || jdone_.back().type == coll) return;
  }
  // keep the entries up to the target collision's own (the collision count after an entry is
  // the count before the ones above it)
  unwind([&](const Done& d) { return d.type == coll && ncoll_ == collisions; }, std::numeric_limits<std::int64_t>::min());
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::rollback_to_tick(std::int64_t tick) {
  require(jon_, "lattice rollback: the engine keeps no journal (keep_journal)");
  require(tick >= j_clock0_ && tick <= clock_, "lattice rollback: the target tick must be in [journal_start_tick, clock] = [" +
                                                   std::to_string(j_clock0_) + ", " + std::to_string(clock_) + "]");
  unwind([&](const Done& d) { return d.t <= tick; }, tick);
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::rollback_before(std::int64_t tick, std::int32_t kind, std::int32_t id) {
  require(jon_, "lattice rollback: the engine keeps no journal (keep_journal)");
  // (a key on the journal's start tick is fine after the last event before the journal)
  require((tick > j_clock0_ || (tick == j_clock0_ && std::make_pair(tick, kind) > j_key0_)) && tick <= clock_ + 1,
          "lattice rollback: the key must come after the journal's start (tick " + std::to_string(j_clock0_) +
              ", kind " + std::to_string(j_key0_.second) + ") and its tick be at most clock + 1 = " + std::to_string(clock_ + 1));
  const EventKey key{tick, kind, id};
  // (the entries are in the queue's order: a collision under the particle whose slot came up)
  unwind([&](const Done& d) { return done_key(d) < key; }, tick - 1);
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::commit(std::uint64_t collisions) {
  require(collisions >= j_ncoll0_ && collisions <= ncoll_,
          "lattice commit: the collision count must be in [journal_start, collisions] = [" + std::to_string(j_ncoll0_) +
              ", " + std::to_string(ncoll_) + "]");
  std::uint64_t n = j_ncoll0_;
  std::size_t k = 0, walls = 0, kept = 0, xs = 0;
  while (n < collisions) {  // through the entry of collision `collisions`
    const Done& d = jdone_[k++];
    kept += d.kept;
    if (d.type == wall) ++walls;
    if (d.type == coll) ++n, ++xs;
    if (n == collisions) {
      j_clock0_ = d.t;
      j_key0_ = {d.t, d.kind};
    }
  }
  jdone_.erase(jdone_.begin(), jdone_.begin() + static_cast<std::ptrdiff_t>(k));
  jwall_.erase(jwall_.begin(), jwall_.begin() + static_cast<std::ptrdiff_t>(walls));
  if (jhow_ == Rollback::save_all) jss1_.erase(jss1_.begin(), jss1_.begin() + static_cast<std::ptrdiff_t>(kept));
  if (jhow_ == Rollback::save_changes) {
    jss2_.erase(jss2_.begin(), jss2_.begin() + static_cast<std::ptrdiff_t>(kept));
    jss2x_.erase(jss2x_.begin(), jss2x_.begin() + static_cast<std::ptrdiff_t>(xs));
  }
  j_ncoll0_ = collisions;
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::touch(int p) {
  if (jmark_[static_cast<std::size_t>(p)] == jepoch_) return;
  jmark_[static_cast<std::size_t>(p)] = jepoch_;
  jtouched_.push_back(p);
}

// Undoes the journal's top entries until keep(top) (or the journal is empty), then predicts
// the touched particles again at the new clock: the kept top entry's tick (or the journal's
// start), unless `clock` (a tick target) is later.
template <class Op, class Bits, class Queue>
template <class Keep>
void BasicEngine<Op, Bits, Queue>::unwind(Keep keep, std::int64_t clock) {
  stop_observing();  // observation is forward only
  if (jmark_.size() != ln_.size() || ++jepoch_ == 0) {
    jmark_.assign(ln_.size(), 0);
    jepoch_ = 1;
  }
  jtouched_.clear();
  // (no engine error can come from here but a broken invariant, a bug: logic_error)
  while (!jdone_.empty() && !keep(jdone_.back())) {
    const Done d = jdone_.back();
    jdone_.pop_back();
    touch(d.p);
    if (d.type == lpw || d.type == lpp) {  // an LP's write or park: the state before it comes back
      auto [was_parked, before] = std::move(jlp_.back());
      jlp_.pop_back();
      const bool parked = parked_[static_cast<std::size_t>(d.p)] != 0;
      lp_set(d.p, before);
      if (parked && was_parked == 0) lp_unpark(d.p);
      if (!parked && was_parked != 0) {
        parked_[static_cast<std::size_t>(d.p)] = 1;
        lp_unplace(d.p);
        schedule(d.p, none, 0, 0, -1);
      }
      continue;
    }
    if (jhow_ != Rollback::reverse && (d.type == wall || d.type == coll)) {  // state saving
      if (d.type == coll) touch(d.q);
      const Vec post = vel(d.p, d.t);  // (a wall: its velocity after, for a field's impulse)
      restore_kept(d);
      if (d.type == wall && gax_ >= 0 && jwall_.back().counted) [[unlikely]] unreflect_impulse(d.p, d.t, post);
      if (d.type == wall) {
        if (jhow_ == Rollback::save_changes) {  // (SS1's record holds the cache)
          pre_wall_[d.p] = jwall_.back().pre_wall;
          wall_tick_[d.p] = jwall_.back().wall_tick;
        }
        jwall_.pop_back();
      }
      if (d.type == coll && trace != nullptr && !trace->empty()) trace->pop_back();
      continue;
    }
    if (d.type == wall) {
      undo_wall(d.p, d.t, jwall_.back());
      jwall_.pop_back();
    } else if (d.type == coll && reversed_) {  // an LP running back: its back step undone
      touch(d.q);
      redo_collision(d);
    } else if (d.type == coll) {
      touch(d.q);
      undo_collision(d.p, d.q, d.t, d.unreflected);
      if (trace != nullptr && !trace->empty()) trace->pop_back();
    }
  }
  if (jdone_.empty()) {
    clock_ = std::max(clock, j_clock0_);
    last_key_ = j_key0_;
  } else {
    clock_ = std::max(clock, jdone_.back().t);
    last_key_ = {jdone_.back().t, jdone_.back().kind};
  }
  // anchor every touched particle at the clock first (its cell or list ball as of the clock:
  // a prediction reads its neighbours' cells), then predict each
  if (!parked_.empty())  // (an LP's parked particles have no place and no event)
    jtouched_.erase(std::remove_if(jtouched_.begin(), jtouched_.end(), [&](int p) { return parked_[static_cast<std::size_t>(p)] != 0; }),
                    jtouched_.end());
  for (int p : jtouched_) {
    ++slot_[static_cast<std::size_t>(p)].ver;
    reanchor(p, clock_);
    sync(p);
  }
  unwinding_ = true;
  for (int p : jtouched_) predict(p, clock_);
  unwinding_ = false;
  if (seen_ != nullptr) seen_->drop_after(last_key());  // an LP's: the undone events' observer calls
}

// A field's wall momentum taken off for p's reflection at a undone by state saving: p's line is
// again the one before it; `post` its velocity at a after it. The forward's test of the walls met
// (reflection() on the tick's move) tells whether the field's axis was one.
template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::unreflect_impulse(int p, std::int64_t a, const Vec& post) noexcept {
  const Vec pre = vel(p, a - 1);
  Vec x = pos(p, a - 1), v = plus_h(pre);
  if (reflection(p, x, v, a) >> gax_ & 1u) field_impulse(pre[gax_], post[gax_], !reversed_);
}

// (a field: the mirror takes the tick's moves, the mid velocities: v at a less h after, the
// velocity at a-1 is the move before less h; the field's wall momentum is taken off, or, in an LP
// running back, given back)
template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::undo_wall(int p, std::int64_t a, const WallDone& w) {
  const Vec post = vel(p, a);
  Vec x = pos(p, a), v = neg(minus_h(post));
  const unsigned axes = reflection(p, x, v, a);
  if (axes == 0) throw std::logic_error("lattice rollback: a reflection's post line meets no wall (a bug)");
  ln_[p] = Line{x, minus_h(neg(v)), a - 1};
  if (gax_ >= 0 && (axes >> gax_ & 1u) && w.counted) [[unlikely]] field_impulse(ln_[p].v[gax_], post[gax_], !reversed_);
  pre_wall_[p] = w.pre_wall;
  wall_tick_[p] = w.wall_tick;
  sync(p);
  ++cnt_.walls;
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::undo_collision(int i, int j, std::int64_t a, std::uint8_t unreflected) {
  // i's last collision is the one undone here: its key is (i, i's count)
  const LogKey key{static_cast<std::uint32_t>(gid(i)), own_[i].pc};
  if (!groups_.empty()) [[unlikely]] {
    if (const auto it = groups_.find(key); it != groups_.end()) {
      const std::shared_ptr<Group> g = it->second;  // (undo_group erases its keys)
      undo_group(a, *g, i, j, unreflected);
      return;
    }
  }
  if (own_[i].pc == 0 || own_[j].pc == 0) throw std::logic_error("lattice rollback: a collision count would step back past 0 (a bug)");
  const auto logged = log_.empty() ? log_.end() : log_.find(key);
  const Vec xj = pos(j, a), xi = diff(pos(i, a), xj), zero{};
  // the post moves (a field: the velocities at a less h; field.hpp) give the pre moves
  const Vec ui = minus_h(vel(i, a)), uj = minus_h(vel(j, a));
  Vec xi0, xj0, vi0, vj0;
  if (mode_ == Mode::specular && logged == log_.end()) {  // (a log entry: a drawn fallback)
    std::optional<Specular> spm;
    if (spec_of(i, j, spm).pair_unmap(xi, zero, ui, uj, xi0, xj0, vi0, vj0) != Refusal::none)
      throw std::logic_error("lattice rollback: the specular map refused a post state it wrote (a bug)");
  } else {
    const std::uint32_t redraws = logged != log_.end() ? logged->second : 0;
    if (own_[i].ctr < 1 + static_cast<std::uint64_t>(redraws)) throw std::logic_error("lattice rollback: a stream would step back past draw 0 (a bug)");
    const std::uint64_t g = draw48(static_cast<std::uint32_t>(gid(i)), seed_, own_[i].ctr - 1);
    std::optional<Op> opm;
    op_of(i, j, opm).pair_reverse(xi, zero, ui, uj, g, own_[i].X, xi0, xj0, vi0, vj0);
    own_[i].ctr -= 1 + redraws;
    if (logged != log_.end()) log_.erase(logged);
  }
  --own_[i].pc;
  --own_[j].pc;
  --ncoll_;
  ln_[i] = Line{shifted(xj, xi0), minus_h(vi0), a - 1};
  ln_[j] = Line{shifted(xj, xj0), minus_h(vj0), a - 1};
  sync(i);
  sync(j);
  ++cnt_.collisions;
}

// An LP running back (built in the reversed frame): a back step about to take back a collision
// drawn by i that read the rare log keeps what its undo needs and the log no longer holds: the
// redraws (the forward's accepted draw is the one after them, so no acceptance test runs again),
// or the group and its members' lines. Returns Done's bit 3 when it kept an entry.
template <class Op, class Bits, class Queue>
std::uint8_t BasicEngine<Op, Bits, Queue>::note_back(int i) {
  const LogKey key{static_cast<std::uint32_t>(gid(i)), own_[i].pc};
  if (const auto it = groups_.empty() ? groups_.end() : groups_.find(key); it != groups_.end()) {
    BackDone b;
    b.group = it->second;
    for (int q : b.group->members) b.lines.push_back(ln_[local(q)]);
    jback_.push_back(std::move(b));
    return 8;
  }
  const auto logged = log_.empty() ? log_.end() : log_.find(key);
  if (logged == log_.end()) return 0;
  jback_.push_back(BackDone{logged->second, nullptr, {}});
  return 8;
}

// The undo of a back step (an LP running back, in the reversed frame): the forward collision it
// took back, computed again. The back step left the pair's lines at their forward pre points
// (at tick a here) with the negated pre velocities; the forward map of those, with the draw the
// forward accepted (after the logged redraws) and the drawer's X, gives the post points (at
// a - 1 here) and velocities and X before the back step, bit for bit (pair_forward is a
// function of its inputs; pair_reverse its inverse). Specular mode: the deterministic map. A
// group: its members' lines come back from the entry note_back kept.
template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::redo_collision(const Done& d) {
  const int i = d.p, j = d.q;
  const std::int64_t a = d.t;
  BackDone side;
  if ((d.unreflected & 8u) != 0) {
    side = std::move(jback_.back());
    jback_.pop_back();
  }
  if (side.group) {
    const std::shared_ptr<Group> g = side.group;
    for (std::size_t m = 0; m < g->members.size(); ++m) {
      const int q = static_cast<int>(local(g->members[m]));
      ln_[q] = side.lines[m];
      touch(q);
      ++own_[q].pc;
      groups_.emplace(LogKey{static_cast<std::uint32_t>(g->members[m]), own_[q].pc}, g);
      sync(q);
    }
    own_[local(g->drawer)].ctr += g->draws;
    ++ngroups_;
    ++ncoll_;
    ++cnt_.collisions;
    return;
  }
  const Vec xj = pos(j, a), xi = diff(pos(i, a), xj), zero{};
  // the back step's moves into a (a field: the velocities at a less h), negated: the forward's
  const Vec ui = neg(minus_h(vel(i, a))), uj = neg(minus_h(vel(j, a)));
  Vec xi2, xj2, vi2, vj2;
  const bool logged = (d.unreflected & 8u) != 0;
  if (mode_ == Mode::specular && !logged) {
    std::optional<Specular> spm;
    if (spec_of(i, j, spm).pair_map(xi, zero, ui, uj, xi2, xj2, vi2, vj2, nullptr) != Refusal::none)
      throw std::logic_error("lattice rollback: the specular map refused a collision a back step took back (a bug)");
  } else {
    const std::uint64_t g = draw48(static_cast<std::uint32_t>(gid(i)), seed_, own_[i].ctr + side.redraws);
    Bits out;
    std::optional<Op> opm;
    if (op_of(i, j, opm).pair_forward(xi, zero, ui, uj, g, own_[i].X, xi2, xj2, vi2, vj2, out) != Refusal::none)
      throw std::logic_error("lattice rollback: the operator refused the draw a back step took back (a bug)");
    own_[i].X = std::move(out);
    own_[i].ctr += 1 + static_cast<std::uint64_t>(side.redraws);
    if (logged) log_.emplace(LogKey{static_cast<std::uint32_t>(gid(i)), own_[i].pc + 1}, side.redraws);
  }
  ++own_[i].pc;
  ++own_[j].pc;
  ++ncoll_;
  ln_[i] = Line{shifted(xj, xi2), minus_h(neg(vi2)), a - 1};  // (a field: the move before less h)
  ln_[j] = Line{shifted(xj, xj2), minus_h(neg(vj2)), a - 1};
  sync(i);
  sync(j);
  ++cnt_.collisions;
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::undo_group(std::int64_t a, const Group& entry, int i, int j, std::uint8_t unreflected) {
  std::vector<int> g;  // the members' local indices (copies: the entry goes with its last key)
  for (int q : entry.members) g.push_back(static_cast<int>(local(q)));
  const std::vector<Vec> pre_v = entry.pre_v;
  const auto drawer = local(entry.drawer);
  const std::uint32_t draws = entry.draws;
  for (std::size_t m = 0; m < g.size(); ++m)
    if (own_[g[m]].pc != entry.counts[m]) throw std::logic_error("lattice rollback: a group undone before a member's later collision (a bug)");
  if (own_[drawer].ctr < draws) throw std::logic_error("lattice rollback: a stream would step back past draw 0 (a bug)");
  for (std::size_t m = 0; m < g.size(); ++m) {
    Line& l = ln_[g[m]];
    // a member's point at a is its a-1 point (the stall); a bounce's velocities at a are the
    // negated ones at a-1 (a field's too: the moves negated, h added)
    l = Line{pos(g[m], a), pre_v.empty() ? neg(vel(g[m], a)) : pre_v[m], a - 1};
    touch(g[m]);
  }
  own_[drawer].ctr -= draws;
  for (int q : g) {
    groups_.erase(LogKey{static_cast<std::uint32_t>(gid(q)), own_[q].pc});
    --own_[q].pc;
  }
  --ngroups_;
  --ncoll_;
  // a member that took in its reflection at a: its line is the one before the reflection; the
  // state between the reflection and the group had the reflected line and the reflection's cache
  for (int s = 0; s < 2; ++s) {
    if (!(unreflected >> s & 1u)) continue;
    const int m = s == 0 ? i : j;
    pre_wall_[m] = ln_[m];
    Vec x = pos(m, a - 1), v = plus_h(ln_[m].v);  // (as reflect(): the tick's move, then h on)
    if (reflection(m, x, v, a) == 0) throw std::logic_error("lattice rollback: a group member's reflection meets no wall (a bug)");
    ln_[m] = Line{x, plus_h(v), a};
    wall_tick_[m] = a;
  }
  for (int q : g) sync(q);
  ++cnt_.collisions;
}

}  // namespace revcol::lattice
