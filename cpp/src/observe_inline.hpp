// The observer's private parts shared by its sources (observe.cpp, observe_hooks.cpp,
// observe_save.cpp): limits, the snapshot layout's sizes, the config check, and the inline
// steps of every hook (a segment's close, the running sums, block ends). Measure before
// changing: the pair hook's fast path is built from these.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>

#include "revcol/engine/observe.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace revcol::engine {
namespace observe_detail {

inline constexpr std::size_t kMaxBlocks = 256;  // merged pairwise when full
inline constexpr std::size_t kHeader = 18, kBlockReals = 9, kBlockCounts = 4;  // snapshots (save)
inline constexpr int kMaxBins = 1 << 20;
inline constexpr std::size_t kMaxPairParticles = 64;
inline constexpr double kRound = 6755399441055744.0;  // 1.5 2^52

// sqrt of x >= 0, correctly rounded like std::sqrt, without its errno branch (x is a sum of
// squares: never negative).
inline double root(double x) {
#if defined(__SSE2__)
  return _mm_cvtsd_f64(_mm_sqrt_sd(_mm_setzero_pd(), _mm_set_sd(x)));
#else
  return std::sqrt(x);
#endif
}

// Time tau in [0, span] with a tau^2 + 2 b tau + c < q (a >= 0): the measure of the
// interval between the roots of the quadratic, clipped to [0, span].
inline double time_below(double a, double b, double c, double q, double span) {
  if (!(a > 0.0)) return c < q ? span : 0.0;
  const double disc = b * b - a * (c - q);
  if (!(disc > 0.0)) return 0.0;
  const double sq = std::sqrt(disc);
  const double lo = std::max(0.0, (-b - sq) / a), hi = std::min(span, (-b + sq) / a);
  return hi > lo ? hi - lo : 0.0;
}

// The integral over [0, span] of sqrt((w0 - g h)^2 + p2) dh: the distance covered at a velocity
// one component of which changes at -g (shear's peculiar u_x, a field's v_f), p2 >= 0 the square
// of the rest. In w = w0 - g h it is (G(w0) - G(w1)) / g, G(w) = (w S + p2 asinh(w / p)) / 2,
// S = sqrt(w^2 + p2), written without the cancellation of two large G (every term a multiple of
// w0 - w1 = g span).
inline double quadratic_distance(double w0, double g, double p2, double span) {
  const double w1 = w0 - g * span;
  const double s0 = std::sqrt(w0 * w0 + p2), s1 = std::sqrt(w1 * w1 + p2);
  if (g == 0.0) return s0 * span;
  if (!(p2 > 0.0))  // |w| along a line: through zero or not
    return w0 * w1 >= 0.0 ? 0.5 * std::fabs(w0 + w1) * span : (w0 * w0 + w1 * w1) / (2.0 * std::fabs(g));
  const double p = std::sqrt(p2), a = w0 / p, b = w1 / p;
  // asinh(a) - asinh(b), from one asinh when a and b have one sign (no cancellation)
  double dasinh;
  if (a * b > 0.0) {
    const double q = (g * span / p) * (a + b) / (a * std::sqrt(1.0 + b * b) + b * std::sqrt(1.0 + a * a));
    dasinh = std::asinh(q);
  } else {
    dasinh = std::asinh(a) - std::asinh(b);
  }
  const double sum = w0 + w1;
  return 0.5 * (0.5 * span * (s0 + s1) + 0.5 * span * sum * sum / (s0 + s1)) + 0.5 * p2 * dasinh / g;
}

/// The config's checks (the constructor's and a snapshot's): n particles in dim dimensions.
void check_config(const ObserveConfig& c, int dim, std::size_t n, const std::array<bool, 3>& walls);

}  // namespace observe_detail

using namespace observe_detail;  // NOLINT: the observer's own sources only

// K: the dimension known at compile time (the pair hook's fast path), 0: dim_ at run time.
// The same sums in the same order either way (same bits).
template <int K>
[[gnu::always_inline]] inline void Observer::set_velocity(int i, const double* v) {
  Segment& s = seg_[i];
  const int d = K > 0 ? K : dim_;
  const double m = mass_of(i);  // (1 x: the same bits for unit masses)
  if (d >= 2) vv_off_[0] += m * (v[0] * v[1] - s.v[0] * s.v[1]);  // sum_i m v_ia v_ib (Helfand), before s.v changes
  if (d >= 3) {
    vv_off_[1] += m * (v[0] * v[2] - s.v[0] * s.v[2]);
    vv_off_[2] += m * (v[1] * v[2] - s.v[1] * s.v[2]);
  }
  double v2 = v[0] * v[0];  // (what 0 + v[0]^2 gives, a square being never -0)
  s.v[0] = v[0];
  for (int k = 1; k < d; ++k) {
    s.v[k] = v[k];
    v2 += v[k] * v[k];
  }
  const double speed = root(v2);
  v2 *= m;  // from here m v^2 (the kinetic sums); the speed is |v|
  if (ns_ > 0) [[unlikely]] v2_sp_[static_cast<std::size_t>(label_[i])] += v2 - s.v2;  // per species
  v2_sum_ += v2 - s.v2;  // sum_i v_i^2 and sum_i |v_i| (their time integrals: accumulate)
  speed_sum_ += speed - s.speed;
  s.v2 = v2;
  s.speed = speed;
  // the speed's bin; speeds from speed_max up, and every speed without a histogram
  // (bin_scale_ 0), go to the last bin, never reported: close adds without a test
  s.bin = static_cast<int>(std::min(speed * bin_scale_, bin_cap_));
}

// Closes i's segment at t: its duration weights its speed bin and its slabs (credited to
// the open block); its position moves to t. K: the position components advanced, the
// dimension on the pair hook's path, elsewhere 3 with no test of dim (the components beyond
// d are 0 whatever dt).
template <int K>
[[gnu::always_inline]] inline void Observer::close(int i, double t) {
  if (curved_) [[unlikely]] return gamma_ != 0.0 ? close_sheared(i, t) : close_field(i, t);
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

[[gnu::always_inline]] inline void Observer::close_pairs(int i, double t) {
  if (cfg_.pair_bins > 0) pairs_to(i, t);  // out of line: the hooks' hot path keeps fewer registers
}

// The integrals of sum v^2, sum |v| and sum v_a v_b (constant between velocity changes) from
// the last update to t, which becomes the last update. All three Helfand components always
// (those beyond hc_ stay 0: no test of the dimension).
[[gnu::always_inline]] inline void Observer::accumulate(double t) {
  const double dt = t - t_now_;
  if (curved_) [[unlikely]] {  // shear's peculiar velocities, a field's parabolas: polynomials between events
    if (gamma_ != 0.0) accumulate_sheared(dt);
    else accumulate_field(dt);
    t_now_ = t;
    return;
  }
  cur_.k2 += v2_sum_ * dt;
  cur_.dist += speed_sum_ * dt;
  for (int c = 0; c < 3; ++c) helf_[c] += vv_off_[c] * dt;
  for (int u = 0; u < ns_; ++u) cur_.sp[2 * static_cast<std::size_t>(u)] += v2_sp_[static_cast<std::size_t>(u)] * dt;
  t_now_ = t;
}

// The collision part of the Helfand moment: r_a Delta p_b for a < b (r, dp: d components).
template <int K>
[[gnu::always_inline]] inline void Observer::helfand_add(const double* r, const double* dp) {
  const int d = K > 0 ? K : dim_;
  if (d >= 2) helf_[0] += r[0] * dp[1];
  if (d >= 3) {
    helf_[1] += r[0] * dp[2];
    helf_[2] += r[1] * dp[2];
  }
}

[[gnu::always_inline]] inline void Observer::reach(double t) {
  while (t >= cur_.t0 + block_time_) end_block();
  accumulate(t);
}

}  // namespace revcol::engine
