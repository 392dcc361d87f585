// The lattice engine in specular mode (specular.hpp): 2D and 3D gases, periodic, specular walls
// and bounce-back walls, forward and back bit for bit and through a midpoint snapshot; no draw
// and no bit of X used; the momentum exact in a periodic box; every pair collision a reflection
// about its contact normal (or a counted turn-back); a known-answer hash of the state.
#include <cmath>
#include <cstdio>

#include "check.hpp"
#include "lattice_gas_util.hpp"
#include "revcol/lattice/engine.hpp"

using namespace revcol::lattice;
namespace en = revcol::engine;
using revcol::Mode;

namespace {

using lattice_test::EngineOf;

// a specular gas (lattice_gas_util.hpp)
template <std::size_t D>
EngineOf<D> make(std::size_t n, double phi, en::Boundary kind, std::uint32_t seed, int tick_bits = default_tick_bits) {
  return lattice_test::make_gas<D>(n, phi, kind, seed, tick_bits, Mode::specular);
}

// FNV-1a over positions, velocities, clock and collision count
template <std::size_t D>
std::uint64_t hash_of(const SnapshotN<D>& s) {
  std::uint64_t h = 1469598103934665603ULL;
  auto mix = [&](std::uint64_t v) {
    for (int b = 0; b < 8; ++b) h = (h ^ ((v >> (8 * b)) & 0xFF)) * 1099511628211ULL;
  };
  for (const auto& x : s.x)
    for (auto c : x) mix(static_cast<std::uint64_t>(c));
  for (const auto& v : s.v)
    for (auto c : v) mix(static_cast<std::uint64_t>(c));
  mix(static_cast<std::uint64_t>(s.clock));
  mix(s.collisions);
  return h;
}

template <std::size_t D>
std::uint64_t round_trip(std::size_t n, double phi, en::Boundary kind, std::uint64_t collisions, int tick_bits = default_tick_bits) {
  EngineOf<D> e = make<D>(n, phi, kind, 5, tick_bits);
  CHECK(e.mode() == Mode::specular);
  const SnapshotN<D> s0 = e.snapshot();
  std::vector<EventRecordN<D>> events;
  e.events = &events;
  REQUIRE(e.run(collisions / 2, tick_limit - 1) == collisions / 2);
  const SnapshotN<D> mid = e.snapshot();
  e.events = nullptr;
  REQUIRE(e.run(collisions - collisions / 2, tick_limit - 1) == collisions - collisions / 2);
  const SnapshotN<D> end = e.snapshot();
  // no draw, no bit of X
  CHECK(end.streams == s0.streams);
  CHECK(end.bits == s0.bits);
  // periodic: the momentum exactly the initial one (walls exchange momentum with the box)
  if (kind == en::Boundary::periodic) {
    const auto p0 = EngineOf<D>::momentum_of(s0.v), p1 = EngineOf<D>::momentum_of(end.v);
    CHECK(p0 == p1);
  }
  const double e0 = static_cast<double>(kinetic2(s0.v)), e1 = static_cast<double>(kinetic2(end.v));
  CHECK(std::fabs(e1 / e0 - 1.0) < 1e-8);
  // each pair collision: the relative velocity reflected about the line of centres at the tick,
  // to within the column normal's error (|w| / sigma of the true normal), or turned back
  std::size_t pairs = 0, turned = 0;
  for (const auto& r : events) {
    if (r.kind != EventRecordN<D>::pair) continue;
    ++pairs;
    double w[D], w2[D], nrm[D], nn = 0, wn = 0, ww = 0;
    for (std::size_t k = 0; k < D; ++k) {
      w[k] = static_cast<double>(r.v_before[0][k] - r.v_before[1][k]);
      w2[k] = static_cast<double>(r.v_after[0][k] - r.v_after[1][k]);
      double dx = static_cast<double>(r.x[0][k] - r.x[1][k]);
      if (!e.units().wall[k]) dx -= std::round(dx / static_cast<double>(e.units().L[k])) * static_cast<double>(e.units().L[k]);
      nrm[k] = dx;
      nn += dx * dx;
      ww += w[k] * w[k];
    }
    for (std::size_t k = 0; k < D; ++k) wn += w[k] * nrm[k] / std::sqrt(nn);
    bool back = true;
    double dev = 0;
    for (std::size_t k = 0; k < D; ++k) {
      back = back && w2[k] == -w[k];
      dev = std::max(dev, std::fabs(w2[k] - (w[k] - 2 * wn * nrm[k] / std::sqrt(nn))));
    }
    // the positions at a are up to a tick's travel from contact: the line of centres there is
    // within a few |w| / sigma of the contact normal
    const double tol = (8.0 * std::sqrt(ww) / static_cast<double>(e.units().sigma) + 1e-7) * std::sqrt(ww);
    if (back && dev > tol) {
      ++turned;
      continue;
    }
    CHECK(dev < tol);
  }
  CHECK(pairs > collisions / 4);
  CHECK(turned <= end.counters.backscatters);  // (a head-on turn-back is also a reflection)
  if (tick_bits == 16) CHECK(!end.groups.empty());  // a coarse tick: third bodies within a tick, resolved as groups
  // back to the midpoint, then to the start
  e.run_back(collisions / 2, e.origin());
  CHECK(same_state(e.snapshot(), mid));
  e.run_back(0, e.origin());
  CHECK(same_state(e.snapshot(), s0));
  // a restored midpoint resumes to the same end
  EngineOf<D> f(mid, operator_for(mid.units));
  REQUIRE(f.mode() == Mode::specular);
  f.run(collisions - collisions / 2, tick_limit - 1);
  CHECK(same_state(f.snapshot(), end));
  std::printf("  D=%zu N=%zu phi=%.2f %s: %llu collisions, log %zu, groups %zu, turned back %zu, |dE/E| %.2g, hash %016llx\n",
              D, n, phi, en::to_string(kind), static_cast<unsigned long long>(collisions), end.log.size(),
              end.groups.size(), turned, std::fabs(e1 / e0 - 1.0), static_cast<unsigned long long>(hash_of(end)));
  return hash_of(end);
}

}  // namespace

// the hashes pin the trajectories (same seed, same build, same bits; any change of the map or the
// event rule changes them and must be explained)
TEST_CASE("2D specular gas: periodic, walls, bounce; forward, midpoint and back bit for bit") {
  CHECK(round_trip<2>(400, 0.5, en::Boundary::periodic, 40000) == 0xa5fa04d438fcaa1aULL);
  CHECK(round_trip<2>(400, 0.7, en::Boundary::wall, 40000) == 0x87595b1c3193d7cdULL);
  CHECK(round_trip<2>(300, 0.3, en::Boundary::bounce, 20000) == 0xd32eb9a95c777e47ULL);
}

TEST_CASE("3D specular gas: periodic, walls, bounce; forward, midpoint and back bit for bit") {
  CHECK(round_trip<3>(400, 0.3, en::Boundary::periodic, 40000) == 0x9588d251fbb2b5e0ULL);
  CHECK(round_trip<3>(500, 0.4, en::Boundary::wall, 40000) == 0xb83cf55bed8963efULL);
  CHECK(round_trip<3>(300, 0.2, en::Boundary::bounce, 20000) == 0x912caa570e05ec33ULL);
}

TEST_CASE("a coarse tick (2^-16): third bodies within a tick go to the group rule, still bit for bit") {
  round_trip<2>(400, 0.7, en::Boundary::periodic, 40000, 16);
  round_trip<3>(500, 0.45, en::Boundary::periodic, 40000, 16);
}

TEST_CASE("specular mode: a snapshot carries the mode; an exact engine refuses nothing of it") {
  EngineOf<2> e = make<2>(50, 0.3, en::Boundary::periodic, 1);
  const Snapshot s = e.snapshot();
  CHECK(s.mode == Mode::specular);
  Snapshot t = s;
  t.mode = Mode::paper;
  CHECK_THROWS_AS(e.restore(t), revcol::InvalidArgument);
  CHECK(same_state(e.snapshot(), s));  // nothing changed
  Snapshot u = s;
  u.mode = Mode::exact;
  CHECK(!same_state(u, s));  // the mode is part of the state
  const LatticeStart st = random_start(LatticeConfig{}, 20, 0.2, 1);
  CHECK_THROWS_AS(LatticeEngine(st.units, st.x, st.v, 1, operator_for(st.units), 0, Mode::paper), revcol::InvalidArgument);
}

CHECK_MAIN()
