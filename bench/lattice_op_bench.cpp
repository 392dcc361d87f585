// Benchmarks of the exact lattice pair operator (revcol/lattice/pair2d.hpp): ns per call of
// forward, reverse and the pair-level (S-transform) calls, on a pool of random approaching pre
// states as an equilibrium gas hands them over (sigma = 2^60 lattice units, relative speeds
// ~2^40 units per tick, incidence drawn from the flux law), X of 256 bits, random 48-bit G.
//
//   revcol-bench --bench lattice/pair2d
#include <chrono>
#include <cmath>
#include <algorithm>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "bench.hpp"
#include "revcol/lattice/pair2d.hpp"

namespace revcol::bench {

void add_lattice_op_benches(std::vector<Bench>& out);  // (declared in bench.hpp by the lead)

namespace {

using lattice::BitsBack;
using lattice::LatticePair2D;
using lattice::Refusal;
using lattice::Vec2;
using Clock = std::chrono::steady_clock;

struct OpState {
  Vec2 q, w;           // relative pre state
  std::uint64_t g;     // draw
  Vec2 q2, w2;         // post state (when accepted)
  BitsBack x2;         // X after the forward
  bool ok = false;     // accepted by the operator
};

// A random pre state as an equilibrium gas hands it over: a contact point anywhere, incidence
// from the flux law, |w| in [2^e, 2^(e+1)), a uniform phase. False when the rounding put it out
// of the operator's contract or check_pre refuses it (the caller draws again).
bool gas_pre(const LatticePair2D& op, std::mt19937_64& rng, int e, Vec2& q, Vec2& w) {
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const double s = static_cast<double>(op.sigma());
  const double ang = 2 * std::numbers::pi * U(rng), a = ang + std::numbers::pi + std::asin(2 * U(rng) - 1);
  const double speed = std::ldexp(1.0 + U(rng), e), frac = U(rng);
  w = {static_cast<std::int64_t>(speed * std::cos(a)), static_cast<std::int64_t>(speed * std::sin(a))};
  q = {static_cast<std::int64_t>(s * std::cos(ang) - static_cast<double>(w[0]) * frac),
       static_cast<std::int64_t>(s * std::sin(ang) - static_cast<double>(w[1]) * frac)};
  auto n2 = [](std::int64_t x, std::int64_t y) { return static_cast<__int128>(x) * x + static_cast<__int128>(y) * y; };
  const __int128 s2 = static_cast<__int128>(op.sigma()) * op.sigma();
  return n2(q[0], q[1]) >= s2 && n2(q[0] + w[0], q[1] + w[1]) < s2 && op.check_pre(q, w) == Refusal::none;
}

std::vector<OpState> make_states(const LatticePair2D& op, std::size_t n, const BitsBack& X) {
  std::mt19937_64 rng(20261123);
  std::vector<OpState> pool;
  pool.reserve(n);
  while (pool.size() < n) {
    OpState st;
    if (!gas_pre(op, rng, 40, st.q, st.w)) continue;
    st.g = rng() >> 16;
    st.ok = op.forward(st.q, st.w, st.g, X, st.q2, st.w2, st.x2) == Refusal::none;
    pool.push_back(st);
  }
  return pool;
}

double secs(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

BitsBack x256() {
  std::mt19937_64 rng(5);
  return BitsBack(std::vector<std::uint64_t>{rng(), rng(), rng(), rng()});
}

std::vector<Metric> run_forward(revcol::Law law, std::uint64_t n) {
  const LatticePair2D op(1LL << 60, law);
  const BitsBack X = x256();
  const std::vector<OpState> pool = make_states(op, 4096, X);
  Vec2 q2, w2;
  BitsBack x2 = X;
  std::uint64_t refused = 0;
  const auto t0 = Clock::now();
  for (std::uint64_t k = 0; k < n; ++k) {
    const OpState& s = pool[k & 4095];
    refused += op.forward(s.q, s.w, s.g, X, q2, w2, x2) != Refusal::none;
  }
  const double t = secs(t0);
  return {{"ns_per_call", 1e9 * t / static_cast<double>(n)},
          {"calls_per_s", static_cast<double>(n) / t},
          {"refused_fraction", static_cast<double>(refused) / static_cast<double>(n)}};
}

std::vector<Metric> run_reverse(std::uint64_t n) {
  const LatticePair2D op(1LL << 60);
  const std::vector<OpState> pool = make_states(op, 4096, x256());
  std::vector<std::size_t> ok;
  for (std::size_t i = 0; i < pool.size(); ++i)
    if (pool[i].ok) ok.push_back(i);
  BitsBack x;
  Vec2 q, w;
  std::int64_t sink = 0;
  const auto t0 = Clock::now();
  for (std::uint64_t k = 0; k < n; ++k) {
    const OpState& s = pool[ok[k % ok.size()]];
    x = s.x2;  // the reverse works in place: start from the forward's X each time
    op.reverse(s.q2, s.w2, s.g, x, q, w);
    sink += q[0];
  }
  const double t = secs(t0);
  volatile std::int64_t keep = sink;
  (void)keep;
  return {{"ns_per_call", 1e9 * t / static_cast<double>(n)}, {"calls_per_s", static_cast<double>(n) / t}};
}

std::vector<Metric> run_pair(std::uint64_t n) {
  const LatticePair2D op(1LL << 60);
  const BitsBack X = x256();
  const std::vector<OpState> pool = make_states(op, 4096, X);
  const Vec2 xj{123456789, -987654321}, vj{1LL << 39, -(1LL << 38)};
  Vec2 xi2, xj2, vi2, vj2, a, b, c, d;
  BitsBack x2 = X, xb;
  std::uint64_t accepted = 0;
  double tf = 0, tr = 0;
  for (std::uint64_t k = 0; k < n; ++k) {
    const OpState& s = pool[k & 4095];
    const Vec2 xi{xj[0] + s.q[0], xj[1] + s.q[1]}, vi{vj[0] + s.w[0], vj[1] + s.w[1]};
    auto t0 = Clock::now();
    const bool ok = op.pair_forward(xi, xj, vi, vj, s.g, X, xi2, xj2, vi2, vj2, x2) == Refusal::none;
    tf += secs(t0);
    if (!ok) continue;
    ++accepted;
    xb = x2;
    t0 = Clock::now();
    op.pair_reverse(xi2, xj2, vi2, vj2, s.g, xb, a, b, c, d);
    tr += secs(t0);
  }
  return {{"forward_ns_per_call", 1e9 * tf / static_cast<double>(n)},
          {"reverse_ns_per_call", 1e9 * tr / static_cast<double>(accepted)}};
}

// X's size over n collisions of random pre states (flux-law incidence, a new state each
// collision, X chained as in a gas); a G-dependent refusal is redrawn, a G-independent one
// skips the state. Under the flux law X stays bounded; under the uniform law it grows by
// E[log2 cos(pre)] - E[log2 cos(post)] = log2(e) (2 ln 2 - 1) = 0.557 bit per collision.
// The engine's 2^16 cells run the flux law too (metrics with the suffix _cells16).
std::vector<Metric> run_drift(std::uint64_t n) {
  std::vector<Metric> out;
  const std::pair<revcol::Law, int> runs[] = {{revcol::Law::flux, 20}, {revcol::Law::uniform, 20}, {revcol::Law::flux, 16}};
  for (const auto& [law, cb] : runs) {
    const LatticePair2D op(1LL << 60, law, cb);
    BitsBack X = x256(), X2;
    const double start = static_cast<double>(X.bit_length());
    double lo = start, hi = start;
    std::mt19937_64 rng(99);
    std::uint64_t redraws = 0;
    const auto t0 = Clock::now();
    for (std::uint64_t k = 0; k < n;) {
      Vec2 q, w, q2, w2;
      if (!gas_pre(op, rng, 40, q, w)) continue;
      while (op.forward(q, w, rng() >> 16, X, q2, w2, X2) != Refusal::none) ++redraws;
      std::swap(X, X2);
      const double b = static_cast<double>(X.bit_length());
      lo = std::min(lo, b);
      hi = std::max(hi, b);
      ++k;
    }
    const std::string tag = law == revcol::Law::flux ? "flux_" : "uniform_";
    const std::string cells = cb == 20 ? "" : "_cells" + std::to_string(cb);
    const double dn = static_cast<double>(n);
    out.push_back({tag + "bits_per_collision" + cells, (static_cast<double>(X.bit_length()) - start) / dn});
    out.push_back({tag + "bits_max_minus_start" + cells, hi - start});
    out.push_back({tag + "bits_start_minus_min" + cells, start - lo});
    out.push_back({tag + "redraws_per_collision" + cells, static_cast<double>(redraws) / dn});
    out.push_back({tag + "seconds" + cells, secs(t0)});
  }
  return out;
}

// The fraction of draws the operator refuses with cell_readback (the lifting round-off moved
// w2 across a cell boundary) at relative speeds 2^20 .. 2^44 lattice units per tick, for 2^20
// direction cells per turn (the prototype's) and 2^16 (the engine's default; suffix _cells16).
std::vector<Metric> run_readback(std::uint64_t n) {
  std::vector<Metric> out;
  for (const int cb : {20, 16}) {
  const LatticePair2D op(1LL << 60, revcol::Law::flux, cb);
  const BitsBack X = x256();
  BitsBack x2 = X;
  std::mt19937_64 rng(7);
  for (int e = 20; e <= 44; e += 4) {
    std::uint64_t tried = 0, readback = 0;
    while (tried < n) {
      Vec2 q, w, q2, w2;
      if (!gas_pre(op, rng, e, q, w)) continue;
      ++tried;
      readback += op.forward(q, w, rng() >> 16, X, q2, w2, x2) == Refusal::cell_readback;
    }
    out.push_back({"readback_at_2^" + std::to_string(e) + (cb == 20 ? "" : "_cells" + std::to_string(cb)),
                   static_cast<double>(readback) / static_cast<double>(n)});
  }
  }
  return out;
}

}  // namespace

void add_lattice_op_benches(std::vector<Bench>& out) {
  out.push_back({"lattice/pair2d/forward", "calls", [](std::uint64_t n) { return run_forward(revcol::Law::flux, n); }});
  out.push_back({"lattice/pair2d/reverse", "calls", [](std::uint64_t n) { return run_reverse(n); }});
  out.push_back({"lattice/pair2d/pair", "calls (clock per call)", [](std::uint64_t n) { return run_pair(n); }});
  out.push_back({"lattice/pair2d/uniform/forward", "calls",
                 [](std::uint64_t n) { return run_forward(revcol::Law::uniform, n); }});
  out.push_back({"lattice/pair2d/drift", "collisions", [](std::uint64_t n) { return run_drift(n); }});
  out.push_back({"lattice/pair2d/readback", "draws per speed", [](std::uint64_t n) { return run_readback(n); }});
}

}  // namespace revcol::bench
