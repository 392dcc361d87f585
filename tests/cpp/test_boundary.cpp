// The boundary seam (revcol/engine/boundary.hpp): the periodic axis's nearest image and
// wrap, the wall axis's contact, reflection (agreeing with the wall operator,
// collide/wall.hpp) and wall position, the bounce axis (v -> -v), Boundaries dispatching
// per axis in a mixed box, and the corner rule.
#include "revcol/engine/boundary.hpp"

#include <array>
#include <cmath>
#include <random>

#include "check.hpp"
#include "revcol/collide/wall.hpp"

using namespace revcol;
using namespace revcol::engine;

TEST_CASE("periodic axis: nearest image with its code, and the wrap by L") {
  unsigned code = 9;
  CHECK(PeriodicAxis::image(3.0, 10.0, code) == 3.0 && code == 0u);
  CHECK(PeriodicAxis::image(6.0, 10.0, code) == -4.0 && code == 1u);   // x_j + L is nearer
  CHECK(PeriodicAxis::image(-7.5, 10.0, code) == 2.5 && code == 2u);   // x_j - L is nearer
  CHECK(PeriodicAxis::image(5.0, 10.0, code) == 5.0 && code == 0u);    // a tie keeps d
  double x = 9.9;
  CHECK(PeriodicAxis::wrap(x, 10.2, 10.0) && std::fabs(x + 0.1) < 1e-12);
  x = 0.3;
  CHECK(PeriodicAxis::wrap(x, -0.05, 10.0) && x == 10.3);
  x = 4.0;
  CHECK(!PeriodicAxis::wrap(x, 4.0, 10.0) && x == 4.0);
  std::array<double, 2> v = {1.0, -2.0};
  CHECK(!PeriodicAxis::meets(0.0, -1.0, 10.0, 0.5, 1e-9));  // no walls
  CHECK(PeriodicAxis::reflect<2>(0, v) == 0u && v[0] == 1.0 && v[1] == -2.0);
}

TEST_CASE("wall axis: reflects exactly what the wall operator reflects, on one axis") {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double L = 6.0, r = 0.5, tol = 1e-9;
  Box box;
  box.dim = 1;
  box.lo = {0.0, 0.0, 0.0};
  box.hi = {L, 0.0, 0.0};
  int flipped = 0;
  for (int s = 0; s < 2000; ++s) {
    // a centre at a wall (within tol), approaching it, or elsewhere
    const int where = s % 3;
    const double x = where == 0 ? r + 0.5 * tol * u(rng) : where == 1 ? (L - r) + 0.5 * tol * u(rng) : 3.0 + u(rng);
    const double v0 = u(rng);
    const bool f = WallAxis::meets(x, v0, L, r, tol);
    CHECK(f == WallAxis::touches_ahead(x, v0 > 0.0 ? 1 : 0, L, r, tol));
    if (f) {
      ++flipped;
      std::array<double, 2> v = {v0, 0.25};
      CHECK(WallAxis::reflect<2>(0, v) == 1u);  // its own component only
      CHECK(v[0] == -v0 && v[1] == 0.25);
      // the wall operator gives the same post velocity, and its reverse gives back v0
      const auto post = Wall::forward(box, {x, 0, 0}, {v0, 0, 0}, r, tol);
      CHECK(post[0] == v[0]);
      CHECK(Wall::reverse(box, {x, 0, 0}, post, r, tol)[0] == v0);
    }
    CHECK(WallAxis::touches(x, L, r, tol) == (where != 2));
  }
  CHECK(flipped > 400);  // about half of the 1333 at a wall approach it
  CHECK(WallAxis::wall_at(1, L, r) == L - r);
  CHECK(WallAxis::wall_at(0, L, r) == r);
  unsigned code = 7;
  CHECK(WallAxis::image(5.5, L, code) == 5.5 && code == 0u);  // no images through walls
}

TEST_CASE("a mixed box: each axis answers by its own kind") {
  Config c;
  c.dim = 3;
  c.box = {10.0, 8.0, 6.0};
  c.boundary = {Boundary::wall, Boundary::periodic, Boundary::wall};
  c.diameter = 1.0;
  c.group_tol = 1e-9;
  const Boundaries<3> b(c);
  CHECK(b.walls(0) && b.periodic(1) && b.walls(2) && b.any_walls());
  CHECK(b.length(1) == 8.0);
  unsigned code;
  CHECK(b.image(0, 7.0, code) == 7.0 && code == 0u);
  CHECK(b.image(1, 7.0, code) == -1.0 && code == 1u);
  CHECK(b.shift(1, 1u) == 8.0 && b.shift(1, 2u) == -8.0 && b.shift(1, 0u) == 0.0);
  CHECK(b.meets(0, 0.5, -2.0) && !b.meets(0, 0.5, 2.0));  // receding: not met
  CHECK(!b.meets(1, 0.5, -2.0));                           // periodic: no wall at 0.5
  // a corner (x low, z high): every met wall flips its own component, the periodic axis none
  std::array<double, 3> v = {-2.0, -1.0, 3.0};
  CHECK(b.reflect({0.5, 0.5, 5.5}, v) == 5u);
  CHECK(v == std::array<double, 3>({2.0, -1.0, -3.0}));
  CHECK(b.reflect({0.5, 0.5, 5.5}, v) == 0u);  // now receding from both: nothing met
  v = {-2.0, -1.0, 3.0};
  CHECK(b.reflect_at(0, {0.5, 0.5, 5.5}, v) == 1u);  // a wall event: its own axis; z waits for its own
  CHECK(v == std::array<double, 3>({2.0, -1.0, 3.0}));
  CHECK(b.touches(2, 5.5) && !b.touches(1, 7.5));
  double x = 7.9;
  CHECK(b.wrap(1, x, 8.1) && std::fabs(x + 0.1) < 1e-12);
  x = 9.9;
  CHECK(!b.wrap(0, x, 10.1) && x == 9.9);  // walls never wrap
  CHECK(b.wall_at(2, 1) == 5.5);
  CHECK(b.touches_ahead(2, 5.5, 1) && !b.touches_ahead(2, 5.5, 0));
}

TEST_CASE("reflection masks: each is its own inverse, counted per wall") {
  const std::array<double, 3> v0 = {1.5, -2.0, 0.25};
  for (Reflection m : {0u, 1u, 2u, 5u, 7u, kReversed}) {
    std::array<double, 3> v = v0;
    apply<3>(m, v);
    for (int k = 0; k < 3; ++k) CHECK(v[k] == ((m & kReversed) || (m >> k & 1u) ? -v0[k] : v0[k]));
    apply<3>(m, v);
    CHECK(v == v0);
  }
  CHECK(reflections(0u) == 0 && reflections(5u) == 2 && reflections(kReversed) == 1);
}

TEST_CASE("bounce axis: the walls of a wall axis, but a particle that meets one reverses its whole velocity") {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double L = 6.0, r = 0.5, tol = 1e-9;
  int reversed = 0, left = 0;
  for (int s = 0; s < 2000; ++s) {
    const int where = s % 3;  // at the lower wall, at the upper one, inside
    const double x = where == 0 ? r + 0.5 * tol * u(rng) : where == 1 ? (L - r) + 0.5 * tol * u(rng) : 3.0 + u(rng);
    const std::array<double, 3> v0 = {u(rng), u(rng), u(rng)};
    // the same contact as a wall axis: touching within tol, met only while approaching
    CHECK(BounceAxis::touches(x, L, r, tol) == WallAxis::touches(x, L, r, tol));
    const bool met = BounceAxis::meets(x, v0[1], L, r, tol);
    CHECK(met == WallAxis::meets(x, v0[1], L, r, tol));
    CHECK(met == (where != 2 && (where == 0 ? v0[1] < 0.0 : v0[1] > 0.0)));
    if (!met) {
      ++left;  // receding or away from the walls: nothing to reflect
      continue;
    }
    ++reversed;
    std::array<double, 3> v = v0;
    CHECK(BounceAxis::reflect<3>(1, v) == kReversed);
    for (int k = 0; k < 3; ++k) CHECK(v[k] == -v0[k]);  // every component, not just the normal one
    // its own inverse under time reversal: -v meets the wall again and reflects back to -v0
    std::array<double, 3> w = {-v[0], -v[1], -v[2]};
    CHECK(BounceAxis::meets(x, w[1], L, r, tol));
    BounceAxis::reflect<3>(1, w);
    for (int k = 0; k < 3; ++k) CHECK(w[k] == -v0[k]);
  }
  CHECK(reversed > 400);  // about half of the 1333 at a wall approach it
  CHECK(left > 1000);
  CHECK(BounceAxis::wall_at(1, L, r) == L - r && BounceAxis::wall_at(0, L, r) == r);
  CHECK(BounceAxis::whole && !WallAxis::whole && BounceAxis::walls && !BounceAxis::periodic);
}

TEST_CASE("corners: a bounce wall among the walls met reverses v once; otherwise the met components flip") {
  Config c;
  c.dim = 3;
  c.box = {10.0, 8.0, 6.0};
  c.boundary = {Boundary::wall, Boundary::bounce, Boundary::bounce};
  c.diameter = 1.0;
  c.group_tol = 1e-9;
  const Boundaries<3> b(c);
  CHECK(b.walls(0) && b.walls(1) && b.walls(2) && !b.periodic(1) && b.whole(1) && !b.whole(0));
  const std::array<double, 3> corner = {0.5, 0.5, 5.5};  // x low, y low, z high
  const std::array<double, 3> v0 = {-2.0, -1.0, 3.0};   // approaching all three
  std::array<double, 3> v = v0;
  CHECK(b.reflect(corner, v) == kReversed);  // once: two bounce walls do not undo each other
  CHECK(v == std::array<double, 3>({2.0, 1.0, -3.0}));
  CHECK(b.reflect(corner, v) == 0u);  // receding from every wall: nothing met
  // the wall at x and the bounce wall at y met, z receded from but untouched (mid-box)
  v = {-2.0, -1.0, -3.0};
  CHECK(b.reflect({0.5, 0.5, 3.0}, v) == kReversed);
  CHECK(v == std::array<double, 3>({2.0, 1.0, 3.0}));
  // only the specular wall met (the bounce walls receded from or far): its component flips
  v = {-2.0, 1.0, -3.0};
  CHECK(b.reflect({0.5, 0.5, 5.5}, v) == 1u);
  CHECK(v == std::array<double, 3>({2.0, 1.0, -3.0}));
  // the bounce wall at y met while touching the wall at x receding from it: -v, then x's
  // component flips again so the particle leaves receding from both (mask: y and z flipped)
  v = {1.0, -1.0, -3.0};
  CHECK(b.reflect({0.5, 0.5, 3.0}, v) == 6u);
  CHECK(v == std::array<double, 3>({1.0, 1.0, 3.0}));
  CHECK(b.reflect({0.5, 0.5, 3.0}, v) == 0u);
  // a standalone wall event: its own wall's reflection, whatever else it touches
  v = v0;
  CHECK(b.reflect_at(0, corner, v) == 1u && v == std::array<double, 3>({2.0, -1.0, 3.0}));
  v = v0;
  CHECK(b.reflect_at(2, corner, v) == kReversed && v == std::array<double, 3>({2.0, 1.0, -3.0}));
  // at a corner exactly, receding from the bounce wall at y: -v would approach it at this
  // very instant, so its component flips too (else y and z hand the particle back and forth)
  v = {-2.0, 1.0, 3.0};
  CHECK(b.reflect_at(2, corner, v) == 5u && v == std::array<double, 3>({2.0, 1.0, -3.0}));
  v = {-2.0, 1.0, 3.0};  // a hair inside y's contact: y's own event comes later, nothing more
  CHECK(b.reflect_at(2, {0.5, 0.5 + 1e-12, 5.5}, v) == kReversed && v == std::array<double, 3>({2.0, -1.0, -3.0}));
  // the corner rule is reversible through its mask: applying it again restores v
  for (const auto& x : {corner, std::array<double, 3>{0.5, 0.5, 3.0}})
    for (const auto& w0 : {v0, std::array<double, 3>{1.0, -1.0, -3.0}, std::array<double, 3>{-2.0, 1.0, -3.0}}) {
      std::array<double, 3> w = w0;
      apply<3>(b.reflect(x, w), w);
      CHECK(w == w0);
    }
}

CHECK_MAIN()
