// Paper-mode cases and the reversal-failure measurement (see paper_study.hpp).
#include "revcol/studies/paper_study.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "revcol/rng/clcg4.hpp"
#include "revcol/studies/paper_adapt.hpp"

namespace revcol::paper {

const std::vector<PaperCase>& paper_cases() {
  // The geometries are those of collide/cases.hpp (diameter 1; particle 0 is the paper's P1).
  static const std::vector<PaperCase> cases = [] {
    const double h = std::sqrt(3.0) / 2.0, th = 5.0 * kPi / 6.0;
    return std::vector<PaperCase>{
        {"pair3d", 2, 3, {1.0, 1.0, 1.0}, {0.25, -0.5, 0.1, 1.0, 0.75, 0.6},
         "2 particles in 3D, contact normal r21 = (1, 1, 1) (§4.3)"},
        {"triple1d", 3, 1, {0.0, 1.0, 2.0}, {0.75, 0.25, -0.5},
         "3 particles in a row, left to right 0, 1, 2 (§4.4, the illustration of §5.1)"},
        {"triple2d-c1", 3, 2, {0.0, 0.0, 1.0, 0.0, 0.5, h}, {0.5, 0.3, -0.5, 0.25, 0.05, -0.6},
         "3 disks in mutual contact, P3 above P1-P2 (C1, §4.5)"},
        {"triple2d-c2", 3, 2, {0.0, 0.0, 1.0, 0.0, 0.5, -h}, {0.5, -0.3, -0.5, -0.25, 0.05, 0.6},
         "3 disks in mutual contact, P3 below P1-P2 (C2, the mirror image of C1)"},
        {"triple2d-c3", 3, 2, {0.0, 0.0, 1.0, 0.0, 1.0 - std::cos(th), -std::sin(th)},
         {0.5, 0.0, -0.25, 0.1, -0.9, 0.4}, "P3 touches P2 only, theta = 5 pi/6 (C3)"},
        {"triple2d-c4", 3, 2, {0.0, 0.0, 1.0, 0.0, std::cos(th), std::sin(th)},
         {0.3, 0.0, -0.4, 0.0, 0.5, -0.4}, "P3 touches P1 only, theta = -pi/6 from P1 (C4)"},
    };
  }();
  return cases;
}

const PaperCase& paper_case(const std::string& name) {
  std::string known;
  for (const PaperCase& c : paper_cases()) {
    if (c.name == name) return c;
    known += (known.empty() ? "" : ", ") + c.name;
  }
  throw InvalidArgument("unknown paper case '" + name + "' (known: " + known + ")");
}

namespace {

template <class Op>
void run(const StudyConfig& c, StudyResult& r) {
  using A = adapt::Adapter<Op>;
  const PaperCase& pc = paper_case(c.case_name);
  const Op op = A::make(c);
  const typename Op::Geometry x = A::geometry(pc.geometry);
  const typename A::Pred pred(x);
  rng::CLCG4 gen(c.seed);
  adapt::Normal N{c.seed * 0x632be59bd9b4e019ULL + 12345};
  const bool chain = c.pre == "chain";
  typename Op::State pre = chain ? A::state(pc.velocities) : adapt::fresh_pre<Op>(N, pred);
  typename Op::Inv inv = A::invariants(pre);
  op.check_pre(pre, x, &inv);
  typename Op::Draws g;
  auto note = [&](std::uint64_t k, const std::string& what) {
    if (!r.first_failure.empty()) return;
    std::ostringstream o;
    o.precision(17);
    o << "collision " << (k + 1) << ": " << what << "; pre = [";
    const std::vector<double> f = A::flat(pre);
    for (std::size_t i = 0; i < f.size(); ++i) o << (i ? ", " : "") << f[i];
    o << "], g = [";
    for (std::size_t i = 0; i < g.size(); ++i) o << (i ? ", " : "") << g[i];
    o << "]";
    r.first_failure = o.str();
  };
  InterruptPoll poll(c.interrupt);
  for (std::uint64_t k = 0; k < c.collisions; ++k) {
    poll.tick();
    for (double& gk : g) gk = gen.next();
    RareLog log;
    const typename Op::State post = op.forward(pre, x, g, log, &inv);
    r.logged += log.pushed();
    bool restart = !chain;
    if (!pred.separates(post)) {
      ++r.invalid_post;
      note(k, "the forward step's post state does not separate");
      restart = true;
    } else {
      try {
        const typename Op::State back = op.reverse(post, x, g, log, &inv);
        const double e = adapt::rel_error(A::flat(back), A::flat(pre));
        if (e <= 1e-9) {
          ++r.ok;
          r.max_ok_error = std::fmax(r.max_ok_error, e);
        } else {
          ++r.wrong;
          note(k, "the reverse step returned another state (relative error " + std::to_string(e) + ")");
        }
      } catch (const InvalidArgument& e) {
        ++r.reverse_threw;
        note(k, std::string("the reverse step threw: ") + e.what());
      }
    }
    if (k + 1 == c.collisions) break;
    if (restart) {
      if (chain) ++r.restarts;
      pre = adapt::fresh_pre<Op>(N, pred);
      inv = A::invariants(pre);
    } else {
      pre = post;
      A::negate(pre);  // the next collision (momentum negated with it: held as in verify)
      for (double& m : inv.momentum) m = -m;
    }
  }
}

template <class Op>
Throughput time_it(const StudyConfig& c) {
  using A = adapt::Adapter<Op>;
  using Clock = std::chrono::steady_clock;
  const PaperCase& pc = paper_case(c.case_name);
  const Op op = A::make(c);
  const typename Op::Geometry x = A::geometry(pc.geometry);
  const typename A::Pred pred(x);
  rng::CLCG4 gen(c.seed);
  typename Op::State pre = A::state(pc.velocities);
  typename Op::Inv inv = A::invariants(pre);
  constexpr std::size_t block = 4096;
  std::vector<typename Op::State> posts(block);
  std::vector<typename Op::Draws> draws(block);
  std::vector<typename Op::Inv> invs(block);
  std::vector<char> valid(block);
  double fwd = 0.0, rev = 0.0;
  std::uint64_t done = 0, reversed = 0;
  RareLog log;
  const InterruptPoll poll(c.interrupt);
  while (done < c.collisions) {
    poll.now();  // once per block of 4096, outside the timed loops
    const std::size_t m = static_cast<std::size_t>(std::min<std::uint64_t>(block, c.collisions - done));
    for (std::size_t k = 0; k < m; ++k)
      for (double& gk : draws[k]) gk = gen.next();
    auto t0 = Clock::now();
    for (std::size_t k = 0; k < m; ++k) {
      invs[k] = inv;
      posts[k] = op.forward(pre, x, draws[k], log, &invs[k]);
      valid[k] = pred.separates(posts[k]);
      if (valid[k]) {
        pre = posts[k];
        A::negate(pre);
        for (double& mm : inv.momentum) mm = -mm;
      } else {
        pre = A::state(pc.velocities);  // restart (rare outside the printed 2D procedures)
        inv = A::invariants(pre);
      }
    }
    fwd += std::chrono::duration<double>(Clock::now() - t0).count();
    t0 = Clock::now();
    double sink = 0.0;
    for (std::size_t k = m; k-- > 0;) {
      if (!valid[k]) continue;
      try {
        sink += A::flat(op.reverse(posts[k], x, draws[k], log, &invs[k]))[0];
      } catch (const InvalidArgument&) {
      }
      ++reversed;
    }
    rev += std::chrono::duration<double>(Clock::now() - t0).count();
    volatile double keep = sink;
    (void)keep;
    done += m;
    log.clear();
  }
  Throughput t;
  t.forward_per_s = fwd > 0 ? static_cast<double>(done) / fwd : 0.0;
  t.reverse_per_s = rev > 0 ? static_cast<double>(reversed) / rev : 0.0;
  t.valid_fraction = static_cast<double>(reversed) / static_cast<double>(done);
  return t;
}

}  // namespace

Throughput throughput(const StudyConfig& c) {
  require(c.collisions >= 1, "collisions must be >= 1");
  const PaperCase& pc = paper_case(c.case_name);
  if (pc.name == "pair3d") return time_it<Pair3DPaper>(c);
  if (pc.name == "triple1d") return time_it<Triple1DPaper>(c);
  return time_it<Triple2DPaper>(c);
}

StudyResult study(const StudyConfig& c) {
  require(c.collisions >= 1, "collisions must be >= 1");
  require(c.pre == "chain" || c.pre == "uniform", "pre must be 'chain' or 'uniform'");
  StudyResult r;
  r.config = c;
  r.collisions = c.collisions;
  const PaperCase& pc = paper_case(c.case_name);
  if (pc.name == "pair3d") run<Pair3DPaper>(c, r);
  else if (pc.name == "triple1d") run<Triple1DPaper>(c, r);
  else run<Triple2DPaper>(c, r);
  r.failure_rate = static_cast<double>(r.invalid_post + r.reverse_threw + r.wrong) / r.collisions;
  return r;
}

std::string to_json(const StudyResult& r) {
  auto num = [](double x) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.17g", x);
    return std::string(buf);
  };
  auto esc = [](const std::string& s) {
    std::string out;
    for (char ch : s) {
      if (ch == '"' || ch == '\\') out += '\\';
      out += ch;
    }
    return out;
  };
  const StudyConfig& c = r.config;
  std::ostringstream o;
  o << "{\"case\": \"" << c.case_name << "\", \"pre\": \"" << c.pre << "\", \"seed\": " << c.seed
    << ", \"printed_reverse\": " << (c.printed_reverse ? "true" : "false")
    << ", \"cos_tol\": " << num(c.cos_tol) << ", \"arc\": \"" << to_string(c.arc)
    << "\", \"angle\": \"" << to_string(c.angle) << "\", \"collisions\": " << r.collisions
    << ", \"ok\": " << r.ok << ", \"invalid_post\": " << r.invalid_post
    << ", \"reverse_threw\": " << r.reverse_threw << ", \"wrong\": " << r.wrong
    << ", \"restarts\": " << r.restarts << ", \"logged\": " << r.logged
    << ", \"failure_rate\": " << num(r.failure_rate) << ", \"max_ok_error\": " << num(r.max_ok_error)
    << ", \"first_failure\": \"" << esc(r.first_failure) << "\"}";
  return o.str();
}

}  // namespace revcol::paper
