// The event machinery of the lattice engine, generic over the exact pair operator and, through
// it, over the dimension D = 2 or 3 (LATTICE.md §2, §4; the concrete engines are in
// lattice/engine.hpp). D is deduced from the operator's pair_forward (its vectors are VecN<D>):
// LatticePair2D gives the disk gas, LatticePair3D the sphere gas; the event search, the
// acceptance test, the redraws, the rare log, the group collisions, the counters and the
// snapshots are one code for both (per-axis loops over D; a wall is a flat plane per axis).
//
// State (per particle, each collision touching only its particles'): state.hpp.
//
// The event rule, the order within a tick, the reverse and the neighbour search: loop.hpp.
// Acceptance, redraws, the rare log: collide.hpp. Sizes (a mixture): sizes.hpp. A logical
// process's view: lp_view.hpp.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <numbers>
#include <stdexcept>
#include <string>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include "revcol/engine/event_queue.hpp"
#include "revcol/engine/logs.hpp"
#include "revcol/engine/observe.hpp"
#include "revcol/collide/common.hpp"
#include "revcol/error.hpp"
#include "revcol/visitable.hpp"
#include "revcol/lattice/cell_grid.hpp"
#include "revcol/lattice/field.hpp"
#include "revcol/lattice/geometry.hpp"
#include "revcol/lattice/lp.hpp"
#include "revcol/lattice/lp_seen.hpp"
#include "revcol/lattice/state.hpp"
#include "revcol/lattice/neighbour_lists.hpp"
#include "revcol/lattice/shear.hpp"
#include "revcol/lattice/sizes.hpp"
#include "revcol/lattice/specular.hpp"
#include "revcol/lattice/streams.hpp"
#include "revcol/lattice/units.hpp"

namespace revcol::lattice {

/// The dimension of a pair operator: that of the vectors its pair_forward takes.
template <class R, class O, std::size_t D, class... A>
constexpr std::size_t pair_dim(R (O::*)(const VecN<D>&, A...) const) noexcept { return D; }
/// The dimension an engine over Op runs in (2 or 3).
template <class Op>
inline constexpr std::size_t op_dim = pair_dim(&Op::pair_forward);

/// The lattice engine's event machinery over a pair operator Op (pair_forward / pair_reverse as
/// LatticePair2D or LatticePair3D; the dimension is the operator's) and a bits-back integer Bits.
template <class Op, class Bits, class Queue = engine::EventQueue<std::int64_t>>
class BasicEngine {
 public:
  static constexpr std::size_t D = op_dim<Op>;  ///< The dimension (2 or 3), from the operator.
  static_assert(D == 2 || D == 3, "the lattice engine runs in 2 or 3 dimensions");
  using Vec = VecN<D>;              ///< a position, velocity or relative vector
  using Units = UnitsN<D>;          ///< the units and box
  using Snapshot = SnapshotN<D>;    ///< the state
  using GroupEntry = GroupEntryN<D>;  ///< a group collision in the rare log

  /// An engine on a validated integer state at tick clock, each X from initial_bits(p, seed); mode exact
  /// (the operator Op, randomized) or specular (the map of specular.hpp: no draws, X never changes).
  BasicEngine(const Units& u, std::vector<Vec> x, std::vector<Vec> v, std::uint32_t seed, Op op,
              std::int64_t clock = 0, Mode mode = Mode::exact)
      : op_(std::move(op)) {
    load(fresh(u, std::move(x), std::move(v), seed, clock, mode));
  }
  /// A mixture (equal masses): particle p of radius radius[p] lattice units, in [sigma / 32,
  /// sigma / 2] (validate_radii; sigma = u.sigma, the largest diameter, the operator's), a
  /// pair's contact distance the sum of its radii; otherwise as above.
  BasicEngine(const Units& u, std::vector<Vec> x, std::vector<Vec> v, std::vector<std::int64_t> radius, std::uint32_t seed,
              Op op, std::int64_t clock = 0, Mode mode = Mode::exact)
      : op_(std::move(op)) {
    require(!radius.empty(), "lattice: a mixture needs one radius per particle");
    load(fresh(u, std::move(x), std::move(v), seed, clock, mode, std::move(radius)));
  }
  BasicEngine(const Snapshot& s, Op op) : op_(std::move(op)) { restore(s); }  ///< An engine resuming a snapshot bit for bit.
  /// The same, its particles stored in another order: local index p holds particle order[p] (a
  /// permutation of [0, N)); every key, draw, tie and output is by particle id (the same bits).
  BasicEngine(const Snapshot& s, Op op, const std::vector<std::uint32_t>& order) : op_(std::move(op)) { restore(s, order); }
  /// A logical process's (timewarp.hpp): its search (`shell` as set_list_shell's: 0 the cell grid,
  /// -1 automatic) and the regions (set_regions) set before its one build; `back`: an LP of a run
  /// back, built in run_back's reversed frame (its events the back steps; Config::back).
  BasicEngine(const Snapshot& s, Op op, int axis, std::vector<std::int64_t> faces, double shell = 0.0, bool back = false) : op_(std::move(op)) {
    list_shell_ = shell, rax_ = axis, faces_ = std::move(faces), load_back_ = back;
    restore(s);
    load_back_ = false;
  }

  /// Replaces the state by a snapshot (validated first: on bad input nothing changes); `order`
  /// (optional): the particle each local index holds, a permutation of [0, N).
  void restore(const Snapshot& s, const std::vector<std::uint32_t>& order = {});
  /// Frees the particles, the search, the queue and the journals (a parallel run holds the state
  /// in its LPs meanwhile, parallel_run.hpp): the clock and counts stay; restore() must follow.
  void release();

  /// Runs forward until `collisions` more collisions (clock = the last one's tick) or up to tick
  /// `until` (clock = until), whichever comes first. Returns the collisions done.
  std::uint64_t run(std::uint64_t collisions, std::int64_t until, const std::function<bool()>& poll = {});
  /// Runs back to collision count `to_collisions` (the state the forward run had right after it,
  /// clock = its tick) or to tick `to_tick` (clock = to_tick), whichever comes first in reverse.
  void run_back(std::uint64_t to_collisions, std::int64_t to_tick, const std::function<bool()>& poll = {});

  // ---- the processed-event journal: events undone one by one (rollback.hpp) ----
  /// Keeps (true) or stops keeping (false) the journal of the events processed forward: per
  /// queue pop 24 bytes (a reflection also the one-tick cache it replaces), from which rollback
  /// undoes the latest events one by one in the forward frame, each by its own reverse
  /// computation, in O(events undone). A rebuild of the search (restore, run_back,
  /// set_list_shell, the undo of an engine error) restarts it at the state (ARCHITECTURE.md).
  /// `how`: reverse computation, or state saving (SS1, SS2) for the comparison (state.hpp).
  void keep_journal(bool on, Rollback how = Rollback::reverse);
  bool journaling() const noexcept { return jon_; }  ///< Whether the journal is kept.
  Rollback rollback_by() const noexcept { return jhow_; }  ///< how a rollback restores the state
  std::size_t journal_bytes() const noexcept;  ///< Bytes the journal holds (its entries and, state saving, the saved states; an LP's, the states its messages replaced).
  /// Rolls back to the state right after collision `collisions` (clock = its tick; the journal's
  /// start when that is where the count is), bit for bit the forward run's state there; a run on
  /// processes the same events. journal_start() <= collisions <= collisions(); ends observation.
  void rollback(std::uint64_t collisions);
  /// Rolls back to tick `tick` (every event after the tick undone; clock = tick): the state
  /// run(until = tick) has. Requires the journal and journal_start_tick() <= tick <= clock().
  void rollback_to_tick(std::int64_t tick);
  /// Rolls back every event whose key (tick, kind, particle id) is at least (tick, kind, id): a
  /// straggler's rollback (the queue's order: a collision's id is the one of the pair whose slot
  /// came up). Clock = the last kept event's tick, or tick - 1. Requires the journal and a key
  /// after the journal's start.
  void rollback_before(std::int64_t tick, std::int32_t kind, std::int32_t id);
  /// Forgets the journal up to collision `collisions` (committed: rollback can go no further
  /// back), freeing it. journal_start() <= collisions <= collisions().
  void commit(std::uint64_t collisions);
  /// The collision count at the journal's start (the earliest state rollback reaches).
  std::uint64_t journal_start() const noexcept { return j_ncoll0_; }
  std::int64_t journal_start_tick() const noexcept { return j_clock0_; }  ///< The tick at the journal's start.
  std::size_t journal_size() const noexcept { return jdone_.size(); }  ///< Entries held (queue pops since the journal's start).

  // ---- a logical process's view (lp_view.hpp; the parallel engine, timewarp.hpp) ----
  using Record = ParticleRecordN<D, Bits>;  ///< one particle's whole state
  Record record(int id) const;              ///< particle id's state (its line as anchored)
  /// Makes this engine an LP's: the particles not `held[id]` parked (in no cell, no event), every
  /// event noted in `notes`, the journal kept. Cells or lists (a parked particle is on no list).
  void lp_begin(const std::vector<std::uint8_t>& held, LpNotes* notes);
  bool held(int id) const { return parked_.empty() || parked_[local(id)] == 0; }  ///< in the view
  /// Particle id takes state r at key k (a message), held from then on; journaled, a rollback
  /// to before k takes it back. lp_clear: false when it overlaps a body it may not (lp_view.hpp).
  void lp_write(int id, const Record& r, const EventKey& k);
  bool lp_clear(int id, const EventKey& k) const;
  void lp_park(int id, const EventKey& k);  ///< particle id leaves the view at key k (journaled)
  bool lp_next(EventKey& k);                ///< the next queue pop's key; false: none
  std::size_t lp_run(const EventKey& stop, std::size_t max);  ///< queue pops before `stop`, at most max; notes->after after each
  void commit_before(const EventKey& k);    ///< forgets the journal's entries before key k
  EventKey last_key() const noexcept;       ///< the key of the journal's last entry (or its start)
  Snapshot snapshot() const;  ///< The state (forward frame, positions at the clock).
  /// A mixture's radii in lattice units, by particle id (empty: every diameter units().sigma).
  std::vector<std::int64_t> radii() const { return sz_.by_id([this](int q) { return local(q); }); }
  /// Starts observing the forward run from the clock (replacing any earlier observation):
  /// the float engine's observer (revcol/engine/observe.hpp) fed at every velocity change
  /// with the exact state converted once to float units (x length_unit, ticks x tick), the
  /// positions the engine gives (its *_at hooks: a lattice event moves centres by up to a
  /// tick's travel). Observation is forward only: run_back ends it; a snapshot keeps a running
  /// one and restore resumes it (or ends a running one of the old state; a stopped one stays).
  void observe(const engine::ObserveConfig& c);
  /// The running or last observation (null before observe()).
  const engine::Observer* observer() const noexcept { return observer_.get(); }
  bool observing() const noexcept { return obs_ != nullptr; }  ///< Whether an observation is running.
  void stop_observing();  ///< Ends the observation at the clock; observer() still reads it.
  /// run() brings a running observation to its end tick (Observer::sync: every particle's segment
  /// closed there); false leaves that to sync_observation() (a run in parts observed as one run).
  bool sync_after_run = true;
  void sync_observation() { if (obs_) obs_->sync(time_of(clock_)); }  ///< The observation brought to the clock.
  /// An observer of state x, v at tick `clock` in units u: a new one (config c) or s's (resumed);
  /// a mixture's radii by id (empty for one size) make its species (ascending radius).
  static std::unique_ptr<engine::Observer> make_observer(const Units& u, const std::vector<Vec>& x, const std::vector<Vec>& v,
                                                         std::int64_t clock, const engine::ObserveConfig* c, const Snapshot* s,
                                                         const std::vector<std::int64_t>& radius);
  double time_of(std::int64_t tick) const noexcept { return static_cast<double>(tick) * u_.tick; }  ///< A tick as float time (the observer's clock).
  double to_length(std::int64_t x) const noexcept { return static_cast<double>(x) * u_.length_unit; }  ///< Lattice units as a float length.
  double to_speed(std::int64_t v) const noexcept { return static_cast<double>(v) * (u_.length_unit / u_.tick); }  ///< Lattice units per tick as a float speed.

  std::vector<Vec> positions() const;  ///< Positions at the clock, wrapped, by particle id.
  std::vector<Vec> velocities() const;  ///< Velocities by particle id (a copy).
  std::int64_t clock() const noexcept { return clock_; }                ///< the current tick
  std::int64_t origin() const noexcept { return origin_; }              ///< the initial tick
  std::uint64_t collisions() const noexcept { return ncoll_; }          ///< collisions since the start
  const Bits& bits(int p) const { return own_[local(p)].X; }  ///< particle p's bits-back integer
  /// The bit lengths of every particle's X, summed.
  std::size_t bits_length() const noexcept {
    std::size_t b = 0;
    for (const Own& o : own_) b += o.X.bit_length();
    return b;
  }
  /// Particle p's collisions since the start (pairs and groups it took part in, net of reverses).
  std::uint64_t particle_collisions(int p) const { return own_[local(p)].pc; }
  const Counters& counters() const noexcept { return cnt_; }            ///< statistics
  /// Rare-log entries held: the collisions that redrew (or were drawn in specular mode) and the groups.
  std::size_t log_size() const noexcept { return log_.size() + ngroups_; }
  std::size_t group_log_size() const noexcept { return ngroups_; }      ///< group collisions held in the log
  const Units& units() const noexcept { return u_; }                    ///< units and box
  std::size_t size() const noexcept { return ln_.size(); }               ///< N
  std::uint32_t seed() const noexcept { return seed_; }                 ///< stream seed
  std::vector<std::uint64_t> streams() const;  ///< The stream counters by particle id.
  const Op& op() const noexcept { return op_; }                         ///< the pair operator
  /// The operator's post-direction law (an operator without one, a test's, counts as flux).
  Law law() const noexcept {
    if constexpr (requires { op_.law(); }) return op_.law();
    else return Law::flux;
  }
  Mode mode() const noexcept { return mode_; }  ///< exact (the randomized operator Op) or specular (the deterministic map, specular.hpp).
  /// Redraws tried before a collision is resolved as a group bounce (group_bounce); -1 (tests
  /// only) resolves every collision so.
  int max_redraws = 256;
  bool group_resolve = true;  ///< When false (tests only), every group collision bounces back instead of resolving.
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
  void set_list_shell(double s);
  /// Slabs along `axis` between `faces` (ascending, in [0, L); the last slab wraps round to the
  /// first on a periodic axis), or none (empty): each particle's slab is kept as of its last
  /// event (region()), with a neutral event at the tick its centre enters another slab, and a
  /// collision or reflection that moves it across a face counts at its tick: the migrations a
  /// decomposition of the box sees, each at its key. Never changes which collisions happen.
  void set_regions(int axis, std::vector<std::int64_t> faces);
  int region(int id) const { return region_.empty() ? 0 : region_[local(id)]; }  ///< Particle id's slab (set_regions; 0 without slabs).
  /// When set, every forward change of a particle's slab is appended: (tick, particle id, from, to).
  std::vector<std::array<std::int64_t, 4>>* migrations = nullptr;
  /// The search in use: 0 the cell grid, 1 lists (the relative vector imaged per pair: a
  /// periodic axis shorter than about 2 (R + 2 h)), 2 lists with the centre offsets.
  int neighbour_search() const noexcept { return lists_ ? (direct_ ? 2 : 1) : 0; }
  /// The shell in use, in diameters (0: the cell grid).
  double list_shell() const noexcept { return lists_ ? 2.0 * static_cast<double>(nl_.radius()) / static_cast<double>(u_.sigma) : 0.0; }
  double auto_list_shell() const noexcept;  ///< The automatic shell for this gas, in diameters (0: cells; see set_list_shell).
  /// Re-sorts the storage in space every `every` neutral events per particle (state.hpp, resort;
  /// 0 never, -1 automatic): a speed setting, no bit changes (test_lattice_order.cpp).
  void set_resort(int every) {
    require(every >= -1, "lattice: resort must be >= -1 (-1: chosen from N, 0: never)");
    resort_every_ = every;
    resort_at_ = next_resort();
  }
  int resort_every() const noexcept { return resort_every_for(ln_.size()); }  ///< in use (0: none)
  std::uint64_t resorts() const noexcept { return resorts_; }  ///< re-sorts since construction
  std::size_t memory_bytes() const noexcept;  ///< Bytes held by the engine's arrays, queue, grid and log.
  std::size_t group_bytes() const noexcept;  ///< Bytes held by the group entries of the rare log (map node, members, pre velocities).
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
  enum Type : std::uint8_t { none = 0, cross = 1, wall = 2, coll = 3, lpw = 4, lpp = 5 };  // lpw/lpp: an LP's write, park
  struct Group;  // a group collision in the rare log (below)
  // a prediction's best event so far, in the slot order (tick, kind, other particle)
  struct Best {  // (the other particle by id: gq; q its local index)
    std::int64_t t = std::numeric_limits<std::int64_t>::max();
    std::int32_t k = 0;
    Type type = none;
    int q = -1, gq = -1;
    // (always inline: out of line, as GCC chose once predict held two scans, it cost 70
    // instructions per collision in 2D)
    [[gnu::always_inline]] void offer(std::int64_t t2, std::int32_t k2, Type ty, int q2, int gq2) noexcept {
      if (t2 >= tick_limit) return;
      if (std::tie(t2, k2, gq2) < std::tie(t, k, gq) || type == none) t = t2, k = k2, type = ty, q = q2, gq = gq2;
    }
  };
  void load(const Snapshot& s, const std::vector<std::uint32_t>& order = {});
  Snapshot fresh(const Units& u, std::vector<Vec> x, std::vector<Vec> v, std::uint32_t seed, std::int64_t clock, Mode mode,
                 std::vector<std::int64_t> radius = {}) const;
  void check_log(const Snapshot& s) const;  // the rare log against the per-particle counts

  // ---- geometry of the lines ----
  // p's point at tick t on its line, wrapped on periodic axes (predict.hpp)
  [[gnu::always_inline]] inline Vec pos(int p, std::int64_t t) const noexcept;
  // a uniform field (field.hpp): its axis (-1 none) and half its acceleration h = g / 2
  int gax_ = -1;
  std::int64_t hg_ = 0;
  double hgd_ = 0.0;  // h as a double (the prediction's filter)
  std::array<std::uint8_t, D> axk_{};  // per axis: 0 periodic, 1 walls, 2 walls and the field, 3 the sheared gradient (pos)
  // Lees-Edwards shear (shear.hpp): the frame's rate s (u_.shear forward, -u_.shear reversed; 0 none)
  std::int64_t sh_ = 0;
  std::int64_t delta(std::int64_t t) const noexcept { return wrap(static_cast<i128>(sh_) * t, u_.L[0]); }
  std::int64_t ups(int p, std::int64_t t) const noexcept;  // boxes up the gradient p's unwrapped line is at t
  [[gnu::noinline]] std::int64_t sheared_at(int p, std::int64_t t, Vec& out) const noexcept;  // (pos)
  // shear's forms of diff, shifted and x - v at tick t (predict.hpp: inline without shear)
  [[gnu::always_inline]] Vec diff_at(const Vec& a, const Vec& b, std::int64_t t, std::int64_t& n) const noexcept;
  [[gnu::always_inline]] Vec diff_at(const Vec& a, const Vec& b, std::int64_t t) const noexcept;
  [[gnu::always_inline]] Vec shifted_at(const Vec& origin, const Vec& d, std::int64_t t, Vec& v) const noexcept;
  [[gnu::always_inline]] Vec back_at(const Vec& x, const Vec& v, std::int64_t t) const noexcept;
  [[gnu::noinline]] Vec sheared_shift(const Vec& origin, const Vec& d, std::int64_t t, Vec& v) const noexcept;
  bool moving_ = false;  // a field or shear: lines are read through vel (gax_ >= 0 || sh_ != 0)
  [[gnu::noinline]] void reanchor_moving(int p, std::int64_t t);  // (predict.hpp)
  // the parabola's point on axis k; p's velocity at t; its move over a-1 -> a; v + h (predict.hpp)
  [[gnu::noinline]] std::int64_t field_at(int p, std::size_t k, std::int64_t dt) const noexcept;
  Vec vel(int p, std::int64_t t) const noexcept;
  Vec move_of(int p, std::int64_t a) const noexcept;
  Vec plus_h(Vec v) const noexcept, minus_h(Vec v) const noexcept;  // +- h on a field's axis (moves and velocities, field.hpp)
  [[gnu::always_inline]] Vec diff(const Vec& a, const Vec& b) const noexcept {
    Vec r;
    for (std::size_t k = 0; k < D; ++k) r[k] = u_.wall[k] ? a[k] - b[k] : min_image(a[k] - b[k], u_.L[k]);
    return r;
  }
  // ---- the sizes (sizes.hpp): a pair's contact distance, a centre's range on a wall axis ----
  std::int64_t rad(int p) const noexcept { return sz_.rad(p); }
  u128 sig2(int p, int q) const noexcept { return sz_.sig2(p, q); }
  bool overlap(const Vec& a, const Vec& b, int p, int q) const noexcept { return norm2(diff(a, b)) < sig2(p, q); }
  bool overlap_at(const Vec& a, const Vec& b, int p, int q, std::int64_t t) const noexcept { return norm2(diff_at(a, b, t)) < sig2(p, q); }
  std::int64_t lo_of(int p) const noexcept { return rad(p); }
  std::int64_t hi_of(int p, int k) const noexcept { return u_.L[k] - rad(p); }
  // f(q) for every q that may be near p: p's neighbour list, or the particles of its 3^D cells
  template <class F>
  void near(int p, F&& f) const {
    if (lists_) nl_.for_each(p, f);
    else if (sh_ != 0) [[unlikely]] grid_.for_neighbours_sheared(grid_.cell_of_particle(p), f);
    else grid_.for_neighbours(grid_.cell_of_particle(p), f);
  }

  // ---- keys ----
  // the particle id of local index p, and the local index of particle id q (identity unless the
  // engine was given an order): every key, draw, tie and output is by id
  int gid(int p) const noexcept { return gid_.empty() ? p : gid_[static_cast<std::size_t>(p)]; }
  std::size_t local(int q) const {
    require(q >= 0 && static_cast<std::size_t>(q) < ln_.size(), "lattice: no such particle id");
    return lid_.empty() ? static_cast<std::size_t>(q) : static_cast<std::size_t>(lid_[static_cast<std::size_t>(q)]);
  }
  std::int32_t n32() const noexcept { return static_cast<std::int32_t>(ln_.size()); }
  std::int32_t coll_kind(int a, int b) const noexcept {
    const int lo = std::min(gid(a), gid(b));
    return reversed_ ? 1 + (n32() - 1 - lo) : 2 + lo;
  }
  std::int32_t wall_kind() const noexcept { return reversed_ ? n32() + 1 : 1; }

  void reanchor(int p, std::int64_t t);
  void schedule(int p, Type type, std::int64_t t, std::int32_t kind, int partner);
  void predict(int p, std::int64_t lo);
  template <bool Mixed, bool Field>  // a mixture's contact distances (a one-size gas's scan reads no radius); a field's fall
  [[gnu::always_inline]] void scan(int p, std::int64_t lo, Best& b);
  void rebuild();
  void flip();

  // ---- the loop ----
  bool valid(int p) const noexcept {
    const Slot& b = slot_[static_cast<std::size_t>(p)];
    if (b.ver != b.vself) return false;
    return b.type != coll || slot_[static_cast<std::size_t>(b.partner)].ver == b.vpart;
  }
  void check_order(std::int64_t t, std::int32_t k);
  std::uint64_t loop(std::uint64_t want, std::int64_t until, bool back, std::uint64_t target, const std::function<bool()>& poll);
  void reflect(int p, std::int64_t a);
  void field_impulse(std::int64_t before, std::int64_t after, bool off) noexcept;  // a field's wall momentum (loop.hpp)
  void unreflect_impulse(int p, std::int64_t a, const Vec& post) noexcept;  // rollback.hpp
  bool impulse_here(int p) const noexcept;  // p's reflection counts in that momentum here (loop.hpp)
  // a state the reverse cannot take back (a loaded state no run wrote): an error naming it, the
  // collision and the pair; run_back restores the state it began with
  [[noreturn, gnu::cold]] void inconsistent(const std::string& what, int i, int j) const;  // (collide.hpp)
  // the reflection map of a line whose tick-(a-1) point is x with velocity v (beyond the walls of
  // the returned axes at a): x becomes its point at a, v its velocity after (loop.hpp)
  unsigned reflection(int p, Vec& x, Vec& v, std::int64_t a) const noexcept;  // p's wall range

  // ---- collisions ----
  Vec shifted(const Vec& origin, const Vec& d) const noexcept;  // origin + d, wrapped (128-bit sum; predict.hpp)
  Vec wrapped(const Vec& x) const noexcept;                      // x wrapped on periodic axes
  int post_reason(int i, int j, const Vec& xi, const Vec& xj, const Vec& vi, const Vec& vj, std::int64_t a, const Vec (&pre_a)[2], bool& multi) const;
  template <bool Sheared, bool Fall = false>
  int post_reason_t(int i, int j, const Vec& xi, const Vec& xj, const Vec& vi, const Vec& vj, std::int64_t a, const Vec (&pre_a)[2], bool& multi) const;
  std::int64_t next_offset(std::int64_t lo) const noexcept;  // shear: the next tick the images move on by a cell (predict.hpp)
  void apply(int i, int j, const Vec& xi, const Vec& xj, const Vec& vi, const Vec& vj, std::int64_t a);
  void collide_forward(int i, int j, std::int64_t a);
  void collide_back(int i, int j, std::int64_t a);
  bool collide_drawn(int i, int j, std::int64_t a, bool fallback);
  void collide_specular(int i, int j, std::int64_t a);
  void back_specular(int i, int j, std::int64_t a);
  std::vector<int> group_of(int i, int j, std::int64_t a) const;
  std::vector<std::int64_t> stall(std::vector<Vec>& x, std::int64_t a) const;  // a group's a-1 points -> its points at a (group.hpp)
  std::vector<Vec> resolve_velocities(const std::vector<int>& g, const std::vector<Vec>& x, std::int64_t a) const;
  bool group_post(std::vector<int>& g, std::int64_t a, bool resolve, std::vector<Vec>& post, std::vector<Vec>& vel) const;
  // false when it can neither resolve nor bounce (nothing changed) and !must; must: throws then
  bool group_collide(int i, int j, std::int64_t a, std::uint64_t ctr0, const std::array<std::uint64_t, 8>& reasons, bool must = true);
  void group_back(int i, int j, std::int64_t a, Group& entry);
  void record(int kind, std::int64_t a, const std::vector<int>& ids, const std::vector<Vec>& x, const std::vector<Vec>& v, unsigned axes);
  [[gnu::noinline, gnu::cold]] void note_pair(std::int64_t a, int i, int j, const Vec& xi, const Vec& xj, const Vec& vi, const Vec& vj);
  [[gnu::noinline, gnu::cold]] void note_wall(std::int64_t a, int p, const Vec& xp, const Vec& vp, unsigned axes);
  [[gnu::noinline, gnu::cold]] void note_group(std::int64_t a, const std::vector<int>& g, const std::vector<Vec>& xg, const std::vector<Vec>& vg);
  std::unique_ptr<engine::Observer> observer_;  // the running or last observation (observe.hpp)
  engine::Observer* obs_ = nullptr;             // observer_ while it runs, else null

  // The operator must work in the units' lattice: the same sigma and (an operator with
  // direction cells) the same cell resolution.
  void check_operator(const Units& u) const;  // (state.hpp)
  Op op_;
  // specular mode: the deterministic map (built by load for the units' sigma)
  using Specular = std::conditional_t<D == 2, LatticeSpecular2D, LatticeSpecular3D>;
  Mode mode_ = Mode::exact;
  Specular spec_{2};
  // the pair's operator and specular map: the units' own, or made for r_i + r_j (a mixture)
  const Op& op_of(int i, int j, std::optional<Op>& tmp) const { return sz_.pair_op(op_, i, j, tmp); }
  const Specular& spec_of(int i, int j, std::optional<Specular>& tmp) const { return sz_.pair_op(spec_, i, j, tmp); }
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
    double r;                 // a mixture: the radius (set by rebuild; the filter's contact distance)
  };
  std::vector<LineD> lnd_;
  // a position x (wrapped) unwrapped about p's list centre, as doubles (predict.hpp)
  std::array<double, D> unwrapped_about(int p, const Vec& x) const noexcept;
  [[gnu::always_inline]] inline void sync(int p) noexcept;  // (predict.hpp)
  std::vector<std::int64_t> wall_tick_;
  std::vector<Line> pre_wall_;  // a particle's line before its reflection at wall_tick_ (that tick only)
  // ---- the forward run's undo journal (run(): an engine error restores the state) ----
  // one particle's own draws and count: its stream counter, bits-back integer and collision
  // count, together in one cache line (a collision of i < j reads i's whole record and j's
  // count; apart they were four lines: docs/lattice.md "The bits-back integers")
  struct alignas(64) Own {
    Bits X;                 // the bits-back integer (the drawer's runs the operator)
    std::uint64_t ctr = 0;  // the Philox stream counter
    std::uint64_t pc = 0;   // collisions (the rare log's keys)
  };
  std::vector<Own> own_;
  struct Saved {  // (Own's fields, not its 64-byte alignment: the journal may hold every particle)
    int p;
    Line line, pre_wall;
    std::int64_t wall_tick;
    Bits X;
    std::uint64_t ctr, pc;
  };
  std::vector<Saved> undo_;
  std::vector<std::uint32_t> undo_epoch_;  // per particle: the run() that journaled it
  std::uint32_t epoch_ = 0;
  std::vector<LogKey> undo_log_, undo_groups_;  // rare-log and group keys this run() added
  Counters undo_cnt_;
  std::int64_t undo_clock_ = 0;
  std::uint64_t undo_ncoll_ = 0;
  void begin_undo();
  // keeps p's state as it was when this run() began (first change only)
  void journal(int p) {
    if (undo_epoch_.empty() || undo_epoch_[p] == epoch_) return;
    undo_epoch_[p] = epoch_;
    undo_.push_back(Saved{p, ln_[p], pre_wall_[p], wall_tick_[p], own_[p].X, own_[p].ctr, own_[p].pc});
  }
  void undo(bool whole = true);  // whole: rebuild; else (an LP's event) predict the particles again
  // one particle's event bookkeeping, together in memory (the loop reads it per event, and the
  // partner's version): its version (bumped at every change of its line), its scheduled event's
  // type and partner, and the versions both had when it was scheduled (stale if either moved on)
  struct alignas(32) Slot {
    std::uint64_t ver = 0, vself = 0, vpart = 0;
    int partner = -1;
    Type type = none;
  };
  std::vector<Slot> slot_;
  // the rare log: (drawer, its count after the collision) -> redraws, for the collisions that
  // redrew (and, specular mode, the drawn fallbacks)
  std::map<LogKey, std::uint32_t> log_;
  struct Group {
    int drawer;                         // whose stream the tried draws came from
    std::uint32_t draws;                // draws tried before the group
    std::vector<int> members;           // ascending
    std::vector<std::uint64_t> counts;  // per member: its count after the group (its key)
    std::vector<Vec> pre_v;             // exact pre velocities (a resolve) or empty (a bounce)
  };
  // group collisions, under every member's key (member, its count after the group)
  std::map<LogKey, std::shared_ptr<Group>> groups_;
  std::size_t ngroups_ = 0;
  std::int64_t clock_ = 0, origin_ = 0;
  std::uint64_t ncoll_ = 0;
  std::array<std::uint64_t, 2> energy0_{};
  std::array<std::int64_t, 2 * D> momentum0_{};
  Counters cnt_;
  bool reversed_ = false, load_back_ = false;  // load_back_: load into the reversed frame (an LP running back)
  // the neighbour search (set_list_shell): the cell grid, or neighbour lists (measured: docs/lattice.md)
  static constexpr double kShellBase = 0.545, kShellSlope = 1.0, kShellMin = 0.6, kShellMax = 1.2;
  static constexpr double kFieldListsMaxLambda = 0.3;  // a field: lists below this Enskog free path (docs/lattice.md)
  double list_shell_ = -1.0;
  // the periodic re-sort (state.hpp, resort; docs/lattice.md "The storage order")
  static constexpr std::size_t kResortMinN = 32768;
  static constexpr int kResortEvery = 16;
  int resort_every_ = -1;
  std::uint64_t resort_at_ = 0, resorts_ = 0;  // the crossing count of the next re-sort (0: none)
  int resort_every_for(std::size_t n) const noexcept { return resort_every_ >= 0 ? resort_every_ : (n >= kResortMinN ? kResortEvery : 0); }
  std::uint64_t next_resort() const noexcept;  // (state.hpp)
  [[gnu::noinline, gnu::cold]] void resort(std::int64_t t);
  static std::vector<std::uint32_t> space_order(const Units& u, const std::vector<Vec>& x);
  bool lists_ = false, direct_ = false;
  NeighbourListsN<D> nl_;
  u128 sigma2_ = 0;
  double sigma2d_ = 0.0, far2_ = 0.0;
  std::array<double, D> Ld_{}, invL_{}, edge_{};  // the prediction's filter: L, 1 / L, L / 2 less rounding
  bool shifted_ = false;  // cells whose images are known (CellGridN::shifted)
  std::array<std::array<double, D>, 1u << (2 * D)> shift_{};  // a list entry's image shift by code (neighbour_lists.hpp)
  Sizes sz_;
  CellGridN<D> grid_;
  Queue queue_;
  std::pair<std::int64_t, std::int32_t> last_key_{};
  std::vector<int> gid_, lid_;  // local index -> particle id and back (empty: the identity)
  // slabs (set_regions): the axis (-1: none), the faces, each particle's slab as of its anchor
  int rax_ = -1;
  std::vector<std::int64_t> faces_;
  std::vector<int> region_;
  bool unwinding_ = false;  // a rollback's predictions record no migration
  int region_of(const Vec& x) const noexcept {
    const auto it = std::upper_bound(faces_.begin(), faces_.end(), x[static_cast<std::size_t>(rax_)]);
    const int m = static_cast<int>(faces_.size());
    return (static_cast<int>(it - faces_.begin()) - 1 + m) % m;
  }
  std::int64_t region_ticks(const Line& l) const noexcept;  // ticks to the next face, -1: none
  // ---- the processed-event journal (rollback.hpp) ----
  struct Done {        // one queue pop
    std::int64_t t;    // its tick
    std::int32_t kind;  // its queue kind
    int p, q;          // the particle popped; a collision: its drawer (the smaller id) and partner
    Type type;         // none: a stale event recomputed
    std::uint8_t unreflected;  // a group: bit 0 (p), bit 1 (q) took in their reflection at t; bit 2: q was popped; bit 3: a jback_ entry
    std::uint8_t kept;         // state saving: the particle states saved before it
  };
  struct WallDone { std::int64_t wall_tick; Line pre_wall; bool counted; };  // a reflection's replaced one-tick cache; a field's momentum counted (impulse_here)
  bool jon_ = false;
  Rollback jhow_ = Rollback::reverse;
  std::deque<Done> jdone_;
  std::deque<Saved> jss1_;                   // SS1: whole records, before each event
  std::deque<std::pair<int, Line>> jss2_;    // SS2: the touched lines, before each event
  std::deque<Bits> jss2x_;                   // SS2: a collision's drawer's X, before it
  std::uint8_t jkept_ = 0;                   // states saved for the event under way
  void save_state(int p, bool drawer = false);  // state saving: p's state before the event under way
  void restore_kept(const Done& d);
  std::deque<WallDone> jwall_;  // one per wall entry of jdone_, in order
  std::deque<std::pair<std::uint8_t, Record>> jlp_;  // per LP write or park: parked before, state before
  struct BackDone {  // a back step that read the rare log: its redraws, or its group and the members' lines before
    std::uint32_t redraws = 0;
    std::shared_ptr<Group> group;
    std::vector<Line> lines;
  };
  std::deque<BackDone> jback_;  // per back step that erased a log entry or a group (an LP running back)
  std::uint8_t note_back(int i);  // its jback_ entry (bit 3 of Done::unreflected) or 0
  void redo_collision(const Done& d);    // the undo of a back step
  std::vector<std::uint8_t> parked_;  // an LP's particles outside its view (empty: none)
  LpNotes* lp_ = nullptr;
  LpSeen* seen_ = nullptr;  // an observed LP's: the observer's calls kept (lp_seen.hpp)
  bool lp_stepped_ = false;  // lp_run: an event was popped (its after-hook is due)
  EventKey done_key(const Done& d) const noexcept {
    return {d.t, d.kind, d.type >= lpw ? d.q : gid(d.unreflected & 4u ? d.q : d.p)};
  }
  void lp_set(int p, const Record& r);
  void lp_unpark(int p), lp_unplace(int p);  // into the view's search (cells or lists), out of it
  void lp_note(int i, int j);  // the collision's particles into lp_'s notes
  std::uint64_t j_ncoll0_ = 0;
  std::int64_t j_clock0_ = 0;
  std::pair<std::int64_t, std::int32_t> j_key0_{};
  std::uint8_t unreflected_ = 0;  // the last group_collide's unreflected members (bits as Done's)
  std::vector<int> jtouched_;     // rollback: the particles its undone span touched
  std::vector<std::uint32_t> jmark_;
  std::uint32_t jepoch_ = 0;
  void restart_journal();
  template <class Keep>
  void unwind(Keep keep, std::int64_t clock);
  void touch(int p);
  void undo_wall(int p, std::int64_t a, const WallDone& w);
  void undo_collision(int i, int j, std::int64_t a, std::uint8_t unreflected);
  void undo_group(std::int64_t a, const Group& g, int i, int j, std::uint8_t unreflected);
};

}  // namespace revcol::lattice
