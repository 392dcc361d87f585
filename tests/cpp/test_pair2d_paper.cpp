#include "revcol/collide/pair2d_paper.hpp"

#include <random>

#include "check.hpp"

using namespace revcol;
using V = PairV<2>;

namespace {
double uniform01(std::mt19937_64& rng) {
  return (static_cast<double>(rng() >> 11) + 0.5) * 0x1.0p-53;
}
double max_diff(const V& a, const V& b) {
  double m = 0;
  for (int k = 0; k < 2; ++k)
    m = std::max({m, std::fabs(a.i[k] - b.i[k]), std::fabs(a.j[k] - b.j[k])});
  return m;
}
}  // namespace

TEST_CASE("Procedure 1 gives a separating post state; fixed Procedure 2 inverts it") {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> N(0.0, 1.0);
  const Pair2DPaper op;
  RareLog log;
  for (int k = 0; k < 100000; ++k) {
    V v{{N(rng), N(rng)}, {N(rng), N(rng)}};
    std::array<double, 2> n{N(rng), N(rng)};
    if ((v.i[0] - v.j[0]) * n[0] + (v.i[1] - v.j[1]) * n[1] > 0) n = {-n[0], -n[1]};
    const double g = uniform01(rng);
    const V post = op.forward(v, n, g, log);
    REQUIRE((post.i[0] - post.j[0]) * n[0] + (post.i[1] - post.j[1]) * n[1] > 0);
    CHECK(max_diff(op.reverse(post, n, g, log), v) <= 1e-14 * 8);
  }
}

TEST_CASE("the printed Procedure 2 (testing the post angle) fails about half the time") {
  std::mt19937_64 rng(6);
  const Pair2DPaper printed(true);
  RareLog log;
  const std::array<double, 2> n{1.0, 1.0};
  int wrong = 0;
  const int total = 20000;
  for (int k = 0; k < total; ++k) {
    const V v{{-0.5, -0.25}, {0.75, 0.5}};
    const double g = uniform01(rng);
    const V post = printed.forward(v, n, g, log);
    if (max_diff(printed.reverse(post, n, g, log), v) > 1e-9) ++wrong;
  }
  // the forward step adds pi with probability 1/2, and the printed reverse always subtracts it
  CHECK(wrong > total * 0.45);
  CHECK(wrong < total * 0.55);
}

TEST_CASE("bad input is rejected") {
  const Pair2DPaper op;
  RareLog log;
  const V pre{{1.0, 0.0}, {-1.0, 0.0}};
  CHECK_THROWS_AS(op.forward(pre, {1.0, 0.0}, 0.5, log), InvalidArgument);
  CHECK_THROWS_AS(op.forward(pre, {0.0, 0.0}, 0.5, log), InvalidArgument);
  CHECK_THROWS_AS(op.forward(pre, {-1.0, 0.0}, 1.5, log), InvalidArgument);
  CHECK_THROWS_AS(op.reverse(pre, {-1.0, 0.0}, 0.5, log), InvalidArgument);
  CHECK_THROWS_AS(op.forward(V{{0, 0}, {0, 0}}, {-1.0, 0.0}, 0.5, log), InvalidArgument);
}

CHECK_MAIN()
