#include "revcol/studies/verify.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>

#include "revcol/collide/pair1d.hpp"
#include "revcol/collide/pair2d_exact.hpp"
#include "revcol/collide/pair2d_paper.hpp"
#include "revcol/collide/pair3d_exact.hpp"
#include "revcol/rng/streams.hpp"

namespace revcol {
namespace {

template <int Dim>
std::vector<double> flat(const PairV<Dim>& v) {
  std::vector<double> out(v.i.begin(), v.i.end());
  out.insert(out.end(), v.j.begin(), v.j.end());
  return out;
}

double max_rel_error(const std::vector<double>& a, const std::vector<double>& b) {
  double scale = 0.0, err = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    scale = std::fmax(scale, std::fabs(b[k]));
    err = std::fmax(err, std::fabs(a[k] - b[k]));
  }
  return scale > 0.0 ? err / scale : err;
}

// Velocities of a pair, negated and flattened (v_i then v_j): the chain's state in 1D and 2D.
template <int Dim>
struct PairChain {
  using State = PairV<Dim>;
  void negate(State& v) const {
    for (int k = 0; k < Dim; ++k) { v.i[k] = -v.i[k]; v.j[k] = -v.j[k]; }
  }
  std::vector<double> flat(const State& v) const { return revcol::flat(v); }
};

// The paper's reversal illustration of 2 particles ("Reversal Illustration for 2-Particle
// Collisions in 2 Dimensions", and the same in 3D) for a pair operator with momentum and energy
// held: either 2D pair operator (one draw) or Pair3DExact (two).
template <class Op>
struct HeldPairChain : PairChain<Op::dim> {
  using State = PairV<Op::dim>;
  static constexpr bool stops_early = false;
  const Op& op;
  std::array<double, Op::dim> n;
  Invariants<Op::dim> inv;
  std::size_t draws() const { return Op::draws; }
  static auto draw(const double* g) {
    if constexpr (Op::draws == 1) return g[0];
    else return std::array<double, 2>{g[0], g[1]};
  }
  void forward(State& v, const double* g, RareLog& log, std::uint64_t) const { v = op.forward(v, n, draw(g), log, &inv); }
  void reverse(State& v, const double* g, RareLog& log, std::uint64_t) const { v = op.reverse(v, n, draw(g), log, &inv); }
};

// The 1D pair: no free parameter and no random number, the exchange is exact in floating point.
struct Pair1DChain : PairChain<1> {
  static constexpr bool stops_early = false;
  Pair1D op;
  double n;
  std::size_t draws() const { return 0; }
  void forward(State& v, const double*, RareLog&, std::uint64_t) const { v = op.forward(v, n); }
  void reverse(State& v, const double*, RareLog&, std::uint64_t) const { v = op.reverse(v, n); }
};

// Case `name`: start v along normal n (VerifyConfig's velocities and normal override them),
// momentum and energy computed once and held, compared at the end with reference(v, n, inv).
template <class Op, class Gen, class Reference>
void run_held_pair(const char* name, const Op& op, PairV<Op::dim> v, std::array<double, Op::dim> n, Gen& gen,
                   const VerifyConfig& c, VerifyResult& r, Reference reference) {
  constexpr int D = Op::dim;
  if (!c.velocities.empty()) {
    require(c.velocities.size() == 2 * D,
            std::string(name) + " needs " + std::to_string(2 * D) + " initial velocity components");
    for (int k = 0; k < D; ++k) {
      v.i[k] = c.velocities[k];
      v.j[k] = c.velocities[D + k];
    }
  }
  if (!c.normal.empty()) {
    require(c.normal.size() == D, std::string(name) + " needs a " + std::to_string(D) + "-component normal");
    for (int k = 0; k < D; ++k) n[k] = c.normal[k];
  }
  Invariants<D> inv{};
  for (int k = 0; k < D; ++k) inv.momentum[k] = v.i[k] + v.j[k];
  inv.energy = 0.0;  // |v_i|^2 then |v_j|^2, one square at a time
  for (int k = 0; k < D; ++k) inv.energy += v.i[k] * v.i[k];
  for (int k = 0; k < D; ++k) inv.energy += v.j[k] * v.j[k];
  op.check_pre(v, n, &inv);  // a bad start throws here, before anything runs
  r.initial = flat(v);
  r.reference = flat(reference(v, n, inv));
  detail::reversal_chain(HeldPairChain<Op>{{}, op, n, inv}, v, gen, c, r);
}

template <class Gen>
bool run_pair_case(const VerifyConfig& c, Gen& gen, VerifyResult& r) {
  // the exact operators come back to their quantized start (the first collision's cells)
  const auto quantized = [](const auto& op) {
    return [&op](const auto& v, const auto& n, const auto& inv) { return op.quantize(v, n, &inv); };
  };
  if (c.case_name == "pair2d") {
    const PairV<2> start{{0.25, -0.5}, {1.0, 0.75}};  // approaches along (1, 1)
    if (c.mode == Mode::exact) {
      const Pair2DExact op(c.law, c.bits);
      run_held_pair("pair2d", op, start, {1.0, 1.0}, gen, c, r, quantized(op));
    } else {
      const Pair2DPaper op(c.printed_reverse);
      run_held_pair("pair2d", op, start, {1.0, 1.0}, gen, c, r, [](const auto& v, const auto&, const auto&) { return v; });
    }
    return true;
  }
  if (c.case_name == "pair3d-fast") {
    // Pair3DExact, the engine's closed-form 3D operator (exact mode's "pair3d" runs the general
    // ExactCollision), from the paper study's pair3d start, approaching along (1, 1, 1)
    if (c.mode != Mode::exact) return false;
    const Pair3DExact op(c.law, c.bits);
    run_held_pair("pair3d-fast", op, {{0.25, -0.5, 0.1}, {1.0, 0.75, 0.6}}, {1.0, 1.0, 1.0}, gen, c, r, quantized(op));
    return true;
  }
  if (c.case_name != "pair1d") return false;
  PairV<1> v{{0.25}, {1.5}};
  if (!c.velocities.empty()) {
    require(c.velocities.size() == 2, "pair1d needs 2 initial velocity components");
    v = {{c.velocities[0]}, {c.velocities[1]}};
  }
  const Pair1DChain chain{{}, Pair1D{}, c.normal.empty() ? 1.0 : c.normal.at(0)};
  r.initial = r.reference = flat(v);
  (void)chain.op.forward(v, chain.n);  // validates the start
  detail::reversal_chain(chain, v, gen, c, r);
  return true;
}

}  // namespace

detail::Generator detail::make_generator(const VerifyConfig& c) {
  if (c.rng == "clcg4") return rng::make_generator<rng::CLCG4>(0, c.seed, 1);
  if (c.rng == "philox") return rng::make_generator<rng::Philox>(0, c.seed, 1);
  throw InvalidArgument("rng must be 'clcg4' or 'philox', got '" + c.rng + "'");
}

bool detail::run_exact_case(const VerifyConfig& c, VerifyResult& r) {
  Generator gen = make_generator(c);
  return run_exact_case(c, gen, r);
}
bool detail::run_paper_case(const VerifyConfig& c, VerifyResult& r) {
  Generator gen = make_generator(c);
  return run_paper_case(c, gen, r);
}

VerifyResult verify(const VerifyConfig& c) {
  require(c.collisions >= 1, "collisions must be >= 1");
  FixedPoint check_bits(c.bits);  // validates K
  (void)check_bits;
  VerifyResult r;
  r.config = c;
  r.collisions = c.collisions;
  detail::Generator gen = detail::make_generator(c);
  const bool known = std::visit([&](auto& g) { return run_pair_case(c, g, r); }, gen) ||
                     detail::run_exact_case(c, gen, r) || detail::run_paper_case(c, gen, r);
  if (!known) {
    std::string names;
    for (const std::string& name : verify_cases(c.mode)) names += (names.empty() ? "" : ", ") + name;
    throw InvalidArgument("unknown verify case '" + c.case_name + "' for mode " +
                          to_string(c.mode) + " (known: " + names + ")");
  }
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
  if (mode == Mode::exact) out.push_back("pair3d-fast");
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
