// The event machinery of the lattice engine, generic over the exact pair operator and, through
// it, over the dimension D = 2 or 3 (LATTICE.md §2, §4; the concrete engines are in
// lattice/engine.hpp). D is deduced from the operator's pair_forward (its vectors are VecN<D>):
// LatticePair2D gives the disk gas, LatticePair3D the sphere gas; the event search, the
// acceptance test, the redraws, the rare log, the group collisions, the counters and the
// snapshots are one code for both (per-axis loops over D; a wall is a flat plane per axis).
//
// State: per particle an anchor position (integer, wrapped into the box) at an anchor tick, an
// integer velocity, a line version (bumped when the line changes) and a Philox stream counter; the
// clock; the bits-back integer X; the rare log; the collision count. Free flight is exact:
// x(t) = x_a + v (t - t_a), wrapped on periodic axes.
//
// Event rule. Invariant: no pair overlaps at any integer tick, and every centre is inside [h, H] on
// wall axes. A pair collides on the transition a-1 -> a where a is the first tick at which its
// incoming lines overlap; a wall reflects on the transition into the first tick beyond it
// (cell_grid.hpp; a line anchored beyond a wall, by a neutral event of the reflection's tick or,
// in the reverse, by the undo of a collision that came right after a reflection on the same
// tick, reflects on that tick); a cell crossing is neutral. One event per particle in the queue (its earliest:
// crossing, wall, or collision with a neighbour); a collision found by p with q is also written into
// q's slot when it is earlier there, so a pair's collision sits in both slots; an event whose versions
// are stale is recomputed when it comes up.
//
// Neighbour search (set_list_shell): the cell grid (a particle's 3^D cells, a cell crossing a
// neutral event) or neighbour lists with a shell (neighbour_lists.hpp, a list renewal the neutral
// event of kind 0 instead); 3D uses lists by default. A prediction drops with a double-precision
// filter the candidates that provably have no overlap tick before its best event so far and sends
// the others to the exact search. Neither the search nor the filter changes which collisions
// happen: the trace and the bits are those of the exhaustive search (test_lattice_lists). That
// needs one order for a particle's slot whoever writes it: (tick, kind, other particle), in its
// own prediction and in a partner's write alike, so a same-tick tie of two partners of one
// particle (same lower index, same kind) goes to the smaller partner whatever order the
// predictions came in (with (tick, kind) alone the first writer kept it, and the searches'
// re-predictions differ: docs/lattice.md "Session 12").
//
// Order within a tick (queue key (tick, kind, id)): forward, crossings (kind 0), walls (1), then
// collisions by pair index lo = min(i, j) ascending (kind 2 + lo); reverse, crossings, collisions by
// lo descending (kind 1 + (N - 1 - lo)), then walls (kind N + 1). So the reverse undoes each tick's
// state changes in exactly the opposite order: the bits-back X and the streams are stacks.
//
// Reverse (the prototype's engine.py): negate velocities, anchor ticks and the clock, run the same
// search, apply v -> -reverse(-v) at each collision with the streams stepping back, negate again.
//
// Forward acceptance (LATTICE.md §4): a candidate post state is redrawn (the drawing stream steps on)
// when the operator refuses it, when a post centre is outside the walls or faster than vmax, when it
// overlaps a third body at tick a, or when its new lines overlap a third body at tick a-1 (a false tie:
// the reverse would meet that body first). The rare log maps the collision index to its redraw count;
// the reverse reads and erases it. Detected and resolved by the rule, counted: three bodies within one
// tick (a third body's line overlapping a pre line at tick a: the pre line belongs to the past of the
// reverse) and a wall and a body within one tick (a collision right after a reflection on the same
// tick). Not resolved, an error naming it (never a silent approximation): a reflected line whose tick
// a-1 point overlaps a body (the reverse would meet the body first), and more than max_redraws redraws.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "revcol/engine/event_queue.hpp"
#include "revcol/engine/observe.hpp"
#include "revcol/error.hpp"
#include "revcol/lattice/cell_grid.hpp"
#include "revcol/lattice/geometry.hpp"
#include "revcol/lattice/neighbour_lists.hpp"
#include "revcol/lattice/units.hpp"
#include "revcol/rng/philox.hpp"

namespace revcol::lattice {

/// Redraw reasons counted by the engine (index into Counters::redraws).
enum RedrawReason : int {
  redraw_cell_readback = 1,    ///< operator: the lifting round-off changes the read-back cell
  redraw_not_approaching = 2,  ///< operator: pre not approaching about the quantized normal
  redraw_empty_post = 3,       ///< operator: empty post phase set
  redraw_out_of_domain = 4,    ///< operator: phases not an interval
  redraw_overlap_after = 5,    ///< post state overlaps a third body at tick a
  redraw_ghost_tie = 6,        ///< new lines overlap a third body at tick a-1
  redraw_outside = 7,          ///< post centre beyond a wall or speed beyond vmax
};
/// Names of the redraw reasons, index 0 unused.
inline constexpr const char* redraw_names[8] = {"",           "cell_readback", "not_approaching", "empty_post",
                                                 "out_of_domain", "overlap_after", "ghost_tie",   "outside"};

/// Event and rare-case counts, cumulative over both directions (not part of the physical state).
struct Counters {
  std::uint64_t events = 0;              ///< queue pops
  std::uint64_t collisions = 0;          ///< collisions applied (forward and reverse)
  std::uint64_t walls = 0;               ///< wall reflections applied (both directions)
  std::uint64_t crossings = 0;           ///< neutral events: cell crossings, or list renewals (set_list_shell)
  std::uint64_t stale = 0;               ///< stale events recomputed
  std::array<std::uint64_t, 8> redraws{};  ///< forward redraws by RedrawReason
  std::uint64_t log_entries = 0;         ///< rare-log entries written (forward)
  std::uint64_t multi_body = 0;          ///< three bodies within one tick (resolved by the rule)
  std::uint64_t wall_body = 0;           ///< a wall and a body within one tick (resolved by the rule)
  std::uint64_t group_resolves = 0;      ///< groups resolved specularly, pre velocities logged (a log entry)
  std::uint64_t group_bounces = 0;       ///< groups that bounced back (the fallback; a log entry)
  std::uint64_t wall_groups = 0;         ///< group members whose reflection at the same tick the group took in
};

/// A group collision in the rare log: a pair that no draw could resolve because a third body (or
/// more) is met within the same tick. Its members stay at their tick a-1 positions ("stall") and
/// either take the velocities of a specular resolution (pre_v holds their exact pre velocities,
/// so the reverse restores them) or, when that post state would break the event rule, bounce
/// back (every velocity negated, an involution: pre_v empty).
template <std::size_t D>
struct GroupEntryN {
  std::uint64_t index = 0;       ///< collision index (1-based)
  int drawer = 0;                ///< whose stream the tried draws came from
  std::vector<int> members;      ///< ascending
  std::vector<VecN<D>> pre_v;    ///< members' exact pre velocities (a resolve); empty: a bounce
  bool operator==(const GroupEntryN&) const = default;
};
/// A 2D group entry.
using GroupEntry = GroupEntryN<2>;

/// Everything that defines a lattice state in D dimensions, in the forward frame, positions at the clock.
template <std::size_t D>
struct SnapshotN {
  UnitsN<D> units;                             ///< units and box
  std::uint32_t seed = 1;                      ///< Philox key {particle, seed}
  std::int64_t clock = 0;                      ///< the current tick
  std::int64_t origin = 0;                     ///< the tick of the initial state (no run back past it)
  std::uint64_t collisions = 0;                ///< collisions since the initial state
  std::vector<VecN<D>> x;                      ///< positions at the clock
  std::vector<VecN<D>> v;                      ///< velocities
  std::vector<std::uint64_t> streams;          ///< per-particle Philox counters
  std::vector<std::uint64_t> bits;             ///< the bits-back integer X, 64-bit words, low first
  std::vector<std::pair<std::uint64_t, std::uint32_t>> log;  ///< rare log: collision index -> redraws
  std::vector<GroupEntryN<D>> groups;          ///< rare log: group collisions (resolves and bounces)
  std::array<std::uint64_t, 2> energy0{};      ///< initial sum |v|^2 (128 bits: low, high word)
  std::array<std::int64_t, 2 * D> momentum0{};  ///< initial momentum per axis (128 bits: low, high)
  Counters counters;                           ///< statistics (not compared by same_state)
};
/// A 2D snapshot.
using Snapshot = SnapshotN<2>;
/// A 3D snapshot.
using Snapshot3 = SnapshotN<3>;

/// True when two snapshots hold the same physical state bit for bit (everything but counters).
template <std::size_t D>
bool same_state(const SnapshotN<D>& a, const SnapshotN<D>& b) {
  const UnitsN<D> &u = a.units, &w = b.units;
  return u.S == w.S && u.sigma == w.sigma && u.L == w.L && u.wall == w.wall && u.vmax == w.vmax &&
         u.tick_bits == w.tick_bits && u.cell_bits == w.cell_bits &&
         a.seed == b.seed && a.clock == b.clock && a.origin == b.origin && a.collisions == b.collisions &&
         a.x == b.x && a.v == b.v && a.streams == b.streams && a.bits == b.bits && a.log == b.log &&
         a.groups == b.groups &&
         a.energy0 == b.energy0 && a.momentum0 == b.momentum0;
}

/// -a, per component.
template <std::size_t D>
inline VecN<D> neg(const VecN<D>& a) noexcept {
  VecN<D> o;
  for (std::size_t k = 0; k < D; ++k) o[k] = -a[k];
  return o;
}
/// a - b, per component (no wrap).
template <std::size_t D>
inline VecN<D> sub(const VecN<D>& a, const VecN<D>& b) noexcept {
  VecN<D> o;
  for (std::size_t k = 0; k < D; ++k) o[k] = a[k] - b[k];
  return o;
}

/// The dimension of a pair operator: that of the vectors its pair_forward takes.
template <class R, class O, std::size_t D, class... A>
constexpr std::size_t pair_dim(R (O::*)(const VecN<D>&, A...) const) noexcept {
  return D;
}
/// The dimension an engine over Op runs in (2 or 3).
template <class Op>
inline constexpr std::size_t op_dim = pair_dim(&Op::pair_forward);

/// The 48-bit draw k of particle p's stream: Philox4x32-10 block (lo32(k), hi32(k), 0, 0) under
/// key {p, seed}, bits w0 (32) and the top 16 of w1.
inline std::uint64_t draw48(std::uint32_t p, std::uint32_t seed, std::uint64_t k) noexcept {
  const auto w = rng::philox4x32_10({static_cast<std::uint32_t>(k), static_cast<std::uint32_t>(k >> 32), 0U, 0U}, {p, seed});
  return (std::uint64_t{w[0]} << 16) | (w[1] >> 16);
}
/// One forward velocity change as the engine applied it (tests and studies: BasicEngine::events;
/// the observer's direct-sum check). Positions at the event's tick (in the box), velocities
/// before and after, per member.
template <std::size_t D>
struct EventRecordN {
  enum Kind : int { pair = 0, wall = 1, group = 2 };
  std::int64_t tick = 0;           ///< the tick the change takes effect (the transition into it)
  int kind = pair;                 ///< pair, wall or group
  unsigned axes = 0;               ///< a wall: bit k, it met a wall of axis k
  std::vector<int> ids;            ///< the particles
  std::vector<VecN<D>> x, v_before, v_after;  ///< per particle
};

/// The 256 initial bits of X for a seed: four words from stream key {2^32 - 1, seed}.
std::vector<std::uint64_t> initial_bits(std::uint32_t seed);

/// The lattice engine's event machinery over a pair operator Op (pair_forward / pair_reverse as
/// LatticePair2D or LatticePair3D; the dimension is the operator's) and a bits-back integer Bits
/// (BitsBack).
template <class Op, class Bits, class Queue = engine::EventQueue<std::int64_t>>
class BasicEngine {
 public:
  /// The dimension (2 or 3), from the operator.
  static constexpr std::size_t D = op_dim<Op>;
  static_assert(D == 2 || D == 3, "the lattice engine runs in 2 or 3 dimensions");
  using Vec = VecN<D>;              ///< a position, velocity or relative vector
  using Units = UnitsN<D>;          ///< the units and box
  using Snapshot = SnapshotN<D>;    ///< the state
  using GroupEntry = GroupEntryN<D>;  ///< a group collision in the rare log

  /// An engine on a validated integer state at tick clock, X from initial_bits(seed).
  BasicEngine(const Units& u, std::vector<Vec> x, std::vector<Vec> v, std::uint32_t seed, Op op,
              std::int64_t clock = 0)
      : op_(std::move(op)) {
    check_operator(u);
    validate_state(u, x, v);
    require(clock > -tick_limit / 2 && clock < tick_limit / 2, "lattice: the start tick must be within +-2^60");
    Snapshot s;
    s.units = u;
    s.seed = seed;
    s.clock = s.origin = clock;
    s.x = std::move(x);
    s.v = std::move(v);
    s.streams.assign(s.x.size(), 0);
    s.bits = initial_bits(seed);
    const u128 e = kinetic2(s.v);
    s.energy0 = {static_cast<std::uint64_t>(e), static_cast<std::uint64_t>(e >> 64)};
    const auto p = momentum_of(s.v);
    for (std::size_t k = 0; k < D; ++k) {
      s.momentum0[2 * k] = static_cast<std::int64_t>(static_cast<std::uint64_t>(static_cast<u128>(p[k])));
      s.momentum0[2 * k + 1] = static_cast<std::int64_t>(p[k] >> 64);
    }
    load(s);
  }
  /// An engine resuming a snapshot bit for bit.
  BasicEngine(const Snapshot& s, Op op) : op_(std::move(op)) { restore(s); }

  /// Replaces the state by a snapshot (validated first: on bad input nothing changes).
  void restore(const Snapshot& s) {
    validate_state(s.units, s.x, s.v);
    require(s.streams.size() == s.x.size(), "lattice snapshot: streams must hold one counter per particle");
    {
      // energy is kept by every collision to the lattice's rounding (~1e-11 relative over 10^4
      // collisions per particle): a checkpoint whose energy0 is not its velocities' (1e-6
      // relative) was not written by a run. (Momentum is not checked: a group bounce reverses
      // its members' velocities.)
      const double E = static_cast<double>(kinetic2(s.v));
      const double E0 = static_cast<double>((static_cast<u128>(s.energy0[1]) << 64) | s.energy0[0]);
      require(std::fabs(E - E0) <= 1e-6 * E0, "lattice snapshot: energy0 is not the sum |v|^2 of v (1e-6 relative)");
    }
    for (const auto& e : s.groups) {
      require(e.index >= 1 && e.index <= s.collisions && e.members.size() >= 2 && e.drawer >= 0 &&
                  static_cast<std::size_t>(e.drawer) < s.x.size(),
              "lattice snapshot: a group entry out of range");
      require(e.pre_v.empty() || e.pre_v.size() == e.members.size(),
              "lattice snapshot: a group entry needs one pre velocity per member (or none: a bounce)");
      for (int m : e.members) require(m >= 0 && static_cast<std::size_t>(m) < s.x.size(), "lattice snapshot: a group member out of range");
      for (const Vec& w : e.pre_v)
        for (std::size_t k = 0; k < D; ++k)
          require(w[k] >= -s.units.vmax && w[k] <= s.units.vmax, "lattice snapshot: a group entry's pre velocity is faster than vmax");
    }
    require(s.origin <= s.clock && tick_limit / 2 > s.clock && s.origin > -tick_limit / 2,
            "lattice snapshot: origin <= clock within +-2^60 required");
    check_operator(s.units);
    load(s);
    observer_.reset();  // another state: an observation of the old one ends
    obs_ = nullptr;
  }

  /// Runs forward until `collisions` more collisions (clock = the last one's tick) or up to tick
  /// `until` (clock = until), whichever comes first. Returns the collisions done.
  std::uint64_t run(std::uint64_t collisions, std::int64_t until, const std::function<bool()>& poll = {}) {
    require(until >= clock_, "lattice run: the end tick is before the clock");
    require(until < tick_limit, "lattice run: the end tick is beyond the tick limit 2^61");
    if (collisions == 0) return 0;
    // an engine error mid-run leaves the state as it was: an undo journal of the particles the
    // run changes (O(changes), so that run(collisions=1) stays O(1) at any N)
    begin_undo();
    try {
      const std::uint64_t done = loop(collisions, until, false, 0, poll);
      if (obs_) obs_->sync(time_of(clock_));
      return done;
    } catch (...) {
      undo();
      // the observer has seen events the undo took back: the observation ends, discarded
      observer_.reset();
      obs_ = nullptr;
      throw;
    }
  }
  /// Runs back to collision count `to_collisions` (the state the forward run had right after it,
  /// clock = its tick) or to tick `to_tick` (clock = to_tick), whichever comes first in reverse.
  void run_back(std::uint64_t to_collisions, std::int64_t to_tick, const std::function<bool()>& poll = {}) {
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

  /// The state (forward frame, positions at the clock).
  Snapshot snapshot() const {
    Snapshot s;
    s.units = u_;
    s.seed = seed_;
    s.clock = clock_;
    s.origin = origin_;
    s.collisions = ncoll_;
    s.x = positions();
    s.v = velocities();
    s.streams = ctr_;
    s.bits = X_.words();
    s.log.assign(log_.begin(), log_.end());
    for (const auto& [k, g] : groups_) s.groups.push_back(GroupEntry{k, g.drawer, g.members, g.pre_v});
    s.energy0 = energy0_;
    s.momentum0 = momentum0_;
    s.counters = cnt_;
    return s;
  }
  /// Starts observing the forward run from the clock (replacing any earlier observation):
  /// the float engine's observer (revcol/engine/observe.hpp) fed at every velocity change
  /// with the exact state converted once to float units (x length_unit, ticks x tick), the
  /// positions the engine gives (its *_at hooks: a lattice event moves centres by up to a
  /// tick's travel). Observation is forward only: run_back ends it; restore discards it.
  void observe(const engine::ObserveConfig& c) {
    const std::size_t n = ln_.size();
    std::vector<double> x(n * D), v(n * D);
    for (std::size_t p = 0; p < n; ++p) {
      const Vec xp = pos(static_cast<int>(p), clock_);
      for (std::size_t k = 0; k < D; ++k) {
        x[p * D + k] = to_length(xp[k]);
        v[p * D + k] = to_speed(ln_[p].v[k]);
      }
    }
    std::array<double, 3> box{};
    std::array<bool, 3> walls{};
    for (std::size_t k = 0; k < D; ++k) {
      box[k] = to_length(u_.L[k]);
      walls[k] = u_.wall[k];
    }
    observer_ = std::make_unique<engine::Observer>(c, static_cast<int>(D), x, v, time_of(clock_), box, walls,
                                                   to_length(u_.sigma));
    obs_ = observer_.get();
  }
  /// The running or last observation (null before observe()).
  const engine::Observer* observer() const noexcept { return observer_.get(); }
  /// Whether an observation is running.
  bool observing() const noexcept { return obs_ != nullptr; }
  /// Ends the observation at the clock; observer() still reads it.
  void stop_observing() {
    if (obs_) obs_->sync(time_of(clock_));
    obs_ = nullptr;
  }
  /// A tick as float time (the observer's clock).
  double time_of(std::int64_t tick) const noexcept { return static_cast<double>(tick) * u_.tick; }
  /// Lattice units as a float length.
  double to_length(std::int64_t x) const noexcept { return static_cast<double>(x) * u_.length_unit; }
  /// Lattice units per tick as a float speed.
  double to_speed(std::int64_t v) const noexcept { return static_cast<double>(v) * (u_.length_unit / u_.tick); }

  /// Positions at the clock, wrapped.
  std::vector<Vec> positions() const {
    std::vector<Vec> out(ln_.size());
    for (std::size_t p = 0; p < ln_.size(); ++p) out[p] = pos(static_cast<int>(p), clock_);
    return out;
  }
  /// Velocities (a copy).
  std::vector<Vec> velocities() const {
    std::vector<Vec> out(ln_.size());
    for (std::size_t p = 0; p < ln_.size(); ++p) out[p] = ln_[p].v;
    return out;
  }
  std::int64_t clock() const noexcept { return clock_; }                ///< the current tick
  std::int64_t origin() const noexcept { return origin_; }              ///< the initial tick
  std::uint64_t collisions() const noexcept { return ncoll_; }          ///< collisions since the start
  const Bits& bits() const noexcept { return X_; }                      ///< the bits-back integer
  const Counters& counters() const noexcept { return cnt_; }            ///< statistics
  std::size_t log_size() const noexcept { return log_.size(); }         ///< rare-log entries held (redraws)
  std::size_t group_log_size() const noexcept { return groups_.size(); }  ///< group collisions held in the log
  const Units& units() const noexcept { return u_; }                    ///< units and box
  std::size_t size() const noexcept { return ln_.size(); }               ///< N
  std::uint32_t seed() const noexcept { return seed_; }                 ///< stream seed
  const std::vector<std::uint64_t>& streams() const noexcept { return ctr_; }  ///< stream counters
  const Op& op() const noexcept { return op_; }                         ///< the pair operator
  /// Redraws tried before a collision is resolved as a group bounce (group_bounce); -1 (tests
  /// only) resolves every collision so.
  int max_redraws = 256;
  /// When false (tests only), every group collision bounces back instead of resolving.
  bool group_resolve = true;
  /// Tests only: when nonzero, applying collision index k (forward: the k-th; reverse: undoing
  /// the k-th) throws, to check that an engine error leaves the state as it was.
  std::uint64_t throw_at_collision = 0;
  /// When set, every forward collision appends (tick, i, j), i < j (tests, studies).
  std::vector<std::array<std::int64_t, 3>>* trace = nullptr;
  /// When set, every forward velocity change (pair, wall, group) is appended (tests, studies).
  std::vector<EventRecordN<D>>* events = nullptr;
  /// Tests only: every candidate pair of a prediction goes to the exact search (no double
  /// filter); the events, hence the state and the bits, must be the same.
  bool exhaustive_search = false;
  /// The neighbour search: s = 0 scans the 3^D cells of the cell grid at each prediction; s > 0
  /// keeps neighbour lists with a shell of s sigma (balls of radius s sigma / 2 about the list
  /// centres, neighbour_lists.hpp), 0.02 <= s <= 2; s < 0 (the default) chooses: lists in 3D with
  /// auto_list_shell(), cells in 2D. Either search finds the same collisions: the state, the
  /// trace and the bits are the same; only the speed and the neutral-event counts differ.
  void set_list_shell(double s) {
    require(std::isfinite(s) && (s <= 0.0 || (s >= 0.02 && s <= 2.0)), "lattice: the list shell must be 0 (cells), negative (automatic) or in [0.02, 2] diameters");
    list_shell_ = s;
    rebuild();
  }
  /// The search in use: 0 the cell grid, 1 lists (the relative vector imaged per pair: a
  /// periodic axis shorter than about 2 (R + 2 h)), 2 lists with the centre offsets.
  int neighbour_search() const noexcept { return lists_ ? (direct_ ? 2 : 1) : 0; }
  /// The shell in use, in diameters (0: the cell grid).
  double list_shell() const noexcept { return lists_ ? 2.0 * static_cast<double>(nl_.radius()) / static_cast<double>(u_.sigma) : 0.0; }
  /// The automatic shell for this gas, in diameters (0: cells; see set_list_shell).
  double auto_list_shell() const noexcept {
    if constexpr (D == 2) {
      return 0.0;
    } else {
      double vol = 1.0;
      for (std::size_t k = 0; k < D; ++k) vol *= static_cast<double>(u_.L[k]) / static_cast<double>(u_.sigma);
      const double phi = static_cast<double>(ln_.size()) * (std::numbers::pi / 6.0) / vol;
      // Enskog mean free path in diameters; the shell grows with it (docs/lattice.md, measured)
      const double g = (1.0 - 0.5 * phi) / ((1.0 - phi) * (1.0 - phi) * (1.0 - phi));
      const double lam = phi > 0.0 ? 1.0 / (6.0 * std::numbers::sqrt2 * phi * g) : 1e9;
      return std::clamp(kShellBase + kShellSlope * lam, kShellMin, kShellMax);
    }
  }
  /// Bytes held by the engine's arrays, queue, grid and log.
  std::size_t memory_bytes() const noexcept {
    const std::size_t n = ln_.size();
    return n * (2 * sizeof(Vec) + 4 * 8 + 3 * 8 + 8 + sizeof(Vec) * 2 + 8) + queue_.memory_bytes() + grid_.memory_bytes() + nl_.memory_bytes() +
           log_.size() * 48 + group_bytes() + X_.words().size() * 8 + undo_.capacity() * sizeof(Saved) +
           undo_epoch_.capacity() * sizeof(std::uint32_t);
  }
  /// Bytes held by the group entries of the rare log (map node, members, pre velocities).
  std::size_t group_bytes() const noexcept {
    std::size_t b = 0;
    for (const auto& [k, g] : groups_) b += 80 + g.members.size() * sizeof(int) + g.pre_v.size() * sizeof(Vec);
    return b;
  }
  /// Momentum sum v per axis, 128 bits.
  static std::array<i128, D> momentum_of(const std::vector<Vec>& v) noexcept {
    std::array<i128, D> p{};
    for (const Vec& a : v)
      for (std::size_t k = 0; k < D; ++k) p[k] += a[k];
    return p;
  }
  /// Initial energy (sum |v|^2) and momentum, as recorded at construction.
  u128 energy0() const noexcept { return (static_cast<u128>(energy0_[1]) << 64) | energy0_[0]; }
  /// Initial momentum along axis k.
  i128 momentum0(int k) const noexcept {
    return static_cast<i128>((static_cast<u128>(static_cast<std::uint64_t>(momentum0_[2 * k + 1])) << 64) |
                             static_cast<std::uint64_t>(momentum0_[2 * k]));
  }

 private:
  enum Type : std::uint8_t { none = 0, cross = 1, wall = 2, coll = 3 };

  void load(const Snapshot& s) {
    u_ = s.units;
    seed_ = s.seed;
    const std::size_t n = s.x.size();
    ln_.resize(n);
    for (std::size_t p = 0; p < n; ++p) ln_[p] = Line{s.x[p], s.v[p], s.clock};
    slot_.assign(n, Slot{});
    ctr_ = s.streams;
    X_ = Bits(s.bits);
    log_.clear();
    for (const auto& e : s.log) log_[e.first] = e.second;
    groups_.clear();
    for (const auto& e : s.groups) groups_[e.index] = Group{e.drawer, e.members, e.pre_v};
    clock_ = s.clock;
    origin_ = s.origin;
    ncoll_ = s.collisions;
    energy0_ = s.energy0;
    momentum0_ = s.momentum0;
    cnt_ = s.counters;
    wall_tick_.assign(n, std::numeric_limits<std::int64_t>::min());
    pre_wall_.assign(n, Line{});
    reversed_ = false;
    sigma2_ = static_cast<u128>(u_.sigma) * static_cast<u128>(u_.sigma);
    sigma2d_ = static_cast<double>(sigma2_);
    const double far = static_cast<double>(u_.sigma) + 4.0 * static_cast<double>(u_.vmax);
    far2_ = far * far * (1.0 + 1e-9);
    for (std::size_t k = 0; k < D; ++k) {
      Ld_[k] = static_cast<double>(u_.L[k]);
      invL_[k] = 1.0 / Ld_[k];
      edge_[k] = 0.5 * Ld_[k] * (1.0 - 1e-9) - 4096.0;
    }
    for (unsigned code = 0; code < shift_.size(); ++code)
      for (std::size_t k = 0; k < D; ++k) {
        const unsigned ck = (code >> (2 * k)) & 3u;
        shift_[code][k] = ck == 1 ? Ld_[k] : ck == 2 ? -Ld_[k] : 0.0;
      }
    hlo_ = u_.sigma / 2;
    rebuild();
  }

  // ---- geometry of the lines ----
  [[gnu::always_inline]] Vec pos(int p, std::int64_t t) const noexcept {
    Vec out;
    const std::int64_t dt = t - ln_[p].ta;
    for (std::size_t k = 0; k < D; ++k) {
      std::int64_t m, y;
      // fast path (measure before changing): the displacement fits int64 and at most one wrap
      if (!__builtin_mul_overflow(ln_[p].v[k], dt, &m) && !__builtin_add_overflow(ln_[p].x[k], m, &y)) {
        if (u_.wall[k]) {
          out[k] = y;
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
      out[k] = u_.wall[k] ? static_cast<std::int64_t>(z) : wrap(z, u_.L[k]);
    }
    return out;
  }
  Vec diff(const Vec& a, const Vec& b) const noexcept {
    Vec r;
    for (std::size_t k = 0; k < D; ++k) r[k] = u_.wall[k] ? a[k] - b[k] : min_image(a[k] - b[k], u_.L[k]);
    return r;
  }
  bool overlap(const Vec& a, const Vec& b) const noexcept {
    const Vec r = diff(a, b);
    return norm2(r) < sigma2_;
  }
  std::int64_t hhi(int k) const noexcept { return u_.L[k] - hlo_; }
  // f(q) for every q that may be near p: p's neighbour list, or the particles of its 3^D cells
  template <class F>
  void near(int p, F&& f) const {
    if (lists_) nl_.for_each(p, f);
    else grid_.for_neighbours(grid_.cell_of_particle(p), f);
  }

  // ---- keys ----
  std::int32_t n32() const noexcept { return static_cast<std::int32_t>(ln_.size()); }
  std::int32_t coll_kind(int a, int b) const noexcept {
    const int lo = std::min(a, b);
    return reversed_ ? 1 + (n32() - 1 - lo) : 2 + lo;
  }
  std::int32_t wall_kind() const noexcept { return reversed_ ? n32() + 1 : 1; }

  // ---- prediction ----
  void reanchor(int p, std::int64_t t) {
    ln_[p].x = pos(p, t);
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
  void schedule(int p, Type type, std::int64_t t, std::int32_t kind, int partner) {
    Slot& b = slot_[static_cast<std::size_t>(p)];
    b.type = type;
    b.partner = partner;
    b.vself = b.ver;
    b.vpart = partner >= 0 ? slot_[static_cast<std::size_t>(partner)].ver : 0;
    if (type == none) queue_.erase(p); else queue_.set(p, t, kind);
  }
  void predict(int p, std::int64_t lo) {
    reanchor(p, lo);
    constexpr std::int64_t inf = std::numeric_limits<std::int64_t>::max();
    std::int64_t bt = inf;
    std::int32_t bk = 0;
    Type btype = none;
    int bq = -1;
    auto offer = [&](std::int64_t t, std::int32_t k, Type ty, int q) {
      if (t >= tick_limit) return;
      if (std::tie(t, k, q) < std::tie(bt, bk, bq) || btype == none) {
        bt = t, bk = k, btype = ty, bq = q;
      }
    };
    std::array<int, D> c{};
    if (lists_) {  // the renewal: when the line leaves the ball about p's list centre
      const std::int64_t dt = nl_.exit_ticks(p, ln_[p].x, ln_[p].v);
      if (dt > 0) offer(lo + dt, 0, cross, -1);
    } else {
      c = grid_.coords(grid_.cell_of_particle(p));
    }
    for (std::size_t k = 0; k < D; ++k) {
      if (!lists_) {
        const std::int64_t dt = grid_.exit_ticks(static_cast<int>(k), c[k], ln_[p].x[k], ln_[p].v[k]);
        if (dt > 0) offer(lo + dt, 0, cross, -1);
      }
      if (u_.wall[k]) {
        const std::int64_t dw = wall_ticks(ln_[p].x[k], ln_[p].v[k], hlo_, hhi(static_cast<int>(k)));
        if (dw >= 0) offer(lo + dw, wall_kind(), wall, -1);
      }
    }
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
    double tb = btype != none ? static_cast<double>(bt - lo) : never;  // the best so far, ticks from lo
    auto exact = [&](int q, double guess) {
      const Vec r = diff(lp.x, pos(q, lo));
      std::int64_t tau;
      if constexpr (D == 3) {
        tau = first_overlap(r, sub(lp.v, ln_[q].v), sigma2_, guess);
      } else {
        (void)guess;
        tau = first_overlap(r, sub(lp.v, ln_[q].v), sigma2_);
      }
      if (tau >= 0) {
        offer(lo + tau, coll_kind(p, q), coll, q);
        tb = static_cast<double>(bt - lo);
      }
    };
    // the filter's tests on r, w (doubles): true when the pair surely has no overlap tick <= t
    auto beyond = [&](double rr, double bb, double aa, double t) {
      // never inside: the smallest |r + w t|^2 over t >= 0 (rr - bb^2 / aa when approaching, here
      // times aa: no division on the loop's path; its rounding, ~4u rr aa by Cauchy-Schwarz, is far
      // inside the margin) is beyond sigma^2
      const double lim = sigma2d_ + 1e-6 * (rr + sigma2d_);
      if (bb >= 0.0 ? rr > lim : rr * aa - bb * bb > lim * aa) return true;
      // not up to t: f(t) = |r + w t|^2 is still falling at t and outside there
      return t != never && -bb >= aa * t && rr + t * (2.0 * bb + aa * t) > sigma2d_ + 1e-6 * (rr + aa * t * t + sigma2d_);
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
          const double r = ((dp.a[k] - dq.a[k]) - sh[k]) - dq.v[k] * dtq;
          const double w = dp.v[k] - dq.v[k];
          rr += r * r;
          bb += r * w;
          aa += w * w;
        }
        if (beyond(rr, bb, aa, tb)) continue;
        // the entry root of aa t^2 + 2 bb t + rr - sigma^2 from these doubles: first_overlap's
        // first guess (its exact predicates decide; any guess gives the same answer)
        const double c0 = rr - sigma2d_;
        exact(q, c0 / (std::sqrt(std::max(0.0, bb * bb - aa * c0)) - bb));
      }
    } else {
      std::array<double, D> xp{};
      for (std::size_t k = 0; k < D; ++k) xp[k] = static_cast<double>(lp.x[k]);
      near(p, [&](int q) {
        if (q == p) return;
        const Line& lq = ln_[q];
        if (!exhaustive_search) {
          const double dtq = static_cast<double>(lo - lq.ta);
          double rr = 0.0, bb = 0.0, aa = 0.0;
          bool edge = false;
          for (std::size_t k = 0; k < D; ++k) {
            double r = (xp[k] - static_cast<double>(lq.x[k])) - static_cast<double>(lq.v[k]) * dtq;
            if (!u_.wall[k]) {  // the nearest image (an inline rounding: libm's is a call)
              const double m = r * invL_[k];
              r -= Ld_[k] * static_cast<double>(static_cast<std::int64_t>(m + (m >= 0.0 ? 0.5 : -0.5)));
              edge = edge || std::fabs(r) > edge_[k];
            }
            const double w = static_cast<double>(lp.v[k] - lq.v[k]);
            rr += r * r;
            bb += r * w;
            aa += w * w;
          }
          if (!edge && beyond(rr, bb, aa, tb)) return;
        }
        exact(q, std::numeric_limits<double>::quiet_NaN());
      });
    }
    schedule(p, btype, bt, bk, bq);
    if (btype == coll) {  // write it into the partner's slot when before the event there
      // in offer's order (tick, kind, other particle): with (tick, kind) alone, a tie (two pairs of
      // one particle at one tick and one kind, i.e. the same lower index) went to whichever
      // prediction wrote the slot first, so the search's neutral events (crossings or renewals,
      // which re-predict) could choose the partner; measured once in 6.6 x 10^6 collisions
      const Slot& sq = slot_[static_cast<std::size_t>(bq)];
      if (!queue_.scheduled(bq) ||
          std::tie(bt, bk, p) < std::tuple<std::int64_t, std::int32_t, int>(queue_.time(bq), queue_.kind(bq), sq.partner)) {
        schedule(bq, coll, bt, bk, p);
      }
    }
  }
  void rebuild() {
    const std::size_t n = ln_.size();
    slot_.resize(n);
    for (Slot& b : slot_) {
      b.type = none;
      b.partner = -1;
      b.vself = b.vpart = 0;
    }
    for (std::size_t p = 0; p < n; ++p) {
      ln_[p].x = pos(static_cast<int>(p), clock_);
      ln_[p].ta = clock_;
    }
    const double shell = list_shell_ < 0.0 ? auto_list_shell() : list_shell_;
    lists_ = shell > 0.0;
    grid_ = CellGridN<D>{};
    nl_ = NeighbourListsN<D>{};
    direct_ = false;
    if (lists_) {
      const double h = std::max(1.0, std::round(0.5 * shell * static_cast<double>(u_.sigma)));
      std::vector<Vec> centres(n);
      for (std::size_t p = 0; p < n; ++p) centres[p] = ln_[p].x;
      nl_.build(u_, static_cast<std::int64_t>(std::min(h, static_cast<double>(u_.sigma))), centres);
      // the prediction takes r from the centre offsets when no periodic axis is short enough
      // for a relative vector (< R + 2 h + 4 vmax) to reach half the box
      direct_ = true;
      for (std::size_t k = 0; k < D; ++k)
        if (!u_.wall[k] && u_.L[k] / 2 - 4096 <= nl_.reach() + 2 * nl_.radius() + 4 * u_.vmax) direct_ = false;
    } else {
      grid_.build(u_, n);
      for (std::size_t p = 0; p < n; ++p) grid_.insert(static_cast<int>(p), grid_.cell_id(ln_[p].x));
    }
    lnd_.resize(n);
    for (std::size_t p = 0; p < n; ++p) sync(static_cast<int>(p));
    // first bucket width: ~2^tick_bits ticks per mean free time per particle, over N particles
    // (the queue adapts it; a speed setting only)
    queue_.reset(n, clock_, std::max<std::int64_t>(1, (std::int64_t{1} << u_.tick_bits) / static_cast<std::int64_t>(n)));
    // forward: events at the clock may still be pending (a run stopped after a collision);
    // reverse: the clock's tick is done (see run_back), the search starts one tick later
    const std::int64_t lo = reversed_ ? clock_ + 1 : clock_;
    for (std::size_t p = 0; p < n; ++p) predict(static_cast<int>(p), lo);
    last_key_ = {std::numeric_limits<std::int64_t>::min(), 0};
  }
  void flip() {
    for (Line& l : ln_) {
      l.v = neg(l.v);
      l.ta = -l.ta;
    }
    clock_ = -clock_;
    for (auto& t : wall_tick_) t = std::numeric_limits<std::int64_t>::min();
    reversed_ = !reversed_;
    rebuild();
  }

  // ---- the loop ----
  bool valid(int p) const noexcept {
    const Slot& b = slot_[static_cast<std::size_t>(p)];
    if (b.ver != b.vself) return false;
    return b.type != coll || slot_[static_cast<std::size_t>(b.partner)].ver == b.vpart;
  }
  void check_order(std::int64_t t, std::int32_t k) {
    if (std::make_pair(t, k) < last_key_)
      throw std::logic_error("lattice engine: events out of order (a bug): (tick " + std::to_string(t) + ", kind " +
                             std::to_string(k) + ") after (tick " + std::to_string(last_key_.first) + ", kind " +
                             std::to_string(last_key_.second) + "), collision " + std::to_string(ncoll_));
    last_key_ = {t, k};
  }
  std::uint64_t loop(std::uint64_t want, std::int64_t until, bool back, std::uint64_t target,
                     const std::function<bool()>& poll) {
    std::uint64_t done = 0;
    std::uint32_t since_poll = 0;
    for (;;) {
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
      ++cnt_.events;
      if (!valid(p)) {
        ++cnt_.stale;
        predict(p, t);
        continue;
      }
      const Slot& sp = slot_[static_cast<std::size_t>(p)];
      if (sp.type == cross) {
        ++cnt_.crossings;
        if (lists_) nl_.renew(p, pos(p, t));
        predict(p, t);
        continue;
      }
      check_order(t, queue_.kind(p));
      if (sp.type == wall) {
        reflect(p, t);
        continue;
      }
      const int i = std::min(p, sp.partner), j = std::max(p, sp.partner);
      if (throw_at_collision != 0 && (back ? ncoll_ : ncoll_ + 1) == throw_at_collision)
        throw std::runtime_error("lattice engine: test hook at collision " + std::to_string(throw_at_collision));
      if (back) {
        if (ncoll_ == target) {
          clock_ = t - 1;
          return done;
        }
        collide_back(i, j, t);
      } else {
        collide_forward(i, j, t);
      }
      ++done;
      if (!back && done == want) {
        clock_ = t;
        return done;
      }
    }
  }

  // ---- walls ----
  void reflect(int p, std::int64_t a) {
    journal(p);
    Vec x = pos(p, a - 1), v = ln_[p].v;
    Vec old_line_at_a = pos(p, a);
    unsigned axes = 0;  // the walls it meets
    for (std::size_t k = 0; k < D; ++k) {
      if (u_.wall[k] && wall_mirror(x[k], v[k], hlo_, hhi(static_cast<int>(k)))) axes |= 1u << k;
      else x[k] += v[k];
      if (!u_.wall[k]) x[k] = wrap(x[k], u_.L[k]);
    }
    const Vec ghost = wrapped(sub(x, v));
    near(p, [&](int q) {
      if (q == p) return;
      // the forward's guard (its reverse would meet q first); the reverse replays the forward, and
      // its ghost is the forward's pre-wall line at a, beyond the wall (right after a collision
      // undone on this tick, a body may well overlap it there)
      if (!reversed_ && overlap(ghost, pos(q, a - 1))) {
        throw std::runtime_error("lattice engine: a wall and a body within one tick that the rule cannot resolve (particle " +
                                 std::to_string(p) + ", tick " + std::to_string(a) + "); not supported yet");
      }
      if (overlap(old_line_at_a, pos(q, a))) ++cnt_.wall_body;
    });
    if (!reversed_ && (obs_ || events)) [[unlikely]] note_wall(a, p, x, v, axes);
    pre_wall_[p] = Line{pos(p, a - 1), ln_[p].v, a - 1};  // a group collision at a may take it back
    ln_[p].x = x;
    ln_[p].v = v;
    ln_[p].ta = a;
    sync(p);
    ++slot_[static_cast<std::size_t>(p)].ver;
    wall_tick_[p] = a;
    ++cnt_.walls;
    predict(p, a);
  }

  // ---- collisions ----
  // origin + d, wrapped on periodic axes (128-bit sum: no overflow whatever the box)
  Vec shifted(const Vec& origin, const Vec& d) const noexcept {
    Vec o;
    for (std::size_t k = 0; k < D; ++k) {
      const i128 y = static_cast<i128>(origin[k]) + d[k];
      o[k] = u_.wall[k] ? static_cast<std::int64_t>(y) : wrap(y, u_.L[k]);
    }
    return o;
  }
  Vec wrapped(const Vec& x) const noexcept {
    Vec o = x;
    for (std::size_t k = 0; k < D; ++k)
      if (!u_.wall[k]) o[k] = wrap(x[k], u_.L[k]);
    return o;
  }
  // why the candidate post state (positions at a, velocities) of i, j must be redrawn; 0 if none.
  // The same scan flags `multi` when a pre line (pre_a: i's and j's pre lines at tick a) overlaps
  // a third body at a: complete whenever 0 is returned (every neighbour was looked at).
  int post_reason(int i, int j, const Vec& xi, const Vec& xj, const Vec& vi, const Vec& vj, std::int64_t a,
                  const Vec (&pre_a)[2], bool& multi) const {
    for (std::size_t k = 0; k < D; ++k) {
      for (const Vec* vv : {&vi, &vj})
        if ((*vv)[k] > u_.vmax || (*vv)[k] < -u_.vmax) return redraw_outside;
      if (!u_.wall[k]) continue;
      for (const Vec* xx : {&xi, &xj})
        if ((*xx)[k] < hlo_ || (*xx)[k] > hhi(static_cast<int>(k))) return redraw_outside;
    }
    int why = 0;
    multi = false;
    for (int s = 0; s < 2 && why == 0; ++s) {
      const Vec& x = s == 0 ? xi : xj;
      const Vec& v = s == 0 ? vi : vj;
      const Vec ghost = wrapped(sub(x, v));
      auto third = [&](int q) {
        if (why != 0 || q == i || q == j) return;
        const Vec qa = pos(q, a);
        // exit (measure before changing): farther than sigma + 4 vmax, none of the three can hold
        // (the ghost and the pre point are within 2 vmax of x, q moves at most vmax per tick)
        const Vec d = diff(x, qa);
        double dd = static_cast<double>(d[0]) * d[0];
        for (std::size_t k = 1; k < D; ++k) dd += static_cast<double>(d[k]) * d[k];
        if (dd > far2_) return;
        if (overlap(x, qa)) why = redraw_overlap_after;
        else if (overlap(ghost, wrapped(sub(qa, ln_[q].v)))) why = redraw_ghost_tie;
        if (overlap(pre_a[s], qa)) multi = true;  // complete: pre_a[s] is within 2 vmax of x
      };
      if (direct_) {  // the owner's list (x is within 2 vmax of its line), far ones dropped in double
        const int o = s == 0 ? i : j;
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
            const double r = ((ax[k] - dq.a[k]) - sh[k]) - dq.v[k] * dt;
            dd += r * r;
          }
          if (dd <= far2_ * (1.0 + 1e-6)) third(ids[e]);
        }
      } else if (lists_) {
        nl_.for_each(s == 0 ? i : j, third);
      } else {
        grid_.for_neighbours(grid_.cell_id(x), third);
      }
    }
    return why;
  }
  void apply(int i, int j, const Vec& xi, const Vec& xj, const Vec& vi, const Vec& vj, std::int64_t a) {
    ln_[i].x = xi;
    ln_[j].x = xj;
    ln_[i].v = vi;
    ln_[j].v = vj;
    ln_[i].ta = ln_[j].ta = a;
    sync(i);
    sync(j);
    ++slot_[static_cast<std::size_t>(i)].ver;
    ++slot_[static_cast<std::size_t>(j)].ver;
    ++cnt_.collisions;
    predict(i, a);
    predict(j, a);
  }
  void collide_forward(int i, int j, std::int64_t a) {
    journal(i);
    journal(j);
    if (wall_tick_[i] == a || wall_tick_[j] == a) ++cnt_.wall_body;
    const Vec pre_a[2] = {pos(i, a), pos(j, a)};
    bool multi = false;
    const std::uint64_t ctr0 = ctr_[i];
    std::array<std::uint64_t, 8> reasons{};
    // the operator runs in coordinates centred on x_j (it is translation equivariant), so its
    // values stay within a few sigma of 0 whatever the box
    const Vec xj = pos(j, a - 1), xi = diff(pos(i, a - 1), xj), zero{};
    Vec xi2, xj2, vi2, vj2;
    Bits out;
    std::uint32_t redraws = 0;
    for (;;) {
      if (static_cast<std::int64_t>(redraws) > max_redraws) {
        group_collide(i, j, a, ctr0, reasons);
        return;
      }
      const std::uint64_t g = draw48(static_cast<std::uint32_t>(i), seed_, ctr_[i]++);
      const auto rf = op_.pair_forward(xi, zero, ln_[i].v, ln_[j].v, g, X_, xi2, xj2, vi2, vj2, out);
      int why = static_cast<int>(rf);
      if (why == 0) {
        xi2 = shifted(xj, xi2);
        xj2 = shifted(xj, xj2);
        why = post_reason(i, j, xi2, xj2, vi2, vj2, a, pre_a, multi);
      }
      if (why == 0) break;
      ++cnt_.redraws[std::min(why, 7)];
      ++reasons[std::min(why, 7)];
      ++redraws;
    }
    if (multi) ++cnt_.multi_body;
    if (redraws > 0) {
      log_[ncoll_ + 1] = redraws;
      ++cnt_.log_entries;
    }
    X_ = std::move(out);
    ++ncoll_;
    if (trace != nullptr) trace->push_back({a, i, j});
    if (obs_ || events) [[unlikely]] note_pair(a, i, j, xi2, xj2, vi2, vj2);
    apply(i, j, xi2, xj2, vi2, vj2, a);
  }
  void collide_back(int i, int j, std::int64_t a) {
    if (const auto g = groups_.find(ncoll_); g != groups_.end()) {
      group_back(i, j, a, g);
      return;
    }
    const Vec xj = pos(j, a - 1), xi = diff(pos(i, a - 1), xj), zero{};
    std::uint32_t redraws = 0;
    const auto it = log_.find(ncoll_);
    if (it != log_.end()) redraws = it->second;
    if (ctr_[i] < 1 + static_cast<std::uint64_t>(redraws)) throw std::logic_error("lattice engine: a stream would step back past draw 0 (a bug)");
    const std::uint64_t g = draw48(static_cast<std::uint32_t>(i), seed_, ctr_[i] - 1);
    Vec xi0, xj0, vi0, vj0;
    op_.pair_reverse(xi, zero, neg(ln_[i].v), neg(ln_[j].v), g, X_, xi0, xj0, vi0, vj0);
    xi0 = shifted(xj, xi0);
    xj0 = shifted(xj, xj0);
    ctr_[i] -= 1 + redraws;
    if (it != log_.end()) log_.erase(it);
    --ncoll_;
    apply(i, j, xi0, xj0, neg(vi0), neg(vj0), a);
  }

  // ---- a third body within one tick: group collisions (LATTICE.md §4, docs/lattice.md) ----
  // When no draw is acceptable (a third body k is met within the tick, so every post state of the
  // pair overlaps it or ties with it), the group G = {i, j}, closed under "a member's pre line
  // overlaps a body at tick a", collides as one. Every member stays at its tick a-1 position at
  // tick a (a stall of one tick), so the members' positions at a never overlap each other.
  //   Resolve (first choice): the members' velocities go through sequential specular collisions
  //   of the touching pairs (normal along the centres at a-1) until no touching pair approaches,
  //   rounded to integers with the momentum kept exactly; the exact pre velocities go to the log.
  //   For one pair this is the specular collision, and its reversed lines overlap at a-1 exactly
  //   where the pre lines did at a, so the reverse meets the group at the same tick.
  //   Bounce (fallback): every member's velocity negated (an involution: nothing but the members
  //   is logged); the group's momentum is reversed.
  // Either way a body that the post state would overlap at a, or whose point at a-1 the new lines
  // would overlap, joins G (up to 16 members); a resolve whose reversed lines meet no member pair
  // at a-1 (the reverse would not see it) or that breaks vmax falls back to the bounce. The post
  // state must meet the invariants against bodies outside G and the walls, otherwise the collision
  // is an error, nothing changed. The draws tried are logged with the entry.
  // The group closed under "a member's pre line at a overlaps a body at a", ascending.
  std::vector<int> group_of(int i, int j, std::int64_t a) const {
    std::vector<int> g{i, j};
    auto member = [&](int q) { return std::find(g.begin(), g.end(), q) != g.end(); };
    for (std::size_t m = 0; m < g.size(); ++m) {
      const Vec xa = pos(g[m], a);
      near(g[m], [&](int q) {
        if (!member(q) && overlap(xa, pos(q, a))) g.push_back(q);
      });
    }
    return g;
  }
  // Post velocities of a resolve for the members g (positions at a-1: x): sequential specular
  // collisions of the pairs whose pre lines overlap at a, then integer rounding with the sum kept.
  std::vector<Vec> resolve_velocities(const std::vector<int>& g, const std::vector<Vec>& x, std::int64_t a) const {
    using VecD = std::array<double, D>;
    // a . b, summed from the first axis on (the 2D engine's order)
    auto ddot = [](const VecD& p, const VecD& q) {
      double s = p[0] * q[0];
      for (std::size_t k = 1; k < D; ++k) s += p[k] * q[k];
      return s;
    };
    const std::size_t n = g.size();
    std::vector<VecD> v(n);
    for (std::size_t m = 0; m < n; ++m)
      for (std::size_t k = 0; k < D; ++k) v[m][k] = static_cast<double>(ln_[g[m]].v[k]);
    struct Touch {
      std::size_t p, q;
      VecD n;
    };
    std::vector<Touch> touch;
    for (std::size_t p = 0; p < n; ++p)
      for (std::size_t q = p + 1; q < n; ++q) {
        const Vec r = diff(x[p], x[q]);
        VecD rd, w;
        for (std::size_t k = 0; k < D; ++k) {
          rd[k] = static_cast<double>(r[k]);
          w[k] = v[p][k] - v[q][k];
        }
        const double len = std::sqrt(ddot(rd, rd));
        // touching: the pre lines overlap at a, or the pair is within one tick's relative travel at a-1
        const bool near = len < static_cast<double>(u_.sigma) + std::sqrt(ddot(w, w));
        if (len > 0.0 && (near || overlap(pos(g[p], a), pos(g[q], a)))) {
          for (std::size_t k = 0; k < D; ++k) rd[k] /= len;
          touch.push_back({p, q, rd});
        }
      }
    // a wall is met within the tick by a member whose line is beyond it at a: -1 lower, +1 upper
    std::vector<std::array<int, D>> wall(n, std::array<int, D>{});
    for (std::size_t m = 0; m < n; ++m) {
      const Vec xa = pos(g[m], a);
      for (std::size_t k = 0; k < D; ++k)
        if (u_.wall[k]) wall[m][k] = xa[k] < hlo_ ? -1 : xa[k] > hhi(static_cast<int>(k)) ? 1 : 0;
    }
    const double eps = 1e-12 * static_cast<double>(u_.vmax);
    for (int sweep = 0; sweep < 64; ++sweep) {
      bool any = false;
      for (std::size_t m = 0; m < n; ++m)
        for (std::size_t k = 0; k < D; ++k)
          if (wall[m][k] * v[m][k] > 0.0) {  // approaching a wall it meets: specular, exact
            v[m][k] = -v[m][k];
            any = true;
          }
      for (const Touch& t : touch) {
        VecD w;
        for (std::size_t k = 0; k < D; ++k) w[k] = v[t.p][k] - v[t.q][k];
        const double wn = ddot(w, t.n);
        if (wn >= -eps) continue;  // not approaching along the normal
        for (std::size_t k = 0; k < D; ++k) {
          v[t.p][k] = v[t.p][k] - wn * t.n[k];
          v[t.q][k] = v[t.q][k] + wn * t.n[k];
        }
        any = true;
      }
      if (!any) break;
    }
    std::vector<Vec> out(n);
    for (std::size_t k = 0; k < D; ++k) {
      i128 before = 0, after = 0;
      std::size_t big = 0;
      for (std::size_t m = 0; m < n; ++m) {
        const double c = std::clamp(v[m][k], -static_cast<double>(tick_limit), static_cast<double>(tick_limit));
        out[m][k] = static_cast<std::int64_t>(std::llround(c));
        before += ln_[g[m]].v[k];
        after += out[m][k];
        if (std::abs(out[m][k]) > std::abs(out[big][k])) big = m;
      }
      out[big][k] += static_cast<std::int64_t>(before - after);  // momentum kept exactly
    }
    return out;
  }
  // The post state of a group collision: positions at a (the a-1 points) and velocities, the
  // group grown by every body the post state would meet. False when it breaks the walls, vmax,
  // the 16-member cap or (a resolve) the reverse's view of it.
  bool group_post(std::vector<int>& g, std::int64_t a, bool resolve, std::vector<Vec>& post, std::vector<Vec>& vel) const {
    auto member = [&](int q) { return std::find(g.begin(), g.end(), q) != g.end(); };
    for (;;) {
      if (g.size() > 16) return false;
      std::sort(g.begin(), g.end());
      post.assign(g.size(), Vec{});
      for (std::size_t m = 0; m < g.size(); ++m) post[m] = pos(g[m], a - 1);
      if (resolve) {
        vel = resolve_velocities(g, post, a);
      } else {
        vel.assign(g.size(), Vec{});
        for (std::size_t m = 0; m < g.size(); ++m) vel[m] = neg(ln_[g[m]].v);
      }
      bool grew = false;
      for (std::size_t m = 0; m < g.size() && !grew; ++m) {
        for (std::size_t k = 0; k < D; ++k) {
          if (vel[m][k] > u_.vmax || vel[m][k] < -u_.vmax) return false;
          if (u_.wall[k] && (post[m][k] < hlo_ || post[m][k] > hhi(static_cast<int>(k)))) return false;
        }
        const Vec ghost = wrapped(sub(post[m], vel[m]));  // the new line at a-1
        near(g[m], [&](int q) {
          if (grew || member(q)) return;
          if (overlap(post[m], pos(q, a)) || overlap(ghost, pos(q, a - 1))) {
            g.push_back(q);
            grew = true;
          }
        });
      }
      if (grew) continue;
      // the reverse must meet the group at this tick: some member pair's new lines overlap at a-1
      // (a bounce's new lines at a-1 are its pre lines at a, so it holds unless a member's line
      // was taken back from a reflection at a)
      for (std::size_t p = 0; p < g.size(); ++p)
        for (std::size_t q = p + 1; q < g.size(); ++q) {
          const Vec gp = wrapped(sub(post[p], vel[p]));
          const Vec gq = wrapped(sub(post[q], vel[q]));
          if (overlap(gp, gq)) return true;  // the reverse meets this pair at a-1
        }
      return false;
    }
  }
  void group_collide(int i, int j, std::int64_t a, std::uint64_t ctr0, const std::array<std::uint64_t, 8>& reasons) {
    // a member reflected at this very tick takes its line from before the reflection, and the
    // wall joins the group as a contact (resolve_velocities): the stall point is then a real point
    // inside the box, and the log's pre velocity is the one before the reflection
    const Line keep[2] = {ln_[i], ln_[j]};
    bool unreflected[2] = {false, false};
    for (int s = 0; s < 2; ++s) {
      const int m = s == 0 ? i : j;
      if (wall_tick_[m] == a) {
        ln_[m] = pre_wall_[m];
        unreflected[s] = true;
      }
    }
    const std::vector<int> g0 = group_of(i, j, a);
    std::vector<int> g = g0;
    std::vector<Vec> post, vel;
    bool resolve = group_resolve, ok = resolve && group_post(g, a, true, post, vel);
    if (!ok) {
      resolve = false;
      g = g0;
      ok = group_post(g, a, false, post, vel);
    }
    if (!ok) {
      ctr_[i] = ctr0;  // nothing changed
      ln_[i] = keep[0];
      ln_[j] = keep[1];
      std::string why = "lattice engine: collision " + std::to_string(ncoll_ + 1) + " of particles " +
                        std::to_string(i) + ", " + std::to_string(j) + " at tick " + std::to_string(a) +
                        " found no acceptable post state in " + std::to_string(max_redraws) +
                        " redraws, and its group of " + std::to_string(g.size()) + " can neither resolve nor bounce back (";
      for (int k = 1; k < 8; ++k) why += std::string(redraw_names[k]) + " " + std::to_string(reasons[k]) + (k < 7 ? ", " : ")");
      throw std::runtime_error(why);
    }
    std::vector<Vec> pre_v;
    for (int q : g) journal(q);
    if (resolve)
      for (int q : g) pre_v.push_back(ln_[q].v);
    ++ncoll_;
    log_[ncoll_] = static_cast<std::uint32_t>(ctr_[i] - ctr0);
    ++cnt_.log_entries;
    groups_[ncoll_] = Group{i, g, std::move(pre_v)};
    ++cnt_.multi_body;
    ++(resolve ? cnt_.group_resolves : cnt_.group_bounces);
    for (int s = 0; s < 2; ++s)
      if (unreflected[s]) {
        wall_tick_[s == 0 ? i : j] = std::numeric_limits<std::int64_t>::min();  // the group took the reflection in
        ++cnt_.wall_groups;
      }
    if (trace != nullptr) trace->push_back({a, i, j});
    if (obs_ || events) [[unlikely]] note_group(a, g, post, vel);
    for (std::size_t m = 0; m < g.size(); ++m) {
      ln_[g[m]] = Line{post[m], vel[m], a};
      sync(g[m]);
      ++slot_[static_cast<std::size_t>(g[m])].ver;
    }
    ++cnt_.collisions;
    for (int q : g) predict(q, a);
  }
  template <class It>
  void group_back(int i, int j, std::int64_t a, It entry) {
    const std::vector<int> g = entry->second.members;
    if (std::find(g.begin(), g.end(), i) == g.end() || std::find(g.begin(), g.end(), j) == g.end()) {
      throw std::logic_error("lattice engine: the reverse met a group at another pair (a bug)");
    }
    const auto it = log_.find(ncoll_);
    const std::uint32_t draws = it == log_.end() ? 0 : it->second;
    const int drawer = entry->second.drawer;
    if (ctr_[drawer] < draws) throw std::logic_error("lattice engine: a stream would step back past draw 0 (a bug)");
    const std::vector<Vec>& pre_v = entry->second.pre_v;  // forward frame; empty: a bounce
    std::vector<Vec> pre(g.size());
    for (std::size_t m = 0; m < g.size(); ++m) pre[m] = pos(g[m], a - 1);
    for (std::size_t m = 0; m < g.size(); ++m) {
      Line& l = ln_[g[m]];
      const Vec v = pre_v.empty() ? neg(l.v) : neg(pre_v[m]);
      l = Line{pre[m], v, a};
      sync(g[m]);
      ++slot_[static_cast<std::size_t>(g[m])].ver;
    }
    ctr_[drawer] -= draws;
    if (it != log_.end()) log_.erase(it);
    groups_.erase(entry);
    --ncoll_;
    ++cnt_.collisions;
    for (int q : g) predict(q, a);
  }

  // ---- the observer's hooks (forward only; cold: one test per velocity change when off) ----
  // A pair and a wall go to the observer from arrays on the stack (measure before changing:
  // building vectors per event cost ~1 000 instructions); the event records (tests) are built
  // only when asked for.
  void record(int kind, std::int64_t a, const std::vector<int>& ids, const std::vector<Vec>& x,
              const std::vector<Vec>& v, unsigned axes) {
    EventRecordN<D> r{a, kind, axes, ids, x, {}, v};
    for (int q : ids) r.v_before.push_back(ln_[q].v);
    events->push_back(std::move(r));
  }
  [[gnu::noinline, gnu::cold]] void note_pair(std::int64_t a, int i, int j, const Vec& xi, const Vec& xj, const Vec& vi,
                                              const Vec& vj) {
    if (events != nullptr) record(EventRecordN<D>::pair, a, {i, j}, {xi, xj}, {vi, vj}, 0);
    if (!obs_) return;
    double x[2 * D], v[2 * D];
    for (std::size_t k = 0; k < D; ++k) {
      x[k] = to_length(xi[k]);
      x[D + k] = to_length(xj[k]);
      v[k] = to_speed(vi[k]);
      v[D + k] = to_speed(vj[k]);
    }
    obs_->pair_at(time_of(a), i, j, x, x + D, v, v + D);
  }
  [[gnu::noinline, gnu::cold]] void note_wall(std::int64_t a, int p, const Vec& xp, const Vec& vp, unsigned axes) {
    if (events != nullptr) record(EventRecordN<D>::wall, a, {p}, {xp}, {vp}, axes);
    if (!obs_) return;
    double x[D], v[D];
    for (std::size_t k = 0; k < D; ++k) {
      x[k] = to_length(xp[k]);
      v[k] = to_speed(vp[k]);
    }
    obs_->wall_at(time_of(a), p, x, v, axes);
  }
  [[gnu::noinline, gnu::cold]] void note_group(std::int64_t a, const std::vector<int>& g, const std::vector<Vec>& xg,
                                               const std::vector<Vec>& vg) {
    if (events != nullptr) record(EventRecordN<D>::group, a, g, xg, vg, 0);
    if (!obs_) return;
    const std::size_t n = g.size();
    std::vector<double> x(n * D), v(n * D);
    for (std::size_t m = 0; m < n; ++m)
      for (std::size_t k = 0; k < D; ++k) {
        // positions image-consistent about the first member's
        x[m * D + k] = to_length(m > 0 ? xg[0][k] + diff(xg[m], xg[0])[k] : xg[m][k]);
        v[m * D + k] = to_speed(vg[m][k]);
      }
    obs_->group_at(time_of(a), static_cast<int>(n), g.data(), x.data(), v.data());
  }
  std::unique_ptr<engine::Observer> observer_;  // the running or last observation (observe.hpp)
  engine::Observer* obs_ = nullptr;             // observer_ while it runs, else null

  // The operator must work in the units' lattice: the same sigma and (an operator with
  // direction cells) the same cell resolution.
  void check_operator(const Units& u) const {
    require(op_.sigma() == u.sigma, "lattice: the operator's sigma differs from the units'");
    if constexpr (requires { op_.cell_bits(); })
      require(op_.cell_bits() == u.cell_bits, "lattice: the operator's cell_bits differ from the units'");
  }
  Op op_;
  Units u_;
  std::uint32_t seed_ = 1;
  // one particle's line, together in memory (the prediction loop reads all three)
  struct Line {
    Vec x;               // anchor position (wrapped)
    Vec v;               // velocity
    std::int64_t ta;     // anchor tick
  };
  std::vector<Line> ln_;
  // the prediction's double mirror of each line (lists: the anchor unwrapped about the list
  // centre, an exact integer rounded once); sync(p) after every change of ln_[p]
  struct alignas(64) LineD {  // one cache line each (56 bytes in 3D would straddle two mostly)
    std::array<double, D> a;  // c_p + min_image(x_p - c_p) (x_p on wall axes); x_p with the cell grid
    std::array<double, D> v;  // velocity
    std::int64_t ta;          // anchor tick
  };
  std::vector<LineD> lnd_;
  // a position x (wrapped) unwrapped about p's list centre: c_p + min_image(x - c_p), in
  // (-L/2, 3L/2), as doubles (two roundings, each within 2^10 lattice units: no integer sum,
  // which could overflow a 2D box near 2^63). In exact arithmetic, two of them less the pair's
  // image shift (neighbour_lists.hpp) are the minimum-image difference of the two positions.
  std::array<double, D> unwrapped_about(int p, const Vec& x) const noexcept {
    std::array<double, D> a{};
    const Vec& c = nl_.centre(p);
    for (std::size_t k = 0; k < D; ++k)
      a[k] = u_.wall[k] ? static_cast<double>(x[k])
                        : static_cast<double>(c[k]) + static_cast<double>(min_image(x[k] - c[k], u_.L[k]));
    return a;
  }
  void sync(int p) noexcept {
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
  std::vector<std::int64_t> wall_tick_;
  std::vector<Line> pre_wall_;  // a particle's line before its reflection at wall_tick_ (that tick only)
  // ---- the forward run's undo journal (run(): an engine error restores the state) ----
  struct Saved {
    int p;
    Line line, pre_wall;
    std::uint64_t ctr;
    std::int64_t wall_tick;
  };
  std::vector<Saved> undo_;
  std::vector<std::uint32_t> undo_epoch_;  // per particle: the run() that journaled it
  std::uint32_t epoch_ = 0;
  Bits undo_X_;
  Counters undo_cnt_;
  std::int64_t undo_clock_ = 0;
  std::uint64_t undo_ncoll_ = 0;
  void begin_undo() {
    if (undo_epoch_.size() != ln_.size() || ++epoch_ == 0) {  // new size, or the epoch wrapped
      undo_epoch_.assign(ln_.size(), 0);
      epoch_ = 1;
    }
    undo_.clear();
    undo_X_ = X_;
    undo_cnt_ = cnt_;
    undo_clock_ = clock_;
    undo_ncoll_ = ncoll_;
  }
  // keeps p's state as it was when this run() began (first change only)
  void journal(int p) {
    if (undo_epoch_.empty() || undo_epoch_[p] == epoch_) return;
    undo_epoch_[p] = epoch_;
    undo_.push_back(Saved{p, ln_[p], pre_wall_[p], ctr_[p], wall_tick_[p]});
  }
  void undo() {
    for (const Saved& sv : undo_) {
      ln_[sv.p] = sv.line;
      pre_wall_[sv.p] = sv.pre_wall;
      ctr_[sv.p] = sv.ctr;
      wall_tick_[sv.p] = sv.wall_tick;
      ++slot_[static_cast<std::size_t>(sv.p)].ver;
    }
    undo_.clear();
    X_ = undo_X_;
    cnt_ = undo_cnt_;
    clock_ = undo_clock_;
    log_.erase(log_.upper_bound(undo_ncoll_), log_.end());  // the forward run only adds keys
    groups_.erase(groups_.upper_bound(undo_ncoll_), groups_.end());
    ncoll_ = undo_ncoll_;
    rebuild();
  }
  std::vector<std::uint64_t> ctr_;
  // one particle's event bookkeeping, together in memory (the loop reads it per event, and the
  // partner's version): its version (bumped at every change of its line), its scheduled event's
  // type and partner, and the versions both had when it was scheduled (stale if either moved on)
  struct alignas(32) Slot {
    std::uint64_t ver = 0, vself = 0, vpart = 0;
    int partner = -1;
    Type type = none;
  };
  std::vector<Slot> slot_;
  Bits X_;
  std::map<std::uint64_t, std::uint32_t> log_;
  struct Group {
    int drawer;                 // whose stream the tried draws came from
    std::vector<int> members;   // ascending
    std::vector<Vec> pre_v;     // exact pre velocities (a resolve) or empty (a bounce)
  };
  std::map<std::uint64_t, Group> groups_;  // collision index -> group collision
  std::int64_t clock_ = 0, origin_ = 0;
  std::uint64_t ncoll_ = 0;
  std::array<std::uint64_t, 2> energy0_{};
  std::array<std::int64_t, 2 * D> momentum0_{};
  Counters cnt_;
  bool reversed_ = false;
  // the neighbour search (set_list_shell): the cell grid of the particles, or neighbour lists
  static constexpr double kShellBase = 0.545, kShellSlope = 1.0, kShellMin = 0.6, kShellMax = 1.2;  // measured: docs/lattice.md
  double list_shell_ = -1.0;
  bool lists_ = false, direct_ = false;
  NeighbourListsN<D> nl_;
  u128 sigma2_ = 0;
  double sigma2d_ = 0.0, far2_ = 0.0;
  std::array<double, D> Ld_{}, invL_{}, edge_{};  // the prediction's filter: L, 1 / L, L / 2 less rounding
  std::array<std::array<double, D>, 1u << (2 * D)> shift_{};  // a list entry's image shift by code (neighbour_lists.hpp)
  std::int64_t hlo_ = 0;
  CellGridN<D> grid_;
  Queue queue_;
  std::pair<std::int64_t, std::int32_t> last_key_{};
};

}  // namespace revcol::lattice
