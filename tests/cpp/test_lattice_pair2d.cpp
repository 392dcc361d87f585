// Tests of the exact lattice pair operator (revcol/lattice/pair2d.hpp, cells.hpp): known answers
// from the prototype (tests/data/lattice, made by tests/reference/make_lattice_vectors.py), exact
// round trips over random pre states, post-state validity, refusals, edges, bad input, and the
// post law (KS against the flux law). `test_lattice_pair2d --long N` runs the KS and the X-size
// drift with N samples per state instead of the CI sizes (docs/lattice.md quotes its output).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "check.hpp"
#include "lattice_test_util.hpp"
#include "revcol/error.hpp"
#include "revcol/lattice/pair2d.hpp"

using namespace revcol::lattice;
using revcol::InvalidArgument;
using revcol::Law;

namespace {

using lattice_test::Rng;
using lattice_test::ks_pvalue;
using lattice_test::random_bits;

long g_long = 0;  // --long N: samples per KS state (0: the CI sizes)

using lattice_test::load;

i64 num(const std::string& s) { return std::stoll(s); }
std::uint64_t unum(const std::string& s) { return std::stoull(s); }
i128 sq(i64 a) { return static_cast<i128>(a) * a; }
i128 norm2(const Vec2& v) { return sq(v[0]) + sq(v[1]); }
Vec2 add(const Vec2& a, const Vec2& b) { return {a[0] + b[0], a[1] + b[1]}; }
Vec2 sub(const Vec2& a, const Vec2& b) { return {a[0] - b[0], a[1] - b[1]}; }

// A pre state near the contact point at angle `ang`: -w makes the incidence angle `inc` with
// the outward normal, speed |w| = speed, the phase a uniform fraction of w. Empty when the
// rounding put it out of the contract (the caller draws again).
bool make_pre(i64 sigma, double ang, double inc, double speed, double frac, Vec2& q, Vec2& w) {
  const double a = ang + std::numbers::pi + inc;
  w = {static_cast<i64>(speed * std::cos(a)), static_cast<i64>(speed * std::sin(a))};
  if (w[0] == 0 && w[1] == 0) return false;
  const double s = static_cast<double>(sigma);
  q = {static_cast<i64>(s * std::cos(ang)) - static_cast<i64>(w[0] * frac),
       static_cast<i64>(s * std::sin(ang)) - static_cast<i64>(w[1] * frac)};
  return norm2(q) >= sq(sigma) && norm2(add(q, w)) < sq(sigma);
}

// Forward, post validity, reverse, and (for a refusal) that X_out == X. Returns the refusal.
Refusal round_trip(const LatticePair2D& op, const Vec2& q, const Vec2& w, std::uint64_t g, BitsBack& X,
                   int& bad) {
  Vec2 q2, w2, qb, wb;
  BitsBack X2;
  const BitsBack X0 = X;
  const Refusal r = op.forward(q, w, g, X, q2, w2, X2);
  if (!(X == X0)) ++bad;
  if (r != Refusal::none) {
    if (!(X2 == X0)) ++bad;
    return r;
  }
  const i128 s2 = sq(op.sigma());
  if (!(norm2(q2) >= s2 && norm2(sub(q2, w2)) < s2)) ++bad;
  BitsBack Xb = X2;
  op.reverse(q2, w2, g, Xb, qb, wb);
  if (!(qb == q && wb == w && Xb == X0)) ++bad;
  X = X2;
  return r;
}

// KS of the post angles theta (about the contact normal) against the CDF.
template <class Cdf>
double ks_stat(std::vector<double> th, Cdf cdf) {
  std::sort(th.begin(), th.end());
  const double n = static_cast<double>(th.size());
  double d = 0.0;
  for (std::size_t i = 0; i < th.size(); ++i) {
    const double f = cdf(th[i]);
    d = std::max({d, f - static_cast<double>(i) / n, static_cast<double>(i + 1) / n - f});
  }
  return d;
}

struct LawRun {
  double p = 0, mean_cos = 0, bits_start = 0, bits_end = 0, bits_min = 1e300, bits_max = 0;
  int refusals = 0, bad = 0;
};

// n collisions of one fixed pre state (normal angle phn, incidence inc): the post angles'
// KS p-value against the law, X's size, exact inverse spot checks.
LawRun run_law(Law law, double phn, double inc_deg, long n, std::uint64_t seed, int cell_bits = kCellBits) {
  const i64 sigma = 1LL << 60;
  const LatticePair2D op(sigma, law, cell_bits);
  Vec2 q, w;
  const bool ok = make_pre(sigma, phn, inc_deg * std::numbers::pi / 180.0, std::ldexp(1.0, 41), 0.37, q, w);
  LawRun out;
  if (!ok) {
    out.bad = 1;
    return out;
  }
  const Vec2 p = add(q, w);
  const double pn = std::hypot(static_cast<double>(p[0]), static_cast<double>(p[1]));
  const double nx = static_cast<double>(p[0]) / pn, ny = static_cast<double>(p[1]) / pn;
  Rng rng(seed);
  std::vector<double> th;
  th.reserve(static_cast<std::size_t>(n));
  double sc = 0;
  const lattice_test::ChainStats cs = lattice_test::fixed_pre_chain(op, q, w, n, rng, [&](const Vec2& w2) {
    const double dx = static_cast<double>(w2[0]), dy = static_cast<double>(w2[1]);
    th.push_back(std::atan2(-ny * dx + nx * dy, nx * dx + ny * dy));
    sc += std::cos(th.back());
  });
  out.refusals = static_cast<int>(cs.refusals);
  out.bad = cs.bad;
  out.bits_start = cs.bits_start;
  out.bits_min = cs.bits_min;
  out.bits_max = cs.bits_max;
  out.bits_end = cs.bits_end;
  out.mean_cos = sc / static_cast<double>(n);
  const double pi = std::numbers::pi;
  const double d = law == Law::flux ? ks_stat(th, [](double t) { return (1.0 + std::sin(t)) / 2.0; })
                                    : ks_stat(th, [pi](double t) { return (t + pi / 2) / pi; });
  out.p = ks_pvalue(d, th.size());
  return out;
}

const char* refusal_name(Refusal r) { return to_string(r); }

}  // namespace

// ---------------------------------------------------------------------------------------------
TEST_CASE("cells: boundaries, cells, normals, coefficients, table = lattice_cells.py") {
  const auto rows = load("cells.txt");
  REQUIRE(rows.size() >= 500);
  for (const auto& r : rows) {
    if (r[0] == "B") CHECK(boundary(num(r[1])) == IVec{num(r[2]), num(r[3])});
    if (r[0] == "dir") CHECK(dir_cell(num(r[1]), num(r[2])) == num(r[3]));
    if (r[0] == "normal") CHECK(normal_cell(num(r[1]), num(r[2])) == num(r[3]));
    if (r[0] == "rot") {
      const RotCoef c = rot_coef(num(r[1]));
      CHECK(c.qt == num(r[2]));
      CHECK(c.p == num(r[3]));
      CHECK(c.s == num(r[4]));
    }
    if (r[0] == "cum") CHECK(flux_cum(num(r[1])) == unum(r[2]));
  }
}

TEST_CASE("cells: boundaries monotone, |B| = 2^62, close to cos/sin, exactly symmetric") {
  const double one = std::ldexp(1.0, 62);
  double worst = 0;
  IVec prev = boundary(0);
  for (std::int64_t h = 1; h <= (1LL << 21); ++h) {
    const IVec b = boundary(h);
    if (boundary_x(h) != b.x || boundary_y(h) != b.y) CHECK(boundary_x(h) == b.x && boundary_y(h) == b.y);
    const i128 cr = static_cast<i128>(prev.x) * b.y - static_cast<i128>(prev.y) * b.x;
    const i128 dt = static_cast<i128>(prev.x) * b.x + static_cast<i128>(prev.y) * b.y;
    if (!(cr > 0 && dt > 0)) CHECK(cr > 0 && dt > 0);
    if (h % 61 == 0) {
      const double a = 2.0 * std::numbers::pi * static_cast<double>(h) / std::ldexp(1.0, 21);
      worst = std::max({worst, std::fabs(b.x / one - std::cos(a)), std::fabs(b.y / one - std::sin(a))});
    }
    prev = b;
  }
  CHECK(worst < 1e-15);
  CHECK(boundary(0) == IVec{1LL << 62, 0});
  CHECK(boundary(1LL << 18).x == boundary(1LL << 18).y);
  std::mt19937_64 rng(5);
  for (int i = 0; i < 20000; ++i) {
    const i64 wx = static_cast<i64>(rng() >> (2 + rng() % 60)) - static_cast<i64>(rng() >> (2 + rng() % 60));
    const i64 wy = static_cast<i64>(rng() >> (2 + rng() % 60)) - static_cast<i64>(rng() >> (2 + rng() % 60));
    if (wx == 0 && wy == 0) continue;
    const std::int64_t k = dir_cell(wx, wy);
    CHECK(in_cell(wx, wy, k));
    CHECK(!in_cell(wx, wy, (k + 1) & (kCells - 1)));
    CHECK(!in_cell(wx, wy, (k - 1) & (kCells - 1)));
    for (int t = 1; t < 4; ++t) {
      const IVec r = rot90({wx, wy}, t);
      CHECK(dir_cell(r.x, r.y) == ((k + t * kQuarterTurn) & (kCells - 1)));
    }
    // the exact cell is the floating-point floor(atan2) within one cell
    const double a = std::atan2(static_cast<double>(wy), static_cast<double>(wx));
    const double fk = std::floor(a / (2 * std::numbers::pi) * static_cast<double>(kCells));
    const std::int64_t kf = static_cast<std::int64_t>(fk) & (kCells - 1);
    CHECK(std::llabs(((k - kf + kHalfTurn) & (kCells - 1)) - kHalfTurn) <= 1);
  }
}

TEST_CASE("half_cell and coarse_cell agree with dir_cell, on random vectors and on the boundaries themselves") {
  auto check_one = [](i64 wx, i64 wy) {
    const std::int64_t k = dir_cell(wx, wy);
    const std::int64_t h = half_cell(wx, wy);
    const i128 mid = static_cast<i128>(boundary(2 * k + 1).x) * wy - static_cast<i128>(boundary(2 * k + 1).y) * wx;
    const std::int64_t want = 2 * k + (mid >= 0 ? 1 : 0);
    if (h != want) CHECK(h == want);
    for (int shift : {0, 2, 4, 8}) {
      IVec b0{}, b1{};
      const std::int64_t c = coarse_cell(wx, wy, shift, b0, b1);
      if (c != (k >> shift)) CHECK(c == (k >> shift));
      const bool same = b0 == boundary((2 * c) << shift) && b1 == boundary((2 * c + 2) << shift);
      if (!same) CHECK(same);
    }
  };
  std::mt19937_64 rng(11);
  for (int i = 0; i < 20000; ++i) {
    const i64 wx = static_cast<i64>(rng() >> (2 + rng() % 60)) - static_cast<i64>(rng() >> (2 + rng() % 60));
    const i64 wy = static_cast<i64>(rng() >> (2 + rng() % 60)) - static_cast<i64>(rng() >> (2 + rng() % 60));
    if (wx == 0 && wy == 0) continue;
    check_one(wx, wy);
  }
  // exactly on a boundary or a half-cell point (the >= / < ties), and one unit either side,
  // at every octant and near the wrap at angle 0
  for (std::int64_t h : {0LL, 1LL, 2LL, 7LL, 8LL, (1LL << 18) - 1, 1LL << 18, (1LL << 18) + 1, (1LL << 19) + 3,
                         (1LL << 20) + 5, (1LL << 21) - 8, (1LL << 21) - 1}) {
    const IVec b = boundary(h);
    for (const IVec& v : {b, IVec{b.x >> 20, b.y >> 20}, IVec{b.x + 1, b.y}, IVec{b.x, b.y + 1}, IVec{b.x - 1, b.y}})
      if (v.x != 0 || v.y != 0) check_one(v.x, v.y);
    CHECK(half_cell(b.x, b.y) == (h & ((1LL << 21) - 1)));
  }
  CHECK_THROWS_AS(half_cell(0, 0), InvalidArgument);
}

TEST_CASE("flux table: every f >= 1, total 2^48, decode exact at every boundary") {
  CHECK(flux_cum(0) == 0);
  CHECK(flux_cum(kHalfTurn) == (1ULL << 48));
  std::uint64_t fmin = ~0ULL, fmax = 0;
  int bad = 0;
  for (std::int64_t a = 0; a < kHalfTurn; ++a) {
    const std::uint64_t c = flux_cum(a), c1 = flux_cum(a + 1);
    if (c1 <= c) ++bad;
    fmin = std::min(fmin, c1 - c);
    fmax = std::max(fmax, c1 - c);
    if (flux_decode(c) != a || flux_decode(c1 - 1) != a) ++bad;
  }
  CHECK(bad == 0);
  CHECK(fmin >= 1000);  // ~2^11 at grazing
  // f(a) ~ 2^48 * (sin(theta_a+1) - sin(theta_a)) / 2 at the centre
  const double fc = std::ldexp(1.0, 47) * 2.0 * std::sin(std::numbers::pi / static_cast<double>(kCells));
  CHECK(std::fabs(static_cast<double>(fmax) / fc - 1.0) < 1e-6);
  std::mt19937_64 rng(9);
  for (int i = 0; i < 100000; ++i) {
    const std::uint64_t s = rng() >> 16;
    std::uint64_t c, f;
    const std::int64_t b = flux_decode(s, c, f);
    if (!(flux_cum(b) <= s && s < flux_cum(b + 1) && c == flux_cum(b) && f == flux_cum(b + 1) - c)) ++bad;
  }
  CHECK(bad == 0);
  const LatticePair2D uni(1LL << 60, Law::uniform);
  CHECK(uni.cum(kHalfTurn) == (1ULL << 48));
  CHECK(uni.decode(uni.cum(12345)) == 12345);
  CHECK(uni.decode(uni.cum(12346) - 1) == 12345);
}

TEST_CASE("face and phase intervals: known answers of the prototype's face_of, lo_pre, lo_post") {
  const auto rows = load("lo.txt");
  REQUIRE(rows.size() >= 500);
  int nnone = 0;
  for (const auto& r : rows) {
    if (r[0] == "face") {
      CHECK(face_of(num(r[1]), num(r[2])) == num(r[3]));
      continue;
    }
    const i128 s2 = sq(num(r[0]));
    const auto a = lo_pre(s2, num(r[1]), static_cast<int>(num(r[2])), num(r[3]), num(r[4]));
    const auto b = lo_post(s2, num(r[1]), static_cast<int>(num(r[2])), num(r[3]), num(r[4]));
    CHECK((r[5] == "none") == !a.has_value());
    CHECK((r[6] == "none") == !b.has_value());
    nnone += (r[5] == "none") + (r[6] == "none");
    if (a && r[5] != "none") CHECK(*a == num(r[5]));
    if (b && r[6] != "none") CHECK(*b == num(r[6]));
  }
  CHECK(nnone > 10);  // the vectors do exercise the "not an interval" branch
}

TEST_CASE("lifting rotation: known answers of the prototype's rotate with given coefficients") {
  const auto rows = load("rotate.txt");
  REQUIRE(rows.size() >= 300);
  for (const auto& r : rows) {
    const RotCoef c{static_cast<int>(num(r[0])), num(r[1]), num(r[2])};
    const IVec w{num(r[3]), num(r[4])};
    const IVec w2 = rotate(w, c);
    CHECK(w2 == IVec{num(r[5]), num(r[6])});
    CHECK(rotate_inv(w2, c) == w);
  }
}

// Rows of op_*.txt: sigma q w G X -> refusal [q2 w2 X2 m m2 jpre jpost].
static void check_op_vectors(const char* file, Law law) {
  const auto rows = load(file);
  REQUIRE(rows.size() >= 150);
  int accepted = 0;
  for (const auto& r : rows) {
    const LatticePair2D op(num(r[0]), law);
    const Vec2 q{num(r[1]), num(r[2])}, w{num(r[3]), num(r[4])};
    const std::uint64_t g = unum(r[5]);
    const BitsBack X = BitsBack::from_hex(r[6]);
    Vec2 q2, w2;
    BitsBack X2;
    Trace tr;
    const Refusal why = op.forward(q, w, g, X, q2, w2, X2, &tr);
    CHECK(std::string(refusal_name(why)) == r[7]);
    if (why != Refusal::none || r[7] != "none") continue;
    ++accepted;
    CHECK(q2 == Vec2{num(r[8]), num(r[9])});
    CHECK(w2 == Vec2{num(r[10]), num(r[11])});
    CHECK(X2.to_hex() == r[12]);
    CHECK(tr.m == num(r[13]));
    CHECK(tr.m2 == num(r[14]));
    CHECK(tr.jpre == num(r[15]));
    CHECK(tr.jpost == num(r[16]));
    BitsBack Xb = X2;
    Vec2 qb, wb;
    op.reverse(q2, w2, g, Xb, qb, wb);
    CHECK(qb == q && wb == w && Xb == X);
  }
  CHECK(accepted * 2 > static_cast<int>(rows.size()));
}

TEST_CASE("whole operator, flux law: = the prototype's C_fwd with these cells and table") {
  check_op_vectors("op_flux.txt", Law::flux);
}

TEST_CASE("whole operator, uniform law: = the prototype's C_fwd with the uniform table") {
  check_op_vectors("op_uniform.txt", Law::uniform);
}

TEST_CASE("pair level: = the prototype's pair_fwd (L = 2^64), and pair_reverse inverts it") {
  const auto rows = load("pair.txt");
  REQUIRE(rows.size() >= 100);
  for (const auto& r : rows) {
    const LatticePair2D op(num(r[0]));
    const std::uint64_t g = unum(r[1]);
    const BitsBack X = BitsBack::from_hex(r[2]);
    auto v = [&](int i) { return Vec2{num(r[static_cast<std::size_t>(3 + 2 * i)]), num(r[static_cast<std::size_t>(4 + 2 * i)])}; };
    Vec2 xi2, xj2, vi2, vj2, xi, xj, vi, vj;
    BitsBack X2;
    REQUIRE(op.pair_forward(v(0), v(1), v(2), v(3), g, X, xi2, xj2, vi2, vj2, X2) == Refusal::none);
    CHECK(xi2 == v(4));
    CHECK(xj2 == v(5));
    CHECK(vi2 == v(6));
    CHECK(vj2 == v(7));
    CHECK(X2.to_hex() == r.back());
    op.pair_reverse(xi2, xj2, vi2, vj2, g, X2, xi, xj, vi, vj);
    CHECK(xi == v(0) && xj == v(1) && vi == v(2) && vj == v(3) && X2 == X);
  }
}

TEST_CASE("round trip: 1.2e5 random pre states, sigma 2^20..2^61, speeds 2^20..2^45, X 64..1024 bits") {
  Rng rng(2026);
  const i64 sigmas[] = {1LL << 61, 1LL << 60, (1LL << 57) + 977, 1LL << 52, (1LL << 45) + 3, 1LL << 40, 1LL << 32, 1LL << 20};
  int bad = 0, accepted = 0, tried = 0, grazing_ok = 0;
  int counts[5] = {0, 0, 0, 0, 0};
  BitsBack X = random_bits(rng.gen, 256);
  for (int i = 0; tried < 120000; ++i) {
    const i64 sigma = sigmas[i % 8];
    // the cell resolution cycles over 20, 16, 12 (i % 3), independently of sigma (i % 8)
    const LatticePair2D op(sigma, (i % 7 == 3) ? Law::uniform : Law::flux, 20 - 4 * (i % 3));
    const int top = std::min(45, static_cast<int>(std::log2(static_cast<double>(sigma))) - 4);
    const double speed = std::ldexp(1.0 + rng.uni(), 20 + static_cast<int>(rng.gen() % static_cast<unsigned>(std::max(1, top - 19))));
    const bool grazing = i % 4 == 0;
    const double inc = grazing ? (rng.uni() < 0.5 ? -1 : 1) * (std::numbers::pi / 2 - std::pow(10.0, -7 + 6 * rng.uni()))
                               : std::asin(2 * rng.uni() - 1);
    Vec2 q, w;
    if (!make_pre(sigma, 2 * std::numbers::pi * rng.uni(), inc, speed, rng.uni(), q, w)) continue;
    ++tried;
    if (i % 50 == 0) X = random_bits(rng.gen, 64 + static_cast<int>(rng.gen() % 961));
    const Refusal r = round_trip(op, q, w, rng.draw(), X, bad);
    ++counts[static_cast<int>(r)];
    accepted += r == Refusal::none;
    grazing_ok += grazing && r == Refusal::none;
  }
  std::printf("  round trip: %d tried, %d accepted (%d grazing), refusals: readback %d, not approaching %d, "
              "empty %d, domain %d\n", tried, accepted, grazing_ok, counts[1], counts[2], counts[3], counts[4]);
  CHECK(bad == 0);
  CHECK(accepted >= 100000);
  CHECK(grazing_ok >= 20000);
}

TEST_CASE("round trip at pair level: S-transform, positions wrapping mod 2^64") {
  Rng rng(77);
  const LatticePair2D op(1LL << 60);
  int bad = 0, accepted = 0;
  BitsBack X = random_bits(rng.gen, 256);
  for (int i = 0; i < 30000; ++i) {
    Vec2 q, w;
    if (!make_pre(op.sigma(), 6.3 * rng.uni(), std::asin(2 * rng.uni() - 1), std::ldexp(1.0 + rng.uni(), 40), rng.uni(), q, w))
      continue;
    const Vec2 xj{static_cast<i64>(rng.gen()), static_cast<i64>(rng.gen())};  // anywhere, wraps
    const Vec2 xi{static_cast<i64>(static_cast<std::uint64_t>(xj[0]) + static_cast<std::uint64_t>(q[0])),
                  static_cast<i64>(static_cast<std::uint64_t>(xj[1]) + static_cast<std::uint64_t>(q[1]))};
    const Vec2 vj{static_cast<i64>((rng.uni() - 0.5) * 0x1p42), static_cast<i64>((rng.uni() - 0.5) * 0x1p42)};
    const Vec2 vi = add(vj, w);
    Vec2 xi2, xj2, vi2, vj2, a, b, c, d;
    BitsBack X2;
    const std::uint64_t g = rng.draw();
    if (op.pair_forward(xi, xj, vi, vj, g, X, xi2, xj2, vi2, vj2, X2) != Refusal::none) continue;
    ++accepted;
    // momentum: +-1 lattice unit per component (the parity of d); relative vector = operator's
    const Vec2 r2{static_cast<i64>(static_cast<std::uint64_t>(xi2[0]) - static_cast<std::uint64_t>(xj2[0])),
                  static_cast<i64>(static_cast<std::uint64_t>(xi2[1]) - static_cast<std::uint64_t>(xj2[1]))};
    if (norm2(r2) < sq(op.sigma()) || norm2(sub(r2, sub(vi2, vj2))) >= sq(op.sigma())) ++bad;
    for (int e = 0; e < 2; ++e)
      if (std::llabs((vi2[e] + vj2[e]) - (vi[e] + vj[e])) > 1) ++bad;
    BitsBack Xb = X2;
    op.pair_reverse(xi2, xj2, vi2, vj2, g, Xb, a, b, c, d);
    if (!(a == xi && b == xj && c == vi && d == vj && Xb == X)) ++bad;
    X = X2;
  }
  CHECK(bad == 0);
  CHECK(accepted > 25000);
}

TEST_CASE("edges: head-on, grazing, each face, axis-parallel, tiny and huge speeds") {
  Rng rng(31);
  int bad = 0, accepted = 0;
  BitsBack X = random_bits(rng.gen, 512);
  const i64 S = 1LL << 60;
  const LatticePair2D op(S);
  // Each face, including p on the diagonals (face 0 and 2 take |px| == |py|, 1 and 3 do not).
  const double faces[] = {0.0, 0.5, 0.785398163397448, 1.5707963, 2.35619449019, 3.14159, 3.9269908, 4.712389, 5.497787};
  int seen[4] = {0, 0, 0, 0};
  for (const double ang : faces) {
    for (int t = 0; t < 200; ++t) {
      Vec2 q, w;
      if (!make_pre(S, ang + 1e-9 * (t - 100), 0.3, 0x1p40, rng.uni(), q, w)) continue;
      const Vec2 p = add(q, w);
      ++seen[face_of(p[0], p[1])];
      accepted += round_trip(op, q, w, rng.draw(), X, bad) == Refusal::none;
    }
  }
  CHECK(seen[0] > 100 && seen[1] > 100 && seen[2] > 100 && seen[3] > 100);
  // Exactly on a diagonal: p = (d, d) is face 0, p = (d, -d) face 2 (strictness at odd faces).
  const i64 dgl = static_cast<i64>(static_cast<double>(S) / std::sqrt(2.0)) - 5;
  for (const Vec2 p : {Vec2{dgl, dgl}, Vec2{dgl, -dgl}, Vec2{-dgl, dgl}, Vec2{-dgl, -dgl}}) {
    const Vec2 w{-p[0] / (1LL << 20), -p[1] / (1LL << 20)};
    accepted += round_trip(op, sub(p, w), w, rng.draw(), X, bad) == Refusal::none;
  }
  CHECK(face_of(dgl, dgl) == 0);
  CHECK(face_of(dgl, -dgl) == 2);
  CHECK(face_of(-dgl, dgl) == 0);
  CHECK(face_of(-dgl, -dgl) == 2);
  // Head-on along the axes and exactly axis-parallel velocities (w = (-V, 0), (-V, 1), ...).
  for (const i64 V : {1LL << 20, (1LL << 33) + 7, 1LL << 45}) {
    for (int f = 0; f < 4; ++f) {
      for (const i64 off : {0LL, 1LL, -1LL}) {
        const IVec wv = rot90({-V, off}, f);
        const IVec pv = rot90({S - V / 3, 0}, f);
        const Vec2 w{wv.x, wv.y}, q{pv.x - wv.x, pv.y - wv.y};
        if (norm2(q) < sq(S) || norm2(add(q, w)) >= sq(S)) continue;
        for (int t = 0; t < 20; ++t) accepted += round_trip(op, q, w, rng.draw(), X, bad) == Refusal::none;
      }
    }
  }
  // Grazing: incidence 90 deg - 1e-9 .. 1e-3.
  for (int t = 0; t < 2000; ++t) {
    Vec2 q, w;
    const double inc = (t & 1 ? 1 : -1) * (std::numbers::pi / 2 - std::pow(10.0, -9 + 6 * rng.uni()));
    if (make_pre(S, 6.28 * rng.uni(), inc, 0x1p40, rng.uni(), q, w))
      accepted += round_trip(op, q, w, rng.draw(), X, bad) == Refusal::none;
  }
  // Tiny speeds (|w| of a few units: most draws refused by the read-back, the rest exact),
  // huge speeds (|w| ~ sigma / 8 and the 2^62 limit at sigma = 2^61).
  const LatticePair2D big(1LL << 61);
  int refused_tiny = 0;
  for (int t = 0; t < 3000; ++t) {
    Vec2 q, w;
    const double speed = (t % 3 == 0) ? 1.0 + 6 * rng.uni() : (t % 3 == 1 ? 0x1p58 : 0x1p61 * (1 + rng.uni()));
    const LatticePair2D& o = (t % 3 == 0) ? op : big;
    if (!make_pre(o.sigma(), 6.28 * rng.uni(), std::asin(2 * rng.uni() - 1), speed, rng.uni(), q, w)) continue;
    if (std::llabs(w[0]) >= (1LL << 62) || std::llabs(w[1]) >= (1LL << 62) || std::llabs(q[0]) >= (1LL << 62) ||
        std::llabs(q[1]) >= (1LL << 62))
      continue;
    const Refusal r = round_trip(o, q, w, rng.draw(), X, bad);
    accepted += r == Refusal::none;
    refused_tiny += (t % 3 == 0) && r != Refusal::none;
  }
  CHECK(refused_tiny > 0);
  CHECK(bad == 0);
  CHECK(accepted > 2500);
}

// A pre state with p within `depth` |w| inside the circle, within `width` |w| along it of one
// of the 4 corners where the circle meets a diagonal, -w within +-spread/2 rad of the normal.
static bool corner_pre(Rng& rng, i64 S, double V, double depth, double width, double spread, Vec2& q, Vec2& w) {
  const double corner = (2 * static_cast<int>(rng.gen() % 4) + 1) * std::numbers::pi / 4;
  const double r = static_cast<double>(S) - V * depth * rng.uni();
  const double ang = corner + (rng.uni() - 0.5) * width * V / static_cast<double>(S);
  const Vec2 p{static_cast<i64>(r * std::cos(ang)), static_cast<i64>(r * std::sin(ang))};
  const double a = ang + std::numbers::pi + (rng.uni() - 0.5) * spread;
  w = {static_cast<i64>(V * std::cos(a)), static_cast<i64>(V * std::sin(a))};
  q = sub(p, w);
  return norm2(q) >= sq(S) && norm2(p) < sq(S);
}

TEST_CASE("face corners: phase intervals that reach the diagonal (odd faces exclude it)") {
  // p within a few |w| of a corner where the circle meets a diagonal: the pre and post phase
  // columns run into the face boundary, and a post phase on the diagonal of an odd face would
  // be read back in the neighbouring face. Round trips must stay exact.
  Rng rng(404);
  const i64 S = 1LL << 40;
  const LatticePair2D op(S);
  BitsBack X = random_bits(rng.gen, 256);
  int bad = 0, accepted = 0, tried = 0;
  for (int t = 0; t < 40000; ++t) {
    const double V = std::ldexp(1.0 + rng.uni(), 18 + static_cast<int>(rng.gen() % 6));
    Vec2 q, w;
    if (!corner_pre(rng, S, V, 1.0, 6.0, 3.0, q, w)) continue;  // inward, up to +-86 deg
    ++tried;
    accepted += round_trip(op, q, w, rng.draw(), X, bad) == Refusal::none;
  }
  std::printf("  corners: %d pre states, %d accepted\n", tried, accepted);
  CHECK(bad == 0);
  CHECK(accepted > 5000);
}

TEST_CASE("face corners: post phases steered onto the lowest point of an odd face's column") {
  // With X = 0 the draw G fixes the post cell b and makes the post phase the lowest of its
  // interval (X after the pops is 0): G = cum(b) - s, s the low 48 bits after the pre pushes.
  // Near a corner that lowest point sits just off the diagonal of an odd face (|x| + 1); a
  // face rule that let the diagonal in would put it on the diagonal, which the reverse reads
  // in the neighbouring face. Every steered forward must invert exactly.
  Rng rng(505);
  const i64 S = 1LL << 40;
  const LatticePair2D op(S);
  int bad = 0, at_diagonal = 0, accepted = 0;
  for (int t = 0; t < 400; ++t) {
    Vec2 q, w;
    if (!corner_pre(rng, S, std::ldexp(1.0 + rng.uni(), 24), 0.5, 2.0, 2.0, q, w) || op.check_pre(q, w) != Refusal::none)
      continue;
    const Vec2 p = add(q, w);
    const int f = face_of(p[0], p[1]);
    const IVec P = rot90({p[0], p[1]}, f), W = rot90({w[0], w[1]}, f);
    const i64 lo = *lo_pre(sq(S), P.x, f & 1, W.x, W.y);
    Trace tr;
    Vec2 q2, w2;
    BitsBack X0, X2;
    (void)op.forward(q, w, 0, X0, q2, w2, X2, &tr);
    BitsBack Xs;  // the pre pushes of the forward, from X = 0
    Xs.push_uniform(static_cast<std::uint64_t>(P.y - lo), static_cast<std::uint64_t>(tr.m));
    const std::uint64_t ca = op.cum(tr.jpre + kQuarterTurn);
    Xs.push_rans(ca, op.cum(tr.jpre + kQuarterTurn + 1) - ca);
    for (int k = 0; k < 64; ++k) {
      const std::int64_t b = (k * 8191 + static_cast<std::int64_t>(rng.gen() % 8191)) % kHalfTurn;
      const std::uint64_t g = (op.cum(b) - Xs.low48()) & (BitsBack::rans_total - 1);
      if (op.forward(q, w, g, X0, q2, w2, X2, &tr) != Refusal::none) continue;
      ++accepted;
      if (!X2.is_zero()) ++bad;  // the steering worked: the post phase is the lowest
      const IVec P2 = rot90({q2[0] - w2[0], q2[1] - w2[1]}, f);
      if ((f & 1) && P2.y == std::llabs(P2.x) + 1) ++at_diagonal;
      BitsBack Xb = X2;
      Vec2 qb, wb;
      op.reverse(q2, w2, g, Xb, qb, wb);
      if (!(qb == q && wb == w && Xb == X0)) ++bad;
    }
  }
  std::printf("  steered: %d accepted, %d next to an odd face's diagonal\n", accepted, at_diagonal);
  CHECK(bad == 0);
  CHECK(at_diagonal > 20);
}

TEST_CASE("small sigma (2 .. 1000): every pre state either refused cleanly or exact") {
  // At a few lattice units per diameter almost every draw is refused by the read-back (w has
  // too few directions); what is accepted must still invert exactly.
  Rng rng(606);
  BitsBack X = random_bits(rng.gen, 128);
  int bad = 0, accepted = 0, tried = 0;
  for (const i64 S : {2LL, 3LL, 5LL, 17LL, 1000LL}) {
    const LatticePair2D op(S);
    for (i64 px = -S; px <= S; ++px)
      for (i64 py = -S; py <= S; ++py)
        for (i64 wx = -3; wx <= 3; ++wx)
          for (i64 wy = -3; wy <= 3; ++wy) {
            const Vec2 p{px * std::max<i64>(1, S / 8), py * std::max<i64>(1, S / 8)}, w{wx * (S + 1) / 3, wy * (S + 1) / 3};
            const Vec2 q = sub(p, w);
            if (norm2(q) < sq(S) || norm2(p) >= sq(S)) continue;
            ++tried;
            accepted += round_trip(op, q, w, rng.draw(), X, bad) == Refusal::none;
          }
  }
  std::printf("  small sigma: %d pre states, %d accepted\n", tried, accepted);
  CHECK(bad == 0);
  CHECK(tried > 1000);
  CHECK(accepted > 0);
}

TEST_CASE("refusals: G-independent ones agree with check_pre; X and X_out stay equal") {
  Rng rng(41);
  const LatticePair2D op(1LL << 60);
  BitsBack X = random_bits(rng.gen, 256);
  int na = 0, other = 0, bad = 0;
  for (int t = 0; t < 20000; ++t) {
    Vec2 q, w;
    // grazing within ~1e-9..1e-5 rad of 90 deg: the normal of the column, quantized, can see
    // such a pre state receding (a G-independent refusal)
    const double inc = (t & 1 ? 1 : -1) * (std::numbers::pi / 2 - std::pow(10.0, -9 + 4 * rng.uni()));
    if (!make_pre(op.sigma(), 6.28 * rng.uni(), inc, 0x1p30, rng.uni(), q, w)) continue;
    const Refusal pre = op.check_pre(q, w);
    const Refusal r = round_trip(op, q, w, rng.draw(), X, bad);
    if (pre != Refusal::none) CHECK(r == pre);
    if (r == Refusal::not_approaching) ++na;
    if (r == Refusal::cell_readback || r == Refusal::empty_post) ++other;
  }
  CHECK(na > 0);
  CHECK(bad == 0);
  (void)other;
}

TEST_CASE("bad input: a clear InvalidArgument, nothing changed") {
  CHECK_THROWS_AS(LatticePair2D(1), InvalidArgument);
  CHECK_THROWS_AS(LatticePair2D((1LL << 61) + 1), InvalidArgument);
  const LatticePair2D op(1LL << 40);
  Rng rng(8);
  const BitsBack X = random_bits(rng.gen, 256);
  BitsBack X2 = X;
  Vec2 q2, w2, a, b;
  const Vec2 q{(1LL << 40) + 5, 0}, w{-(1LL << 20), 3};
  REQUIRE(op.forward(q, w, 5, X, q2, w2, X2) == Refusal::none);
  CHECK_THROWS_AS(op.forward({(1LL << 40) - 5, 0}, w, 5, X, q2, w2, X2), InvalidArgument);   // q inside
  CHECK_THROWS_AS(op.forward(q, {-1, 0}, 5, X, q2, w2, X2), InvalidArgument);               // p outside
  CHECK_THROWS_AS(op.forward(q, w, 1ULL << 48, X, q2, w2, X2), InvalidArgument);            // g too big
  BitsBack Y = X;
  CHECK_THROWS_AS(op.forward(q, w, 5, Y, q2, w2, Y), InvalidArgument);                      // aliasing
  CHECK(Y == X);
  CHECK_THROWS_AS(op.forward({1LL << 62, 0}, w, 5, X, q2, w2, X2), InvalidArgument);        // too large
  CHECK_THROWS_AS(op.check_pre({0, 0}, w), InvalidArgument);
  // reverse: a post state that violates the contract, X untouched
  BitsBack Z = X;
  CHECK_THROWS_AS(op.reverse({(1LL << 40) - 5, 0}, w, 5, Z, a, b), InvalidArgument);       // q2 inside
  CHECK_THROWS_AS(op.reverse(q, {-(1LL << 20), 0}, 5, Z, a, b), InvalidArgument);          // q2-w2 outside
  CHECK_THROWS_AS(op.reverse(q, {1LL << 20, 0}, 1ULL << 48, Z, a, b), InvalidArgument);     // g too big
  CHECK(Z == X);
  // random outgoing post states that no forward produced: exact answer or a throw, X kept
  int thrown = 0, answered = 0;
  for (int t = 0; t < 3000; ++t) {
    Vec2 qq, ww;
    if (!make_pre(op.sigma(), 6.28 * rng.uni(), std::asin(2 * rng.uni() - 1), 0x1p30, rng.uni(), qq, ww)) continue;
    const Vec2 post_q{qq[0] + ww[0], qq[1] + ww[1]};
    const Vec2 post_w{-ww[0], -ww[1]};
    const Vec2 post_q2 = add(post_q, post_w);  // outside again, and post_q2 - post_w = post_q inside
    BitsBack W = BitsBack(std::vector<std::uint64_t>{rng.gen() % 7});  // tiny X: pops may fail
    const BitsBack W0 = W;
    try {
      op.reverse(post_q2, post_w, rng.draw(), W, a, b);
      ++answered;
    } catch (const InvalidArgument&) {
      ++thrown;
      CHECK(W == W0);
    }
  }
  CHECK(thrown + answered > 2000);
  // pair level: velocities beyond 2^61
  Vec2 c, d, e, f;
  BitsBack P = X;
  CHECK_THROWS_AS(op.pair_forward(q, {0, 0}, {1LL << 61, 0}, {0, 0}, 5, X, c, d, e, f, P), InvalidArgument);
  CHECK_THROWS_AS(op.pair_reverse(q, {0, 0}, {0, 1LL << 61}, {0, 0}, 5, P, c, d, e, f), InvalidArgument);
  CHECK(P == X);
}

TEST_CASE("post law: KS against the flux law at 4 fixed pre states (p > 0.001), X bounded, 2^20 and 2^16 cells") {
  const double states[4][2] = {{0.3, 0.0}, {1.1, 45.0}, {2.9, 80.0}, {-2.0, 89.0}};
  const long n = g_long > 0 ? g_long : 20000;
  for (int i = 0; i < 8; ++i) {
    const int cb = i < 4 ? 20 : 16;  // the prototype's cells, the engine's default
    const LawRun r = run_law(Law::flux, states[i % 4][0], states[i % 4][1], n, 100 + static_cast<std::uint64_t>(i), cb);
    std::printf("  flux, 2^%d cells, normal %+.2f rad, incidence %4.1f deg, n %ld: KS p = %.4f, mean cos %.5f (pi/4 = %.5f), "
                "refused %d, X bits %g -> %g (min %g, max %g)\n",
                cb, states[i % 4][0], states[i % 4][1], n, r.p, r.mean_cos, std::numbers::pi / 4, r.refusals, r.bits_start,
                r.bits_end, r.bits_min, r.bits_max);
    CHECK(r.bad == 0);
    CHECK(r.p > 0.001);
    CHECK(std::fabs(r.mean_cos - std::numbers::pi / 4) < 6.0 / std::sqrt(static_cast<double>(n)));
    // X at one fixed pre state: the pushed log2(m / f_pre) and the popped log2(m2 / f_post)
    // balance up to the quantized normal's offset delta from the column's true normal (the
    // same for pre and post): m ~ cos(theta), f ~ cos(theta + delta), so X drifts by
    // -log2(e) delta tan(theta_pre) per collision (E_flux[tan theta_post] = 0), with |delta| <=
    // 1.5 cells (half a cell of the normal, a cell of w's offset). Over a gas of pre states
    // delta tan(theta) averages out: the next test checks X stays bounded there.
    const double cell = 2 * std::numbers::pi / std::ldexp(1.0, cb);
    const double drift = std::log2(std::exp(1.0)) * 1.5 * cell * std::tan(states[i % 4][1] * std::numbers::pi / 180.0);
    CHECK(r.bits_max - r.bits_start < 200 + drift * static_cast<double>(n));
    CHECK(r.bits_start - r.bits_min < 200 + drift * static_cast<double>(n));
  }
}

TEST_CASE("post law, uniform: KS against the uniform angle law; X grows ~1 bit per collision") {
  const long n = g_long > 0 ? std::min(g_long, 100000L) : 20000;
  const LawRun r = run_law(Law::uniform, 0.3, 0.0, n, 7);
  const double rate = (r.bits_end - r.bits_start) / static_cast<double>(n);
  std::printf("  uniform, head-on, n %ld: KS p = %.4f, mean cos %.5f (2/pi = %.5f), X bits %g -> %g: %.4f bit/collision\n",
              n, r.p, r.mean_cos, 2 / std::numbers::pi, r.bits_start, r.bits_end, rate);
  CHECK(r.bad == 0);
  CHECK(r.p > 0.001);
  // head-on pre (cos = 1) and uniform post: E[log2(m/m2)] = -E[log2 cos theta] = 1 bit
  CHECK(rate > 0.9 && rate < 1.1);
}

TEST_CASE("X's size over a gas of pre states: bounded under flux, +0.557 bit/collision under uniform") {
  // Random pre states with flux-law incidence (an equilibrium gas), X chained. Per collision X
  // changes by log2(m f_post / (f_pre m2)), m ~ cos(pre), m2 ~ cos(post): under the flux law
  // (f ~ cos) that is ~0 every time; under the uniform law its mean is
  // E_flux[log2 cos] - E_uniform[log2 cos] = log2(e) (2 ln 2 - 1) = 0.5573 bit.
  const long n = 20000;
  for (const int cb : {20, 16})
  for (const Law law : {Law::flux, Law::uniform}) {
    const LatticePair2D op(1LL << 60, law, cb);
    Rng rng(law == Law::flux ? 61 : 62);
    BitsBack X = random_bits(rng.gen, 256), X2;
    const double start = static_cast<double>(X.bit_length());
    double lo = start, hi = start;
    int bad = 0;
    for (long k = 0; k < n;) {
      Vec2 q, w;
      if (!make_pre(op.sigma(), 6.3 * rng.uni(), std::asin(2 * rng.uni() - 1), std::ldexp(1 + rng.uni(), 40), rng.uni(), q, w) ||
          op.check_pre(q, w) != Refusal::none)
        continue;
      while (round_trip(op, q, w, rng.draw(), X, bad) != Refusal::none) {
      }
      lo = std::min(lo, static_cast<double>(X.bit_length()));
      hi = std::max(hi, static_cast<double>(X.bit_length()));
      ++k;
    }
    const double rate = (static_cast<double>(X.bit_length()) - start) / static_cast<double>(n);
    std::printf("  %s, 2^%d cells: X %g -> %zu bits over %ld collisions (min %g, max %g): %.4f bit/collision\n", to_string(law), cb, start,
                X.bit_length(), n, lo, hi, rate);
    CHECK(bad == 0);
    if (law == Law::flux) CHECK(hi - lo <= 16);
    if (law == Law::uniform) CHECK(std::fabs(rate - 0.5573) < 0.05);
  }
}

int main(int argc, char** argv) {
  for (int i = 1; i + 1 < argc; ++i)
    if (std::strcmp(argv[i], "--long") == 0) g_long = std::atol(argv[i + 1]);
  return check::run_all();
}
