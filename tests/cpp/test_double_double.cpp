// Double-double arithmetic: the error-free transformations must be exact, checked in
// exact integer arithmetic (__int128) on integer-valued doubles, where every partial
// result is an integer too; the derived operations (add, square, div, sqrt, norm2) must
// reach about 2^-100 relative accuracy, checked against long double (64-bit mantissa)
// where it is enough and against exact identities where it is not.
#include "revcol/double_double.hpp"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <random>

#include "check.hpp"

using namespace revcol;

namespace {
using i128 = __int128;

// A random integer-valued double with `bits` significant bits and a random sign.
double random_int(std::mt19937_64& rng, int bits) {
  const std::uint64_t m = (rng() >> (64 - bits)) | (std::uint64_t{1} << (bits - 1));
  return (rng() & 1) ? -static_cast<double>(m) : static_cast<double>(m);
}
i128 as_int(double x) { return static_cast<i128>(x); }  // exact for integer-valued |x| < 2^127
// Half an ulp of x (for |x| >= 2^52 this is an integer or 1/2).
double half_ulp(double x) { return 0.5 * (std::nextafter(std::fabs(x), INFINITY) - std::fabs(x)); }
// the same two doubles, bit for bit (signed zeros included)
bool same(dd::DD a, dd::DD b) {
  return std::memcmp(&a.hi, &b.hi, sizeof(double)) == 0 && std::memcmp(&a.lo, &b.lo, sizeof(double)) == 0;
}
}  // namespace

TEST_CASE("two_sum is exact: s + e == a + b, |e| <= ulp(s)/2") {
  std::mt19937_64 rng(1);
  for (int t = 0; t < 20000; ++t) {
    // integers of up to 53 bits at shifts up to 2^60: the sum needs more than 53 bits
    const double a = std::ldexp(random_int(rng, 53), static_cast<int>(rng() % 8));
    const double b = random_int(rng, 1 + static_cast<int>(rng() % 53));
    const dd::DD s = dd::two_sum(a, b);
    CHECK(s.hi == a + b);
    CHECK(as_int(s.hi) + as_int(s.lo) == as_int(a) + as_int(b));
    CHECK(std::fabs(s.lo) <= half_ulp(s.hi));
    const dd::DD r = dd::two_sum(b, a);  // order does not matter
    CHECK(r.hi == s.hi);
    CHECK(r.lo == s.lo);
  }
  // a lost low part is recovered whole
  const dd::DD big = dd::two_sum(1.0, std::ldexp(1.0, -80));
  CHECK(big.hi == 1.0);
  CHECK(big.lo == std::ldexp(1.0, -80));
}

TEST_CASE("quick_two_sum is exact when |a| >= |b|") {
  std::mt19937_64 rng(2);
  for (int t = 0; t < 20000; ++t) {
    const double a = std::ldexp(random_int(rng, 53), 10);
    const double b = random_int(rng, 1 + static_cast<int>(rng() % 53));
    const dd::DD s = dd::quick_two_sum(a, b);
    CHECK(as_int(s.hi) + as_int(s.lo) == as_int(a) + as_int(b));
    CHECK(std::fabs(s.lo) <= half_ulp(s.hi));
  }
}

TEST_CASE("two_prod is exact: p + e == a * b to the last of 106 bits") {
  std::mt19937_64 rng(3);
  for (int t = 0; t < 20000; ++t) {
    const double a = random_int(rng, 1 + static_cast<int>(rng() % 53));
    const double b = random_int(rng, 1 + static_cast<int>(rng() % 53));
    const dd::DD p = dd::two_prod(a, b);
    CHECK(p.hi == a * b);
    CHECK(as_int(p.hi) + as_int(p.lo) == as_int(a) * as_int(b));
    CHECK(std::fabs(p.lo) <= half_ulp(p.hi));
    // scaling by powers of two keeps it exact (away from overflow and underflow)
    const int ea = static_cast<int>(rng() % 200) - 100, eb = static_cast<int>(rng() % 200) - 100;
    const dd::DD q = dd::two_prod(std::ldexp(a, ea), std::ldexp(b, eb));
    CHECK(std::ldexp(q.hi, -ea - eb) == p.hi);
    CHECK(std::ldexp(q.lo, -ea - eb) == p.lo);
  }
  // the classic: (1 + 2^-30)^2 = 1 + 2^-29 + 2^-60, whose last bit a double loses
  const dd::DD sq = dd::two_prod(1.0 + std::ldexp(1.0, -30), 1.0 + std::ldexp(1.0, -30));
  CHECK(sq.hi == 1.0 + std::ldexp(1.0, -29));
  CHECK(sq.lo == std::ldexp(1.0, -60));
}

TEST_CASE("two_square is two_prod(x, x) bit for bit, and exact") {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int t = 0; t < 200000; ++t) {
    // integer-valued, checked exactly; then random reals over a wide exponent range, as the
    // operators square them (frame components near 1, speeds up to 2^500). Below |x| ~
    // 2^-484 the error term x^2 - p falls among the subnormals, where Dekker's product is no
    // longer exact and the two forms round it differently: not compared there
    const double a = random_int(rng, 1 + static_cast<int>(rng() % 53));
    const dd::DD s = dd::two_square(a);
    CHECK(same(s, dd::two_prod(a, a)));
    CHECK(same(dd::two_square_dekker(a), dd::two_prod_dekker(a, a)));
    CHECK(as_int(s.hi) + as_int(s.lo) == as_int(a) * as_int(a));
    const double x = std::ldexp(unit(rng), static_cast<int>(rng() % 980) - 480);
    CHECK(same(dd::two_square(x), dd::two_prod(x, x)));
    CHECK(same(dd::two_square_dekker(x), dd::two_prod_dekker(x, x)));
    const double y = 1.0 + std::ldexp(unit(rng), -static_cast<int>(rng() % 60));
    CHECK(same(dd::two_square(y), dd::two_prod(y, y)));
    CHECK(same(dd::two_square_dekker(y), dd::two_prod_dekker(y, y)));
  }
}

TEST_CASE("the fused multiply-add's products are Dekker's bit for bit (a host build's bits are a baseline build's)") {
  // two_prod and two_square take their error term from one fma where the build has FMA
  // (CMake REVCOL_ISA=x86-64-v3), from Dekker's split otherwise. Both are exact over the
  // operators' range, so they must agree to the last bit; where they would not, a host
  // build's collisions would differ from a baseline build's. In a baseline build both sides
  // are Dekker's (the comparison then holds trivially; .ci/run builds both ways, and
  // test_engine_hash checks the same constants in each).
  std::printf("  two_prod here: %s\n", dd::kFusedProducts ? "fused multiply-add" : "Dekker's split");
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  int bad = 0;
  for (int t = 0; t < 400000; ++t) {
    // exponents as the operators see them: speeds in [2^-480, 2^450], frame components near 1,
    // products of a speed and a component (products above 2^-969: see two_prod)
    const double a = std::ldexp(unit(rng), static_cast<int>(rng() % 930) - 480);
    const double b = std::ldexp(unit(rng), static_cast<int>(rng() % 40) - 20);
    const double c = 1.0 + std::ldexp(unit(rng), -static_cast<int>(rng() % 60));
    bad += same(dd::two_prod(a, b), dd::two_prod_dekker(a, b)) ? 0 : 1;
    bad += same(dd::two_prod(c, b), dd::two_prod_dekker(c, b)) ? 0 : 1;
    bad += same(dd::two_square(a), dd::two_square_dekker(a)) ? 0 : 1;
    bad += same(dd::two_square(c), dd::two_square_dekker(c)) ? 0 : 1;
    // integer-valued: both exact by construction, whatever the exponent
    const double i = random_int(rng, 1 + static_cast<int>(rng() % 53));
    const double j = random_int(rng, 1 + static_cast<int>(rng() % 53));
    bad += same(dd::two_prod(i, j), dd::two_prod_dekker(i, j)) ? 0 : 1;
  }
  CHECK(bad == 0);
}

TEST_CASE("add, square, div, sqrt and norm2 reach double-double accuracy") {
  // references in long double (2^-64 relative; a sum of three rounded products is within
  // 2^-62): each result must beat a double's 2^-53 by far, so the check is at 2^-60
  const long double tol = std::ldexp(1.0L, -60);
  // x - y in double-double, for identities that must hold beyond long double's reach
  auto diff = [](dd::DD x, double y) { return dd::add(x, {-y, 0.0}).hi; };
  auto val = [](dd::DD x) { return static_cast<long double>(x.hi) + static_cast<long double>(x.lo); };
  auto rel = [](long double a, long double b) { return std::fabs(a - b) / std::fabs(b); };
  const dd::DD third = dd::div({1.0, 0.0}, {3.0, 0.0});
  CHECK(rel(val(third), 1.0L / 3.0L) <= tol);
  CHECK(third.lo != 0.0);  // a plain double quotient would leave it 0
  const dd::DD root2 = dd::sqrt({2.0, 0.0});
  CHECK(rel(val(root2), std::sqrt(2.0L)) <= tol);
  // sqrt(x)^2 = x and (a / b) b = a to double-double accuracy
  CHECK(std::fabs(diff(dd::square(root2), 2.0)) <= std::ldexp(2.0, -100));
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> unif(0.5, 2.0);
  for (int t = 0; t < 2000; ++t) {
    const dd::DD x{unif(rng), 0.0}, y{unif(rng), 0.0};
    const dd::DD s = dd::add(x, dd::div(x, y));
    CHECK(rel(val(s), static_cast<long double>(x.hi) + static_cast<long double>(x.hi) / y.hi) <= tol);
    const dd::DD q = dd::square(dd::sqrt(x));
    CHECK(std::fabs(diff(q, x.hi)) <= std::ldexp(x.hi, -100));
    const double u[3] = {unif(rng), -unif(rng), unif(rng)};
    const long double n2 = static_cast<long double>(u[0]) * u[0] +
                           static_cast<long double>(u[1]) * u[1] + static_cast<long double>(u[2]) * u[2];
    CHECK(rel(val(dd::norm2<3>(u)), n2) <= tol);
  }
}

CHECK_MAIN()

// The operators' shortcuts leave out a QuickTwoSum that cannot change anything; each must give
// the full form's bits, signed zeros included, on random, tied and near-unit inputs.
TEST_CASE("compensated_norm2<2>, compensated_norm2_minus_one and add_minus_one: the full forms' bits") {
  const auto same = [](double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; };
  std::mt19937_64 rng(31);
  std::normal_distribution<double> N(0.0, 1.0);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  int bad = 0;
  for (int k = 0; k < 2000000; ++k) {
    // 2D |w|^2: random scales, exact ties (small integers), and zeros
    double w[2];
    if (k % 4 == 0) {
      w[0] = static_cast<double>(static_cast<int>(U(rng) * 3e7)), w[1] = static_cast<double>(static_cast<int>(U(rng) * 3e7));
    } else if (k % 1000 == 1) {
      w[0] = 0.0, w[1] = k % 3 ? -0.0 : 0.0;
    } else {
      w[0] = N(rng) * std::ldexp(1.0, static_cast<int>(U(rng) * 60)), w[1] = N(rng);
    }
    dd::DD s{w[0] * w[0], 0.0};
    const dd::DD t = dd::two_sum(s.hi, w[1] * w[1]);
    s = {t.hi, s.lo + t.lo};
    const dd::DD full = dd::quick_two_sum(s.hi, s.lo), fast = dd::compensated_norm2<2>(w);
    bad += same(full.hi, fast.hi) && same(full.lo, fast.lo) ? 0 : 1;
    // a unit vector to rounding, in 3D and 2D
    double u[3] = {N(rng), N(rng), N(rng)};
    const double r = 1.0 / std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (double& x : u) x *= r;
    const dd::DD U3 = dd::compensated_norm2<3>(u);
    bad += same((U3.hi - 1.0) + U3.lo, dd::compensated_norm2_minus_one<3>(u)) ? 0 : 1;
    const double r2 = 1.0 / std::sqrt(u[0] * u[0] + u[1] * u[1]);
    const double a0 = u[0] * r2, a1 = u[1] * r2;
    const dd::DD A = dd::add(dd::two_square(a0), dd::two_square(a1));
    bad += same((A.hi - 1.0) + A.lo, dd::add_minus_one(dd::two_square(a0), dd::two_square(a1))) ? 0 : 1;
  }
  CHECK(bad == 0);
}
