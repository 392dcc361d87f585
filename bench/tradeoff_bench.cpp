// revcol-bench family "tradeoff" (issue 18): what a collision costs against what accuracy it
// buys, one operator or engine and one setting of its knobs per run. The driver
// (python/revcol/tradeoff.py, `revcol bench tradeoff`) runs every point in a fresh process,
// the variants of one knob interleaved, and adds the law's KS distance (computed in Python
// from the bound operators); this file does the timing and the chain errors.
//
//   tradeoff/op      one collision operator (REVCOL_TRADEOFF: case, mode, law, rng, bits, seed, arc)
//   tradeoff/engine  the float engine on periodic gases (dim, particles, phi, group_tol, bits, rng, seed, seeds, warm)
//   tradeoff/arc     the 1D triple's G-to-Psi (arc = simpson | elliptic | table, tol, cells)
//   tradeoff/calotte the 2D triple's G-to-Psi tables (cells, nodes)
//
//   REVCOL_TRADEOFF="case=triple2d-c1,mode=exact,law=flux,rng=clcg4,bits=40" revcol-bench --bench tradeoff/op --collisions 100000 --repeats 1
//
// tradeoff/op metrics, for a chain of N = --collisions collisions:
//   forward_per_s, reverse_per_s   the reversal illustration's chain (revcol::verify: momentum
//                                  and energy held, velocities negated after each collision, then
//                                  all reversed with the generator stepping back); the 1D
//                                  triple's other arc methods run the same chain here
//                                  (verify() knows only the paper's Simpson method)
//   roundtrip_error, bit_exact     max |v_end - v_0| / max |v_0| of that chain; bit_exact: 1 when
//                                  the end equals the quantized start (exact) / the start (paper)
//   log_bytes_per_collision        the rare log at the turn over N
//   chain_failed                   1 when the chain stopped early or a reverse step threw
//   collisions                     collisions the chain actually took
//   energy_drift, momentum_drift   the same chain forward WITHOUT held invariants (each collision
//                                  computes momentum and energy from its own input): |E_N/E_0 - 1|
//                                  and max_k |P_N,k - (-1)^N P_0,k| / sqrt(E_0) after the N taken
//   drift_collisions               collisions that free chain took (paper mode can stop early)
//   paper mode only (pair3d, triple1d, triple2d-c1..c4): failure_rate and single_error from
//   paper::study (N single collisions of the chain, each reversed at once: the fraction that
//   does not come back, and the largest error among those that do), and the times from
//   paper::throughput (the same chain restarted where a post state does not separate; reverse
//   over the valid post states): the illustration's chain can stop after a few collisions
//
// tradeoff/engine metrics, over `seeds` gases (seed, seed + 1, ...): forward_per_s,
// reverse_per_s (N collisions each way after `warm` collisions per particle, summed over the
// gases), roundtrip_error (the worst max |v - v_start| / max |v_start|), broken_fraction (gases
// whose round trip exceeds 1e-6), log_bytes_per_collision (the engine's logs after the forward
// run over N), group_fraction (collisions of three or more over N, forward), energy_drift (the
// worst relative drift, after the forward run).
//
// tradeoff/arc and tradeoff/calotte: ns_per_sample (one G-to-Psi evaluation: a collision does
// one forward and one reverse), map_error (arc: the parametric angle's largest error against
// EllipseArc::reference_parametric; calotte: the largest CDF error |F(psi(g)) - g| of either
// table against CalotteTable::fraction_direct, i.e. the error of the sampled probability),
// build_ms (calotte: building both tables).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <variant>
#include <vector>

#include "bench.hpp"
#include "revcol/collide/calotte.hpp"
#include "revcol/collide/cases.hpp"
#include "revcol/collide/ellipse_arc.hpp"
#include "revcol/collide/pair2d_exact.hpp"
#include "revcol/collide/pair2d_paper.hpp"
#include "revcol/engine/engine.hpp"
#include "revcol/engine/init.hpp"
#include "revcol/rng/clcg4.hpp"
#include "revcol/studies/paper_adapt.hpp"
#include "revcol/studies/verify.hpp"

namespace revcol::bench {
namespace {

/// One point of the tradeoff: which operator or gas, with which knobs.
struct Point {
  VerifyConfig verify;                            ///< case, mode, law, rng, seed, bits
  paper::ArcMethod arc = paper::ArcMethod::simpson;  ///< the 1D triple's G-to-Psi (paper mode)
  int dim = 2;                                    ///< engine: dimension
  std::size_t particles = 400;                    ///< engine: N
  double phi = 0.3;                               ///< engine: packing fraction
  double group_tol = 1e-9;                        ///< engine: contact tolerance (relative to D)
  double warm = 5.0;                              ///< engine: collisions per particle before timing
  double tol = paper::EllipseArc::simpson_tolerance;   ///< arc map: the simpson method's tolerance
  int cells = 0;                                  ///< arc / calotte map: table cells (0: the default)
  int nodes = paper::CalotteTable::quadrature_nodes;   ///< calotte map: Gauss-Legendre nodes per cell
  int seeds = 1;                                  ///< engine: gases (seed, seed + 1, ...)
};

Point read_point() {
  Point p;
  apply_settings("REVCOL_TRADEOFF",
                 "case, mode, law, rng, bits, seed, arc, dim, particles, phi, group_tol, warm, tol, cells, nodes, seeds",
                 [&](const std::string& key, const std::string& value) {
                   if (key == "case") p.verify.case_name = value;
                   else if (key == "mode") p.verify.mode = parse_mode(value);
                   else if (key == "law") p.verify.law = parse_law(value);
                   else if (key == "rng") p.verify.rng = value;
                   else if (key == "bits") p.verify.bits = std::stoi(value);
                   else if (key == "seed") p.verify.seed = std::stoull(value);
                   else if (key == "arc") p.arc = paper::parse_arc_method(value);
                   else if (key == "dim") p.dim = std::stoi(value);
                   else if (key == "particles") p.particles = std::stoull(value);
                   else if (key == "phi") p.phi = std::stod(value);
                   else if (key == "group_tol") p.group_tol = std::stod(value);
                   else if (key == "warm") p.warm = std::stod(value);
                   else if (key == "tol") p.tol = std::stod(value);
                   else if (key == "cells") p.cells = std::stoi(value);
                   else if (key == "nodes") p.nodes = std::stoi(value);
                   else if (key == "seeds") p.seeds = std::max(1, std::stoi(value));
                   else return false;
                   return true;
                 });
  return p;
}

// ---- drift: the chain forward with nothing held --------------------------------------------

struct Drift {
  double energy = 0.0, momentum = 0.0;
  std::uint64_t done = 0;
};

// `step(v, g)` replaces the flat velocities v (n x d) by the post state of one collision with
// draws g, throwing InvalidArgument when it refuses v; the chain negates v after each step.
template <class Step>
Drift free_chain(std::vector<double> v, int d, std::size_t draws, std::uint64_t n,
                 detail::Generator& gen, Step&& step) {
  auto sums = [d](const std::vector<double>& x, std::vector<double>& p) {
    double e = 0.0;
    p.assign(d, 0.0);
    for (std::size_t k = 0; k < x.size(); ++k) {
      p[k % d] += x[k];
      e += x[k] * x[k];
    }
    return e;
  };
  std::vector<double> p0, p1, g(draws > 0 ? draws : 1);
  const double e0 = sums(v, p0);
  Drift out;
  for (; out.done < n; ++out.done) {
    std::visit([&](auto& gn) { for (double& x : g) x = gn.next(); }, gen);
    try {
      step(v, g.data());
    } catch (const InvalidArgument&) {
      break;  // paper mode: a post state the next collision refuses ends the chain
    }
    for (double& x : v) x = -x;
  }
  const double e1 = sums(v, p1);
  const double sign = out.done % 2 ? -1.0 : 1.0;
  out.energy = std::fabs(e1 / e0 - 1.0);
  for (int k = 0; k < d; ++k) out.momentum = std::fmax(out.momentum, std::fabs(p1[k] - sign * p0[k]));
  out.momentum /= std::sqrt(e0);
  return out;
}

template <class Op>
Drift paper_drift(const Point& pt, const std::vector<double>& start, std::uint64_t n, detail::Generator& gen) {
  using A = paper::adapt::Adapter<Op>;
  paper::StudyConfig sc;
  sc.arc = pt.arc;
  const Op op = A::make(sc);
  const paper::PaperCase& pc = paper::paper_case(pt.verify.case_name);
  const typename Op::Geometry x = A::geometry(pc.geometry);
  RareLog log;
  return free_chain(start, pc.d, Op::draws, n, gen, [&](std::vector<double>& v, const double* g) {
    typename Op::Draws dr;
    for (std::size_t k = 0; k < dr.size(); ++k) dr[k] = g[k];
    v = A::flat(op.forward(A::state(v), x, dr, log));
  });
}

Drift drift(const Point& pt, const std::vector<double>& start, std::uint64_t n) {
  const VerifyConfig& c = pt.verify;
  detail::Generator gen = detail::make_generator(c);
  if (c.mode == Mode::paper && c.case_name != "pair1d" && c.case_name != "pair2d") {
    if (c.case_name == "pair3d") return paper_drift<Pair3DPaper>(pt, start, n, gen);
    if (c.case_name == "triple1d") return paper_drift<Triple1DPaper>(pt, start, n, gen);
    return paper_drift<Triple2DPaper>(pt, start, n, gen);
  }
  RareLog log;
  if (c.case_name == "pair2d") {  // verify's pair2d: the fast 2D operators, normal (1, 1)
    const std::array<double, 2> r{1.0, 1.0};
    const Pair2DExact ex(c.law, c.bits);
    const Pair2DPaper pp(false);
    return free_chain(start, 2, 1, n, gen, [&](std::vector<double>& v, const double* g) {
      const PairV<2> pre{{v[0], v[1]}, {v[2], v[3]}};
      const PairV<2> post = c.mode == Mode::exact ? ex.forward(pre, r, g[0], log) : pp.forward(pre, r, g[0], log);
      v = {post.i[0], post.i[1], post.j[0], post.j[1]};
    });
  }
  const NamedCase nc = named_case(c.case_name);  // pair1d in either mode is the exchange
  const ExactCollision op = exact_operator(nc, c.law, c.bits);
  std::vector<double> out(start.size());
  return free_chain(start, nc.d, static_cast<std::size_t>(op.draws()), n, gen,
                    [&](std::vector<double>& v, const double* g) {
                      op.forward(v.data(), g, out.data(), log);
                      v.swap(out);
                    });
}

// ---- the round trip of the 1D triple with another arc method ----------------------------------

// verify()'s paper chain for Triple1DPaper built with pt.arc: momentum and energy of the start
// held, the draws of one collision in `Draws`.
struct ArcChain {
  using A = paper::adapt::Adapter<Triple1DPaper>;
  using State = Triple1DPaper::State;
  static constexpr bool stops_early = true;
  Triple1DPaper op;
  Triple1DPaper::Geometry x;
  Triple1DPaper::Inv held;
  std::size_t draws() const { return 1; }
  void forward(State& v, const double* g, RareLog& log, std::uint64_t) const { v = op.forward(v, x, {g[0]}, log, &held); }
  void reverse(State& v, const double* g, RareLog& log, std::uint64_t) const { v = op.reverse(v, x, {g[0]}, log, &held); }
  void negate(State& v) const { A::negate(v); }
  std::vector<double> flat(const State& v) const { return A::flat(v); }
};

VerifyResult arc_roundtrip(const Point& pt) {
  using A = ArcChain::A;
  paper::StudyConfig sc;
  sc.arc = pt.arc;
  const paper::PaperCase& pc = paper::paper_case("triple1d");
  const ArcChain::State v = A::state(pc.velocities);
  const ArcChain chain{A::make(sc), A::geometry(pc.geometry), A::invariants(v)};
  VerifyResult r;
  r.config = pt.verify;
  r.initial = r.reference = A::flat(v);
  detail::Generator gen = detail::make_generator(pt.verify);
  std::visit([&](auto& g) { detail::reversal_chain(chain, v, g, pt.verify, r); }, gen);
  double scale = 0.0, err = 0.0;
  for (std::size_t k = 0; k < r.initial.size(); ++k) {
    scale = std::fmax(scale, std::fabs(r.initial[k]));
    err = std::fmax(err, std::fabs(r.final_velocities[k] - r.initial[k]));
  }
  r.max_rel_error = err / scale;
  r.bit_exact = r.final_velocities == r.initial;
  r.forward_per_s = static_cast<double>(r.collisions) / r.forward_s;
  r.reverse_per_s = static_cast<double>(r.collisions) / r.reverse_s;
  return r;
}

std::vector<Metric> run_op(std::uint64_t n) {
  Point pt = read_point();
  pt.verify.collisions = n;
  const bool other_arc = pt.verify.mode == Mode::paper && pt.verify.case_name == "triple1d" &&
                         pt.arc != paper::ArcMethod::simpson;
  const VerifyResult r = other_arc ? arc_roundtrip(pt) : verify(pt.verify);
  const Drift dr = drift(pt, r.initial, n);
  const auto nd = static_cast<double>(n);
  std::vector<Metric> out{{"forward_per_s", r.forward_per_s},
                          {"reverse_per_s", r.reverse_per_s},
                          {"roundtrip_error", r.max_rel_error},
                          {"bit_exact", r.bit_exact ? 1.0 : 0.0},
                          {"log_bytes_per_collision", static_cast<double>(r.log_bytes) / nd},
                          {"chain_failed", r.error.empty() && r.collisions == n ? 0.0 : 1.0},
                          {"collisions", static_cast<double>(r.collisions)},
                          {"energy_drift", dr.energy},
                          {"momentum_drift", dr.momentum},
                          {"drift_collisions", static_cast<double>(dr.done)}};
  const bool paper_case = pt.verify.mode == Mode::paper && pt.verify.case_name != "pair1d" &&
                          pt.verify.case_name != "pair2d";
  if (paper_case) {
    paper::StudyConfig sc;
    sc.case_name = pt.verify.case_name;
    sc.collisions = n;
    sc.seed = pt.verify.seed;
    sc.arc = pt.arc;
    const paper::StudyResult s = paper::study(sc);
    out.push_back({"failure_rate", s.failure_rate});
    out.push_back({"single_error", s.max_ok_error});
    // the chain of a paper case can stop after a few collisions (a post state the next one
    // refuses): time the study's chain instead, restarted where it stops
    const paper::Throughput t = paper::throughput(sc);
    out[0].value = t.forward_per_s;
    out[1].value = t.reverse_per_s;
  }
  return out;
}

// ---- the float engine on a small gas ---------------------------------------------------------

// One gas (seed `seed`): warm-up, n collisions forward timed, n back timed.
struct EngineRun {
  double forward_s = 0.0, reverse_s = 0.0, error = 0.0, energy_drift = 0.0;
  std::uint64_t collisions = 0, back = 0, groups = 0, log_bytes = 0;
};

EngineRun engine_once(const Point& pt, std::uint64_t seed, std::uint64_t n) {
  namespace en = revcol::engine;
  using Clock = std::chrono::steady_clock;
  constexpr double inf = std::numeric_limits<double>::infinity();
  en::Config cfg;
  cfg.dim = pt.dim;
  cfg.law = pt.verify.law;
  cfg.bits = pt.verify.bits;
  cfg.group_tol = pt.group_tol;
  cfg.seed = static_cast<std::uint32_t>(seed);
  cfg.generator = en::parse_generator(pt.verify.rng);
  const en::InitialState st = en::random_state(cfg, pt.particles, pt.phi, seed + 1);
  auto sim = en::make_simulation(st.config, st.x, st.v);
  sim->run(static_cast<std::uint64_t>(pt.warm * static_cast<double>(pt.particles) / 2.0), inf);
  const std::vector<double> v0 = sim->velocities();
  const en::Diagnostics d0 = sim->diagnostics();
  EngineRun r;
  const auto t0 = Clock::now();
  r.collisions = sim->run(n, inf).collisions;
  const auto t1 = Clock::now();
  const en::Diagnostics d1 = sim->diagnostics();
  r.back = sim->run_back(n, -inf).collisions;
  r.reverse_s = std::chrono::duration<double>(Clock::now() - t1).count();
  r.forward_s = std::chrono::duration<double>(t1 - t0).count();
  const std::vector<double> v1 = sim->velocities();
  double scale = 0.0;
  for (std::size_t k = 0; k < v0.size(); ++k) {
    scale = std::fmax(scale, std::fabs(v0[k]));
    r.error = std::fmax(r.error, std::fabs(v1[k] - v0[k]));
  }
  r.error /= scale;
  r.groups = d1.counters.group_collisions - d0.counters.group_collisions;
  r.log_bytes = d1.log_bytes;
  r.energy_drift = std::fabs(d1.energy_drift);
  return r;
}

// `seeds` gases (seed, seed + 1, ...): times summed, the worst round trip, and the fraction of
// gases whose round trip exceeds 1e-6 (a reversal that left the forward trajectory).
std::vector<Metric> run_engine(std::uint64_t n) {
  const Point pt = read_point();
  double fs = 0.0, bs = 0.0, err = 0.0, drift = 0.0, coll = 0.0, back = 0.0, groups = 0.0, log = 0.0, broken = 0.0;
  for (int k = 0; k < pt.seeds; ++k) {
    const EngineRun r = engine_once(pt, pt.verify.seed + static_cast<std::uint64_t>(k), n);
    fs += r.forward_s;
    bs += r.reverse_s;
    coll += static_cast<double>(r.collisions);
    back += static_cast<double>(r.back);
    groups += static_cast<double>(r.groups);
    log += static_cast<double>(r.log_bytes);
    err = std::fmax(err, r.error);
    drift = std::fmax(drift, r.energy_drift);
    broken += r.error > 1e-6 ? 1.0 : 0.0;
  }
  return {{"forward_per_s", coll / fs},
          {"reverse_per_s", back / bs},
          {"roundtrip_error", err},
          {"broken_fraction", broken / pt.seeds},
          {"log_bytes_per_collision", log / coll},
          {"group_fraction", groups / coll},
          {"energy_drift", drift},
          {"collisions", coll / pt.seeds}};
}

// ---- the G-to-Psi maps of the paper's triples, with their accuracy knobs ------------------------

using Clock = std::chrono::steady_clock;

// ns per call of f(g) over n CLCG4 draws (each call takes `per` draws).
template <class F>
double ns_per_sample(std::uint64_t n, int per, F&& f) {
  rng::CLCG4 gen(7);
  double sink = 0.0;
  const auto t0 = Clock::now();
  for (std::uint64_t k = 0; k < n; ++k) {
    double g[2] = {gen.next(), per > 1 ? gen.next() : 0.0};
    sink += f(g);
  }
  const double dt = std::chrono::duration<double>(Clock::now() - t0).count();
  volatile double keep = sink;  // the loop must run
  (void)keep;
  return dt / static_cast<double>(n) * 1e9;
}

// The ellipse arc (triple1d): ns per psi, and the largest error of the parametric angle against
// the long double reference at 400 evenly spread G.
std::vector<Metric> run_arc(std::uint64_t n) {
  const Point pt = read_point();
  const int cells = pt.cells > 0 ? pt.cells : paper::EllipseArc::table_cells;
  const paper::EllipseArc ell(pt.arc, paper::ArcAngle::parametric, paper::kPaperAspect, pt.tol, cells);
  // the paper's Simpson method costs ~20 us a sample: fewer samples
  const std::uint64_t m = pt.arc == paper::ArcMethod::simpson ? std::max<std::uint64_t>(1, n / 20) : n;
  const double ns = ns_per_sample(m, 1, [&](const double* g) { return ell.parametric(g[0]); });
  long double err = 0.0L;
  for (int k = 0; k < 400; ++k) {
    const double g = (k + 0.375) / 400.0;
    const long double ref = paper::EllipseArc::reference_parametric(g, paper::kPaperAspect);
    err = std::max(err, std::fabs(static_cast<long double>(ell.parametric(g)) - ref));
  }
  return {{"ns_per_sample", ns}, {"map_error", static_cast<double>(err)}};
}

// The calotte tables (triple2d, Procedure 5): ns per (psi_1, psi_2), the build time of the two
// tables, and the largest CDF error |F(F_table^-1(g)) - g| of either (F by direct quadrature)
// at 60 evenly spread g.
std::vector<Metric> run_calotte(std::uint64_t n) {
  const Point pt = read_point();
  const int cells = pt.cells > 0 ? pt.cells : paper::CalotteTable::cells;
  const auto t0 = Clock::now();
  const paper::CalotteTable h4 = paper::CalotteTable::build(4, cells, pt.nodes);
  const paper::CalotteTable h3 = paper::CalotteTable::build(3, cells, pt.nodes);
  const double build_ms = std::chrono::duration<double>(Clock::now() - t0).count() * 1e3;
  const double ns = ns_per_sample(n, 2, [&](const double* g) { return h4.inverse(g[0]) + h3.inverse(g[1]); });
  double err = 0.0;
  for (int k = 0; k < 60; ++k) {
    const double g = (k + 0.375) / 60.0;
    for (const paper::CalotteTable* t : {&h4, &h3})
      err = std::fmax(err, std::fabs(paper::CalotteTable::fraction_direct(t->dim(), t->inverse(g)) - g));
  }
  return {{"ns_per_sample", ns}, {"map_error", err}, {"build_ms", build_ms}};
}

}  // namespace

void add_tradeoff_benches(std::vector<Bench>& out) {
  out.push_back({"tradeoff/op", "collisions/s", run_op});
  out.push_back({"tradeoff/engine", "collisions/s", run_engine});
  out.push_back({"tradeoff/arc", "ns/sample", run_arc});
  out.push_back({"tradeoff/calotte", "ns/sample", run_calotte});
}

}  // namespace revcol::bench
