// The lattice engine's state: load and restore a snapshot, take one, rebuild the search and
// the queue, flip the frame for a reversed run, the neighbour search's choice, memory, and the
// forward run's undo journal (an engine error mid-run restores the state).
// Part of BasicEngine (revcol/lattice/engine_core.hpp, which declares it and explains the
// design); included by engine_impl.hpp, which the instantiating sources include.
//
// State: per particle an anchor position (integer, wrapped into the box) at an anchor tick, an
// integer velocity, a line version (bumped when the line changes), a Philox stream counter, a
// bits-back integer X (about 128 bits) and a collision count; the clock; the rare log; the
// collision count. Free flight is exact: x(t) = x_a + v (t - t_a), wrapped on periodic axes.
// Every collision reads and writes only its particles' state: the pair operator runs on the
// drawing particle's X (the lower index i of the pair), and the rare log and the group entries
// are keyed by (particle, that particle's collision count after the collision), never by a global
// index. So collisions in different places commute, and a state cut into regions is the same
// state (ARCHITECTURE.md, "Per-particle state"); the global collision count is the sum.
// A mixture adds each particle's radius (sizes.hpp), fixed for the run.
//
#pragma once
#include <algorithm>
#include <cmath>
#include <limits>

#include "revcol/lattice/engine_core.hpp"

namespace revcol::lattice {

// The rare log of a snapshot against its per-particle counts: every key (particle, count) names
// a collision the particle has had (1 <= count <= its count), no key twice, entries and groups
// in key order, and the counts add up: each pair collision counts for two particles, each group
// for its members, so sum(counts) = 2 collisions + sum over groups (members - 2).
template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::check_log(const Snapshot& s) const {
  const std::size_t n = s.x.size();
  require(s.particle_collisions.size() == n, "lattice snapshot: particle_collisions must hold one count per particle");
  require(s.bits_size.size() == n, "lattice snapshot: bits_size must hold one bits-back integer's size per particle");
  {
    u128 words = 0;
    for (std::uint64_t k : s.bits_size) words += k;
    require(words == s.bits.size(), "lattice snapshot: bits must hold the words bits_size says, no more, no fewer");
  }
  std::map<LogKey, int> seen;  // 0 a redraw entry, 1 a group member
  auto key_ok = [&](std::size_t p, std::uint64_t c) { return p < n && c >= 1 && c <= s.particle_collisions[p]; };
  for (std::size_t k = 0; k < s.log.size(); ++k) {
    const LogEntry& e = s.log[k];
    require(key_ok(e.particle, e.count), "lattice snapshot: a rare-log entry names a collision its particle has not had");
    require(k == 0 || LogKey{s.log[k - 1].particle, s.log[k - 1].count} < LogKey{e.particle, e.count},
            "lattice snapshot: rare-log entries must be in (particle, count) order, each once");
    seen.emplace(LogKey{e.particle, e.count}, 0);
  }
  u128 extra = 0;
  for (std::size_t k = 0; k < s.groups.size(); ++k) {
    const auto& e = s.groups[k];
    const std::size_t m = e.members.size();
    require(m >= 2 && m <= 64 && e.counts.size() == m, "lattice snapshot: a group entry needs 2-64 members, one count each");
    require(e.pre_v.empty() || e.pre_v.size() == m, "lattice snapshot: a group entry needs one pre velocity per member (or none: a bounce)");
    bool has_drawer = false;
    std::uint64_t drawer_count = 0;
    for (std::size_t q = 0; q < m; ++q) {
      const int p = e.members[q];
      require(p >= 0 && (q == 0 || e.members[q - 1] < p), "lattice snapshot: a group's members must ascend, each once");
      require(key_ok(static_cast<std::size_t>(p), e.counts[q]), "lattice snapshot: a group entry names a collision its member has not had");
      require(seen.emplace(LogKey{static_cast<std::uint32_t>(p), e.counts[q]}, 1).second,
              "lattice snapshot: two rare-log entries name the same collision of a particle");
      if (p == e.drawer) has_drawer = true, drawer_count = e.counts[q];
    }
    require(has_drawer, "lattice snapshot: a group's drawer must be one of its members");
    if (k > 0) {
      const auto& f = s.groups[k - 1];
      const auto fc = f.counts[static_cast<std::size_t>(std::find(f.members.begin(), f.members.end(), f.drawer) - f.members.begin())];
      require(LogKey{static_cast<std::uint32_t>(f.drawer), fc} < LogKey{static_cast<std::uint32_t>(e.drawer), drawer_count},
              "lattice snapshot: group entries must be in (drawer, count) order");
    }
    for (const Vec& w : e.pre_v)
      for (std::size_t a = 0; a < D; ++a)
        require(w[a] >= -s.units.vmax && w[a] <= s.units.vmax, "lattice snapshot: a group entry's pre velocity is faster than vmax");
    extra += m - 2;
  }
  u128 sum = 0;
  for (std::uint64_t c : s.particle_collisions) sum += c;
  require(sum == 2 * static_cast<u128>(s.collisions) + extra,
          "lattice snapshot: particle_collisions do not add up to collisions (2 per pair collision, 1 per group member)");
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::restore(const Snapshot& s, const std::vector<std::uint32_t>& order) {
  validate_state(s.units, s.x, s.v, true, s.radius, s.clock);  // collisions may be pending at the clock (rebuild finds them)
  if (!s.radius.empty()) Sizes::require_resizable<Op>();
  require(rax_ < 0 || rax_ != field_axis(s.units), "lattice: a gas in a field is cut across the field, not along it (regions' axis must be another than the field's)");
  require(s.units.shear == 0 || (rax_ < 0 && !jon_ && list_shell_ <= 0.0),
          "lattice: a sheared gas runs without regions, journal or neighbour lists (not built for moving images yet)");
  if (!order.empty()) {
    require(order.size() == s.x.size(), "lattice: an order must name every particle once (a permutation of [0, N))");
    std::vector<char> seen(order.size(), 0);
    for (std::uint32_t q : order) {
      require(q < order.size() && !seen[q], "lattice: an order must name every particle once (a permutation of [0, N))");
      seen[q] = 1;
    }
  }
  require(s.streams.size() == s.x.size(), "lattice snapshot: streams must hold one counter per particle");
  if (s.units.shear == 0) {
    // energy is kept by every collision to the lattice's rounding (~1e-11 relative over 10^4
    // collisions per particle): a checkpoint whose energy0 is not its velocities' (1e-6
    // relative) was not written by a run. (Momentum is not checked: a group bounce reverses
    // its members' velocities.)
    const double E = static_cast<double>(energy2(s.units, s.x, s.v));
    const double E0 = static_cast<double>((static_cast<u128>(s.energy0[1]) << 64) | s.energy0[0]);
    require(std::fabs(E - E0) <= 1e-6 * E0, "lattice snapshot: energy0 is not the sum |v|^2 of v (1e-6 relative)");
  }  // (shear: the boundary does work, energy0 is the start's)
  check_log(s);
  require(s.origin <= s.clock && tick_limit / 2 > s.clock && s.origin > -tick_limit / 2,
          "lattice snapshot: origin <= clock within +-2^60 required");
  require(s.law == law(), "lattice snapshot: its law is not the operator's");
  require(s.mode == Mode::exact || s.mode == Mode::specular, "lattice snapshot: mode must be exact or specular");
  check_operator(s.units);
  // a running observation resumes (built before anything changes: a spoiled one is an error)
  std::unique_ptr<engine::Observer> resumed;
  require(!s.observer.empty() || s.observer_counts.empty(), "lattice snapshot: observer_counts without observer");
  if (!s.observer.empty()) resumed = make_observer(s.units, s.x, s.v, s.clock, nullptr, &s, s.radius);
  // a large gas is stored in space order from the start (resort), unless an order is given
  const bool sort = order.empty() && s.observer.empty() && resort_every_for(s.x.size()) > 0;
  load(s, sort ? space_order(s.units, s.x) : order);
  // none: a running observation of the old state ends; a stopped one stays readable (not fed)
  const bool running = resumed != nullptr;
  if (running || obs_) observer_ = std::move(resumed);
  obs_ = running ? observer_.get() : nullptr;
}

template <class Op, class Bits, class Queue>
auto BasicEngine<Op, Bits, Queue>::snapshot() const -> Snapshot {
  Snapshot s;
  s.units = u_;
  s.law = law();
  s.mode = mode_;
  s.seed = seed_;
  s.clock = clock_;
  s.origin = origin_;
  s.collisions = ncoll_;
  s.x = positions();
  s.v = velocities();
  s.streams = streams();
  s.particle_collisions.resize(own_.size());
  s.bits_size.resize(own_.size());
  for (std::size_t q = 0; q < own_.size(); ++q) {  // by particle id
    const Own& o = own_[local(static_cast<int>(q))];
    s.particle_collisions[q] = o.pc;
    const auto w = o.X.words();
    s.bits.insert(s.bits.end(), w.begin(), w.end());
    s.bits_size[q] = w.size();
  }
  for (const auto& [k, r] : log_) s.log.push_back(LogEntry{k.first, k.second, r});
  for (const auto& [k, g] : groups_)  // each group once, under its drawer's key
    if (k.first == static_cast<std::uint32_t>(g->drawer)) s.groups.push_back(GroupEntry{g->drawer, g->draws, g->members, g->counts, g->pre_v});
  s.energy0 = energy0_;
  s.momentum0 = momentum0_;
  s.counters = cnt_;
  s.radius = radii();
  if (obs_) obs_->save(s.observer, s.observer_counts);  // a running observation resumes (observe.hpp)
  return s;
}

template <class Op, class Bits, class Queue>
auto BasicEngine<Op, Bits, Queue>::positions() const -> std::vector<Vec> {
  std::vector<Vec> out(ln_.size());
  for (std::size_t p = 0; p < ln_.size(); ++p) out[static_cast<std::size_t>(gid(static_cast<int>(p)))] = pos(static_cast<int>(p), clock_);
  return out;
}

template <class Op, class Bits, class Queue>
auto BasicEngine<Op, Bits, Queue>::velocities() const -> std::vector<Vec> {
  std::vector<Vec> out(ln_.size());
  for (std::size_t p = 0; p < ln_.size(); ++p) out[static_cast<std::size_t>(gid(static_cast<int>(p)))] = vel(static_cast<int>(p), clock_);
  return out;
}

template <class Op, class Bits, class Queue>
auto BasicEngine<Op, Bits, Queue>::streams() const -> std::vector<std::uint64_t> {
  std::vector<std::uint64_t> c(own_.size());
  for (std::size_t p = 0; p < own_.size(); ++p) c[static_cast<std::size_t>(gid(static_cast<int>(p)))] = own_[p].ctr;
  return c;
}

// A new state: the particles' streams at 0, their X from initial_bits, energy and momentum recorded.
template <class Op, class Bits, class Queue>
auto BasicEngine<Op, Bits, Queue>::fresh(const Units& u, std::vector<Vec> x, std::vector<Vec> v, std::uint32_t seed,
                                         std::int64_t clock, Mode mode, std::vector<std::int64_t> radius) const -> Snapshot {
  check_operator(u);
  require(mode == Mode::exact || mode == Mode::specular, "lattice: mode must be 'exact' or 'specular'");
  validate_state(u, x, v, false, radius, clock);
  if (!radius.empty()) Sizes::require_resizable<Op>();
  require(clock > -tick_limit / 2 && clock < tick_limit / 2, "lattice: the start tick must be within +-2^60");
  Snapshot s;
  s.units = u;
  s.law = law();
  s.mode = mode;
  s.seed = seed;
  s.clock = s.origin = clock;
  s.x = std::move(x);
  s.v = std::move(v);
  s.radius = std::move(radius);
  s.streams.assign(s.x.size(), 0);
  s.particle_collisions.assign(s.x.size(), 0);
  for (std::size_t p = 0; p < s.x.size(); ++p) {
    const auto w = initial_bits(static_cast<std::uint32_t>(p), seed);
    s.bits.insert(s.bits.end(), w.begin(), w.end());
    s.bits_size.push_back(w.size());
  }
  const u128 e = energy2(s.units, s.x, s.v);
  s.energy0 = {static_cast<std::uint64_t>(e), static_cast<std::uint64_t>(e >> 64)};
  const auto p = momentum_of(s.v);
  for (std::size_t k = 0; k < D; ++k) {
    s.momentum0[2 * k] = static_cast<std::int64_t>(static_cast<std::uint64_t>(static_cast<u128>(p[k])));
    s.momentum0[2 * k + 1] = static_cast<std::int64_t>(p[k] >> 64);
  }
  return s;
}

// The state of a validated snapshot, local index p holding particle order[p] (empty: p).
template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::load(const Snapshot& s, const std::vector<std::uint32_t>& order) {
  u_ = s.units;
  gax_ = field_axis(u_);
  sh_ = load_back_ ? -u_.shear : u_.shear;  // the frame's rate (shear.hpp)
  moving_ = gax_ >= 0 || sh_ != 0;
  hg_ = gax_ >= 0 ? u_.gravity[static_cast<std::size_t>(gax_)] / 2 : 0;
  hgd_ = static_cast<double>(hg_);
  for (std::size_t k = 0; k < D; ++k) axk_[k] = static_cast<std::uint8_t>(static_cast<int>(k) == gax_ ? 2 : u_.wall[k] ? 1 : 0);
  if (u_.shear != 0) axk_[1] = 3;  // the gradient axis: a crossing moves the flow coordinate too (pos)
  seed_ = s.seed;
  mode_ = s.mode;
  if (mode_ == Mode::specular) spec_ = Specular(u_.sigma);
  if (rax_ >= 0 && faces_.back() >= u_.L[static_cast<std::size_t>(rax_)]) {  // slabs of another box
    rax_ = -1;
    faces_.clear();
  }
  const std::size_t n = s.x.size();
  gid_.assign(order.begin(), order.end());
  lid_.assign(order.empty() ? 0 : n, 0);
  for (std::size_t p = 0; p < gid_.size(); ++p) lid_[static_cast<std::size_t>(gid_[p])] = static_cast<int>(p);
  std::vector<std::size_t> at(n + 1, 0);  // where each particle's words start in s.bits
  for (std::size_t q = 0; q < n; ++q) at[q + 1] = at[q] + static_cast<std::size_t>(s.bits_size[q]);
  ln_.resize(n);
  slot_.assign(n, Slot{});
  own_.assign(n, Own{});
  sz_.set(u_.sigma, s.radius, [this](int p) { return gid(p); });
  for (std::size_t p = 0; p < n; ++p) {
    const auto q = static_cast<std::size_t>(gid(static_cast<int>(p)));
    ln_[p] = Line{s.x[q], s.v[q], s.clock};
    own_[p].X = Bits(std::vector<std::uint64_t>(s.bits.begin() + static_cast<std::ptrdiff_t>(at[q]), s.bits.begin() + static_cast<std::ptrdiff_t>(at[q + 1])));
    own_[p].ctr = s.streams[q];
    own_[p].pc = s.particle_collisions[q];
  }
  log_.clear();
  for (const LogEntry& e : s.log) log_.emplace(LogKey{e.particle, e.count}, e.redraws);
  groups_.clear();
  for (const auto& e : s.groups) {
    auto g = std::make_shared<Group>(Group{e.drawer, e.draws, e.members, e.counts, e.pre_v});
    for (std::size_t m = 0; m < e.members.size(); ++m) groups_.emplace(LogKey{static_cast<std::uint32_t>(e.members[m]), e.counts[m]}, g);
  }
  ngroups_ = s.groups.size();
  clock_ = s.clock;
  origin_ = s.origin;
  ncoll_ = s.collisions;
  energy0_ = s.energy0;
  momentum0_ = s.momentum0;
  cnt_ = s.counters;
  resort_at_ = next_resort();
  wall_tick_.assign(n, std::numeric_limits<std::int64_t>::min());
  pre_wall_.assign(n, Line{});
  reversed_ = false;
  if (load_back_) {  // an LP of a run back: the frame flipped as flip() does, before the one build
    for (Line& l : ln_) l.v = neg(l.v), l.ta = -l.ta;
    clock_ = -clock_;
    reversed_ = true;
  }
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
  rebuild();
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::rebuild() {
  const std::size_t n = ln_.size();
  slot_.resize(n);
  for (Slot& b : slot_) {
    b.type = none;
    b.partner = -1;
    b.vself = b.vpart = 0;
  }
  for (std::size_t p = 0; p < n; ++p) {
    const Vec v = vel(static_cast<int>(p), clock_);  // (before the anchor moves: shear reads the old line's crossings)
    ln_[p].x = pos(static_cast<int>(p), clock_);
    ln_[p].v = v;
    ln_[p].ta = clock_;
  }
  const double shell = list_shell_ < 0.0 ? auto_list_shell() : list_shell_;
  lists_ = shell > 0.0;
  grid_ = CellGridN<D>{};
  nl_ = NeighbourListsN<D>{};
  direct_ = shifted_ = false;
  if (lists_) {
    const double h = std::max(1.0, std::round(0.5 * shell * static_cast<double>(u_.sigma)));
    std::vector<Vec> centres(n);
    for (std::size_t p = 0; p < n; ++p) centres[p] = ln_[p].x;
    if (gax_ >= 0) nl_.set_field(gax_, hg_);
    nl_.build(u_, static_cast<std::int64_t>(std::min(h, static_cast<double>(u_.sigma))), centres);
    // the prediction takes r from the centre offsets when no periodic axis is short enough
    // for a relative vector (< R + 2 h + 4 vmax) to reach half the box
    direct_ = true;
    for (std::size_t k = 0; k < D; ++k)
      if (!u_.wall[k] && u_.L[k] / 2 - 4096 <= nl_.reach() + 2 * nl_.radius() + 4 * u_.vmax) direct_ = false;
  } else {
    grid_.build(u_, n);
    for (std::size_t p = 0; p < n; ++p) grid_.insert(static_cast<int>(p), grid_.cell_id(ln_[p].x));
    shifted_ = grid_.shifted() && sh_ == 0;  // (shear: the images across the gradient faces move)
  }
  lnd_.resize(n);
  for (std::size_t p = 0; p < n; ++p) {
    sync(static_cast<int>(p));
    lnd_[p].r = static_cast<double>(rad(static_cast<int>(p)));
  }
  // first bucket width: ~2^tick_bits ticks per mean free time per particle, over N particles
  // (the queue adapts it; a speed setting only)
  queue_.reset(n, clock_, std::max<std::int64_t>(1, (std::int64_t{1} << u_.tick_bits) / static_cast<std::int64_t>(n)), !gid_.empty());
  // forward: events at the clock may still be pending (a run stopped after a collision);
  // reverse: the clock's tick is done (see run_back), the search starts one tick later
  const std::int64_t lo = reversed_ ? clock_ + 1 : clock_;
  region_.clear();  // each particle's slab at the clock (set_regions)
  if (rax_ >= 0)
    for (std::size_t p = 0; p < n; ++p) region_.push_back(region_of(ln_[p].x));
  for (std::size_t p = 0; p < n; ++p) predict(static_cast<int>(p), lo);
  last_key_ = {std::numeric_limits<std::int64_t>::min(), 0};
  restart_journal();  // a rollback can not cross a rebuild (every line anchored at the clock)
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::release() {
  const auto drop = [](auto& v) { std::remove_reference_t<decltype(v)>().swap(v); };
  drop(ln_), drop(lnd_), drop(wall_tick_), drop(pre_wall_), drop(own_), drop(slot_), drop(gid_), drop(lid_);
  drop(region_), drop(parked_), drop(undo_), drop(undo_epoch_), drop(jmark_), drop(jtouched_);
  drop(jdone_), drop(jss1_), drop(jss2_), drop(jss2x_), drop(jwall_), drop(jlp_), drop(jback_);
  grid_ = CellGridN<D>{};
  nl_ = NeighbourListsN<D>{};
  queue_ = Queue{};
  sz_.clear();
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::check_operator(const Units& u) const {
  require(op_.sigma() == u.sigma, "lattice: the operator's sigma differs from the units' (the largest diameter)");
  if constexpr (requires { op_.cell_bits(); })
    require(op_.cell_bits() == u.cell_bits, "lattice: the operator's cell_bits differ from the units'");
}

template <class Op, class Bits, class Queue>
std::uint64_t BasicEngine<Op, Bits, Queue>::next_resort() const noexcept {
  const int k = resort_every();
  return k > 0 ? cnt_.crossings + static_cast<std::uint64_t>(k) * ln_.size() : 0;
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::flip() {
  for (Line& l : ln_) {
    l.v = neg(l.v);
    l.ta = -l.ta;
  }
  clock_ = -clock_;
  sh_ = -sh_;  // the images' offset at a physical time stays (shear.hpp)
  for (auto& t : wall_tick_) t = std::numeric_limits<std::int64_t>::min();
  reversed_ = !reversed_;
  rebuild();
}

// The ids in space order: cells about two diameters wide in row-major order, ids ascending
// within a cell (x: the positions by id, in the units u).
template <class Op, class Bits, class Queue>
auto BasicEngine<Op, Bits, Queue>::space_order(const Units& u, const std::vector<Vec>& x) -> std::vector<std::uint32_t> {
  const std::size_t n = x.size();
  std::array<std::int64_t, D> m{};
  std::size_t cells = 1;
  for (std::size_t k = 0; k < D; ++k) {
    m[k] = std::clamp<std::int64_t>(u.L[k] / (2 * u.sigma), 1, 1024);
    cells *= static_cast<std::size_t>(m[k]);
  }
  std::vector<std::uint32_t> key(n);
  std::vector<std::size_t> start(cells + 1, 0);
  for (std::size_t id = 0; id < n; ++id) {
    std::size_t c = 0;
    for (std::size_t k = 0; k < D; ++k) {
      const i128 q = static_cast<i128>(x[id][k]) * m[k] / u.L[k];  // walls: within [0, L) too
      c = c * static_cast<std::size_t>(m[k]) + static_cast<std::size_t>(std::clamp<i128>(q, 0, m[k] - 1));
    }
    key[id] = static_cast<std::uint32_t>(c);
    ++start[c + 1];
  }
  for (std::size_t c = 0; c < cells; ++c) start[c + 1] += start[c];
  std::vector<std::uint32_t> order(n);
  for (std::size_t id = 0; id < n; ++id) order[start[key[id]]++] = static_cast<std::uint32_t>(id);
  return order;
}

// Stores the particles in space order and rebuilds the search at clock t - 1, between two
// ticks: every event before t is done and none at t. A rebuild there is the one a run stopped
// at t - 1 and resumed would do (forward: restore, which predicts from the clock; reverse:
// run_back's flip, from the next tick), and storage order decides nothing (keys, draws, ties
// and outputs are by id: an observation and the event records too), so the collisions and the
// bits are unchanged. The run's undo journal follows its particles; the rollback journal holds
// local indices, so the loop does not re-sort while it is kept. Clocked by the neutral events (a
// list renewal or cell crossing: distance travelled, which is what loses the order), from 32 768
// particles every 16 per particle, as the float engine (below that the state fits the caches).
template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::resort(std::int64_t t) {
  const std::size_t n = ln_.size();
  clock_ = t - 1;
  std::vector<Vec> x(n);
  for (std::size_t id = 0; id < n; ++id) x[id] = pos(static_cast<int>(local(static_cast<int>(id))), clock_);
  std::vector<std::uint32_t> order = space_order(u_, x);
  std::vector<int> to(n);  // old local index -> new
  for (std::size_t p = 0; p < n; ++p) to[local(static_cast<int>(order[p]))] = static_cast<int>(p);
  auto permute = [&](auto& v) {
    if (v.size() != n) return;
    std::remove_reference_t<decltype(v)> w(n);
    for (std::size_t p = 0; p < n; ++p) w[static_cast<std::size_t>(to[p])] = std::move(v[p]);
    v.swap(w);
  };
  permute(ln_);
  permute(own_);
  permute(wall_tick_);
  permute(pre_wall_);
  permute(undo_epoch_);
  permute(sz_.data());
  for (Saved& sv : undo_) sv.p = to[static_cast<std::size_t>(sv.p)];
  gid_.assign(order.begin(), order.end());
  lid_.assign(n, 0);
  for (std::size_t p = 0; p < n; ++p) lid_[static_cast<std::size_t>(gid_[p])] = static_cast<int>(p);
  rebuild();
  ++resorts_;
  resort_at_ = next_resort();
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::begin_undo() {
  if (undo_epoch_.size() != ln_.size() || ++epoch_ == 0) {  // new size, or the epoch wrapped
    undo_epoch_.assign(ln_.size(), 0);
    epoch_ = 1;
  }
  undo_.clear();
  undo_log_.clear();
  undo_groups_.clear();
  undo_cnt_ = cnt_;
  undo_clock_ = clock_;
  undo_ncoll_ = ncoll_;
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::undo(bool whole) {
  std::vector<int> changed;
  for (const Saved& sv : undo_) {
    changed.push_back(sv.p);
    ln_[sv.p] = sv.line;
    pre_wall_[sv.p] = sv.pre_wall;
    own_[sv.p].X = sv.X;
    own_[sv.p].ctr = sv.ctr;
    own_[sv.p].pc = sv.pc;
    wall_tick_[sv.p] = sv.wall_tick;
    ++slot_[static_cast<std::size_t>(sv.p)].ver;
  }
  undo_.clear();
  cnt_ = undo_cnt_;
  clock_ = undo_clock_;
  for (const LogKey& k : undo_log_) log_.erase(k);  // the forward run only adds keys
  for (const LogKey& k : undo_groups_) {
    const auto it = groups_.find(k);
    if (it != groups_.end() && it->first.first == static_cast<std::uint32_t>(it->second->drawer)) --ngroups_;
    if (it != groups_.end()) groups_.erase(it);
  }
  undo_log_.clear();
  undo_groups_.clear();
  ncoll_ = undo_ncoll_;
  if (!whole) {  // one event of an LP's run (lp_view.hpp): the rest of the queue is as it was
    for (int p : changed) {
      reanchor(p, clock_);
      sync(p);
    }
    for (int p : changed) predict(p, clock_);
    return;
  }
  rebuild();
  resort_at_ = next_resort();  // (the counters went back with the run)
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::set_regions(int axis, std::vector<std::int64_t> faces) {
  if (faces.empty()) {
    rax_ = -1;
    faces_.clear();
  } else {
    require(sh_ == 0, "lattice regions: not built for a sheared gas yet (the parallel engine runs without shear)");
    require(axis >= 0 && axis < static_cast<int>(D), "lattice regions: the axis must be 0, 1 or (3D) 2");
    require(axis != gax_, "lattice regions: a gas in a field is cut across the field, not along it (its slabs' axis must be another than the field's)");
    const std::int64_t L = u_.L[static_cast<std::size_t>(axis)];
    for (std::size_t k = 0; k < faces.size(); ++k)
      require(faces[k] >= 0 && faces[k] < L && (k == 0 || faces[k - 1] < faces[k]),
              "lattice regions: the faces must ascend within [0, L) of their axis, each once");
    rax_ = axis;
    faces_ = std::move(faces);
  }
  rebuild();
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::set_list_shell(double s) {
  require(std::isfinite(s) && (s <= 0.0 || (s >= 0.02 && s <= 2.0)), "lattice: the list shell must be 0 (cells), negative (automatic) or in [0.02, 2] diameters");
  require(s <= 0.0 || sh_ == 0, "lattice: a sheared gas searches with the cell grid (neighbour lists are not built for moving images yet): shell 0 or automatic");
  list_shell_ = s;
  rebuild();
}

template <class Op, class Bits, class Queue>
auto BasicEngine<Op, Bits, Queue>::auto_list_shell() const noexcept -> double {
  if (sh_ != 0) return 0.0;  // shear: the cell grid (its images move; a list's would go stale)
  if constexpr (D == 2) {
    return 0.0;
  } else {
    double vol = 1.0;
    for (std::size_t k = 0; k < D; ++k) vol *= static_cast<double>(u_.L[k]) / static_cast<double>(u_.sigma);
    const double phi = static_cast<double>(ln_.size()) * (std::numbers::pi / 6.0) / vol;
    // Enskog mean free path in diameters; the shell grows with it (docs/lattice.md, measured)
    const double g = (1.0 - 0.5 * phi) / ((1.0 - phi) * (1.0 - phi) * (1.0 - phi));
    const double lam = phi > 0.0 ? 1.0 / (6.0 * std::numbers::sqrt2 * phi * g) : 1e9;
    if (gax_ >= 0 && lam > kFieldListsMaxLambda) return 0.0;  // a sparse gas in a field: the cell grid
    return std::clamp(kShellBase + kShellSlope * lam, kShellMin, kShellMax);
  }
}

template <class Op, class Bits, class Queue>
auto BasicEngine<Op, Bits, Queue>::memory_bytes() const noexcept -> std::size_t {
  const std::size_t n = ln_.size();
  std::size_t heap = 0;
  for (const Own& o : own_) heap += o.X.heap_bytes();
  return n * (2 * sizeof(Vec) + 4 * 8 + 3 * 8 + sizeof(Vec) * 2 + 8 + sizeof(Own)) + heap + queue_.memory_bytes() +
         grid_.memory_bytes() + nl_.memory_bytes() + log_.size() * (48 + sizeof(LogKey) + 8) + group_bytes() +
         undo_.capacity() * sizeof(Saved) + undo_epoch_.capacity() * sizeof(std::uint32_t) +
         (gid_.capacity() + lid_.capacity()) * sizeof(int);
}

template <class Op, class Bits, class Queue>
auto BasicEngine<Op, Bits, Queue>::group_bytes() const noexcept -> std::size_t {
  std::size_t b = 0;
  for (const auto& [k, g] : groups_) {
    b += 48 + sizeof(LogKey) + 16;  // the map node of this key
    if (k.first == static_cast<std::uint32_t>(g->drawer))
      b += sizeof(Group) + 16 + g->members.size() * (sizeof(int) + 8) + g->pre_v.size() * sizeof(Vec);
  }
  return b;
}

}  // namespace revcol::lattice
