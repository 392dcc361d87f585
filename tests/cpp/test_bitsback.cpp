// Tests of the bits-back integer (revcol/lattice/bitsback.hpp) and the exact integer helpers
// (revcol/lattice/int128.hpp): known answers from the Python prototype (tests/data/lattice,
// made by tests/reference/make_lattice_vectors.py), exact inverses, edges, bad input.
#include <cstdint>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "check.hpp"
#include "revcol/error.hpp"
#include "revcol/lattice/bitsback.hpp"
#include "revcol/lattice/int128.hpp"

using namespace revcol::lattice;
using revcol::InvalidArgument;

namespace {

std::string data_path(const char* name) {
  std::string here = __FILE__;
  return here.substr(0, here.find_last_of('/')) + "/../data/lattice/" + name;
}

// The data file's lines, split into words (comment lines dropped).
std::vector<std::vector<std::string>> read_rows(const char* name) {
  std::ifstream in(data_path(name));
  std::vector<std::vector<std::string>> rows;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ss(line);
    std::vector<std::string> words;
    for (std::string w; ss >> w;) words.push_back(w);
    rows.push_back(words);
  }
  return rows;
}

u128 parse_hex128(const std::string& s) {
  u128 v = 0;
  for (std::size_t i = 2; i < s.size(); ++i) {
    const char c = s[i];
    v = v * 16 + static_cast<unsigned>(c <= '9' ? c - '0' : c - 'a' + 10);
  }
  return v;
}

i128 parse_dec(const std::string& s) {
  const bool neg = s[0] == '-';
  i128 v = 0;
  for (std::size_t i = neg ? 1 : 0; i < s.size(); ++i) v = v * 10 + (s[i] - '0');
  return neg ? -v : v;
}

std::uint64_t u(const std::string& s) { return static_cast<std::uint64_t>(parse_dec(s)); }

BitsBack random_x(std::mt19937_64& rng, int bits) {
  std::vector<std::uint64_t> w((bits + 63) / 64);
  for (auto& x : w) x = rng();
  if (bits % 64) w.back() &= (1ULL << (bits % 64)) - 1;
  return BitsBack(w);
}

}  // namespace

TEST_CASE("isqrt: known answers of Python's math.isqrt") {
  const auto rows = read_rows("isqrt.txt");
  REQUIRE(rows.size() >= 150);
  for (const auto& r : rows) CHECK(isqrt(parse_hex128(r[0])) == static_cast<u64>(parse_hex128(r[1])));
}

TEST_CASE("isqrt: edges (0, perfect squares, k^2 - 1, near 2^127 and 2^128)") {
  const u128 top = ~static_cast<u128>(0);
  CHECK(isqrt(0) == 0);
  CHECK(isqrt(1) == 1);
  CHECK(isqrt(3) == 1);
  CHECK(isqrt(4) == 2);
  CHECK(isqrt(top) == ~0ULL);
  CHECK(isqrt(static_cast<u128>(1) << 127) == 13043817825332782212ULL);  // floor(2^63.5)
  CHECK(isqrt((static_cast<u128>(1) << 127) - 1) == 13043817825332782212ULL);
  std::mt19937_64 rng(7);
  for (int i = 0; i < 20000; ++i) {
    const u64 k = (i < 64) ? (~0ULL >> i) : (rng() >> (rng() % 64));
    if (k == 0) continue;
    const u128 sq = static_cast<u128>(k) * k;
    CHECK(isqrt(sq) == k);
    CHECK(isqrt(sq - 1) == k - 1);
    if (k < ~0ULL) CHECK(isqrt(sq + 2 * static_cast<u128>(k)) == k);  // (k+1)^2 - 1
    CHECK(isqrt_ceil(sq) == k);
    CHECK(isqrt_ceil(sq + 1) == k + 1);
  }
  CHECK(isqrt_ceil(0) == 0);
}

TEST_CASE("to_double: the bits of static_cast<double> for every word pattern") {
  // one word zero (the fast paths: sigma^2 = 2^(2S) for S = 20..60), both words set (the library
  // call), halfway cases that round to even, and a run of random values
  std::vector<u128> xs = {0, 1, ~u128{0}, u128{1} << 64, u128{1} << 127, (u128{1} << 64) - 1};
  for (int s = 20; s <= 60; ++s) xs.push_back(u128{1} << (2 * s));
  for (int k = 0; k < 64; ++k) {
    xs.push_back((u128{1} << (64 + k)) | (u128{1} << k));    // both words set
    xs.push_back((u128{(1ULL << 53) + 1}) << (k + 11));      // a halfway case above 2^64
    xs.push_back(u128{(1ULL << 53) + 1} << 11 | 1);          // just above halfway, one word
  }
  std::uint64_t z = 0x9e3779b97f4a7c15ULL;
  auto next = [&z] {  // splitmix64
    std::uint64_t x = (z += 0x9e3779b97f4a7c15ULL);
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
    return x ^ (x >> 31);
  };
  for (int k = 0; k < 20000; ++k) {
    const u64 hi = next(), lo = next();
    const int shape = k % 4;  // both words, high only, low only, high with few bits
    xs.push_back(shape == 0 ? (u128{hi} << 64 | lo) : shape == 1 ? u128{hi} << 64 : shape == 2 ? u128{lo} : u128{hi >> (k % 64)} << 64);
  }
  int bad = 0;
  for (u128 x : xs) bad += to_double(x) != static_cast<double>(x);
  CHECK(bad == 0);
}

TEST_CASE("floor_div, floor_mod, >>: Python's semantics on negatives") {
  const auto rows = read_rows("floor.txt");
  REQUIRE(rows.size() >= 300);
  int n = 0;
  for (const auto& r : rows) {
    if (r[0] == "div") {
      const i64 a = static_cast<i64>(parse_dec(r[1])), b = static_cast<i64>(parse_dec(r[2]));
      CHECK(floor_div(a, b) == static_cast<i64>(parse_dec(r[3])));
      CHECK(floor_mod(a, b) == static_cast<i64>(parse_dec(r[4])));
      ++n;
    } else {
      CHECK(floor_shift(parse_dec(r[1]), static_cast<int>(parse_dec(r[2]))) == parse_dec(r[3]));
    }
  }
  CHECK(n > 100);
  CHECK(floor_div(-7, 2) == -4);
  CHECK(floor_mod(-7, 2) == 1);
  CHECK(floor_shift(-7, 1) == -4);
}

TEST_CASE("BitsBack: known answers of the prototype's push / pop / shift steps") {
  const auto rows = read_rows("bitsback.txt");
  REQUIRE(rows.size() >= 700);
  BitsBack X;
  int steps = 0;
  for (const auto& r : rows) {
    const std::string& op = r[0];
    if (op == "X") {
      X = BitsBack::from_hex(r[1]);
      CHECK(X.to_hex() == r[1]);
      continue;
    }
    if (op == "U") X.push_uniform(u(r[1]), u(r[2]));
    if (op == "u") CHECK(X.pop_uniform(u(r[1])) == u(r[2]));
    if (op == "R") X.push_rans(u(r[1]), u(r[2]));
    if (op == "r") X.pop_rans(u(r[1]), u(r[2]));
    if (op == "A") X.add_low48(u(r[1]));
    if (op == "S") X.sub_low48(u(r[1]));
    CHECK(X.to_hex() == r.back());
    ++steps;
  }
  CHECK(steps >= 600);
}

TEST_CASE("BitsBack: every pop inverts its push, 64..1024-bit X") {
  std::mt19937_64 rng(11);
  for (int t = 0; t < 2000; ++t) {
    const BitsBack X0 = random_x(rng, 64 + static_cast<int>(rng() % 961));
    BitsBack X = X0;
    const std::uint64_t m = (rng() >> (rng() % 64)) | 1, idx = rng() % m;
    X.push_uniform(idx, m);
    const std::uint64_t f = (rng() >> 17) % (1ULL << 40) + 1, c = rng() % (BitsBack::rans_total - f + 1);
    X.push_rans(c, f);
    const std::uint64_t g = rng() >> 16;
    X.add_low48(g);
    CHECK(!(X == X0));
    X.sub_low48(g);
    CHECK(X.low48() >= c && X.low48() - c < f);
    X.pop_rans(c, f);
    CHECK(X.pop_uniform(m) == idx);
    CHECK(X == X0);
  }
}

TEST_CASE("BitsBack: canonical words, bit_length, hex, zero") {
  const BitsBack a(std::vector<std::uint64_t>{5, 0, 0});
  CHECK(a.words().size() == 1);
  CHECK(a == BitsBack(std::vector<std::uint64_t>{5}));
  CHECK(a.bit_length() == 3);
  CHECK(BitsBack().bit_length() == 0);
  CHECK(BitsBack().is_zero());
  CHECK(BitsBack::from_hex("0x0").is_zero());
  CHECK(BitsBack::from_hex("0x1" + std::string(32, '0')).bit_length() == 129);
  CHECK(BitsBack::from_hex("0xABCdef").to_hex() == "0xabcdef");
  BitsBack z;
  z.push_uniform(0, 7);
  CHECK(z.is_zero());
  z.add_low48(9);
  CHECK(z.low48() == 9);
  z.sub_low48(9);
  CHECK(z.is_zero());
  BitsBack w(std::vector<std::uint64_t>{~0ULL, ~0ULL});
  w.push_uniform(1, 2);
  CHECK(w.bit_length() == 129);
  CHECK(w.pop_uniform(2) == 1);
  CHECK(w.bit_length() == 128);
}

TEST_CASE("BitsBack: bad input throws and changes nothing") {
  std::mt19937_64 rng(3);
  BitsBack X = random_x(rng, 256);
  const BitsBack X0 = X;
  CHECK_THROWS_AS(X.push_uniform(5, 5), InvalidArgument);
  CHECK_THROWS_AS(X.push_uniform(0, 0), InvalidArgument);
  CHECK_THROWS_AS(X.pop_uniform(0), InvalidArgument);
  CHECK_THROWS_AS(X.push_rans(0, 0), InvalidArgument);
  CHECK_THROWS_AS(X.push_rans(BitsBack::rans_total - 3, 4), InvalidArgument);
  const std::uint64_t s = X.low48();
  CHECK_THROWS_AS(X.pop_rans(s + 1, 10), InvalidArgument);
  CHECK_THROWS_AS(X.pop_rans(s > 5 ? s - 5 : 0, s > 5 ? 5 : 0), InvalidArgument);
  CHECK_THROWS_AS(X.add_low48(BitsBack::rans_total), InvalidArgument);
  CHECK_THROWS_AS(X.sub_low48(BitsBack::rans_total), InvalidArgument);
  CHECK_THROWS_AS(BitsBack::from_hex("0x12g4"), InvalidArgument);
  CHECK(X == X0);
}

TEST_CASE("BitsBack: the same value whether its words are inline (up to 4) or on the heap; copies and moves keep it") {
  std::mt19937_64 rng(11);
  BitsBack X = random_x(rng, 100);  // inline
  std::vector<std::uint64_t> idx;
  for (int k = 0; k < 40; ++k) {  // to ~500 bits: on the heap
    idx.push_back(rng() % 1000003);
    X.push_uniform(idx.back(), 1000003);
  }
  CHECK(X.bit_length() > 4 * 64);
  CHECK(X.heap_bytes() > 0);
  const BitsBack Y = X;                      // a copy of a heap value
  CHECK(Y == X);
  CHECK(BitsBack::from_hex(X.to_hex()) == X);
  BitsBack Z = std::move(X);                 // a move takes the words
  CHECK(Z == Y);
  CHECK(X.is_zero());
  BitsBack W = random_x(rng, 64);
  W = Z;                                     // copy-assigned over an inline value
  CHECK(W == Y);
  for (int k = 39; k >= 0; --k) CHECK(Z.pop_uniform(1000003) == idx[static_cast<std::size_t>(k)]);
  CHECK(Z.bit_length() <= 100);               // back to the start value, still equal by value
  BitsBack V(Z.words());                      // the same value built inline
  CHECK(V == Z);
  CHECK(V.heap_bytes() == 0);
  W = std::move(V);                          // move-assigned over a heap value
  CHECK(W == Z);
}

CHECK_MAIN()
