// verify() cases of the exact family: every named case (cases.hpp) through the general
// operator. The paper's illustration with one change for n >= 3: the energy is held, and
// the held momentum follows the sign of the negated velocities (it is their momentum). The
// paper's literal fixed momentum hands the reverse step -cm + h where forward produced
// cm + h: for two particles the exchange symmetry makes those the same bits, for three or
// more it does not.
#include <algorithm>
#include <variant>

#include "revcol/collide/cases.hpp"
#include "revcol/studies/verify.hpp"

namespace revcol::detail {
namespace {

// ExactCollision in the chain: flat velocities, the held momentum's sign following the
// negation (collision t holds +M when t is even, -M when odd).
struct ExactChain {
  using State = std::vector<double>;
  static constexpr bool stops_early = false;
  const ExactCollision& op;
  Held hp, hn;
  mutable std::vector<double> tmp;  // the operator writes out of place
  std::size_t draws() const { return static_cast<std::size_t>(op.draws()); }
  const Held* held(std::uint64_t t) const { return t % 2 ? &hn : &hp; }
  void forward(State& v, const double* g, RareLog& log, std::uint64_t t) const {
    op.forward(v.data(), g, tmp.data(), log, held(t));
    v.swap(tmp);
  }
  void reverse(State& v, const double* g, RareLog& log, std::uint64_t t) const {
    op.reverse(v.data(), g, tmp.data(), log, held(t));
    v.swap(tmp);
  }
  void negate(State& v) const {
    for (double& x : v) x = -x;
  }
  std::vector<double> flat(const State& v) const { return v; }
};

template <class Gen>
void run(const VerifyConfig& c, const NamedCase& nc, Gen& gen, VerifyResult& r) {
  const ExactCollision op = exact_operator(nc, c.law, c.bits);
  const int nd = nc.n * nc.d;
  std::vector<double> v;
  if (!c.velocities.empty()) {
    require(static_cast<int>(c.velocities.size()) == nd, [&] {
      return nc.name + " needs " + std::to_string(nd) + " initial velocity components";
    });
    v = c.velocities;
  } else if (nc.name.rfind("cradle", 0) == 0) {
    v.assign(nd, 0.0);  // particle 0 moves towards the resting others
    v[0] = 1.0;
    if (nc.d > 1) v[1] = 0.25;
  } else {
    v = approaching_state(op, 1);
  }
  std::vector<double> mp(nc.d, 0.0), mn(nc.d);
  double e = 0.0;
  for (int i = 0; i < nc.n; ++i)
    for (int a = 0; a < nc.d; ++a) {
      mp[a] += v[i * nc.d + a];
      e += v[i * nc.d + a] * v[i * nc.d + a];
    }
  for (int a = 0; a < nc.d; ++a) mn[a] = -mp[a];
  const ExactChain chain{op, Held{mp.data(), e}, Held{mn.data(), e}, std::vector<double>(nd)};
  op.check_pre(v.data(), &chain.hp);  // a bad start throws here, before anything runs
  r.initial = v;
  r.reference.assign(nd, 0.0);
  op.quantize(v.data(), r.reference.data(), &chain.hp);
  reversal_chain(chain, v, gen, c, r);
}

}  // namespace

bool run_exact_case(const VerifyConfig& c, Generator& gen, VerifyResult& r) {
  if (c.mode != Mode::exact) return false;
  bool known = false;
  for (const NamedCase& nc : named_cases()) known = known || nc.name == c.case_name;
  if (!known) return false;
  const NamedCase nc = named_case(c.case_name);
  std::visit([&](auto& g) { run(c, nc, g, r); }, gen);
  return true;
}

std::vector<std::string> exact_case_names() {
  std::vector<std::string> out;
  for (const NamedCase& nc : named_cases()) out.push_back(nc.name);
  return out;
}

}  // namespace revcol::detail
