// Benchmarks of the fast exact 3D pair operator (collide/pair3d_exact.hpp), side by side in one
// run with the general exact operator (collide/exact.hpp) on the same states: random
// approaching pre states (standard normal velocities), a random contact normal per state, and
// random draws, as an event-driven gas hands them over. The general operator needs a geometry
// (a QR) per normal: it is timed both prebuilt (one ExactCollision per state, built outside the
// clock) and with its construction (what an engine would pay per collision).
//
//   revcol-bench --bench pair3d
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <vector>

#include "bench.hpp"
#include "pair_pool.hpp"
#include "revcol/collide/exact.hpp"
#include "revcol/collide/pair3d_exact.hpp"

namespace revcol::bench {
namespace {

using Clock = std::chrono::steady_clock;
using State = PairState<3>;

std::vector<Metric> run_pair3d(Law law, std::uint64_t n) {
  const std::size_t P = static_cast<std::size_t>(std::min<std::uint64_t>(n, 1 << 16));
  const std::vector<State> pool = approaching_pool<3>(P, 20240917);
  const Pair3DExact op(law);
  std::vector<PairV<3>> post(P);
  RareLog log;
  double sink = 0.0;

  // fast operator: n forward collisions over the pool, then n reverse ones
  auto t0 = Clock::now();
  for (std::uint64_t k = 0; k < n; ++k) {
    const State& s = pool[k % P];
    post[k % P] = op.forward(s.pre, s.n, s.g, log);
  }
  const double fwd = seconds_since(t0);
  const double logged = static_cast<double>(log.pushed() / 2) / static_cast<double>(n);
  // reverse from the stored posts; the log holds what the last pass pushed, popped in
  // reverse order (every pass over the pool pushes the same entries)
  RareLog rlog;
  std::vector<std::array<std::uint64_t, 2>> cells(P);
  std::vector<char> flagged(P, 0);
  for (std::size_t k = 0; k < P; ++k) {
    flagged[k] = op.logs(post[k], pool[k].n) ? 1 : 0;
    cells[k] = op.pre_cell(pool[k].pre, pool[k].n);
  }
  t0 = Clock::now();
  for (std::uint64_t k = n; k-- > 0;) {
    const std::size_t i = k % P;
    const State& s = pool[i];
    if (flagged[i]) {  // rare: put back what forward pushed for this entry
      rlog.push(cells[i][0]);
      rlog.push(cells[i][1]);
    }
    const PairV<3> back = op.reverse(post[i], s.n, s.g, rlog);
    sink += back.i[0];
  }
  const double rev = seconds_since(t0);

  // general operator on the first Pg states: built once each, outside the clock
  const std::size_t Pg = std::min<std::size_t>(P, 1024);
  const std::uint64_t ng = std::max<std::uint64_t>(1, n / 10);
  t0 = Clock::now();
  std::vector<ExactCollision> gens;
  gens.reserve(Pg);
  for (std::size_t k = 0; k < Pg; ++k)
    gens.emplace_back(2, 3, std::vector<Contact>{{0, 1}},
                      std::vector<double>{pool[k].n[0], pool[k].n[1], pool[k].n[2]}, law);
  const double build = seconds_since(t0) / static_cast<double>(Pg);
  std::vector<std::array<double, 6>> gpost(Pg);
  RareLog glog;
  t0 = Clock::now();
  for (std::uint64_t k = 0; k < ng; ++k) {
    const std::size_t i = k % Pg;
    const State& s = pool[i];
    const double v[6] = {s.pre.i[0], s.pre.i[1], s.pre.i[2], s.pre.j[0], s.pre.j[1], s.pre.j[2]};
    gens[i].forward(v, s.g.data(), gpost[i].data(), glog);
  }
  const double gfwd = seconds_since(t0);
  std::vector<char> gflagged(Pg, 0);
  for (std::size_t i = 0; i < Pg; ++i) gflagged[i] = gens[i].logs(gpost[i].data()) ? 1 : 0;
  t0 = Clock::now();
  for (std::uint64_t k = ng; k-- > 0;) {
    const std::size_t i = k % Pg;
    double back[6];
    if (gflagged[i]) continue;  // rare (the log's order is not rebuilt here): skipped
    gens[i].reverse(gpost[i].data(), pool[i].g.data(), back, glog);
    sink += back[0];
  }
  const double grev = seconds_since(t0);
  volatile double keep = sink;  // keeps the loops from being optimized away
  (void)keep;

  const double f = n / fwd, r = n / rev, gf = ng / gfwd, gr = ng / grev;
  return {{"forward_per_s", f},
          {"reverse_per_s", r},
          {"general_forward_per_s", gf},
          {"general_reverse_per_s", gr},
          {"general_build_per_s", 1.0 / build},
          {"general_build_forward_per_s", 1.0 / (build + 1.0 / gf)},
          {"speedup_forward", f / gf},
          {"speedup_vs_build_forward", f * (build + 1.0 / gf)},
          {"log_per_collision", logged}};
}

}  // namespace

void add_pair3d_benches(std::vector<Bench>& out) {
  for (Law law : {Law::flux, Law::uniform}) {
    out.push_back({std::string("pair3d/") + to_string(law), "collisions/s",
                   [law](std::uint64_t n) { return run_pair3d(law, n); }});
  }
}

}  // namespace revcol::bench
