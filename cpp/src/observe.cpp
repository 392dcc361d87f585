// The observer: its start, segments, slabs, pair distances, blocks and the float engine's pair
// hook (the physics and the definitions are in revcol/engine/observe.hpp; the other hooks in
// observe_hooks.cpp, snapshots in observe_save.cpp, results in observe_results.cpp).
#include "revcol/engine/observe.hpp"

#include "observe_inline.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "revcol/error.hpp"


namespace revcol::engine {


void Observer::Block::add(const Block& b) {
  t1 = b.t1;
  k2 += b.k2;
  w += b.w;
  w_wall += b.w_wall;
  dist += b.dist;
  for (int k = 0; k < 3; ++k) wall_dp[k] += b.wall_dp[k];
  pairs += b.pairs;
  groups += b.groups;
  parts += b.parts;
  walls += b.walls;
  auto sum = [](std::vector<double>& a, const std::vector<double>& c) {
    for (std::size_t i = 0; i < a.size(); ++i) a[i] += c[i];
  };
  sum(slab, b.slab);
  sum(speed, b.speed);
  sum(pair, b.pair);
  sum(sp, b.sp);
  pyx += b.pyx;
  sum(slab_vx, b.slab_vx);
}

// The config's checks (the constructor's and a snapshot's): n particles in dim dimensions.
void observe_detail::check_config(const ObserveConfig& c, int dim, std::size_t n, const std::array<bool, 3>& walls) {
  require(std::isfinite(c.block_time) && c.block_time >= 0.0,
          [&] { return "observe: block_time must be finite and >= 0, got " + num(c.block_time); });
  require(c.min_blocks >= 2 && c.min_blocks <= 64,
          [&] { return "observe: min_blocks must be in [2, 64], got " + std::to_string(c.min_blocks); });
  require(c.slabs >= 0 && c.slabs <= kMaxBins,
          [&] { return "observe: slabs must be in [0, 2^20], got " + std::to_string(c.slabs); });
  require(c.slabs == 0 || (c.slab_axis >= 0 && c.slab_axis < dim),
          [&] { return "observe: slab_axis must be in [0, dim), got " + std::to_string(c.slab_axis); });
  require(c.speed_bins >= 0 && c.speed_bins <= kMaxBins,
          [&] { return "observe: speed_bins must be in [0, 2^20], got " + std::to_string(c.speed_bins); });
  require(std::isfinite(c.speed_max) && c.speed_max >= 0.0,
          [&] { return "observe: speed_max must be finite and >= 0, got " + num(c.speed_max); });
  require(c.pair_bins >= 0 && c.pair_bins <= kMaxBins,
          [&] { return "observe: pair_bins must be in [0, 2^20], got " + std::to_string(c.pair_bins); });
  if (c.pair_bins > 0) {
    require(std::isfinite(c.pair_rmax) && c.pair_rmax > 0.0,
            [&] { return "observe: pair_rmax must be finite and > 0 with pair_bins, got " + num(c.pair_rmax); });
    require(n <= kMaxPairParticles && n >= 2, "observe: pair distances need 2 to 64 particles");
    for (int k = 0; k < dim; ++k) require(walls[k], "observe: pair distances need walls on every axis");
  }
}


Observer::Observer(const ObserveConfig& c, int dim, const std::vector<double>& x, const std::vector<double>& v,
                   double t, const std::array<double, 3>& box, const std::array<bool, 3>& walls, double diameter)
    : cfg_(c), dim_(dim), n_(0), box_(box), walls_(walls), diameter_(diameter) {
  require(dim >= 1 && dim <= 3, "observe: dim must be 1, 2 or 3");
  require(!x.empty() && x.size() % static_cast<std::size_t>(dim) == 0 && v.size() == x.size(),
          "observe: positions and velocities must be n x dim");
  n_ = x.size() / static_cast<std::size_t>(dim);
  check_config(c, dim, n_, walls);
  double vv = 0.0;
  for (double q : v) vv += q * q;
  const double vrms = std::sqrt(vv / static_cast<double>(n_));
  require(vrms > 0.0 && std::isfinite(vrms), "observe: the particles must move");
  block_time_ = c.block_time > 0.0 ? c.block_time : diameter / vrms;
  speed_max_ = c.speed_max > 0.0 ? c.speed_max : 5.0 * vrms;
  bin_scale_ = c.speed_bins / speed_max_;
  bin_cap_ = c.speed_bins;
  set_geometry(box);
  slab_w_ = c.slabs > 0 ? box_[c.slab_axis] / c.slabs : 0.0;
  t_start_ = t_now_ = t;
  seg_.resize(n_);
  for (std::size_t i = 0; i < n_; ++i) {
    Segment& s = seg_[i];
    for (int k = 0; k < 3; ++k) s.x[k] = s.v[k] = 0.0;
    for (int k = 0; k < dim; ++k) s.x[k] = x[i * dim + k];
    s.t0 = t;
    s.v2 = s.speed = 0.0;
    if (c.slabs > 0) set_cell(s, std::floor(s.x[c.slab_axis] / slab_w_));
    set_velocity<0>(static_cast<int>(i), &v[i * dim]);
  }
  start_ = x;
  start_v_ = v;
  hc_ = dim * (dim - 1) / 2;
  if (c.pair_bins > 0) pair_t_.assign(n_ * n_, t);
  cur_ = empty_block(t);
  set_fast_until();
}

// The pair hook's fast path runs while t < fast_until_: the open block's end, or -inf
// with pair distances, the collision record or curved flights (a field: every hook then takes
// pair_general).
void Observer::set_fast_until() {
  const bool extras = cfg_.pair_bins > 0 || cfg_.collision_record || curved_;
  fast_until_ = extras ? -std::numeric_limits<double>::infinity() : cur_.t0 + block_time_;
}

void Observer::set_geometry(const std::array<double, 3>& box) {
  volume_ = 1.0;
  for (int k = 0; k < 3; ++k) {
    if (k >= dim_) box_[k] = 1.0;
    inv_box_[k] = 1.0 / box_[k];
    fold_[k] = k < dim_ && !walls_[k] ? box_[k] : 0.0;
    if (k < dim_) volume_ *= box[k];
  }
}

Observer::Block Observer::empty_block(double t0) const {
  Block b;
  b.t0 = b.t1 = t0;
  b.slab.assign(2 * static_cast<std::size_t>(cfg_.slabs), 0.0);
  b.speed.assign(cfg_.speed_bins + 1, 0.0);  // + the overflow bin (set_velocity)
  b.pair.assign(cfg_.pair_bins, 0.0);
  b.sp.assign(2 * static_cast<std::size_t>(ns_), 0.0);
  if (gamma_ != 0.0) b.slab_vx.assign(static_cast<std::size_t>(cfg_.slabs), 0.0);
  return b;
}








// Slabs. A segment keeps its cell along the slab axis, cell = floor(x_a / w) in unwrapped
// coordinates (any whole number on a periodic axis; [0, slabs) between walls), as the
// cell's lower edge lo = cell w, and its slab (cell mod slabs). A segment whose end is
// still in its cell never left it (the motion is linear): closing it is two comparisons and
// two additions. One that crossed walks the cells it went through (a piece of its duration
// to each) and takes its cell afresh from its end position (round-off at an edge never
// accumulates).
void Observer::set_cell(Segment& s, double c) const {
  const int ns = cfg_.slabs;
  if (walls_[cfg_.slab_axis]) c = std::min(static_cast<double>(ns - 1), std::max(0.0, c));
  s.lo = c * slab_w_;
  s.hi = s.lo + slab_w_;
  const double m = std::fmod(c, static_cast<double>(ns));
  s.slab = static_cast<int>(m < 0.0 ? m + ns : m);
}

// s's line left its cell before t: each cell it went through gets its piece of [t0, t]
// (s.x, s.t0 are still the segment's start; end is its position on the axis at t).
void Observer::slab_cross(Segment& s, double t, double end) {
  const int a = cfg_.slab_axis, ns = cfg_.slabs;
  const double va = s.v[a], step = slab_w_ / std::fabs(va);
  const int dir = va > 0.0 ? 1 : -1;
  int sl = s.slab;
  double from = s.t0, edge = s.t0 + ((va > 0.0 ? s.lo + slab_w_ : s.lo) - s.x[a]) / va;
  while (true) {
    const double until = std::min(t, std::max(from, edge));
    cur_.slab[2 * sl] += until - from;
    cur_.slab[2 * sl + 1] += s.v2 * (until - from);
    from = until;
    if (!(t > edge)) break;
    sl += dir;
    if (sl < 0 || sl >= ns) sl = walls_[a] ? std::min(ns - 1, std::max(0, sl)) : (sl < 0 ? ns - 1 : 0);
    edge += step;
  }
  set_cell(s, std::floor(end / slab_w_));
}

// Pair (i, j) from t0 to t1: the time |r| spends in each distance bin, exactly. In a field the
// two fall alike, so r is still linear in the time: its rate is the difference of the velocities
// at one instant (a segment's velocity is the one at its own start).
void Observer::pair_interval(int i, int j, double t0, double t1) {
  const double span = t1 - t0;
  if (!(span > 0.0)) return;
  double a = 0.0, b = 0.0, c = 0.0;
  for (int k = 0; k < dim_; ++k) {
    const double r = pos(i, k, t0) - pos(j, k, t0);
    double w = seg_[i].v[k] - seg_[j].v[k];
    if (k == fax_) [[unlikely]] w -= g_ * (seg_[i].t0 - seg_[j].t0);
    a += w * w;
    b += r * w;
    c += r * r;
  }
  const double end = a * span * span + 2.0 * b * span + c;
  double lo2 = std::min(c, end);
  const double tm = a > 0.0 ? -b / a : -1.0;
  if (tm > 0.0 && tm < span) lo2 = std::min(lo2, c - b * b / a);
  const double hi2 = std::max(c, end);
  const int nb = cfg_.pair_bins;
  const double h = cfg_.pair_rmax / nb;
  const int k0 = static_cast<int>(std::sqrt(std::max(0.0, lo2)) / h);
  const int k1 = std::min(nb - 1, static_cast<int>(std::sqrt(hi2) / h));
  if (k0 >= nb) return;
  if (k0 == k1 && std::sqrt(hi2) < cfg_.pair_rmax) {
    cur_.pair[k0] += span;
    return;
  }
  double below = time_below(a, b, c, (k0 * h) * (k0 * h), span);
  for (int k = k0; k <= k1; ++k) {
    const double up = time_below(a, b, c, ((k + 1) * h) * ((k + 1) * h), span);
    cur_.pair[k] += up - below;
    below = up;
  }
}


void Observer::pairs_to(int i, double t) {
  for (std::size_t j = 0; j < n_; ++j) {
    if (static_cast<int>(j) == i) continue;
    const std::size_t lo = std::min<std::size_t>(i, j), hi = std::max<std::size_t>(i, j);
    double& tp = pair_t_[lo * n_ + hi];
    pair_interval(static_cast<int>(lo), static_cast<int>(hi), tp, t);
    tp = t;
  }
}

// The open block ends at te: the sums are integrated to te and the MSD is taken from every
// particle's position then, without closing the segments (a segment's profile time goes
// to the block in which it closes), except with pair distances (small systems, exact).
void Observer::end_block() {
  const double te = cur_.t0 + block_time_;
  accumulate(te);
  if (cfg_.pair_bins > 0)
    for (std::size_t i = 0; i < n_; ++i) {
      close<3>(static_cast<int>(i), te);
      close_pairs(static_cast<int>(i), te);
    }
  double msd = 0.0;
  const std::size_t s0 = msd_sp_.size();  // a mixture: each species' MSD too (ns_ per point)
  msd_sp_.resize(s0 + static_cast<std::size_t>(ns_), 0.0);
  for (std::size_t i = 0; i < n_; ++i) {
    double own = 0.0;
    for (int k = 0; k < dim_; ++k) {
      const double d = pos(static_cast<int>(i), k, te) - start_[i * dim_ + k];
      msd += d * d;
      own += d * d;
    }
    if (ns_ > 0) msd_sp_[s0 + static_cast<std::size_t>(label_[i])] += own;
  }
  msd_t_.push_back(te - t_start_);
  msd_.push_back(msd / static_cast<double>(n_));
  for (int u = 0; u < ns_; ++u) msd_sp_[s0 + static_cast<std::size_t>(u)] /= static_cast<double>(sp_count_[u]);
  if (helf_kept_) helf_rec_.insert(helf_rec_.end(), helf_.begin(), helf_.begin() + hc_);  // integrated to te above
  if (!start_v_.empty()) {  // velocities are constant on segments: the segment's is the one at te
    double c = 0.0;
    for (std::size_t i = 0; i < n_; ++i)
      for (int k = 0; k < dim_; ++k) {
        double v = seg_[i].v[k];  // (shear: the peculiar velocity at te; a field: the velocity then)
        if (k == 0 && gamma_ != 0.0) v -= gamma_ * (pos(static_cast<int>(i), 1, te) - yref_);
        if (k == fax_) v += g_ * (te - seg_[i].t0);
        c += v * start_v_[i * dim_ + k];
      }
    vacf_.push_back(c / static_cast<double>(n_));
  }
  if (gamma_ != 0.0) {  // the shear stress of the block (integrated to te above)
    cur_.pyx = pyx_ - pyx_open_;
    pyx_open_ = pyx_;
  }
  cur_.t1 = te;
  blocks_.push_back(cur_);
  cur_ = empty_block(te);
  if (blocks_.size() == kMaxBlocks) {
    for (std::size_t u = 0; u < kMaxBlocks / 2; ++u) {
      Block m = blocks_[2 * u];
      m.add(blocks_[2 * u + 1]);
      blocks_[u] = std::move(m);
    }
    blocks_.resize(kMaxBlocks / 2);
    block_time_ *= 2.0;
  }
  set_fast_until();
}


// The pair hook with the dimension at compile time: the loops unrolled, positions advanced
// in d components only. Its common case runs in a path that calls nothing (fewer registers
// to save; measured: docs/physics.md): no block ends, no pair distances or collision
// record, and with slabs both segments end in their cells. Anything else takes
// pair_general: the same sums in the same order (same bits either way; test_observe).
template <int Dim>
void Observer::pair_d(double t, int a, int b, const double* va, const double* vb) {
  Segment& sa = seg_[a];
  Segment& sb = seg_[b];
  const double da = t - sa.t0, db = t - sb.t0;
  bool rare = t >= fast_until_;
  if (cfg_.slabs > 0) {
    const int x = cfg_.slab_axis;
    const double ea = sa.x[x] + sa.v[x] * da, eb = sb.x[x] + sb.v[x] * db;
    rare |= !in_cell(sa, ea) | !in_cell(sb, eb);
  }
  if (rare) [[unlikely]] {
    pair_general<Dim>(t, a, b, va, vb);
    return;
  }
  accumulate(t);
  cur_.speed[sa.bin] += da;
  if (cfg_.slabs > 0) add_slab(sa, da);
  fly<Dim>(sa, t, da);
  cur_.speed[sb.bin] += db;
  if (cfg_.slabs > 0) add_slab(sb, db);
  fly<Dim>(sb, t, db);
  virial<Dim>(a, b, va);
  set_velocity<Dim>(a, va);
  set_velocity<Dim>(b, vb);
  ++cur_.pairs;
  cur_.parts += 2;
}

// r . Delta p_a of a pair at the positions just closed, into the open block, and r_a Delta
// p_b into the Helfand moment.
template <int Dim>
[[gnu::always_inline]] inline void Observer::virial(int a, int b, const double* va) {
  double w = 0.0, r[Dim], dp[Dim];
  for (int k = 0; k < Dim; ++k) {
    // the nearest image (|r| = D < L / 2; fold_ is 0 on walled axes), rounding q to the
    // nearest whole number by adding and subtracting 1.5 2^52 (|q| < 2^51; no branch)
    const double r0 = seg_[a].x[k] - seg_[b].x[k], q = r0 * inv_box_[k];
    r[k] = r0 - fold_[k] * ((q + kRound) - kRound);
    dp[k] = mass_of(a) * (va[k] - seg_[a].v[k]);  // (1 x: the same bits for unit masses)
    w += r[k] * dp[k];
  }
  cur_.w += w;
  if (ns_ > 0) [[unlikely]] species_pair_virial(a, b, w);
  helfand_add<Dim>(r, dp);
}

// Any pair collision: blocks ended, pair distances, the record, slab crossings.
template <int Dim>
void Observer::pair_general(double t, int a, int b, const double* va, const double* vb) {
  reach(t);
  close<Dim>(a, t);
  close<Dim>(b, t);
  if (fax_ >= 0) [[unlikely]] {  // a field's running sums: the pair's terms out, in after (observe_field.cpp)
    field_terms(a, -1.0);
    field_terms(b, -1.0);
  }
  if (cfg_.collision_record) [[unlikely]] record_pair(a, b, va, vb);
  virial<Dim>(a, b, va);
  close_pairs(a, t);
  close_pairs(b, t);
  set_velocity<Dim>(a, va);
  set_velocity<Dim>(b, vb);
  if (fax_ >= 0) [[unlikely]] {
    field_terms(a, 1.0);
    field_terms(b, 1.0);
  }
  ++cur_.pairs;
  cur_.parts += 2;
}
template void Observer::pair_d<1>(double, int, int, const double*, const double*);
template void Observer::pair_d<2>(double, int, int, const double*, const double*);
template void Observer::pair_d<3>(double, int, int, const double*, const double*);

}  // namespace revcol::engine
