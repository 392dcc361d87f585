#include "revcol/collide/triple1d_paper.hpp"

#include <cmath>
#include <random>

#include "check.hpp"
#include "revcol/collide/batch.hpp"
#include "revcol/rng/clcg4.hpp"

using namespace revcol;
using T = paper::Triple<1>;
using X = std::array<double, 3>;

namespace {
constexpr double kPi = 3.141592653589793238462643383279502884;
double uniform01(std::mt19937_64& rng) { return (static_cast<double>(rng() >> 11) + 0.5) * 0x1.0p-53; }
double max_diff(const T& a, const T& b) {
  return std::max({std::fabs(a[0][0] - b[0][0]), std::fabs(a[1][0] - b[1][0]), std::fabs(a[2][0] - b[2][0])});
}
// a random pre state: left > centre > right in velocity, positions 0 < 1 < 2
T random_pre(std::mt19937_64& rng) {
  std::normal_distribution<double> N;
  for (;;) {
    T v{{{N(rng)}, {N(rng)}, {N(rng)}}};
    if (v[0][0] > v[1][0] && v[1][0] > v[2][0]) return v;
  }
}
const X kRow{0.0, 1.0, 2.0};
}  // namespace

TEST_CASE("Procedures 3 and 4 (fixed) invert each other for every arc method") {
  std::mt19937_64 rng(1);
  for (paper::ArcMethod m : {paper::ArcMethod::simpson, paper::ArcMethod::elliptic, paper::ArcMethod::table}) {
    const Triple1DPaper op(m);
    RareLog log;
    const int n = m == paper::ArcMethod::simpson ? 2000 : 30000;
    for (int k = 0; k < n; ++k) {
      const T v = random_pre(rng);
      const Triple1DPaper::Draws g{uniform01(rng)};
      const T post = op.forward(v, kRow, g, log);
      REQUIRE(post[0][0] < post[1][0] && post[1][0] < post[2][0]);  // separates at both contacts
      CHECK_NEAR(post[0][0] + post[1][0] + post[2][0], v[0][0] + v[1][0] + v[2][0], 1e-13);
      CHECK(max_diff(op.reverse(post, kRow, g, log), v) <= 1e-13);
    }
  }
}

TEST_CASE("the forward step is a rotation of the arc S1: 7pi/6 + (phi' + psi - 7pi/6) mod pi/3") {
  const Triple1DPaper op(paper::ArcMethod::table, 0.0);
  std::mt19937_64 rng(2);
  for (int k = 0; k < 100000; ++k) {
    const double phi = kPi / 6 + (kPi / 3) * uniform01(rng), psi = 2 * kPi * uniform01(rng);
    const double expect = 7 * kPi / 6 + paper::wrap(phi + psi - 7 * kPi / 6, kPi / 3);
    CHECK_NEAR(op.forward_angle(phi, psi), expect, 1e-13);
    CHECK_NEAR(op.reverse_angle(op.forward_angle(phi, psi), psi), phi, 1e-13);
  }
}

TEST_CASE("V-to-Phi / Phi-to-V: the paper's formulas, particles ordered by position") {
  // a - b = lambda cos phi, b - c = lambda cos(phi - 2pi/3), c - a = lambda cos(phi + 2pi/3)
  const T v{{{0.75}, {0.25}, {-0.5}}};
  const double phi = Triple1DPaper::angle(v, kRow);
  const double mean = (0.75 + 0.25 - 0.5) / 3, delta = 0.75 * 0.75 + 0.25 * 0.25 + 0.25;
  const double lambda = std::sqrt(2.0) * std::sqrt(delta - 3 * mean * mean);
  CHECK_NEAR(0.75 - 0.25, lambda * std::cos(phi), 1e-15);
  CHECK_NEAR(0.25 + 0.5, lambda * std::cos(phi - 2 * kPi / 3), 1e-15);
  CHECK_NEAR(-0.5 - 0.75, lambda * std::cos(phi + 2 * kPi / 3), 1e-15);
  CHECK(phi > kPi / 6 && phi < kPi / 2);  // pre range R1
  // ids need not be in positional order: permute both
  const T w{{{-0.5}, {0.75}, {0.25}}};
  const X x{5.0, 3.0, 4.0};  // particle 1 left, 2 centre, 0 right
  CHECK_NEAR(Triple1DPaper::angle(w, x), phi, 1e-15);
  const Triple1DPaper op(paper::ArcMethod::elliptic);
  RareLog log;
  const T a = op.forward(v, kRow, {0.3}, log), b = op.forward(w, x, {0.3}, log);
  CHECK(a[0][0] == b[1][0] && a[1][0] == b[2][0] && a[2][0] == b[0][0]);
}

TEST_CASE("the printed Procedure 4 never undoes Step 2: it fails exactly when the forward added pi") {
  const Triple1DPaper fixed(paper::ArcMethod::table), printed(paper::ArcMethod::table, 1e-8, true);
  std::mt19937_64 rng(3);
  RareLog log;
  int step2 = 0, wrong = 0, mismatch = 0;
  const int total = 50000;
  for (int k = 0; k < total; ++k) {
    const T v = random_pre(rng);
    const Triple1DPaper::Draws g{uniform01(rng)};
    const T post = fixed.forward(v, kRow, g, log);
    const double theta = paper::wrap(Triple1DPaper::angle(v, kRow) + fixed.arc().psi(g[0]));
    const int positives = (std::cos(theta) > 1e-8) + (std::cos(theta - 2 * kPi / 3) > 1e-8) +
                          (std::cos(theta + 2 * kPi / 3) > 1e-8);
    const bool added_pi = positives >= 2;
    bool bad;
    try {
      bad = max_diff(printed.reverse(post, kRow, g, log), v) > 1e-9;
    } catch (const InvalidArgument&) {
      bad = true;
    }
    step2 += added_pi;
    wrong += bad;
    mismatch += bad != added_pi;
  }
  CHECK(mismatch == 0);
  CHECK(wrong > total * 0.4 && wrong < total * 0.6);
  // fixing only WHICH angle is tested (the candidate, with the printed "more than one
  // positive" condition) is not enough: that condition picks the R regions, not S
  int half_fixed_wrong = 0;
  for (int k = 0; k < 10000; ++k) {
    const double phi = kPi / 6 + (kPi / 3) * uniform01(rng), psi = 2 * kPi * uniform01(rng);
    const double post = fixed.forward_angle(phi, psi);
    double cand = paper::wrap(post - psi);
    const int pos = (std::cos(cand) > 1e-8) + (std::cos(cand - 2 * kPi / 3) > 1e-8) + (std::cos(cand + 2 * kPi / 3) > 1e-8);
    if (pos >= 2) cand = paper::wrap(cand - kPi);
    if (std::cos(cand) < -1e-8) cand = paper::wrap(cand - 2 * kPi / 3);
    else if (std::cos(cand - 2 * kPi / 3) < -1e-8) cand = paper::wrap(cand + 2 * kPi / 3);
    half_fixed_wrong += std::fabs(cand - phi) > 1e-9;
  }
  CHECK(half_fixed_wrong > 4000);
}

TEST_CASE("the cosine tolerance: inside its bands the forward step leaves S1 by up to cos_tol") {
  // theta = phi' + psi just below pi/2 (R1, cos theta in (0, tol)): the paper's test does not
  // count cos theta as positive, so Step 2 is skipped and Step 3b sends theta to 7pi/6 - eps,
  // outside S1 (centre and right still approach by lambda sin eps)
  const Triple1DPaper tol8(paper::ArcMethod::table, 1e-8), exact(paper::ArcMethod::table, 0.0);
  const double phi = 1.0, psi = kPi / 2 - 1e-9 - phi;
  const double a = tol8.forward_angle(phi, psi), b = exact.forward_angle(phi, psi);
  CHECK(a < 7 * kPi / 6 && a > 7 * kPi / 6 - 2e-9);  // outside S1
  CHECK(b > 7 * kPi / 6 && b < 3 * kPi / 2);          // inside S1 (= 3pi/2 - 1e-9)
  // both remain invertible on these angles
  CHECK_NEAR(tol8.reverse_angle(a, psi), phi, 1e-12);
  CHECK_NEAR(exact.reverse_angle(b, psi), phi, 1e-12);
  // away from the bands the tolerance changes nothing
  CHECK(tol8.forward_angle(phi, 0.3) == exact.forward_angle(phi, 0.3));
  CHECK_THROWS_AS(Triple1DPaper(paper::ArcMethod::table, -1e-3), InvalidArgument);
  CHECK_THROWS_AS(Triple1DPaper(paper::ArcMethod::table, 0.7), InvalidArgument);
}

TEST_CASE("held invariants: 2000 collisions of the paper's illustration and back") {
  const Triple1DPaper op(paper::ArcMethod::table);
  RareLog log;
  T v{{{0.75}, {0.25}, {-0.5}}};
  const T start = v;
  const Invariants<1> inv{{0.5}, 0.75 * 0.75 + 0.25 * 0.25 + 0.25};
  rng::CLCG4 gen(9);
  for (int k = 0; k < 2000; ++k) {
    v = op.forward(v, kRow, {gen.next()}, log, &inv);
    for (auto& p : v) p[0] = -p[0];
  }
  for (int k = 0; k < 2000; ++k) {
    for (auto& p : v) p[0] = -p[0];
    v = op.reverse(v, kRow, {gen.prev()}, log, &inv);
  }
  CHECK(gen == rng::CLCG4(9));
  CHECK(max_diff(v, start) <= 1e-12);
}

TEST_CASE("exactly one draw per collision; validation changes nothing") {
  const Triple1DPaper op(paper::ArcMethod::table);
  RareLog log;
  std::vector<T> v = {T{{{0.75}, {0.25}, {-0.5}}}, T{{{2.0}, {0.0}, {-1.0}}}, T{{{1.0}, {0.5}, {0.0}}}};
  std::vector<X> x(3, kRow);
  rng::CLCG4 gen(4), ref(4);
  forward_batch(op, v.data(), x.data(), v.size(), gen, log);
  for (int k = 0; k < 3; ++k) ref.next();
  CHECK(gen == ref);
  reverse_batch(op, v.data(), x.data(), v.size(), gen, log);
  CHECK(gen == rng::CLCG4(4));
  CHECK(std::fabs(v[1][0][0] - 2.0) < 1e-14);
  const Triple1DPaper::Draws g{0.5};
  CHECK_THROWS_AS(op.forward(T{{{0.0}, {0.5}, {-1.0}}}, kRow, g, log), InvalidArgument);  // left-centre separate
  CHECK_THROWS_AS(op.forward(T{{{1.0}, {0.5}, {0.5}}}, kRow, g, log), InvalidArgument);   // centre-right at rest
  CHECK_THROWS_AS(op.forward(T{{{1.0}, {0.5}, {0.0}}}, X{0.0, 1.0, 1.0}, g, log), InvalidArgument);
  CHECK_THROWS_AS(op.forward(T{{{1.0}, {0.5}, {0.0}}}, X{0.0, 1.0, std::nan("")}, g, log), InvalidArgument);
  CHECK_THROWS_AS(op.forward(T{{{1.0}, {std::nan("")}, {0.0}}}, kRow, g, log), InvalidArgument);
  CHECK_THROWS_AS(op.forward(T{{{1.0}, {0.5}, {0.0}}}, kRow, {1.01}, log), InvalidArgument);
  CHECK_THROWS_AS(op.reverse(T{{{1.0}, {0.5}, {0.0}}}, kRow, g, log), InvalidArgument);  // approaching
  const Invariants<1> wrong{{1.5}, 10.0};
  CHECK_THROWS_AS(op.forward(T{{{1.0}, {0.5}, {0.0}}}, kRow, g, log, &wrong), InvalidArgument);
  // edges: G = 0 and 1 both give a valid post state and reverse
  for (double ge : {0.0, 1.0}) {
    const T pre{{{1.0}, {0.5}, {0.0}}};
    const T post = op.forward(pre, kRow, {ge}, log);
    CHECK(post[0][0] < post[1][0] && post[1][0] < post[2][0]);
    CHECK(max_diff(op.reverse(post, kRow, {ge}, log), pre) < 1e-14);
  }
}

CHECK_MAIN()
