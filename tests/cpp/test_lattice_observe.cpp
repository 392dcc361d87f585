// Tests of observation on the lattice engine (engine_core.hpp's observer hooks feeding
// revcol/engine/observe.hpp): the observer's virial, kinetic integral and wall terms equal a
// direct sum over the engine's own velocity changes (its event records, exact integers) to
// 1e-9 relative, and so does the Helfand moment at every block end (relative to the sum of
// its terms' sizes); the hooks see every collision and reflection; an observed run is the same
// run as an unobserved one and still reverses bit for bit; run_back and restore end it.
#include <cmath>
#include <cstdlib>
#include <string>

#include "check.hpp"
#include "revcol/lattice/engine.hpp"

using namespace revcol::lattice;
namespace en = revcol::engine;

namespace {

template <std::size_t D>
BasicEngine<std::conditional_t<D == 2, LatticePair2D, LatticePair3D>, BitsBack> make(std::size_t n, double phi, bool walls,
                                                                                      std::uint32_t seed,
                                                                                      bool specular = false) {
  LatticeConfigN<D> c;
  c.wall = filled<D>(walls);
  c.seed = seed;
  const LatticeStartN<D> s = random_start(c, n, phi, seed);
  return {s.units, s.x, s.v, seed, operator_for(s.units), 0, specular ? revcol::Mode::specular : revcol::Mode::exact};
}

// The direct sums over a trajectory's event records, in lattice units (long double: a term
// r . dv is below 2^107, exact to 64 bits): the collision virial W, the wall virial, the
// wall impulses per axis, and K2 = the integral of sum |v|^2 over the ticks.
template <std::size_t D>
struct Direct {
  long double w = 0, w_wall = 0, k2 = 0;
  std::array<long double, D> wall_dp{};
  std::uint64_t pairs = 0, groups = 0, walls = 0;
};

template <class E>
Direct<E::D> direct_sums(const E& e, const std::vector<EventRecordN<E::D>>& events, std::int64_t t0,
                         const std::vector<VecN<E::D>>& v0) {
  constexpr std::size_t D = E::D;
  const UnitsN<D>& u = e.units();
  Direct<D> out;
  long double e2 = 0;  // sum |v|^2 now
  for (const auto& v : v0)
    for (std::size_t k = 0; k < D; ++k) e2 += static_cast<long double>(v[k]) * v[k];
  std::int64_t t = t0;
  for (const auto& r : events) {
    out.k2 += e2 * static_cast<long double>(r.tick - t);
    t = r.tick;
    for (std::size_t m = 0; m < r.ids.size(); ++m)
      for (std::size_t k = 0; k < D; ++k) {
        const long double a = r.v_after[m][k], b = r.v_before[m][k];
        e2 += a * a - b * b;
      }
    if (r.kind == EventRecordN<D>::pair) {
      ++out.pairs;
      for (std::size_t k = 0; k < D; ++k) {
        std::int64_t d = r.x[0][k] - r.x[1][k];
        if (!u.wall[k]) d = min_image(d, u.L[k]);
        out.w += static_cast<long double>(d) * static_cast<long double>(r.v_after[0][k] - r.v_before[0][k]);
      }
    } else if (r.kind == EventRecordN<D>::wall) {
      ++out.walls;
      for (std::size_t k = 0; k < D; ++k) {
        if (!(r.axes >> k & 1u)) continue;
        const long double dv = static_cast<long double>(r.v_after[0][k] - r.v_before[0][k]);
        const long double plane = r.v_after[0][k] > 0 ? u.sigma / 2 : u.L[k] - u.sigma / 2;
        out.w_wall += plane * dv;
        out.wall_dp[k] += std::fabs(dv);
      }
    } else {
      ++out.groups;
      for (std::size_t m = 0; m < r.ids.size(); ++m)
        for (std::size_t k = 0; k < D; ++k) {
          std::int64_t x = r.x[m][k];
          if (!u.wall[k] && m > 0) x = r.x[0][k] + min_image(r.x[m][k] - r.x[0][k], u.L[k]);
          out.w += static_cast<long double>(x) * static_cast<long double>(r.v_after[m][k] - r.v_before[m][k]);
        }
    }
  }
  out.k2 += e2 * static_cast<long double>(e.clock() - t);
  return out;
}

double rel(double a, double b) { return std::fabs(a - b) / std::fabs(b); }

// The Helfand moment I_ab (a < b) at each time of `times` (float units, the observer's block
// ends) straight from the event records, in lattice units (long double; exact integers but
// for the fractional tick of a block end): the integral of sum v_a v_b over the ticks plus
// r_a dv_b per pair (nearest image), x_a dv_b summed over a group's members (one image).
// Also the sum of |terms| up to each time (the scale of the round-off).
template <class E>
std::pair<std::vector<long double>, std::vector<long double>> direct_helfand(
    const E& e, const std::vector<EventRecordN<E::D>>& events, std::int64_t t0, const std::vector<VecN<E::D>>& v0,
    const std::vector<double>& times) {
  constexpr std::size_t D = E::D, C = D * (D - 1) / 2;
  const UnitsN<D>& u = e.units();
  constexpr std::size_t A[3] = {0, 0, 1}, B[3] = {1, 2, 2};
  std::array<long double, 3> off{}, I{}, scale{};  // sum v_a v_b now; the moment; sum of |terms|
  for (const auto& v : v0)
    for (std::size_t c = 0; c < C; ++c) off[c] += static_cast<long double>(v[A[c]]) * v[B[c]];
  std::vector<long double> out, mag;
  long double t = static_cast<long double>(t0);
  std::size_t next = 0;
  auto fly = [&](long double to) {
    for (std::size_t c = 0; c < C; ++c) {
      I[c] += off[c] * (to - t);
      scale[c] += std::fabs(off[c] * (to - t));
    }
    t = to;
  };
  auto kick = [&](std::size_t c, long double q) {
    I[c] += q;
    scale[c] += std::fabs(q);
  };
  for (double tq : times) {
    const long double end = static_cast<long double>(tq) / static_cast<long double>(u.tick);
    for (; next < events.size() && static_cast<long double>(events[next].tick) < end; ++next) {
      const auto& r = events[next];
      fly(static_cast<long double>(r.tick));
      for (std::size_t m = 0; m < r.ids.size(); ++m)
        for (std::size_t c = 0; c < C; ++c)
          off[c] += static_cast<long double>(r.v_after[m][A[c]]) * r.v_after[m][B[c]] -
                    static_cast<long double>(r.v_before[m][A[c]]) * r.v_before[m][B[c]];
      if (r.kind == EventRecordN<D>::pair) {
        VecN<D> d;
        for (std::size_t k = 0; k < D; ++k) d[k] = u.wall[k] ? r.x[0][k] - r.x[1][k] : min_image(r.x[0][k] - r.x[1][k], u.L[k]);
        for (std::size_t c = 0; c < C; ++c)
          kick(c, static_cast<long double>(d[A[c]]) * static_cast<long double>(r.v_after[0][B[c]] - r.v_before[0][B[c]]));
      } else if (r.kind == EventRecordN<D>::group) {
        for (std::size_t m = 0; m < r.ids.size(); ++m) {
          VecN<D> x = r.x[m];
          for (std::size_t k = 0; k < D; ++k)
            if (!u.wall[k] && m > 0) x[k] = r.x[0][k] + min_image(r.x[m][k] - r.x[0][k], u.L[k]);
          for (std::size_t c = 0; c < C; ++c)
            kick(c, static_cast<long double>(x[A[c]]) * static_cast<long double>(r.v_after[m][B[c]] - r.v_before[m][B[c]]));
        }
      }  // walls: no term (observe.hpp)
    }
    fly(end);
    for (std::size_t c = 0; c < C; ++c) {
      out.push_back(I[c]);
      mag.push_back(scale[c]);
    }
  }
  return {out, mag};
}

// observe `collisions` collisions; the observer's results against the direct sums
template <class E>
void check_direct(E e, std::uint64_t warm, std::uint64_t collisions, const char* what) {
  constexpr std::size_t D = E::D;
  e.run(warm, tick_limit - 1);
  std::vector<EventRecordN<D>> events;
  e.events = &events;
  const std::int64_t t0 = e.clock();
  const auto v0 = e.velocities();
  const Counters c0 = e.counters();
  e.observe(en::ObserveConfig{});
  // several run calls: a sync at each end, events at the syncs' ticks
  for (int part = 0; part < 4; ++part) e.run(collisions / 4, tick_limit - 1);
  const en::Observation o = e.observer()->results();
  const Direct<D> d = direct_sums(e, events, t0, v0);
  const Counters& c1 = e.counters();
  // the hooks saw every velocity change: as many records as the engine's counts
  CHECK(d.pairs + d.groups == c1.collisions - c0.collisions);
  CHECK(d.walls == c1.walls - c0.walls);
  CHECK(o.pair_collisions == d.pairs);
  CHECK(o.group_collisions == d.groups);
  CHECK(o.wall_reflections == d.walls);
  // float units: lengths x length_unit, speeds x length_unit / tick, times x tick
  const UnitsN<D>& u = e.units();
  const double l = u.length_unit, tk = u.tick, tau = static_cast<double>(e.clock() - t0) * tk;
  const double k2 = static_cast<double>(d.k2) * (l / tk) * (l / tk) * tk;
  const double w = static_cast<double>(d.w) * l * (l / tk);
  const double w_wall = static_cast<double>(d.w_wall) * l * (l / tk);
  const double n = static_cast<double>(e.size());
  CHECK(rel(o.t_end - o.t_start, tau) < 1e-12);
  CHECK(rel(o.temperature.value, k2 / (D * n * tau)) < 1e-9);
  CHECK(rel(o.compressibility.value - 1.0, w / k2) < 1e-9);
  if (d.walls > 0) {
    CHECK(rel(o.virial_balance.value, (k2 + w + w_wall) / k2) < 1e-9);
    for (std::size_t k = 0; k < D; ++k) {
      if (!u.wall[k]) continue;
      double area = 1.0;
      for (std::size_t j = 0; j < D; ++j)
        if (j != k) area *= static_cast<double>(u.L[j]) * l;
      CHECK(rel(o.pressure_wall[k].value, static_cast<double>(d.wall_dp[k]) * (l / tk) / (2.0 * tau * area)) < 1e-9);
    }
  }
  // the Helfand moment at every block end: I (float units) = I (lattice units) x length_unit^2 / tick
  std::vector<double> ends;
  for (double q : o.msd_time) ends.push_back(o.t_start + q);
  const auto [hd, hmag] = direct_helfand(e, events, t0, v0, ends);
  CHECK(o.helfand_components == static_cast<int>(D * (D - 1) / 2));
  CHECK(o.helfand.size() == hd.size() && ends.size() >= 8);
  double worst = 0.0;
  for (std::size_t q = 0; q < hd.size() && q < o.helfand.size(); ++q) {
    const double want = static_cast<double>(hd[q]) * l * l / tk, mag = static_cast<double>(hmag[q]) * l * l / tk;
    worst = std::max(worst, std::fabs(o.helfand[q] - want) / mag);
  }
  CHECK(worst < 1e-9);
  if (std::getenv("REVCOL_TEST_VERBOSE")) std::printf("  %s: Helfand worst |observed - direct| / sum|terms| %.3g\n", what, worst);
  if (std::getenv("REVCOL_TEST_VERBOSE") || !(rel(o.compressibility.value - 1.0, w / k2) < 1e-9))
    std::printf("  %s: %llu pairs, %llu walls, %llu groups; Z - 1 observed %.15g, direct %.15g; T %.15g vs %.15g\n", what,
                static_cast<unsigned long long>(d.pairs), static_cast<unsigned long long>(d.walls),
                static_cast<unsigned long long>(d.groups), o.compressibility.value - 1.0, w / k2, o.temperature.value,
                k2 / (D * n * tau));
}

}  // namespace

TEST_CASE("observer = direct sum over the engine's velocity changes: 2D periodic, area fraction 0.5") {
  check_direct(make<2>(200, 0.5, false, 3), 2000, 8000, "2D periodic 0.5");
}

TEST_CASE("observer = direct sum: 2D walls, area fraction 0.3 (wall virial and wall pressure too)") {
  check_direct(make<2>(150, 0.3, true, 4), 2000, 8000, "2D walls 0.3");
}

TEST_CASE("observer = direct sum: 3D periodic 0.3 and 3D walls 0.3") {
  check_direct(make<3>(150, 0.3, false, 5), 2000, 8000, "3D periodic 0.3");
  check_direct(make<3>(120, 0.3, true, 6), 2000, 8000, "3D walls 0.3");
}

TEST_CASE("observer = direct sum in specular mode: 3D periodic 0.45 and 2D walls 0.4") {
  check_direct(make<3>(200, 0.45, false, 9, true), 2000, 20000, "3D periodic 0.45 specular");
  check_direct(make<2>(150, 0.4, true, 10, true), 2000, 8000, "2D walls 0.4 specular");
}

TEST_CASE("an observed run is the unobserved run, and reverses bit for bit; run_back ends the observation") {
  auto a = make<2>(150, 0.4, true, 7);
  auto b = make<2>(150, 0.4, true, 7);
  const Snapshot s0 = a.snapshot();
  a.observe(en::ObserveConfig{.slabs = 4, .speed_bins = 20});
  CHECK(a.observing());
  a.run(20000, tick_limit - 1);
  b.run(20000, tick_limit - 1);
  CHECK(same_state(a.snapshot(), b.snapshot()));
  const en::Observation o = a.observer()->results();
  CHECK(o.pair_collisions + o.group_collisions == 20000);
  a.run_back(0, a.origin());
  CHECK(!a.observing());
  CHECK(a.observer() != nullptr);  // the results stay readable
  CHECK(a.observer()->results().pair_collisions == o.pair_collisions);
  CHECK(same_state(a.snapshot(), s0));
  // a forward run after run_back adds nothing to the stopped observation
  a.run(100, tick_limit - 1);
  CHECK(a.observer()->results().pair_collisions == o.pair_collisions);
  // restore replaces the state: a stopped observation stays readable, a running one is gone
  a.restore(s0);
  CHECK(a.observer() != nullptr && !a.observing());
  a.run(100, tick_limit - 1);  // (not fed by the restored state's run)
  CHECK(a.observer()->results().pair_collisions == o.pair_collisions);
  a.observe(en::ObserveConfig{});
  a.restore(s0);
  CHECK(!a.observing());
  CHECK(a.observer() == nullptr);
}

TEST_CASE("a bad observe config is refused, nothing started") {
  auto e = make<2>(50, 0.3, false, 8);
  en::ObserveConfig c;
  c.min_blocks = 1;
  CHECK_THROWS_AS(e.observe(c), revcol::InvalidArgument);
  CHECK(!e.observing());
}

int main() { return check::run_all(); }
