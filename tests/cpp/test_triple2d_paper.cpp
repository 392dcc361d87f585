#include "revcol/collide/triple2d_paper.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "check.hpp"
#include "revcol/collide/batch.hpp"
#include "revcol/rng/clcg4.hpp"

using namespace revcol;
using paper::Canonical;
using paper::Config;
using T = paper::Triple<2>;
using P = paper::Positions2;

namespace {
constexpr double kPi = 3.141592653589793238462643383279502884;
const double h = std::sqrt(3.0) / 2.0, th = 5.0 * kPi / 6.0;
// the four geometries of collide/cases.hpp
const P kC1{{{0.0, 0.0}, {1.0, 0.0}, {0.5, h}}};
const P kC2{{{0.0, 0.0}, {1.0, 0.0}, {0.5, -h}}};
const P kC3{{{0.0, 0.0}, {1.0, 0.0}, {1.0 - std::cos(th), -std::sin(th)}}};
const P kC4{{{0.0, 0.0}, {1.0, 0.0}, {std::cos(th), std::sin(th)}}};

double uniform01(std::mt19937_64& rng) { return (static_cast<double>(rng() >> 11) + 0.5) * 0x1.0p-53; }
double max_diff(const T& a, const T& b) {
  double m = 0;
  for (int p = 0; p < 3; ++p) m = std::max({m, std::fabs(a[p][0] - b[p][0]), std::fabs(a[p][1] - b[p][1])});
  return m;
}
// normal relative velocities of the world geometry: (x_i - x_j).(v_i - v_j) / |x_i - x_j|
std::vector<double> world_speeds(const P& x, const T& v) {
  std::vector<double> d, out;
  const int pairs[3][2] = {{0, 1}, {1, 2}, {0, 2}};
  for (auto& pr : pairs) d.push_back(std::hypot(x[pr[0]][0] - x[pr[1]][0], x[pr[0]][1] - x[pr[1]][1]));
  const double dmin = *std::min_element(d.begin(), d.end());
  for (int k = 0; k < 3; ++k) {
    if (d[k] > dmin * (1 + 1e-9)) continue;
    const int i = pairs[k][0], j = pairs[k][1];
    out.push_back(((x[i][0] - x[j][0]) * (v[i][0] - v[j][0]) + (x[i][1] - x[j][1]) * (v[i][1] - v[j][1])) / d[k]);
  }
  std::sort(out.begin(), out.end());
  return out;
}
T random_pre(std::mt19937_64& rng, const P& x) {
  std::normal_distribution<double> N;
  for (;;) {
    T v;
    for (auto& p : v) p = {N(rng), N(rng)};
    const auto s = world_speeds(x, v);
    if (std::all_of(s.begin(), s.end(), [](double q) { return q < 0; })) return v;
  }
}
P rigid(const P& x, double a, double tx, double ty) {
  P out;
  for (int p = 0; p < 3; ++p)
    out[p] = {std::cos(a) * x[p][0] - std::sin(a) * x[p][1] + tx, std::sin(a) * x[p][0] + std::cos(a) * x[p][1] + ty};
  return out;
}
T rotate(const T& v, double a) {
  T out;
  for (int p = 0; p < 3; ++p)
    out[p] = {std::cos(a) * v[p][0] - std::sin(a) * v[p][1], std::sin(a) * v[p][0] + std::cos(a) * v[p][1]};
  return out;
}
}  // namespace

TEST_CASE("canonical configuration from the positions alone: C1-C4, ids, theta") {
  const Canonical c1 = paper::canonical(kC1), c2 = paper::canonical(kC2), c3 = paper::canonical(kC3),
                  c4 = paper::canonical(kC4);
  CHECK(c1.config == Config::c1 && c1.contacts == 3 && c1.id == (std::array<int, 3>{0, 1, 2}));
  CHECK(c2.config == Config::c2 && c2.contacts == 3);
  CHECK(c3.config == Config::c3 && c3.contacts == 2);
  CHECK_NEAR(c3.theta, 5 * kPi / 6, 1e-14);
  CHECK(c4.config == Config::c4 && c4.contacts == 2);
  CHECK_NEAR(c4.theta, -kPi / 6, 1e-14);
  // the frame: x from P2 to P1, y = x turned by +90 degrees (mirrored for C2)
  CHECK_NEAR(c1.R(0, 0), -1.0, 1e-15);
  CHECK_NEAR(c1.R.determinant(), 1.0, 1e-15);
  CHECK_NEAR(c2.R.determinant(), -1.0, 1e-15);
  // a chain whose middle particle has the largest id: the pair (0, 2) is horizontal, C3
  const Canonical ch = paper::canonical(P{{{0.0, 0.0}, {2.0, 0.0}, {1.0, 0.0}}});
  CHECK(ch.config == Config::c3 && ch.id == (std::array<int, 3>{0, 2, 1}));
  CHECK_NEAR(ch.theta, kPi, 1e-14);
  // middle particle 0: C4 with P1 = 0
  const Canonical c0 = paper::canonical(P{{{1.0, 0.0}, {2.0, 0.0}, {0.0, 0.0}}});
  CHECK(c0.config == Config::c4 && c0.id == (std::array<int, 3>{0, 1, 2}));
  // invariant under rigid motions (rotation and translation)
  for (double a : {0.3, 1.9, -2.4, kPi}) {
    const Canonical r1 = paper::canonical(rigid(kC1, a, 3.0, -7.0)), r3 = paper::canonical(rigid(kC3, a, -1.0, 2.0));
    CHECK(r1.config == Config::c1 && r3.config == Config::c3);
    CHECK_NEAR(r3.theta, c3.theta, 1e-12);
    CHECK(paper::canonical(rigid(kC2, a, 0.5, 0.5)).config == Config::c2);
    CHECK_NEAR(paper::canonical(rigid(kC4, a, 0.5, 0.5)).theta, c4.theta, 1e-12);
  }
}

TEST_CASE("bad geometries are refused") {
  CHECK_THROWS_AS(paper::canonical(P{{{0, 0}, {1, 0}, {3, 0}}}), InvalidArgument);  // one contact
  CHECK_THROWS_AS(paper::canonical(P{{{0, 0}, {0, 0}, {1, 0}}}), InvalidArgument);  // coincident
  CHECK_THROWS_AS(paper::canonical(P{{{0, 0}, {1, 0}, {std::nan(""), 0}}}), InvalidArgument);
  // C3 at the edge of its theta range is a near-triangle: two contacts within 1e-9
  CHECK(paper::canonical(P{{{0, 0}, {1, 0}, {0.5, h * (1 + 1e-12)}}}).contacts == 3);
}

TEST_CASE("the canonical contact normals are the world's, and each constraint is its phi form") {
  std::mt19937_64 rng(7);
  for (const P* x : {&kC1, &kC2, &kC3, &kC4}) {
    const Canonical cf = paper::canonical(*x);
    for (int k = 0; k < 2000; ++k) {
      std::normal_distribution<double> N;
      T v;
      for (auto& p : v) p = {N(rng), N(rng)};
      auto s = Triple2DPaper::normal_speeds(v, cf);
      std::vector<double> mine(s.begin(), s.begin() + cf.contacts);
      std::sort(mine.begin(), mine.end());
      const auto world = world_speeds(*x, v);
      REQUIRE(world.size() == mine.size());
      for (std::size_t c = 0; c < mine.size(); ++c) CHECK_NEAR(mine[c], world[c], 1e-12);
      // K1: cos phi1 > 0; contact k >= 1: sqrt3 s1 s2 cos(phi3 - c) < p c1 + q s1 c2
      const auto a = Triple2DPaper::angles(v, *x);
      CHECK((s[0] > 0) == (std::cos(a[0]) > 0));
      for (int c = 1; c < cf.contacts; ++c) {
        const double form = cf.p[c] * std::cos(a[0]) + cf.q[c] * std::sin(a[0]) * std::cos(a[1]) -
                            std::sqrt(3.0) * std::sin(a[0]) * std::sin(a[1]) * std::cos(a[2] - cf.centre[c]);
        if (std::fabs(form) > 1e-12) CHECK((s[c] > 0) == (form > 0));
      }
    }
  }
}

TEST_CASE("C1 bounds of phi2: the printed closed forms are where both L1 and L2 can hold") {
  const Canonical cf = paper::canonical(kC1);
  for (int i = 1; i < 90; ++i) {
    const double phi1 = (kPi / 2) * i / 90.0;
    const auto b = Triple2DPaper::bounds2(cf, phi1);
    for (int j = 1; j < 400; ++j) {
      const double phi2 = kPi * j / 400.0;
      const double A = std::cos(phi1) / (2 * std::sqrt(3.0) * std::sin(phi1) * std::sin(phi2));
      const double B = std::cos(phi2) / (2 * std::sin(phi2));
      const bool feasible = A - B > -1 && A + B > -1;
      const bool inside = phi2 >= b.lo && phi2 <= b.hi;
      if (std::fabs(phi2 - b.lo) > 1e-9 && std::fabs(phi2 - b.hi) > 1e-9) CHECK(feasible == inside);
    }
  }
}

TEST_CASE("bounds of phi3 hold every permitted phi3; C3 has phi1 with no permitted state at all") {
  std::mt19937_64 rng(8);
  for (const P* x : {&kC1, &kC3, &kC4}) {
    const Canonical cf = paper::canonical(*x);
    for (int k = 0; k < 3000; ++k) {
      const double phi1 = (kPi / 2) * uniform01(rng), phi2 = kPi * uniform01(rng);
      const auto b = Triple2DPaper::bounds3(cf, phi1, phi2);
      CHECK(b.lo >= 0.0 && b.hi <= 2 * kPi && b.lo <= b.hi);
      for (int j = 0; j < 720; ++j) {
        const double phi3 = 2 * kPi * (j + 0.5) / 720;
        bool ok = true;
        for (int c = 1; c < cf.contacts; ++c)
          ok = ok && std::sqrt(3.0) * std::sin(phi1) * std::sin(phi2) * std::cos(phi3 - cf.centre[c]) <
                         cf.p[c] * std::cos(phi1) + cf.q[c] * std::sin(phi1) * std::cos(phi2);
        if (ok) CHECK(phi3 >= b.lo - 1e-12 && phi3 <= b.hi + 1e-12);
      }
    }
  }
  // C3, theta = 5pi/6: for phi1 below about 0.45 no (phi2, phi3) lets P2 and P3 separate,
  // although the paper says phi1's range stays [0, pi/2)
  const Canonical cf = paper::canonical(kC3);
  for (double phi1 : {0.1, 0.3, 0.44}) {
    bool any = false;
    for (int j = 1; j < 200; ++j)
      for (int l = 0; l < 200; ++l) {
        const double phi2 = kPi * j / 200, phi3 = 2 * kPi * l / 200;
        any = any || std::sqrt(3.0) * std::sin(phi1) * std::sin(phi2) * std::cos(phi3 - cf.centre[1]) <
                         cf.p[1] * std::cos(phi1) + cf.q[1] * std::sin(phi1) * std::cos(phi2);
      }
    CHECK(!any);
  }
}

TEST_CASE("rotation: a rigidly rotated contact gives the rotated post state for the same draws") {
  std::mt19937_64 rng(9);
  const Triple2DPaper op;
  RareLog log;
  for (const P* x : {&kC1, &kC2, &kC3, &kC4}) {
    for (int k = 0; k < 500; ++k) {
      const T v = random_pre(rng, *x);
      const Triple2DPaper::Draws g{uniform01(rng), uniform01(rng), uniform01(rng)};
      const double a = 2 * kPi * uniform01(rng);
      const T post = op.forward(v, *x, g, log);
      const T post_rot = op.forward(rotate(v, a), rigid(*x, a, 2.5, -1.5), g, log);
      CHECK(max_diff(post_rot, rotate(post, a)) <= 1e-12);
    }
  }
}

TEST_CASE("where no fold fires, Procedure 7 inverts Procedure 6 exactly") {
  std::mt19937_64 rng(10);
  const Triple2DPaper op;
  RareLog log;
  for (const P* x : {&kC1, &kC2, &kC3, &kC4}) {
    const Canonical cf = paper::canonical(*x);
    int unfolded = 0;
    for (int k = 0; k < 5000; ++k) {
      const T v = random_pre(rng, *x);
      const Triple2DPaper::Draws g{uniform01(rng), uniform01(rng), uniform01(rng)};
      const auto pre = Triple2DPaper::angles(v, *x);
      const auto psi = op.sampler().psi(g);
      const double a1 = paper::wrap(pre[0] - kPi / 2 + psi[0], kPi / 2);
      const double a2 = paper::wrap(pre[1] + psi[1], kPi);
      const auto b2 = Triple2DPaper::bounds2(cf, a1);
      if (a2 < b2.lo || a2 > b2.hi) continue;
      const auto b3 = Triple2DPaper::bounds3(cf, a1, a2);
      const double a3 = paper::wrap(pre[2] + psi[2]);
      if (a3 < b3.lo || a3 > b3.hi) continue;
      ++unfolded;
      const auto back = op.reverse_angles(cf, op.forward_angles(cf, pre, psi), psi);
      // the reverse tests the candidate against the post bounds: sound only if the
      // candidates fall inside them too
      const auto b2r = Triple2DPaper::bounds2(cf, a1);
      if (pre[1] < b2r.lo || pre[1] > b2r.hi) continue;
      const auto b3r = Triple2DPaper::bounds3(cf, a1, a2);
      if (pre[2] < b3r.lo || pre[2] > b3r.hi) continue;
      for (int c = 0; c < 3; ++c) CHECK_NEAR(back[c], pre[c], 1e-12);
      const T post = op.forward(v, *x, g, log);
      const auto sp = Triple2DPaper::normal_speeds(post, cf);
      // (1e-9, not 1e-12: near phi2 = 0 or pi the velocities carry phi3 only to 1e-16 / sin phi2)
      if (std::all_of(sp.begin(), sp.begin() + cf.contacts, [](double s) { return s > 0; }))
        CHECK(max_diff(op.reverse(post, *x, g, log), v) <= 1e-9);
    }
    CHECK(unfolded > 100);
  }
}

TEST_CASE("as printed, the forward step can fail to separate and the reverse can return another state") {
  std::mt19937_64 rng(11);
  const Triple2DPaper op;
  RareLog log;
  for (const P* x : {&kC1, &kC2, &kC3, &kC4}) {
    const Canonical cf = paper::canonical(*x);
    int invalid = 0, wrong = 0, ok = 0;
    for (int k = 0; k < 4000; ++k) {
      const T v = random_pre(rng, *x);
      const Triple2DPaper::Draws g{uniform01(rng), uniform01(rng), uniform01(rng)};
      const T post = op.forward(v, *x, g, log);
      // momentum and energy are conserved whatever the angles
      double e0 = 0, e1 = 0;
      for (int p = 0; p < 3; ++p) {
        e0 += v[p][0] * v[p][0] + v[p][1] * v[p][1];
        e1 += post[p][0] * post[p][0] + post[p][1] * post[p][1];
      }
      CHECK_NEAR(e1, e0, 1e-12 * e0);
      CHECK_NEAR(post[0][1] + post[1][1] + post[2][1], v[0][1] + v[1][1] + v[2][1], 1e-12);
      const auto s = Triple2DPaper::normal_speeds(post, cf);
      if (!std::all_of(s.begin(), s.begin() + cf.contacts, [](double q) { return q > 0; })) {
        ++invalid;
        CHECK_THROWS_AS(op.reverse(post, *x, g, log), InvalidArgument);
        continue;
      }
      const double err = max_diff(op.reverse(post, *x, g, log), v);
      if (err <= 1e-9) ++ok; else ++wrong;
    }
    CHECK(invalid > 0);
    CHECK(wrong > 0);
    CHECK(ok > 0);
  }
}

TEST_CASE("exactly three draws per collision; validation changes nothing") {
  const Triple2DPaper op;
  RareLog log;
  std::vector<T> v = {T{{{0.5, 0.3}, {-0.5, 0.25}, {0.05, -0.6}}}, T{{{0.5, -0.3}, {-0.5, -0.25}, {0.05, 0.6}}}};
  std::vector<P> x = {kC1, kC2};
  rng::CLCG4 gen(2), ref(2);
  const auto before = v;
  forward_batch(op, v.data(), x.data(), v.size(), gen, log);
  for (int k = 0; k < 6; ++k) ref.next();
  CHECK(gen == ref);
  // C1 and C2 are mirror images: the same draws give mirrored post states
  const Triple2DPaper::Draws g{0.81, 0.27, 0.63};
  const T a = op.forward(before[0], kC1, g, log), b = op.forward(before[1], kC2, g, log);
  for (int p = 0; p < 3; ++p) {
    CHECK_NEAR(a[p][0], b[p][0], 1e-14);
    CHECK_NEAR(a[p][1], -b[p][1], 1e-14);
  }
  // a bad entry: nothing drawn, nothing changed
  std::vector<T> bad = before;
  bad[1] = T{{{-0.5, 0.3}, {0.5, 0.25}, {0.05, -0.6}}};  // P1 and P2 separate
  const auto copy = bad;
  rng::CLCG4 g3(2);
  CHECK_THROWS_AS(forward_batch(op, bad.data(), x.data(), bad.size(), g3, log), InvalidArgument);
  CHECK(g3 == rng::CLCG4(2));
  CHECK(bad == copy);
  const Triple2DPaper::Draws mid{0.5, 0.5, 0.5};
  CHECK_THROWS_AS(op.forward(before[0], kC1, {0.5, 1.5, 0.5}, log), InvalidArgument);
  CHECK_THROWS_AS(op.forward(T{{{0.5, 0.3}, {-0.5, 0.25}, {0.05, std::nan("")}}}, kC1, mid, log), InvalidArgument);
  CHECK_THROWS_AS(op.forward(T{{{0.0, 0.0}, {0.0, 0.0}, {0.0, 0.0}}}, kC1, mid, log), InvalidArgument);
  CHECK_THROWS_AS(op.reverse(before[0], kC1, mid, log), InvalidArgument);  // approaching, not a post state
  const Invariants<2> wrong{{0.05, -0.05}, 9.0};
  CHECK_THROWS_AS(op.forward(before[0], kC1, mid, log, &wrong), InvalidArgument);
}

CHECK_MAIN()
