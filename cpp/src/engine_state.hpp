// EngineImpl's state readers: diagnostics() (energy, momentum, drifts, logs, counters, the
// collision trace) and snapshot() (the full state a checkpoint holds). Private to cpp/src:
// included by engine_build.hpp beside engine_impl.hpp and engine_collide.hpp.
#pragma once
#include <cmath>
#include <cstdint>

#include "engine_impl.hpp"

namespace revcol::engine::detail {

template <int Dim, PairOperator Op>
Diagnostics EngineImpl<Dim, Op>::diagnostics() const {
  Diagnostics d;
  double e = 0.0;
  for (std::size_t i = 0; i < n_; ++i)  // in id order: the sums' bits do not depend on storage
    for (int k = 0; k < Dim; ++k) {
      const double vk = p_[slot(i)].v[k];
      e += 0.5 * vk * vk;
      d.momentum[k] += vk;
    }
  d.energy = e;
  d.energy_drift = e0_ > 0 ? (e - e0_) / e0_ : 0.0;
  double dp = 0.0;
  for (int k = 0; k < Dim; ++k) dp += (d.momentum[k] - p0_[k]) * (d.momentum[k] - p0_[k]);
  d.momentum_drift = e0_ > 0 ? std::sqrt(dp) / std::sqrt(2.0 * e0_ * static_cast<double>(n_)) : 0.0;
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

}  // namespace revcol::engine::detail
