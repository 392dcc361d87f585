// randomness.hpp: the word stream. Under the operator's own law each chart coordinate of the
// post state is uniform, so the words pass a Kolmogorov-Smirnov test (1e5 words, every
// case, both laws); mapped through the other law's CDF they fail it (the test can fail).
// The exact chain is the torus shift itself (word_t - word_(t-1) = floor(G_t 2^32) up to
// one unit); raw words are the generator's draws; the bad controls have their defects; a
// stream is deterministic and resumable; bad configurations throw. The engine's collisions
// in a gas (gas2d, gas3d) pass KS through their law's CDF and fail through the other's;
// a Newton's cradle starts from rest, so its words are not triple1d's.
#include "revcol/studies/randomness.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "check.hpp"
#include "revcol/collide/cases.hpp"
#include "revcol/error.hpp"
#include "revcol/rng/philox.hpp"
#include "revcol/rng/streams.hpp"

using namespace revcol;
using randomness::StreamConfig;
using randomness::WordStream;

namespace {

// Kolmogorov-Smirnov distance of words k, k + step, ... from the uniform law on [0, 2^32).
double ks_distance(const std::vector<std::uint32_t>& w, std::size_t k, std::size_t step) {
  std::vector<double> u;
  for (std::size_t i = k; i < w.size(); i += step) u.push_back((w[i] + 0.5) / 4294967296.0);
  std::sort(u.begin(), u.end());
  const double n = static_cast<double>(u.size());
  double d = 0.0;
  for (std::size_t i = 0; i < u.size(); ++i)
    d = std::max({d, (i + 1) / n - u[i], u[i] - i / n});
  return d;
}
// The largest KS distance over the coordinates, scaled by sqrt(n): the KS statistic K.
double worst_ks(const std::vector<std::uint32_t>& w, int width) {
  double worst = 0.0;
  for (int k = 0; k < width; ++k) {
    const double n = static_cast<double>(w.size() / width);
    worst = std::max(worst, ks_distance(w, k, width) * std::sqrt(n));
  }
  return worst;
}
// P(K > 1.95) = 1e-3 for one coordinate; K > 4 has probability 3e-14.
constexpr double kPass = 1.95, kFail = 4.0;

std::vector<std::uint32_t> take(const StreamConfig& c, std::size_t n) {
  WordStream s(c);
  std::vector<std::uint32_t> w(n);
  s.fill(w.data(), n);
  return w;
}

StreamConfig config(const std::string& name, Law law, Law cdf, const std::string& rng = "philox") {
  StreamConfig c;
  c.case_name = name;
  c.law = law;
  c.cdf_law = cdf;
  c.rng = rng;
  c.seed = 3;
  return c;
}

bool is_gas(const std::string& name) { return name.rfind("gas", 0) == 0; }

}  // namespace

TEST_CASE("exact mode: every case, both laws: the words are uniform (KS, 1e5 words; CLCG4 too for the paper's cases)") {
  for (const std::string& name : randomness::stream_cases(Mode::exact)) {
    if (name == "raw" || is_gas(name)) continue;  // the gas: its own test below
    const bool paper_case = name == "pair2d" || name == "triple1d" || name == "triple2d-c1";
    for (Law law : {Law::flux, Law::uniform})
      for (const char* rng : {"philox", "clcg4"}) {
        if (!paper_case && std::string(rng) == "clcg4") continue;
        const StreamConfig c = config(name, law, law, rng);
        const int width = WordStream(c).width();
        const double k = worst_ks(take(c, 100000 - 100000 % width), width);
        if (!(k < kPass)) std::fprintf(stderr, "%s %s %s: K = %g\n", name.c_str(), to_string(law), rng, k);
        CHECK(k < kPass);
      }
  }
}

TEST_CASE("exact mode: mapped through the other law's CDF the words fail KS (every case with f >= 1)") {
  // With f = 0 free dimensions (triple1d, cradle1d, chain4-1d) the flux weight cos(eta) has
  // no eta to act on: the two laws are one, and so are their charts (checked here too).
  for (const std::string& name : randomness::stream_cases(Mode::exact)) {
    if (name == "raw" || is_gas(name)) continue;
    if (exact_operator(named_case(name)).free_dim() == 0) {
      const StreamConfig c = config(name, Law::flux, Law::uniform);
      CHECK(take(c, 1000) == take(config(name, Law::uniform, Law::uniform), 1000));
      continue;
    }
    for (Law law : {Law::flux, Law::uniform}) {
      const Law other = law == Law::flux ? Law::uniform : Law::flux;
      const StreamConfig c = config(name, law, other);
      const int width = WordStream(c).width();
      const double k = worst_ks(take(c, 100000 - 100000 % width), width);
      if (!(k > kFail)) std::fprintf(stderr, "%s %s read as %s: K = %g\n", name.c_str(), to_string(law), to_string(other), k);
      CHECK(k > kFail);
    }
  }
}

TEST_CASE("exact pair2d: each word is the last plus the draw (the torus shift, top 32 bits)") {
  for (Law law : {Law::flux, Law::uniform}) {
    const StreamConfig c = config("pair2d", law, law);
    const std::vector<std::uint32_t> w = take(c, 10000);
    rng::Philox g = rng::make_generator<rng::Philox>(0, c.seed, 1);
    (void)g.next();  // the first word's draw
    int bad = 0;
    for (std::size_t t = 1; t < w.size(); ++t) {
      const std::uint32_t step = w[t] - w[t - 1];                 // mod 2^32
      const auto draw = static_cast<std::uint32_t>(std::floor(g.next() * 4294967296.0));
      const std::uint32_t diff = step - draw;                     // 0 or 1 (carry of the low 8 bits)
      bad += (diff == 0 || diff == 1) ? 0 : 1;
    }
    CHECK(bad == 0);
  }
}

TEST_CASE("raw words are floor(G 2^32) of the generator; the stream is resumable and deterministic") {
  const StreamConfig c = config("raw", Law::flux, Law::flux);
  const std::vector<std::uint32_t> w = take(c, 1000);
  rng::Philox g = rng::make_generator<rng::Philox>(0, c.seed, 1);
  for (std::uint32_t x : w) CHECK(x == static_cast<std::uint32_t>(std::floor(g.next() * 4294967296.0)));
  for (const char* name : {"raw", "pair2d", "triple2d-c1"}) {
    const StreamConfig ci = config(name, Law::flux, Law::flux);
    const std::vector<std::uint32_t> whole = take(ci, 999);
    WordStream s(ci);
    std::vector<std::uint32_t> parts(999);
    s.fill(parts.data(), 1);
    s.fill(parts.data() + 1, 500);
    s.fill(parts.data() + 501, 498);
    CHECK(parts == whole);
    CHECK(s.words() == 999);
    CHECK(s.collisions() == static_cast<std::uint64_t>((999 + s.width() - 1) / s.width()));
  }
}

TEST_CASE("bad controls: RANDU's triples obey x2 = 6 x1 - 9 x0; repeat100 repeats every 100th draw") {
  const std::vector<std::uint32_t> r = take(config("raw", Law::flux, Law::flux, "randu"), 3000);
  int bad = 0;
  for (std::size_t k = 2; k < r.size(); ++k) {
    const std::int64_t x0 = r[k - 2] >> 1, x1 = r[k - 1] >> 1, x2 = r[k] >> 1;
    bad += ((x2 - 6 * x1 + 9 * x0) % (std::int64_t{1} << 31) == 0) ? 0 : 1;
  }
  CHECK(bad == 0);
  const std::vector<std::uint32_t> p = take(config("raw", Law::flux, Law::flux, "philox-repeat100"), 1000);
  for (std::size_t k = 1; k < p.size(); ++k) CHECK((p[k] == p[k - 1]) == ((k + 1) % 100 == 0));
}

TEST_CASE("paper mode: pair2d is uniform on the half circle; every paper case streams") {
  StreamConfig c = config("pair2d", Law::uniform, Law::uniform);
  c.mode = Mode::paper;
  WordStream s(c);
  std::vector<std::uint32_t> w(100000);
  s.fill(w.data(), w.size());
  CHECK(worst_ks(w, 1) < kPass);
  CHECK(s.restarts() == 0);
  for (const std::string& name : randomness::stream_cases(Mode::paper)) {
    StreamConfig cp = config(name, Law::uniform, Law::uniform);
    cp.mode = Mode::paper;
    WordStream sp(cp);
    std::vector<std::uint32_t> wp(300);
    sp.fill(wp.data(), wp.size());
    CHECK(sp.words() == 300);
  }
}

TEST_CASE("the engine's collisions in a gas: uniform through the law's CDF, not through the other's (KS, 1e5 words)") {
  for (const char* name : {"gas2d", "gas3d"})
    for (Law law : {Law::flux, Law::uniform}) {
      const Law other = law == Law::flux ? Law::uniform : Law::flux;
      const char* rng = law == Law::flux ? "philox" : "clcg4";
      StreamConfig c = config(name, law, law, rng);
      c.gas_particles = 400;
      WordStream s(c);
      CHECK(s.width() == (name[3] == '2' ? 1 : 2));
      std::vector<std::uint32_t> w(100000);
      s.fill(w.data(), w.size());
      const double k = worst_ks(w, s.width());
      if (!(k < kPass)) std::fprintf(stderr, "%s %s %s: K = %g\n", name, to_string(law), rng, k);
      CHECK(k < kPass);
      CHECK(s.collisions() == w.size() / s.width());
      c.cdf_law = other;  // the same collisions read through the other law's CDF
      const double kw = worst_ks(take(c, w.size()), s.width());
      if (!(kw > kFail)) std::fprintf(stderr, "%s %s read as %s: K = %g\n", name, to_string(law), to_string(other), kw);
      CHECK(kw > kFail);
    }
}

TEST_CASE("the gas stream is deterministic and resumable; the seed and the law change it") {
  StreamConfig c = config("gas3d", Law::flux, Law::flux);
  c.gas_particles = 200;
  const std::vector<std::uint32_t> whole = take(c, 99999);
  WordStream s(c);
  std::vector<std::uint32_t> parts(99999);
  s.fill(parts.data(), 1);
  s.fill(parts.data() + 1, 70000);  // across an observation chunk (2^16 collisions)
  s.fill(parts.data() + 70001, 29998);
  CHECK(parts == whole);
  CHECK(s.words() == 99999);
  StreamConfig c2 = c;
  c2.seed = 4;
  CHECK(take(c2, 1000) != take(c, 1000));
  c2 = c;
  c2.law = Law::uniform;
  CHECK(take(c2, 1000) != take(c, 1000));
}

TEST_CASE("cradles start from rest: cradle1d's words are not triple1d's (same geometry)") {
  for (Law law : {Law::flux, Law::uniform}) {
    const std::vector<std::uint32_t> cradle = take(config("cradle1d", law, law), 1000);
    const std::vector<std::uint32_t> triple = take(config("triple1d", law, law), 1000);
    int same = 0;
    for (std::size_t k = 0; k < cradle.size(); ++k) same += cradle[k] == triple[k] ? 1 : 0;
    CHECK(same < 10);
  }
}

TEST_CASE("bad configurations throw InvalidArgument") {
  auto throws = [](StreamConfig c) {
    try {
      WordStream s(c);
    } catch (const InvalidArgument&) {
      return true;
    }
    return false;
  };
  StreamConfig c;
  c.case_name = "nope";
  CHECK(throws(c));
  c.case_name = "pair1d";  // no free parameter
  CHECK(throws(c));
  c.case_name = "pair2d";
  c.rng = "mt19937";
  CHECK(throws(c));
  c.rng = "philox";
  c.mode = Mode::specular;
  CHECK(throws(c));
  c.mode = Mode::paper;
  c.case_name = "chain4-2d";  // no paper-mode operator
  CHECK(throws(c));
  c.mode = Mode::exact;
  c.bits = 60;
  CHECK(throws(c));
  c.bits = 40;
  StreamConfig g = c;  // the gas
  g.case_name = "gas2d";
  g.gas_particles = 100;
  g.rng = "randu";  // the engine's generators only
  CHECK(throws(g));
  g.rng = "philox";
  g.mode = Mode::paper;
  CHECK(throws(g));
  g.mode = Mode::exact;
  g.seed = std::uint64_t{1} << 32;
  CHECK(throws(g));
  g.seed = 1;
  g.gas_particles = 1;
  CHECK(throws(g));
  g.gas_particles = 100;
  g.gas_fraction = 0.95;  // above the densest packing
  CHECK(throws(g));
  g.gas_fraction = 0.2;
  g.gas_warmup = -1.0;
  CHECK(throws(g));
  WordStream s(c);
  bool threw = false;
  try {
    s.write("/nonexistent-dir/words.bin", 10);
  } catch (const InvalidArgument&) {
    threw = true;
  }
  CHECK(threw);
  CHECK(randomness::to_word(-0.1) == 0u);
  CHECK(randomness::to_word(1.0) == 4294967295u);
  CHECK(randomness::to_word(0.5) == 2147483648u);
}

int main() { return check::run_all(); }
