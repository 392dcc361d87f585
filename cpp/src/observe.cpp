// The observer of a float-engine run: segments, blocks and results (the physics and the
// definitions are in revcol/engine/observe.hpp).
#include "revcol/engine/observe.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "revcol/error.hpp"

namespace revcol::engine {

namespace {

constexpr std::size_t kMaxBlocks = 256;  // merged pairwise when full
constexpr int kMaxBins = 1 << 20;
constexpr std::size_t kMaxPairParticles = 64;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Time tau in [0, span] with a tau^2 + 2 b tau + c < q (a >= 0): the measure of the
// interval between the roots of the quadratic, clipped to [0, span].
double time_below(double a, double b, double c, double q, double span) {
  if (!(a > 0.0)) return c < q ? span : 0.0;
  const double disc = b * b - a * (c - q);
  if (!(disc > 0.0)) return 0.0;
  const double sq = std::sqrt(disc);
  const double lo = std::max(0.0, (-b - sq) / a), hi = std::min(span, (-b + sq) / a);
  return hi > lo ? hi - lo : 0.0;
}

double sample_sd(const std::vector<double>& x) {
  const double n = static_cast<double>(x.size());
  double m = 0.0;
  for (double q : x) m += q;
  m /= n;
  double s = 0.0;
  for (double q : x) s += (q - m) * (q - m);
  return std::sqrt(s / (n - 1.0));
}

}  // namespace

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
  sum(slab_t, b.slab_t);
  sum(slab_k2, b.slab_k2);
  sum(speed, b.speed);
  sum(pair, b.pair);
}

Observer::Observer(const ObserveConfig& c, int dim, const std::vector<double>& x, const std::vector<double>& v,
                   double t, const std::array<double, 3>& box, const std::array<bool, 3>& walls, double diameter)
    : cfg_(c), dim_(dim), n_(0), box_(box), walls_(walls), diameter_(diameter) {
  require(dim >= 1 && dim <= 3, "observe: dim must be 1, 2 or 3");
  require(!x.empty() && x.size() % static_cast<std::size_t>(dim) == 0 && v.size() == x.size(),
          "observe: positions and velocities must be n x dim");
  n_ = x.size() / static_cast<std::size_t>(dim);
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
    require(n_ <= kMaxPairParticles && n_ >= 2, "observe: pair distances need 2 to 64 particles");
    for (int k = 0; k < dim; ++k) require(walls[k], "observe: pair distances need walls on every axis");
  }
  double vv = 0.0;
  for (double q : v) vv += q * q;
  const double vrms = std::sqrt(vv / static_cast<double>(n_));
  require(vrms > 0.0 && std::isfinite(vrms), "observe: the particles must move");
  block_time_ = c.block_time > 0.0 ? c.block_time : diameter / vrms;
  speed_max_ = c.speed_max > 0.0 ? c.speed_max : 5.0 * vrms;
  bin_scale_ = c.speed_bins / speed_max_;
  volume_ = 1.0;
  for (int k = 0; k < 3; ++k) {
    if (k >= dim) box_[k] = 1.0;
    inv_box_[k] = 1.0 / box_[k];
    if (k < dim) volume_ *= box[k];
  }
  t_start_ = t_now_ = t;
  seg_.resize(n_);
  for (std::size_t i = 0; i < n_; ++i) {
    Segment& s = seg_[i];
    for (int k = 0; k < 3; ++k) s.x[k] = s.v[k] = 0.0;
    for (int k = 0; k < dim; ++k) s.x[k] = x[i * dim + k];
    s.t0 = t;
    set_velocity(static_cast<int>(i), &v[i * dim]);
  }
  start_ = x;
  if (c.pair_bins > 0) pair_t_.assign(n_ * n_, t);
  cur_ = empty_block(t);
}

Observer::Block Observer::empty_block(double t0) const {
  Block b;
  b.t0 = b.t1 = t0;
  b.slab_t.assign(cfg_.slabs, 0.0);
  b.slab_k2.assign(cfg_.slabs, 0.0);
  b.speed.assign(cfg_.speed_bins, 0.0);
  b.pair.assign(cfg_.pair_bins, 0.0);
  return b;
}

[[gnu::always_inline]] inline void Observer::set_velocity(int i, const double* v) {
  Segment& s = seg_[i];
  double v2 = 0.0;
  for (int k = 0; k < dim_; ++k) {
    s.v[k] = v[k];
    v2 += v[k] * v[k];
  }
  s.v2 = v2;
  s.speed = std::sqrt(v2);
  s.bin = -1;
  if (cfg_.speed_bins > 0) {
    const double b = s.speed * bin_scale_;
    if (b < cfg_.speed_bins) s.bin = static_cast<int>(b);
  }
}

// Closes i's segment at t: its duration weights v^2, the speed, its speed bin and its slabs.
// (Components beyond dim are 0: the loops run over 3, unrolled, with no test of dim.)
[[gnu::always_inline]] inline void Observer::close(int i, double t) {
  Segment& s = seg_[i];
  const double dt = t - s.t0;
  cur_.k2 += s.v2 * dt;
  cur_.dist += s.speed * dt;
  if (s.bin >= 0) cur_.speed[s.bin] += dt;
  if (cfg_.slabs > 0 && dt > 0.0) slab_walk(s, dt);
  for (int k = 0; k < 3; ++k) s.x[k] += s.v[k] * dt;
  s.t0 = t;
}

// The slabs s's line crosses in dt after its start, each with the time spent in it.
void Observer::slab_walk(const Segment& s, double dt) {
  const int a = cfg_.slab_axis, ns = cfg_.slabs;
  const double L = box_[a], w = L / ns, va = s.v[a];
  double u = s.x[a];
  if (!walls_[a]) {  // folded into [0, L) (a periodic axis); floor by a cast (no libm call)
    const double q = u * inv_box_[a];
    double fl = static_cast<double>(static_cast<std::int64_t>(q));
    if (fl > q) fl -= 1.0;
    u -= L * fl;
  }
  int sl = std::min(ns - 1, std::max(0, static_cast<int>(u * (ns * inv_box_[a]))));
  const double end = u + va * dt;
  if (end >= sl * w && end < (sl + 1) * w) {  // the common case: the segment stays in its slab
    cur_.slab_t[sl] += dt;
    cur_.slab_k2[sl] += s.v2 * dt;
    return;
  }
  double rem = dt;
  while (rem > 0.0) {
    double piece = rem;
    if (va != 0.0) {
      const double d = std::max(0.0, va > 0.0 ? (sl + 1) * w - u : u - sl * w);
      piece = std::min(rem, d / std::fabs(va));
    }
    cur_.slab_t[sl] += piece;
    cur_.slab_k2[sl] += s.v2 * piece;
    rem -= piece;
    if (rem <= 0.0) break;
    sl += va > 0.0 ? 1 : -1;
    if (sl < 0 || sl >= ns) {
      if (walls_[a]) {  // round-off at a wall: the rest stays in the end slab
        sl = std::min(ns - 1, std::max(0, sl));
        cur_.slab_t[sl] += rem;
        cur_.slab_k2[sl] += s.v2 * rem;
        break;
      }
      sl = sl < 0 ? ns - 1 : 0;
    }
    u = va > 0.0 ? sl * w : (sl + 1) * w;
  }
}

// Pair (i, j) from t0 to t1: the time |r| spends in each distance bin, exactly.
void Observer::pair_interval(int i, int j, double t0, double t1) {
  const double span = t1 - t0;
  if (!(span > 0.0)) return;
  double a = 0.0, b = 0.0, c = 0.0;
  for (int k = 0; k < dim_; ++k) {
    const double r = pos(i, k, t0) - pos(j, k, t0), w = seg_[i].v[k] - seg_[j].v[k];
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

[[gnu::always_inline]] inline void Observer::close_pairs(int i, double t) {
  if (cfg_.pair_bins == 0) return;
  for (std::size_t j = 0; j < n_; ++j) {
    if (static_cast<int>(j) == i) continue;
    const std::size_t lo = std::min<std::size_t>(i, j), hi = std::max<std::size_t>(i, j);
    double& tp = pair_t_[lo * n_ + hi];
    pair_interval(static_cast<int>(lo), static_cast<int>(hi), tp, t);
    tp = t;
  }
}

void Observer::end_block() {
  const double te = cur_.t0 + block_time_;
  for (std::size_t i = 0; i < n_; ++i) {
    close(static_cast<int>(i), te);
    close_pairs(static_cast<int>(i), te);
  }
  double msd = 0.0;
  for (std::size_t i = 0; i < n_; ++i)
    for (int k = 0; k < dim_; ++k) {
      const double d = seg_[i].x[k] - start_[i * dim_ + k];
      msd += d * d;
    }
  msd_t_.push_back(te - t_start_);
  msd_.push_back(msd / static_cast<double>(n_));
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
}

[[gnu::always_inline]] inline void Observer::reach(double t) {
  while (t >= cur_.t0 + block_time_) end_block();
  t_now_ = t;
}

void Observer::pair(double t, int a, int b, const double* va, const double* vb) {
  reach(t);
  close(a, t);
  close(b, t);
  if (cfg_.collision_record) [[unlikely]] record_pair(a, b, va, vb);
  double w = 0.0;
  for (int k = 0; k < dim_; ++k) {
    double r = seg_[a].x[k] - seg_[b].x[k];
    if (!walls_[k]) {  // the nearest image (|r| = D < L / 2), rounding by a cast
      const double q = r * inv_box_[k];
      r -= box_[k] * static_cast<double>(static_cast<std::int64_t>(q + (q >= 0.0 ? 0.5 : -0.5)));
    }
    w += r * (va[k] - seg_[a].v[k]);
  }
  cur_.w += w;
  close_pairs(a, t);
  close_pairs(b, t);
  set_velocity(a, va);
  set_velocity(b, vb);
  ++cur_.pairs;
  cur_.parts += 2;
}

void Observer::group(double t, int n, const int* ids, const double* x, const double* v) {
  reach(t);
  for (int u = 0; u < n; ++u) {
    const int i = ids[u];
    for (int k = 0; k < dim_; ++k) cur_.w += x[u * dim_ + k] * (v[u * dim_ + k] - seg_[i].v[k]);
    close(i, t);
    close_pairs(i, t);
  }
  for (int u = 0; u < n; ++u) set_velocity(ids[u], v + u * dim_);
  ++cur_.groups;
  cur_.parts += static_cast<std::uint64_t>(n);
}

void Observer::wall(double t, int i, const double* v) {
  reach(t);
  close(i, t);
  close_pairs(i, t);
  const double r = 0.5 * diameter_, tol = 1e-6 * diameter_;
  for (int k = 0; k < dim_; ++k) {
    const double dv = v[k] - seg_[i].v[k], xk = seg_[i].x[k];
    if (!walls_[k] || dv == 0.0) continue;
    if (std::fabs(xk - r) > tol && std::fabs(xk - (box_[k] - r)) > tol) continue;  // a tangential flip (v -> -v)
    cur_.wall_dp[k] += std::fabs(dv);
    cur_.w_wall += xk * dv;
  }
  set_velocity(i, v);
  ++cur_.walls;
}

void Observer::sync(double t) {
  reach(t);
  for (std::size_t i = 0; i < n_; ++i) {
    close(static_cast<int>(i), t);
    close_pairs(static_cast<int>(i), t);
  }
}

Observation Observer::results() const {
  Observation o;
  o.dim = dim_;
  o.n = n_;
  o.t_start = t_start_;
  o.t_end = t_now_;
  Block tot = empty_block(t_start_);
  for (const Block& b : blocks_) tot.add(b);
  tot.add(cur_);
  tot.t1 = t_now_;
  o.pair_collisions = tot.pairs;
  o.group_collisions = tot.groups;
  o.particle_collisions = tot.parts;
  o.wall_reflections = tot.walls;
  // the blocks of the errors: complete ones, merged down to [min_blocks, 2 min_blocks)
  std::vector<Block> bl = blocks_;
  while (bl.size() >= 2 * static_cast<std::size_t>(cfg_.min_blocks)) {
    std::vector<Block> m;
    for (std::size_t u = 0; u + 1 < bl.size(); u += 2) {
      m.push_back(bl[u]);
      m.back().add(bl[u + 1]);
    }
    bl = std::move(m);
  }
  o.blocks = static_cast<int>(bl.size());
  o.block_time = bl.empty() ? 0.0 : bl[0].t1 - bl[0].t0;
  const double N = static_cast<double>(n_), d = dim_;
  auto est = [&](auto f) {
    Estimate e;
    const double tau = tot.t1 - tot.t0;
    e.value = tau > 0.0 ? f(tot, tau) : kNaN;
    if (bl.size() >= 2) {
      std::vector<double> vals;
      for (const Block& b : bl) vals.push_back(f(b, b.t1 - b.t0));
      e.error = sample_sd(vals) / std::sqrt(static_cast<double>(vals.size()));
    }
    return e;
  };
  auto ratio = [](double a, double b) { return b != 0.0 ? a / b : kNaN; };
  o.temperature = est([&](const Block& b, double tau) { return b.k2 / (d * N * tau); });
  o.pressure_virial = est([&](const Block& b, double tau) { return (b.k2 + b.w) / (d * volume_ * tau); });
  o.compressibility = est([&](const Block& b, double) { return 1.0 + ratio(b.w, b.k2); });
  o.collision_rate = est([&](const Block& b, double tau) { return static_cast<double>(b.parts) / (N * tau); });
  o.mean_free_time = est([&](const Block& b, double tau) { return ratio(N * tau, static_cast<double>(b.parts)); });
  o.mean_free_path = est([&](const Block& b, double) { return ratio(b.dist, static_cast<double>(b.parts)); });
  o.virial_balance = est([&](const Block& b, double) { return ratio(b.k2 + b.w + b.w_wall, b.k2); });
  for (int k = 0; k < dim_; ++k) {
    if (!walls_[k]) continue;
    const double area = volume_ / box_[k];
    o.pressure_wall[k] = est([&](const Block& b, double tau) { return b.wall_dp[k] / (2.0 * tau * area); });
  }
  auto profile = [&](int bins, double width, auto f) {
    Profile p;
    for (int u = 0; u <= bins; ++u) p.edges.push_back(u * width);
    for (int u = 0; u < bins; ++u) {
      const Estimate e = est([&](const Block& b, double tau) { return f(b, tau, u); });
      p.value.push_back(e.value);
      p.error.push_back(e.error);
    }
    return p;
  };
  if (cfg_.slabs > 0) {
    const double w = box_[cfg_.slab_axis] / cfg_.slabs, vol = volume_ / cfg_.slabs;
    o.slab_density = profile(cfg_.slabs, w, [&](const Block& b, double tau, int u) { return b.slab_t[u] / (tau * vol); });
    o.slab_temperature =
        profile(cfg_.slabs, w, [&](const Block& b, double, int u) { return ratio(b.slab_k2[u], d * b.slab_t[u]); });
  }
  if (cfg_.speed_bins > 0) {
    const double h = speed_max_ / cfg_.speed_bins;
    o.speed = profile(cfg_.speed_bins, h, [&](const Block& b, double tau, int u) { return b.speed[u] / (N * tau * h); });
  }
  if (cfg_.pair_bins > 0) {
    const double h = cfg_.pair_rmax / cfg_.pair_bins, np = 0.5 * N * (N - 1.0);
    o.pair_distance =
        profile(cfg_.pair_bins, h, [&](const Block& b, double tau, int u) { return b.pair[u] / (np * tau * h); });
  }
  o.msd_time = msd_t_;
  o.msd = msd_;
  return o;
}

// The collision record's entry of a pair at the positions just closed (header comment).
void Observer::record_pair(int a, int b, const double* va, const double* vb) {
  double r[3] = {0.0, 0.0, 0.0}, rr = 0.0;
  for (int k = 0; k < dim_; ++k) {
    r[k] = seg_[a].x[k] - seg_[b].x[k];
    if (!walls_[k]) r[k] -= box_[k] * std::nearbyint(r[k] * inv_box_[k]);  // the nearest image
    rr += r[k] * r[k];
  }
  const double inv = 1.0 / std::sqrt(rr);
  for (int k = 0; k < dim_; ++k) record_.push_back(r[k] * inv);
  for (int k = 0; k < dim_; ++k) record_.push_back(va[k] - vb[k]);
}

}  // namespace revcol::engine
