// verify() cases of the exact family: every named case (cases.hpp) through the general
// operator. The paper's illustration with one change for n >= 3: the energy is held, and
// the held momentum follows the sign of the negated velocities (it is their momentum). The
// paper's literal fixed momentum hands the reverse step -cm + h where forward produced
// cm + h: for two particles the exchange symmetry makes those the same bits, for three or
// more it does not.
#include <chrono>

#include "revcol/collide/cases.hpp"
#include "revcol/rng/streams.hpp"
#include "revcol/verify.hpp"

namespace revcol::detail {
namespace {

using Clock = std::chrono::steady_clock;

template <class Gen>
void run(const VerifyConfig& c, const NamedCase& nc, VerifyResult& r) {
  const ExactCollision op = exact_operator(nc, c.law, c.bits);
  const int nd = nc.n * nc.d, k = op.draws();
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
  const Held hp{mp.data(), e}, hn{mn.data(), e};
  op.check_pre(v.data(), &hp);  // a bad start throws here, before anything runs

  Gen gen = rng::make_generator<Gen>(0, c.seed, 1);
  const Gen start = gen;
  r.initial = v;
  r.reference.assign(nd, 0.0);
  op.quantize(v.data(), r.reference.data(), &hp);
  RareLog log;
  std::vector<double> g(std::max(k, 1)), tmp(nd);

  auto t0 = Clock::now();
  for (std::uint64_t t = 0; t < c.collisions; ++t) {
    for (int j = 0; j < k; ++j) g[j] = gen.next();
    op.forward(v.data(), g.data(), tmp.data(), log, t % 2 ? &hn : &hp);
    for (int i = 0; i < nd; ++i) v[i] = -tmp[i];  // reverse the velocities: the next collision
  }
  r.forward_s = std::chrono::duration<double>(Clock::now() - t0).count();
  r.log_bytes = log.bytes();
  r.log_entries = log.size();
  r.random_numbers_drawn = c.collisions * k;

  t0 = Clock::now();
  std::uint64_t undone = 0;
  try {
    for (std::uint64_t t = c.collisions; t-- > 0;) {
      for (int i = 0; i < nd; ++i) v[i] = -v[i];
      for (int j = k - 1; j >= 0; --j) { g[j] = gen.prev(); ++undone; }
      op.reverse(v.data(), g.data(), tmp.data(), log, t % 2 ? &hn : &hp);
      v = tmp;
    }
  } catch (const InvalidArgument& e) {
    r.error = std::string("reverse step failed: ") + e.what();
  }
  r.reverse_s = std::chrono::duration<double>(Clock::now() - t0).count();
  r.random_numbers_undone = undone;
  r.final_velocities = v;
  r.rng_restored = gen == start;
  r.passed = log.size() == 0;
}

}  // namespace

bool run_exact_case(const VerifyConfig& c, VerifyResult& r) {
  if (c.mode != Mode::exact) return false;
  bool known = false;
  for (const NamedCase& nc : named_cases()) known = known || nc.name == c.case_name;
  if (!known) return false;
  const NamedCase nc = named_case(c.case_name);
  if (c.rng == "philox") run<rng::Philox>(c, nc, r);
  else run<rng::CLCG4>(c, nc, r);
  return true;
}

std::vector<std::string> exact_case_names() {
  std::vector<std::string> out;
  for (const NamedCase& nc : named_cases()) out.push_back(nc.name);
  return out;
}

}  // namespace revcol::detail
