// EngineImpl's state: diagnostics() (energy, momentum, drifts, logs, counters, the collision
// trace), snapshot() (the full state a checkpoint holds) and the constructor that resumes one,
// and the cold set-up steps (geometry, lists, the storage re-sort, the queue, the reversal's
// flip). Private to cpp/src: included by engine_build.hpp beside engine_impl.hpp and
// engine_collide.hpp.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "engine_impl.hpp"

namespace revcol::engine::detail {

template <int Dim, PairOperator Op>
Diagnostics EngineImpl<Dim, Op>::diagnostics() const {
  Diagnostics d;
  d.energy = energy_momentum(d.momentum);
  if (field_) d.potential = potential();
  d.energy_drift = e0_ > 0 ? (d.energy - e0_) / e0_ : 0.0;
  double dp = 0.0;
  for (int k = 0; k < Dim; ++k) dp += (d.momentum[k] - p0_[k]) * (d.momentum[k] - p0_[k]);
  d.momentum_drift = e0_ > 0 ? std::sqrt(dp) / std::sqrt(2.0 * e0_ * total_mass_) : 0.0;
  d.log_bytes = log_.bytes() + pre_.bytes() + wlog_.bytes();
  d.wall_log_entries = wlog_.entries();
  d.log_pushed = log_.pushed() + log_offset_;
  d.exact_pre_pushed = pre_.pushed();
  d.exact_pre_entries = pre_.entries();
  std::uint64_t parts = 0;
  for (const Book& b : bk_) parts += b.ncoll;
  d.collisions_per_particle = static_cast<double>(parts) / static_cast<double>(n_);
  d.net_collisions = net_;
  d.divergence = trace_.reason();
  d.diverged_at = trace_.diverged_at();
  d.verified_at = trace_.verified_at();
  d.trace_reorderings = trace_.reorderings();
  d.trace_stride = trace_.stride();
  d.trace_points = trace_.points();
  d.clock_deviation = trace_.clock_deviation();
  d.storage_resorts = resorts_;
  d.counters = counters_;
  return d;
}

template <int Dim, PairOperator Op>
Snapshot EngineImpl<Dim, Op>::snapshot() const {
  Snapshot s;
  s.config = cfg_;
  s.n = n_;
  s.time = clock_;
  s.start_time = start_;
  s.net_collisions = net_;
  s.x.resize(n_ * Dim);
  s.v.resize(n_ * Dim);
  s.centre.resize(n_ * Dim);
  s.t_local.resize(n_);
  s.stamp.resize(n_);
  s.ev_t.resize(n_);
  s.ev_kind.resize(n_);
  s.ev_partner.resize(n_);
  s.ev_stamp.resize(n_);
  s.ncoll.resize(n_);
  s.netc.resize(n_);
  s.second.resize(n_);
  s.touching.resize(n_);
  s.cell.resize(nl_.cells().size());
  for (std::size_t i = 0; i < n_; ++i) {  // per id: particle i is in slot j
    const std::size_t j = slot(i);
    for (int k = 0; k < Dim; ++k) {
      s.x[i * Dim + k] = p_[j].x[k];
      s.v[i * Dim + k] = p_[j].v[k];
      s.centre[i * Dim + k] = nl_.centre(static_cast<int>(j))[k];
      s.cell[i * Dim + k] = nl_.cells()[j * Dim + k];
    }
    s.t_local[i] = p_[j].t;
    s.stamp[i] = p_[j].stamp;
    const Book& b = bk_[j];
    s.ev_t[i] = b.ev.t;
    s.ev_kind[i] = b.ev.kind;
    s.ev_partner[i] = b.ev.kind == kColl ? bk_[static_cast<std::size_t>(b.ev.partner)].id : b.ev.partner;
    s.ev_stamp[i] = b.ev.stamp;
    s.ncoll[i] = b.ncoll;
    s.netc[i] = b.netc;
    s.second[i] = b.second;
    s.touching[i] = b.touching;
  }
  s.rng.resize(stream_count());
  for (std::size_t k = 0; k < s.rng.size(); ++k) s.rng[k] = drawn(static_cast<int>(k));
  s.log_cells = log_.cells();
  s.log_pushed = log_.pushed() + log_offset_;
  WallLog::fields(wlog_, [&](const char* key, const auto& field) { s.field(key, field); });
  ExactPreLog::fields(pre_, [&](const char* key, const auto& field) { s.field(key, field); });
  s.trace = trace_.save();
  s.counters = counters_;
  s.energy0 = e0_;
  s.momentum0 = p0_;
  if (obs_) obs_->save(s.observer, s.observer_counts);  // a running observation resumes (observe.hpp)
  return s;
}

// A simulation resuming a snapshot bit for bit.
template <int Dim, PairOperator Op>
EngineImpl<Dim, Op>::EngineImpl(const Snapshot& s, Op op) : cfg_(s.config), n_(s.n), op_(std::move(op)) {
  setup_geometry();
  p_.assign(n_, Particle<Dim>{});
  for (std::size_t i = 0; i < n_; ++i) {
    for (int k = 0; k < Dim; ++k) {
      p_[i].x[k] = s.x[i * Dim + k];
      p_[i].v[k] = s.v[i * Dim + k];
    }
    p_[i].t = s.t_local[i];
    p_[i].stamp = s.stamp[i];
  }
  clock_ = s.time;
  start_ = s.start_time;
  net_ = s.net_collisions;
  bk_.assign(n_, Book{});
  number_slots();
  for (std::size_t i = 0; i < n_; ++i) {
    bk_[i].ncoll = s.ncoll[i];
    bk_[i].netc = s.netc[i];
  }
  require(s.rng.size() == stream_count(), "snapshot: rng must hold one draw count per stream");
  for (std::size_t k = 0; k < s.rng.size(); ++k) drawn(static_cast<int>(k)) = s.rng[k];
  make_generators();
  // list centres (cells and lists follow from them); a checkpoint without them (written
  // before the neighbour lists) starts them where the particles are and predicts anew
  const bool old_format = s.centre.empty();
  nl_.set_centres(old_format ? positions() : s.centre);
  // each centre where its particle is, wrapped into the box as a renewal wraps it (issue 59:
  // a position at the clock just outside a periodic box made a centre outside it)
  if (old_format)
    for (std::size_t i = 0; i < n_; ++i) move_centre(static_cast<int>(i), clock_);
  WallLog::fields(wlog_, [&](const char* key, auto& field) { s.field(key, field); });
  ExactPreLog::fields(pre_, [&](const char* key, auto& field) { s.field(key, field); });
  double vmax = 0.0;
  for (double q : s.v) vmax = std::max(vmax, std::fabs(q));
  for (std::size_t i = 0; i < n_; ++i) {
    require(s.ev_kind[i] >= kWall && s.ev_kind[i] <= kNone, "snapshot: ev_kind must be 0..3 (wall, renewal, collision, none)");
    // a scheduled event lies at or after the clock and within the clock's range (issue 17's fuzz
    // suite: event times of +-2^40 sent run() into an endless stream of events)
    require(s.ev_t[i] == kInf || (s.ev_t[i] >= s.time && limits::clock_fits(s.ev_t[i], cfg_.diameter, vmax)),
            "snapshot: ev_t: an event time before the clock or beyond the clock's range");
    require(!std::isnan(s.second[i]), "snapshot: second (a second event time) is NaN");
    require(s.ev_kind[i] != kColl || (s.ev_partner[i] >= 0 && static_cast<std::size_t>(s.ev_partner[i]) < n_),
            "snapshot: ev_partner of a collision outside [0, n)");
    // a wall event's partner is 2 axis + (upper wall), on an axis with walls (issue 17: a forged
    // partner wrote out of bounds)
    if (s.ev_kind[i] == kWall) {  // (issue 59: one message said "an axis without walls" for both cases)
      require(s.ev_partner[i] >= 0 && s.ev_partner[i] < 2 * Dim, [&] {
        return "snapshot: ev_partner of a wall event must be 2 axis + (upper wall), in [0, " + std::to_string(2 * Dim) +
               "), got " + std::to_string(s.ev_partner[i]);
      });
      require(has_walls(cfg_.boundary[static_cast<std::size_t>(s.ev_partner[i] / 2)]), [&] {
        return "snapshot: ev_partner: a wall event on axis " + std::to_string(s.ev_partner[i] / 2) + ", which has no walls";
      });
    }
    require(!std::isnan(s.ev_t[i]), "snapshot: ev_t (an event time) is NaN");
    bk_[i].ev = Ev{s.ev_t[i], static_cast<std::int32_t>(s.ev_kind[i]), static_cast<std::int32_t>(s.ev_partner[i]),
                s.ev_stamp[i]};
    bk_[i].second = s.second[i];
    bk_[i].touching = s.touching[i] != 0;
  }
  for (std::uint64_t c : s.log_cells) log_.push(c);
  log_offset_ = s.log_pushed - log_.pushed();
  counters_ = s.counters;
  e0_ = s.energy0;
  p0_ = s.momentum0;
  // absent in checkpoints written before the trace: a new one (nothing below is checked)
  trace_ = s.trace.empty() ? CollisionTrace(n_, s.net_collisions == 0) : CollisionTrace::load(s.trace, n_);
  resort_at_ = counters_.list_renewals + static_cast<std::uint64_t>(resort_every_) * n_;
  if (resort_every_ > 0) sort_storage();  // the snapshot's ids (ev_partner too) become slots here
  build_lists();
  if (old_format) rebuild_events();
  else build_queue();
  require(!s.observer.empty() || s.observer_counts.empty(), "snapshot: observer_counts without observer");
  if (!s.observer.empty()) {  // a running observation resumes (revcol/engine/observe.hpp)
    std::array<bool, 3> walls{};
    for (int k = 0; k < Dim; ++k) walls[k] = box_.walls(k);
    // (in a field the snapshot's velocities are at each particle's own time: the observer's
    // segments are checked against those at the clock)
    observer_ = std::make_unique<Observer>(s.observer, s.observer_counts, Dim, field_ ? velocities() : s.v, clock_, cfg_.box, walls,
                                           cfg_.diameter);
    describe_particles(*observer_);
    obs_ = observer_.get();
  }
}

// ---- geometry ------------------------------------------------------------------------
// Listed centres must be within D + shell < L / 2, so that each listed pair has one
// nearest image: a small periodic box (L >= 3 D) takes a thinner shell. A particle stays
// within h = (shell - 1e-3 D) / 2 of its list centre (revcol/engine/neighbours.hpp).
template <int Dim, PairOperator Op>
void EngineImpl<Dim, Op>::setup_geometry() {
  sigma2_ = cfg_.diameter * cfg_.diameter;
  field_ = false;
  gn_ = 0.0;
  for (int k = 0; k < Dim; ++k) {
    g_[k] = cfg_.gravity[k];
    field_ = field_ || g_[k] != 0.0;
    gn_ += g_[k] * g_[k];
  }
  gn_ = std::sqrt(gn_);
  // 1D ring: stored positions stay within wrap_ of the box, so the rod beside a rod lies at
  // least its contact distance >= the smallest diameter > 2 wrap_ away (NeighbourLists::right_code)
  double smallest = cfg_.diameter;
  for (const double d : cfg_.diameters) smallest = std::min(smallest, d);
  wrap_ = kWrap * smallest;
  contact_tol_ = 2.0 * cfg_.group_tol * sigma2_;
  box_ = Boundaries<Dim>(cfg_);
  walled_ = box_.any_walls();
  double vol = 1.0;  // in diameters^d
  for (int k = 0; k < Dim; ++k) vol *= cfg_.box[k] / cfg_.diameter;
  // the particles' volume in largest ones' (a mixture: the sum of (D_i / D)^d, n when all are D)
  double parts = static_cast<double>(n_);
  if (!cfg_.diameters.empty()) {
    parts = 0.0;
    for (const double d : cfg_.diameters) {
      const double q = d / cfg_.diameter;
      parts += Dim == 1 ? q : Dim == 2 ? q * q : q * q * q;
    }
  }
  const double phi = parts * particle_volume(Dim, 1.0) / vol;
  shell_ = (cfg_.shell > 0.0 ? cfg_.shell : auto_shell(Dim, phi)) * cfg_.diameter;
  for (int k = 0; k < Dim; ++k)
    if (box_.periodic(k)) shell_ = std::min(shell_, 0.9 * (0.5 * cfg_.box[k] - cfg_.diameter));
  renew_h_ = 0.5 * (shell_ - 1e-3 * cfg_.diameter);
  renew_h2_ = renew_h_ * renew_h_;
  nl_.setup(n_, box_, cfg_.diameter + shell_, Dim == 1 && (!box_.periodic(0) || n_ >= 3));
  // 1D keeps its rods in id order: lists of the rods beside, no cells to sort by
  resort_every_ = Dim == 1 ? 0 : cfg_.resort >= 0 ? cfg_.resort : (n_ >= kResortMinN ? kResortEvery : 0);
}

template <int Dim, PairOperator Op>
void EngineImpl<Dim, Op>::build_lists() {
  nl_.build([&](int j) { return pos_at(j, 0, clock_); });
}

// Slots in id order (construction, restore). slot_ is held only by an engine that
// re-sorts (empty otherwise: slot i holds id i, and nothing is held for it).
template <int Dim, PairOperator Op>
void EngineImpl<Dim, Op>::number_slots() {
  if (resort_every_ > 0) slot_.resize(n_);
  else std::vector<std::int32_t>().swap(slot_);
  for (std::size_t i = 0; i < n_; ++i) {
    if (resort_every_ > 0) slot_[i] = static_cast<std::int32_t>(i);
    bk_[i].id = static_cast<std::int32_t>(i);
  }
  rad_.clear();
  for (const double d : cfg_.diameters) rad_.push_back(0.5 * d);  // a mixture: slot i holds id i
  mass_ = cfg_.masses;
  total_mass_ = 0.0;
  for (std::size_t i = 0; i < n_; ++i) total_mass_ += mass_.empty() ? 1.0 : mass_[i];
}

// Stores the particles in the order of their list centres' cells (the grid's row-major
// order; ids within a cell): a list scan then reads a few runs of nearby slots. Moves
// Particles, Books (a scheduled collision's partner slot follows its particle) and centres;
// the caller rebuilds the lists and the queue.
template <int Dim, PairOperator Op>
void EngineImpl<Dim, Op>::sort_storage() {
  const std::size_t cells = nl_.cell_count();
  std::vector<std::uint32_t> start(cells + 1, 0);
  std::vector<std::uint32_t> key(n_);
  for (std::size_t j = 0; j < n_; ++j) {
    key[j] = static_cast<std::uint32_t>(nl_.cell_key(static_cast<int>(j)));
    ++start[key[j] + 1];
  }
  for (std::size_t c = 0; c < cells; ++c) start[c + 1] += start[c];
  std::vector<std::int32_t> to(n_);  // old slot -> new slot
  for (std::size_t id = 0; id < n_; ++id) {
    const std::size_t j = static_cast<std::size_t>(slot_[id]);
    to[j] = static_cast<std::int32_t>(start[key[j]]++);
  }
  permute_in_place(p_, to);
  permute_in_place(bk_, to);
  if (!rad_.empty()) permute_in_place(rad_, to);
  if (!mass_.empty()) permute_in_place(mass_, to);
  for (std::size_t j = 0; j < n_; ++j) {
    Book& q = bk_[j];
    if (q.ev.kind == kColl) q.ev.partner = to[static_cast<std::size_t>(q.ev.partner)];
    slot_[static_cast<std::size_t>(q.id)] = static_cast<std::int32_t>(j);
  }
  nl_.permute_centres(to);
}

// The periodic re-sort (every resort_every_ renewals per particle), between two events.
template <int Dim, PairOperator Op>
[[gnu::noinline, gnu::cold]] void EngineImpl<Dim, Op>::resort() {
  sort_storage();
  build_lists();
  build_queue();  // the same keys in new slots: the same order (the keys are distinct)
  resort_at_ = counters_.list_renewals + static_cast<std::uint64_t>(resort_every_) * n_;
  ++resorts_;
}

// Negates velocities, local times and the clock; rebuilds every prediction.
template <int Dim, PairOperator Op>
void EngineImpl<Dim, Op>::flip() {
  for (auto& q : p_) {
    for (int k = 0; k < Dim; ++k) q.v[k] = -q.v[k];
    q.t = -q.t;
  }
  clock_ = -clock_;
  rev_ = !rev_;
  for (auto& q : p_) ++q.stamp;
  rebuild_events();
}

// Every event into the queue (construction, restore, reversal): the window starts at the
// clock, ~8 events per bucket from the median distance of the events ahead.
template <int Dim, PairOperator Op>
void EngineImpl<Dim, Op>::build_queue() {
  std::vector<double> ahead;
  ahead.reserve(n_);
  for (std::size_t i = 0; i < n_; ++i)
    if (bk_[i].ev.t < kInf) ahead.push_back(bk_[i].ev.t - clock_);
  double width = 0.0;
  if (!ahead.empty()) {
    auto mid = ahead.begin() + ahead.size() / 2;
    std::nth_element(ahead.begin(), mid, ahead.end());
    width = 8.0 * 2.0 * *mid / static_cast<double>(ahead.size());
  }
  if (!(width > 0.0) || !std::isfinite(width)) width = 1.0;
  queue_.reset(n_, clock_, width, /*ties=*/!slot_.empty());
  for (std::size_t i = 0; i < n_; ++i) update(static_cast<int>(i));
}

}  // namespace revcol::engine::detail
