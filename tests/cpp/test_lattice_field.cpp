// A uniform field on the lattice engine (field.hpp): the exact quadratic event times against a
// brute-force scan of the ticks, and gases under gravity in 2D and 3D (one size and a mixture,
// exact and specular, specular and bounce-back walls) run forward and back bit for bit, also
// from a midpoint, the same events with and without the prediction's double filter, the
// energy with its potential kept to the lattice's rounding, a checkpoint resumed bit for bit,
// and what a field refuses.
#include <cmath>
#include <random>

#include "check.hpp"
#include "lattice_gas_util.hpp"
#include "revcol/lattice/engine.hpp"

using namespace revcol::lattice;
namespace en = revcol::engine;
using revcol::Mode;

namespace {

template <std::size_t D>
using EngineOf = std::conditional_t<D == 2, LatticeEngine, LatticeEngine3D>;

// the first n >= 1 with a n^2 + b n + c < 0 by scanning (n < limit), or -1
std::int64_t scan_negative(std::int64_t a, std::int64_t b, std::int64_t c, std::int64_t limit) {
  for (std::int64_t n = 1; n < limit; ++n)
    if ((static_cast<i128>(a) * n + b) * n + c < 0) return n;
  return -1;
}

template <std::size_t D>
LatticeStartN<D> start(std::size_t n, double phi, const std::array<en::Boundary, D>& kinds, int axis, double g,
                       std::uint32_t seed, std::vector<double> diameters = {}) {
  LatticeConfigN<D> c;
  for (std::size_t k = 0; k < D; ++k) {
    c.wall[k] = en::has_walls(kinds[k]);
    c.bounce[k] = kinds[k] == en::Boundary::bounce;
  }
  c.gravity[static_cast<std::size_t>(axis)] = g;
  c.seed = seed;
  c.diameters = std::move(diameters);
  return random_start(c, n, phi, seed);
}


// the mean height on the field's axis (lattice units), by the snapshot's positions
template <std::size_t D>
double mean_height(const SnapshotN<D>& s, int axis) {
  double h = 0.0;
  for (const auto& x : s.x) h += static_cast<double>(x[static_cast<std::size_t>(axis)]);
  return h / static_cast<double>(s.x.size());
}

// forward in two halves and back to the midpoint and the start, bit for bit; the same run with
// every candidate pair sent to the exact search ends on the same bits; energy with the potential
// kept; the gas falls (mean height down) and every reflection on the field's axis reverses it
template <std::size_t D>
void round_trip(const LatticeStartN<D>& st, Mode mode, std::uint64_t collisions, std::uint32_t seed, int axis) {
  EngineOf<D> e = lattice_test::engine_of<D>(st, seed, mode);
  CHECK(e.units().gravity[static_cast<std::size_t>(axis)] != 0);
  const SnapshotN<D> s0 = e.snapshot();
  std::vector<EventRecordN<D>> events;
  e.events = &events;
  CHECK(e.run(collisions / 2, tick_limit - 1) == collisions / 2);
  e.events = nullptr;
  const SnapshotN<D> s1 = e.snapshot();
  CHECK(e.run(collisions - collisions / 2, tick_limit - 1) == collisions - collisions / 2);
  const SnapshotN<D> s2 = e.snapshot();
  // a wall met on the field's axis: the velocity there reversed exactly (the tick's move mirrored)
  std::size_t floor_hits = 0;
  for (const auto& r : events)
    if (r.kind == EventRecordN<D>::wall && (r.axes >> axis & 1u)) {
      CHECK(r.v_after[0][static_cast<std::size_t>(axis)] == -r.v_before[0][static_cast<std::size_t>(axis)]);
      ++floor_hits;
    }
  CHECK(floor_hits > 0);
  // energy (kinetic and potential, 2E in lattice units) kept to the lattice's rounding
  const auto E0 = static_cast<double>(energy2(s0.units, s0.x, s0.v)), E2 = static_cast<double>(energy2(s2.units, s2.x, s2.v));
  CHECK(std::fabs(E2 - E0) <= 1e-7 * E0);
  // the gas fell: with g pulling toward 0 (g < 0) its mean height went down
  const double g = static_cast<double>(s0.units.gravity[static_cast<std::size_t>(axis)]);
  CHECK((g < 0 ? 1.0 : -1.0) * (mean_height(s2, axis) - mean_height(s0, axis)) < 0.0);
  // the same events without the double filter, from the midpoint's checkpoint, and back
  lattice_test::check_replays(e, [&] { return lattice_test::engine_of<D>(st, seed, mode); }, s0, s1, s2, collisions);
}

}  // namespace

TEST_CASE("field event times: the exact first tick beyond a bound equals a scan of the ticks") {
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<std::int64_t> coef(-40, 40), cst(0, 400);
  int found = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const std::int64_t a = coef(rng), b = coef(rng) * 7, c = cst(rng);
    const std::int64_t want = scan_negative(a, b, c, 10000);
    const std::int64_t got = first_negative(a, b, c);
    CHECK(got == want);
    found += want > 0;
  }
  CHECK(found > 5000);
  // large values: lattice-sized anchors, speeds and fields (the root checked at the tick and before)
  std::uniform_int_distribution<std::int64_t> big(-(std::int64_t{1} << 40), std::int64_t{1} << 40), hh(1, 1 << 14);
  for (int trial = 0; trial < 2000; ++trial) {
    const std::int64_t x = (std::int64_t{1} << 60) + big(rng), v = big(rng), h = -hh(rng), lo = std::int64_t{1} << 59;
    const std::int64_t hi = (std::int64_t{1} << 62) - 1;
    const std::int64_t n = field_wall_ticks(x, v, h, lo, hi);
    CHECK(n >= 1);  // a falling line always meets the floor
    auto at = [&](std::int64_t m) { return field_point(x, v, h, m); };
    CHECK(at(n) < lo || at(n) > hi);
    CHECK(at(n - 1) >= lo && at(n - 1) <= hi);
  }
  // a line rising 10 n - n^2 peaks at 25 (n = 5): a ceiling at 24 is met at n = 5, one at 25
  // never (the floor far below is met at n = 38: 380 - 1444 < -1000, 370 - 1369 = -999)
  CHECK(first_negative(1, -10, 24) == 5);
  CHECK(first_negative(1, -10, 25) == -1);
  CHECK(first_negative(1, -10, 23) == 4);  // 40 - 16 = 24 > 23; 30 - 9 = 21
  CHECK(field_wall_ticks(0, 10, -1, -1000, 25) == 38);
  CHECK(field_wall_ticks(0, 10, -1, -1000, 24) == 5);
  // an anchor beyond the floor that arrived there moving down reflects on its own tick
  CHECK(field_wall_ticks(-1, -3, -1, 0, 100) == 0);
  // cell exits: a wall side is left to the wall's event
  CHECK(field_exit_ticks(5, 0, -1, 0, 100, true, false) == -1);
  CHECK(field_exit_ticks(5, 0, -1, 0, 100, false, false) == 3);  // 5 - 9 < 0 at n = 3
  CHECK(field_exit_ticks(95, 4, 1, 0, 100, false, false) == 1);  // 95 + 4 + 1 = 100 >= 100
}

TEST_CASE("2D gas under gravity, walls on y: forward and back bit for bit, exact and specular") {
  const std::array<en::Boundary, 2> kinds{en::Boundary::periodic, en::Boundary::wall};
  round_trip<2>(start<2>(200, 0.3, kinds, 1, -0.5, 21), Mode::exact, 6000, 21, 1);
  round_trip<2>(start<2>(200, 0.3, kinds, 1, -0.5, 22), Mode::specular, 6000, 22, 1);
  // pulled toward the upper wall, in a box walled all round with bounce-back sides
  const std::array<en::Boundary, 2> box{en::Boundary::bounce, en::Boundary::wall};
  round_trip<2>(start<2>(150, 0.4, box, 1, 0.8, 23), Mode::exact, 4000, 23, 1);
}

TEST_CASE("3D gas under gravity along z, walls all round; a binary mixture (ratio 1.4) under gravity") {
  const std::array<en::Boundary, 3> kinds{en::Boundary::wall, en::Boundary::wall, en::Boundary::wall};
  round_trip<3>(start<3>(150, 0.3, kinds, 2, -0.5, 31), Mode::exact, 4000, 31, 2);
  round_trip<3>(start<3>(150, 0.3, kinds, 2, -0.5, 32), Mode::specular, 4000, 32, 2);
  std::vector<double> d(200);
  for (std::size_t p = 0; p < d.size(); ++p) d[p] = p % 2 == 0 ? 1.0 : 1.4;
  const std::array<en::Boundary, 2> ch{en::Boundary::periodic, en::Boundary::wall};
  round_trip<2>(start<2>(200, 0.4, ch, 1, -0.5, 33, d), Mode::exact, 6000, 33, 1);
}

TEST_CASE("a field's refusals: a periodic axis, two axes, an odd field, regions along it") {
  LatticeStartN<2> s = start<2>(100, 0.2, std::array<en::Boundary, 2>{en::Boundary::periodic, en::Boundary::wall}, 1, -0.5, 41);
  CHECK(s.units.gravity[1] % 2 == 0 && s.units.gravity[1] < 0);
  CHECK(s.gravity_error < 1e-3);
  UnitsN<2> u = s.units;
  u.gravity = {-2, 0};  // the periodic axis
  CHECK_THROWS_AS(validate(u), revcol::InvalidArgument);
  u.gravity = {0, -3};  // odd
  CHECK_THROWS_AS(validate(u), revcol::InvalidArgument);
  UnitsN<2> w = s.units;
  w.wall = {true, true};
  w.gravity = {-2, -2};  // two axes
  CHECK_THROWS_AS(validate(w), revcol::InvalidArgument);
  LatticeConfigN<2> c;
  c.wall = {false, true};
  c.gravity = {-1.0, 0.0};  // along the periodic axis
  CHECK_THROWS_AS(random_start(c, 100, 0.2, 1), revcol::InvalidArgument);
  c.gravity = {0.0, -1e-12};  // below one lattice unit per tick^2
  CHECK_THROWS_AS(random_start(c, 100, 0.2, 1), revcol::InvalidArgument);
  LatticeEngine e(s.units, s.x, s.v, 41, operator_for(s.units));
  CHECK(e.neighbour_search() == 0);  // 2D: the cell grid unless lists are asked for
  const Snapshot before = e.snapshot();
  lattice_test::check_refusals(e, false, 1);
  // a state whose potential would let a particle pass vmax is refused
  UnitsN<2> strong = s.units;
  strong.gravity[1] = -max_gravity;
  CHECK_THROWS_AS(validate_state(strong, s.x, s.v), revcol::InvalidArgument);
}
int main() { return check::run_all(); }
