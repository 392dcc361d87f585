// Boundary kinds on the lattice engine (engine/boundary_kind.hpp, shared with the float engine):
// bounce-back walls (v -> -v) beside specular walls and periodic axes, forward and back bit for
// bit in 2D and 3D; a bounce reverses the whole velocity where a specular wall flips one
// component; the units carry the kinds and refuse a bounce axis without walls.
#include <cmath>

#include "check.hpp"
#include "revcol/lattice/engine.hpp"

using namespace revcol::lattice;
namespace en = revcol::engine;

namespace {

template <std::size_t D>
using EngineOf = std::conditional_t<D == 2, LatticeEngine, LatticeEngine3D>;

template <std::size_t D>
EngineOf<D> make(std::size_t n, double phi, const std::array<en::Boundary, D>& kinds, std::uint32_t seed) {
  LatticeConfigN<D> c;
  for (std::size_t k = 0; k < D; ++k) {
    c.wall[k] = en::has_walls(kinds[k]);
    c.bounce[k] = kinds[k] == en::Boundary::bounce;
  }
  c.seed = seed;
  const LatticeStartN<D> s = random_start(c, n, phi, seed);
  return {s.units, s.x, s.v, seed, operator_for(s.units)};
}

// forward `collisions`, every wall event recorded, back to the start: bit for bit
template <std::size_t D>
void round_trip(const std::array<en::Boundary, D>& kinds, std::size_t n, std::uint64_t collisions, std::uint32_t seed) {
  EngineOf<D> e = make<D>(n, 0.3, kinds, seed);
  for (std::size_t k = 0; k < D; ++k) CHECK(boundary_of(e.units(), k) == kinds[k]);
  const SnapshotN<D> s0 = e.snapshot();
  std::vector<EventRecordN<D>> events;
  e.events = &events;
  CHECK(e.run(collisions, tick_limit - 1) == collisions);
  // every reflection on a bounce axis reversed the whole velocity; on a specular axis (alone)
  // it flipped the components of the walls met and kept the others
  std::size_t bounces = 0, mirrors = 0;
  for (const auto& r : events) {
    if (r.kind != EventRecordN<D>::wall) continue;
    bool whole = false;
    for (std::size_t k = 0; k < D; ++k) whole = whole || ((r.axes >> k & 1u) && kinds[k] == en::Boundary::bounce);
    for (std::size_t k = 0; k < D; ++k) {
      const bool flips = whole || (r.axes >> k & 1u);
      CHECK(r.v_after[0][k] == (flips ? -r.v_before[0][k] : r.v_before[0][k]));
    }
    ++(whole ? bounces : mirrors);
  }
  bool any_bounce = false, any_wall = false;
  for (std::size_t k = 0; k < D; ++k) {
    any_bounce = any_bounce || kinds[k] == en::Boundary::bounce;
    any_wall = any_wall || kinds[k] == en::Boundary::wall;
  }
  CHECK(bounces > 0 || !any_bounce);
  CHECK(mirrors > 0 || !any_wall);
  e.events = nullptr;
  e.run_back(0, e.origin());
  CHECK(same_state(e.snapshot(), s0));
}

}  // namespace

TEST_CASE("2D bounce-back walls: 20 collisions per particle forward and back bit for bit") {
  round_trip<2>({en::Boundary::bounce, en::Boundary::bounce}, 200, 4000, 11);
}

TEST_CASE("2D channel: periodic x, bounce-back y; and bounce beside a specular wall") {
  round_trip<2>({en::Boundary::periodic, en::Boundary::bounce}, 200, 4000, 12);
  round_trip<2>({en::Boundary::wall, en::Boundary::bounce}, 200, 4000, 13);
}

TEST_CASE("3D bounce-back walls, and a mix of all three kinds") {
  round_trip<3>({en::Boundary::bounce, en::Boundary::bounce, en::Boundary::bounce}, 150, 3000, 14);
  round_trip<3>({en::Boundary::periodic, en::Boundary::bounce, en::Boundary::wall}, 150, 3000, 15);
}

TEST_CASE("a bounce-back channel takes away the tangential momentum; specular walls keep it") {
  // periodic x, walls in y: the x momentum changes only at bounce-back walls
  for (const en::Boundary kind : {en::Boundary::wall, en::Boundary::bounce}) {
    LatticeEngine e = make<2>(150, 0.3, {en::Boundary::periodic, kind}, 16);
    std::vector<EventRecordN<2>> events;
    e.events = &events;
    e.run(3000, tick_limit - 1);
    std::int64_t dpx_walls = 0;
    for (const auto& r : events)
      if (r.kind == EventRecordN<2>::wall) dpx_walls += r.v_after[0][0] - r.v_before[0][0];
    if (kind == en::Boundary::wall) CHECK(dpx_walls == 0);
    else CHECK(dpx_walls != 0);
  }
}

TEST_CASE("units: a bounce axis needs walls; the kinds read back by name") {
  Units u = choose_units({20.0, 20.0}, 1.0, 1.0, {true, false});
  u.bounce = {true, false};
  validate(u);  // fine
  CHECK(boundary_of(u, 0) == en::Boundary::bounce);
  CHECK(boundary_of(u, 1) == en::Boundary::periodic);
  u.bounce = {false, true};
  CHECK_THROWS_AS(validate(u), revcol::InvalidArgument);
  set_boundary(u, 1, en::Boundary::wall);
  CHECK(u.wall[1] && !u.bounce[1]);
  CHECK(en::parse_boundary("bounce") == en::Boundary::bounce);
  CHECK_THROWS_AS(en::parse_boundary("walls"), revcol::InvalidArgument);
}

int main() { return check::run_all(); }
