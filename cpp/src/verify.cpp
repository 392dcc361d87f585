#include "revcol/verify.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <sstream>

#include "revcol/collide/pair1d.hpp"
#include "revcol/collide/pair2d_exact.hpp"
#include "revcol/collide/pair2d_paper.hpp"
#include "revcol/rng/streams.hpp"

namespace revcol {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

template <int Dim>
std::vector<double> flat(const PairV<Dim>& v) {
  std::vector<double> out(v.i.begin(), v.i.end());
  out.insert(out.end(), v.j.begin(), v.j.end());
  return out;
}
template <int Dim>
void negate(PairV<Dim>& v) {
  for (int k = 0; k < Dim; ++k) { v.i[k] = -v.i[k]; v.j[k] = -v.j[k]; }
}

double max_rel_error(const std::vector<double>& a, const std::vector<double>& b) {
  double scale = 0.0, err = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    scale = std::fmax(scale, std::fabs(b[k]));
    err = std::fmax(err, std::fabs(a[k] - b[k]));
  }
  return scale > 0.0 ? err / scale : err;
}

// The 2-particle 2D illustration (the paper's Procedure for "Reversal Illustration for
// 2-Particle Collisions in 2 Dimensions") for any 2D pair operator and generator.
template <class Op, class Gen>
void run_pair2d(const Op& op, Gen& gen, const VerifyConfig& c, VerifyResult& r,
                const std::function<PairV<2>(const PairV<2>&, const std::array<double, 2>&,
                                             const Invariants<2>&)>& reference) {
  PairV<2> v{{0.25, -0.5}, {1.0, 0.75}};  // default start: approaches along (1, 1)
  if (!c.velocities.empty()) {
    require(c.velocities.size() == 4, "pair2d needs 4 initial velocity components");
    v.i = {c.velocities[0], c.velocities[1]};
    v.j = {c.velocities[2], c.velocities[3]};
  }
  std::array<double, 2> n{1.0, 1.0};
  if (!c.normal.empty()) {
    require(c.normal.size() == 2, "pair2d needs a 2-component normal");
    n = {c.normal[0], c.normal[1]};
  }
  const Invariants<2> inv{{v.i[0] + v.j[0], v.i[1] + v.j[1]},
                          v.i[0] * v.i[0] + v.i[1] * v.i[1] + v.j[0] * v.j[0] + v.j[1] * v.j[1]};
  op.check_pre(v, n, &inv);  // a bad start throws here, before anything runs
  const auto start_state = gen;
  r.initial = flat(v);
  r.reference = flat(reference(v, n, inv));
  RareLog log;

  auto t0 = Clock::now();
  for (std::uint64_t k = 0; k < c.collisions; ++k) {
    v = op.forward(v, n, gen.next(), log, &inv);
    negate(v);  // reverse the velocities to create the next collision
  }
  r.forward_s = seconds_since(t0);
  r.log_bytes = log.bytes();
  r.log_entries = log.size();
  r.random_numbers_drawn = c.collisions;

  t0 = Clock::now();
  std::uint64_t undone = 0;
  try {
    for (; undone < c.collisions; ++undone) {
      negate(v);
      const double g = gen.prev();
      v = op.reverse(v, n, g, log, &inv);
    }
  } catch (const InvalidArgument& e) {
    // a wrong reversal (the printed Procedure 2) hands the next step an invalid state
    r.error = "reverse step " + std::to_string(undone + 1) + " of " +
              std::to_string(c.collisions) + ": " + e.what();
    ++undone;  // its number was stepped back
  }
  r.reverse_s = seconds_since(t0);
  r.random_numbers_undone = undone;
  r.final_velocities = flat(v);
  r.rng_restored = gen == start_state;
  r.passed = log.size() == 0;
}

template <class Gen>
void run_case(const VerifyConfig& c, VerifyResult& r) {
  Gen gen = rng::make_generator<Gen>(0, c.seed, 1);
  if (c.case_name == "pair2d") {
    if (c.mode == Mode::exact) {
      const Pair2DExact op(c.law, c.bits);
      run_pair2d(op, gen, c, r, [&](const PairV<2>& v, const std::array<double, 2>& n,
                                    const Invariants<2>& inv) { return op.quantize(v, n, &inv); });
    } else {
      const Pair2DPaper op(c.printed_reverse);
      run_pair2d(op, gen, c, r, [](const PairV<2>& v, const std::array<double, 2>&,
                                   const Invariants<2>&) { return v; });
    }
  } else if (c.case_name == "pair1d") {
    // no free parameter and no random number: the exchange is exact in floating point
    const Pair1D op;
    PairV<1> v{{0.25}, {1.5}};
    if (!c.velocities.empty()) {
      require(c.velocities.size() == 2, "pair1d needs 2 initial velocity components");
      v = {{c.velocities[0]}, {c.velocities[1]}};
    }
    const double n = c.normal.empty() ? 1.0 : c.normal.at(0);
    r.initial = r.reference = flat(v);
    (void)op.forward(v, n);  // validates the start
    auto t0 = Clock::now();
    for (std::uint64_t k = 0; k < c.collisions; ++k) { v = op.forward(v, n); negate(v); }
    r.forward_s = seconds_since(t0);
    t0 = Clock::now();
    for (std::uint64_t k = 0; k < c.collisions; ++k) { negate(v); v = op.reverse(v, n); }
    r.reverse_s = seconds_since(t0);
    r.final_velocities = flat(v);
    r.rng_restored = true;
    r.passed = true;
  } else {
    if (detail::run_exact_case(c, r) || detail::run_paper_case(c, r)) return;
    std::string known;
    for (const std::string& name : verify_cases(c.mode)) known += (known.empty() ? "" : ", ") + name;
    throw InvalidArgument("unknown verify case '" + c.case_name + "' for mode " +
                          to_string(c.mode) + " (known: " + known + ")");
  }
}

}  // namespace

VerifyResult verify(const VerifyConfig& c) {
  require(c.collisions >= 1, "collisions must be >= 1");
  FixedPoint check_bits(c.bits);  // validates K
  (void)check_bits;
  VerifyResult r;
  r.config = c;
  r.collisions = c.collisions;  // a case runner lowers it when its chain stops early
  if (c.rng == "clcg4") run_case<rng::CLCG4>(c, r);
  else if (c.rng == "philox") run_case<rng::Philox>(c, r);
  else throw InvalidArgument("rng must be 'clcg4' or 'philox', got '" + c.rng + "'");
  r.max_rel_error = max_rel_error(r.final_velocities, r.initial);
  r.bit_exact = r.final_velocities == r.reference;
  r.forward_per_s = r.forward_s > 0 ? static_cast<double>(r.collisions) / r.forward_s : 0.0;
  r.reverse_per_s = r.reverse_s > 0 ? static_cast<double>(r.collisions) / r.reverse_s : 0.0;
  const bool exact = detail::promises_bit_exact(c);
  r.passed = r.passed && r.error.empty() && r.rng_restored && r.max_rel_error <= 1e-9 && (!exact || r.bit_exact);
  return r;
}

std::vector<std::string> verify_cases(Mode mode) {
  std::vector<std::string> out{"pair1d", "pair2d"};
  const std::vector<std::string> more =
      mode == Mode::exact ? detail::exact_case_names() : detail::paper_case_names();
  for (const std::string& n : more)
    if (n != "pair1d" && n != "pair2d") out.push_back(n);
  return out;
}

bool detail::promises_bit_exact(const VerifyConfig& c) {
  return c.case_name == "pair1d" || c.mode == Mode::exact;
}

namespace {
std::string escaped(const std::string& s) {
  std::string out;
  for (char ch : s) {
    if (ch == '"' || ch == '\\') out += '\\';
    out += ch;
  }
  return out;
}
}  // namespace

std::string to_json(const VerifyResult& r) {
  auto num = [](double x) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.17g", x);
    return std::string(buf);
  };
  auto arr = [&](const std::vector<double>& v) {
    std::string s = "[";
    for (std::size_t k = 0; k < v.size(); ++k) s += (k ? ", " : "") + num(v[k]);
    return s + "]";
  };
  const VerifyConfig& c = r.config;
  std::ostringstream o;
  o << "{\"case\": \"" << c.case_name << "\", \"mode\": \"" << to_string(c.mode)
    << "\", \"law\": \"" << to_string(c.law) << "\", \"rng\": \"" << c.rng
    << "\", \"seed\": " << c.seed << ", \"bits\": " << c.bits
    << ", \"printed_reverse\": " << (c.printed_reverse ? "true" : "false")
    << ", \"passed\": " << (r.passed ? "true" : "false")
    << ", \"bit_exact\": " << (r.bit_exact ? "true" : "false")
    << ", \"max_rel_error\": " << num(r.max_rel_error) << ", \"collisions\": " << r.collisions
    << ", \"forward_per_s\": " << num(r.forward_per_s)
    << ", \"reverse_per_s\": " << num(r.reverse_per_s) << ", \"forward_s\": " << num(r.forward_s)
    << ", \"reverse_s\": " << num(r.reverse_s) << ", \"log_bytes\": " << r.log_bytes
    << ", \"log_entries\": " << r.log_entries
    << ", \"random_numbers_drawn\": " << r.random_numbers_drawn
    << ", \"random_numbers_undone\": " << r.random_numbers_undone
    << ", \"rng_restored\": " << (r.rng_restored ? "true" : "false")
    << ", \"error\": \"" << escaped(r.error) << "\""
    << ", \"initial\": " << arr(r.initial) << ", \"final\": " << arr(r.final_velocities)
    << ", \"reference\": " << arr(r.reference) << "}";
  return o.str();
}

}  // namespace revcol
