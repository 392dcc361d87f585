// Lees-Edwards shear on the lattice engine (shear.hpp): a line crossing a gradient face comes
// back offset by the images' shift with its flow velocity jumped by the shear, exactly; sheared
// gases in 2D and 3D (exact and specular, walls on the third axis, a binary mixture, either sign)
// run forward and back bit for bit, also from a midpoint, the same events with and without the
// prediction's double filter, a checkpoint resumed bit for bit; the boundary heats the gas;
// an overlap through a moving image is refused; and what shear refuses.
#include <cmath>

#include "check.hpp"
#include "lattice_gas_util.hpp"
#include "revcol/lattice/engine.hpp"

using namespace revcol::lattice;
using lattice_test::EngineOf;
using revcol::Mode;
namespace en = revcol::engine;

namespace {

using lattice_test::sheared_start;

template <std::size_t D>
LatticeStartN<D> start(std::size_t n, double phi, double rate, std::uint32_t seed, bool walls = false,
                       std::vector<double> diameters = {}) {
  return sheared_start<D>(n, phi, rate, seed, walls, std::move(diameters));
}


// sum of v along axis k, 128 bits
template <std::size_t D>
i128 momentum(const SnapshotN<D>& s, std::size_t k) {
  i128 p = 0;
  for (const auto& v : s.v) p += v[k];
  return p;
}

// forward in two halves and back to the midpoint and the start, bit for bit; the same run
// without the double filter and from a checkpoint at the midpoint; the gas heats; specular,
// without group collisions, the gradient momentum is kept and the flow momentum changes by whole jumps
template <std::size_t D>
void round_trip(const LatticeStartN<D>& st, Mode mode, std::uint64_t collisions, std::uint32_t seed) {
  EngineOf<D> e = lattice_test::engine_of<D>(st, seed, mode);
  CHECK(e.units().shear != 0);
  CHECK(e.neighbour_search() == 0);
  const SnapshotN<D> s0 = e.snapshot();
  CHECK(e.run(collisions / 2, tick_limit - 1) == collisions / 2);
  const SnapshotN<D> s1 = e.snapshot();
  CHECK(e.run(collisions - collisions / 2, tick_limit - 1) == collisions - collisions / 2);
  const SnapshotN<D> s2 = e.snapshot();
  // viscous heating: the boundary's work
  CHECK(energy2(s2.units, s2.x, s2.v) > energy2(s0.units, s0.x, s0.v));
  const auto& c = e.counters();  // (the exact operator keeps momentum within a unit per collision)
  if (mode == Mode::specular && c.group_resolves + c.group_bounces + c.drawn_fallbacks == 0) {
    CHECK(momentum(s2, 1) == momentum(s0, 1));
    CHECK((momentum(s2, 0) - momentum(s0, 0)) % s0.units.shear == 0);
  }
  // the same events without the double filter, from the midpoint's checkpoint, and back
  lattice_test::check_replays(e, [&] { return lattice_test::engine_of<D>(st, seed, mode); }, s0, s1, s2, collisions);
}

}  // namespace

TEST_CASE("a line crossing a gradient face: offset by the images' shift, its flow velocity jumped by the shear") {
  UnitsN<2> u = choose_units_d<2>({12.0, 8.0}, 1.0, 1.0, {false, false});
  u.shear = std::int64_t{3} << 30;
  validate(u);
  const std::int64_t s = u.sigma, L0 = u.L[0], L1 = u.L[1];
  // particle 0 near the upper face moving up and along the flow, particle 1 far away at rest-ish
  std::vector<Vec2> x{{L0 / 2, L1 - s}, {L0 / 8, L1 / 2}}, v{{std::int64_t{1} << 28, std::int64_t{1} << 30}, {0, 1}};
  LatticeEngine e(u, x, v, 5, operator_for(u));
  const std::int64_t T = (s / (std::int64_t{1} << 30)) * 3;  // three diameters of rise: across the face
  CHECK(e.run(10, T) == 0);
  CHECK(e.clock() == T);
  const auto xs = e.positions();
  const auto vs = e.velocities();
  const i128 y = static_cast<i128>(x[0][1]) + static_cast<i128>(v[0][1]) * T;
  CHECK(y >= L1);
  CHECK(xs[0][1] == static_cast<std::int64_t>(y - L1));
  CHECK(xs[0][0] == wrap(static_cast<i128>(x[0][0]) + static_cast<i128>(v[0][0]) * T - shear_offset(u, T), L0));
  CHECK(vs[0][0] == v[0][0] - u.shear);
  CHECK(vs[0][1] == v[0][1]);
  CHECK(shear_offset(u, T) == wrap(static_cast<i128>(u.shear) * T, L0));
  e.run_back(0, 0);
  CHECK(e.positions() == x);
  CHECK(e.velocities() == v);
}

TEST_CASE("2D sheared gas: forward and back bit for bit, exact and specular, either sign, a binary mixture") {
  round_trip<2>(start<2>(300, 0.4, 0.5, 21), Mode::exact, 8000, 21);
  round_trip<2>(start<2>(300, 0.4, 0.5, 22), Mode::specular, 8000, 22);
  round_trip<2>(start<2>(300, 0.5, -0.3, 23), Mode::exact, 8000, 23);
  std::vector<double> d(300);
  for (std::size_t p = 0; p < d.size(); ++p) d[p] = p % 2 == 0 ? 1.0 : 1.4;
  round_trip<2>(start<2>(300, 0.5, 0.4, 24, false, d), Mode::exact, 8000, 24);
}

TEST_CASE("3D sheared gas: periodic and with walls on z, exact and specular") {
  round_trip<3>(start<3>(900, 0.3, 0.5, 31), Mode::exact, 8000, 31);
  round_trip<3>(start<3>(900, 0.3, 0.5, 32), Mode::specular, 8000, 32);
  round_trip<3>(start<3>(900, 0.3, 0.4, 33, true), Mode::exact, 8000, 33);
}

TEST_CASE("group collisions forced on every collision, across the gradient faces too: forward and back bit for bit") {
  // (a group stalls in the frame of its first member, so members across a face keep their
  // relative vectors; a bounce negates the velocities in that frame: stall() in group.hpp)
  for (bool resolve : {true, false}) {
    const LatticeStartN<2> st = start<2>(300, 0.5, 0.5, 51);
    LatticeEngine e = lattice_test::engine_of<2>(st, 51, Mode::exact);
    e.max_redraws = -1;  // every collision takes the group path
    e.group_resolve = resolve;
    const Snapshot s0 = e.snapshot();
    e.run(4000, tick_limit - 1);
    const Counters& c = e.counters();
    CHECK(c.group_resolves + c.group_bounces == 4000);
    CHECK(resolve ? c.group_resolves > 3900 : c.group_resolves == 0);
    e.run_back(0, e.origin());
    CHECK(same_state(e.snapshot(), s0));
  }
  const LatticeStartN<3> st = start<3>(900, 0.4, 0.5, 52);
  LatticeEngine3D e = lattice_test::engine_of<3>(st, 52, Mode::specular);
  e.max_redraws = -1;
  const Snapshot3 s0 = e.snapshot();
  e.run(4000, tick_limit - 1);
  e.run_back(0, e.origin());
  CHECK(same_state(e.snapshot(), s0));
}

TEST_CASE("an overlap through a moving image is refused; the plain image's is not an overlap then") {
  UnitsN<2> u = choose_units_d<2>({12.0, 8.0}, 1.0, 1.0, {false, false});
  u.shear = std::int64_t{1} << 30;
  const std::int64_t s = u.sigma, L0 = u.L[0], L1 = u.L[1];
  const std::int64_t T = 4 * (s / u.shear);  // the images above are at + delta(T) = 4 diameters along the flow
  const std::int64_t d = shear_offset(u, T);
  CHECK(d == 4 * s);
  // particle 1 just below the upper face, particle 0 just above the lower one: apart by s / 2 on
  // the gradient axis through the faces; particle 1's image below is at - d along the flow
  std::vector<Vec2> x{{L0 / 2, s / 4}, {wrap(static_cast<i128>(L0 / 2) + d, L0), L1 - s / 4}}, v{{1, 1}, {-1, -1}};
  CHECK_THROWS_AS(validate_state(u, x, v, false, {}, T), revcol::InvalidArgument);
  CHECK_THROWS_AS(LatticeEngine(u, x, v, 1, operator_for(u), T), revcol::InvalidArgument);
  x[1][0] = L0 / 2;  // above particle 0 through the plain image: not an overlap under shear at T
  validate_state(u, x, v, false, {}, T);
  UnitsN<2> still = u;
  still.shear = 0;
  CHECK_THROWS_AS(validate_state(still, x, v, false, {}, T), revcol::InvalidArgument);
}

TEST_CASE("shear's refusals: walls on the flow or gradient, a small box, too fast, with gravity; lists, journal, regions") {
  LatticeStartN<2> s = start<2>(300, 0.4, 0.2, 41);
  CHECK(s.units.shear > 0);
  CHECK(s.shear_error < 1e-6);
  UnitsN<2> u = s.units;
  u.wall = {false, true};
  CHECK_THROWS_AS(validate(u), revcol::InvalidArgument);
  u = s.units;
  u.shear = u.vmax / 4 + 1;
  CHECK_THROWS_AS(validate(u), revcol::InvalidArgument);
  UnitsN<3> g = choose_units_d<3>({12.0, 12.0, 12.0}, 1.0, 1.0, {false, false, true});
  g.gravity[2] = -2;
  g.shear = 1000;
  CHECK_THROWS_AS(validate(g), revcol::InvalidArgument);
  g.gravity[2] = 0;
  g.bounce[2] = true;  // bounce-back walls on z
  CHECK_THROWS_AS(validate(g), revcol::InvalidArgument);
  UnitsN<2> small = choose_units_d<2>({8.0, 8.0}, 1.0, 1.0, {false, false});
  small.shear = 1000;  // 8 diameters along the flow: below 9
  CHECK_THROWS_AS(validate(small), revcol::InvalidArgument);
  LatticeConfigN<2> c;
  c.wall = {false, true};
  c.shear_rate = 0.1;
  CHECK_THROWS_AS(random_start(c, 300, 0.4, 1), revcol::InvalidArgument);
  c.wall = {false, false};
  c.shear_rate = 1e-15;  // below one lattice unit per tick
  CHECK_THROWS_AS(random_start(c, 300, 0.4, 1), revcol::InvalidArgument);
  c.shear_rate = std::nan("");
  CHECK_THROWS_AS(random_start(c, 300, 0.4, 1), revcol::InvalidArgument);
  LatticeEngine e(s.units, s.x, s.v, 41, operator_for(s.units));
  e.run(500, tick_limit - 1);
  const Snapshot before = e.snapshot();
  lattice_test::check_refusals(e, true);
  // a checkpoint of a sheared run resumes (its energy0 is the start's, not its velocities')
  LatticeEngine r(before, operator_for(before.units));
  CHECK(same_state(r.snapshot(), before));
}
int main() { return check::run_all(); }
