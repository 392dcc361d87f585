// The lattice engine's observation hooks: the float engine's observer (revcol/engine/observe.hpp)
// fed at every forward velocity change, and the event records of tests and studies.
// Part of BasicEngine (revcol/lattice/engine_core.hpp, which declares it and explains the
// design); included by engine_impl.hpp, which the instantiating sources include.
#pragma once
#include <algorithm>
#include <memory>

#include "revcol/lattice/engine_core.hpp"

namespace revcol::lattice {

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::observe(const engine::ObserveConfig& c) {
  observer_ = make_observer(u_, positions(), velocities(), clock_, &c, nullptr, radii());
  obs_ = observer_.get();
}

// An observer of the state (units u, positions x at tick clock, velocities v) in float units:
// a new one with config c, or the one a snapshot s saved (resumed; InvalidArgument if spoiled).
template <class Op, class Bits, class Queue>
auto BasicEngine<Op, Bits, Queue>::make_observer(const Units& u, const std::vector<Vec>& x, const std::vector<Vec>& v,
                                                 std::int64_t clock, const engine::ObserveConfig* c,
                                                 const Snapshot* s, const std::vector<std::int64_t>& radius)
    -> std::unique_ptr<engine::Observer> {
  const double len = u.length_unit, speed = u.length_unit / u.tick;
  const std::size_t n = x.size();
  std::vector<double> xf(n * D), vf(n * D);
  for (std::size_t p = 0; p < n; ++p)
    for (std::size_t k = 0; k < D; ++k) {
      xf[p * D + k] = static_cast<double>(x[p][k]) * len;
      vf[p * D + k] = static_cast<double>(v[p][k]) * speed;
    }
  std::array<double, 3> box{};
  std::array<bool, 3> walls{};
  for (std::size_t k = 0; k < D; ++k) {
    box[k] = static_cast<double>(u.L[k]) * len;
    walls[k] = u.wall[k];
  }
  const double t = static_cast<double>(clock) * u.tick, diameter = static_cast<double>(u.sigma) * len;
  auto o = s != nullptr ? std::make_unique<engine::Observer>(s->observer, s->observer_counts, static_cast<int>(D), vf,
                                                             t, box, walls, diameter)
                        : std::make_unique<engine::Observer>(*c, static_cast<int>(D), xf, vf, t, box, walls, diameter);
  if (!radius.empty()) {  // a mixture: its species by radius (engine::Observer::set_sizes)
    std::vector<double> rf(n);
    for (std::size_t q = 0; q < n; ++q) rf[q] = static_cast<double>(radius[q]) * len;  // distinct radii stay distinct (< 2^52)
    o->set_sizes(rf);
  }
  // shear: the observer takes the images one box up as moving s lattice units per tick faster
  if (u.shear != 0) o->set_shear(static_cast<double>(u.shear) * speed / box[1]);
  require(u.shear != 0 || o->saved_shear() == 0.0, "snapshot: observer: it was taken of a sheared gas, this one is not");
  // a field: flights are parabolas (acceleration gravity[k] lattice units per tick^2)
  const int fk = field_axis(u);
  if (fk >= 0) o->set_field(fk, static_cast<double>(u.gravity[static_cast<std::size_t>(fk)]) * len / (u.tick * u.tick));
  require(fk >= 0 || o->saved_field_axis() < 0, "snapshot: observer: it was taken of a gas in a field, this one is in none");
  return o;
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::stop_observing() {
  if (obs_) obs_->sync(time_of(clock_));
  obs_ = nullptr;
}

// ---- the observer's hooks (forward only; cold: one test per velocity change when off) ----
// A pair and a wall go to the observer from arrays on the stack (measure before changing:
// building vectors per event cost ~1 000 instructions); the event records (tests) are built
// only when asked for.
template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::record(int kind, std::int64_t a, const std::vector<int>& ids, const std::vector<Vec>& x, const std::vector<Vec>& v, unsigned axes) {
  EventRecordN<D> r{a, kind, axes, {}, x, {}, v};  // by particle id
  for (int q : ids) {
    r.ids.push_back(gid(q));
    r.v_before.push_back(vel(q, a - 1));  // (a field: its velocity at a-1)
  }
  events->push_back(std::move(r));
}

template <class Op, class Bits, class Queue>
[[gnu::noinline, gnu::cold]] void BasicEngine<Op, Bits, Queue>::note_pair(std::int64_t a, int i, int j, const Vec& xi, const Vec& xj, const Vec& vi, const Vec& vj) {
  if (events != nullptr) record(EventRecordN<D>::pair, a, {i, j}, {xi, xj}, {vi, vj}, 0);
  if (!obs_ && !seen_) return;
  double x[2 * D], v[2 * D];
  for (std::size_t k = 0; k < D; ++k) {
    x[k] = to_length(xi[k]);
    x[D + k] = to_length(xj[k]);
    v[k] = to_speed(vi[k]);
    v[D + k] = to_speed(vj[k]);
  }
  if (seen_) {  // an LP's: kept, the committed ones replayed (lp_seen.hpp)
    const int ids[2] = {gid(i), gid(j)};
    seen_->add(lp_->key, LpSeen::pair, time_of(a), 0, 2, ids, x, v);
    return;
  }
  obs_->pair_at(time_of(a), gid(i), gid(j), x, x + D, v, v + D);
}

template <class Op, class Bits, class Queue>
[[gnu::noinline, gnu::cold]] void BasicEngine<Op, Bits, Queue>::note_wall(std::int64_t a, int p, const Vec& xp, const Vec& vp, unsigned axes) {
  if (events != nullptr) record(EventRecordN<D>::wall, a, {p}, {xp}, {vp}, axes);
  if (!obs_ && !seen_) return;
  double x[D], v[D];
  for (std::size_t k = 0; k < D; ++k) {
    x[k] = to_length(xp[k]);
    v[k] = to_speed(vp[k]);
  }
  const int id = gid(p);
  if (seen_) seen_->add(lp_->key, LpSeen::wall, time_of(a), axes, 1, &id, x, v);
  else obs_->wall_at(time_of(a), id, x, v, axes);
}

template <class Op, class Bits, class Queue>
[[gnu::noinline, gnu::cold]] void BasicEngine<Op, Bits, Queue>::note_group(std::int64_t a, const std::vector<int>& g, const std::vector<Vec>& xg, const std::vector<Vec>& vg) {
  if (events != nullptr) record(EventRecordN<D>::group, a, g, xg, vg, 0);
  if (!obs_ && !seen_) return;
  const std::size_t n = g.size();
  std::vector<double> x(n * D), v(n * D);
  std::vector<int> ids(n);
  for (std::size_t m = 0; m < n; ++m) ids[m] = gid(g[m]);
  for (std::size_t m = 0; m < n; ++m)
    for (std::size_t k = 0; k < D; ++k) {
      // positions image-consistent about the first member's (under shear each its own: the
      // observer takes the moving images, Observer::group_at)
      x[m * D + k] = to_length(m > 0 && sh_ == 0 ? xg[0][k] + diff(xg[m], xg[0])[k] : xg[m][k]);
      v[m * D + k] = to_speed(vg[m][k]);
    }
  if (seen_) seen_->add(lp_->key, LpSeen::group, time_of(a), 0, n, ids.data(), x.data(), v.data());
  else obs_->group_at(time_of(a), static_cast<int>(n), ids.data(), x.data(), v.data());
}

}  // namespace revcol::lattice
