// The parallel lattice engine: one gas cut into K slabs, each run by a logical process (LP)
// ahead of the others (Time Warp), a straggler rolled back by the engine's own reverse
// computation (no state saved per event), and the committed state the sequential engine's bit
// for bit whatever K and the schedule (ARCHITECTURE.md "The parallel engine"; PARALLEL.md).
//
// Views. LP m owns the particles whose centres are in its slab [F_m, F_m+1) and holds those in
// its band, the slab widened by W on each side (W = 3 sigma + 8 vmax: everything an event of an
// owned particle reads, two bodies and a tick of travel from the slab); the others are parked
// (lp_view.hpp). The slab and band faces cut the axis into fine regions, each with one owner and
// a set of bands: ownership and views are functions of a centre's position, kept by the engine's
// region machinery (set_regions) at the keys at which they change.
//
// Who computes what. Every LP processes every event of the particles it holds, in key order
// (tick, kind, id). One of them is the event's authority: for a collision, the LP that owned the
// key particle (the pair's lower id) before it; for a crossing or a wall, the particle's owner.
// The authority's view holds everything the event reads (a collision of an owned particle reads
// bodies within two diameters and a tick of travel of the slab; a group that reaches further
// is refused when it would be committed), so its result is the sequential engine's once its view
// is right. Every other LP's result is a guess. After a collision, the authority sends each
// particle's whole post state to every other LP whose band held it before or holds it after; an
// LP that guessed the same state (bit for bit) counts it confirmed, any other LP rolls back to
// before the key and writes the state at the key instead of computing it. After a crossing or a
// wall of an owned particle that enters another band, the owner sends it there. A particle
// leaving a band is parked by the LP itself, at the key at which it leaves.
//
// Time Warp. A message whose key is at or before the LP's last processed key is a straggler
// (unless it confirms a guess): the LP's engine runs back to before the key (rollback_before),
// the messages it had taken in since go back to its input, and the messages it sent since are
// cancelled by anti-messages (aggressive cancellation). GVT is the least key any LP could still
// process or any message in flight carries; everything before it is committed: the journals and
// message histories are forgotten there, and a guess not yet confirmed there is a protocol bug.
//
// Transport. workers = 1: the LPs on the calling thread, one step at a time, round robin or
// (fuzz) in a random order with random message delays. workers > 1: that many threads (the
// calling one among them), each running its share of the LPs a batch of steps at a time; a
// message goes into its receiver's inbox (a mutex each), and mail ends the receiver's turn
// after its event under way (a straggler then undoes fewer events); LPs that share a thread run
// in key order among themselves (a turn stops at the others' least next key). GVT is computed
// with every worker stopped at a barrier (every gvt_every steps of a worker, or when one finds
// nothing to do), which is also where the run ends, the calling thread polls for Ctrl-C, and an
// LP's error is raised. Neither the schedule nor the delays may change a bit.
//
// Running back (Config::back). Every LP is built in run_back's reversed frame (one build), and
// the same protocol runs on the back steps, keyed by the reversed frame's order; a rollback
// undoes a back step by computing its forward collision again (rollback.hpp, redo_collision).
#pragma once
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "revcol/error.hpp"
#include "revcol/lattice/engine.hpp"
#include "revcol/lattice/lp.hpp"
#include "revcol/lattice/lp_seen.hpp"
#include "revcol/lattice/slab_views.hpp"
#include "revcol/lattice/timewarp_state.hpp"
#include "revcol/lattice/workers.hpp"
#include "revcol/lattice/state.hpp"

namespace revcol::lattice {

template <class Engine>
class TimeWarp {
 public:
  static constexpr std::size_t D = Engine::D;
  using Vec = VecN<D>;
  using Snapshot = SnapshotN<D>;
  using Record = typename Engine::Record;

  struct Config {
    int lps = 2;                    ///< K, the logical processes (slabs)
    int axis = 0;                   ///< the slabs' axis
    std::uint64_t fuzz = 0;         ///< 0: round robin, messages delivered at once; else the seed of a random order and delays
    int max_delay = 16;             ///< fuzz: a message waits up to this many scheduler steps
    std::uint64_t gvt_every = 512;  ///< scheduler steps (threads: a worker's steps) between GVT computations
    int workers = 1;                ///< threads (the calling one among them), at most the LPs
    int batch = 64;                 ///< threads: an LP's steps per turn
    Rollback how = Rollback::reverse;  ///< how an LP rolls back: reverse computation, or state saving (SS1, SS2)
    bool lazy = true;               ///< lazy cancellation (else aggressive: anti-messages at once)
    std::int64_t window = 0;        ///< optimism: no event more than this many ticks past GVT (0: none)
    double shell = -1.0;            ///< the LPs' search, as set_list_shell's: -1 the sequential engine's automatic one, 0 cells
    bool back = false;              ///< a run back: the LPs in run_back's reversed frame (ticks and keys too); rollback by reverse computation
  };

  /// K LPs on the state s (validated: bad input throws InvalidArgument, nothing is built).
  TimeWarp(const TimeWarp&) = delete;  // (its LPs' engines call back into it)
  TimeWarp& operator=(const TimeWarp&) = delete;
  TimeWarp(const Snapshot& s, const Config& c) : c_(c), rng_(c.fuzz) {
    base_.counters = s.counters;  // (the LPs' counters start from these: committed_state)
    require(c.axis >= 0 && c.axis < static_cast<int>(D), "parallel lattice engine: the slabs' axis must be 0, 1 or (3D) 2");
    require(c.max_delay >= 0 && c.gvt_every >= 1 && c.batch >= 1, "parallel lattice engine: max_delay >= 0, gvt_every >= 1, batch >= 1");
    require(c.workers >= 1 && c.workers <= c.lps, "parallel lattice engine: 1 to K (the logical processes) workers");
    require(c.workers == 1 || c.fuzz == 0, "parallel lattice engine: the fuzzed schedule runs on one worker");
    require(!(c.shell > 2.0) && (c.shell <= 0.0 || c.shell >= 0.02), "parallel lattice engine: the LPs' list shell must be 0 (cells), < 0 (automatic) or in [0.02, 2]");
    const auto& u = s.units;
    const std::size_t ax = static_cast<std::size_t>(c.axis);
    reach_ = u.sigma + 4 * u.vmax;
    sv_ = SlabViews(c.lps, u.L[ax], u.wall[ax], 3 * u.sigma + 8 * u.vmax);
    require(!c.back || c.how == Rollback::reverse, "parallel lattice engine: a run back rolls back by reverse computation");
    horizon_ = c.back ? -s.clock : s.clock;
    // the LPs' engines (their search and regions: one build each), built by the workers side by side
    lps_.resize(static_cast<std::size_t>(c.lps));
    build_in_workers(c.workers, c.lps, [&](int m) {
      lps_[static_cast<std::size_t>(m)] = std::make_unique<Lp>(s, c.axis, sv_.faces(), c.shell, c.back);
    });
    if (!s.observer.empty() && !c.back) obs_ = Engine::make_observer(s.units, s.x, s.v, s.clock, nullptr, &s, s.radius);  // a running observation goes on (lp_seen.hpp)
    for (int m = 0; m < c.lps; ++m) {
      Lp& lp = *lps_[static_cast<std::size_t>(m)];
      lp.me = m;
      std::vector<std::uint8_t> held(s.x.size());
      for (std::size_t id = 0; id < held.size(); ++id) held[id] = sv_.in_view(m, lp.eng.region(static_cast<int>(id)));
      lp.eng.migrations = &lp.notes.migrations;
      lp.hook = {this, &lp};
      lp.notes.after = &TimeWarp::after_hook;
      lp.notes.ctx = &lp.hook;
      if (obs_) lp.notes.seen = &lp.seen;
      lp.mine.resize(sv_.faces().size());  // the fine regions it owns (a field's wall momentum: its authority's)
      for (std::size_t r = 0; r < lp.mine.size(); ++r) lp.mine[r] = sv_.owner(static_cast<int>(r)) == m ? 1 : 0;
      lp.notes.mine = &lp.mine;
      lp.eng.keep_journal(true, c.how);
      lp.eng.lp_begin(held, &lp.notes);
      lp.last = lp.eng.last_key();
    }
  }

  /// Runs every LP to tick `until` (no event after it), then commits: the state is the
  /// sequential engine's run(until) bit for bit (snapshot()). A run back: `until` in the reversed
  /// frame (-T), the state run_back(to_tick = T) reaches.
  /// Ctrl-C (poll() false, asked by the calling thread): every LP goes back to the last tick GVT
  /// has passed, and the run ends there, as run(until = that tick) would. Returns false then.
  bool run_until(std::int64_t until, const std::function<bool()>& poll = {}) {
    require(until >= horizon_, "parallel lattice engine: the end tick is before the clock");
    require(until < tick_limit, "parallel lattice engine: the end tick is beyond the tick limit");
    start_ = horizon_;
    gvt_t_ = std::max(gvt_t_, start_);
    horizon_ = until;
    stopped_ = false;
    if (c_.workers > 1) run_threads(poll);
    else run_one(poll);
    return !stopped_;
  }

  /// The committed state at the last run_until's tick, by particle id (each particle from its
  /// owner; the rare log and the groups the union of the LPs'; timewarp_state.hpp).
  Snapshot snapshot() const {
    std::vector<const Engine*> engines;
    for (const auto& lp : lps_) engines.push_back(&lp->eng);
    Snapshot s = committed_state(engines, sv_, horizon_, c_.back, &base_);
    if (obs_) obs_->save(s.observer, s.observer_counts);  // (not synced: run_parallel syncs the whole run's once)
    return s;
  }

  /// The counts so far, all LPs.
  TimeWarpStats stats() const {
    TimeWarpStats t;
    t.gvts = gvts_;
    t.gvt_seconds = gvt_s_;
    t.journal_peak_bytes = jpeak_;
    t.journal_bytes_at_gvts = jbytes_;
    t.journal_entries_at_gvts = jentries_;
    for (const auto& lp : lps_) {
      t.add(lp->st);
      t.lp_events.push_back(lp->st.events);
    }
    return t;
  }
  Engine& engine(int m) { return lps_.at(static_cast<std::size_t>(m))->eng; }  ///< LP m's engine (tests)
  int lps() const noexcept { return c_.lps; }                      ///< K
  std::int64_t band() const noexcept { return sv_.band(); }         ///< W, lattice units

 private:
  struct Message {
    EventKey key;
    int id = 0;  // the particle
    int to = 0;
    std::uint64_t serial = 0;
    bool anti = false;
    Record rec;
  };
  using MKey = std::pair<EventKey, std::uint64_t>;  // (key, serial): messages in key order
  struct Lp {
    Lp(const Snapshot& s, int axis, std::vector<std::int64_t> faces, double shell, bool back)
        : eng(s, operator_for(s.units, s.law), axis, std::move(faces), shell, back) {}
    int me = 0;
    Engine eng;
    LpNotes notes;
    std::vector<std::uint8_t> mine;                   // per fine region: this LP owns it (notes.mine)
    LpSeen seen;                                      // an observed run: the observer's calls of its events
    EventKey last;                                    // the last key processed
    std::map<MKey, Message> pending, taken;           // input not yet processed; processed (written or confirming)
    std::map<std::pair<EventKey, int>, Record> guesses;  // (key, particle): a guessed post state, unconfirmed
    std::map<MKey, Message> sent;                     // sent since GVT (for anti-messages)
    std::map<MKey, Message> lazy;                     // sent, then rolled back: cancelled unless sent again
    std::map<EventKey, std::string> refused;          // events whose reach the LP's view cannot vouch for
    std::vector<std::uint64_t> annihilate;            // anti-messages that overtook their message
    bool blocked = false;
    EventKey block_key;
    std::string block_error;                          // blocked by an engine error (else by a write)
    TimeWarpStats st;
    std::uint64_t nsent = 0;                          // (serials: (LP << 48) + its count)
    std::pair<TimeWarp*, Lp*> hook;                   // the engine's after-event hook's argument
    std::mutex inbox_mx;                              // threads: messages posted to it
    std::vector<Message> inbox;
    std::atomic<bool> mail{false};                    // threads: the inbox holds some (set and cleared under inbox_mx)
  };

  // ---- one LP step ----
  // Processes the LP's next keys: its messages at the least pending key, or else its engine's
  // events before that key (at most `batch`), if any at or before the horizon (and the window)
  // and before `cap`. False: nothing to do.
  bool step(Lp& lp, const EventKey& cap = EventKey::never()) {
    if (lp.blocked) return false;
    const std::int64_t limit = c_.window > 0 ? std::min(horizon_, gvt_t_ + c_.window) : horizon_;
    const EventKey end = std::min(cap, EventKey::tick_start(limit + 1));
    EventKey ke;
    const bool has_e = lp.eng.lp_next(ke) && ke < end;
    const bool has_m = !lp.pending.empty() && lp.pending.begin()->first.first < end;
    if (!has_e && !has_m) {
      flush(lp, end);  // nothing up to it will send them again
      return false;
    }
    if (has_m && (!has_e || !(ke < lp.pending.begin()->first.first))) {
      flush(lp, lp.pending.begin()->first.first);
      take_messages(lp);
      return true;
    }
    flush(lp, ke);
    lp.notes.migrations.clear();
    lp.eng.lp_run(has_m ? lp.pending.begin()->first.first : end, static_cast<std::size_t>(c_.workers > 1 ? c_.batch : 1));
    if (!lp.notes.error.empty()) {  // an engine error: real only if no rollback comes before GVT passes it
      block(lp, lp.notes.key, "parallel lattice engine: logical process " + std::to_string(lp.me) + ": " + lp.notes.error);
      lp.notes.error.clear();
    }
    return true;
  }

  // the LP waits at key k for a rollback (why: an engine error's message, else a view that
  // cannot hold what it was told)
  void block(Lp& lp, const EventKey& k, std::string why = {}) {
    if (lp.blocked) return;
    lp.blocked = true;
    lp.block_key = k;
    lp.block_error = std::move(why);
    ++lp.st.blocked;
  }

  // the engine's hook after each event of an LP's run (LpNotes::after)
  static void after_hook(void* ctx) {
    auto* h = static_cast<std::pair<TimeWarp*, Lp*>*>(ctx);
    Lp& lp = *h->second;
    lp.last = lp.notes.key;
    if (lp.notes.type == LpNotes::none) {
      ++lp.st.stale;
    } else {
      ++lp.st.events;
      h->first->after_event(lp);
      h->first->flush(lp, lp.last.next());
    }
    lp.notes.migrations.clear();
    // threads: mail ends the turn, so that a straggler rolls back as few events as it can
    if (lp.mail.load(std::memory_order_relaxed)) lp.notes.max = lp.notes.done;
  }

  // lazy cancellation: the messages sent before a rollback, at keys before k, that the
  // re-execution did not send again: cancelled now
  void flush(Lp& lp, const EventKey& k) {
    while (!lp.lazy.empty() && lp.lazy.begin()->first.first < k) {
      Message a = std::move(lp.lazy.begin()->second);
      lp.lazy.erase(lp.lazy.begin());
      a.anti = true;
      ++lp.st.anti;
      post(std::move(a));
    }
  }

  // the messages at the least pending key, written into the view
  void take_messages(Lp& lp) {
    const EventKey k = lp.pending.begin()->first.first;
    std::vector<int> ids;
    while (!lp.pending.empty() && lp.pending.begin()->first.first == k) {
      auto node = lp.pending.extract(lp.pending.begin());
      const Message& m = node.mapped();
      ++lp.st.written;
      lp.eng.lp_write(m.id, m.rec, k);
      ids.push_back(m.id);
      lp.taken.insert(std::move(node));
    }
    lp.last = k;
    // a view that cannot hold what it was told waits for the rollback that must come; so does
    // one told part of an event it would compute itself (the key particle's message, which must
    // come, makes its own computation stale; the messages still to come roll it back)
    EventKey ke;
    if (lp.eng.lp_next(ke) && ke == k && lp.eng.held(k.id) && std::find(ids.begin(), ids.end(), k.id) == ids.end()) block(lp, k);
    for (int id : ids)
      if (!lp.blocked && !lp.eng.lp_clear(id, k)) block(lp, k);
    park_leavers(lp, k, ids);  // a particle written outside the band leaves the view at the key
    lp.notes.migrations.clear();
  }

  // the particles `ids` (or, none given, those whose region the last event changed) that are
  // outside the band now: parked at the key
  void park_leavers(Lp& lp, const EventKey& k, std::vector<int> ids = {}) {
    if (ids.empty()) ids = moved(lp);
    for (int id : ids)
      if (lp.eng.held(id) && !sv_.in_view(lp.me, lp.eng.region(id))) lp.eng.lp_park(id, k);
  }
  // the particles whose region the last event changed, each once
  std::vector<int> moved(const Lp& lp) const {
    std::vector<int> ids;
    for (const auto& mg : lp.notes.migrations)
      if (std::find(ids.begin(), ids.end(), static_cast<int>(mg[1])) == ids.end()) ids.push_back(static_cast<int>(mg[1]));
    return ids;
  }

  // a particle's region before the last event (its first migration's `from`, else its region)
  int region_before(const Lp& lp, int id) const {
    for (const auto& mg : lp.notes.migrations)
      if (mg[1] == id) return static_cast<int>(mg[2]);
    return lp.eng.region(id);
  }

  // the authority's messages after an event (timewarp_messages.hpp)
  void after_event(Lp& lp);
  void check_reach(Lp& lp, const EventKey& k);
  void send(Lp& lp, const EventKey& k, int id, std::uint64_t to);

  // ---- the transport ----
  // (never delivered at once: a receiver's rollback sends anti-messages, and their receiver may
  // be the sender, in the middle of an event)
  void post(Message m) {
    if (threaded_) {
      Lp& to = *lps_[static_cast<std::size_t>(m.to)];
      const std::lock_guard<std::mutex> hold(to.inbox_mx);
      to.inbox.push_back(std::move(m));
      to.mail.store(true, std::memory_order_relaxed);
      return;
    }
    const std::uint64_t wait = c_.fuzz == 0 || c_.max_delay == 0 ? 0 : rng_() % static_cast<std::uint64_t>(c_.max_delay + 1);
    flight_.push_back({tick_ + wait, std::move(m)});
  }
  // one worker: delivers the messages whose delay has passed (all: every one in flight)
  void deliver(bool all) {
    ++tick_;
    std::deque<std::pair<std::uint64_t, Message>> now, keep;
    for (auto& item : flight_) (all || item.first <= tick_ ? now : keep).push_back(std::move(item));
    flight_ = std::move(keep);
    for (auto& item : now) receive(*lps_[static_cast<std::size_t>(item.second.to)], std::move(item.second));
  }
  // threads: the messages in an LP's inbox, taken in; true if there were any
  bool drain(Lp& lp) {
    if (!lp.mail.load(std::memory_order_relaxed)) return false;  // (a post after this: the next turn's)
    std::vector<Message> got;
    {
      const std::lock_guard<std::mutex> hold(lp.inbox_mx);
      got.swap(lp.inbox);
      lp.mail.store(false, std::memory_order_relaxed);
    }
    for (Message& m : got) receive(lp, std::move(m));
    return !got.empty();
  }

  // one worker: round robin, or (fuzz) a random order with random delays
  void run_one(const std::function<bool()>& poll) {
    threaded_ = false;
    std::uint64_t since_gvt = 0;
    for (;;) {
      bool any = false;
      for (int n = 0; n < c_.lps; ++n) {
        deliver(false);
        any = step(*lps_[c_.fuzz != 0 ? pick(c_.lps) : static_cast<std::size_t>(n)]) || any;
      }
      for (int n = 0; n < c_.lps && !any; ++n) any = step(*lps_[static_cast<std::size_t>(n)]);  // (a random order may miss one)
      if (!any && !flight_.empty()) {
        deliver(true);
        continue;
      }
      if (++since_gvt >= c_.gvt_every || !any) {
        since_gvt = 0;
        const auto t0 = std::chrono::steady_clock::now();
        const bool end = settle(poll, !any);
        gvt_s_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (end) return;
      }
    }
  }

  // threads (workers.hpp): a turn of an LP takes in its inbox and runs a batch of its events;
  // at the barrier, every inbox is emptied first (a rollback posts anti-messages)
  void run_threads(const std::function<bool()>& poll) {
    threaded_ = true;
    run_workers(
        c_.workers, c_.lps, c_.gvt_every,
        [&](int m) {
          Lp& lp = *lps_[static_cast<std::size_t>(m)];
          const bool got = drain(lp);
          return step(lp, shared_cap(m)) || got;
        },
        [&](bool idle) {
          const auto t0 = std::chrono::steady_clock::now();
          for (bool more = true; more;) {
            more = false;
            for (auto& lp : lps_) more = drain(*lp) || more;
          }
          const bool end = settle(poll, idle);
          gvt_s_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
          return end;
        });
  }

  // threads: LP m's turn ends after the least next key of the other LPs on its worker (blocked
  // ones aside), so that LPs sharing a thread run in key order among themselves and roll back
  // only for the other workers' messages
  EventKey shared_cap(int m) {
    EventKey cap = EventKey::never(), k;
    if (c_.lps <= c_.workers) return cap;  // (an LP to each thread)
    const auto [lo, hi] = share_of(m, c_.workers, c_.lps);
    for (int j = lo; j < hi; ++j) {
      Lp& o = *lps_[static_cast<std::size_t>(j)];
      if (j == m || o.blocked) continue;
      if (o.eng.lp_next(k) && k < cap) cap = k;
      if (!o.pending.empty() && o.pending.begin()->first.first < cap) cap = o.pending.begin()->first.first;
    }
    return cap.is_never() ? cap : cap.next();
  }

  // With nothing in flight: GVT and commit; then, when `idle` and no LP has anything left up to
  // the horizon, the run is done (true); a Ctrl-C ends it at the last tick GVT has passed.
  bool settle(const std::function<bool()>& poll, bool idle) {
    const EventKey g = gvt_commit();
    if (poll && !poll() && g.t - 1 >= start_) {
      stop_at(g.t - 1);
      return true;
    }
    if (!idle) return false;
    for (auto& lp : lps_) {  // (a blocked LP has nothing to do, but another may still roll it back)
      EventKey k;
      if (lp->blocked) continue;
      if ((lp->eng.lp_next(k) && k.t <= horizon_) || (!lp->pending.empty() && lp->pending.begin()->first.first.t <= horizon_) ||
          !lp->lazy.empty() || !lp->inbox.empty() || !flight_.empty())
        return false;
    }
    for (auto& lp : lps_) {  // nothing can take a blocked LP back now
      if (lp->blocked && !lp->block_error.empty()) throw std::runtime_error(lp->block_error);
      if (lp->blocked) throw std::logic_error("parallel lattice engine: an LP waits for a rollback that no message brings (a bug)");
    }
    return true;
  }

  // every LP back to the state after tick t (nothing after it processed), every message after
  // it cancelled: the state run(until = t) has
  void stop_at(std::int64_t t) {
    const EventKey k = EventKey::tick_start(t + 1);
    for (auto& lp : lps_) {
      if (!(lp->last < k)) rollback(*lp, k);
      flush(*lp, EventKey::never());
    }
    for (bool more = true; more;) {  // the anti-messages, each to its message
      more = !flight_.empty();
      deliver(true);
      for (auto& lp : lps_) more = drain(*lp) || more;
    }
    for (auto& lp : lps_)
      if (!lp->pending.empty() && !(lp->pending.begin()->first.first < k))
        lp->pending.erase(lp->pending.lower_bound(MKey{k, 0}), lp->pending.end());
    horizon_ = t;
    stopped_ = true;
  }

  void receive(Lp& lp, Message m) {
    const MKey mk{m.key, m.serial};
    if (m.anti) {
      if (lp.pending.erase(mk) != 0) return;
      if (lp.taken.count(mk) != 0) {
        rollback(lp, m.key);
        lp.pending.erase(mk);
        return;
      }
      lp.annihilate.push_back(m.serial);  // it overtook its message
      return;
    }
    if (const auto a = std::find(lp.annihilate.begin(), lp.annihilate.end(), m.serial); a != lp.annihilate.end()) {
      lp.annihilate.erase(a);
      return;
    }
    if (lp.last < m.key) {
      lp.pending.emplace(mk, std::move(m));
      return;
    }
    const auto g = lp.guesses.find({m.key, m.id});
    if (g != lp.guesses.end() && g->second == m.rec) {  // the guess was right
      lp.guesses.erase(g);
      ++lp.st.confirmed;
      lp.taken.emplace(mk, std::move(m));
      return;
    }
    rollback(lp, m.key);
    lp.pending.emplace(mk, std::move(m));
  }

  // ---- rollback ----
  void rollback(Lp& lp, const EventKey& k) {
    const std::size_t before = lp.eng.journal_size();
    lp.eng.rollback_before(k.t, k.kind, k.id);
    ++lp.st.rollbacks;
    lp.st.undone += before - lp.eng.journal_size();
    lp.last = lp.eng.last_key();
    // the messages taken in at or after k go back to the input; guesses from then are gone
    for (auto it = lp.taken.lower_bound(MKey{k, 0}); it != lp.taken.end();) lp.pending.insert(lp.taken.extract(it++));
    lp.guesses.erase(lp.guesses.lower_bound({k, std::numeric_limits<int>::min()}), lp.guesses.end());
    lp.refused.erase(lp.refused.lower_bound(k), lp.refused.end());
    if (lp.blocked && !(lp.block_key < k)) {
      lp.blocked = false;
      lp.block_error.clear();
    }
    // what it sent from then is cancelled: now (aggressive), or when the re-execution passes its
    // key without sending it again (lazy)
    for (auto it = lp.sent.lower_bound(MKey{k, 0}); it != lp.sent.end();) lp.lazy.insert(lp.sent.extract(it++));
    if (!c_.lazy) flush(lp, EventKey::never());
  }

  // ---- GVT ----
  // GVT: the least key an LP could still process or a message in flight carries; everything
  // before its tick is committed (whole ticks: a Ctrl-C can stop on the tick before it)
  EventKey gvt_commit() {
    ++gvts_;
    EventKey g = EventKey::never();
    for (const auto& item : flight_) g = std::min(g, item.second.key);
    for (auto& lp : lps_) {
      EventKey k;
      if (lp->blocked) g = std::min(g, lp->block_key);
      if (!lp->lazy.empty()) g = std::min(g, lp->lazy.begin()->first.first);  // (an anti-message it may still send)
      if (!lp->pending.empty()) g = std::min(g, lp->pending.begin()->first.first);
      if (lp->eng.lp_next(k)) g = std::min(g, k);
    }
    // (a run that reached its horizon: everything up to it is committed)
    const EventKey whole = EventKey::tick_start(g.t);
    std::uint64_t bytes = 0;  // the journals' memory, before the commit frees some
    for (auto& lp : lps_) bytes += lp->eng.journal_bytes(), jentries_ += lp->eng.journal_size();
    jbytes_ += bytes;
    jpeak_ = std::max(jpeak_, bytes);
    for (auto& lp : lps_) {
      const EventKey until = std::min(whole, lp->last.next());
      if (!lp->refused.empty() && lp->refused.begin()->first < until) throw std::runtime_error("parallel lattice engine: " + lp->refused.begin()->second);
      if (!lp->guesses.empty() && lp->guesses.begin()->first.first < until)
        throw std::logic_error("parallel lattice engine: a guess of logical process " + std::to_string(lp->me) + " at tick " +
                               std::to_string(lp->guesses.begin()->first.first.t) + " was never confirmed (a bug)");
      lp->eng.commit_before(until);
      lp->taken.erase(lp->taken.begin(), lp->taken.lower_bound(MKey{until, 0}));
      lp->sent.erase(lp->sent.begin(), lp->sent.lower_bound(MKey{until, 0}));
    }
    if (obs_) {  // the committed events' observer calls, in key order
      std::vector<LpSeen*> seen;
      for (auto& lp : lps_) seen.push_back(&lp->seen);
      feed_committed(seen, whole, *obs_);
    }
    if (!g.is_never()) gvt_t_ = g.t;
    return g;
  }

  // ---- helpers ----
  std::size_t pick(int k) { return static_cast<std::size_t>(rng_() % static_cast<std::uint64_t>(k)); }
  Snapshot base_;  // the counters the LPs were built with (committed_state)
  Config c_;
  std::mt19937_64 rng_;
  SlabViews sv_;
  std::int64_t reach_ = 0, horizon_ = 0, start_ = 0;
  std::vector<std::unique_ptr<Lp>> lps_;
  std::deque<std::pair<std::uint64_t, Message>> flight_;  // one worker: (delivery step, message)
  std::uint64_t tick_ = 0, gvts_ = 0;                     // one worker: scheduler steps
  std::int64_t gvt_t_ = 0;                                // the last GVT's tick (the window)
  double gvt_s_ = 0.0;                                    // seconds in the GVT step
  std::uint64_t jpeak_ = 0, jbytes_ = 0, jentries_ = 0;   // the journals at the GVTs (TimeWarpStats)
  std::unique_ptr<engine::Observer> obs_;                 // a running observation: fed the committed events
  bool threaded_ = false, stopped_ = false;
};

}  // namespace revcol::lattice

#include "revcol/lattice/timewarp_messages.hpp"  // (TimeWarp's after_event, check_reach, send)
