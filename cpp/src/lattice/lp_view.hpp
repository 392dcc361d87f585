// A logical process's view of the gas: the engine of one LP of the parallel engine
// (timewarp.hpp; ARCHITECTURE.md "The parallel engine"). The LP holds the particles of its slab
// and of a band about it; the others are parked (in no cell, no event, their state not this LP's
// to know). A message writes a particle's whole state at the key of the event that produced it
// (lp_write: it enters the view, or its state is replaced); a particle that leaves the band is
// parked (lp_park). Both are journal entries like the events, so a rollback to before their key
// takes them back (the state they replaced is kept with them: a message is not this LP's
// computation, so it cannot be undone by reverse computation).
// Part of BasicEngine (revcol/lattice/engine_core.hpp, which declares it); included by
// engine_impl.hpp, which the instantiating sources include.
#pragma once
#include <limits>
#include <stdexcept>

#include "revcol/lattice/engine_core.hpp"

namespace revcol::lattice {

template <class Op, class Bits, class Queue>
auto BasicEngine<Op, Bits, Queue>::record(int id) const -> Record {
  const std::size_t p = local(id);
  const Line &l = ln_[p], &w = pre_wall_[p];
  return Record{l.x, l.v, l.ta, w.x, w.v, w.ta, wall_tick_[p], own_[p].X, own_[p].ctr, own_[p].pc};
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::lp_set(int p, const Record& r) {
  ln_[p] = Line{r.x, r.v, r.ta};
  pre_wall_[p] = Line{r.pre_x, r.pre_v, r.pre_ta};
  wall_tick_[p] = r.wall_tick;
  own_[p].X = r.X;
  own_[p].ctr = r.ctr;
  own_[p].pc = r.pc;
  ++slot_[static_cast<std::size_t>(p)].ver;
  sync(p);
}

// p into the view's search (its cell, or lists about its anchor: a prediction renews them when
// the line has left the ball by then) and out of it
template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::lp_unpark(int p) {
  parked_[static_cast<std::size_t>(p)] = 0;
  if (lists_) {
    nl_.insert(p, ln_[p].x);
    sync(p);  // (the anchor unwrapped about the new centre)
  } else {
    grid_.insert(p, grid_.cell_id(ln_[p].x));
  }
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::lp_unplace(int p) {
  if (lists_) nl_.remove(p);
  else grid_.remove(p);
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::lp_begin(const std::vector<std::uint8_t>& held, LpNotes* notes) {
  require(held.size() == ln_.size(), "lattice LP: the view must say, for every particle, whether it is held");
  require(notes != nullptr, "lattice LP: the engine needs somewhere to leave its notes");
  parked_.assign(ln_.size(), 0);
  for (std::size_t id = 0; id < held.size(); ++id) {
    if (held[id] != 0) continue;
    const int p = static_cast<int>(local(static_cast<int>(id)));
    parked_[static_cast<std::size_t>(p)] = 1;
    lp_unplace(p);
    schedule(p, none, 0, 0, -1);
    ++slot_[static_cast<std::size_t>(p)].ver;  // a held particle's slot naming it is stale
  }
  require(!reversed_ || jhow_ == Rollback::reverse, "lattice LP: a run back rolls back by reverse computation");
  lp_ = notes;
  observer_.reset();  // an LP never observes itself: an observed one keeps the observer's calls
  obs_ = nullptr;
  seen_ = notes->seen;
  if (seen_ != nullptr) seen_->dim = static_cast<int>(D);
  keep_journal(true, jhow_);
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::lp_write(int id, const Record& r, const EventKey& k) {
  require(lp_ != nullptr, "lattice LP: lp_write before lp_begin");
  // (the clock may be past k's tick after a rollback to before a later key: no event is)
  require(!(k < last_key()) && k.t < tick_limit, "lattice LP: a message's key is before the last processed event (roll back first)");
  const int p = static_cast<int>(local(id));
  jlp_.emplace_back(parked_[static_cast<std::size_t>(p)], record(id));
  jdone_.push_back(Done{k.t, k.kind, p, k.id, lpw, 0, 0});
  const bool was = parked_[static_cast<std::size_t>(p)] != 0;
  lp_set(p, r);
  if (was) lp_unpark(p);
  clock_ = k.t;
  last_key_ = {k.t, k.kind};
  predict(p, k.t);
}

// A state this view cannot hold: particle id overlaps a held body at k's tick t, and not as a
// pair whose collision comes later on the tick (their first overlap at t, a key after k). The
// view is then inconsistent (a message it has not had yet, or one to be cancelled).
template <class Op, class Bits, class Queue>
bool BasicEngine<Op, Bits, Queue>::lp_clear(int id, const EventKey& k) const {
  const int p = static_cast<int>(local(id));
  if (!parked_.empty() && parked_[static_cast<std::size_t>(p)] != 0) return true;
  const Vec x = pos(p, k.t), x0 = pos(p, k.t - 1);
  bool clear = true;
  near(p, [&](int q) {
    if (q == p || !overlap(x, pos(q, k.t), p, q)) return;
    const EventKey pair{k.t, coll_kind(p, q), std::min(gid(p), gid(q))};
    if (!(k < pair) || overlap(x0, pos(q, k.t - 1), p, q)) clear = false;
  });
  return clear;
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::lp_park(int id, const EventKey& k) {
  require(lp_ != nullptr, "lattice LP: lp_park before lp_begin");
  const int p = static_cast<int>(local(id));
  require(parked_[static_cast<std::size_t>(p)] == 0, "lattice LP: the particle is already parked");
  jlp_.emplace_back(0, record(id));
  jdone_.push_back(Done{k.t, k.kind, p, k.id, lpp, 0, 0});
  parked_[static_cast<std::size_t>(p)] = 1;
  lp_unplace(p);
  schedule(p, none, 0, 0, -1);
  ++slot_[static_cast<std::size_t>(p)].ver;
  last_key_ = {k.t, k.kind};
}

template <class Op, class Bits, class Queue>
bool BasicEngine<Op, Bits, Queue>::lp_next(EventKey& k) {
  const int p = queue_.top();
  if (p < 0) return false;
  k = EventKey{queue_.time(p), queue_.kind(p), gid(p)};
  return true;
}

// The engine's loop, in an LP: the events before `stop` (and at most max), notes->after called
// after each (it may write or park particles: the loop reads the queue afresh). An engine error
// in an event (a speculative state can hold what no sequential state does) undoes that event and
// stops the run there, its message in notes->error: the LP waits for a rollback (timewarp.hpp).
template <class Op, class Bits, class Queue>
std::size_t BasicEngine<Op, Bits, Queue>::lp_run(const EventKey& stop, std::size_t max) {
  require(lp_ != nullptr, "lattice LP: lp_run before lp_begin");
  lp_->stop = stop;
  lp_->max = max;
  lp_->done = 0;
  lp_->ids.clear();
  lp_stepped_ = false;
  try {
    loop(std::numeric_limits<std::uint64_t>::max(), tick_limit - 1, reversed_, 0, {});
  } catch (const std::exception& e) {
    if (lp_->in_after) {  // not the engine's: the LP's own
      lp_->in_after = false;
      throw;
    }
    // the event under way, undone: its journal entries go, its particles come back as they
    // were and are predicted again (its slot will come up again, as it was)
    auto cut = [](auto& q, std::size_t m) { q.erase(q.begin() + static_cast<std::ptrdiff_t>(m), q.end()); };
    cut(jdone_, lp_->marks[0]);
    cut(jwall_, lp_->marks[1]);
    cut(jss1_, lp_->marks[2]);
    cut(jss2_, lp_->marks[3]);
    cut(jss2x_, lp_->marks[4]);
    cut(jlp_, lp_->marks[5]);
    cut(jback_, lp_->marks[6]);
    undo(false);
    last_key_ = jdone_.empty() ? j_key0_ : std::make_pair(jdone_.back().t, jdone_.back().kind);
    if (seen_ != nullptr) seen_->drop_after(last_key());  // (the event's observer calls)
    lp_stepped_ = false;
    lp_->error = e.what();
  }
  return lp_->done;
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::lp_note(int i, int j) {
  lp_->ids.clear();
  const auto it = ngroups_ == 0 ? groups_.end() : groups_.find(LogKey{static_cast<std::uint32_t>(gid(i)), own_[i].pc});
  if (it != groups_.end()) {
    for (int q : it->second->members) lp_->ids.push_back(q);
  } else {
    lp_->ids.push_back(gid(i));
    lp_->ids.push_back(gid(j));
  }
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::commit_before(const EventKey& k) {
  std::size_t n = 0, walls = 0, kept = 0, xs = 0, lps = 0, backs = 0;
  while (n < jdone_.size() && done_key(jdone_[n]) < k) {
    const Done& d = jdone_[n++];
    kept += d.kept;
    backs += d.type == coll && (d.unreflected & 8u) != 0;
    walls += d.type == wall;
    xs += d.type == coll;
    lps += d.type == lpw || d.type == lpp;
    j_clock0_ = d.t;
    j_key0_ = {d.t, d.kind};
  }
  auto cut = [](auto& q, std::size_t m) { q.erase(q.begin(), q.begin() + static_cast<std::ptrdiff_t>(m)); };
  cut(jdone_, n);
  cut(jwall_, walls);
  cut(jlp_, lps);
  cut(jback_, backs);
  if (jhow_ == Rollback::save_all) cut(jss1_, kept);
  if (jhow_ == Rollback::save_changes) {
    cut(jss2_, kept);
    cut(jss2x_, xs);
  }
  j_ncoll0_ = reversed_ ? j_ncoll0_ - xs : j_ncoll0_ + xs;
}

template <class Op, class Bits, class Queue>
EventKey BasicEngine<Op, Bits, Queue>::last_key() const noexcept {
  if (!jdone_.empty()) return done_key(jdone_.back());
  return EventKey{j_key0_.first, j_key0_.second, std::numeric_limits<std::int32_t>::min()};
}

}  // namespace revcol::lattice
