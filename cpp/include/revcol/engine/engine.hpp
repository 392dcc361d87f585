// The event-driven engine (DESIGN.md §2 and §5): N hard spheres of one diameter in d = 1, 2, 3,
// run forward with randomized elastic collisions, and back to any earlier time with no
// per-collision memory (the paper §3.2).
//
// Forward. Per-particle local times (a particle's stored position is where it was at its
// local time; x(t) = x_i + v_i (t - t_i)), neighbour lists with a shell, one event per
// particle (its earliest wall contact, list renewal or collision) in an event queue,
// invalidation by a per-particle stamp that changes whenever the particle's stored state
// changes. Each particle has a list centre (where it was at its last renewal) and lists
// the particles whose centres lie within D + shell of it, each with its periodic image;
// the lists are symmetric and a function of the centres alone (a snapshot keeps the
// centres, a restore rebuilds the lists). Its renewal event fires when it is h =
// (shell - 1e-3 D) / 2 from its centre: the centre moves there, the list is rebuilt from a
// cell grid of the centres, and nothing physical changes; a pair off each other's lists is
// more than D (1 + 1e-3) apart, so a prediction scans the list alone. In 1D (walls, or a
// periodic ring of 3 rods or more) rods keep their order, so each lists the rods beside it
// for the whole run: no cell grid, no renewals, only a wrap event on a periodic axis (a
// stored position moves by L a quarter diameter past the box's end). The queue is Paul's
// O(1) queue (time buckets, the current one a binary heap); its keys (time, kind, id) are
// distinct, so the order of events does not depend on its bucket width. Collision times
// use the cancellation-free root
// t = (r^2 - D^2) / (-b + sqrt(b^2 - w^2 (r^2 - D^2))), b = r.w < 0 (only approaching pairs
// are candidates), computed for the pair ordered by id from the later of the two local
// times, so that both partners predict the same bits.
//
// Reverse. Negate every velocity and every time (local times and the clock), run the same
// event search, and at each collision apply v -> -reverse(-v) with the generator stepping
// back; wall events are their own inverse (a reflection, engine/boundary.hpp), and
// so are list renewals (no physical change: a reversed run renews where its own trajectory
// leaves its spheres). Negating again at the end returns the state to the forward
// orientation. Negation is exact, so free flight is bit-identical both ways; what is not is
// the collision time and the contact normal, recomputed from positions that carry
// round-off. A hard-sphere gas is chaotic and amplifies that round-off, and exact mode's
// K-bit chart cells return each pre-collision state to its cell centre (a relative error
// ~2^-K of the relative speed): round trips are exact to 1e-9 only within a horizon of
// collisions per particle, which bench/engine_study.py measures.
//
// Random numbers: by default one Philox stream per particle (key {id, seed}); a pair
// collision draws from the stream of its smaller id, a group from that of its smallest id
// (the paper's per-particle policy, §4.6). Two collisions that share no particle commute: if
// round-off swaps their order in the reversed run, each still steps back its own stream.
// CLCG4 (stream seed * count + i, rng/streams.hpp) is the other generator, and `single`
// the other policy: one stream for the system. A single stream does not commute: two
// disjoint collisions at exactly the same time are met in the same (id) order by the
// reversed run, and two that round-off swaps step the stream back out of order, so its
// horizon can only be shorter than per-particle's. Each stream keeps its draw count (the
// snapshot's `rng`); a CLCG4 state is rebuilt from it by a modular power on restore.
//
// Ties and groups. The queue orders events by (time, kind, particle id) with walls before
// list renewals before collisions, so at one instant a particle reflects on walls first and
// collides after; the reversed run meets the same instant with the particle approaching the
// walls again, so it undoes the walls first there too, which is the opposite order of the
// forward sequence (collision, then the wall it was sent into). When a collision of a and b
// is processed at time t, every particle whose contact with the pair's component is closed
// within `group_tol` (|r| - D <= group_tol D, from r^2 - D^2 <= 2 group_tol D^2) and
// approaching or at rest (r.w <= 0) joins it: the connected component of that contact graph
// is one collision of n particles resolved by ExactCollision (any n, d, at most 3
// independent contacts), drawing (n-1)d-1 numbers from the stream of its smallest id. The
// reversed run meets the negated post state, in which every one of those contacts
// approaches, and gathers the same component. Particles and contacts are sorted by id, so
// the operator's geometry does not depend on the order of discovery. A group the operator
// refuses (more than 3 independent contacts, more than 8 particles) falls back to the pair
// alone and is counted (`group_fallbacks`). The gather scans two neighbourhoods, so it runs
// only when a group is possible: a neighbour in contact (approaching or at rest) at a
// prediction, or a second collision predicted within a relative 1e-9 of the first.
//
// Walls at a collision. A particle of a collision that touches a wall (within group_tol D)
// and approaches it reflects before the operator (W1), and again after it if the operator
// sends it into a touched wall (W2). What W1 and W2 did (their Reflection masks) cannot be
// read off the post state (the wall operator's two-to-one case), so the forward run keeps them, in a
// small log keyed by (smallest id, its net collision count), for collisions at a wall only;
// the reversed collision undoes W2, reverses the operator, undoes W1, and a reversed run
// schedules no standalone wall event for a particle already touching a wall unless that
// log says W2 applied that wall's reflection at this instant.
//
// The exact-pre log. At singular points of a chart (a 3D pair almost head-on, groups with
// resting contacts such as Newton's cradle) a pre state's K-bit cell spans up to
// ~2^(-K/2) and its centre is far from the state; when the cell centre is off by more than
// 1e-10 (relative), the forward run keeps the pre velocities, keyed by (stream, generator
// counter), and the reversed collision restores them. In a gas this is a few entries per
// million collisions (measured: 7 KB after 1e7 collisions at N = 1e4, docs/engine.md).
//
// Storage. Particle ids name the particles everywhere above; where the engine stores a
// particle (its slot) is its own affair. From 32 768 particles in 2D and 3D (Config::resort)
// it stores them in the order of their list centres' cells, at construction and restore and
// again after every 16 list renewals per particle, so that a gas diffused far from its start
// still scans lists that lie close in memory. No decision reads a slot (queue ties, the
// choice between equal times, pair order, streams, groups, logs, sums and outputs all go by
// id), so a run's bits do not depend on it (tests/cpp/test_engine_hash.cpp).
//
// A state at an event (a particle touching a wall or another particle at the start time)
// is ambiguous for a run back to that time: start between events (random_state keeps
// 1e-6 D from the walls).
#pragma once
#include <array>
#include <cstdint>
#include <cstring>
#include <functional>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "revcol/collide/common.hpp"
#include "revcol/engine/boundary_kind.hpp"
#include "revcol/engine/trace.hpp"
#include "revcol/error.hpp"
#include "revcol/visitable.hpp"
#include "revcol/rng/streams.hpp"

namespace revcol::engine {

/// The reversible generator behind the collisions' random numbers.
enum class Generator { philox, clcg4 };

/// "philox" / "clcg4".
inline const char* to_string(Generator g) { return g == Generator::philox ? "philox" : "clcg4"; }
/// Parses "philox" / "clcg4"; throws InvalidArgument otherwise.
Generator parse_generator(const std::string& s);
/// Parses a mode the engine runs: "exact", "paper", and the engine-only modes of
/// cpp/src/engine_operators.hpp; throws InvalidArgument otherwise.
Mode parse_engine_mode(const std::string& s);
/// Parses "per_particle" (or "per-particle") / "single"; throws InvalidArgument otherwise
/// (the engine has no per-draw policy: a collision's draw count depends on its size).
rng::StreamPolicy parse_engine_streams(const std::string& s);

/// Everything that defines a simulation besides its particles.
struct Config {
  int dim = 2;                                   ///< d = 1, 2, 3
  std::array<double, 3> box{1.0, 1.0, 1.0};      ///< box lengths L_k: the box is [0, L_k] per axis
  std::array<Boundary, 3> boundary{Boundary::periodic, Boundary::periodic, Boundary::periodic};  ///< per axis
  double diameter = 1.0;                         ///< D (a mixture: the largest of `diameters`)
  std::vector<double> diameters;                 ///< a mixture: one diameter per particle (id order),
                                                 ///< the largest equal to `diameter`; empty: one size
  std::vector<double> masses;                    ///< one mass per particle (id order); empty: all 1. A pair of
                                                 ///< unequal masses collides in its centre-of-mass frame
  std::array<double, 3> gravity{0.0, 0.0, 0.0};  ///< a uniform field (acceleration), nonzero only on walled
                                                 ///< axes; energy then includes -m g . x
  Mode mode = Mode::exact;                       ///< the pair operator: exact (default), paper, ... (engine_operators.hpp)
  Law law = Law::flux;                           ///< exact mode's target law
  std::uint32_t seed = 1;                        ///< the generator family (rng/streams.hpp)
  Generator generator = Generator::philox;       ///< Philox (key {stream, seed}) or CLCG4 (stream seed * count + i)
  rng::StreamPolicy streams = rng::StreamPolicy::per_particle;  ///< per_particle (smallest id draws) or single
  int bits = 40;                                 ///< K, exact mode's chart bits
  bool groups = true;                            ///< gather multi-particle contacts into one collision
  double group_tol = 1e-9;                       ///< contact tolerance, relative to D
  bool force_group_search = false;  ///< benchmarks only: search for a group at every collision, as an
                                    ///< engine without the gate would (not saved in snapshots)
  double shell = 0.0;  ///< benchmarks only: the neighbour-list shell in diameters; 0 (the default)
                       ///< chooses it from the packing fraction (not saved in snapshots)
  int resort = -1;  ///< speed only: the particles' storage is re-sorted in space after every
                    ///< `resort` list renewals per particle (2D, 3D); 0 never; -1 (the default)
                    ///< chooses (engine_impl.hpp, kResortEvery and kResortMinN). The trajectory
                    ///< does not depend on it, to the bit (not saved in snapshots)
};

using revcol::Visitable;  // revcol/visitable.hpp, shared with the lattice engine

/// Event counts (cumulative over both directions).
struct Counters : Visitable<Counters> {
  std::uint64_t events = 0;            ///< events popped from the heap
  std::uint64_t pair_collisions = 0;   ///< two-particle collisions
  std::uint64_t group_collisions = 0;  ///< collisions of three or more particles
  std::uint64_t group_particles = 0;   ///< particles taking part in those
  std::uint64_t group_fallbacks = 0;   ///< groups the operator refused (processed as a pair)
  std::uint64_t wall_events = 0;       ///< wall reflections
  std::uint64_t list_renewals = 0;     ///< neighbour-list renewals (1D ring: wraps); formerly cell_crossings
  std::uint64_t invalid_events = 0;    ///< predictions whose partner had changed
  std::uint64_t grazing_skipped = 0;   ///< predicted contacts found not approaching at contact
  std::uint64_t reverse_failures = 0;  ///< reversed collisions the operator refused (beyond the horizon)
  std::uint64_t forward_collisions = 0;  ///< collisions processed forward
  std::uint64_t reverse_collisions = 0;  ///< collisions processed in reverse

  /// Calls f(name, count) for every counter of c, in the checkpoint format's order (its
  /// `counters` array) and with the names of the diagnostics (visit(f) on an object).
  template <class S, class F>
  static void visit_fields(S& c, F& f) {
    f("events", c.events);
    f("pair_collisions", c.pair_collisions);
    f("group_collisions", c.group_collisions);
    f("group_particles", c.group_particles);
    f("group_fallbacks", c.group_fallbacks);
    f("wall_events", c.wall_events);
    f("list_renewals", c.list_renewals);
    f("invalid_events", c.invalid_events);
    f("grazing_skipped", c.grazing_skipped);
    f("reverse_failures", c.reverse_failures);
    f("forward_collisions", c.forward_collisions);
    f("reverse_collisions", c.reverse_collisions);
  }
};

/// What one run or run_back call did.
struct RunResult {
  std::uint64_t collisions = 0;  ///< collisions processed (pairs and groups)
  std::uint64_t events = 0;      ///< events popped
  double time = 0.0;             ///< the clock at the end
  bool interrupted = false;      ///< the progress callback (or the poll) asked to stop
  bool diverged = false;         ///< run_back found this call's reversal off the forward trajectory (trace.hpp)
};

/// The full state, for checkpoints: restoring it resumes bit for bit.
struct Snapshot : Visitable<Snapshot> {
  Config config;
  std::size_t n = 0;
  double time = 0.0, start_time = 0.0;
  std::int64_t net_collisions = 0;             ///< forward minus reverse collisions
  std::vector<double> x, v;                    ///< n x dim, stored positions (at local times) and velocities
  std::vector<double> t_local;                 ///< n
  std::vector<std::int64_t> cell;              ///< n x dim cell coordinates of the list centres
  std::vector<double> centre;                  ///< n x dim list centres (empty: from x, events predicted anew)
  std::vector<std::uint64_t> stamp, ncoll;     ///< n: state stamps, collisions
  std::vector<std::uint64_t> rng;              ///< per stream (n, or 1 for a single stream): draws taken
  std::vector<double> ev_t;                    ///< n: scheduled event times
  std::vector<std::int64_t> ev_kind, ev_partner;  ///< n
  std::vector<std::uint64_t> ev_stamp;         ///< n
  std::vector<double> second;                  ///< n: second earliest predicted collision (group gate)
  std::vector<std::int64_t> touching;          ///< n: a neighbour within the contact tolerance (group gate)
  std::vector<std::uint64_t> log_cells;        ///< the rare log, oldest first
  std::uint64_t log_pushed = 0;                ///< entries ever pushed
  std::vector<std::int64_t> netc;              ///< n: net collisions per particle (wall-log keys)
  std::vector<std::uint64_t> wall_keys;        ///< wall-mask log: (smallest id, its net count) per entry
  std::vector<std::uint64_t> wall_sizes;       ///< wall-mask log: members per entry
  std::vector<std::uint64_t> wall_masks;       ///< wall-mask log: W1 | W2 << 8 per member
  std::vector<std::uint64_t> wall_ids;         ///< wall-mask log: member ids
  std::vector<std::int64_t> wall_netc;         ///< wall-mask log: members' net counts before
  std::vector<double> wall_times;              ///< wall-mask log: forward time per entry
  std::vector<std::uint64_t> pre_keys;         ///< exact-pre log: (stream, counter) per entry
  std::vector<std::uint64_t> pre_sizes;        ///< exact-pre log: values per entry
  std::vector<double> pre_vals;                ///< exact-pre log: kept pre velocities
  std::uint64_t pre_pushed = 0;                ///< exact-pre entries ever pushed
  std::vector<std::uint64_t> trace;            ///< the collision trace (CollisionTrace::save; empty: a new one)
  std::vector<double> observer;                ///< a running observation (Observer::save; empty: none)
  std::vector<std::uint64_t> observer_counts;  ///< its counts per block
  Counters counters;
  double energy0 = 0.0;                        ///< kinetic energy at construction
  std::array<double, 3> momentum0{};           ///< momentum at construction

  /// Copies the field `name` into out (its type must match; throws InvalidArgument if no
  /// field of that name and type exists).
  template <class T>
  void field(const char* name, T& out) const {
    bool found = false;
    visit([&](const char* key, const auto& v) {
      if constexpr (std::is_same_v<std::decay_t<decltype(v)>, T>)
        if (!found && std::strcmp(key, name) == 0) {
          out = v;
          found = true;
        }
    });
    require(found, std::string("snapshot has no field '") + name + "' of this type");
  }
  /// Sets the field `name` from value (same rules).
  template <class T>
  void field(const char* name, const T& value) {
    bool found = false;
    visit([&](const char* key, auto& v) {
      if constexpr (std::is_same_v<std::decay_t<decltype(v)>, T>)
        if (!found && std::strcmp(key, name) == 0) {
          v = value;
          found = true;
        }
    });
    require(found, std::string("snapshot has no field '") + name + "' of this type");
  }

  /// Calls f(name, field) for every field of s but `config`, `counters` and `momentum0`, in
  /// the checkpoint format's order and with its names: a binding or an archive loops over
  /// this instead of naming each field (`centre` may be empty: a checkpoint written before
  /// the lists). visit(f) on an object.
  template <class S, class F>
  static void visit_fields(S& s, F& f) {
    f("n", s.n);
    f("time", s.time);
    f("start_time", s.start_time);
    f("net_collisions", s.net_collisions);
    f("x", s.x);
    f("v", s.v);
    f("t_local", s.t_local);
    f("cell", s.cell);
    f("centre", s.centre);
    f("stamp", s.stamp);
    f("ncoll", s.ncoll);
    f("rng", s.rng);
    f("ev_t", s.ev_t);
    f("ev_kind", s.ev_kind);
    f("ev_partner", s.ev_partner);
    f("ev_stamp", s.ev_stamp);
    f("second", s.second);
    f("touching", s.touching);
    f("log_cells", s.log_cells);
    f("log_pushed", s.log_pushed);
    f("netc", s.netc);
    f("wall_keys", s.wall_keys);
    f("wall_sizes", s.wall_sizes);
    f("wall_masks", s.wall_masks);
    f("wall_ids", s.wall_ids);
    f("wall_netc", s.wall_netc);
    f("wall_times", s.wall_times);
    f("pre_keys", s.pre_keys);
    f("pre_sizes", s.pre_sizes);
    f("pre_vals", s.pre_vals);
    f("pre_pushed", s.pre_pushed);
    f("trace", s.trace);
    f("energy0", s.energy0);
    f("observer", s.observer);
    f("observer_counts", s.observer_counts);
  }
};

/// Conservation and activity diagnostics.
struct Diagnostics {
  double energy = 0.0;                    ///< sum m v^2 / 2, plus potential under a field
  double potential = 0.0;                 ///< under a field: sum m |g_k| times the distance from the wall it pulls to
  std::array<double, 3> momentum{};       ///< sum v
  double energy_drift = 0.0;              ///< (E - E0) / E0
  double momentum_drift = 0.0;            ///< |P - P0| / sqrt(2 E0 N)
  std::size_t log_bytes = 0;              ///< rare log and exact-pre log now held
  std::uint64_t exact_pre_pushed = 0;     ///< exact-pre entries ever pushed (singular pre states)
  std::size_t exact_pre_entries = 0;      ///< exact-pre entries now held
  std::size_t wall_log_entries = 0;       ///< wall-mask entries now held (collisions at walls)
  std::uint64_t log_pushed = 0;           ///< rare-log entries ever pushed
  double collisions_per_particle = 0.0;   ///< 2 pairs + group particles, over N (cumulative)
  std::int64_t net_collisions = 0;        ///< forward minus reverse
  Divergence divergence = Divergence::none;  ///< why a reversed run was found off the forward one
  std::int64_t diverged_at = CollisionTrace::kNever;  ///< net collision count where it was first found off
  std::int64_t verified_at = CollisionTrace::kNever;  ///< the last net count a reversed run was found on
  std::uint64_t trace_reorderings = 0;    ///< single mismatches not confirmed (swapped disjoint collisions)
  std::uint64_t trace_stride = 0;         ///< the trace's grid stride now (collisions)
  std::size_t trace_points = 0;           ///< grid points kept
  double clock_deviation = 0.0;           ///< largest |t - t_forward| at the trace's points in the last reversed pass
  std::uint64_t storage_resorts = 0;      ///< periodic re-sorts of the particles' storage by run / run_back since construction or restore (Config::resort)
  Counters counters;
};

/// Called every `every` collisions with the collisions done so far in this call;
/// returning false stops the run between events.
using Progress = std::function<bool(std::uint64_t)>;
/// Called every kPollEvents events whatever happens (collisions or not); returning false stops
/// the run between events, at a state as valid as any other stop (the binding checks Ctrl-C).
using Poll = std::function<bool()>;
/// Events between two polls: about 10 ms of events (a poll is one flag check in Python).
inline constexpr std::uint32_t kPollEvents = 1u << 14;

struct ObserveConfig;
class Observer;

/// The engine for any d (runtime); one implementation per d behind it.
class Simulation {
 public:
  virtual ~Simulation() = default;
  /// Runs forward until `max_collisions` more collisions or the clock reaches t_end,
  /// whichever first, ending between events.
  virtual RunResult run(std::uint64_t max_collisions, double t_end, const Progress& cb = {},
                        std::uint64_t every = 0, const Poll& poll = {}) = 0;
  /// Runs backwards until `max_collisions` collisions are undone or the clock is back at
  /// t_target (<= time()), whichever first, ending between events (or when poll says stop).
  /// The collision trace checks that the reversal follows the forward trajectory
  /// (revcol/engine/trace.hpp): a divergence sets RunResult::diverged and, with
  /// stop_on_divergence, stops the run there as a collision count would.
  virtual RunResult run_back(std::uint64_t max_collisions, double t_target, const Poll& poll = {},
                             bool stop_on_divergence = false) = 0;
  /// Positions at the current time (n x dim, row-major).
  virtual std::vector<double> positions() const = 0;
  /// Velocities (n x dim).
  virtual std::vector<double> velocities() const = 0;
  /// Collisions per particle (n).
  virtual std::vector<std::uint64_t> collision_counts() const = 0;
  /// The clock.
  virtual double time() const = 0;
  /// The time the simulation was built at.
  virtual double start_time() const = 0;
  /// Number of particles.
  virtual std::size_t size() const = 0;
  /// The configuration.
  virtual const Config& config() const = 0;
  /// Energy, momentum, counters.
  virtual Diagnostics diagnostics() const = 0;
  /// The full state.
  virtual Snapshot snapshot() const = 0;
  /// Approximate bytes held by the engine's arrays.
  virtual std::size_t memory_bytes() const = 0;
  /// The first way the state fails the event loop's invariants at the clock, or "": two
  /// particles overlap, a particle is beyond its list's reach, or the schedule (event times,
  /// list centres) misses an event (cpp/src/engine_check.hpp). restore_simulation refuses a
  /// snapshot with one; a run_back ending with overlaps reports a divergence.
  virtual std::string fault() const = 0;
  /// Starts observing the forward run from the clock (revcol/engine/observe.hpp), replacing
  /// any earlier observation; a bad config throws InvalidArgument and changes nothing.
  virtual void observe(const ObserveConfig& c) = 0;
  /// The running or last observation's accumulator (null if none was started).
  virtual const Observer* observer() const = 0;
  /// Whether an observation is running (run_back and stop_observing end it).
  virtual bool observing() const = 0;
  /// Ends the observation at the clock; its results stay readable.
  virtual void stop_observing() = 0;
};

/// Builds a simulation from positions and velocities (n x dim each, row-major) at time t0.
/// Validates everything first (throws InvalidArgument naming the problem): n > 0, finite
/// values, box and diameter, particles inside the box, no overlap (|r| < D (1 - 1e-9)),
/// non-zero kinetic energy, at least 3 cells on a periodic axis, paper mode only in 1D/2D.
std::unique_ptr<Simulation> make_simulation(const Config& config, const std::vector<double>& x,
                                            const std::vector<double>& v, double t0 = 0.0);

/// Rebuilds a simulation from a snapshot (validated the same way); resumes bit for bit.
std::unique_ptr<Simulation> restore_simulation(const Snapshot& s);

}  // namespace revcol::engine
