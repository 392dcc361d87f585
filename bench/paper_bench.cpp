// revcol-bench family "paper": the paper-mode operators of §4.3-4.5 and their G-to-Psi maps.
//
//   paper/<case>           forward and reverse collisions per second (pair3d, triple1d with
//                          each arc method, triple2d-c1..c4); reverse counts valid posts only
//   paper/arc/<method>     ellipse arc-length G-to-Psi (§4.4): ns per sample, and the max
//                          error against the long double reference over 2000 fixed G
//   paper/calotte          hyper-ellipsoid G-to-Psi (Procedure 5): ns per sample (3 draws)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

#include "bench.hpp"
#include "revcol/collide/calotte.hpp"
#include "revcol/collide/ellipse_arc.hpp"
#include "revcol/rng/clcg4.hpp"
#include "revcol/studies/paper_study.hpp"

namespace revcol::bench {
namespace {

using Clock = std::chrono::steady_clock;

std::vector<Metric> case_metrics(const std::string& name, paper::ArcMethod arc, std::uint64_t n) {
  paper::StudyConfig c;
  c.case_name = name;
  c.collisions = n;
  c.arc = arc;
  const paper::Throughput t = paper::throughput(c);
  return {{"forward_per_s", t.forward_per_s}, {"reverse_per_s", t.reverse_per_s},
          {"valid_fraction", t.valid_fraction}};
}

// The reference parametric angles at 2000 fixed G (computed once: long double, slow).
const std::vector<std::pair<double, long double>>& references() {
  static const std::vector<std::pair<double, long double>> refs = [] {
    std::vector<std::pair<double, long double>> out;
    for (int k = 0; k < 2000; ++k) {
      const double g = (k + 0.5) / 2000.0;
      out.emplace_back(g, paper::EllipseArc::reference_parametric(g, paper::kPaperAspect));
    }
    out.emplace_back(0.0, 0.0L);
    out.emplace_back(1.0, paper::EllipseArc::reference_parametric(1.0L, paper::kPaperAspect));
    return out;
  }();
  return refs;
}

std::vector<Metric> arc_metrics(paper::ArcMethod m, std::uint64_t n) {
  const paper::EllipseArc ell(m);
  rng::CLCG4 gen(7);
  double sink = 0.0;
  const auto t0 = Clock::now();
  for (std::uint64_t k = 0; k < n; ++k) sink += ell.parametric(gen.next());
  const double dt = std::chrono::duration<double>(Clock::now() - t0).count();
  volatile double keep = sink;
  (void)keep;
  long double err = 0.0L;
  for (const auto& [g, ref] : references())
    err = std::max(err, std::fabs(static_cast<long double>(ell.parametric(g)) - ref));
  return {{"ns_per_sample", dt / static_cast<double>(n) * 1e9},
          {"max_error", static_cast<double>(err)}};
}

}  // namespace

void add_paper_benches(std::vector<Bench>& out) {
  out.push_back({"paper/pair3d", "collisions/s",
                 [](std::uint64_t n) { return case_metrics("pair3d", paper::ArcMethod::simpson, n); }});
  for (paper::ArcMethod m : {paper::ArcMethod::simpson, paper::ArcMethod::elliptic, paper::ArcMethod::table}) {
    out.push_back({std::string("paper/triple1d/") + paper::to_string(m), "collisions/s",
                   [m](std::uint64_t n) {
                     // the paper's Simpson method costs ~20 us a sample: fewer collisions
                     return case_metrics("triple1d", m, m == paper::ArcMethod::simpson ? std::max<std::uint64_t>(1, n / 20) : n);
                   }});
  }
  for (const char* c : {"triple2d-c1", "triple2d-c2", "triple2d-c3", "triple2d-c4"}) {
    const std::string name = c;
    out.push_back({"paper/" + name, "collisions/s",
                   [name](std::uint64_t n) { return case_metrics(name, paper::ArcMethod::simpson, n); }});
  }
  for (paper::ArcMethod m : {paper::ArcMethod::simpson, paper::ArcMethod::elliptic, paper::ArcMethod::table}) {
    out.push_back({std::string("paper/arc/") + paper::to_string(m), "ns/sample", [m](std::uint64_t n) {
                     return arc_metrics(m, m == paper::ArcMethod::simpson ? std::max<std::uint64_t>(1, n / 20) : n);
                   }});
  }
  out.push_back({"paper/calotte", "ns/sample", [](std::uint64_t n) {
                   const paper::HyperEllipsoidSampler s;
                   rng::CLCG4 gen(11);
                   double sink = 0.0;
                   const auto t0 = Clock::now();
                   for (std::uint64_t k = 0; k < n; ++k) {
                     const auto psi = s.psi({gen.next(), gen.next(), gen.next()});
                     sink += psi[0] + psi[1] + psi[2];
                   }
                   const double dt = std::chrono::duration<double>(Clock::now() - t0).count();
                   volatile double keep = sink;
                   (void)keep;
                   return std::vector<Metric>{{"ns_per_sample", dt / static_cast<double>(n) * 1e9}};
                 }});
}

}  // namespace revcol::bench
