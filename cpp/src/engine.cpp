// The event-driven engine's entry points: parsing, validation, and the choice of the
// implementation (dimension and pair operator, once) behind revcol::engine::Simulation.
// The physics and the reversal protocol are in revcol/engine/engine.hpp, the engine itself
// in engine_impl.hpp / engine_collide.hpp, instantiated per dimension in engine_<d>d.cpp.
#include "revcol/collide/common.hpp"
#include "revcol/engine/boundary.hpp"
#include "revcol/engine/engine.hpp"
#include "revcol/engine/limits.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "engine_impl.hpp"
#include "engine_operators.hpp"
#include "revcol/error.hpp"

namespace revcol::engine {

namespace {
// "'wall', 'periodic'": the names of kBoundaries, for messages.
std::string boundary_names() {
  std::string names;
  for (Boundary b : kBoundaries) names += std::string(names.empty() ? "'" : ", '") + to_string(b) + "'";
  return names;
}
}  // namespace

Boundary parse_boundary(const std::string& s) {
  for (Boundary b : kBoundaries)
    if (s == to_string(b)) return b;
  throw InvalidArgument("boundary must be one of " + boundary_names() + ", got '" + s + "'");
}

Boundary boundary_from_value(std::int64_t v) {
  for (Boundary b : kBoundaries)
    if (v == static_cast<std::int64_t>(b)) return b;
  throw InvalidArgument("boundary value " + std::to_string(v) + " names no kind (" + boundary_names() + ": 0, 1, ...)");
}

Generator parse_generator(const std::string& s) {
  if (s == "philox") return Generator::philox;
  if (s == "clcg4") return Generator::clcg4;
  throw InvalidArgument("generator must be 'philox' or 'clcg4', got '" + s + "'");
}

Mode parse_engine_mode(const std::string& s) {
  Mode m;
  if (detail::engine_only_mode(s, m)) return m;
  if (s != "exact" && s != "paper")  // the engine's message names its modes too (parse_mode knows two)
    throw InvalidArgument("mode must be 'exact', 'paper' or 'specular', got '" + s + "'");
  return parse_mode(s);
}

rng::StreamPolicy parse_engine_streams(const std::string& s) {
  if (s == "per_particle" || s == "per-particle") return rng::StreamPolicy::per_particle;
  if (s == "single") return rng::StreamPolicy::single;
  throw InvalidArgument("streams must be 'per_particle' or 'single', got '" + s +
                        "' (a per-draw policy needs a fixed draw count per collision)");
}

namespace {

void validate_config(const Config& c) {
  // every limit comes from engine/limits.hpp (the scene reader asks the same header)
  require(c.dim >= limits::kMinDim && c.dim <= limits::kMaxDim,
          [&] { return "dim must be 1, 2 or 3, got " + std::to_string(c.dim); });
  require(std::isfinite(c.diameter) && c.diameter > 0.0, "diameter must be finite and > 0");
  require(c.bits >= limits::kMinBits && c.bits <= limits::kMaxBits, [&] {
    return "bits must be in [" + std::to_string(limits::kMinBits) + ", " + std::to_string(limits::kMaxBits) + "]";
  });
  require(c.streams == rng::StreamPolicy::per_particle || c.streams == rng::StreamPolicy::single,
          "streams must be per_particle or single (a per-draw policy needs a fixed draw count per collision)");
  require(c.generator == Generator::philox || c.generator == Generator::clcg4, "generator must be philox or clcg4");
  require(std::isfinite(c.group_tol) && c.group_tol >= 0.0 && c.group_tol < limits::kMaxGroupTol,
          "group_tol must be finite and in [0, 1e-3)");
  require(std::isfinite(c.shell) && c.shell >= 0.0, "shell must be finite and >= 0 (0: from the packing fraction)");
  require(c.resort >= -1, "resort must be >= -1 (-1: chosen from N, 0: never)");
  for (int k = 0; k < 3; ++k) {
    require(std::isfinite(c.gravity[k]), "gravity must be finite");
    require(c.gravity[k] == 0.0 || (k < c.dim && has_walls(c.boundary[k])), [&] {
      return "gravity along axis " + std::to_string(k) + " needs walls on that axis (a periodic axis has no floor)";
    });
  }
  require(c.mode != Mode::paper || limits::paper_mode_allowed(c.dim),
          "paper mode has no invertible 3D pair operator (Pair3DPaper is not a bijection): use exact mode in 3D");
  for (int k = 0; k < c.dim; ++k) {
    const double L = c.box[k];
    require(std::isfinite(L) && L > 0.0, [&] { return "box length on axis " + std::to_string(k) + " must be finite and > 0"; });
    require(limits::box_ratio_fits(L, c.diameter), [&] {
      return "box length on axis " + std::to_string(k) + " is " + std::to_string(L / c.diameter) +
             " diameters: at most 2^30 (a smaller box or a larger diameter)";
    });
    if (has_walls(c.boundary[k])) {
      require(limits::wall_axis_fits(L, c.diameter), [&] {
        return "diameter " + num(c.diameter) + " is too large for the box: axis " + std::to_string(k) +
               " has length " + num(L) + " (walls need L > D)";
      });
    } else {
      require(limits::periodic_axis_fits(L, c.diameter), [&] {
        return "periodic box too small for the neighbour lists: axis " + std::to_string(k) + " has length " +
               num(L) + " < 3 diameters (L >= 3 D keeps each listed neighbour's nearest image "
               "unique with a shell of at least 0.45 D)";
      });
    }
  }
}

// Particle i's radius: half its own diameter in a mixture, else D / 2.
double radius_of(const Config& c, std::size_t i) { return 0.5 * (c.diameters.empty() ? c.diameter : c.diameters[i]); }

// A mixture's sizes: one per particle, finite, > 0, the largest equal to `diameter` and the
// smallest at least the largest / kMaxSizeRatio.
void validate_sizes(const Config& c, std::size_t n) {
  if (c.diameters.empty()) return;
  require(c.diameters.size() == n, [&] {
    return "diameters must have one entry per particle (" + std::to_string(n) + "), got " + std::to_string(c.diameters.size());
  });
  double hi = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double d = c.diameters[i];
    require(std::isfinite(d) && d > 0.0, [&] { return "diameter of particle " + std::to_string(i) + " must be finite and > 0"; });
    hi = std::max(hi, d);
  }
  require(hi == c.diameter, [&] {
    return "diameter must be the largest of the diameters (" + num(hi) + "), got " + num(c.diameter);
  });
  for (std::size_t i = 0; i < n; ++i)
    require(c.diameters[i] * limits::kMaxSizeRatio >= hi, [&] {
      return "diameter of particle " + std::to_string(i) + ", " + num(c.diameters[i]) + ", is more than " +
             std::to_string(static_cast<int>(limits::kMaxSizeRatio)) + " times smaller than the largest, " + num(hi);
    });
}

// Masses: one per particle, finite, > 0, within kMaxMassRatio of each other; not in paper mode.
void validate_masses(const Config& c, std::size_t n) {
  if (c.masses.empty()) return;
  require(c.masses.size() == n, [&] {
    return "masses must have one entry per particle (" + std::to_string(n) + "), got " + std::to_string(c.masses.size());
  });
  require(c.mode != Mode::paper, "paper mode collides equal masses only: use exact or specular mode with masses");
  double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double m = c.masses[i];
    require(std::isfinite(m) && m > 0.0, [&] { return "mass of particle " + std::to_string(i) + " must be finite and > 0"; });
    lo = std::min(lo, m);
    hi = std::max(hi, m);
  }
  require(hi <= limits::kMaxMassRatio * lo, [&] {
    return "masses range over a ratio of " + num(hi / lo) + ": at most " + num(limits::kMaxMassRatio);
  });
}

// Throws InvalidArgument naming the first pair closer than D (1 - 1e-9): a cell grid of cells >= D,
// the 3^d neighbouring cells, minimum images on periodic axes. x: n x d positions inside the box.
void check_overlaps(const Config& c, const std::vector<double>& x, std::size_t n) {
  const int d = c.dim;
  std::array<int, 3> nc{1, 1, 1};
  std::array<double, 3> cw{1, 1, 1};
  std::size_t total = 1;
  limits::capped_cell_counts(d, c.box.data(), c.diameter, limits::max_cells(n), nc.data());  // cells >= D
  for (int k = 0; k < d; ++k) {
    nc[k] = std::min(nc[k], 1 << 20);
    cw[k] = c.box[k] / nc[k];
    total *= static_cast<std::size_t>(nc[k]);
  }
  require(total <= (std::size_t{1} << 31), "box has too many cells (more than 2^31)");
  std::vector<int> head(total, -1), next(n, -1);
  std::vector<std::array<int, 3>> cc(n);
  auto index = [&](const std::array<int, 3>& q) {
    std::size_t id = 0, stride = 1;
    for (int k = 0; k < d; ++k) {
      id += static_cast<std::size_t>(q[k]) * stride;
      stride *= static_cast<std::size_t>(nc[k]);
    }
    return id;
  };
  const double min2 = c.diameter * c.diameter * (1.0 - 1e-9) * (1.0 - 1e-9);
  const bool mixed = !c.diameters.empty();  // then each pair's own contact distance
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < d; ++k) cc[i][k] = std::clamp(static_cast<int>(std::floor(x[i * d + k] / cw[k])), 0, nc[k] - 1);
    const int noff = d == 1 ? 3 : d == 2 ? 9 : 27;
    for (int o = 0; o < noff; ++o) {
      int rem = o;
      std::array<int, 3> q{0, 0, 0};
      std::array<double, 3> sh{0, 0, 0};
      bool ok = true;
      for (int k = 0; k < d; ++k) {
        int ck = cc[i][k] + rem % 3 - 1;
        rem /= 3;
        if (ck < 0 || ck >= nc[k]) {
          if (has_walls(c.boundary[k]) || nc[k] < 3) { ok = false; break; }
          if (ck < 0) { ck += nc[k]; sh[k] = -c.box[k]; } else { ck -= nc[k]; sh[k] = c.box[k]; }
        }
        q[k] = ck;
      }
      if (!ok) continue;
      for (int j = head[index(q)]; j >= 0; j = next[j]) {
        double r2 = 0.0;
        for (int k = 0; k < d; ++k) {
          const double dx = x[i * d + k] - (x[j * d + k] + sh[k]);
          r2 += dx * dx;
        }
        const double sig = mixed ? radius_of(c, i) + radius_of(c, static_cast<std::size_t>(j)) : c.diameter;
        require(r2 >= (mixed ? sig * sig * (1.0 - 1e-9) * (1.0 - 1e-9) : min2), [&] {
          return "particles " + std::to_string(j) + " and " + std::to_string(i) + " overlap: distance " +
                 num(std::sqrt(r2)) + " < " + (mixed ? "contact distance " : "diameter ") + num(sig);
        });
      }
    }
    const std::size_t id = index(cc[i]);
    next[i] = head[id];
    head[id] = static_cast<int>(i);
  }
}

// Cold validation of a state (nothing built yet).
void validate_state(const Config& c, const std::vector<double>& x, const std::vector<double>& v) {
  validate_config(c);
  const int d = c.dim;
  require(!x.empty(), "no particles (N = 0)");
  require(x.size() % d == 0, "positions must have n x dim entries");
  require(v.size() == x.size(), "velocities must have the same shape as positions");
  const std::size_t n = x.size() / d;
  require(n <= limits::max_particles(d), [&] { return limits::too_many_particles(d, n); });
  validate_sizes(c, n);
  validate_masses(c, n);
  double e = 0.0;
  for (std::size_t i = 0; i < n; ++i)
    for (int k = 0; k < d; ++k) {
      const double r = radius_of(c, i);
      const double m = c.masses.empty() ? 1.0 : c.masses[i];
      const double xk = x[i * d + k], vk = v[i * d + k];
      require(std::isfinite(xk), [&] { return "position of particle " + std::to_string(i) + " is not finite"; });
      require(std::isfinite(vk), [&] { return "velocity of particle " + std::to_string(i) + " is not finite"; });
      if (has_walls(c.boundary[k]))
        require(xk >= r && xk <= c.box[k] - r, [&] {
          return "particle " + std::to_string(i) + " is outside the box on axis " + std::to_string(k) + ": x = " +
                 num(xk) + ", allowed [" + num(r) + ", " + num(c.box[k] - r) +
                 "] (walls at 0 and L, centre at least its radius inside)";
        });
      else
        require(xk >= 0.0 && xk < c.box[k], [&] {
          return "particle " + std::to_string(i) + " is outside the periodic box on axis " + std::to_string(k) +
                 ": x = " + num(xk) + ", allowed [0, " + num(c.box[k]) + ")";
        });
      e += 0.5 * m * vk * vk;
    }
  require(std::isfinite(e), "kinetic energy overflows");
  require(e > 0.0, "zero kinetic energy: nothing would ever move");
  double vmax = 0.0;
  for (double q : v) vmax = std::max(vmax, std::fabs(q));
  require(vmax >= limits::kMinGasSpeed && vmax <= limits::max_gas_speed(static_cast<double>(n), d), [&] {
    return "largest velocity component " + num(vmax) + " is outside the speeds the operators resolve: [2^-420, 2^450 / sqrt(N d)] = [" +
           num(limits::kMinGasSpeed) + ", " + num(limits::max_gas_speed(static_cast<double>(n), d)) + "] (rescale velocities and time)";
  });
  require(std::isfinite(c.diameter / vmax), "diameter / speed overflows: rescale lengths or velocities");
  check_overlaps(c, x, n);
}

}  // namespace

namespace detail {

// The shell in diameters, from the packing fraction phi. Renewals come about once per
// h / lambda collisions when the mean free path lambda exceeds the half-shell h and more
// rarely below it, while a prediction scans ~ phi ((D + shell) / (D / 2))^d listed
// particles: the best shell grows with lambda. lambda / D is the Enskog estimate,
// 1 / (6 sqrt2 phi g) in 3D (Carnahan-Starling contact value g), pi / (8 sqrt2 phi g) in 2D
// (Henderson's g), and the free length per rod (1 - phi) / phi in 1D. The rule's constants
// fit the sweep in docs/engine.md (Throughput: the shell): the best shell measured was
// 3D ~1.0 (phi 0.05), 0.6-1.0 (0.1), 0.4-0.8 (0.3), 0.4 (0.45); 2D >= 2.4 (0.05, 0.1),
// 1.0-1.4 (0.3), 0.8 (0.5); 1D >= 8 (0.1), 4-8 (0.3), 2.4-4 (0.5). In 3D the constants
// were refit in session 22 to cachegrind's counts per collision at N = 10 976 (deterministic
// where those timings were +-10%): from the old rule's shell to the new one, instructions fell
// 4-9% and mispredicted branches 4-26% at all four densities (0.05 to 0.45), cache misses fell
// or stayed within 2% (docs/peers.md, "Session 22").
double auto_shell(int dim, double phi) {
  const double sqrt2 = std::sqrt(2.0);
  double lam, lo, base, slope, hi;
  if (dim == 3) {
    const double g = (1.0 - 0.5 * phi) / ((1.0 - phi) * (1.0 - phi) * (1.0 - phi));
    lam = 1.0 / (6.0 * sqrt2 * phi * g);
    lo = 0.55, base = 0.55, slope = 0.35, hi = 1.5;
  } else if (dim == 2) {
    const double g = (1.0 - 7.0 * phi / 16.0) / ((1.0 - phi) * (1.0 - phi));
    lam = std::numbers::pi / (8.0 * sqrt2 * phi * g);
    lo = 0.8, base = 0.6, slope = 1.0, hi = 2.5;
  } else {
    lam = (1.0 - phi) / phi;
    lo = 1.5, base = 1.5, slope = 1.0, hi = 10.0;
  }
  return std::isfinite(lam) ? std::clamp(base + slope * lam, lo, hi) : lo;
}

}  // namespace detail

std::unique_ptr<Simulation> make_simulation(const Config& c, const std::vector<double>& x,
                                            const std::vector<double>& v, double t0) {
  require(std::isfinite(t0), "start time must be finite");
  validate_state(c, x, v);
  double vmax = 0.0;
  for (double q : v) vmax = std::max(vmax, std::fabs(q));
  require(limits::clock_fits(t0, c.diameter, vmax), [&] {
    return "start time " + num(t0) + " is too large for the clock to resolve flights of one diameter (at most " +
           num(limits::kMaxClockFlights) + " D / v_max = " + num(limits::kMaxClockFlights * c.diameter / vmax) +
           "); shift the time origin";
  });
  if (c.dim == 1) return detail::make_engine<1>(c, x, v, t0);
  if (c.dim == 2) return detail::make_engine<2>(c, x, v, t0);
  return detail::make_engine<3>(c, x, v, t0);
}

namespace {

// A snapshot array of the wrong length: its name, the length wanted and what that length is.
void require_size(const char* name, std::size_t got, std::size_t want, const char* what) {
  require(got == want, [&] {
    return std::string("snapshot: ") + name + " must have " + std::to_string(want) + " entries (" + what +
           "), got " + std::to_string(got);
  });
}

void require_finite(const char* name, const std::vector<double>& a) {
  for (double q : a) require(std::isfinite(q), [&] { return std::string("snapshot: ") + name + " must be finite"; });
}

// The per-particle arrays: n x dim or n entries each (and the centre's values finite).
void check_snapshot_shapes(const Snapshot& s) {
  const std::size_t n = s.n, d = static_cast<std::size_t>(s.config.dim);
  require(n > 0, "snapshot: n must be > 0 (no particles)");
  if (!s.config.diameters.empty()) require_size("diameters", s.config.diameters.size(), n, "n, or none");
  if (!s.config.masses.empty()) require_size("masses", s.config.masses.size(), n, "n, or none");
  try {
    validate_sizes(s.config, n);
    validate_masses(s.config, n);
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(std::string("snapshot: ") + e.what());
  }
  require_size("x", s.x.size(), n * d, "n x dim");
  require_size("v", s.v.size(), n * d, "n x dim");
  require_size("cell", s.cell.size(), n * d, "n x dim");
  if (!s.centre.empty()) require_size("centre", s.centre.size(), n * d, "n x dim, or none");
  require_finite("centre", s.centre);
  require_size("t_local", s.t_local.size(), n, "n");
  require_size("stamp", s.stamp.size(), n, "n");
  require_size("ncoll", s.ncoll.size(), n, "n");
  require_size("ev_t", s.ev_t.size(), n, "n");
  require_size("ev_kind", s.ev_kind.size(), n, "n");
  require_size("ev_partner", s.ev_partner.size(), n, "n");
  require_size("ev_stamp", s.ev_stamp.size(), n, "n");
  require_size("second", s.second.size(), n, "n");
  require_size("touching", s.touching.size(), n, "n");
  require_size("netc", s.netc.size(), n, "n");
  require_size("rng", s.rng.size(), s.config.streams == rng::StreamPolicy::single ? 1 : n, "one per stream: n, or 1");
}

// The clock and the velocities: finite, resolvable, and still carrying the conserved energy and
// momentum.
void check_snapshot_motion(const Snapshot& s) {
  const std::size_t n = s.n, d = static_cast<std::size_t>(s.config.dim);
  for (auto q : s.touching) require(q == 0 || q == 1, "snapshot: touching must be 0 or 1");
  require(std::isfinite(s.time), "snapshot: time must be finite");
  require(std::isfinite(s.start_time), "snapshot: start_time must be finite");
  require_finite("t_local", s.t_local);
  require_finite("x", s.x);
  require_finite("v", s.v);
  double vmax = 0.0;
  for (double q : s.v) vmax = std::max(vmax, std::fabs(q));
  require(limits::clock_fits(s.time, s.config.diameter, vmax) && limits::clock_fits(s.start_time, s.config.diameter, vmax),
          "snapshot: time or start_time too large for the clock to resolve flights of one diameter (|t| v_max / D > 4.5e9)");
  require(vmax >= limits::kMinGasSpeed && vmax <= limits::max_gas_speed(static_cast<double>(n), static_cast<int>(d)),
          "snapshot: v outside the speeds the operators resolve ([2^-420, 2^450 / sqrt(N d)] for v_max)");
  require(std::isfinite(s.energy0) && s.energy0 > 0.0, "snapshot: energy0 must be finite and > 0");
  for (double q : s.momentum0) require(std::isfinite(q), "snapshot: momentum0 must be finite");
  // both are conserved: the velocities must still carry them (round-off keeps them within
  // ~1e-12 over 10^9 collisions; 1e-6 is the bar). Momentum only on periodic axes without
  // bounce walls (specular walls flip their own component, bounce walls every component).
  double e = 0.0, mass = 0.0;
  std::array<double, 3> p{};
  const auto& g = s.config.gravity;  // a field: velocities and heights at the clock
  for (std::size_t i = 0; i < n; ++i) {
    const double m = s.config.masses.empty() ? 1.0 : s.config.masses[i];
    const double dt = s.time - s.t_local[i];
    mass += m;
    for (std::size_t k = 0; k < d; ++k) {
      const double vk = g[k] == 0.0 ? s.v[i * d + k] : s.v[i * d + k] + g[k] * dt;
      e += 0.5 * m * vk * vk;
      p[k] += m * vk;
      if (g[k] != 0.0) {
        const double x = s.x[i * d + k] + s.v[i * d + k] * dt + 0.5 * g[k] * dt * dt;
        e += m * (g[k] < 0.0 ? -g[k] * x : g[k] * (s.config.box[k] - x));
      }
    }
  }
  require(std::fabs(e - s.energy0) <= 1e-6 * s.energy0,
          "snapshot: energy0 is not the kinetic energy of v (energy is conserved; 1e-6 relative)");
  bool bounce = false;
  for (std::size_t k = 0; k < d; ++k) bounce = bounce || s.config.boundary[k] == Boundary::bounce;
  const double scale = std::sqrt(2.0 * s.energy0 * mass);
  for (std::size_t k = 0; k < d && !bounce; ++k)
    require(s.config.boundary[k] != Boundary::periodic || std::fabs(p[k] - s.momentum0[k]) <= 1e-6 * scale,
            "snapshot: momentum0 is not the momentum of v on a periodic axis (it is conserved; 1e-6 of sqrt(2 E0 M))");
}

// The list centres inside the box, and the positions at the clock inside the box (walls: to
// 1e-9 D) and without overlaps (a damaged diameter or position made the list build spin
// forever: the fuzz suite, issue 17).
void check_snapshot_positions(const Snapshot& s) {
  const std::size_t n = s.n, d = static_cast<std::size_t>(s.config.dim);
  for (std::size_t i = 0; i < s.centre.size(); ++i)
    require(s.centre[i] >= 0.0 && s.centre[i] <= s.config.box[i % d], "snapshot: centre (a list centre) outside the box");
  const Config& c = s.config;
  const double slack = 1e-9 * c.diameter;
  std::vector<double> now(n * d);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t k = 0; k < d; ++k) {
      const double r = radius_of(c, i);
      const double dt = s.time - s.t_local[i];
      double q = s.x[i * d + k] + s.v[i * d + k] * dt + (c.gravity[k] == 0.0 ? 0.0 : 0.5 * c.gravity[k] * dt * dt);
      require(std::isfinite(q), "snapshot: x + v (time - t_local), a position at the clock, is not finite");
      if (has_walls(c.boundary[k])) {
        require(q >= r - slack && q <= c.box[k] - r + slack, [&] {
          return "snapshot: particle " + std::to_string(i) + " (x, v, t_local) is outside the box on axis " +
                 std::to_string(k) + " at the clock (x = " + num(q) + ")";
        });
      } else {
        q -= c.box[k] * std::floor(q / c.box[k]);
        if (!(q < c.box[k])) q = 0.0;  // q / L rounded up to 1
      }
      now[i * d + k] = q;
    }
  try {
    check_overlaps(c, now, n);
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(std::string("snapshot: x (positions at the clock), diameter: ") + e.what());
  }
}

// The logs: the rare log's count, the exact-pre log ((stream, counter) keys, values that are
// velocities) and the wall-mask log ((smallest id, its net count) keys, members, masks).
void check_snapshot_logs(const Snapshot& s) {
  const std::size_t n = s.n, d = static_cast<std::size_t>(s.config.dim);
  require(s.log_pushed >= s.log_cells.size(), "snapshot: log_pushed is smaller than log_cells");
  require(s.pre_keys.size() == 2 * s.pre_sizes.size(), "snapshot: pre_keys must hold 2 per pre_sizes entry");
  for (std::size_t e = 0; e < s.pre_sizes.size(); ++e)
    require(s.pre_keys[2 * e] < s.rng.size(), "snapshot: pre_keys names a stream outside the rng streams");
  std::uint64_t total = 0;
  for (auto q : s.pre_sizes) {
    require(q > 0 && q <= n * d, "snapshot: pre_sizes entries must be in [1, n dim]");
    total += q;
  }
  require(total == s.pre_vals.size(), "snapshot: pre_sizes do not add up to pre_vals");
  for (double q : s.pre_vals)
    require(std::isfinite(q) && std::fabs(q) <= kMaxSpeed, "snapshot: pre_vals must be finite velocities (|v| <= 2^450)");
  require(s.pre_pushed >= s.pre_sizes.size(), "snapshot: pre_pushed is smaller than the exact-pre log");
  // the wall-mask log: masks W1 | W2 << 8
  require(s.wall_keys.size() == 2 * s.wall_sizes.size(), "snapshot: wall_keys must hold 2 per wall_sizes entry");
  for (std::size_t e = 0; e < s.wall_sizes.size(); ++e)
    require(s.wall_keys[2 * e] < n, "snapshot: wall_keys names a particle outside [0, n)");
  std::uint64_t wm = 0;
  for (auto q : s.wall_sizes) {
    require(q >= 2 && q <= n, "snapshot: wall_sizes entries must be in [2, n]");
    wm += q;
  }
  require(wm == s.wall_masks.size() && wm == s.wall_ids.size() && wm == s.wall_netc.size(),
          "snapshot: wall_sizes do not add up to wall_masks, wall_ids and wall_netc");
  require_size("wall_times", s.wall_times.size(), s.wall_sizes.size(), "one per wall_sizes entry");
  require_finite("wall_times", s.wall_times);
  for (auto q : s.wall_ids) require(q < n, "snapshot: wall_ids names a particle outside [0, n)");
  // a Reflection (boundary.hpp): bit k flips component k (k < dim), or kReversed; W1 | W2 << 8
  const std::uint64_t one = ((std::uint64_t{1} << d) - 1) | kReversed;
  for (auto q : s.wall_masks)
    require((q & ~(one | one << 8)) == 0, "snapshot: wall_masks holds a reflection on an axis that does not exist");
}

}  // namespace

// Every snapshot field checked before anything is built, each message naming its field
// (issue 17's crafted-checkpoint suite, tests/python/test_checkpoints.py). The checks run in
// this order (shapes before values), so a snapshot damaged in two places names the same field.
void validate_snapshot(const Snapshot& s) {
  validate_config(s.config);
  check_snapshot_shapes(s);
  check_snapshot_motion(s);
  check_snapshot_positions(s);
  check_snapshot_logs(s);
}

std::unique_ptr<Simulation> restore_simulation(const Snapshot& s) {
  validate_snapshot(s);
  const std::size_t d = static_cast<std::size_t>(s.config.dim);
  if (d == 1) return detail::restore_engine<1>(s);
  if (d == 2) return detail::restore_engine<2>(s);
  return detail::restore_engine<3>(s);
}

}  // namespace revcol::engine
