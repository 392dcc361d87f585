// Tests of revcol/rng: the known-answer vectors of /work/shared/reference/rng-vectors.md
// (exact), exact reversal of both generators, and the stream policies.
#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "check.hpp"
#include "revcol/error.hpp"
#include "revcol/rng/clcg4.hpp"
#include "revcol/rng/philox.hpp"
#include "revcol/rng/streams.hpp"

using revcol::InvalidArgument;
using revcol::rng::CLCG4;
using revcol::rng::Philox;
using revcol::rng::StreamPolicy;
using revcol::rng::Streams;
namespace detail = revcol::rng::clcg4_detail;

namespace {

// rng-vectors.md, CLCG4 stream 0 and stream 1, first 10 outputs (17 significant digits:
// each literal rounds to exactly the double the specified arithmetic produces).
constexpr std::array<double, 10> kStream0 = {
    0.90587718250437343, 0.47279111812206831, 0.36845768553167524, 0.70033861772271799, 0.61484668235320883,
    0.40032273186718703, 0.57916775835025025, 0.90917692633632563, 0.87682302862674377, 0.035659564059150939};
constexpr std::array<double, 10> kStream1 = {
    0.87071393243675543, 0.46094963871096417, 0.30366232076037525, 0.34418951708168244, 0.44760916359360575,
    0.12758681500302321, 0.65220051874100049, 0.48505806243278493, 0.68128041072774992, 0.48604248436572384};

CLCG4::State times(CLCG4::State s, const CLCG4::State& f, std::uint64_t power = 1) {
  for (int j = 0; j < 4; ++j)
    s[j] = detail::mulmod(s[j], detail::powmod(f[j], power, CLCG4::modulus[j]), CLCG4::modulus[j]);
  return s;
}

std::string hex(const std::array<std::uint32_t, 4>& w) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%08x %08x %08x %08x", w[0], w[1], w[2], w[3]);
  return buf;
}

}  // namespace

// ---------------------------------------------------------------- CLCG4 constants ----

TEST_CASE("clcg4: parameters and jump constants match rng-vectors.md") {
  CHECK((CLCG4::modulus == CLCG4::State{2147483647U, 2147483543U, 2147483423U, 2147483323U}));
  CHECK((CLCG4::multiplier == CLCG4::State{45991U, 207707U, 138556U, 49689U}));
  CHECK((CLCG4::inverse_multiplier == CLCG4::State{1441196816U, 1463744518U, 499766181U, 660421676U}));
  CHECK((CLCG4::default_seed == CLCG4::State{11111111U, 22222222U, 33333333U, 44444444U}));
  // a_j^(2^72) and a_j^(2^41) mod m_j.
  CHECK((CLCG4::stream_jump == CLCG4::State{584425330U, 1351201844U, 1323813018U, 28067816U}));
  CHECK((CLCG4::substream_jump == CLCG4::State{1405571282U, 808907468U, 587771764U, 1036762801U}));
  for (int j = 0; j < 4; ++j) {
    const std::uint64_t m = CLCG4::modulus[j];
    CHECK(detail::mulmod(CLCG4::multiplier[j], CLCG4::inverse_multiplier[j], m) == 1U);
    // Two independent routes to the same powers: 72 squarings vs (a^(2^36))^(2^36) by powmod.
    const std::uint32_t a36 = detail::pow_pow2(CLCG4::multiplier[j], 36, m);
    CHECK(detail::powmod(a36, std::uint64_t{1} << 36, m) == CLCG4::stream_jump[j]);
    CHECK(detail::powmod(CLCG4::multiplier[j], std::uint64_t{1} << 41, m) == CLCG4::substream_jump[j]);
    CHECK(detail::powmod(CLCG4::multiplier[j], m - 1, m) == 1U);  // Fermat: m_j prime
  }
  CHECK(CLCG4::draws_per_next == 1);
}

TEST_CASE("clcg4: pseudo-Mersenne reduction equals % m") {
  std::mt19937_64 rng(12345);
  auto check_x = [](std::uint64_t x) {  // x < 2^49: the forward products
    CHECK(detail::reduce<1>(x) == x % 2147483647U);
    CHECK(detail::reduce<105>(x) == x % 2147483543U);
    CHECK(detail::reduce<225>(x) == x % 2147483423U);
    CHECK(detail::reduce<325>(x) == x % 2147483323U);
  };
  for (int i = 0; i < 200000; ++i) check_x(rng() >> 15);
  // Extremes: the largest products a_j (m_j - 1), multiples of each m_j and their neighbours.
  for (int j = 0; j < 4; ++j) {
    const std::uint64_t m = CLCG4::modulus[j];
    for (std::uint64_t d : {0ULL, 1ULL, 2ULL}) {
      check_x(std::uint64_t{CLCG4::multiplier[j]} * (m - 1) - d);
      check_x(m * 1000 + d);
      check_x(m * 1000 - 1 - d);
      check_x(m * 262143 + d);
    }
  }
  check_x(0);
  check_x((std::uint64_t{1} << 49) - 1);
  // The step itself against the plain definition, from random valid states.
  for (int i = 0; i < 100000; ++i) {
    CLCG4::State s;
    for (int j = 0; j < 4; ++j) s[j] = static_cast<std::uint32_t>(1 + rng() % (CLCG4::modulus[j] - 1));
    CLCG4 g;
    g.set_state(s);
    g.next();
    bool ok = true;
    for (int j = 0; j < 4; ++j)
      ok = ok && g.state()[j] == std::uint64_t{CLCG4::multiplier[j]} * s[j] % CLCG4::modulus[j];
    CHECK(ok);
  }
}

// ----------------------------------------------------------- CLCG4 known answers ----

TEST_CASE("clcg4: stream 0 first 10 outputs and state after 10 (exact)") {
  CLCG4 g;
  CHECK((g.state() == CLCG4::default_seed));
  for (int i = 0; i < 10; ++i) {
    const double u = g.next();
    if (u != kStream0[i]) check::fail(__FILE__, __LINE__, "stream 0 draw " + std::to_string(i + 1));
  }
  CHECK((g.state() == CLCG4::State{2067168963U, 326151508U, 803323983U, 320279480U}));
}

TEST_CASE("clcg4: stream 0 state and draw after 10^6 draws") {
  CLCG4 g(0);
  double u = 0;
  for (int i = 0; i < 1000000; ++i) u = g.next();
  CHECK((g.state() == CLCG4::State{1948270257U, 1257470799U, 48078532U, 96916113U}));
  CHECK(u == 0.2989367613540953);
}

TEST_CASE("clcg4: stream 1 start, first 10 outputs, state after 10 (exact)") {
  CLCG4 g(1);
  CHECK((g.state() == CLCG4::State{2121435502U, 1887977043U, 897632862U, 446466865U}));
  CHECK((g.state() == times(CLCG4::default_seed, CLCG4::stream_jump)));
  for (int i = 0; i < 10; ++i) {
    const double u = g.next();
    if (u != kStream1[i]) check::fail(__FILE__, __LINE__, "stream 1 draw " + std::to_string(i + 1));
  }
  CHECK((g.state() == CLCG4::State{918989740U, 856469078U, 915786109U, 2082021871U}));
}

TEST_CASE("clcg4: stream and substream starts are the specified powers") {
  for (std::uint64_t k : {0ULL, 1ULL, 2ULL, 7ULL, 1000003ULL, (1ULL << 48) + 5}) {
    const CLCG4::State start = times(CLCG4::default_seed, CLCG4::stream_jump, k);
    CHECK((CLCG4(k).state() == start));
    CHECK((CLCG4(k, 0).state() == start));
    CHECK((CLCG4(k, 1).state() == times(start, CLCG4::substream_jump)));
    CHECK((CLCG4(k, 3).state() == times(times(times(start, CLCG4::substream_jump), CLCG4::substream_jump),
                                        CLCG4::substream_jump)));
    CHECK((CLCG4(k + 1).state() == times(CLCG4(k).state(), CLCG4::stream_jump)));
  }
  // 2^31 substreams of 2^41 draws make one stream: substream 2^31 of k is stream k + 1.
  CHECK((CLCG4(5, std::uint64_t{1} << 31).state() == CLCG4(6).state()));
  // A substream start really is 2^41 steps on (checked on the cheap: 2^41 = (2^20)(2^21)).
  CLCG4 g(0);
  CLCG4::State s = g.state();
  s = times(s, CLCG4::multiplier, std::uint64_t{1} << 41);
  CHECK((CLCG4(0, 1).state() == s));
}

// ------------------------------------------------------------------ CLCG4 reversal ----

TEST_CASE("clcg4: next(); prev(); is the identity and prev returns the undone value") {
  CLCG4 g(3, 2);
  const auto s0 = g.state();
  const double u = g.next();
  const auto s1 = g.state();
  CHECK(g.prev() == u);
  CHECK((g.state() == s0));
  CHECK(g.next() == u);
  CHECK((g.state() == s1));
  // prev() from a fresh generator steps into the past: next() then returns the same value.
  CLCG4 h(1);
  const double back = h.prev();
  CHECK(back == CLCG4::output(CLCG4(1).state()));
  CHECK(h.next() == back);
  CHECK((h.state() == CLCG4(1).state()));
}

TEST_CASE("clcg4: 10^7 next then 10^7 prev restores the state, values match exactly") {
  const int n = 10000000;
  CLCG4 g(0);
  const auto start = g.state();
  std::vector<double> drawn(n);
  for (int i = 0; i < n; ++i) drawn[i] = g.next();
  int mismatches = 0;
  for (int i = n - 1; i >= 0; --i) mismatches += g.prev() != drawn[i];
  CHECK(mismatches == 0);
  CHECK((g.state() == start));
  // Outputs are in [0, 1] (the specification's mod-1 arithmetic); sanity of the mean.
  double sum = 0, lo = 1, hi = 0;
  for (double u : drawn) {
    sum += u;
    lo = std::min(lo, u);
    hi = std::max(hi, u);
  }
  CHECK(lo >= 0.0);
  CHECK(hi <= 1.0);
  CHECK_NEAR(sum / n, 0.5, 1e-3);
}

TEST_CASE("clcg4: set_state validates each component, state untouched on error") {
  CLCG4 g(2);
  g.next();
  const auto before = g.state();
  for (int j = 0; j < 4; ++j) {
    for (std::uint32_t bad : {0U, CLCG4::modulus[j], CLCG4::modulus[j] + 1U, 0xffffffffU}) {
      CLCG4::State s = {5, 6, 7, 8};
      s[j] = bad;
      bool named = false;
      try {
        g.set_state(s);
      } catch (const InvalidArgument& e) {
        named = std::string(e.what()).find("s_" + std::to_string(j)) != std::string::npos;
      }
      CHECK(named);
      CHECK((g.state() == before));
    }
    CHECK_THROWS_AS(g.set_state({0, 0, 0, 0}), InvalidArgument);
  }
  CHECK((g.state() == before));
  const CLCG4::State lo = {1, 1, 1, 1};
  const CLCG4::State hi = {CLCG4::modulus[0] - 1, CLCG4::modulus[1] - 1, CLCG4::modulus[2] - 1,
                           CLCG4::modulus[3] - 1};
  g.set_state(lo);
  CHECK((g.state() == lo));
  g.set_state(hi);
  CHECK((g.state() == hi));
  CHECK(CLCG4::valid_state(hi));
  CHECK(!CLCG4::valid_state({1, 0, 1, 1}));
  // set_state then draw: identical to the generator it was copied from.
  CLCG4 a(9), b;
  a.next();
  b.set_state(a.state());
  CHECK(a == b);
  CHECK(a.next() == b.next());
}

// -------------------------------------------------------------------------- Philox ----

// Random123 known answers, also at compile time.
static_assert(revcol::rng::philox4x32_10({0, 0, 0, 0}, {0, 0}) ==
              std::array<std::uint32_t, 4>{0x6627e8d5U, 0xe169c58dU, 0xbc57ac4cU, 0x9b00dbd8U});

TEST_CASE("philox: Random123 known-answer vectors") {
  using revcol::rng::philox4x32_10;
  const auto a = philox4x32_10({0, 0, 0, 0}, {0, 0});
  const auto b = philox4x32_10({0xffffffffU, 0xffffffffU, 0xffffffffU, 0xffffffffU}, {0xffffffffU, 0xffffffffU});
  const auto c = philox4x32_10({0x243f6a88U, 0x85a308d3U, 0x13198a2eU, 0x03707344U}, {0xa4093822U, 0x299f31d0U});
  CHECK(hex(a) == "6627e8d5 e169c58d bc57ac4c 9b00dbd8");
  CHECK(hex(b) == "408f276d 41c83b0e a20bc7c6 6d5451fd");
  CHECK(hex(c) == "d16cfe09 94fdcceb 5001e420 24126ea1");
}

TEST_CASE("philox: draw k is (53 bits of block k + 1/2) 2^-53") {
  const Philox::Key key = {0xdeadbeefU, 42U};
  const Philox p(key);
  for (std::uint64_t k : {0ULL, 1ULL, 2ULL, 0xffffffffULL, 0x100000000ULL, 0x123456789abcdefULL, ~0ULL}) {
    const auto w = revcol::rng::philox4x32_10(
        {static_cast<std::uint32_t>(k), static_cast<std::uint32_t>(k >> 32), 0, 0}, key);
    const std::uint64_t bits = (std::uint64_t{w[0]} << 21) | (w[1] >> 11);
    CHECK(bits < (std::uint64_t{1} << 53));
    CHECK(p.at(k) == (static_cast<double>(bits) + 0.5) * 0x1p-53);
  }
  // Small B: exact midpoints; the top pattern stays below 1.
  CHECK(Philox::to_open_unit(0) == 0x1p-54);
  CHECK(Philox::to_open_unit(1) == 1.5 * 0x1p-53);
  CHECK(Philox::to_open_unit((std::uint64_t{1} << 52) - 1) == 0.5 - 0x1p-54);
  CHECK(Philox::to_open_unit((std::uint64_t{1} << 53) - 1) < 1.0);
  CHECK(Philox::to_open_unit((std::uint64_t{1} << 53) - 1) == 0x1.fffffffffffffp-1);
  // Above 2^52 the +1/2 ties to even: B = 2j - 1 and B = 2j both give 2j 2^-53.
  CHECK(Philox::to_open_unit((std::uint64_t{1} << 53) - 2) == 0x1.ffffffffffffep-1);
  CHECK(Philox::to_open_unit((std::uint64_t{1} << 53) - 3) == 0x1.ffffffffffffep-1);
  CHECK(Philox::to_open_unit(std::uint64_t{1} << 52) == 0.5);
  CHECK(Philox::to_open_unit((std::uint64_t{1} << 52) + 1) == 0.5 + 0x1p-52);
  // The counter's high word matters; different keys give different streams.
  CHECK(p.at(5) != p.at((std::uint64_t{1} << 32) + 5));
  CHECK(Philox({1, 0}).at(0) != Philox({0, 1}).at(0));
  CHECK(Philox::draws_per_next == 1);
}

TEST_CASE("philox: next/prev/counter") {
  Philox p({3, 4}, 10);
  CHECK(p.counter() == 10U);
  CHECK((p.key() == Philox::Key{3, 4}));
  const double u10 = p.at(10);
  CHECK(p.next() == u10);
  CHECK(p.counter() == 11U);
  CHECK(p.prev() == u10);
  CHECK(p.counter() == 10U);
  p.set_counter(0);
  const double u0 = p.next();
  CHECK(u0 == p.at(0));
  CHECK(p.prev() == u0);
  // At draw 0 there is nothing to undo: throws, nothing changes.
  bool message_ok = false;
  try {
    p.prev();
  } catch (const InvalidArgument& e) {
    message_ok = std::string(e.what()).find("cannot step back before draw 0") != std::string::npos;
  }
  CHECK(message_ok);
  CHECK(p.counter() == 0U);
  CHECK(p.next() == u0);
}

TEST_CASE("philox: 10^7 next then 10^7 prev restores the counter, values match exactly") {
  const int n = 10000000;
  Philox p({0x01234567U, 0x89abcdefU}, 12345);
  const Philox start = p;
  std::vector<double> drawn(n);
  for (int i = 0; i < n; ++i) drawn[i] = p.next();
  CHECK(p.counter() == 12345U + n);
  int mismatches = 0;
  for (int i = n - 1; i >= 0; --i) mismatches += p.prev() != drawn[i];
  CHECK(mismatches == 0);
  CHECK(p == start);
  double sum = 0, lo = 1, hi = 0;
  for (double u : drawn) {
    sum += u;
    lo = std::min(lo, u);
    hi = std::max(hi, u);
  }
  CHECK(lo > 0.0);
  CHECK(hi < 1.0);
  CHECK_NEAR(sum / n, 0.5, 1e-3);
}

// ------------------------------------------------------------------------- Streams ----

TEST_CASE("streams: generator families (CLCG4 stream seed*count+i, Philox key {i, seed})") {
  using revcol::rng::make_generator;
  CHECK(make_generator<CLCG4>(2, 3, 5) == CLCG4(17));
  CHECK(make_generator<Philox>(2, 3, 5) == Philox({2, 3}, 0));
  const auto fam = revcol::rng::generator_traits<CLCG4>::family(4, 6);
  REQUIRE(fam.size() == 6U);
  for (std::uint64_t i = 0; i < 6; ++i) CHECK(fam[i] == CLCG4(4 * 6 + i));
  CHECK_THROWS_AS(make_generator<Philox>(0, std::uint64_t{1} << 32, 1), InvalidArgument);
  CHECK_THROWS_AS(make_generator<Philox>(std::uint64_t{1} << 32, 0, 1), InvalidArgument);
  CHECK_THROWS_AS(make_generator<CLCG4>(1, ~0ULL, 2), InvalidArgument);
}

TEST_CASE("streams: single policy draws everything from one generator") {
  Streams<CLCG4> s(StreamPolicy::single, 7, 100, 3);
  CHECK(s.policy() == StreamPolicy::single);
  REQUIRE(s.size() == 1U);
  CHECK(s.generator(0) == CLCG4(7));
  CLCG4 ref(7);
  for (std::size_t id : {0U, 5U, 99U, 3U})
    for (int k = 0; k < 3; ++k) CHECK(s.next(id, k) == ref.next());
  CHECK(s.generator(0) == ref);
  CHECK(s.stream_index(50, 2) == 0U);
  CHECK_THROWS_AS(s.next(0, 3), InvalidArgument);
  CHECK_THROWS_AS(s.next(0, -1), InvalidArgument);
  CHECK(s.generator(0) == ref);
}

TEST_CASE("streams: per_particle uses the stream of the smallest particle id") {
  const std::size_t n = 10;
  Streams<CLCG4> s(StreamPolicy::per_particle, 2, n, 2);
  REQUIRE(s.size() == n);
  std::vector<CLCG4> ref;
  for (std::size_t i = 0; i < n; ++i) ref.emplace_back(2 * n + i);
  for (std::size_t i = 0; i < n; ++i) CHECK(s.generator(i) == ref[i]);
  for (std::size_t id : {3U, 3U, 0U, 9U, 3U}) {
    for (int k = 0; k < 2; ++k) CHECK(s.next(id, k) == ref[id].next());
  }
  for (std::size_t i = 0; i < n; ++i) CHECK(s.generator(i) == ref[i]);  // the others untouched
  CHECK(s.stream_index(4, 1) == 4U);
  CHECK_THROWS_AS(s.next(n, 0), InvalidArgument);
  CHECK_THROWS_AS(s.generator(n), InvalidArgument);
  // Philox: key {id, seed}.
  Streams<Philox> p(StreamPolicy::per_particle, 9, n, 2);
  for (std::size_t i = 0; i < n; ++i) CHECK(p.generator(i) == Philox({static_cast<std::uint32_t>(i), 9}, 0));
  CHECK(p.next(6, 0) == Philox({6, 9}).at(0));
  CHECK(p.next(6, 1) == Philox({6, 9}).at(1));
  CHECK(p.generator(6).counter() == 2U);
  CHECK(p.generator(5).counter() == 0U);
}

TEST_CASE("streams: per_draw takes the k-th number of every collision from stream k") {
  Streams<CLCG4> s(StreamPolicy::per_draw, 5, 1000, 3);
  REQUIRE(s.size() == 3U);
  std::vector<CLCG4> ref = {CLCG4(15), CLCG4(16), CLCG4(17)};
  for (std::size_t id : {0U, 500U, 17U})
    for (int k = 0; k < 3; ++k) CHECK(s.next(id, k) == ref[k].next());
  for (int k = 0; k < 3; ++k) CHECK(s.generator(k) == ref[k]);
  CHECK(s.stream_index(999, 2) == 2U);
  CHECK(s.draws_per_collision() == 3);
  CHECK(s.seed() == 5U);
  Streams<Philox> p(StreamPolicy::per_draw, 1, 4, 2);
  CHECK(p.next(3, 1) == Philox({1, 1}).at(0));
  CHECK(p.generator(0).counter() == 0U);
  // d_n = 0 (1-D two-particle collisions): no generators, nothing to draw.
  Streams<CLCG4> none(StreamPolicy::per_draw, 0, 4, 0);
  CHECK(none.size() == 0U);
  CHECK_THROWS_AS(none.next(0, 0), InvalidArgument);
  CHECK_THROWS_AS(Streams<CLCG4>(StreamPolicy::single, 0, 4, -1), InvalidArgument);
}

template <class Gen>
static void round_trip(StreamPolicy policy) {
  const std::size_t n = 50;
  const int dn = 3;
  Streams<Gen> s(policy, 11, n, dn);
  std::vector<Gen> before;
  for (std::size_t i = 0; i < s.size(); ++i) before.push_back(s.generator(i));
  std::mt19937 pick(99);
  std::vector<std::size_t> ids;
  std::vector<double> drawn;
  for (int c = 0; c < 20000; ++c) {
    const std::size_t id = pick() % n;
    ids.push_back(id);
    for (int k = 0; k < dn; ++k) drawn.push_back(s.next(id, k));
  }
  int mismatches = 0;
  for (int c = static_cast<int>(ids.size()) - 1; c >= 0; --c)
    for (int k = dn - 1; k >= 0; --k) mismatches += s.prev(ids[c], k) != drawn[static_cast<std::size_t>(c) * dn + k];
  CHECK(mismatches == 0);
  for (std::size_t i = 0; i < s.size(); ++i) CHECK(s.generator(i) == before[i]);
}

TEST_CASE("streams: every policy round-trips (CLCG4 and Philox)") {
  for (auto policy : {StreamPolicy::single, StreamPolicy::per_particle, StreamPolicy::per_draw}) {
    round_trip<CLCG4>(policy);
    round_trip<Philox>(policy);
  }
}

TEST_CASE("streams: seeds pick disjoint families; policy names") {
  Streams<CLCG4> a(StreamPolicy::per_draw, 0, 1, 2), b(StreamPolicy::per_draw, 1, 1, 2);
  CHECK(a.generator(0) == CLCG4(0));
  CHECK(a.generator(1) == CLCG4(1));
  CHECK(b.generator(0) == CLCG4(2));
  CHECK(b.generator(1) == CLCG4(3));
  using revcol::rng::stream_policy_from_string;
  using revcol::rng::to_string;
  for (auto p : {StreamPolicy::single, StreamPolicy::per_particle, StreamPolicy::per_draw})
    CHECK(stream_policy_from_string(to_string(p)) == p);
  CHECK(to_string(StreamPolicy::per_draw) == "per_draw");
  CHECK_THROWS_AS(stream_policy_from_string("per-draw"), InvalidArgument);
}

CHECK_MAIN()
