// The observer of a float-engine run: segments, blocks and results (the physics and the
// definitions are in revcol/engine/observe.hpp).
#include "revcol/engine/observe.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "revcol/error.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace revcol::engine {

namespace {

constexpr std::size_t kMaxBlocks = 256;  // merged pairwise when full
constexpr std::size_t kHeader = 18, kBlockReals = 9, kBlockCounts = 4;  // snapshots (save)
constexpr int kMaxBins = 1 << 20;
constexpr std::size_t kMaxPairParticles = 64;
constexpr double kRound = 6755399441055744.0;  // 1.5 2^52

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

// sqrt of x >= 0, correctly rounded like std::sqrt, without its errno branch (x is a sum of
// squares: never negative).
inline double root(double x) {
#if defined(__SSE2__)
  return _mm_cvtsd_f64(_mm_sqrt_sd(_mm_setzero_pd(), _mm_set_sd(x)));
#else
  return std::sqrt(x);
#endif
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
  sum(slab, b.slab);
  sum(speed, b.speed);
  sum(pair, b.pair);
}

namespace {

// The config's checks (the constructor's and a snapshot's): n particles in dim dimensions.
void check_config(const ObserveConfig& c, int dim, std::size_t n, const std::array<bool, 3>& walls) {
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

}  // namespace

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
  if (c.pair_bins > 0) pair_t_.assign(n_ * n_, t);
  cur_ = empty_block(t);
  set_fast_until();
}

// The pair hook's fast path runs while t < fast_until_: the open block's end, or -inf
// with pair distances or the collision record (every hook then takes pair_general).
void Observer::set_fast_until() {
  const bool extras = cfg_.pair_bins > 0 || cfg_.collision_record;
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
  return b;
}

// K: the dimension known at compile time (the pair hook's fast path), 0: dim_ at run time.
// The same sums in the same order either way (same bits).
template <int K>
[[gnu::always_inline]] inline void Observer::set_velocity(int i, const double* v) {
  Segment& s = seg_[i];
  double v2 = v[0] * v[0];  // (what 0 + v[0]^2 gives, a square being never -0)
  s.v[0] = v[0];
  for (int k = 1; k < (K > 0 ? K : dim_); ++k) {
    s.v[k] = v[k];
    v2 += v[k] * v[k];
  }
  const double speed = root(v2);
  v2_sum_ += v2 - s.v2;  // sum_i v_i^2 and sum_i |v_i| (their time integrals: accumulate)
  speed_sum_ += speed - s.speed;
  s.v2 = v2;
  s.speed = speed;
  // the speed's bin; speeds from speed_max up, and every speed without a histogram
  // (bin_scale_ 0), go to the last bin, never reported: close adds without a test
  s.bin = static_cast<int>(std::min(speed * bin_scale_, bin_cap_));
}

// ---- snapshots (the layout of save's reals and counts: observe.hpp) ----------------------

void Observer::save(std::vector<double>& reals, std::vector<std::uint64_t>& counts) const {
  const ObserveConfig& c = cfg_;
  reals = {static_cast<double>(dim_), static_cast<double>(n_), c.block_time, static_cast<double>(c.min_blocks),
           static_cast<double>(c.slab_axis), static_cast<double>(c.slabs), static_cast<double>(c.speed_bins),
           c.speed_max, static_cast<double>(c.pair_bins), c.pair_rmax, block_time_, t_start_, t_now_, speed_max_,
           static_cast<double>(blocks_.size()), static_cast<double>(msd_.size()), v2_sum_, speed_sum_};
  for (const Segment& s : seg_) {
    reals.insert(reals.end(), s.x, s.x + dim_);
    reals.insert(reals.end(), s.v, s.v + dim_);
    reals.push_back(s.t0);
    if (cfg_.slabs > 0) reals.push_back(std::round(s.lo / slab_w_));  // its cell
  }
  reals.insert(reals.end(), start_.begin(), start_.end());
  reals.insert(reals.end(), pair_t_.begin(), pair_t_.end());
  counts.clear();
  auto block = [&](const Block& b) {
    for (double q : {b.t0, b.t1, b.k2, b.w, b.w_wall, b.dist, b.wall_dp[0], b.wall_dp[1], b.wall_dp[2]})
      reals.push_back(q);
    for (int half = 0; half < 2; ++half)  // the times, then the v^2 times
      for (std::size_t u = 0; u < b.slab.size(); u += 2) reals.push_back(b.slab[u + half]);
    reals.insert(reals.end(), b.speed.begin(), b.speed.end() - 1);  // not the overflow bin
    reals.insert(reals.end(), b.pair.begin(), b.pair.end());
    for (std::uint64_t q : {b.pairs, b.groups, b.parts, b.walls}) counts.push_back(q);
  };
  for (const Block& b : blocks_) block(b);
  block(cur_);
  reals.insert(reals.end(), msd_t_.begin(), msd_t_.end());
  reals.insert(reals.end(), msd_.begin(), msd_.end());
}

Observer::Observer(const std::vector<double>& reals, const std::vector<std::uint64_t>& counts, int dim,
                   const std::vector<double>& v, double t, const std::array<double, 3>& box,
                   const std::array<bool, 3>& walls, double diameter)
    : dim_(dim), n_(0), box_(box), walls_(walls), diameter_(diameter) {
  require(dim >= 1 && dim <= 3 && !v.empty() && v.size() % static_cast<std::size_t>(dim) == 0,
          "snapshot: observer: the particles' velocities must be n x dim");
  n_ = v.size() / static_cast<std::size_t>(dim);
  require(reals.size() >= kHeader, "snapshot: observer holds fewer values than its header");
  for (double q : reals) require(std::isfinite(q), "snapshot: observer values must be finite");
  auto whole = [&](std::size_t k, double lo, double hi, const char* name) {
    const double q = reals[k];
    require(q >= lo && q <= hi && q == std::floor(q),
            [&] { return std::string("snapshot: observer ") + name + " must be a whole number in range, got " +
                         num(q); });
    return static_cast<std::int64_t>(q);
  };
  require(whole(0, 1, 3, "dim") == dim && whole(1, 1, 1e15, "n") == static_cast<std::int64_t>(n_),
          "snapshot: observer was taken of another number of particles or dimensions");
  cfg_.block_time = reals[2];
  cfg_.min_blocks = static_cast<int>(whole(3, 2, 64, "min_blocks"));
  cfg_.slab_axis = static_cast<int>(whole(4, 0, 2, "slab_axis"));
  cfg_.slabs = static_cast<int>(whole(5, 0, kMaxBins, "slabs"));
  cfg_.speed_bins = static_cast<int>(whole(6, 0, kMaxBins, "speed_bins"));
  cfg_.speed_max = reals[7];
  cfg_.pair_bins = static_cast<int>(whole(8, 0, kMaxBins, "pair_bins"));
  cfg_.pair_rmax = reals[9];
  check_config(cfg_, dim, n_, walls);
  block_time_ = reals[10];
  t_start_ = reals[11];
  t_now_ = reals[12];
  speed_max_ = reals[13];
  require(block_time_ > 0.0 && speed_max_ > 0.0, "snapshot: observer block time and speed_max must be > 0");
  require(t_start_ <= t_now_ && t_now_ <= t, "snapshot: observer times must be ordered: start <= last update <= clock");
  const auto nb = static_cast<std::size_t>(whole(14, 0, kMaxBlocks - 1, "block count"));
  const auto nm = static_cast<std::size_t>(whole(15, 0, 1e12, "MSD count"));
  const std::size_t d = static_cast<std::size_t>(dim), np = cfg_.pair_bins > 0 ? n_ * n_ : 0;
  const std::size_t per_block = kBlockReals + 2 * cfg_.slabs + cfg_.speed_bins + cfg_.pair_bins;
  const std::size_t per_particle = 3 * d + 1 + (cfg_.slabs > 0 ? 1 : 0);
  require(reals.size() == kHeader + n_ * per_particle + np + (nb + 1) * per_block + 2 * nm,
          "snapshot: observer: its size does not match its header (particles, bins, blocks, MSD points)");
  require(counts.size() == (nb + 1) * kBlockCounts, "snapshot: observer_counts must hold 4 counts per block");
  bin_scale_ = cfg_.speed_bins / speed_max_;
  bin_cap_ = cfg_.speed_bins;
  set_geometry(box);
  slab_w_ = cfg_.slabs > 0 ? box_[cfg_.slab_axis] / cfg_.slabs : 0.0;
  std::size_t u = kHeader;
  seg_.resize(n_);
  for (std::size_t i = 0; i < n_; ++i) {
    Segment& s = seg_[i];
    for (int k = 0; k < 3; ++k) s.x[k] = s.v[k] = 0.0;
    s.v2 = s.speed = 0.0;
    for (std::size_t k = 0; k < d; ++k) s.x[k] = reals[u++];
    for (std::size_t k = 0; k < d; ++k)
      require(reals[u++] == v[i * d + k], "snapshot: observer: a segment's velocity is not its particle's");
    s.t0 = reals[u++];
    require(s.t0 >= t_start_ && s.t0 <= t, "snapshot: observer: a segment starts outside the observed time");
    if (cfg_.slabs > 0) {
      const double cell = reals[u++];
      require(cell == std::floor(cell) && std::fabs(cell) < 1e15 &&
                  (!walls_[cfg_.slab_axis] || (cell >= 0.0 && cell < cfg_.slabs)),
              "snapshot: observer: a segment's slab cell must be a whole number (in [0, slabs) between walls)");
      set_cell(s, cell);
    }
    set_velocity<0>(static_cast<int>(i), &v[i * d]);
  }
  auto take = [&](std::vector<double>& out, std::size_t m) {
    out.assign(reals.begin() + static_cast<std::ptrdiff_t>(u), reals.begin() + static_cast<std::ptrdiff_t>(u + m));
    u += m;
  };
  take(start_, n_ * d);
  take(pair_t_, np);
  auto block = [&](std::size_t b) {
    Block k = empty_block(reals[u]);
    k.t1 = reals[u + 1];
    k.k2 = reals[u + 2];
    k.w = reals[u + 3];
    k.w_wall = reals[u + 4];
    k.dist = reals[u + 5];
    for (int a = 0; a < 3; ++a) k.wall_dp[a] = reals[u + 6 + a];
    require(k.t0 >= t_start_ && k.t1 >= k.t0 && k.t1 <= t, "snapshot: observer: a block outside the observed time");
    u += kBlockReals;
    for (int half = 0; half < 2; ++half)
      for (std::size_t w = 0; w < k.slab.size(); w += 2) k.slab[w + half] = reals[u++];
    take(k.speed, k.speed.size() - 1);
    k.speed.push_back(0.0);  // the overflow bin (never reported, not saved)
    take(k.pair, k.pair.size());
    k.pairs = counts[b * kBlockCounts];
    k.groups = counts[b * kBlockCounts + 1];
    k.parts = counts[b * kBlockCounts + 2];
    k.walls = counts[b * kBlockCounts + 3];
    return k;
  };
  for (std::size_t b = 0; b < nb; ++b) blocks_.push_back(block(b));
  cur_ = block(nb);
  take(msd_t_, nm);
  take(msd_, nm);
  v2_sum_ = reals[16];  // the running sums as they were (set_velocity above rebuilt them afresh)
  speed_sum_ = reals[17];
  set_fast_until();
}

// Closes i's segment at t: its duration weights its speed bin and its slabs (credited to
// the open block); its position moves to t. K: the position components advanced, the
// dimension on the pair hook's path, elsewhere 3 with no test of dim (the components beyond
// d are 0 whatever dt).
template <int K>
[[gnu::always_inline]] inline void Observer::close(int i, double t) {
  Segment& s = seg_[i];
  const double dt = t - s.t0;
  cur_.speed[s.bin] += dt;
  if (cfg_.slabs > 0) {
    const double end = s.x[cfg_.slab_axis] + s.v[cfg_.slab_axis] * dt;
    if (in_cell(s, end)) {
      add_slab(s, dt);
    } else {
      slab_cross(s, t, end);
    }
  }
  fly<K>(s, t, dt);
}

// Slabs: whether s's position on the slab axis at its end is still in its cell (then the
// segment never left it: the motion is linear).
[[gnu::always_inline]] inline bool Observer::in_cell(const Segment& s, double end) {
  return end >= s.lo && end < s.hi;
}

// A segment that ends in its cell: its duration (and v^2 times it) to its slab.
[[gnu::always_inline]] inline void Observer::add_slab(const Segment& s, double dt) {
  double* q = &cur_.slab[2 * static_cast<std::size_t>(s.slab)];
  q[0] += dt;
  q[1] += s.v2 * dt;
}

// The segment's position moves on by dt to t (K components).
template <int K>
[[gnu::always_inline]] inline void Observer::fly(Segment& s, double t, double dt) {
  for (int k = 0; k < K; ++k) s.x[k] += s.v[k] * dt;
  s.t0 = t;
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
  if (cfg_.pair_bins > 0) pairs_to(i, t);  // out of line: the hooks' hot path keeps fewer registers
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

// The integrals of sum v^2 and sum |v| (constant between velocity changes) from the last
// update to t, which becomes the last update.
[[gnu::always_inline]] inline void Observer::accumulate(double t) {
  const double dt = t - t_now_;
  cur_.k2 += v2_sum_ * dt;
  cur_.dist += speed_sum_ * dt;
  t_now_ = t;
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
  for (std::size_t i = 0; i < n_; ++i)
    for (int k = 0; k < dim_; ++k) {
      const double d = pos(static_cast<int>(i), k, te) - start_[i * dim_ + k];
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
  set_fast_until();
}

[[gnu::always_inline]] inline void Observer::reach(double t) {
  while (t >= cur_.t0 + block_time_) end_block();
  accumulate(t);
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

// r . Delta p_a of a pair at the positions just closed, into the open block.
template <int Dim>
[[gnu::always_inline]] inline void Observer::virial(int a, int b, const double* va) {
  double w = 0.0;
  for (int k = 0; k < Dim; ++k) {
    // the nearest image (|r| = D < L / 2; fold_ is 0 on walled axes), rounding q to the
    // nearest whole number by adding and subtracting 1.5 2^52 (|q| < 2^51; no branch)
    const double r0 = seg_[a].x[k] - seg_[b].x[k], q = r0 * inv_box_[k];
    const double r = r0 - fold_[k] * ((q + kRound) - kRound);
    w += r * (va[k] - seg_[a].v[k]);
  }
  cur_.w += w;
}

// Any pair collision: blocks ended, pair distances, the record, slab crossings.
template <int Dim>
void Observer::pair_general(double t, int a, int b, const double* va, const double* vb) {
  reach(t);
  close<Dim>(a, t);
  close<Dim>(b, t);
  if (cfg_.collision_record) [[unlikely]] record_pair(a, b, va, vb);
  virial<Dim>(a, b, va);
  close_pairs(a, t);
  close_pairs(b, t);
  set_velocity<Dim>(a, va);
  set_velocity<Dim>(b, vb);
  ++cur_.pairs;
  cur_.parts += 2;
}
template void Observer::pair_d<1>(double, int, int, const double*, const double*);
template void Observer::pair_d<2>(double, int, int, const double*, const double*);
template void Observer::pair_d<3>(double, int, int, const double*, const double*);

void Observer::group(double t, int n, const int* ids, const double* x, const double* v) {
  reach(t);
  for (int u = 0; u < n; ++u) {
    const int i = ids[u];
    for (int k = 0; k < dim_; ++k) cur_.w += x[u * dim_ + k] * (v[u * dim_ + k] - seg_[i].v[k]);
    close<3>(i, t);
    close_pairs(i, t);
  }
  for (int u = 0; u < n; ++u) set_velocity<0>(ids[u], v + u * dim_);
  ++cur_.groups;
  cur_.parts += static_cast<std::uint64_t>(n);
}

void Observer::wall(double t, int i, const double* v) {
  reach(t);
  close<3>(i, t);
  close_pairs(i, t);
  const double r = 0.5 * diameter_, tol = 1e-6 * diameter_;
  for (int k = 0; k < dim_; ++k) {
    const double dv = v[k] - seg_[i].v[k], xk = seg_[i].x[k];
    if (!walls_[k] || dv == 0.0) continue;
    if (std::fabs(xk - r) > tol && std::fabs(xk - (box_[k] - r)) > tol) continue;  // a tangential flip (v -> -v)
    cur_.wall_dp[k] += std::fabs(dv);
    cur_.w_wall += xk * dv;
  }
  set_velocity<0>(i, v);
  ++cur_.walls;
}

// The *_at hooks (engines whose events move centres, the lattice engine): i's segment,
// closed at the event, moves to the position x the engine gives, by the nearest image of
// the difference on periodic axes (its position stays unwrapped), and takes the slab cell
// of its new position.
void Observer::place(int i, const double* x) {
  Segment& s = seg_[i];
  for (int k = 0; k < dim_; ++k) {
    double d = x[k] - s.x[k];
    if (!walls_[k]) d -= box_[k] * std::nearbyint(d * inv_box_[k]);
    s.x[k] += d;
  }
  if (cfg_.slabs > 0) set_cell(s, std::floor(s.x[cfg_.slab_axis] / slab_w_));
}

void Observer::pair_at(double t, int a, int b, const double* xa, const double* xb, const double* va,
                       const double* vb) {
  reach(t);
  close<3>(a, t);
  close<3>(b, t);
  close_pairs(a, t);
  close_pairs(b, t);
  double w = 0.0;
  for (int k = 0; k < dim_; ++k) {
    double r = xa[k] - xb[k];
    if (!walls_[k]) r -= box_[k] * std::nearbyint(r * inv_box_[k]);  // the nearest image
    w += r * (va[k] - seg_[a].v[k]);
  }
  cur_.w += w;
  place(a, xa);
  place(b, xb);
  if (cfg_.collision_record) [[unlikely]] record_pair(a, b, va, vb);
  set_velocity<0>(a, va);
  set_velocity<0>(b, vb);
  ++cur_.pairs;
  cur_.parts += 2;
}

void Observer::group_at(double t, int n, const int* ids, const double* x, const double* v) {
  reach(t);
  for (int u = 0; u < n; ++u) {
    const int i = ids[u];
    close<3>(i, t);
    close_pairs(i, t);
    for (int k = 0; k < dim_; ++k) cur_.w += x[u * dim_ + k] * (v[u * dim_ + k] - seg_[i].v[k]);
  }
  for (int u = 0; u < n; ++u) {
    place(ids[u], x + u * dim_);
    set_velocity<0>(ids[u], v + u * dim_);
  }
  ++cur_.groups;
  cur_.parts += static_cast<std::uint64_t>(n);
}

void Observer::wall_at(double t, int i, const double* x, const double* v, unsigned axes) {
  reach(t);
  close<3>(i, t);
  close_pairs(i, t);
  const double r = 0.5 * diameter_;
  for (int k = 0; k < dim_; ++k) {
    if (!(axes >> k & 1u) || !walls_[k]) continue;
    const double dv = v[k] - seg_[i].v[k];
    cur_.wall_dp[k] += std::fabs(dv);
    cur_.w_wall += (v[k] > 0.0 ? r : box_[k] - r) * dv;  // the contact plane it left from
  }
  place(i, x);
  set_velocity<0>(i, v);
  ++cur_.walls;
}

void Observer::sync(double t) {
  reach(t);
  for (std::size_t i = 0; i < n_; ++i) {
    close<3>(static_cast<int>(i), t);
    close_pairs(static_cast<int>(i), t);
  }
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
