// Slabs (set_regions): the engine keeps each particle's slab along an axis, with a neutral event
// at the tick its centre enters another one, so a decomposition of the box sees each migration
// at its key. The slabs never change which collisions happen (the same state and trace as without
// them), every particle's slab is its centre's at every stop, and the migrations recorded are
// exactly the slab changes between stops.
#include <cstdio>
#include <vector>

#include "check.hpp"
#include "lattice_gas_util.hpp"
#include "revcol/lattice/engine.hpp"

using namespace revcol::lattice;
namespace en = revcol::engine;
using revcol::Mode;

namespace {

using lattice_test::EngineOf;
using lattice_test::refused;

template <std::size_t D>
void check_slabs(EngineOf<D> e, int axis, int slabs, std::uint64_t collisions, const char* what) {
  e.run(e.size(), tick_limit - 1);
  const SnapshotN<D> s0 = e.snapshot();
  const std::int64_t L = s0.units.L[static_cast<std::size_t>(axis)];
  std::vector<std::int64_t> faces;
  for (int k = 0; k < slabs; ++k) faces.push_back(L / slabs * k + L / (3 * slabs));  // not at 0
  EngineOf<D> a(s0, operator_for(s0.units, s0.law)), b(s0, operator_for(s0.units, s0.law));
  b.set_regions(axis, faces);
  std::vector<std::array<std::int64_t, 3>> ta, tb;
  std::vector<std::array<std::int64_t, 4>> moves;
  a.trace = &ta;
  b.trace = &tb;
  b.migrations = &moves;
  auto slab_of = [&](std::int64_t x) {
    int r = slabs - 1;
    for (int k = 0; k < slabs; ++k)
      if (x >= faces[static_cast<std::size_t>(k)]) r = k;
    return r;
  };
  std::vector<int> last(s0.x.size());
  for (std::size_t p = 0; p < s0.x.size(); ++p) last[p] = slab_of(s0.x[p][static_cast<std::size_t>(axis)]);
  int wrong_slab = 0, wrong_moves = 0;
  std::size_t changes = 0;
  for (std::uint64_t c = 0; c < collisions; c += 10) {
    a.run(10, tick_limit - 1);
    moves.clear();
    b.run(10, tick_limit - 1);
    const SnapshotN<D> s = b.snapshot();
    std::vector<int> now(s.x.size()), net = last;
    for (std::size_t p = 0; p < s.x.size(); ++p) {
      now[p] = slab_of(s.x[p][static_cast<std::size_t>(axis)]);
      if (b.region(static_cast<int>(p)) != now[p]) ++wrong_slab;
    }
    for (const auto& m : moves) {  // each migration from the slab the particle was in
      if (net[static_cast<std::size_t>(m[1])] != m[2] || m[0] > s.clock) ++wrong_moves;
      net[static_cast<std::size_t>(m[1])] = static_cast<int>(m[3]);
    }
    if (net != now) ++wrong_moves;
    changes += moves.size();
    last = now;
  }
  const bool same = same_state(a.snapshot(), b.snapshot()) && ta == tb;
  std::printf("  %s, %d slabs on axis %d: %llu collisions, %zu migrations; same run as without slabs: %s, slabs right: %s\n",
              what, slabs, axis, static_cast<unsigned long long>(collisions), changes, same ? "yes" : "NO",
              wrong_slab == 0 && wrong_moves == 0 ? "yes" : "NO");
  CHECK(same);
  CHECK(wrong_slab == 0);
  CHECK(wrong_moves == 0);
  CHECK(changes > 0);
  // and back: the reverse runs with the slabs too, and comes back
  b.run_back(s0.collisions, s0.clock);
  CHECK(same_state(b.snapshot(), s0));
}

}  // namespace

TEST_CASE("slabs see every migration at its tick and change no collision (2D and 3D, walls and periodic)") {
  using B = en::Boundary;
  check_slabs<2>(lattice_test::make_gas<2>(400, 0.5, B::periodic, 61, 16), 0, 4, 6000, "2D 0.5 periodic (cells)");
  check_slabs<2>(lattice_test::make_gas<2>(400, 0.6, B::wall, 62, 16), 1, 3, 6000, "2D 0.6 walls");
  check_slabs<2>(lattice_test::make_gas<2>(300, 0.4, B::periodic, 63, 16, Mode::specular), 1, 8, 6000, "2D 0.4 periodic specular");
  check_slabs<3>(lattice_test::make_gas<3>(400, 0.3, B::periodic, 64, 16), 2, 4, 6000, "3D 0.3 periodic (lists)");
  check_slabs<3>(lattice_test::make_gas<3>(400, 0.35, B::bounce, 65, 16), 0, 2, 6000, "3D 0.35 bounce-back walls");
}

TEST_CASE("bad slabs are refused, the state unchanged") {
  auto e = lattice_test::make_gas<2>(50, 0.3, en::Boundary::periodic, 7, 16);
  e.run(100, tick_limit - 1);
  const Snapshot s = e.snapshot();
  const std::int64_t L = s.units.L[0];
  CHECK(refused([&] { e.set_regions(2, {0}); }, "the axis must be"));
  CHECK(refused([&] { e.set_regions(0, {L / 2, L / 4}); }, "must ascend within [0, L)"));
  CHECK(refused([&] { e.set_regions(0, {L}); }, "must ascend within [0, L)"));
  CHECK(refused([&] { e.set_regions(0, {-1, 5}); }, "must ascend within [0, L)"));
  CHECK(same_state(e.snapshot(), s));
  CHECK(e.region(3) == 0);
}

int main() { return check::run_all(); }
