// FixedPoint: K-bit cells of [0,1), decoded at their centres, and the exact torus shift.
// Known answers at the edges (cells 0 and 2^K - 1, c = 0 and c = 1), centres re-encoding
// to their own cell, and the shift wrapping both ways, for the smallest, default and
// largest K.
#include "revcol/fixed_point.hpp"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "check.hpp"
#include "revcol/trig.hpp"

using namespace revcol;

namespace {
const int kBits[] = {FixedPoint::min_bits, 20, FixedPoint::default_bits, FixedPoint::max_bits};
}

TEST_CASE("K outside [min_bits, max_bits] is refused") {
  CHECK_THROWS_AS(FixedPoint(FixedPoint::min_bits - 1), InvalidArgument);
  CHECK_THROWS_AS(FixedPoint(FixedPoint::max_bits + 1), InvalidArgument);
  CHECK_THROWS_AS(FixedPoint(0), InvalidArgument);
  CHECK(FixedPoint(FixedPoint::min_bits).bits() == FixedPoint::min_bits);
  CHECK(FixedPoint(FixedPoint::max_bits).bits() == FixedPoint::max_bits);
  CHECK(FixedPoint().bits() == 40);
}

TEST_CASE("encode at the edges: cell 0, cell 2^K - 1, clamping and NaN") {
  for (int K : kBits) {
    const FixedPoint fp(K);
    const std::uint64_t last = (std::uint64_t{1} << K) - 1;
    const double cell = std::ldexp(1.0, -K);
    CHECK(fp.cells() == std::ldexp(1.0, K));
    CHECK(fp.encode(0.0) == 0);
    CHECK(fp.encode(-0.0) == 0);
    CHECK(fp.encode(-1e-300) == 0);                      // below 0 clamps to cell 0
    CHECK(fp.encode(std::numeric_limits<double>::quiet_NaN()) == 0);
    CHECK(fp.encode(cell) == 1);                         // the first edge belongs to cell 1
    CHECK(fp.encode(std::nextafter(cell, 0.0)) == 0);    // just below it: cell 0
    CHECK(fp.encode(1.0) == last);                       // c = 1 (rounding) clamps to the last cell
    CHECK(fp.encode(std::nextafter(1.0, 0.0)) == last);
    CHECK(fp.encode(1.0 - cell) == last);                // the last edge opens the last cell
    CHECK(fp.encode(std::nextafter(1.0 - cell, 0.0)) == last - 1);
    CHECK(fp.encode(2.0) == last);
    // far outside [0, 1]: the branch-free clamp (encode's [0, 2^62] before the conversion)
    CHECK(fp.encode(1e300) == last);
    CHECK(fp.encode(std::numeric_limits<double>::infinity()) == last);
    CHECK(fp.encode(-std::numeric_limits<double>::infinity()) == 0);
    CHECK(fp.encode(-1e300) == 0);
    CHECK(fp.encode(std::ldexp(1.0, 62 - K)) == last);  // s = 2^62 exactly: the clamp's edge
  }
}

TEST_CASE("decode gives exact cell centres that re-encode to their cell") {
  for (int K : kBits) {
    const FixedPoint fp(K);
    const std::uint64_t last = (std::uint64_t{1} << K) - 1;
    const double half = std::ldexp(1.0, -K - 1);
    CHECK(fp.decode(0) == half);                  // (0 + 1/2) 2^-K, exact
    CHECK(fp.decode(last) == 1.0 - half);         // (2^K - 1/2) 2^-K, exact for K <= 52
    CHECK(fp.decode(last) < 1.0);
    CHECK(fp.offset_in_cell(fp.decode(0)) == 0.5);
    CHECK(fp.offset_in_cell(fp.decode(last)) == 0.5);
    std::mt19937_64 rng(static_cast<unsigned>(K));
    for (int t = 0; t < 10000; ++t) {
      const std::uint64_t u = rng() & last;
      const double c = fp.decode(u);
      CHECK(fp.encode(c) == u);
      CHECK(fp.offset_in_cell(c) == 0.5);
      CHECK(c > 0.0);
      CHECK(c < 1.0);
    }
    for (std::uint64_t u : {std::uint64_t{0}, std::uint64_t{1}, last - 1, last})
      CHECK(fp.encode(fp.decode(u)) == u);
  }
}

TEST_CASE("the torus shift wraps at 2^K and is undone exactly by sub") {
  for (int K : kBits) {
    const FixedPoint fp(K);
    const std::uint64_t last = (std::uint64_t{1} << K) - 1;
    CHECK(fp.add(last, 1) == 0);
    CHECK(fp.add(last, last) == last - 1);
    CHECK(fp.sub(0, 1) == last);
    CHECK(fp.sub(0, last) == 1);
    CHECK(fp.add(0, 0) == 0);
    CHECK(fp.sub(last, last) == 0);
    // a shift of G = 1/2 moves every cell by half the torus
    const std::uint64_t halfway = fp.shift(0.5);
    CHECK(halfway == (std::uint64_t{1} << (K - 1)));
    CHECK(fp.add(halfway, halfway) == 0);
    // G = 1 (CLCG4 can return it) is the last cell, one short of a full turn
    CHECK(fp.shift(1.0) == last);
    CHECK(fp.add(5, fp.shift(1.0)) == 4);
    std::mt19937_64 rng(static_cast<unsigned>(1000 + K));
    std::uniform_real_distribution<double> unif(0.0, 1.0);
    for (int t = 0; t < 10000; ++t) {
      const std::uint64_t u = rng() & last;
      const std::uint64_t g = fp.shift(unif(rng));
      const std::uint64_t v = fp.add(u, g);
      CHECK(v <= last);
      CHECK(fp.sub(v, g) == u);
      CHECK(fp.add(fp.sub(u, g), g) == u);
      CHECK(v == (u + g) % (last + 1));
    }
  }
}

CHECK_MAIN()

namespace {
bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }
// cells 0, 1, 2, around the quarters and halves, 2^K - 2, 2^K - 1, and random ones
std::vector<std::uint64_t> test_cells(int K, std::mt19937_64& rng) {
  const std::uint64_t M = (std::uint64_t{1} << K) - 1, Q = (M + 1) / 4, H = (M + 1) / 2;
  std::vector<std::uint64_t> u = {0, 1, 2, Q - 1, Q, Q + 1, H - 1, H, H + 1, 3 * Q - 1, 3 * Q, 3 * Q + 1,
                                  M / 8, M / 8 + 1, 3 * (M / 8) + 1, M - 1, M};
  for (int k = 0; k < 20000; ++k) u.push_back(rng() & M);
  return u;
}
}  // namespace

// The operators decode straight from the integers where that is shorter; each shortcut must
// give the bits of the plain decode-then-compute form, at every K.
TEST_CASE("shortcuts give the bits of the plain forms: encode_half, shift, centered, roots, quarters") {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> Y(-1.0, 1.0);
  int checked = 0;
  for (int K = FixedPoint::min_bits; K <= FixedPoint::max_bits; ++K) {
    const FixedPoint fp(K);
    for (const std::uint64_t U : test_cells(K, rng)) {
      const double c = fp.decode(U);
      // 2 c - 1 and the roots sqrt(c), sqrt(1 - c)
      CHECK(same_bits(static_cast<double>(fp.centered(U)) * fp.inv_cells(), 2.0 * c - 1.0));
      double s, co;
      fp.roots(U, s, co);
      CHECK(same_bits(s, std::sqrt(c)));
      CHECK(same_bits(co, std::sqrt(1.0 - c)));
      // the quarter-turn reduction: exact, and sincos_turns' bits
      const FixedPoint::Quarters qr = fp.quarters(U);
      CHECK(qr.q >= 0 && qr.q <= 4 && std::fabs(qr.r) <= 0.125);
      CHECK(0.25 * static_cast<double>(qr.q) + qr.r == c);
      double s1, c1, s2, c2;
      trig::sincos_turns(c, s1, c1);
      trig::sincos_quarters(qr.q, qr.r, s2, c2);
      CHECK(same_bits(s1, s2) && same_bits(c1, c2));
      ++checked;
    }
    // encode_half(y) = encode(0.5 + 0.5 y): random y, the ends, signed zeros, tiny, beyond, NaN
    std::vector<double> ys = {-1.0, 1.0, 0.0, -0.0, 1e-300, -1e-300, 0x1.0p-60, -0x1.0p-60,
                              std::nextafter(-1.0, 0.0), std::nextafter(1.0, 0.0), -1.5, 1.5,
                              std::numeric_limits<double>::quiet_NaN()};
    for (int k = 0; k < 20000; ++k) ys.push_back(Y(rng));
    for (int k = 0; k < 200; ++k) {  // on and beside cell edges: (1 + y) / 2 = U 2^-K
      const double y = 2.0 * std::ldexp(static_cast<double>(rng() & ((std::uint64_t{1} << K) - 1)), -K) - 1.0;
      ys.insert(ys.end(), {y, std::nextafter(y, -2.0), std::nextafter(y, 2.0)});
    }
    for (const double y : ys) CHECK(fp.encode_half(y) == fp.encode(0.5 + 0.5 * y));
    // shift(g) = encode(g) for every g in [0, 1]: the ends, next to them, cell edges, random
    std::vector<double> gs = {0.0, 1.0, std::nextafter(1.0, 0.0), 0x1.0p-1074, 0x1.0p-60, 0.5};
    for (int k = 0; k < 20000; ++k) gs.push_back(0.5 * (Y(rng) + 1.0));
    for (int k = 0; k < 200; ++k) {
      const double g = std::ldexp(static_cast<double>(rng() & ((std::uint64_t{1} << K) - 1)), -K);
      gs.insert(gs.end(), {g, std::nextafter(g, 0.0), std::nextafter(g, 1.0)});
    }
    for (const double g : gs) CHECK(fp.shift(g) == fp.encode(g));
  }
  std::printf("  %d cells over K = %d..%d\n", checked, FixedPoint::min_bits, FixedPoint::max_bits);
}
