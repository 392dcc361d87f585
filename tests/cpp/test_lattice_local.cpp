// The lattice engine's state is per particle (engine_core.hpp, ARCHITECTURE.md "Per-particle
// state"): a collision reads and writes only its own particles' velocities, stream counters,
// bits-back integers and collision counts; the rare log is keyed by (particle, its count), every
// key names a collision that particle had and the counts add up; a snapshot that breaks those
// rules is refused with the state unchanged; each X stays near its 128 start bits; two gases
// far apart in one box leave each other's particles exactly as each alone would.
#include <cstdio>
#include <set>
#include <string>

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
EngineOf<D> make(std::size_t n, double phi, bool walls, std::uint32_t seed, int tick_bits, Mode mode = Mode::exact) {
  return lattice_test::make_gas<D>(n, phi, walls ? en::Boundary::wall : en::Boundary::periodic, seed, tick_bits, mode);
}

// One collision at a time: the particles whose velocity, stream, X or count changed are the
// collision's own (a pair, or a group's members; a wall reflection before it changes only a
// velocity); X changes only for the drawer (the pair's lower index); counts step by one.
template <std::size_t D>
void check_locality(EngineOf<D>& e, int steps, const char* what) {
  std::vector<EventRecordN<D>> ev;
  e.events = &ev;
  int pairs = 0, groups = 0, bad = 0;
  for (int s = 0; s < steps; ++s) {
    const SnapshotN<D> a = e.snapshot();
    ev.clear();
    e.run(1, tick_limit - 1);
    const SnapshotN<D> b = e.snapshot();
    const auto abits = bits_per_particle(a), bbits = bits_per_particle(b);
    std::set<int> own, walled;
    for (const auto& r : ev) {
      if (r.kind == EventRecordN<D>::wall) walled.insert(r.ids[0]);
      else own.insert(r.ids.begin(), r.ids.end());
    }
    const auto& last = ev.back();
    if (last.kind == EventRecordN<D>::group) ++groups;
    else ++pairs;
    for (std::size_t p = 0; p < a.x.size(); ++p) {
      const int q = static_cast<int>(p);
      const bool mine = own.count(q) > 0;
      const bool v_ok = a.v[p] == b.v[p] || mine || walled.count(q) > 0;
      const bool s_ok = a.streams[p] == b.streams[p] || mine;
      const bool x_ok = abits[p] == bbits[p] || (mine && last.kind == EventRecordN<D>::pair && q == std::min(last.ids[0], last.ids[1]));
      const bool c_ok = b.particle_collisions[p] == a.particle_collisions[p] + (mine ? 1 : 0);
      if (!(v_ok && s_ok && x_ok && c_ok)) ++bad;
    }
  }
  e.events = nullptr;
  std::printf("  %s: %d pair and %d group collisions, one at a time, %d foreign changes\n", what, pairs, groups, bad);
  CHECK(bad == 0);
  CHECK(pairs + groups == steps);
}

}  // namespace

TEST_CASE("a collision changes only its own particles' velocities, streams, X and counts (2D and 3D, exact and specular)") {
  auto e2 = make<2>(200, 0.5, true, 3, 16);
  check_locality<2>(e2, 3000, "2D 0.5 walls T=16 exact");
  auto s2 = make<2>(200, 0.5, false, 4, 16, Mode::specular);
  check_locality<2>(s2, 2000, "2D 0.5 periodic T=16 specular");
  auto e3 = make<3>(250, 0.4, false, 5, 16);
  check_locality<3>(e3, 3000, "3D 0.4 periodic T=16 exact");
  auto g2 = make<2>(120, 0.4, false, 6, 16);
  g2.max_redraws = -1;  // every collision a group
  check_locality<2>(g2, 500, "2D forced groups");
}

TEST_CASE("the rare log is keyed per particle: each key a collision its particle had, the counts add up, bad ones refused") {
  auto e = make<2>(300, 0.6, true, 7, 16);
  e.run(60000, tick_limit - 1);
  auto g = make<2>(100, 0.4, false, 8, 16);
  g.max_redraws = -1;
  g.run(300, tick_limit - 1);
  for (auto* eng : {&e, &g}) {
    const Snapshot s = eng->snapshot();
    std::uint64_t sum = 0, extra = 0;
    for (std::uint64_t c : s.particle_collisions) sum += c;
    for (const auto& gr : s.groups) extra += gr.members.size() - 2;
    CHECK(sum == 2 * s.collisions + extra);
    for (const LogEntry& l : s.log) CHECK(l.count >= 1 && l.count <= s.particle_collisions[l.particle]);
    std::printf("  %llu collisions: %zu redraw entries, %zu groups held\n", static_cast<unsigned long long>(s.collisions),
                s.log.size(), s.groups.size());
  }
  const Snapshot s = e.snapshot();
  const Snapshot sg = g.snapshot();
  REQUIRE(!s.log.empty());
  REQUIRE(!sg.groups.empty());
  auto keeps = [](EngineOf<2>& eng, const Snapshot& bad, const std::string& what) {
    const Snapshot before = eng.snapshot();
    const bool ok = refused([&] { eng.restore(bad); }, what);
    return ok && same_state(eng.snapshot(), before);
  };
  Snapshot b = s;
  b.log[0].count = b.particle_collisions[b.log[0].particle] + 1;  // a collision not had yet
  CHECK(keeps(e, b, "names a collision its particle has not had"));
  b = s;
  b.particle_collisions[0] += 1;  // counts that do not add up
  CHECK(keeps(e, b, "particle_collisions do not add up"));
  b = s;
  b.log.push_back(b.log.back());  // a key twice
  CHECK(keeps(e, b, "each once"));
  b = sg;
  b.groups[0].drawer = b.groups[0].members.back() + 1;  // a drawer outside its group
  CHECK(keeps(g, b, "drawer must be one of its members"));
  b = sg;
  b.groups[0].counts[0] = b.particle_collisions[static_cast<std::size_t>(b.groups[0].members[0])] + 1;
  CHECK(keeps(g, b, "names a collision its member has not had"));
  b = s;
  b.bits_size.pop_back();
  CHECK(keeps(e, b, "one bits-back integer's size per particle"));
  b = s;
  b.bits.pop_back();
  CHECK(keeps(e, b, "the words bits_size says"));
  // the untouched snapshots load and run back to the start bit for bit
  e.restore(s);
  e.run_back(0, e.origin());
  CHECK(e.collisions() == 0 && e.log_size() == 0);
  g.restore(sg);
  g.run_back(0, g.origin());
  CHECK(g.group_log_size() == 0);
}

TEST_CASE("each particle's X stays near its 128 start bits (the flux law's balance): no heap words") {
  for (bool walls : {false, true}) {
    auto e = make<3>(400, 0.3, walls, 11, 20);
    e.run(400 * 200, tick_limit - 1);  // 400 collisions per particle
    std::size_t lo = 1000, hi = 0, heap = 0;
    for (int p = 0; p < 400; ++p) {
      lo = std::min(lo, e.bits(p).bit_length());
      hi = std::max(hi, e.bits(p).bit_length());
      heap += e.bits(p).heap_bytes();
    }
    std::printf("  3D 0.3 %s, 400 collisions per particle: X %zu..%zu bits, %zu heap bytes\n", walls ? "walls" : "periodic", lo, hi, heap);
    CHECK(lo >= 120 && hi <= 136);
    CHECK(heap == 0);
  }
}

// Two gases in one box, A on the left and B on the right, too far apart to meet before tick T:
// the run of A and B together leaves every particle of A in exactly the state that A's run
// alone leaves it in (B's particles present but at rest), and the same for B. With one X for
// the whole gas (the older layout) B's collisions changed A's draws; per-particle state makes
// the state of a region independent of what happens elsewhere, as the parallel engine needs.
template <std::size_t D>
void check_cut(std::size_t n, double phi, std::uint32_t seed) {
  LatticeConfigN<D> c;
  c.tick_bits = 16;
  for (std::size_t k = 0; k < D; ++k) c.wall[k] = true;
  c.seed = seed;
  const LatticeStartN<D> s0 = random_start(c, n, phi, seed);
  // the same gas twice, B shifted by the box length and a gap of 40 diameters, quantized once
  const double len = s0.units.length_unit, L0 = static_cast<double>(s0.units.L[0]) * len, gap = 40.0;
  std::vector<double> xf, vf;
  for (int copy = 0; copy < 2; ++copy)
    for (std::size_t p = 0; p < n; ++p)
      for (std::size_t k = 0; k < D; ++k) {
        xf.push_back(static_cast<double>(s0.x[p][k]) * len + (k == 0 && copy == 1 ? L0 + gap : 0.0));
        vf.push_back(static_cast<double>(s0.v[p][k]) * len / s0.units.tick);
      }
  for (std::size_t k = 0; k < D; ++k) c.box[k] = static_cast<double>(s0.units.L[k]) * len;
  c.box[0] = 2.0 * L0 + gap;
  const LatticeStartN<D> s = quantize_start(c, xf, vf);
  const UnitsN<D>& u = s.units;
  const std::vector<VecN<D>>& x = s.x;
  const std::vector<VecN<D>>& v = s.v;
  // a typical particle moves 2 sigma by then (2^tick_bits ticks per sigma); the 40 sigma gap is
  // not crossed (if it were, the states below would differ and the test fail, not pass)
  const std::int64_t T = std::int64_t{2} << u.tick_bits;
  auto run = [&](bool a_moves, bool b_moves) {
    std::vector<VecN<D>> w = v;
    for (std::size_t p = 0; p < 2 * n; ++p)
      if ((p < n && !a_moves) || (p >= n && !b_moves)) w[p] = VecN<D>{};
    EngineOf<D> e(u, x, w, seed, operator_for(u));
    e.run(~std::uint64_t{0}, T);
    return e.snapshot();
  };
  const SnapshotN<D> ab = run(true, true), a = run(true, false), b = run(false, true);
  auto same_particles = [&](const SnapshotN<D>& one, std::size_t lo, std::size_t hi) {
    bool ok = true;
    const auto abits = bits_per_particle(ab), obits = bits_per_particle(one);
    for (std::size_t p = lo; p < hi; ++p) {
      const bool same = ab.x[p] == one.x[p] && ab.v[p] == one.v[p] && ab.streams[p] == one.streams[p] && abits[p] == obits[p] &&
                        ab.particle_collisions[p] == one.particle_collisions[p];
      if (!same && ok)
        std::printf("    particle %zu differs: x %d v %d streams %d bits %d count %d\n", p, ab.x[p] == one.x[p], ab.v[p] == one.v[p],
                    ab.streams[p] == one.streams[p], abits[p] == obits[p], ab.particle_collisions[p] == one.particle_collisions[p]);
      ok = ok && same;
    }
    std::vector<LogEntry> mine, theirs;
    for (const LogEntry& l : ab.log)
      if (l.particle >= lo && l.particle < hi) mine.push_back(l);
    for (const LogEntry& l : one.log)
      if (l.particle >= lo && l.particle < hi) theirs.push_back(l);
    if (!(mine == theirs))
      for (const auto* L : {&mine, &theirs})
        for (const LogEntry& l : *L) std::printf("    log (%u, %llu) %u\n", l.particle, static_cast<unsigned long long>(l.count), l.redraws);
    return ok && mine == theirs;
  };
  std::printf("  %zuD, 2 x %zu at %.2f, %lld ticks: %llu collisions together, %llu + %llu apart; log %zu = %zu + %zu\n", D, n, phi,
              static_cast<long long>(T), static_cast<unsigned long long>(ab.collisions), static_cast<unsigned long long>(a.collisions),
              static_cast<unsigned long long>(b.collisions), ab.log.size(), a.log.size(), b.log.size());
  CHECK(a.collisions > 4 * n && b.collisions > 4 * n);
  CHECK(ab.collisions == a.collisions + b.collisions);
  CHECK(same_particles(a, 0, n));
  CHECK(same_particles(b, n, 2 * n));
}

TEST_CASE("a region's state does not depend on what happens elsewhere: two far gases together equal each alone") {
  check_cut<2>(300, 0.6, 21);
  check_cut<3>(300, 0.4, 22);
}

int main() { return check::run_all(); }
