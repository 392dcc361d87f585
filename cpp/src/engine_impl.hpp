// The event-driven engine for one dimension and one pair operator: EngineImpl<Dim, Op>,
// behind revcol::engine::Simulation. The physics and the reversal protocol are in
// revcol/engine/engine.hpp; the parts it is made of in revcol/engine/ (event queue,
// neighbour lists, boundaries, keyed logs, kinematics) and the operator concept in
// revcol/collide/operator.hpp. This header holds the class, its state and its event loop;
// engine_collide.hpp the collisions (pairs, groups, walls at a collision).
// Private to cpp/src: included by the per-dimension engine_<d>d.cpp files only.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "revcol/collide/exact.hpp"
#include "revcol/collide/operator.hpp"
#include "revcol/collide/specular.hpp"
#include "revcol/engine/boundary.hpp"
#include "revcol/engine/engine.hpp"
#include "revcol/engine/limits.hpp"
#include "revcol/engine/init.hpp"
#include "revcol/engine/event_queue.hpp"
#include "revcol/engine/kinematics.hpp"
#include "revcol/engine/logs.hpp"
#include "revcol/engine/neighbours.hpp"
#include "revcol/engine/observe.hpp"
#include "revcol/engine/prefetch.hpp"
#include "revcol/error.hpp"
#include "revcol/rng/clcg4.hpp"
#include "revcol/rng/philox.hpp"
#include "revcol/rng/streams.hpp"

namespace revcol::engine::detail {

inline constexpr double kInf = std::numeric_limits<double>::infinity();
inline constexpr int kMaxGroup = 8;  // particles in one group collision
// The group gate's window: a second collision within a relative kTieWindow of t (collide)
// may make a group; a prediction never skips a candidate within twice that (prune_limit).
inline constexpr double kTieWindow = 1e-9;
// The spatial re-sort of the particles' storage (sort_storage): by default from this many
// particles, after every kResortEvery list renewals per particle (Config::resort overrides).
inline constexpr std::size_t kResortMinN = 32768;
inline constexpr int kResortEvery = 16;

enum Kind : std::int32_t { kWall = 0, kRenew = 1, kColl = 2, kNone = 3 };  // kRenew: neighbour-list renewal

/// One particle's scheduled event (the queue holds its key (t, kind, id)).
struct Ev {
  double t = kInf;              ///< time
  std::int32_t kind = kNone;    ///< Kind
  std::int32_t partner = -1;    ///< particle's slot (collision), 2 axis + (v > 0) (wall) or 0 (renewal)
  std::uint64_t stamp = 0;      ///< the partner's stamp at prediction
};

/// One particle's bookkeeping beside its Particle, one cache line: its scheduled event and
/// what a collision of it reads and writes (the group gate, its counts, its stream's draws),
/// and its id (the particle's storage slot is not its id once sorted, see sort_storage).
/// One record instead of six arrays: the event loop and a collision touch one line per
/// particle, not six (cachegrind, 3D N = 10 976 phi 0.45: 37.8 -> 29.3 misses of a 1 MiB
/// cache per collision, docs/peers.md "Session 20").
struct alignas(64) Book {
  Ev ev;                          ///< the scheduled event
  double second = kInf;           ///< second earliest predicted collision time (the group gate)
  std::uint64_t ncoll = 0;        ///< collisions
  std::int64_t netc = 0;          ///< net collisions, forward minus reverse (wall-log keys)
  std::uint64_t drawn = 0;        ///< draws taken from this particle's stream (per_particle streams)
  unsigned char touching = 0;     ///< a neighbour within the contact tolerance (the group gate)
  std::int32_t id = 0;            ///< the particle's id (its storage slot's occupant)
};
static_assert(sizeof(Book) == 64, "a Book is one cache line");

/// Lexicographic (t, kind, partner) for a wall or a renewal: a canonical earliest candidate
/// whatever the scan order (a collision candidate compares partners by id: EngineImpl::predict).
inline bool earlier(double t, std::int32_t kind, std::int32_t partner, const Ev& e) {
  if (t != e.t) return t < e.t;
  if (kind != e.kind) return kind < e.kind;
  return partner < e.partner;
}

/// The shell in diameters, from the packing fraction phi (see setup_geometry).
double auto_shell(int dim, double phi);

/// Builds the engine for config.mode in dimension Dim (engine_<d>d.cpp).
template <int Dim>
std::unique_ptr<Simulation> make_engine(const Config& c, const std::vector<double>& x, const std::vector<double>& v,
                                        double t0);
/// Restores the engine for s.config.mode in dimension Dim (engine_<d>d.cpp).
template <int Dim>
std::unique_ptr<Simulation> restore_engine(const Snapshot& s);

template <int Dim, PairOperator Op>
class EngineImpl final : public Simulation {
  static_assert(Op::dim == Dim, "the operator's dimension must be the engine's");

 public:
  using Vec = std::array<double, Dim>;
  using Kin = FloatKinematics<Dim>;

  EngineImpl(const Config& c, const std::vector<double>& x, const std::vector<double>& v, double t0, Op op)
      : cfg_(c), n_(x.size() / Dim), op_(std::move(op)) {
    setup_geometry();
    p_.assign(n_, Particle<Dim>{});
    for (std::size_t i = 0; i < n_; ++i) {
      for (int k = 0; k < Dim; ++k) {
        p_[i].x[k] = x[i * Dim + k];
        p_[i].v[k] = v[i * Dim + k];
      }
      p_[i].t = t0;
    }
    clock_ = t0;
    start_ = t0;
    bk_.assign(n_, Book{});
    number_slots();
    make_generators();
    nl_.set_centres(x);  // list centres: where the particles start
    resort_at_ = static_cast<std::uint64_t>(resort_every_) * n_;
    if (resort_every_ > 0) sort_storage();
    build_lists();
    const Diagnostics d = diagnostics();
    e0_ = d.energy;
    p0_ = d.momentum;
    trace_ = CollisionTrace(n_, /*start=*/true);
    rebuild_events();
  }

  EngineImpl(const Snapshot& s, Op op);

  // ---- the Simulation interface -------------------------------------------------------

  RunResult run(std::uint64_t max_collisions, double t_end, const Progress& cb, std::uint64_t every,
                const Poll& poll) override {
    require(!std::isnan(t_end), "end time must not be NaN");
    require(std::isfinite(t_end) || max_collisions != std::numeric_limits<std::uint64_t>::max(),
            "run: give a finite end time or a collision count (an infinite run never returns)");
    const RunResult r = loop(max_collisions, t_end, cb, every, poll, /*reversed=*/false);
    if (obs_) obs_->sync(clock_);
    return r;
  }

  RunResult run_back(std::uint64_t max_collisions, double t_target, const Poll& poll,
                     bool stop_on_divergence) override {
    require(!std::isnan(t_target), "target time must not be NaN");
    require(std::isfinite(t_target) || max_collisions != std::numeric_limits<std::uint64_t>::max(),
            "run_back: give a finite target time or a collision count (an infinite run back never returns)");
    require(t_target <= clock_, [&] {
      return "run_back: target time " + num(t_target) + " is later than the current time " +
             num(clock_);
    });
    const Divergence before = trace_.reason();
    stop_on_divergence_ = stop_on_divergence && before == Divergence::none;  // a new divergence only
    stop_observing();  // observation is forward only (revcol/engine/observe.hpp)
    flip();
    RunResult r;
    try {
      r = loop(max_collisions, -t_target, {}, 0, poll, /*reversed=*/true);
    } catch (...) {
      flip();
      throw;
    }
    flip();
    trace_.check_start(net_);
    // back at the start time, every collision must be undone
    if (clock_ == start_ && net_ != 0) trace_.diverge(net_, Divergence::sequence);
    check_conservation();
    // a reversed run that leaves the forward trajectory can pass particles through each other
    // (a particle's local time is ahead of its clock until its next reversed event, and no
    // collision before it is predicted): the end state says so (issue 59)
    if (trace_.reason() == Divergence::none && !first_overlap().empty()) trace_.diverge(net_, Divergence::overlap);
    r.diverged = before == Divergence::none && trace_.reason() != Divergence::none;
    if (clock_ == 0.0) clock_ = 0.0;  // -0 from the negations reads as 0
    r.time = clock_;
    return r;
  }

  // (every per-particle output is in id order: slot(id) is where particle id is stored)
  std::vector<double> positions() const override {
    std::vector<double> out(n_ * Dim);
    for (std::size_t i = 0; i < n_; ++i)
      for (int k = 0; k < Dim; ++k) out[i * Dim + k] = pos_at(static_cast<int>(slot(i)), k, clock_);
    return out;
  }
  std::vector<double> velocities() const override {
    std::vector<double> out(n_ * Dim);
    for (std::size_t i = 0; i < n_; ++i)
      for (int k = 0; k < Dim; ++k) out[i * Dim + k] = vel_at(static_cast<int>(slot(i)), k, clock_);
    return out;
  }
  std::vector<std::uint64_t> collision_counts() const override {
    std::vector<std::uint64_t> out(n_);
    for (std::size_t i = 0; i < n_; ++i) out[i] = bk_[slot(i)].ncoll;
    return out;
  }
  double time() const override { return clock_; }
  double start_time() const override { return start_; }
  std::size_t size() const override { return n_; }
  const Config& config() const override { return cfg_; }

  Diagnostics diagnostics() const override;  // engine_state.hpp
  Snapshot snapshot() const override;        // engine_state.hpp
  std::string fault() const override;  // engine_check.hpp
  std::string schedule_fault() const;  // engine_check.hpp
  std::string first_overlap() const;   // engine_check.hpp
  void observe(const ObserveConfig& c) override;  // engine_collide.hpp
  const Observer* observer() const override { return observer_.get(); }
  bool observing() const override { return obs_ != nullptr; }
  void stop_observing() override;
  [[gnu::noinline, gnu::cold]] void note_wall(int i);  // observer hooks (engine_collide.hpp)
  [[gnu::noinline, gnu::cold]] void note_pair(int a, int b);

  std::size_t memory_bytes() const override {
    return n_ * (sizeof(Particle<Dim>) + sizeof(Book)) + slot_.capacity() * sizeof(std::int32_t) +
           (rad_.capacity() + cfg_.diameters.capacity() + mass_.capacity() + cfg_.masses.capacity()) * sizeof(double) +
           nl_.memory_bytes() + queue_.memory_bytes() + log_.bytes() + pre_.bytes() + wlog_.bytes() + trace_.bytes() +
           clcg_.size() * sizeof(rng::CLCG4);
  }

 private:
  void setup_geometry();
  bool adjacent() const { return nl_.adjacent(); }  // a constant false in 2D and 3D
  void build_lists();
  double pos_at(int j, int k, double t) const {
    return field_ ? Kin::pos_at(p_[j], k, t, g_.data()) : Kin::pos_at(p_[j], k, t);
  }
  // Component k of j's velocity at t (a field changes it between events).
  double vel_at(int j, int k, double t) const { return field_ ? Kin::vel_at(p_[j], k, t, g_.data()) : p_[j].v[k]; }
  template <class F>
  void for_neighbours(int i, F&& f) const {
    nl_.for_neighbours(i, f, [&](int j) { __builtin_prefetch(&p_[j]); });
  }
  static constexpr int kPrefetchNext = 6;  // the loop prefetches the Books of this many likely next tops
  static constexpr double kWrap = 0.25;  // 1D ring: a rod is wrapped kWrap D past the box's end
                                         // (a mixture: kWrap times the smallest diameter, wrap_)

  // ---- prediction ---------------------------------------------------------------------

  // ---- sizes (a mixture: rad_, each slot's radius; one size: rad_ empty) ----------------

  // Slot i's radius for the walls (one size: Boundaries' own D / 2).
  double radius(int i) const { return rad_.empty() ? Boundaries<Dim>::kOwn : rad_[static_cast<std::size_t>(i)]; }
  // The squared contact distance of slots i and j, and the contact tolerance of a pair whose
  // squared contact distance is s2 (r^2 - s2 <= 2 group_tol s2: |r| within group_tol of it).
  double sigma2(int i, int j) const {
    if (rad_.empty()) return sigma2_;
    const double s = rad_[static_cast<std::size_t>(i)] + rad_[static_cast<std::size_t>(j)];
    return s * s;
  }
  double contact_tol(double s2) const { return rad_.empty() ? contact_tol_ : 2.0 * cfg_.group_tol * s2; }
  // A field's potential energy at the clock: per particle m |g_k| times its height above the
  // wall the field pulls it to (-m g_k x_k, or m g_k (L_k - x_k)); >= 0, in id order.
  double potential() const {
    double u = 0.0;
    for (std::size_t i = 0; i < n_; ++i) {
      const int j = static_cast<int>(slot(i));
      for (int k = 0; k < Dim; ++k)
        if (g_[k] != 0.0) {
          const double x = pos_at(j, k, clock_);
          u += mass(j) * (g_[k] < 0.0 ? -g_[k] * x : g_[k] * (box_.length(k) - x));
        }
    }
    return u;
  }
  // The energy at the clock (sum m v^2 / 2, plus the field's potential) and the momentum sum m v
  // into p, summed in id order (their bits do not depend on storage; unit masses multiply by 1).
  double energy_momentum(std::array<double, 3>& p) const {
    double e = 0.0;
    for (std::size_t i = 0; i < n_; ++i) {
      const int j = static_cast<int>(slot(i));
      const double m = mass(j);
      for (int k = 0; k < Dim; ++k) {
        const double vk = vel_at(j, k, clock_);
        e += 0.5 * m * vk * vk;
        p[k] += m * vk;
      }
    }
    return field_ ? e + potential() : e;
  }
  // Unequal masses (mass_, each slot's; empty: all 1).
  double mass(int i) const { return mass_.empty() ? 1.0 : mass_[static_cast<std::size_t>(i)]; }
  // The radii in id order (the observer's species).
  std::vector<double> radii() const {
    std::vector<double> r(n_, 0.5 * cfg_.diameter);
    for (std::size_t i = 0; i < cfg_.diameters.size(); ++i) r[i] = 0.5 * cfg_.diameters[i];
    return r;
  }
  // A new or resumed observer learns the masses, then the species (by size, then mass), then
  // the field (one axis: Observer::set_field follows the parabolas).
  void describe_particles(Observer& o) const {
    if (!cfg_.masses.empty()) o.set_masses(cfg_.masses);
    if (!cfg_.diameters.empty() || !cfg_.masses.empty()) o.set_sizes(radii());
    if (!field_) return;
    int axis = -1;
    for (int k = 0; k < Dim; ++k)
      if (g_[k] != 0.0) {
        require(axis < 0, "observe: a field along more than one axis is not observed (the observer follows a "
                          "parabola along one axis); take frames (positions, velocities) instead");
        axis = k;
      }
    o.set_field(axis, g_[static_cast<std::size_t>(axis)]);
  }

  // i's earliest event: a wall, its list renewal (in 1D on a ring: its wrap), or a
  // collision with a listed particle; also its second earliest collision time and whether
  // a neighbour touches it (the group gate). A mixture's scan reads each pair's contact
  // distance; one size's reads no radius (a template: one branch per prediction).
  void predict(int i) {
    if (field_) [[unlikely]] {
      if (rad_.empty()) predict_sized<false, true>(i);
      else predict_sized<true, true>(i);
    } else if (rad_.empty()) {
      predict_sized<false, false>(i);
    } else {
      predict_sized<true, false>(i);
    }
  }
  template <bool Mixed, bool Field>
  void predict_sized(int i);  // engine_predict.hpp
  // Under a field along axis k: i's next wall on k, the floor or the ceiling, into `best`;
  // in a reversed run, a wall i touches and approaches at the clock as on a field-free axis.
  void field_wall(int i, int k, double r_own, Ev& best);  // engine_predict.hpp

  // Candidates provably later than this are skipped before their square root. The margin,
  // 2 kTieWindow (max(|t|, |clock|) + 1), is twice the group gate's window (collide): a collision
  // time the gate compares (second_) is never skipped, and rounding in the test (a few
  // ulps) is far inside it.
  double prune_limit(double t) const {
    if (t == kInf) return kInf;
    return t + 2.0 * kTieWindow * (std::max(std::fabs(t), std::fabs(clock_)) + 1.0);
  }

  // ---- the event queue (revcol/engine/event_queue.hpp), key (t, kind, id) ----------------
  // The queue is indexed by slot, and each slot's particle id breaks its ties: the order does
  // not depend on where particles are stored. A re-sort of the storage rebuilds it.

  void build_queue();
  void update(int i) { queue_.set(i, bk_[i].ev.t, bk_[i].ev.kind, bk_[i].id); }  // the id: slot i's tie
  void rebuild_events() {
    for (std::size_t i = 0; i < n_; ++i) predict(static_cast<int>(i));
    build_queue();
  }
  void repredict(int i) {
    predict(i);
    update(i);
  }

  // ---- storage order --------------------------------------------------------------------
  // Particle id is stored in slot slot(id) (its Particle, Book and list centre); the Book
  // names its id back. Every array of the engine's state is per slot, and everything that
  // decides the trajectory reads ids: the queue's key (t, kind, id), a prediction's choice
  // between equal times, the pair's order and its stream, a group's order, the logs' keys,
  // the collision trace, the observer. Lists list slots, sorted: a scan's order is not an
  // input (a prediction's choice is canonical). So where a particle is stored changes no bit
  // of a run, and the storage can follow the particles through space: a gas that diffused
  // from a sorted start scans lists whose entries lie all over memory.

  void number_slots();
  // The slot of particle id.
  std::size_t slot(std::size_t id) const { return slot_.empty() ? id : static_cast<std::size_t>(slot_[id]); }

  void sort_storage();

  [[gnu::noinline, gnu::cold]] void resort();

  // ---- state changes ------------------------------------------------------------------

  void advance(int i, double t) {
    if (field_) [[unlikely]] advance_field(i, t);
    else Kin::advance(p_[i], t);
  }
  [[gnu::noinline, gnu::cold]] void advance_field(int i, double t) { Kin::advance(p_[i], t, g_.data()); }

  void flip();

  // A wall event on axis k: axis k's own reflection (Boundaries::reflect_at).
  void wall_event(int i, const Ev& e) {
    advance(i, e.t);
    const Reflection mask = wall_mask(i, e.partner / 2, e.t);
    if (rev_) {
      // arriving at a wall at the instant of a logged collision: only W2's reflections are
      // undone here; a wall that collision left untouched waits for it
      const long m = wall_entry(i);
      if (m >= 0) {
        if (!w2_covers(m, mask)) {
          repredict(i);
          return;
        }
        wlog_.clear(m, std::uint64_t{mask} << 8);
      }
    }
    flip_mask(i, mask);
    repredict(i);
  }

  // The list renewal (nothing physical changes: no stamp) and i's centre moved to where i is at
  // t (engine_predict.hpp)
  void renew_event(int i, const Ev& e);
  void move_centre(int i, double t);

  // ---- random numbers -----------------------------------------------------------------

  std::size_t stream_count() const { return cfg_.streams == rng::StreamPolicy::single ? 1 : n_; }
  // The stream a collision whose particle of smallest id is stored in slot `s` draws from.
  int stream_of(int s) const { return cfg_.streams == rng::StreamPolicy::single ? 0 : bk_[s].id; }
  // Draws taken from that stream: in the slot's Book, or the single stream's count.
  std::uint64_t& drawn_at(int s) { return cfg_.streams == rng::StreamPolicy::single ? drawn1_ : bk_[s].drawn; }

  // Draws taken from stream k (its particle's Book, or the single stream's count).
  std::uint64_t& drawn(int stream) {
    return cfg_.streams == rng::StreamPolicy::single ? drawn1_ : bk_[slot(static_cast<std::size_t>(stream))].drawn;
  }
  std::uint64_t drawn(int stream) const {
    return cfg_.streams == rng::StreamPolicy::single ? drawn1_ : bk_[slot(static_cast<std::size_t>(stream))].drawn;
  }
  // CLCG4 only: each stream's state, from the family and the draws taken (drawn).
  void make_generators();
  // One number from a stream whose draw count is `count`, forward (the next) or reversed
  // (the last one, stepped back).
  double draw(int stream, std::uint64_t& count, bool reversed);

  // ---- collisions (engine_collide.hpp) --------------------------------------------------

  struct Group;  // members of a contact component, with image offsets and edges
  void gather(int a, int b, const Vec& s, double t, Group& g) const;
  bool collide(int a, int b, double t, bool reversed);
  PairV<Dim> apply_pair(const PairV<Dim>& in, const Vec& r, int s, bool reversed);
  PairV<Dim> to_relative(const PairV<Dim>& v, int a, int b, Vec& vcm) const;
  PairV<Dim> from_relative(const PairV<Dim>& u, int a, int b, const Vec& vcm) const;
  bool equal_masses(const Group& g) const;
  bool group_collide(Group& g, double t, bool reversed);
  bool group_operator(Group& g, const int* order, double t, bool reversed, const Reflection* w1);
  Reflection touch_walls(int i);
  void flip_mask(int i, Reflection mask);
  void set_velocity(int i, const Vec& v, Reflection mask);
  Reflection wall_mask(int i, int k, double t) const;
  bool w2_covers(long m, Reflection mask) const;
  bool touches_wall(int i) const;
  long wall_entry(int i) const { return wlog_.entry(bk_[i].id, bk_[i].netc, rev_ ? -clock_ : clock_); }
  void finish_collision(int i, bool reversed) {
    ++bk_[i].ncoll;
    ++p_[i].stamp;
    bk_[i].netc += reversed ? -1 : 1;
  }
  void validate_collision(const int* slots, int n) const;
  void trace_collision(const int* ids, int n, bool reversed);
  void trace_point(bool reversed);
  void check_conservation();

  // ---- the event loop -----------------------------------------------------------------

  // The likely next top g (the queue's second event) is the next top 72-77% of the time (3D,
  // N = 10 976). Its Book came in with the last event's for_next, so its partner is known a
  // whole event before g is popped. g's Particle and list centre (every event reads them),
  // and for a collision the partner's Particle and Book (the stamp check, collide's id order
  // and group gate) and centre (the pair's image; the predictions' renewal times), load
  // meanwhile. Collide's wait on them fell from half its samples to a fifth (perf, docs/peers.md
  // "Session 31"). A prefetch changes no value: the same bits.
  void prefetch_collision(int g) const {
    if (g < 0) return;
    prefetch(&p_[g]);
    prefetch(nl_.centre(g));
    const Ev& eg = bk_[g].ev;
    if (eg.kind != kColl) return;
    prefetch(&p_[eg.partner]);
    prefetch(&bk_[eg.partner]);
    prefetch(nl_.centre(eg.partner));
  }

  RunResult loop(std::uint64_t max_collisions, double t_end, const Progress& cb, std::uint64_t every,
                 const Poll& poll, bool reversed) {
    RunResult res;
    double t_last = clock_;
    bool done_count = max_collisions == 0;
    std::uint32_t since_poll = 0;
    while (true) {
      if (poll && ++since_poll == kPollEvents) {  // Ctrl-C: stop as a collision count would
        since_poll = 0;
        if (!done_count && !poll()) {
          res.interrupted = true;
          done_count = true;
        }
      }
      const int i = queue_.top();
      if (i < 0) break;  // nothing scheduled (never: every particle has an event, maybe at infinity)
      const Ev e = bk_[i].ev;
      // the next top is among the bucket's other events 88% of the time (3D, phi 0.45): its
      // Book arrives while this event runs. The wait on the top's Book fell from 8% of the
      // run's samples to 1% (perf, docs/peers.md "Session 28")
      queue_.for_next(kPrefetchNext, [&](int j) { prefetch(&bk_[j]); });
      prefetch_collision(queue_.second());
      if (done_count) {
        // finish the instant of the last collision, then stop half way to the next event
        if (e.t > t_last || e.t == kInf) {
          double te = e.t == kInf ? t_last : t_last + 0.5 * (e.t - t_last);
          if (te > t_end) te = t_end;
          if (te > clock_) clock_ = te;
          break;
        }
      } else if (e.t > t_end || e.t == kInf) {
        if (t_end != kInf && t_end > clock_) clock_ = t_end;
        break;
      }
      clock_ = e.t;
      ++res.events;
      ++counters_.events;
      if (e.kind == kWall) {
        wall_event(i, e);
      } else if (e.kind == kRenew) {
        renew_event(i, e);
        if (counters_.list_renewals >= resort_at_ && resort_every_ > 0) [[unlikely]] resort();
      } else if (e.kind == kColl) {
        if (p_[e.partner].stamp != e.stamp) {
          ++counters_.invalid_events;
          repredict(i);
          continue;
        }
        if (!collide(i, e.partner, e.t, reversed)) continue;
        ++res.collisions;
        if (reversed) {
          --net_;
          ++counters_.reverse_collisions;
        } else {
          ++net_;
          ++counters_.forward_collisions;
        }
        t_last = e.t;
        if (trace_.on_grid(net_)) trace_point(reversed);
        if (res.collisions >= max_collisions) done_count = true;
        if (reversed && stop_on_divergence_ && trace_.reason() != Divergence::none) done_count = true;
        if (cb && every > 0 && res.collisions % every == 0 && !cb(res.collisions)) {
          res.interrupted = true;
          done_count = true;
        }
      } else {
        break;
      }
    }
    res.time = clock_;
    return res;
  }

  Config cfg_;
  std::size_t n_;
  Op op_;                                  // the pair operator, chosen once (make_engine)
  Boundaries<Dim> box_;
  bool walled_ = true;                     // box_.any_walls(): predict tests no wall without
  double sigma2_ = 1.0, contact_tol_ = 0.0;  // one size's squared contact distance and tolerance
  std::vector<double> rad_;                // a mixture: each slot's radius (Config::diameters / 2); empty: one size
  double wrap_ = 0.0;                      // 1D ring: kWrap times the smallest diameter (setup_geometry)
  std::vector<double> mass_;               // unequal masses: each slot's (Config::masses); empty: all 1
  bool field_ = false;                     // a uniform field (Config::gravity): parabolas between events
  std::array<double, Dim> g_{};            // its components
  double gn_ = 0.0;                        // its magnitude
  double total_mass_ = 0.0;                // sum of the masses (n for unit masses)
  double shell_ = 0.0, renew_h_ = 0.0, renew_h2_ = 0.0;  // the neighbour lists
  std::vector<Particle<Dim>> p_;
  NeighbourLists<Dim> nl_;
  static_assert(limits::max_particles(Dim) <= NeighbourLists<Dim>::kMaxIds,
                "the engine's limit on N must fit the lists' packed ids");
  EventQueue<double> queue_;               // one event per slot, key (t, kind, the slot's particle id)
  std::vector<Book> bk_;                   // per slot: its event, group gate, counts, draws and id
  std::vector<std::int32_t> slot_;         // per id: its slot (held when re-sorting: slot())
  int resort_every_ = 0;                   // list renewals per particle between re-sorts (0: never)
  std::uint64_t resort_at_ = 0;            // the renewal count of the next re-sort
  std::uint64_t resorts_ = 0;              // re-sorts done by run / run_back
  std::uint64_t drawn1_ = 0;               // draws taken from the single stream (StreamPolicy::single)
  std::vector<rng::CLCG4> clcg_;             // CLCG4 only: one generator per stream
  double clock_ = 0.0, start_ = 0.0;
  std::int64_t net_ = 0;
  RareLog log_;
  std::uint64_t log_offset_ = 0;
  ExactPreLog pre_;
  WallLog wlog_;
  bool rev_ = false;                // inside a reversed run
  Counters counters_;
  double e0_ = 0.0;
  std::array<double, 3> p0_{};
  CollisionTrace trace_;                 // divergence detection for run_back (revcol/engine/trace.hpp)
  bool stop_on_divergence_ = false;      // run_back stops where the trace finds a divergence
  std::unique_ptr<Observer> observer_;  // the running or last observation (observe.hpp)
  Observer* obs_ = nullptr;             // observer_ while it runs, else null: the one test per velocity change
};

}  // namespace revcol::engine::detail
