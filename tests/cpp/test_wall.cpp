#include "revcol/collide/wall.hpp"

#include "revcol/collide/pair1d.hpp"
#include "check.hpp"

using namespace revcol;

TEST_CASE("a particle at a face reflects the normal component only") {
  Box b; b.dim = 2; b.lo = {0, 0, 0}; b.hi = {10, 10, 0};
  const auto v = Wall::forward(b, {0.5, 3.0, 0}, {-1.0, 2.0, 0}, 0.5);
  CHECK(v[0] == 1.0);
  CHECK(v[1] == 2.0);
  const auto back = Wall::reverse(b, {0.5, 3.0, 0}, v, 0.5);
  CHECK(back[0] == -1.0);
  CHECK(back[1] == 2.0);
}

TEST_CASE("at a corner every touched and approached wall reflects") {
  Box b; b.dim = 3; b.lo = {0, 0, 0}; b.hi = {4, 4, 4};
  const std::array<double, 3> x{0.5, 3.5, 0.5};  // touches x-lo, y-hi, z-lo
  const std::array<double, 3> pre{-1.0, 2.0, -3.0};
  const auto post = Wall::forward(b, x, pre, 0.5);
  CHECK(post == (std::array<double, 3>{1.0, -2.0, 3.0}));
  CHECK(Wall::reverse(b, x, post, 0.5) == pre);
  // the engine reverses with -reverse(-u) on the time-reversed velocity u = -post
  auto neg = [](std::array<double, 3> a) { for (auto& c : a) c = -c; return a; };
  CHECK(neg(Wall::reverse(b, x, neg(neg(post)), 0.5)) == neg(pre));
  // grazing a touched wall (zero normal velocity) leaves that component alone both ways
  const std::array<double, 3> graze{-1.0, 0.0, -3.0};
  const auto gpost = Wall::forward(b, x, graze, 0.5);
  CHECK(gpost == (std::array<double, 3>{1.0, 0.0, 3.0}));
  CHECK(Wall::reverse(b, x, gpost, 0.5) == graze);
  // leaving a touched wall is not one reversible event: (-1,2,3) and (-1,2,-3) would both
  // give (1,-2,3)
  CHECK_THROWS_AS(Wall::forward(b, x, {-1.0, 2.0, 3.0}, 0.5), InvalidArgument);
  CHECK_THROWS_AS(Wall::reverse(b, x, {1.0, -2.0, -3.0}, 0.5), InvalidArgument);
}

TEST_CASE("walls reject particles that touch none or approach none") {
  Box b; b.dim = 2; b.lo = {0, 0, 0}; b.hi = {10, 10, 0};
  CHECK_THROWS_AS(Wall::forward(b, {5, 5, 0}, {1, 1, 0}, 0.5), InvalidArgument);
  CHECK_THROWS_AS(Wall::forward(b, {0.5, 5, 0}, {1, 1, 0}, 0.5), InvalidArgument);
  CHECK_THROWS_AS(Wall::forward(b, {0.5, 5, 0}, {std::nan(""), 1, 0}, 0.5), InvalidArgument);
  Box narrow = b; narrow.hi = {0.9, 10, 0};
  CHECK_THROWS_AS(Wall::forward(narrow, {0.5, 5, 0}, {-1, 1, 0}, 0.5), InvalidArgument);
}

TEST_CASE("pair1d exchanges velocities and is its own inverse") {
  const Pair1D op;
  const PairV<1> pre{{0.25}, {1.5}};  // i right of j (normal +1), j catches up
  const PairV<1> post = op.forward(pre, 1.0);
  CHECK(post.i[0] == 1.5);
  CHECK(post.j[0] == 0.25);
  CHECK(op.reverse(post, 1.0) == pre);
  CHECK_THROWS_AS(op.forward(post, 1.0), InvalidArgument);  // separating
  CHECK_THROWS_AS(op.forward(pre, 0.0), InvalidArgument);
  CHECK_THROWS_AS(op.forward(PairV<1>{{1.0}, {1.0}}, 1.0), InvalidArgument);
}

TEST_CASE("a Wall holds its box: its members give the static forms' results") {
  Box b; b.dim = 3; b.lo = {0, 0, 0}; b.hi = {4, 4, 4};
  const Wall w(b);
  const std::array<double, 3> x{0.5, 3.5, 0.5}, pre{-1.0, 2.0, -3.0};
  CHECK(w.box().hi[1] == 4.0);
  CHECK(w.forward(x, pre, 0.5) == Wall::forward(b, x, pre, 0.5));
  CHECK(w.reverse(x, w.forward(x, pre, 0.5), 0.5) == pre);
  CHECK_THROWS_AS(w.forward({2.0, 2.0, 2.0}, pre, 0.5), InvalidArgument);  // touches no wall
}

CHECK_MAIN()
