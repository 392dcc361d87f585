// Tests of the lattice engine in 3D (issue 14): the 3D geometry (norm2 at the box limit, the
// exact first overlap against brute force), units, quantization and validation in 3D, the 3D cell
// grid, and BasicEngine<LatticePair3D, BitsBack> (LatticeEngine3D) on random sphere gases,
// periodic and walled: forward, back to a midpoint and to the start bit for bit, snapshots, the
// rare log (printed), group collisions forced, and bad input refused with the state unchanged.
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <string>

#include "check.hpp"
#include "lattice_test_util.hpp"
#include "revcol/lattice/engine.hpp"

using namespace revcol::lattice;

namespace {

LatticeStart3 start3(std::size_t n, double phi, std::array<bool, 3> wall, std::uint64_t seed) {
  LatticeConfig3 c;
  c.wall = wall;
  c.seed = static_cast<std::uint32_t>(seed);
  return random_start(c, n, phi, seed);
}

LatticeEngine3D make3(std::size_t n, double phi, std::array<bool, 3> wall, std::uint64_t seed) {
  LatticeStart3 s = start3(n, phi, wall, seed);
  return LatticeEngine3D(s.units, s.x, s.v, static_cast<std::uint32_t>(seed), operator_for(s.units));
}

// true when f throws InvalidArgument naming `word`
template <class F>
bool refuses(F&& f, const char* word) {
  try {
    f();
  } catch (const revcol::InvalidArgument& ex) {
    const bool named = std::string(ex.what()).find(word) != std::string::npos;
    if (!named) std::fprintf(stderr, "message '%s' lacks '%s'\n", ex.what(), word);
    return named;
  }
  return false;
}

void print_counters(const char* what, const LatticeEngine3D& e, std::uint64_t collisions) {
  const Counters& c = e.counters();
  std::printf("  %s: %llu collisions, %llu walls, log entries %llu (%.2e per collision), redraws", what,
              static_cast<unsigned long long>(collisions), static_cast<unsigned long long>(c.walls),
              static_cast<unsigned long long>(c.log_entries),
              static_cast<double>(c.log_entries) / static_cast<double>(collisions));
  for (int k = 1; k < 8; ++k) std::printf(" %s=%llu", redraw_names[k], static_cast<unsigned long long>(c.redraws[k]));
  std::printf(", multi-body %llu, wall-body %llu, groups %llu/%llu\n", static_cast<unsigned long long>(c.multi_body),
              static_cast<unsigned long long>(c.wall_body), static_cast<unsigned long long>(c.group_resolves),
              static_cast<unsigned long long>(c.group_bounces));
}

}  // namespace

TEST_CASE("3D norm2: exact at the 3D box limit (three components of 2^62 - 1)") {
  const std::int64_t m = (std::int64_t{1} << 62) - 1;
  const u128 want = 3 * (static_cast<u128>(m) * static_cast<u128>(m));
  CHECK(norm2(Vec3{m, -m, m}) == want);
  CHECK(want < (u128{1} << 126));  // fits a signed 128-bit integer, with room for a sum of two
  CHECK(norm2(Vec3{3, -4, 12}) == 169);
  CHECK(norm2(Vec2{-5, 12}) == norm2(-5, 12));  // the generic form is the 2D one in 2D
  CHECK(dot(Vec3{1, -2, 3}, Vec3{-4, 5, 6}) == 4);
}

TEST_CASE("3D first_overlap is the first integer tick with |r + w t| < sigma (brute force)") {
  std::mt19937_64 g(71);
  const std::int64_t sigma = 1 << 10;
  const u128 s2 = static_cast<u128>(sigma) * sigma;
  int found = 0, grazing = 0;
  for (int n = 0; n < 20000; ++n) {
    std::uniform_int_distribution<std::int64_t> pos(-2 * sigma, 2 * sigma), vel(-200, 200);
    Vec3 r{pos(g), pos(g), pos(g)}, w{vel(g), vel(g), vel(g)};
    if (n % 3 == 0) w = {vel(g) / 40, vel(g) / 40, vel(g) / 40};  // slow: grazing and long searches
    if (norm2(r) < s2) continue;
    std::int64_t brute = -1;
    for (std::int64_t t = 0; t < 40000; ++t) {
      if (overlaps_at(r, w, t, s2)) {
        brute = t;
        break;
      }
    }
    const std::int64_t got = first_overlap(r, w, s2);
    // the overload with a caller's guess gives the same answer for any guess: right, off by
    // one either way, far, negative, huge, infinite, NaN
    const double b = static_cast<double>(brute);
    for (double guess : {b, b - 0.5, b - 1.0, b + 1.0, b - 1.5, b + 7.0, -3.0, 0.0, 0.25, 1e30,
                         std::numeric_limits<double>::infinity(), std::numeric_limits<double>::quiet_NaN()}) {
      const std::int64_t gg = first_overlap(r, w, s2, guess);
      if (gg != brute) CHECK(gg == brute);
    }
    if (brute >= 0) ++found;
    if (brute > 200) ++grazing;
    CHECK(got == brute);
    if (got != brute) {
      std::fprintf(stderr, "r=(%lld,%lld,%lld) w=(%lld,%lld,%lld): %lld vs brute %lld\n", (long long)r[0], (long long)r[1],
                   (long long)r[2], (long long)w[0], (long long)w[1], (long long)w[2], (long long)got, (long long)brute);
      return;
    }
  }
  std::printf("  %d of 20000 random lines overlap (%d after 200 ticks)\n", found, grazing);
  CHECK(found > 1000);
  CHECK(grazing > 50);
}

TEST_CASE("3D first_overlap at full scale (sigma 2^60, |w| ~ 2^41): the tick before is outside, the tick inside") {
  std::mt19937_64 g(13);
  const std::int64_t sigma = std::int64_t{1} << 60;
  const u128 s2 = static_cast<u128>(sigma) * sigma;
  std::normal_distribution<double> nd;
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  int hits = 0;
  for (int n = 0; n < 5000; ++n) {
    // a random direction d, a distance 1..1.6 sigma, a line aimed near the origin
    double d[3] = {nd(g), nd(g), nd(g)}, e[3] = {nd(g), nd(g), nd(g)};
    const double dl = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (double& a : d) a /= dl;
    const double ed = e[0] * d[0] + e[1] * d[1] + e[2] * d[2];
    for (int k = 0; k < 3; ++k) e[k] -= ed * d[k];  // e perpendicular to d
    const double el = std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
    const double dist = std::ldexp(1.0, 60) * (1.0 + 0.6 * u01(g)), b = 1.1 * u01(g) * std::ldexp(1.0, 60) / dist;
    const double speed = std::ldexp(1.0, 41) * (0.01 + u01(g));
    Vec3 r, w;
    for (int k = 0; k < 3; ++k) {
      r[k] = static_cast<std::int64_t>(dist * d[k]);
      w[k] = static_cast<std::int64_t>(speed * (-d[k] + b * e[k] / el));
    }
    if (norm2(r) < s2) continue;
    const std::int64_t t = first_overlap(r, w, s2);
    for (double guess : {static_cast<double>(t), static_cast<double>(t) + 1.0, static_cast<double>(t) - 2.0}) {
      const std::int64_t gg = first_overlap(r, w, s2, guess);
      if (gg != t) CHECK(gg == t);
    }
    if (t < 0) continue;
    ++hits;
    CHECK(overlaps_at(r, w, t, s2));
    CHECK(t == 0 || !overlaps_at(r, w, t - 1, s2));
  }
  CHECK(hits > 1000);
}

TEST_CASE("3D units: choose_units3 per axis, the 3D box limit 2^62, the 2D limit unchanged") {
  const Units3 u = choose_units3({20.0, 10.0, 40.0}, 1.0, 1.0, {false, true, false});
  CHECK(u.S == 55);  // the longest axis, 40 diameters, stays below 2^61 units
  CHECK(u.L[0] == 20 * u.sigma && u.L[1] == 10 * u.sigma && u.L[2] == 40 * u.sigma);
  CHECK(u.wall[1] && !u.wall[0] && !u.wall[2]);
  CHECK(u.tick_bits == 24);  // the automatic tick, as in 2D
  Units3 big;
  big.S = 8;
  big.sigma = 256;
  big.vmax = 1;
  big.L = {std::int64_t{1} << 61, std::int64_t{1} << 61, (std::int64_t{1} << 62) - 1};
  big.wall = {true, true, true};
  validate(big);  // just inside the 3D limit
  big.L[2] = std::int64_t{1} << 62;
  CHECK(refuses([&] { validate(big); }, "2^62"));
  Units big2;  // the 2D limit stays 2^63 - 2^56
  big2.S = 8;
  big2.sigma = 256;
  big2.vmax = 1;
  big2.L = {std::int64_t{1} << 62, max_box - 1};
  big2.wall = {true, true};
  validate(big2);
  CHECK(refuses([] { choose_units3({20.0, 20.0, 20.0}, 1.0, 1.0, {false, false, false}, 15); }, "tick_bits"));
  CHECK(refuses([] { choose_units3({20.0, 3.0, 20.0}, 1.0, 1.0, {false, false, false}); }, "4.5 diameters"));
}

TEST_CASE("3D quantize and validate_state: n x 3, overlaps across a periodic face, walls, speeds") {
  const Units3 u = choose_units3({10.0, 10.0, 10.0}, 1.0, 1.0, {false, false, true});
  const QuantizedN<3> q = quantize(u, {1.0, 1.0, 1.0, 5.0, 5.0, 5.0}, {1.0, 0.0, 0.0, 0.0, -1.0, 0.0});
  CHECK(q.x.size() == 2);
  CHECK(q.x[1][2] == 5 * u.sigma);
  CHECK(q.max_position_error < 1e-15);
  CHECK(refuses([&] { quantize(u, {1.0, 1.0, 1.0, 5.0}, {1.0, 0.0, 0.0, 0.0}); }, "n x 3"));
  // 0.3 and 9.6 on the periodic x axis are 0.7 apart: an overlap through the face
  CHECK(refuses([&] { quantize(u, {0.3, 5.0, 5.0, 9.6, 5.0, 5.0}, {1.0, 0.0, 0.0, 0.0, 0.0, 0.0}); }, "overlap"));
  CHECK(refuses([&] { quantize(u, {5.0, 5.0, 0.3}, {1.0, 0.0, 0.0}); }, "wall"));
  // the same through the walled z axis is no overlap (no image): accepted
  const QuantizedN<3> w = quantize(u, {5.0, 5.0, 0.6, 5.0, 5.0, 9.4}, {1.0, 0.0, 0.0, 0.0, 0.0, 1.0});
  CHECK(w.x.size() == 2);
  std::vector<Vec3> x = w.x, v = w.v;
  v[0][2] = u.vmax + 1;
  CHECK(refuses([&] { validate_state(u, x, v); }, "faster"));
  CHECK(kinetic2(std::vector<Vec3>{{1, 2, 3}, {0, 0, 4}}) == 30);
}

TEST_CASE("3D cell grid: ids and coordinates agree, every neighbour enumerated once") {
  const Units3 u = choose_units3({30.0, 12.0, 4.5}, 1.0, 1.0, {true, false, false});
  CellGridN<3> g;
  g.build(u, 2000);
  CHECK(g.count(0) >= 5 && g.count(1) >= 5);
  CHECK(g.count(2) == 8);  // a small periodic axis: 8 cells, every one a neighbour
  const int cells = g.count(0) * g.count(1) * g.count(2);
  for (int id = 0; id < cells; ++id) {
    const auto c = g.coords(id);
    CHECK(g.cell_id(Vec3{g.boundary(0, c[0]), g.boundary(1, c[1]), g.boundary(2, c[2])}) == id);
  }
  for (int p = 0; p < 2000; ++p) g.insert(p, (p * 7919) % cells);
  g.remove(5);
  const int id = g.cell_id(Vec3{u.L[0] / 2, 0, u.L[2] / 3});
  std::vector<int> seen(2000, 0);
  g.for_neighbours(id, [&](int q) { ++seen[q]; });
  const auto c = g.coords(id);
  for (int p = 0; p < 2000; ++p) {
    CHECK(seen[p] <= 1);
    if (p == 5) continue;
    const auto d = g.coords((p * 7919) % cells);
    const int d0 = std::abs(d[0] - c[0]), n1 = g.count(1);
    const int d1 = std::min(std::abs(d[1] - c[1]), n1 - std::abs(d[1] - c[1]));  // periodic
    const bool near = d0 <= 1 && d1 <= 1;                                            // axis 2: all
    CHECK(seen[p] == (near ? 1 : 0));
  }
  CHECK(seen[5] == 0);
}

TEST_CASE("3D engine: N = 64..1000, volume fractions 0.1, 0.3, 0.45, periodic and walled: forward, midpoint, back bit for bit") {
  struct Case {
    std::size_t n;
    double phi;
    std::array<bool, 3> wall;
    std::uint64_t collisions;
  };
  const std::array<bool, 3> per{false, false, false}, walls{true, true, true}, slab{false, false, true};
  // (the jittered FCC start of random_state holds 0.45 only where its sites fit: 108 = 4 x 3^3
  // spheres periodic, 500 walled)
  for (const Case c : {Case{64, 0.1, per, 10000}, Case{64, 0.3, per, 10000}, Case{108, 0.45, per, 10000},
                       Case{100, 0.3, walls, 20000}, Case{500, 0.45, walls, 30000}, Case{1000, 0.1, walls, 30000},
                       Case{1000, 0.3, per, 100000}, Case{1000, 0.45, per, 50000}, Case{500, 0.45, slab, 30000}}) {
    LatticeEngine3D e = make3(c.n, c.phi, c.wall, 40 + c.n);
    const Snapshot3 s0 = e.snapshot();
    const u128 E0 = kinetic2(s0.v);
    const auto P0 = LatticeEngine3D::momentum_of(s0.v);
    CHECK(e.run(c.collisions / 2, tick_limit - 1) == c.collisions / 2);
    const Snapshot3 sm = e.snapshot();
    CHECK(e.run(c.collisions - c.collisions / 2, tick_limit - 1) == c.collisions - c.collisions / 2);
    const Snapshot3 s1 = e.snapshot();
    CHECK(e.collisions() == c.collisions);
    CHECK(!same_state(s0, s1));
    CHECK(s1.bits != s0.bits);
    // energy: a random walk of about a unit of |w| per collision; momentum: a unit per axis
    const double dE = (static_cast<double>(kinetic2(s1.v)) - static_cast<double>(E0)) / static_cast<double>(E0);
    CHECK(std::fabs(dE) < 1e-6);
    const auto P1 = LatticeEngine3D::momentum_of(s1.v);
    if (c.wall == per && e.counters().group_bounces == 0)
      for (int k = 0; k < 3; ++k) {
        const double dp = static_cast<double>(P1[k] - P0[k]);
        CHECK(std::fabs(dp) <= static_cast<double>(c.collisions));
      }
    char what[96];
    std::snprintf(what, sizeof what, "N=%zu phi=%.2f %s", c.n, c.phi,
                  c.wall == per ? "periodic" : c.wall == walls ? "walls" : "walls in z");
    print_counters(what, e, c.collisions);
    std::printf("    X %zu -> %zu bits, dE/E %.2e, log held %zu (groups %zu), S = %d, T = %d\n", lattice_test::total_bits(s0),
                lattice_test::total_bits(s1), dE, e.log_size(), e.group_log_size(), s0.units.S, s0.units.tick_bits);
    CHECK(e.log_size() == e.counters().log_entries);
    if (c.wall != per) CHECK(e.counters().walls > 0);
    // back to the midpoint: the forward run's snapshot there, bit for bit
    e.run_back(c.collisions / 2, e.origin());
    CHECK(same_state(e.snapshot(), sm));
    // a snapshot resumes: forward from the midpoint again gives the same end
    LatticeEngine3D f(sm, operator_for(sm.units));
    f.run(c.collisions - c.collisions / 2, tick_limit - 1);
    CHECK(same_state(f.snapshot(), s1));
    // back to the start: positions, velocities, X, streams, clock, log
    e.run_back(0, e.origin());
    const Snapshot3 s2 = e.snapshot();
    const bool ok = same_state(s0, s2);
    if (!ok) std::fprintf(stderr, "%s: round trip not bit for bit\n", what);
    CHECK(ok);
    CHECK(s2.x == s0.x && s2.v == s0.v && s2.streams == s0.streams && s2.bits == s0.bits && s2.clock == s0.clock);
    CHECK(s2.log.empty() && s2.groups.empty());
  }
}

TEST_CASE("3D engine, a coarse tick (T = 16): redraws and rare-log entries, still forward and back bit for bit") {
  for (bool walls : {false, true}) {
    LatticeConfig3 c;
    c.wall = {walls, walls, walls};
    c.tick_bits = 16;  // a tick of 2^-16 diameters: third bodies within one tick are 256 times likelier
    const std::size_t n = walls ? 500 : 1000;
    LatticeStart3 s = random_start(c, n, 0.45, 77);
    LatticeEngine3D e(s.units, s.x, s.v, 77, operator_for(s.units));
    const Snapshot3 s0 = e.snapshot();
    e.run(40000, tick_limit - 1);
    print_counters(walls ? "T=16, N=500 phi=0.45 walls" : "T=16, N=1000 phi=0.45 periodic", e, 40000);
    std::uint64_t redraws = 0;
    for (std::uint64_t r : e.counters().redraws) redraws += r;
    CHECK(redraws > 0);
    CHECK(e.counters().log_entries > 0);
    CHECK(e.log_size() == e.counters().log_entries);
    e.run_back(0, e.origin());
    CHECK(same_state(e.snapshot(), s0));
  }
}

TEST_CASE("3D engine: back by time to a tick between collisions equals forward to that tick") {
  LatticeEngine3D e = make3(150, 0.3, {true, false, true}, 5);
  const Snapshot3 s0 = e.snapshot();
  e.run(6000, tick_limit - 1);
  const std::int64_t t = s0.clock + (e.clock() - s0.clock) / 3;
  e.run_back(0, t);
  CHECK(e.clock() == t);
  const Snapshot3 st = e.snapshot();
  LatticeEngine3D f(s0, operator_for(s0.units));
  f.run(UINT64_MAX, t);
  CHECK(same_state(f.snapshot(), st));
  e.run_back(0, e.origin());
  CHECK(same_state(e.snapshot(), s0));
}

TEST_CASE("3D walls: a collision right after a reflection on one tick; back to the tick before equals forward there") {
  // The reverse undoes such a collision at the forward's tick a - 1 and restores the reflected
  // line, whose point there is beyond the wall: its reflection belongs to that tick (after the
  // tick's collisions), not to the next (where it was once scheduled: the state at a - 1 held a
  // centre beyond the wall, and a collision of the same pair one tick earlier came out of order).
  LatticeConfig3 c;
  c.wall = {true, true, true};
  c.tick_bits = 16;  // coarse ticks: a reflection and a collision on one tick ~ every 30 000 collisions
  LatticeStart3 s = random_start(c, 256, 0.45, 1);
  LatticeEngine3D e(s.units, s.x, s.v, 1, operator_for(s.units));
  const Snapshot3 s0 = e.snapshot();
  std::vector<std::int64_t> ticks;  // the ticks a of such collisions
  for (int k = 0; k < 100000; ++k) {
    const std::uint64_t before = e.counters().wall_body;
    e.run(1, tick_limit - 1);
    if (e.counters().wall_body != before) ticks.push_back(e.clock());
  }
  std::printf("  N = 256, 0.45, walls, T = 16: %zu collisions right after a reflection in 10^5\n", ticks.size());
  CHECK(ticks.size() >= 2);
  const std::int64_t h = s0.units.sigma / 2;
  LatticeEngine3D f(s0, operator_for(s0.units));
  std::vector<Snapshot3> fwd;
  for (std::int64_t a : ticks) {
    f.run(UINT64_MAX, a - 1);
    fwd.push_back(f.snapshot());
  }
  for (std::size_t m = ticks.size(); m-- > 0;) {
    e.run_back(0, ticks[m] - 1);
    const Snapshot3 st = e.snapshot();
    bool inside = true;
    for (const Vec3& x : st.x)
      for (std::size_t k = 0; k < 3; ++k) inside = inside && x[k] >= h && x[k] <= st.units.L[k] - h;
    CHECK(inside);
    CHECK(same_state(st, fwd[m]));
  }
  e.run_back(0, e.origin());
  CHECK(same_state(e.snapshot(), s0));
}

TEST_CASE("3D group collisions forced on every collision (resolve and bounce), periodic and walled, bit for bit") {
  for (bool resolve : {true, false})
    for (bool walls : {false, true}) {
      LatticeEngine3D e = make3(120, 0.3, {walls, walls, walls}, 21);
      e.max_redraws = -1;  // every collision takes the group path
      e.group_resolve = resolve;
      const Snapshot3 s0 = e.snapshot();
      const auto p0 = LatticeEngine3D::momentum_of(s0.v);
      e.run(2000, tick_limit - 1);
      const Counters& c = e.counters();
      CHECK(c.group_resolves + c.group_bounces == 2000);
      CHECK(e.group_log_size() == 2000);
      std::printf("  forced groups, %s, %s: %llu resolves, %llu bounces\n", resolve ? "resolve" : "bounce",
                  walls ? "walls" : "periodic", static_cast<unsigned long long>(c.group_resolves),
                  static_cast<unsigned long long>(c.group_bounces));
      if (resolve) {
        CHECK(c.group_resolves > 1900);
        if (!walls && c.group_bounces == 0) CHECK(LatticeEngine3D::momentum_of(e.velocities()) == p0);
      } else {
        CHECK(c.group_resolves == 0);
      }
      const Snapshot3 s1 = e.snapshot();
      e.run(500, tick_limit - 1);
      e.run_back(2000, e.origin());  // back through 500 group entries to the snapshot
      CHECK(same_state(e.snapshot(), s1));
      // an engine restored from a snapshot holding 2000 group entries runs back through them
      LatticeEngine3D f(s1, operator_for(s1.units));
      f.run_back(0, f.origin());
      CHECK(same_state(f.snapshot(), s0));
      CHECK(f.group_log_size() == 0 && f.log_size() == 0);
    }
}

TEST_CASE("3D engine: bad input is refused with a clear error and the state unchanged") {
  LatticeEngine3D e = make3(100, 0.3, {false, false, false}, 9);
  e.run(1000, tick_limit - 1);
  const Snapshot3 s = e.snapshot();
  CHECK(refuses([&] { e.run_back(2000, e.origin()); }, "ahead"));
  CHECK(refuses([&] { e.run(10, e.clock() - 1); }, "before the clock"));
  Snapshot3 bad = s;
  bad.x[3] = bad.x[4];
  CHECK(refuses([&] { e.restore(bad); }, "overlap"));
  bad = s;
  bad.v[0][2] = s.units.vmax + 1;
  CHECK(refuses([&] { e.restore(bad); }, "faster"));
  bad = s;
  bad.x[7][2] = s.units.L[2];
  CHECK(refuses([&] { e.restore(bad); }, "outside the box"));
  bad = s;
  bad.streams.pop_back();
  CHECK(refuses([&] { e.restore(bad); }, "stream"));
  bad = s;
  bad.units.L[1] = std::int64_t{1} << 62;
  CHECK(refuses([&] { e.restore(bad); }, "2^62"));
  CHECK(refuses([&] { LatticeEngine3D(s, LatticePair3D(s.units.sigma / 2)); }, "sigma"));
  CHECK(refuses([&] { LatticeEngine3D(s, LatticePair3D(s.units.sigma, revcol::Law::flux, 18)); }, "cell_bits"));
  CHECK(refuses([] { start3(10, 0.3, {false, false, false}, 1); }, "4.5 diameters"));
  CHECK(same_state(e.snapshot(), s));
  e.run_back(0, e.origin());
  CHECK(e.collisions() == 0);
}

int main() { return check::run_all(); }
