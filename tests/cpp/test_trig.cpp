// Trigonometry in turns (trig.hpp): the errors of sin(2 pi c), cos(2 pi c) and
// atan2(y, x) / (2 pi) against long double (64-bit mantissa: its own error, ~1e-19, is far
// below what is measured), at random points, where the reductions' branches meet, and at the
// ends; the exact values the symmetries give. The exact operators' rare-log bounds count on
// these errors (Pair3DExact::bound: "sincos" inside 3 u of the decoded direction, atan2
// inside the 8 u of c1).
#include "revcol/trig.hpp"

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "check.hpp"

using namespace revcol;

namespace {
constexpr long double kTwoPiL = 6.283185307179586476925286766559005768L;

struct Err {
  double sin = 0.0, cos = 0.0;
};
void measure(double c, Err& e) {
  double s, co;
  trig::sincos_turns(c, s, co);
  const long double x = kTwoPiL * static_cast<long double>(c);
  e.sin = std::fmax(e.sin, static_cast<double>(std::fabs(static_cast<long double>(s) - std::sin(x))));
  e.cos = std::fmax(e.cos, static_cast<double>(std::fabs(static_cast<long double>(co) - std::cos(x))));
}
}  // namespace

TEST_CASE("sincos_turns: absolute error below 2.5e-16 on [0, 1] (random, dyadic and edge points)") {
  Err e;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int t = 0; t < 2000000; ++t) measure(u(rng), e);
  // the branch points of the reduction (multiples of 1/8) and their neighbours
  for (int k = 0; k <= 8; ++k) {
    double c = k / 8.0;
    for (int m = 0; m < 40; ++m) {
      if (c >= 0.0 && c <= 1.0) measure(c, e);
      const double up = std::nextafter(k / 8.0, 2.0) + m * 1e-17, dn = std::nextafter(k / 8.0, -1.0) - m * 1e-17;
      if (up <= 1.0) measure(up, e);
      if (dn >= 0.0) measure(dn, e);
      c = std::nextafter(c, 2.0);
    }
  }
  // tiny arguments: sin(2 pi c) ~ 2 pi c keeps relative accuracy
  for (int p = 1; p < 1000; ++p) measure(std::ldexp(1.0, -p), e);
  std::printf("  max |error|: sin %.3g, cos %.3g\n", e.sin, e.cos);
  CHECK(e.sin < 2.5e-16);
  CHECK(e.cos < 2.5e-16);
}

TEST_CASE("sincos_turns: the quarter turns are exact, and sin keeps its relative accuracy (3e-16) below 1/8 turn") {
  const double want[5][2] = {{0, 1}, {1, 0}, {0, -1}, {-1, 0}, {0, 1}};
  for (int k = 0; k <= 4; ++k) {
    double s, c;
    trig::sincos_turns(k / 4.0, s, c);
    CHECK(s == want[k][0]);
    CHECK(c == want[k][1]);
  }
  double rel = 0.0;
  for (int p = 5; p < 1000; ++p) {  // c <= 2.48 / 32 < 1/8
    const double c = std::ldexp(1.0, -p) * (1.0 + 0.37 * (p % 5));
    double s, co;
    trig::sincos_turns(c, s, co);
    const long double x = kTwoPiL * static_cast<long double>(c);
    rel = std::fmax(rel, static_cast<double>(std::fabs((static_cast<long double>(s) - std::sin(x)) / std::sin(x))));
    if (p >= 30) CHECK(co == 1.0);  // 1 - (2 pi c)^2 / 2 rounds to 1
  }
  std::printf("  max relative error of sin below 1/8 turn: %.3g\n", rel);
  CHECK(rel < 3e-16);
}

TEST_CASE("sincos_turns: s^2 + c^2 = 1 within 4e-16 and the symmetries c -> 1 - c, c -> c + 1/2 hold to 4e-16") {
  std::mt19937_64 rng(6);
  std::uniform_real_distribution<double> u(0.0, 0.5);
  double worst = 0.0, sym = 0.0;
  for (int t = 0; t < 200000; ++t) {
    const double c = u(rng);
    double s, co, s1, co1, s2, co2;
    trig::sincos_turns(c, s, co);
    trig::sincos_turns(1.0 - c, s1, co1);
    trig::sincos_turns(c + 0.5, s2, co2);
    worst = std::fmax(worst, std::fabs(s * s + co * co - 1.0));
    // 1 - c and c + 1/2 round by up to 2^-54: the derivative 2 pi turns that into 3.5e-16
    sym = std::fmax(sym, std::fmax(std::fabs(s1 + s), std::fabs(co1 - co)));
    sym = std::fmax(sym, std::fmax(std::fabs(s2 + s), std::fabs(co2 + co)));
  }
  std::printf("  max |s^2 + c^2 - 1| %.3g, max symmetry defect %.3g\n", worst, sym);
  CHECK(worst < 4e-16);
  CHECK(sym < 4e-16 + 3.5e-16);
}

namespace {
// atan2(y, x) / (2 pi) in [0, 1) in long double, the reference for atan2_turns
long double atan2_turns_ref(double y, double x) {
  long double a = std::atan2(static_cast<long double>(y), static_cast<long double>(x)) / kTwoPiL;
  if (a < 0.0L) a += 1.0L;
  return a;
}
// the error in turns, taken on the circle (0 and 1 are the same angle)
double turn_error(double got, long double want) {
  long double e = std::fabs(static_cast<long double>(got) - want);
  if (e > 0.5L) e = 1.0L - e;
  return static_cast<double>(e);
}
}  // namespace

TEST_CASE("atan2_turns: error below 2e-16 of a turn (random directions, octant edges, axes, scales)") {
  double worst = 0.0;
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_int_distribution<int> sc(-300, 300);
  for (int t = 0; t < 2000000; ++t) {
    const double s = std::ldexp(1.0, sc(rng));  // the angle must not depend on the scale
    const double x = s * g(rng), y = s * g(rng);
    worst = std::fmax(worst, turn_error(trig::atan2_turns(y, x), atan2_turns_ref(y, x)));
  }
  // the diagonals, the axes, the table's knots t = i/32 and the midpoints between them, in
  // every octant, with neighbours
  for (int i = 0; i <= 64; ++i) {
    for (int sx = -1; sx <= 1; sx += 2)
      for (int sy = -1; sy <= 1; sy += 2)
        for (int m = -3; m <= 3; ++m) {
          const double t = std::nextafter(i / 64.0, m < 0 ? -1.0 : 2.0) + m * 1e-17;
          const double xs[2] = {sx * 1.0, sx * t}, ys[2] = {sy * t, sy * 1.0};
          for (int o = 0; o < 2; ++o)
            worst = std::fmax(worst, turn_error(trig::atan2_turns(ys[o], xs[o]), atan2_turns_ref(ys[o], xs[o])));
        }
  }
  std::printf("  max |error| in turns: %.3g\n", worst);
  CHECK(worst < 2e-16);
}

TEST_CASE("atan2_turns: axes, diagonals and signed zeros give libm's angles, in [0, 1]") {
  CHECK(trig::atan2_turns(0.0, 1.0) == 0.0);
  CHECK(trig::atan2_turns(-0.0, 1.0) == 0.0);
  CHECK(trig::atan2_turns(1.0, 0.0) == 0.25);
  CHECK(trig::atan2_turns(0.0, -1.0) == 0.5);
  CHECK(trig::atan2_turns(-0.0, -1.0) == 0.5);
  CHECK(trig::atan2_turns(-1.0, 0.0) == 0.75);
  CHECK(trig::atan2_turns(1.0, 1.0) == 0.125);
  CHECK(trig::atan2_turns(-2.0, -2.0) == 0.625);
  CHECK(trig::atan2_turns(0.0, 0.0) == 0.0);
  std::mt19937_64 rng(8);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int t = 0; t < 100000; ++t) {
    const double a = trig::atan2_turns(g(rng), g(rng));
    CHECK(a >= 0.0 && a <= 1.0);
  }
}

TEST_CASE("atan2_turns inverts sincos_turns to 3e-16 of a turn") {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double worst = 0.0;
  for (int t = 0; t < 500000; ++t) {
    const double c = u(rng);
    double s, co;
    trig::sincos_turns(c, s, co);
    worst = std::fmax(worst, turn_error(trig::atan2_turns(s, co), c));
  }
  std::printf("  max |atan2_turns(sincos_turns(c)) - c|: %.3g\n", worst);
  CHECK(worst < 3e-16);
}

CHECK_MAIN()
