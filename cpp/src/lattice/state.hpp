// The lattice engine's state: load and restore a snapshot, take one, rebuild the search and
// the queue, flip the frame for a reversed run, the neighbour search's choice, memory, and the
// forward run's undo journal (an engine error mid-run restores the state).
// Part of BasicEngine (revcol/lattice/engine_core.hpp, which declares it and explains the
// design); included by engine_impl.hpp, which the instantiating sources include.
#pragma once
#include <algorithm>
#include <cmath>
#include <limits>

#include "revcol/lattice/engine_core.hpp"

namespace revcol::lattice {

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::restore(const Snapshot& s) {
  validate_state(s.units, s.x, s.v, true);  // collisions may be pending at the clock (rebuild finds them)
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
  // the logs are stacks keyed by collision index (engine/logs.hpp): strictly increasing keys
  // within [1, collisions], so that the reverse meets each entry on top at its collision
  for (std::size_t k = 0; k < s.log.size(); ++k)
    require(s.log[k].first >= 1 && s.log[k].first <= s.collisions && (k == 0 || s.log[k - 1].first < s.log[k].first),
            "lattice snapshot: rare-log indices must increase within [1, collisions]");
  for (std::size_t k = 1; k < s.groups.size(); ++k)
    require(s.groups[k - 1].index < s.groups[k].index, "lattice snapshot: group entries' indices must increase");
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
  require(s.law == law(), "lattice snapshot: its law is not the operator's");
  require(s.mode == Mode::exact || s.mode == Mode::specular, "lattice snapshot: mode must be exact or specular");
  check_operator(s.units);
  // a running observation resumes (built before anything changes: a spoiled one is an error)
  std::unique_ptr<engine::Observer> resumed;
  require(!s.observer.empty() || s.observer_counts.empty(), "lattice snapshot: observer_counts without observer");
  if (!s.observer.empty()) resumed = make_observer(s.units, s.x, s.v, s.clock, nullptr, &s);
  load(s);
  observer_ = std::move(resumed);  // none: an observation of the old state ends
  obs_ = observer_.get();
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
  s.streams = ctr_;
  s.bits = X_.words();
  s.log.assign(log_.items().begin(), log_.items().end());
  for (const auto& [k, g] : groups_.items()) s.groups.push_back(GroupEntry{k, g.drawer, g.members, g.pre_v});
  s.energy0 = energy0_;
  s.momentum0 = momentum0_;
  s.counters = cnt_;
  if (obs_) obs_->save(s.observer, s.observer_counts);  // a running observation resumes (observe.hpp)
  return s;
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::load(const Snapshot& s) {
  u_ = s.units;
  seed_ = s.seed;
  mode_ = s.mode;
  if (mode_ == Mode::specular) spec_ = Specular(u_.sigma);
  const std::size_t n = s.x.size();
  ln_.resize(n);
  for (std::size_t p = 0; p < n; ++p) ln_[p] = Line{s.x[p], s.v[p], s.clock};
  slot_.assign(n, Slot{});
  ctr_ = s.streams;
  X_ = Bits(s.bits);
  log_.clear();
  for (const auto& e : s.log) log_.push(e.first, e.second);
  groups_.clear();
  for (const auto& e : s.groups) groups_.push(e.index, Group{e.drawer, e.members, e.pre_v});
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

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::flip() {
  for (Line& l : ln_) {
    l.v = neg(l.v);
    l.ta = -l.ta;
  }
  clock_ = -clock_;
  for (auto& t : wall_tick_) t = std::numeric_limits<std::int64_t>::min();
  reversed_ = !reversed_;
  rebuild();
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::begin_undo() {
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

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::undo() {
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
  log_.truncate_after(undo_ncoll_);  // the forward run only adds keys
  groups_.truncate_after(undo_ncoll_);
  ncoll_ = undo_ncoll_;
  rebuild();
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::set_list_shell(double s) {
  require(std::isfinite(s) && (s <= 0.0 || (s >= 0.02 && s <= 2.0)), "lattice: the list shell must be 0 (cells), negative (automatic) or in [0.02, 2] diameters");
  list_shell_ = s;
  rebuild();
}

template <class Op, class Bits, class Queue>
auto BasicEngine<Op, Bits, Queue>::auto_list_shell() const noexcept -> double {
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

template <class Op, class Bits, class Queue>
auto BasicEngine<Op, Bits, Queue>::memory_bytes() const noexcept -> std::size_t {
  const std::size_t n = ln_.size();
  return n * (2 * sizeof(Vec) + 4 * 8 + 3 * 8 + 8 + sizeof(Vec) * 2 + 8) + queue_.memory_bytes() + grid_.memory_bytes() + nl_.memory_bytes() +
         log_.size() * sizeof(std::pair<std::uint64_t, std::uint32_t>) + group_bytes() + X_.words().size() * 8 + undo_.capacity() * sizeof(Saved) +
         undo_epoch_.capacity() * sizeof(std::uint32_t);
}

template <class Op, class Bits, class Queue>
auto BasicEngine<Op, Bits, Queue>::group_bytes() const noexcept -> std::size_t {
  std::size_t b = 0;
  for (const auto& [k, g] : groups_.items()) b += 48 + g.members.size() * sizeof(int) + g.pre_v.size() * sizeof(Vec);
  return b;
}

}  // namespace revcol::lattice
