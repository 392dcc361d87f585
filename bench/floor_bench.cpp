// The exact-flux pair operators against their bare floor (issue 21): the same torus shift of
// the same chart, with nothing that makes it exact.
//
// The floor, per collision: the contact frame from the normal (normalized; in 3D the tangent
// from the least aligned axis, as Pair3DExact::Frame), the chart of the relative velocity in
// plain doubles (flux: c = (1 + q/|w|)/2 in 2D; c0 = T/|w|^2 and c1 = atan2(q2, q1)/(2 pi) in
// 3D, with the operator's own trigonometry in turns, trig.hpp), the shift by the draws mod 1
// in doubles, the inverse chart (sqrt, sincos) and the scale
// by a plain sqrt(|w|^2). It runs backwards too, to round-off only: no validation, no fixed
// point cells, no double-double |w|^2 or scale, no rare-log bound. That is the least a
// randomized reversible collision of this law computes; what the exact operator adds on top
// is the price of exactness.
//
// Both operators see the same pool of random approaching states (standard normal velocities,
// a random normal, random draws), and are timed in interleaved rounds (exact, floor, floor,
// exact, ...) in one process. Metrics: ns per collision (median over rounds) and the median
// of the per-round ratios exact / floor, forward and reverse; floor_roundtrip_rel_err checks
// that the floor really reverses (its largest relative error over the pool).
//
//   revcol-bench --bench floor --collisions 1000000 --repeats 3
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <vector>

#include "bench.hpp"
#include "pair_pool.hpp"
#include "revcol/collide/pair2d_exact.hpp"
#include "revcol/collide/pair3d_exact.hpp"
#include "revcol/trig.hpp"

namespace revcol::bench {
namespace {

using Clock = std::chrono::steady_clock;
constexpr int kRounds = 6;  // interleaved rounds per repeat

double wrap_add(double c, double g) {
  c += g;
  return c >= 1.0 ? c - 1.0 : c;
}
double wrap_sub(double c, double g) {
  c -= g;
  return c < 0.0 ? c + 1.0 : c;
}

// The 2D floor: sign +1 forward (chart of -w_pre, shift +g), -1 reverse (chart of w_post,
// shift -g, output -chart^-1).
PairV<2> floor2(const PairV<2>& v, const std::array<double, 2>& n, double g, bool forward) {
  const double inv = 1.0 / std::sqrt(n[0] * n[0] + n[1] * n[1]);
  const double a0 = n[0] * inv, a1 = n[1] * inv;  // t = (-a1, a0)
  const double w0 = v.i[0] - v.j[0], w1 = v.i[1] - v.j[1];
  const double w2 = w0 * w0 + w1 * w1, norm = std::sqrt(w2);
  const double sg = forward ? -1.0 : 1.0;  // forward charts -w
  const double q = sg * (-w0 * a1 + w1 * a0);
  double c = 0.5 + 0.5 * (q / norm);
  c = forward ? wrap_add(c, g) : wrap_sub(c, g);
  const double sn = 2.0 * c - 1.0, cn = std::sqrt((1.0 - sn) * (1.0 + sn));
  const double h = (forward ? 0.5 : -0.5) * norm;
  const double u0 = cn * a0 - sn * a1, u1 = cn * a1 + sn * a0;
  const double cm0 = 0.5 * (v.i[0] + v.j[0]), cm1 = 0.5 * (v.i[1] + v.j[1]);
  PairV<2> out;
  out.i = {cm0 + h * u0, cm1 + h * u1};
  out.j = {cm0 - h * u0, cm1 - h * u1};
  return out;
}

// The 3D floor, the same way.
PairV<3> floor3(const PairV<3>& v, const std::array<double, 3>& n, const std::array<double, 2>& g, bool forward) {
  const double inv = 1.0 / std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  const double a[3] = {n[0] * inv, n[1] * inv, n[2] * inv};
  const double b0 = std::fabs(a[0]), b1 = std::fabs(a[1]), b2 = std::fabs(a[2]);
  const int axis = (b0 <= b1 && b0 <= b2) ? 0 : (b1 <= b2 ? 1 : 2);
  double t1[3];
  if (axis == 0) {
    const double r = 1.0 / std::sqrt(a[1] * a[1] + a[2] * a[2]);
    t1[0] = 0.0, t1[1] = -a[2] * r, t1[2] = a[1] * r;
  } else if (axis == 1) {
    const double r = 1.0 / std::sqrt(a[0] * a[0] + a[2] * a[2]);
    t1[0] = a[2] * r, t1[1] = 0.0, t1[2] = -a[0] * r;
  } else {
    const double r = 1.0 / std::sqrt(a[0] * a[0] + a[1] * a[1]);
    t1[0] = -a[1] * r, t1[1] = a[0] * r, t1[2] = 0.0;
  }
  const double t2[3] = {a[1] * t1[2] - a[2] * t1[1], a[2] * t1[0] - a[0] * t1[2], a[0] * t1[1] - a[1] * t1[0]};
  const double sg = forward ? -1.0 : 1.0;
  const double w[3] = {sg * (v.i[0] - v.j[0]), sg * (v.i[1] - v.j[1]), sg * (v.i[2] - v.j[2])};
  const double p = w[0] * a[0] + w[1] * a[1] + w[2] * a[2];
  const double q1 = w[0] * t1[0] + w[1] * t1[1] + w[2] * t1[2];
  const double q2 = w[0] * t2[0] + w[1] * t2[1] + w[2] * t2[2];
  const double T = q1 * q1 + q2 * q2, n2 = p * p + T;
  double c0 = T / n2, c1 = trig::atan2_turns(q2, q1);  // the operator's own trigonometry
  c0 = forward ? wrap_add(c0, g[0]) : wrap_sub(c0, g[0]);
  c1 = forward ? wrap_add(c1, g[1]) : wrap_sub(c1, g[1]);
  const double sn = std::sqrt(c0), cn = std::sqrt(1.0 - c0);
  double sph, cph;
  trig::sincos_turns(c1, sph, cph);
  const double d1 = sn * cph, d2 = sn * sph;
  const double h = (forward ? 0.5 : -0.5) * std::sqrt(n2);
  PairV<3> out;
  for (int k = 0; k < 3; ++k) {
    const double u = cn * a[k] + d1 * t1[k] + d2 * t2[k];
    const double cm = 0.5 * (v.i[k] + v.j[k]);
    out.i[k] = cm + h * u;
    out.j[k] = cm - h * u;
  }
  return out;
}

// One exact operator (Op: Pair2DExact or Pair3DExact, flux) and its floor on one pool.
template <int D, class Op, class Floor>
std::vector<Metric> run_floor(std::uint64_t n, Floor&& floor_op) {
  const std::size_t P = static_cast<std::size_t>(std::min<std::uint64_t>(std::max<std::uint64_t>(n, 1), 1 << 16));
  const std::vector<PairState<D>> pool = approaching_pool<D>(P, 20261125);
  const Op op(Law::flux);
  const auto draws = [](const PairState<D>& s) {
    if constexpr (D == 2) return s.g[0];
    else return s.g;
  };
  std::vector<PairV<D>> post(P), fpost(P);
  RareLog log;
  // the exact reverse pops what forward pushed: the logged entries and their pre cells
  for (std::size_t k = 0; k < P; ++k) post[k] = op.forward(pool[k].pre, pool[k].n, draws(pool[k]), log);
  std::vector<char> flagged(P, 0);
  std::vector<std::array<std::uint64_t, D - 1>> cells(P);
  for (std::size_t k = 0; k < P; ++k) {
    flagged[k] = op.logs(post[k], pool[k].n) ? 1 : 0;
    if constexpr (D == 2) cells[k] = {op.pre_cell(pool[k].pre, pool[k].n)};
    else cells[k] = op.pre_cell(pool[k].pre, pool[k].n);
  }
  double sink = 0.0;
  const auto exact_fwd = [&] {
    RareLog l;
    const auto t0 = Clock::now();
    for (std::uint64_t k = 0; k < n; ++k) {
      const PairState<D>& s = pool[k % P];
      post[k % P] = op.forward(s.pre, s.n, draws(s), l);
    }
    return seconds_since(t0) / static_cast<double>(n);
  };
  const auto exact_rev = [&] {
    RareLog l;
    const auto t0 = Clock::now();
    for (std::uint64_t k = n; k-- > 0;) {
      const std::size_t i = k % P;
      if (flagged[i])  // rare: what forward pushed for this entry
        for (std::uint64_t c : cells[i]) l.push(c);
      sink += op.reverse(post[i], pool[i].n, draws(pool[i]), l).i[0];
    }
    return seconds_since(t0) / static_cast<double>(n);
  };
  const auto floor_fwd = [&] {
    const auto t0 = Clock::now();
    for (std::uint64_t k = 0; k < n; ++k) {
      const PairState<D>& s = pool[k % P];
      fpost[k % P] = floor_op(s.pre, s.n, draws(s), true);
    }
    return seconds_since(t0) / static_cast<double>(n);
  };
  const auto floor_rev = [&] {
    const auto t0 = Clock::now();
    for (std::uint64_t k = n; k-- > 0;) {
      const std::size_t i = k % P;
      sink += floor_op(fpost[i], pool[i].n, draws(pool[i]), false).i[0];
    }
    return seconds_since(t0) / static_cast<double>(n);
  };
  std::vector<double> ef, er, ff, fr, rf, rr;
  for (int r = 0; r < kRounds; ++r) {
    double a, b, c, d;
    if (r % 2 == 0) {
      a = exact_fwd(), c = floor_fwd(), d = floor_rev(), b = exact_rev();
    } else {
      c = floor_fwd(), a = exact_fwd(), b = exact_rev(), d = floor_rev();
    }
    ef.push_back(a * 1e9), er.push_back(b * 1e9), ff.push_back(c * 1e9), fr.push_back(d * 1e9);
    rf.push_back(a / c), rr.push_back(b / d);
  }
  // the floor reverses to round-off: back from its posts to the pool's pre states
  double err = 0.0;
  for (std::size_t k = 0; k < P; ++k) {
    const PairV<D> f = floor_op(pool[k].pre, pool[k].n, draws(pool[k]), true);
    const PairV<D> back = floor_op(f, pool[k].n, draws(pool[k]), false);
    double num = 0.0, den = 0.0;
    for (int q = 0; q < D; ++q) {
      num = std::max({num, std::fabs(back.i[q] - pool[k].pre.i[q]), std::fabs(back.j[q] - pool[k].pre.j[q])});
      den = std::max({den, std::fabs(pool[k].pre.i[q]), std::fabs(pool[k].pre.j[q])});
    }
    err = std::max(err, num / den);
  }
  volatile double keep = sink;  // keeps the loops from being optimized away
  (void)keep;
  return {{"exact_forward_ns", median(ef)}, {"exact_reverse_ns", median(er)},
          {"floor_forward_ns", median(ff)}, {"floor_reverse_ns", median(fr)},
          {"ratio_forward", median(rf)},    {"ratio_reverse", median(rr)},
          {"floor_roundtrip_rel_err", err}};
}

}  // namespace

void add_floor_benches(std::vector<Bench>& out) {
  out.push_back({"floor/pair2d", "ns/collision", [](std::uint64_t n) {
                   return run_floor<2, Pair2DExact>(n, floor2);
                 }});
  out.push_back({"floor/pair3d", "ns/collision", [](std::uint64_t n) {
                   return run_floor<3, Pair3DExact>(n, floor3);
                 }});
}

}  // namespace revcol::bench
