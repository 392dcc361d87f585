// Mixtures on the lattice engine (equal masses): particle p has radius r_p lattice units, a pair
// meets at r_i + r_j, a centre stays r_p from a wall. Each collision happens at its own pair's
// contact distance and each reflection at the particle's own wall distance (checked on every
// event record); binary mixtures and a polydisperse gas run forward and back bit for bit in
// 2D and 3D, periodic and walled, exact and specular modes, cells and neighbour lists, also to a
// midpoint; a checkpoint resumes bit for bit; the journal rolls a mixture back exactly; the
// parallel engine commits the sequential run's bits; bad radii are refused by name.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "check.hpp"
#include "lattice_gas_util.hpp"
#include "revcol/error.hpp"
#include "revcol/lattice/engine.hpp"
#include "revcol/lattice/parallel_run.hpp"
#include "revcol/rng/philox.hpp"

using namespace revcol::lattice;
namespace en = revcol::engine;
using lattice_test::EngineOf;

namespace {

// Diameters: a binary mixture (every other particle 1 / ratio) or, ratio <= 0, a polydisperse
// gas (Gaussian, 10% relative width, cut at 3 widths).
std::vector<double> diameters(std::size_t n, double ratio, std::uint32_t seed) {
  std::vector<double> d(n, 1.0);
  if (ratio > 0.0) {
    for (std::size_t p = 1; p < n; p += 2) d[p] = 1.0 / ratio;
    return d;
  }
  revcol::rng::Philox g({0xABCDu, seed}, 0);
  for (double& x : d) {
    double z;
    do {
      z = std::sqrt(-2.0 * std::log(g.next())) * std::cos(6.283185307179586 * g.next());
    } while (std::fabs(z) > 3.0);
    x = 1.0 + 0.1 * z;
  }
  return d;
}

template <std::size_t D>
EngineOf<D> make_mix(std::size_t n, double phi, en::Boundary kind, std::uint32_t seed, double ratio,
                     revcol::Mode mode = revcol::Mode::exact) {
  LatticeConfigN<D> c;
  for (std::size_t k = 0; k < D; ++k) {
    c.wall[k] = en::has_walls(kind);
    c.bounce[k] = kind == en::Boundary::bounce;
  }
  c.seed = seed;
  c.diameters = diameters(n, ratio, seed);
  const LatticeStartN<D> s = random_start(c, n, phi, seed);
  REQUIRE(s.radius.size() == n);
  return {s.units, s.x, s.v, s.radius, seed, operator_for(s.units), 0, mode};
}

// Every event of a forward run against the sizes: a pair's post points at its tick are outside
// r_i + r_j and within 8 vmax of it (the pre points overlapped there, each post point is within
// 2 vmax of its pre point), so a pair meeting at any other distance (sigma, or another pair's)
// fails; every centre stays its radius inside the walls, and a reflection puts it within
// 2 vmax of its own wall distance. Returns the pair collisions per kind (small-small, mixed,
// large-large: by radius against the median).
template <std::size_t D>
std::array<std::size_t, 3> check_events(const std::vector<EventRecordN<D>>& events, const SnapshotN<D>& s) {
  const UnitsN<D>& u = s.units;
  std::vector<std::int64_t> sorted = s.radius;
  std::sort(sorted.begin(), sorted.end());
  const std::int64_t median = sorted[sorted.size() / 2];
  std::array<std::size_t, 3> kinds{};
  for (const auto& r : events) {
    for (std::size_t m = 0; m < r.ids.size(); ++m) {
      const std::int64_t rp = s.radius[static_cast<std::size_t>(r.ids[m])];
      for (std::size_t k = 0; k < D; ++k)
        if (u.wall[k]) CHECK(r.x[m][k] >= rp && r.x[m][k] <= u.L[k] - rp);
    }
    if (r.kind == EventRecordN<D>::wall) {
      const std::int64_t rp = s.radius[static_cast<std::size_t>(r.ids[0])];
      for (std::size_t k = 0; k < D; ++k)
        if (r.axes >> k & 1u) CHECK(std::min(r.x[0][k] - rp, u.L[k] - rp - r.x[0][k]) <= 2 * u.vmax);
    }
    if (r.kind != EventRecordN<D>::pair) continue;
    const std::int64_t ri = s.radius[static_cast<std::size_t>(r.ids[0])], rj = s.radius[static_cast<std::size_t>(r.ids[1])];
    VecN<D> d;
    for (std::size_t k = 0; k < D; ++k) {
      const std::int64_t x = r.x[0][k] - r.x[1][k];
      d[k] = u.wall[k] ? x : min_image(x, u.L[k]);
    }
    const u128 d2 = norm2(d);
    CHECK(d2 >= contact2(ri + rj));
    CHECK(d2 < contact2(ri + rj + 8 * u.vmax));
    ++kinds[static_cast<std::size_t>((ri >= median) + (rj >= median))];
  }
  return kinds;
}

// forward `c` collisions (events checked), on to 2c, back to c and to the start: bit for bit
template <std::size_t D>
void round_trip(EngineOf<D> e, std::uint64_t c, const char* what, double shell = -2.0) {
  if (shell > -2.0) e.set_list_shell(shell);
  const SnapshotN<D> s0 = e.snapshot();
  std::vector<EventRecordN<D>> events;
  e.events = &events;
  CHECK(e.run(c, tick_limit - 1) == c);
  e.events = nullptr;
  const auto kinds = check_events<D>(events, s0);
  const SnapshotN<D> s1 = e.snapshot();
  CHECK(s1.radius == s0.radius);
  CHECK(e.run(c, tick_limit - 1) == c);
  e.run_back(c, e.origin());
  CHECK(same_state(e.snapshot(), s1));
  e.run_back(0, e.origin());
  CHECK(same_state(e.snapshot(), s0));
  std::printf("  %s: pair collisions small-small %zu, mixed %zu, large-large %zu; walls %llu; redraws logged %zu\n", what,
              kinds[0], kinds[1], kinds[2], static_cast<unsigned long long>(e.counters().walls), s1.log.size());
  CHECK(kinds[1] > 0);
  CHECK(kinds[0] + kinds[2] > 0);
}

}  // namespace

TEST_CASE("2D binary mixture (size ratio 1.4, area fraction 0.5): forward, to a midpoint and back bit for bit") {
  round_trip<2>(make_mix<2>(400, 0.5, en::Boundary::periodic, 3, 1.4), 6000, "2D periodic, cells");
  round_trip<2>(make_mix<2>(400, 0.5, en::Boundary::wall, 4, 1.4), 6000, "2D walls, cells");
  round_trip<2>(make_mix<2>(400, 0.5, en::Boundary::periodic, 5, 1.4), 6000, "2D periodic, lists", 0.8);
  round_trip<2>(make_mix<2>(300, 0.4, en::Boundary::bounce, 6, 1.4), 4000, "2D bounce-back walls");
}

TEST_CASE("3D binary mixture (size ratio 1.4, packing fraction 0.4): forward, to a midpoint and back bit for bit") {
  round_trip<3>(make_mix<3>(400, 0.4, en::Boundary::periodic, 7, 1.4), 6000, "3D periodic, lists (automatic)");
  // (a random start places every particle as one of the largest: in walls, 0.3 here)
  round_trip<3>(make_mix<3>(400, 0.3, en::Boundary::wall, 8, 1.4), 6000, "3D walls, cells", 0.0);
}

TEST_CASE("polydisperse gases (Gaussian diameters, 10% width) and the specular mode") {
  round_trip<2>(make_mix<2>(400, 0.45, en::Boundary::periodic, 9, 0.0), 5000, "2D polydisperse");
  round_trip<3>(make_mix<3>(400, 0.25, en::Boundary::wall, 10, 0.0), 5000, "3D polydisperse, walls");
  round_trip<2>(make_mix<2>(300, 0.4, en::Boundary::wall, 11, 1.4, revcol::Mode::specular), 4000, "2D specular, walls");
  round_trip<3>(make_mix<3>(300, 0.35, en::Boundary::periodic, 12, 1.4, revcol::Mode::specular), 4000, "3D specular");
}

TEST_CASE("dense mixtures from relaxed starts (past the crystal of the largest): forward, midpoint, back bit for bit") {
  // as the largest, a 1:1 mixture of ratio 1.4 fits up to about 0.5 (3D) and 0.62 (2D): these
  // start by relaxing overlaps (engine/init.hpp, "auto" falls back to it)
  round_trip<2>(make_mix<2>(400, 0.80, en::Boundary::periodic, 13, 1.4), 6000, "2D binary 0.80, periodic");
  round_trip<3>(make_mix<3>(400, 0.58, en::Boundary::periodic, 14, 1.4), 6000, "3D binary 0.58, periodic");
  round_trip<3>(make_mix<3>(400, 0.55, en::Boundary::wall, 15, 1.4), 5000, "3D binary 0.55, walls");
  round_trip<3>(make_mix<3>(400, 0.58, en::Boundary::periodic, 16, 0.0), 5000, "3D polydisperse 0.58");
}

TEST_CASE("a mixture of one size is the one-diameter gas, bit for bit") {
  for (const auto kind : {en::Boundary::periodic, en::Boundary::wall}) {
    EngineOf<3> mono = lattice_test::make_gas<3>(500, 0.35, kind, 17);
    const SnapshotN<3> s = mono.snapshot();
    EngineOf<3> mix(s.units, s.x, s.v, std::vector<std::int64_t>(s.x.size(), s.units.sigma / 2), s.seed, operator_for(s.units));
    mono.run(5000, tick_limit - 1);
    mix.run(5000, tick_limit - 1);
    SnapshotN<3> a = mono.snapshot(), b = mix.snapshot();
    CHECK(b.radius.size() == s.x.size());
    b.radius.clear();
    CHECK(same_state(a, b));
  }
}

TEST_CASE("a mixture's checkpoint resumes bit for bit, in any storage order") {
  EngineOf<3> a = make_mix<3>(300, 0.4, en::Boundary::periodic, 13, 1.4);
  a.run(2000, tick_limit - 1);
  const SnapshotN<3> s = a.snapshot();
  std::vector<std::uint32_t> order(s.x.size());
  for (std::size_t p = 0; p < order.size(); ++p) order[p] = static_cast<std::uint32_t>(order.size() - 1 - p);
  EngineOf<3> b(s, operator_for(s.units, s.law)), c(s, operator_for(s.units, s.law), order);
  a.run(3000, tick_limit - 1);
  b.run(3000, tick_limit - 1);
  c.run(3000, tick_limit - 1);
  CHECK(same_state(a.snapshot(), b.snapshot()));
  CHECK(same_state(a.snapshot(), c.snapshot()));
  // a snapshot without its radii is another gas: refused (its large-diameter pairs overlap)
  SnapshotN<3> mono = s;
  mono.radius.clear();
  CHECK(lattice_test::refused([&] { EngineOf<3> d(mono, operator_for(mono.units, mono.law)); }, "overlap"));
}

TEST_CASE("the journal rolls a mixture back by reverse computation, and the parallel engine commits its bits") {
  EngineOf<2> e = make_mix<2>(400, 0.5, en::Boundary::wall, 14, 1.4);
  const SnapshotN<2> s0 = e.snapshot();
  EngineOf<2> ref(s0, operator_for(s0.units, s0.law));
  ref.run(1500, tick_limit - 1);
  const SnapshotN<2> at = ref.snapshot();
  e.keep_journal(true);
  e.run(4000, tick_limit - 1);
  e.rollback(1500);
  CHECK(same_state(e.snapshot(), at));
  // K = 3 LPs on 2 workers against the sequential run
  EngineOf<3> seq = make_mix<3>(2000, 0.4, en::Boundary::periodic, 15, 1.4);
  const SnapshotN<3> t0 = seq.snapshot();
  EngineOf<3> par(t0, operator_for(t0.units, t0.law));
  seq.run(20000, tick_limit - 1);
  const ParallelReport r = run_parallel(par, 20000, tick_limit - 1, lattice_test::run_config<TimeWarp<EngineOf<3>>::Config>(3, 2));
  CHECK(r.collisions == 20000);
  CHECK(r.parallel > 0);
  CHECK(same_state(par.snapshot(), seq.snapshot()));
  run_parallel_back(par, 0, t0.clock, lattice_test::run_config<TimeWarp<EngineOf<3>>::Config>(3, 2));
  CHECK(same_state(par.snapshot(), t0));
}

TEST_CASE("bad radii are refused by name, nothing built") {
  EngineOf<2> e = make_mix<2>(50, 0.3, en::Boundary::periodic, 16, 1.4);
  const SnapshotN<2> s = e.snapshot();
  const Units& u = s.units;
  auto with = [&](const std::vector<std::int64_t>& r) {
    return [&s, r] {
      SnapshotN<2> t = s;
      t.radius = r;
      EngineOf<2> f(t, operator_for(t.units, t.law));
    };
  };
  std::vector<std::int64_t> r = s.radius;
  r.pop_back();
  CHECK(lattice_test::refused(with(r), "one entry per particle"));
  r = s.radius;
  r[3] = u.sigma / 2 + 1;
  CHECK(lattice_test::refused(with(r), "is outside [sigma / 32, sigma / 2]"));
  r = s.radius;
  r[4] = u.sigma / 64;
  CHECK(lattice_test::refused(with(r), "is outside [sigma / 32, sigma / 2]"));
  LatticeConfig c;
  c.diameters = {1.0, 0.5, -1.0};
  CHECK(lattice_test::refused([&] { random_start(c, 3, 0.2, 1); }, "finite and > 0"));
  c.diameters = {1.0, 0.5};
  CHECK(lattice_test::refused([&] { random_start(c, 3, 0.2, 1); }, "one entry per particle"));
  c.diameters.assign(100, 1.0);
  c.diameters[7] = 0.05;
  CHECK(lattice_test::refused([&] { random_start(c, 100, 0.2, 1); }, "sigma / 32"));
}

CHECK_MAIN()
