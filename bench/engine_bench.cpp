// Benchmarks of the event-driven engine (revcol/engine/engine.hpp): collisions per second
// forward and in reverse, one core, exact mode, flux law unless told otherwise.
//
//   engine/d3/n10000/phi0.3   engine/d3/n10000/phi0.45   engine/d3/n100000/phi0.3
//   engine/d3/n100000/phi0.45 engine/d2/n10000/phi0.5    engine/custom
//
// --collisions is how many collisions are timed forward, then the same number back. Before
// timing, the gas is equilibrated for `warm` collisions per particle (default 10) from its
// random start. engine/custom takes everything from the environment, and every key there
// also overrides the named cases:
//
//   REVCOL_ENGINE="d=3,n=10000,phi=0.3,boundary=periodic,law=flux,mode=exact,seed=1,warm=10,groups=1,shell=0,observe=0"
//
// (shell: the neighbour-list shell in diameters, Config::shell; 0, the default, chooses it from phi;
// observe: 1 observes the timed forward run's scalars, 2 also a 50-bin speed histogram and 10
// slabs (revcol/engine/observe.hpp); run_back ends the observation, so the reverse is unobserved;
// shuffle=1 numbers the start's particles in a random order, as a gas long diffused from a
// sorted start is; resort: Config::resort, the spatial re-sort of the particles' storage)
//
// Metrics: forward_per_s, reverse_per_s, events_per_collision, invalid_per_collision,
// resorts_timed (storage re-sorts in the timed runs), log_bytes, engine_bytes,
// peak_rss_bytes (the process's VmHWM: run one case per process to read it per case),
// roundtrip_rel_error_v (max |v - v_start| / max |v_start| after
// forward and back: beyond the horizon at large --collisions, a measure, not a check).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <string>

#include "bench.hpp"
#include "revcol/engine/engine.hpp"
#include "revcol/engine/init.hpp"
#include "revcol/engine/observe.hpp"
#include "revcol/error.hpp"

namespace revcol::bench {
namespace {

namespace en = revcol::engine;

struct Case {
  int d = 3;
  std::size_t n = 10000;
  double phi = 0.3;
  std::string boundary = "periodic";
  Law law = Law::flux;
  Mode mode = Mode::exact;
  std::uint64_t seed = 1;
  double warm = 10.0;
  bool groups = true;
  double shell = 0.0;  // Config::shell: 0 chooses it from phi
  int observe = 0;     // 0 off, 1 scalars, 2 scalars + speed histogram + slabs
  bool shuffle = false;  // the start's ids in a random order (a gas long diffused from a sorted start)
  int resort = -1;       // Config::resort: -1 chooses from N, 0 never, R every R renewals per particle
};

void apply_environment(Case& c) {
  apply_settings("REVCOL_ENGINE", "d, n, phi, boundary, law, mode, seed, warm, groups, shell, observe, shuffle, resort",
                 [&](const std::string& key, const std::string& value) {
                   if (key == "d") c.d = std::stoi(value);
                   else if (key == "n") c.n = std::stoull(value);
                   else if (key == "phi") c.phi = std::stod(value);
                   else if (key == "boundary") c.boundary = value;
                   else if (key == "law") c.law = parse_law(value);
                   else if (key == "mode") c.mode = revcol::engine::parse_engine_mode(value);
                   else if (key == "seed") c.seed = std::stoull(value);
                   else if (key == "warm") c.warm = std::stod(value);
                   else if (key == "groups") c.groups = value != "0";
                   else if (key == "shell") c.shell = std::stod(value);
                   else if (key == "observe") c.observe = std::stoi(value);
                   else if (key == "shuffle") c.shuffle = value != "0";
                   else if (key == "resort") c.resort = std::stoi(value);
                   else return false;
                   return true;
                 });
}

double peak_rss_bytes() {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) * 1024.0;
  return 0.0;
}

// Renumbers the particles of st in a random order (Fisher-Yates from a fixed generator): the
// same gas, its ids no longer following the lattice the start was built on.
void shuffle_ids(en::InitialState& st, std::uint64_t seed) {
  const int d = st.config.dim;
  const std::size_t n = st.x.size() / static_cast<std::size_t>(d);
  std::uint64_t s = seed * 0x9E3779B97F4A7C15ull + 1;
  for (std::size_t i = n; i > 1; --i) {
    s = s * 6364136223846793005ull + 1442695040888963407ull;
    const std::size_t j = static_cast<std::size_t>((s >> 33) % i);
    for (int k = 0; k < d; ++k) {
      std::swap(st.x[(i - 1) * d + k], st.x[j * d + k]);
      std::swap(st.v[(i - 1) * d + k], st.v[j * d + k]);
    }
  }
}

std::vector<Metric> run_case(Case c, std::uint64_t nc) {
  apply_environment(c);
  en::Config cfg;
  cfg.dim = c.d;
  for (int k = 0; k < 3; ++k) cfg.boundary[k] = en::parse_boundary(c.boundary);
  cfg.law = c.law;
  cfg.mode = c.mode;
  cfg.seed = static_cast<std::uint32_t>(c.seed);
  cfg.groups = c.groups;
  cfg.shell = c.shell;
  cfg.resort = c.resort;
  en::InitialState st = en::random_state(cfg, c.n, c.phi, c.seed);
  if (c.shuffle) shuffle_ids(st, c.seed);
  auto sim = en::make_simulation(st.config, st.x, st.v);
  const auto warm = static_cast<std::uint64_t>(c.warm * static_cast<double>(c.n) / 2.0);
  if (warm > 0) sim->run(warm, std::numeric_limits<double>::infinity());
  const auto v0 = sim->velocities();
  const en::Diagnostics d0 = sim->diagnostics();
  if (c.observe > 0) {
    en::ObserveConfig oc;
    if (c.observe > 1) {
      oc.speed_bins = 50;
      oc.slabs = 10;
    }
    sim->observe(oc);
  }
  using clock = std::chrono::steady_clock;
  const auto t0 = clock::now();
  const en::RunResult f = sim->run(nc, std::numeric_limits<double>::infinity());
  const auto t1 = clock::now();
  const en::Diagnostics d1 = sim->diagnostics();
  const en::RunResult b = sim->run_back(nc, -std::numeric_limits<double>::infinity());
  const auto t2 = clock::now();
  const double fs = std::chrono::duration<double>(t1 - t0).count();
  const double bs = std::chrono::duration<double>(t2 - t1).count();
  const auto v1 = sim->velocities();
  double vmax = 0.0, err = 0.0;
  for (std::size_t i = 0; i < v0.size(); ++i) {
    vmax = std::fmax(vmax, std::fabs(v0[i]));
    err = std::fmax(err, std::fabs(v1[i] - v0[i]));
  }
  const double coll = static_cast<double>(f.collisions);
  return {{"forward_per_s", coll / fs},
          {"reverse_per_s", static_cast<double>(b.collisions) / bs},
          {"events_per_collision", static_cast<double>(f.events) / coll},
          {"invalid_per_collision",
           static_cast<double>(d1.counters.invalid_events - d0.counters.invalid_events) / coll},
          {"log_bytes", static_cast<double>(sim->diagnostics().log_bytes)},
          {"engine_bytes", static_cast<double>(sim->memory_bytes())},
          {"peak_rss_bytes", peak_rss_bytes()},
          {"roundtrip_rel_error_v", err / vmax},
          {"resorts_timed", static_cast<double>(sim->diagnostics().storage_resorts - d0.storage_resorts)},
          {"n", static_cast<double>(c.n)},
          {"phi", c.phi},
          {"dim", static_cast<double>(c.d)}};
}

}  // namespace

void add_engine_benches(std::vector<Bench>& out) {
  struct Named {
    const char* name;
    int d;
    std::size_t n;
    double phi;
  };
  static const Named named[] = {{"engine/d3/n10000/phi0.3", 3, 10000, 0.3},
                                {"engine/d3/n10000/phi0.45", 3, 10000, 0.45},
                                {"engine/d3/n100000/phi0.3", 3, 100000, 0.3},
                                {"engine/d3/n100000/phi0.45", 3, 100000, 0.45},
                                {"engine/d2/n10000/phi0.5", 2, 10000, 0.5}};
  for (const Named& m : named) {
    Case c;
    c.d = m.d;
    c.n = m.n;
    c.phi = m.phi;
    out.push_back({m.name, "collisions/s", [c](std::uint64_t n) { return run_case(c, n); }});
  }
  out.push_back({"engine/custom", "collisions/s", [](std::uint64_t n) { return run_case(Case{}, n); }});
}

}  // namespace revcol::bench
