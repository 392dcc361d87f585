// The exact pair operators of two source trees in one binary, timed in interleaved rounds
// (issue 21): Pair2DExactOld / Pair3DExactOld are an older revision's headers renamed by
// bench/op_ab/run.sh, Pair2DExact / Pair3DExact the working tree's. One process, one core,
// rounds alternating old-new / new-old: the host's slow and fast phases hit both alike, so
// the paired per-round ratios resolve a few per cent where separate runs cannot.
//
//   bash bench/op_ab/run.sh REV [ROUNDS]      (e.g. bash bench/op_ab/run.sh HEAD 150)
//
// Prints, per operator and direction, the old and new medians (ns per collision) and the
// median of the paired new/old ratios with its quartiles.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <random>
#include <vector>
#include "revcol/collide/pair2d_exact.hpp"
#include "revcol/collide/pair3d_exact.hpp"
#include "revcol/collide/pair2d_exact_old.hpp"
#include "revcol/collide/pair3d_exact_old.hpp"
using namespace revcol;
using Clock = std::chrono::steady_clock;
// One pooled approaching state: velocities, a normal (non-unit), two draws.
template <int D> struct St { PairV<D> v; std::array<double, D> n; std::array<double, 2> g; };
template <int D> std::vector<St<D>> pool(size_t P) {
  std::mt19937_64 rng(7); std::normal_distribution<double> N(0, 1); std::uniform_real_distribution<double> U(0, 1);
  std::vector<St<D>> out;
  while (out.size() < P) {
    St<D> s; double p = 0;
    for (int k = 0; k < D; ++k) { s.v.i[k] = N(rng); s.v.j[k] = N(rng); s.n[k] = N(rng); p += (s.v.i[k] - s.v.j[k]) * s.n[k]; }
    if (p == 0) continue;
    if (p > 0) for (auto& x : s.n) x = -x;
    s.g = {U(rng), U(rng)};
    out.push_back(s);
  }
  return out;
}
double sink = 0;
template <int D, class Op> std::pair<double, double> run(const Op& op, const std::vector<St<D>>& pl, std::vector<PairV<D>>& post, size_t n) {
  RareLog l; size_t P = pl.size();
  auto t0 = Clock::now();
  for (size_t k = 0; k < n; ++k) {
    const auto& s = pl[k % P];
    if constexpr (D == 2) post[k % P] = op.forward(s.v, s.n, s.g[0], l); else post[k % P] = op.forward(s.v, s.n, s.g, l);
  }
  double f = std::chrono::duration<double>(Clock::now() - t0).count() / n * 1e9;
  RareLog l2 = l;
  t0 = Clock::now();
  for (size_t k = n; k-- > 0;) {
    const auto& s = pl[k % P];
    if (l2.size() > 1000000) break;
    if constexpr (D == 2) sink += op.reverse(post[k % P], s.n, s.g[0], l2).i[0]; else sink += op.reverse(post[k % P], s.n, s.g, l2).i[0];
  }
  double r = std::chrono::duration<double>(Clock::now() - t0).count() / n * 1e9;
  return {f, r};
}
double med(std::vector<double> v) { std::sort(v.begin(), v.end()); return v[v.size() / 2]; }
template <int D, class A, class B> void cmp(const char* name, const A& a, const B& b, int rounds, size_t n) {
  auto pl = pool<D>(1 << 16); std::vector<PairV<D>> post(pl.size());
  std::vector<double> fa, fb, ra, rb, pf, pr;
  for (int r = 0; r < rounds; ++r) {
    std::pair<double, double> x, y;
    if (r % 2) { x = run<D>(a, pl, post, n); y = run<D>(b, pl, post, n); } else { y = run<D>(b, pl, post, n); x = run<D>(a, pl, post, n); }
    fa.push_back(x.first); ra.push_back(x.second); fb.push_back(y.first); rb.push_back(y.second);
    pf.push_back(y.first / x.first); pr.push_back(y.second / x.second);
  }
  auto q = [](std::vector<double> v, double f) { std::sort(v.begin(), v.end()); return v[size_t(f * (v.size() - 1))]; };
  std::printf("%s fwd old %.2f new %.2f paired %.3f [%.3f, %.3f] | rev old %.2f new %.2f paired %.3f [%.3f, %.3f]\n", name, med(fa), med(fb), med(pf), q(pf, .25), q(pf, .75), med(ra), med(rb), med(pr), q(pr, .25), q(pr, .75));
}
int main(int argc, char** argv) {
  int rounds = argc > 1 ? atoi(argv[1]) : 20;
  cmp<2>("pair2d", Pair2DExactOld(Law::flux), Pair2DExact(Law::flux), rounds, 200000);
  cmp<3>("pair3d", Pair3DExactOld(Law::flux), Pair3DExact(Law::flux), rounds, 100000);
  std::printf("sink %g\n", sink);
}
