// The lattice engine's state as data: the snapshot that defines it bit for bit (SnapshotN, with
// its field list for checkpoints), the rare log's group entries, the counters of events and
// rare cases, and the records of forward velocity changes that tests and studies ask for
// (BasicEngine, lattice/engine_core.hpp, produces and consumes them).
#pragma once
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "revcol/collide/common.hpp"
#include "revcol/lattice/geometry.hpp"
#include "revcol/lattice/units.hpp"
#include "revcol/visitable.hpp"

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
/// How a rollback restores what the undone events changed (BasicEngine::keep_journal): by reverse
/// computation (nothing of the state saved: the paper's RC), or by state saving, the paper's two
/// variants on a per-particle engine: SS1 saves each touched particle's whole record before
/// every event (line, stream counter, X, count, wall cache), SS2 only what the event changes
/// and no counter can give back (the touched lines and the drawer's X; the counters step back).
enum class Rollback : std::uint8_t { reverse = 0, save_all = 1, save_changes = 2 };

struct Counters : Visitable<Counters> {
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
  std::uint64_t backscatters = 0;        ///< specular mode: pairs turned back in place (specular.hpp; forward)
  std::uint64_t drawn_fallbacks = 0;     ///< specular mode: refused post states drawn by the randomized operator (logged)
  /// A field: the momentum the walls of its axis gave the gas, sum |v_after - v_before| over the
  /// reflections there, net of those run back (lattice units per tick, 128 bits each: lower
  /// wall low and high word, upper wall low and high word). Over a run in steady state, the
  /// lower wall's less the upper's is the weight N |g| times the ticks run.
  std::array<std::uint64_t, 4> field_wall_impulse{};

  /// Calls f(name, count) for every counter, with the names of the diagnostics (redraws: the
  /// array by RedrawReason, index 0 unused).
  template <class S, class F>
  static void visit_fields(S& c, F& f) {
    f("events", c.events);
    f("collisions_applied", c.collisions);
    f("walls", c.walls);
    f("crossings", c.crossings);
    f("stale", c.stale);
    f("redraws", c.redraws);
    f("log_entries_written", c.log_entries);
    f("multi_body", c.multi_body);
    f("wall_body", c.wall_body);
    f("group_resolves", c.group_resolves);
    f("group_bounces", c.group_bounces);
    f("wall_groups", c.wall_groups);
    f("backscatters", c.backscatters);
    f("drawn_fallbacks", c.drawn_fallbacks);
    f("field_wall_impulse", c.field_wall_impulse);
  }
};

/// The key of a rare-log entry: (particle, that particle's collision count right after the
/// collision). Per particle, never global: collisions in different places commute.
using LogKey = std::pair<std::uint32_t, std::uint64_t>;

/// A rare-log entry: a pair collision that redrew (or, specular mode, was drawn), keyed by its
/// drawer (the pair's lower index) and the drawer's collision count after it.
struct LogEntry {
  std::uint32_t particle = 0;  ///< the drawer
  std::uint64_t count = 0;     ///< its collision count right after the collision (>= 1)
  std::uint32_t redraws = 0;   ///< redraws before the accepted draw
  bool operator==(const LogEntry&) const = default;
};

/// A group collision in the rare log: a pair that no draw could resolve because a third body (or
/// more) is met within the same tick. Its members stay at their tick a-1 positions ("stall") and
/// either take the velocities of a specular resolution (pre_v holds their exact pre velocities,
/// so the reverse restores them) or, when that post state would break the event rule, bounce
/// back (every velocity negated, an involution: pre_v empty). Keyed by every member's
/// (member, count after), so the reverse finds it from whichever member pair it meets.
template <std::size_t D>
struct GroupEntryN {
  int drawer = 0;                     ///< whose stream the tried draws came from (a member)
  std::uint32_t draws = 0;            ///< draws tried before the group
  std::vector<int> members;           ///< ascending
  std::vector<std::uint64_t> counts;  ///< per member: its collision count right after the group
  std::vector<VecN<D>> pre_v;         ///< members' exact pre velocities (a resolve); empty: a bounce
  bool operator==(const GroupEntryN&) const = default;
};
/// A 2D group entry.
using GroupEntry = GroupEntryN<2>;

/// Everything that defines a lattice state in D dimensions, in the forward frame, positions at the clock.
template <std::size_t D>
struct SnapshotN : Visitable<SnapshotN<D>> {
  UnitsN<D> units;                             ///< units and box
  Law law = Law::flux;                         ///< the pair operator's post-direction law
  Mode mode = Mode::exact;                     ///< exact (the randomized operator) or specular (specular.hpp)
  std::uint32_t seed = 1;                      ///< Philox key {particle, seed}
  std::int64_t clock = 0;                      ///< the current tick
  std::int64_t origin = 0;                     ///< the tick of the initial state (no run back past it)
  std::uint64_t collisions = 0;                ///< collisions since the initial state
  std::vector<VecN<D>> x;                      ///< positions at the clock
  std::vector<VecN<D>> v;                      ///< velocities
  std::vector<std::uint64_t> streams;          ///< per-particle Philox counters
  std::vector<std::uint64_t> particle_collisions;  ///< per particle: its collisions since the start
  std::vector<std::uint64_t> bits;             ///< every particle's bits-back integer X in turn, 64-bit words, low first
  std::vector<std::uint64_t> bits_size;        ///< per particle: the words of its X in `bits`
  std::vector<LogEntry> log;                   ///< rare log, by (particle, count) ascending
  std::vector<GroupEntryN<D>> groups;          ///< group collisions, by (drawer, its count) ascending
  std::array<std::uint64_t, 2> energy0{};      ///< initial sum |v|^2 (128 bits: low, high word)
  std::array<std::int64_t, 2 * D> momentum0{};  ///< initial momentum per axis (128 bits: low, high)
  Counters counters;                           ///< statistics (not compared by same_state)
  std::vector<double> observer;                ///< a running observation (engine::Observer::save; empty: none)
  std::vector<std::uint64_t> observer_counts;  ///< its counts per block (not compared by same_state)
  /// Per particle (by id): its radius in lattice units, a pair's contact distance being the sum
  /// of its two radii (a mixture; equal masses). Empty: every particle of diameter units.sigma.
  std::vector<std::int64_t> radius;

  /// Calls f(name, field) for every field but `counters`, in the checkpoint format's order and
  /// with its names (log and groups are each written as several arrays by the binding).
  template <class S, class F>
  static void visit_fields(S& s, F& f) {
    f("units", s.units);
    f("law", s.law);
    f("mode", s.mode);
    f("seed", s.seed);
    f("clock", s.clock);
    f("origin", s.origin);
    f("collisions", s.collisions);
    f("x", s.x);
    f("v", s.v);
    f("streams", s.streams);
    f("particle_collisions", s.particle_collisions);
    f("bits", s.bits);
    f("bits_size", s.bits_size);
    f("log", s.log);
    f("groups", s.groups);
    f("energy0", s.energy0);
    f("momentum0", s.momentum0);
    f("observer", s.observer);
    f("observer_counts", s.observer_counts);
    f("radius", s.radius);
  }
};
/// A 2D snapshot.
using Snapshot = SnapshotN<2>;
/// A 3D snapshot.
using Snapshot3 = SnapshotN<3>;

/// True when two snapshots hold the same physical state bit for bit (everything but counters).
template <std::size_t D>
bool same_state(const SnapshotN<D>& a, const SnapshotN<D>& b) {
  const UnitsN<D> &u = a.units, &w = b.units;
  return u.S == w.S && u.sigma == w.sigma && u.L == w.L && u.wall == w.wall && u.bounce == w.bounce && u.vmax == w.vmax &&
         u.tick_bits == w.tick_bits && u.cell_bits == w.cell_bits && u.gravity == w.gravity && u.shear == w.shear &&
         a.law == b.law && a.mode == b.mode && a.seed == b.seed && a.clock == b.clock && a.origin == b.origin && a.collisions == b.collisions &&
         a.x == b.x && a.v == b.v && a.streams == b.streams && a.particle_collisions == b.particle_collisions &&
         a.bits == b.bits && a.bits_size == b.bits_size && a.log == b.log &&
         a.groups == b.groups &&
         a.energy0 == b.energy0 && a.momentum0 == b.momentum0 && a.radius == b.radius;
}

/// Particle by particle, the words of each X in a snapshot (bits split by bits_size).
template <std::size_t D>
std::vector<std::vector<std::uint64_t>> bits_per_particle(const SnapshotN<D>& s) {
  std::vector<std::vector<std::uint64_t>> out;
  std::size_t at = 0;
  for (std::uint64_t k : s.bits_size) {
    out.emplace_back(s.bits.begin() + static_cast<std::ptrdiff_t>(at), s.bits.begin() + static_cast<std::ptrdiff_t>(at + k));
    at += static_cast<std::size_t>(k);
  }
  return out;
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

}  // namespace revcol::lattice
