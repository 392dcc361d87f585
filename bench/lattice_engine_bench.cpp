// The lattice family of revcol-bench: the 2D lattice engine's collisions per second forward and
// reverse (periodic, N = 10^4, area fractions 0.3 and 0.5; walls at 0.3), with the round trip's
// bit-exactness and the rare counts; lattice3d/... the same for the 3D engine (spheres, volume
// fractions 0.3 and 0.45) and lattice3d/float/... the float engine on the same 3D gases. Run it beside engine/d2/... in one invocation to compare
// with the float engine (the machine is shared: never compare across runs). lattice/float/...
// runs the float engine (2D, exact mode, flux law, periodic) with the same timing, so that one
// invocation of --bench lattice/ carries both; the *_cpu_per_s metrics divide by the process's CPU
// time, which a loaded machine distorts less than the wall clock.
//
//   revcol-bench --bench lattice/ --collisions 200000
//
// REVCOL_LATTICE=tick_bits=T,cell_bits=B overrides the units' defaults (automatic T, 2^16 cells);
// observe=1 (scalars) or 2 (+ speed histogram and slabs) observes the timed forward run.
//
// Metrics: forward_per_s, reverse_per_s, forward_cpu_per_s, reverse_cpu_per_s, bit_exact (1 when positions, velocities, streams, X and
// clock are restored bit for bit), events_per_collision, log_entries, redraws_per_collision,
// multi_body, wall_body, bits_length (X after the forward run), energy_drift (relative, after the
// forward run), engine_bytes, n, phi.
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <ctime>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

#include "bench.hpp"
#include "revcol/engine/engine.hpp"
#include "revcol/engine/init.hpp"
#include "revcol/lattice/engine.hpp"

namespace revcol::bench {
namespace {

namespace la = revcol::lattice;
namespace en = revcol::engine;

double cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

struct LatticeCase {
  std::size_t n = 10000;
  double phi = 0.3;
  bool walls = false;
  std::uint64_t seed = 1;
  int dim = 2;
  revcol::Mode mode = revcol::Mode::exact;  // the lattice engine's mode; the float engine's (exact: the flux law)
};

// the initial placement: 2D as before; 3D: random_state's choice (rsa to 0.2, else FCC)
const char* init_of(const LatticeCase& c) { return c.dim == 3 ? "auto" : c.phi > 0.35 ? "crystal" : "auto"; }

template <std::size_t D>
using EngineOf = std::conditional_t<D == 2, la::LatticeEngine, la::LatticeEngine3D>;

// the lattice configuration of a case: its walls and seed (the rest the units' defaults)
template <std::size_t D>
la::LatticeConfigN<D> config_of(const LatticeCase& c) {
  la::LatticeConfigN<D> cfg;
  cfg.wall = la::filled<D>(c.walls);
  cfg.seed = static_cast<std::uint32_t>(c.seed);
  return cfg;
}

template <std::size_t D>
std::vector<Metric> run_lattice(const LatticeCase& c, std::uint64_t nc) {
  using Engine = EngineOf<D>;
  la::LatticeConfigN<D> cfg = config_of<D>(c);
  // REVCOL_LATTICE=tick_bits=20,cell_bits=20 runs the engine as before the automatic tick;
  // shell=S sets the neighbour search (set_list_shell: 0 the cell grid, S > 0 lists, < 0 automatic)
  // observe=1 observes the timed forward run's scalars, 2 also a 50-bin speed histogram and 10
  // slabs (revcol/engine/observe.hpp; run_back ends it: the reverse is unobserved)
  // shuffle=1 stores the particles in a random order after the warm-up (the start's ids are in
  // space order; a long run loses that order): the cost of memory order (the bits are the same)
  double shell = -1.0;
  // resort=K: set_resort(K) (events per particle between re-sorts of the storage; 0 never)
  int observe = 0, shuffle = 0, resort = -1;
  apply_settings("REVCOL_LATTICE", "tick_bits, cell_bits, shell, observe, shuffle, resort", [&](const std::string& k, const std::string& v) {
    if (k == "tick_bits") cfg.tick_bits = std::stoi(v);
    else if (k == "cell_bits") cfg.cell_bits = std::stoi(v);
    else if (k == "shell") shell = std::stod(v);
    else if (k == "observe") observe = std::stoi(v);
    else if (k == "shuffle") shuffle = std::stoi(v);
    else if (k == "resort") resort = std::stoi(v);
    else return false;
    return true;
  });
  const la::LatticeStartN<D> st = la::random_start(cfg, c.n, c.phi, c.seed, init_of(c));
  Engine e(st.units, st.x, st.v, cfg.seed, la::operator_for(st.units), 0, c.mode);
  if (shell >= 0.0) e.set_list_shell(shell);
  e.set_resort(resort);
  // warm up a collision per particle from the initialiser's lattice, then start the clock
  e.run(c.n, la::tick_limit - 1);
  const la::SnapshotN<D> s0 = e.snapshot();
  if (shuffle != 0) {
    std::vector<std::uint32_t> order(c.n);
    for (std::size_t i = 0; i < c.n; ++i) order[i] = static_cast<std::uint32_t>(i);
    std::uint64_t z = 0x9e3779b97f4a7c15ULL;  // Fisher-Yates with a fixed splitmix64 stream
    for (std::size_t i = c.n - 1; i > 0; --i) {
      z += 0x9e3779b97f4a7c15ULL;
      std::uint64_t r = z;
      r = (r ^ (r >> 30)) * 0xbf58476d1ce4e5b9ULL;
      r = (r ^ (r >> 27)) * 0x94d049bb133111ebULL;
      r ^= r >> 31;
      std::swap(order[i], order[r % (i + 1)]);
    }
    e.restore(s0, order);
  }
  const la::Counters k0 = e.counters();
  if (observe > 0) {
    en::ObserveConfig oc;
    if (observe > 1) {
      oc.speed_bins = 50;
      oc.slabs = 10;
    }
    e.observe(oc);
  }
  using clock = std::chrono::steady_clock;
  const auto t0 = clock::now();
  const double c0 = cpu_seconds();
  const std::uint64_t done = e.run(nc, la::tick_limit - 1);
  const auto t1 = clock::now();
  const double c1 = cpu_seconds();
  const la::DiagnosticsN<D> d1 = la::diagnostics(e);
  const la::Counters k1 = e.counters();
  e.run_back(s0.collisions, s0.origin);
  const auto t2 = clock::now();
  const double c2 = cpu_seconds();
  const bool exact = la::same_state(e.snapshot(), s0);
  double redraws = 0.0;
  for (int k = 1; k < 8; ++k) redraws += static_cast<double>(k1.redraws[k] - k0.redraws[k]);
  const double coll = static_cast<double>(done);
  return {{"forward_per_s", coll / std::chrono::duration<double>(t1 - t0).count()},
          {"reverse_per_s", coll / std::chrono::duration<double>(t2 - t1).count()},
          {"forward_cpu_per_s", coll / (c1 - c0)},
          {"reverse_cpu_per_s", coll / (c2 - c1)},
          {"bit_exact", exact ? 1.0 : 0.0},
          {"events_per_collision", static_cast<double>(k1.events - k0.events) / coll},
          {"neutral_per_collision", static_cast<double>(k1.crossings - k0.crossings) / coll},
          {"list_shell", e.list_shell()},
          {"log_entries", static_cast<double>(k1.log_entries - k0.log_entries)},
          {"redraws_per_collision", redraws / coll},
          {"multi_body", static_cast<double>(k1.multi_body - k0.multi_body)},
          {"wall_body", static_cast<double>(k1.wall_body - k0.wall_body)},
          {"bits_length", static_cast<double>(d1.bits_length)},
          {"energy_drift", d1.energy_drift},
          {"engine_bytes", static_cast<double>(e.memory_bytes())},
          {"resorts", static_cast<double>(e.resorts())},
          {"n", static_cast<double>(c.n)},
          {"phi", c.phi}};
}

// The cell grid (shell 0) and the automatic lists run in lockstep from the same start, their
// collision traces (tick, i, j) compared chunk by chunk: `first_difference` is the index of the
// first collision where they part (-1: none in the collisions asked). The searches must never
// decide anything, so anything but -1 is a bug (the last one found, a same-tick tie of two
// partners, parted the periodic N = 10^4 gas at collision 6 620 344: docs/lattice.md "Session 12").
template <std::size_t D>
std::vector<Metric> run_lockstep(const LatticeCase& c, std::uint64_t nc) {
  using Engine = EngineOf<D>;
  const la::LatticeConfigN<D> cfg = config_of<D>(c);
  const la::LatticeStartN<D> st = la::random_start(cfg, c.n, c.phi, c.seed, init_of(c));
  Engine a(st.units, st.x, st.v, cfg.seed, la::operator_for(st.units));
  Engine b(st.units, st.x, st.v, cfg.seed, la::operator_for(st.units));
  a.set_list_shell(0.0);
  const double shell = b.list_shell();
  std::vector<std::array<std::int64_t, 3>> ta, tb;
  a.trace = &ta;
  b.trace = &tb;
  double first = -1.0;
  std::uint64_t done = 0;
  const std::uint64_t chunk = 100000;
  while (done < nc && first < 0.0) {
    const std::uint64_t k = std::min(chunk, nc - done);
    ta.clear();
    tb.clear();
    a.run(k, la::tick_limit - 1);
    b.run(k, la::tick_limit - 1);
    for (std::size_t e = 0; e < std::max(ta.size(), tb.size()); ++e)
      if (e >= ta.size() || e >= tb.size() || ta[e] != tb[e]) {
        first = static_cast<double>(done + e);
        break;
      }
    done += k;
  }
  return {{"first_difference", first}, {"collisions_compared", static_cast<double>(first < 0.0 ? done : first)},
          {"list_shell", shell}, {"n", static_cast<double>(c.n)}, {"phi", c.phi}};
}

// the float engine on the same kind of gas, timed the same way (its own family is engine/...)
std::vector<Metric> run_float(const LatticeCase& c, std::uint64_t nc) {
  en::Config cfg;
  cfg.dim = c.dim;
  cfg.seed = static_cast<std::uint32_t>(c.seed);
  cfg.mode = c.mode;
  const en::InitialState st = en::random_state(cfg, c.n, c.phi, c.seed, 0.0, init_of(c));
  auto sim = en::make_simulation(st.config, st.x, st.v);
  const double inf = std::numeric_limits<double>::infinity();
  sim->run(c.n, inf);
  using clock = std::chrono::steady_clock;
  const auto t0 = clock::now();
  const double c0 = cpu_seconds();
  const en::RunResult f = sim->run(nc, inf);
  const auto t1 = clock::now();
  const double c1 = cpu_seconds();
  const en::RunResult b = sim->run_back(nc, -inf);
  const auto t2 = clock::now();
  const double c2 = cpu_seconds();
  const double fc = static_cast<double>(f.collisions), bc = static_cast<double>(b.collisions);
  return {{"forward_per_s", fc / std::chrono::duration<double>(t1 - t0).count()},
          {"reverse_per_s", bc / std::chrono::duration<double>(t2 - t1).count()},
          {"forward_cpu_per_s", fc / (c1 - c0)},
          {"reverse_cpu_per_s", bc / (c2 - c1)},
          {"n", static_cast<double>(c.n)},
          {"phi", c.phi}};
}

}  // namespace

void add_lattice_benches(std::vector<Bench>& out) {
  struct Named {
    const char* name;
    LatticeCase c;
  };
  // the lattice engine (periodic at N = 1e4 and 1e5, area fractions 0.3, 0.5 and 0.7, and 1e6 at 0.5; walls at
  // 1e4) and the float engine on the same periodic gases (lattice/float/...), for the 2D table (issue 57)
  static const Named named[] = {{"lattice/periodic/n10000/phi0.3", {10000, 0.3, false, 1}},
                                {"lattice/periodic/n10000/phi0.5", {10000, 0.5, false, 1}},
                                {"lattice/periodic/n10000/phi0.7", {10000, 0.7, false, 1}},
                                {"lattice/periodic/n100000/phi0.3", {100000, 0.3, false, 1}},
                                {"lattice/periodic/n100000/phi0.5", {100000, 0.5, false, 1}},
                                {"lattice/periodic/n100000/phi0.7", {100000, 0.7, false, 1}},
                                {"lattice/periodic/n1000000/phi0.5", {1000000, 0.5, false, 1}},
                                {"lattice/walls/n10000/phi0.3", {10000, 0.3, true, 1}},
                                {"lattice/walls/n10000/phi0.5", {10000, 0.5, true, 1}}};
  for (const Named& m : named) {
    const LatticeCase c = m.c;
    out.push_back({m.name, "collisions/s", [c](std::uint64_t n) { return run_lattice<2>(c, n); }});
  }
  // the 3D engine (spheres) at N = 1e4, volume fractions 0.1, 0.3 and 0.45 (1e5 at 0.3 and 0.45, 1e6 at 0.3), and the float engine on
  // the same 3D gases
  static const Named named3[] = {{"lattice3d/periodic/n10000/phi0.1", {10000, 0.1, false, 1, 3}},
                                 {"lattice3d/periodic/n10000/phi0.3", {10000, 0.3, false, 1, 3}},
                                 {"lattice3d/periodic/n10000/phi0.45", {10000, 0.45, false, 1, 3}},
                                 {"lattice3d/walls/n10000/phi0.3", {10000, 0.3, true, 1, 3}},
                                 {"lattice3d/periodic/n1000/phi0.3", {1000, 0.3, false, 1, 3}},
                                 {"lattice3d/periodic/n100000/phi0.3", {100000, 0.3, false, 1, 3}},
                                 {"lattice3d/periodic/n100000/phi0.45", {100000, 0.45, false, 1, 3}},
                                 {"lattice3d/periodic/n1000000/phi0.3", {1000000, 0.3, false, 1, 3}}};
  for (const Named& m : named3) {
    const LatticeCase c = m.c;
    out.push_back({m.name, "collisions/s", [c](std::uint64_t n) { return run_lattice<3>(c, n); }});
  }
  // the cell grid against lists in lockstep (run_lockstep): the first collision where they part
  static const Named lock3[] = {{"lattice3d/lockstep/n10000/phi0.3", {10000, 0.3, false, 1, 3}},
                                {"lattice3d/lockstep/n1000/phi0.45", {1000, 0.45, false, 1, 3}},
                                {"lattice3d/lockstep/walls/n1000/phi0.45", {1000, 0.45, true, 1, 3}}};
  for (const Named& m : lock3) {
    const LatticeCase c = m.c;
    out.push_back({m.name, "first differing collision", [c](std::uint64_t n) { return run_lockstep<3>(c, n); }});
  }
  static const Named floats3[] = {{"lattice3d/float/n10000/phi0.1", {10000, 0.1, false, 1, 3}},
                                  {"lattice3d/float/n10000/phi0.3", {10000, 0.3, false, 1, 3}},
                                  {"lattice3d/float/n10000/phi0.45", {10000, 0.45, false, 1, 3}},
                                  {"lattice3d/float/n1000/phi0.3", {1000, 0.3, false, 1, 3}}};
  for (const Named& m : floats3) {
    const LatticeCase c = m.c;
    out.push_back({m.name, "collisions/s", [c](std::uint64_t n) { return run_float(c, n); }});
  }
  static const Named floats[] = {{"lattice/float/n10000/phi0.3", {10000, 0.3, false, 1}},
                                 {"lattice/float/n10000/phi0.5", {10000, 0.5, false, 1}},
                                 {"lattice/float/n10000/phi0.7", {10000, 0.7, false, 1}},
                                 {"lattice/float/n100000/phi0.3", {100000, 0.3, false, 1}},
                                 {"lattice/float/n100000/phi0.5", {100000, 0.5, false, 1}},
                                 {"lattice/float/n100000/phi0.7", {100000, 0.7, false, 1}}};
  for (const Named& m : floats) {
    const LatticeCase c = m.c;
    out.push_back({m.name, "collisions/s", [c](std::uint64_t n) { return run_float(c, n); }});
  }
  // specular dynamics (issue 53's table): the lattice engine's specular map, the lattice flux law
  // and the float engine's specular mode on the same periodic gases (2D 0.5, 3D 0.3; N 1e4, 1e5);
  // bench/specular_speed.py runs them interleaved
  using revcol::Mode;
  for (const auto& [dim, phi] : {std::pair{2, 0.5}, std::pair{3, 0.3}})
    for (std::size_t n : {std::size_t{10000}, std::size_t{100000}}) {
      const std::string tail = "/d" + std::to_string(dim) + "/n" + std::to_string(n) + (dim == 2 ? "/phi0.5" : "/phi0.3");
      const LatticeCase spec{n, phi, false, 1, dim, Mode::specular}, flux{n, phi, false, 1, dim, Mode::exact};
      out.push_back({"specular/lattice" + tail, "collisions/s", [spec](std::uint64_t k) {
                       return spec.dim == 3 ? run_lattice<3>(spec, k) : run_lattice<2>(spec, k); }});
      out.push_back({"specular/flux" + tail, "collisions/s", [flux](std::uint64_t k) {
                       return flux.dim == 3 ? run_lattice<3>(flux, k) : run_lattice<2>(flux, k); }});
      out.push_back({"specular/float" + tail, "collisions/s", [spec](std::uint64_t k) { return run_float(spec, k); }});
    }
}

}  // namespace revcol::bench
