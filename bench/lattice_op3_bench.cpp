// Benchmarks and the design study of the exact 3D lattice pair operator (revcol/lattice/pair3d.hpp):
// ns per forward / reverse on a pool of gas-like pre states (sigma = 2^60 lattice units, relative
// speed |w| in [2^31, 2^32) units per tick as the engine's automatic tick gives, incidence from
// the flux law, X of 256 bits, random 48-bit G), beside the 2D operator on the same speeds; and
// the engine's candidate of docs/lattice.md "3D: the direction chart" (bits-back over the exact
// rows of the azimuth cell): refusals by kind, energy change, X's balance.
//
//   revcol-bench --bench lattice/pair3d
#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "bench.hpp"
#include "revcol/lattice/pair2d.hpp"
#include "revcol/lattice/pair3d.hpp"

namespace revcol::bench {

namespace {

using lattice::BitsBack;
using lattice::LatticePair2D;
using lattice::LatticePair3D;
using lattice::Refusal;
using lattice::Vec2;
using lattice::Vec3;
using Clock = std::chrono::steady_clock;
constexpr double kPi = std::numbers::pi;

double secs(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }
double n2(const Vec3& v) {
  return static_cast<double>(v[0]) * static_cast<double>(v[0]) + static_cast<double>(v[1]) * static_cast<double>(v[1]) +
         static_cast<double>(v[2]) * static_cast<double>(v[2]);
}
__int128 n2i(const Vec3& v) {
  return static_cast<__int128>(v[0]) * v[0] + static_cast<__int128>(v[1]) * v[1] + static_cast<__int128>(v[2]) * v[2];
}

BitsBack x256() {
  std::mt19937_64 rng(5);
  return BitsBack(std::vector<std::uint64_t>{rng(), rng(), rng(), rng()});
}

// A random pre state as an equilibrium gas hands it over: contact point uniform on the sphere,
// incidence from the 3D flux law (sin^2 uniform), azimuth uniform, |w| in [2^e, 2^(e+1)), a
// uniform phase; false when rounding left the contract or check_pre refuses it.
bool gas_pre(const LatticePair3D& op, std::mt19937_64& rng, int e, Vec3& q, Vec3& w) {
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const double s = static_cast<double>(op.sigma());
  const double ct = 2 * U(rng) - 1, st = std::sqrt(1 - ct * ct), ph = 2 * kPi * U(rng);
  const double n[3] = {st * std::cos(ph), st * std::sin(ph), ct};
  const double a0[3] = {std::fabs(n[0]) < 0.6 ? 1.0 : 0.0, std::fabs(n[0]) < 0.6 ? 0.0 : 1.0, 0.0};
  const double d = a0[0] * n[0] + a0[1] * n[1];
  double e1[3] = {a0[0] - d * n[0], a0[1] - d * n[1], -d * n[2]};
  const double l = std::sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
  for (double& c : e1) c /= l;
  const double e2[3] = {n[1] * e1[2] - n[2] * e1[1], n[2] * e1[0] - n[0] * e1[2], n[0] * e1[1] - n[1] * e1[0]};
  const double si = std::sqrt(U(rng)), ci = std::sqrt(1 - si * si), az = 2 * kPi * U(rng);
  const double speed = std::ldexp(1.0 + U(rng), e), frac = U(rng);
  for (std::size_t k = 0; k < 3; ++k) {
    w[k] = static_cast<std::int64_t>(-speed * (ci * n[k] + si * (std::cos(az) * e1[k] + std::sin(az) * e2[k])));
    q[k] = static_cast<std::int64_t>(s * n[k] - static_cast<double>(w[k]) * frac);
  }
  const __int128 s2 = static_cast<__int128>(op.sigma()) * op.sigma();
  const Vec3 p{q[0] + w[0], q[1] + w[1], q[2] + w[2]};
  return n2i(q) >= s2 && n2i(p) < s2 && op.check_pre(q, w) == Refusal::none;
}

struct OpState {
  Vec3 q, w, q2, w2;
  std::uint64_t g = 0;
  BitsBack x2;
  bool ok = false;
};

std::vector<OpState> make_states(const LatticePair3D& op, const BitsBack& X) {
  std::mt19937_64 rng(20261124);
  std::vector<OpState> pool;
  while (pool.size() < 4096) {
    OpState st;
    if (!gas_pre(op, rng, 31, st.q, st.w)) continue;
    st.g = rng() >> 16;
    st.ok = op.forward(st.q, st.w, st.g, X, st.q2, st.w2, st.x2) == Refusal::none;
    pool.push_back(st);
  }
  return pool;
}

std::vector<Metric> run_forward(std::uint64_t n) {
  const LatticePair3D op(1LL << 60, revcol::Law::flux, 16);
  const BitsBack X = x256();
  const std::vector<OpState> pool = make_states(op, X);
  Vec3 q2, w2;
  BitsBack x2 = X;
  std::uint64_t refused = 0;
  const auto t0 = Clock::now();
  for (std::uint64_t k = 0; k < n; ++k) {
    const OpState& s = pool[k & 4095];
    refused += op.forward(s.q, s.w, s.g, X, q2, w2, x2) != Refusal::none;
  }
  const double t = secs(t0);
  return {{"ns_per_call", 1e9 * t / static_cast<double>(n)},
          {"refused_fraction", static_cast<double>(refused) / static_cast<double>(n)}};
}

std::vector<Metric> run_reverse(std::uint64_t n) {
  const LatticePair3D op(1LL << 60);
  const std::vector<OpState> pool = make_states(op, x256());
  std::vector<std::size_t> ok;
  for (std::size_t i = 0; i < pool.size(); ++i)
    if (pool[i].ok) ok.push_back(i);
  BitsBack x;
  Vec3 q, w;
  std::int64_t sink = 0;
  const auto t0 = Clock::now();
  for (std::uint64_t k = 0; k < n; ++k) {
    const OpState& s = pool[ok[k % ok.size()]];
    x = s.x2;
    op.reverse(s.q2, s.w2, s.g, x, q, w);
    sink += q[0];
  }
  const double t = secs(t0);
  volatile std::int64_t keep = sink;
  (void)keep;
  return {{"ns_per_call", 1e9 * t / static_cast<double>(n)}};
}

// The 2D operator's forward on the same speeds (2^16 cells), for the cost ratio.
std::vector<Metric> run_forward2d(std::uint64_t n) {
  const LatticePair2D op(1LL << 60, revcol::Law::flux, 16);
  const BitsBack X = x256();
  std::mt19937_64 rng(20261124);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  struct S2 {
    Vec2 q, w;
    std::uint64_t g;
  };
  std::vector<S2> pool;
  while (pool.size() < 4096) {
    const double ang = 2 * kPi * U(rng), a = ang + kPi + std::asin(2 * U(rng) - 1), speed = std::ldexp(1.0 + U(rng), 31), f = U(rng);
    const Vec2 w{static_cast<std::int64_t>(speed * std::cos(a)), static_cast<std::int64_t>(speed * std::sin(a))};
    const Vec2 q{static_cast<std::int64_t>(std::ldexp(std::cos(ang), 60) - static_cast<double>(w[0]) * f),
                 static_cast<std::int64_t>(std::ldexp(std::sin(ang), 60) - static_cast<double>(w[1]) * f)};
    const __int128 s2 = static_cast<__int128>(1) << 120;
    auto nn = [](std::int64_t x, std::int64_t y) { return static_cast<__int128>(x) * x + static_cast<__int128>(y) * y; };
    if (nn(q[0], q[1]) < s2 || nn(q[0] + w[0], q[1] + w[1]) >= s2 || op.check_pre(q, w) != Refusal::none) continue;
    pool.push_back({q, w, rng() >> 16});
  }
  Vec2 q2, w2;
  BitsBack x2 = X;
  const auto t0 = Clock::now();
  for (std::uint64_t k = 0; k < n; ++k) {
    const S2& s = pool[k & 4095];
    op.forward(s.q, s.w, s.g, X, q2, w2, x2);
  }
  return {{"ns_per_call", 1e9 * secs(t0) / static_cast<double>(n)}};
}

// The design study: n gas collisions per speed (a new gas pre state each, X chained, a
// G-dependent refusal redrawn): refusals per collision by kind, the energy change per
// collision (|w2|^2 - |w|^2) / |w|^2 (mean, rms, max |.|), X's balance (bits per collision and
// its range), at |w| ~ 2^31, 2^27 and 2^23 (refusals scale ~1 / |w|).
std::vector<Metric> run_study(std::uint64_t n) {
  std::vector<Metric> out;
  struct Run {
    int e;
    const char* tag;
  };
  const Run runs[] = {{31, "rows"}, {27, "rows_w2^27"}, {23, "rows_w2^23"}};
  for (const Run& r : runs) {
    const LatticePair3D op(1LL << 60, revcol::Law::flux, 16);
    std::mt19937_64 rng(7);
    BitsBack X = x256(), X2;
    const double start = static_cast<double>(X.bit_length());
    double lo = start, hi = start, de_sum = 0, de_sq = 0, de_max = 0;
    std::uint64_t kinds[5] = {0, 0, 0, 0, 0}, accepted = 0, draws = 0;
    const auto t0 = Clock::now();
    while (accepted < n) {
      Vec3 q, w, q2, w2;
      if (!gas_pre(op, rng, r.e, q, w)) continue;
      Refusal why;
      int tries = 0;
      while ((why = op.forward(q, w, rng() >> 16, X, q2, w2, X2)) != Refusal::none && ++tries < 1000) ++kinds[static_cast<int>(why)];
      draws += static_cast<std::uint64_t>(tries) + 1;
      if (why != Refusal::none) continue;  // a state no draw accepts
      ++accepted;
      std::swap(X, X2);
      const double b = static_cast<double>(X.bit_length());
      lo = std::min(lo, b);
      hi = std::max(hi, b);
      const double de = (n2(w2) - n2(w)) / n2(w);
      de_sum += de;
      de_sq += de * de;
      de_max = std::max(de_max, std::fabs(de));
    }
    const double dn = static_cast<double>(n), tag_s = secs(t0);
    const std::string t = std::string(r.tag) + "_";
    out.push_back({t + "draws_per_collision", static_cast<double>(draws) / dn});
    out.push_back({t + "cell_readback_per_collision", static_cast<double>(kinds[1]) / dn});
    out.push_back({t + "empty_post_per_collision", static_cast<double>(kinds[3]) / dn});
    out.push_back({t + "out_of_domain_per_collision", static_cast<double>(kinds[4]) / dn});
    out.push_back({t + "energy_mean_2^-30", de_sum / dn * 0x1p30});
    out.push_back({t + "energy_rms_2^-30", std::sqrt(de_sq / dn) * 0x1p30});
    out.push_back({t + "energy_max_abs_2^-30", de_max * 0x1p30});
    out.push_back({t + "X_bits_per_collision", (static_cast<double>(X.bit_length()) - start) / dn});
    out.push_back({t + "X_bits_range", hi - lo});
    out.push_back({t + "seconds", tag_s});
  }
  return out;
}

// Refusals per draw at gas pre states by relative speed 2^e (e = 20, 23, ..., 35) and polar
// cells 2^cb per turn (cb = 12, 16, 20): the read-back refusal falls as ~cells / |w| (the lifting
// round-off crossing a polar boundary); empty rows appear only at the slowest speeds.
std::vector<Metric> run_readback(std::uint64_t n) {
  std::vector<Metric> out;
  for (const int cb : {12, 16, 20}) {
    const LatticePair3D op(1LL << 60, revcol::Law::flux, cb);
    const BitsBack X = x256();
    BitsBack x2 = X;
    std::mt19937_64 rng(11);
    for (int e = 20; e <= 35; e += 3) {
      std::uint64_t tried = 0, readback = 0, empty = 0;
      while (tried < n) {
        Vec3 q, w, q2, w2;
        if (!gas_pre(op, rng, e, q, w)) continue;
        ++tried;
        const Refusal r = op.forward(q, w, rng() >> 16, X, q2, w2, x2);
        readback += r == Refusal::cell_readback;
        empty += r == Refusal::empty_post;
      }
      const std::string tag = "_w2^" + std::to_string(e) + "_cells" + std::to_string(cb);
      out.push_back({"readback" + tag, static_cast<double>(readback) / static_cast<double>(n)});
      out.push_back({"empty_post" + tag, static_cast<double>(empty) / static_cast<double>(n)});
    }
  }
  return out;
}

}  // namespace

void add_lattice_op3_benches(std::vector<Bench>& out) {
  out.push_back({"lattice/pair3d/forward", "calls", [](std::uint64_t n) { return run_forward(n); }});
  out.push_back({"lattice/pair3d/reverse", "calls", [](std::uint64_t n) { return run_reverse(n); }});
  out.push_back({"lattice/pair3d/pair2d_forward_same_speed", "calls", [](std::uint64_t n) { return run_forward2d(n); }});
  out.push_back({"lattice/pair3d/study", "collisions per speed", [](std::uint64_t n) { return run_study(n); }});
  out.push_back({"lattice/pair3d/readback", "draws per speed and cells", [](std::uint64_t n) { return run_readback(n); }});
}

}  // namespace revcol::bench
