// Random initial states for the engine (engine/init.hpp): random sequential addition or a
// jittered crystal in any box, Gaussian (or equal-speed) velocities. Draws come from Philox
// keys {stream, seed} with streams 0xFFFFFF00+ (never a particle id the engine uses for
// collisions).
#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>
#include <vector>

#include "revcol/engine/engine.hpp"
#include "revcol/engine/init.hpp"
#include "revcol/engine/limits.hpp"
#include "revcol/error.hpp"
#include "revcol/rng/philox.hpp"
#include "init_relax.hpp"

namespace revcol::engine {
namespace {

struct Draws {
  rng::Philox gen;
  explicit Draws(std::uint32_t stream, std::uint64_t seed)
      : gen({stream, static_cast<std::uint32_t>(seed)}, 0) {}
  double u() { return gen.next(); }
  double normal() {  // Box-Muller, one value per call (the other discarded: simple, deterministic)
    const double a = u(), b = u();
    return std::sqrt(-2.0 * std::log(a)) * std::cos(2.0 * limits::kPi * b);
  }
};

// The box as the placements see it: per axis its length, whether it is walled, and the
// range [lo, hi] a centre may take (a wall keeps centres D/2 (1 + 2e-6) inside).
struct Geometry {
  int d = 0;
  double D = 1.0;
  double L[3] = {1, 1, 1}, lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  bool wall[3] = {false, false, false};

  Geometry(const Config& c) : d(c.dim), D(c.diameter) {
    for (int k = 0; k < d; ++k) {
      L[k] = c.box[k];
      wall[k] = has_walls(c.boundary[k]);  // reflecting or bounce-back walls
      // a margin of 1e-6 D from the walls: a particle touching a wall at the start would be
      // at an event at t0, which a reversed run cannot tell from a departure (engine.hpp)
      lo[k] = wall[k] ? 0.5 * D * (1.0 + limits::kWallMargin) : 0.0;
      hi[k] = wall[k] ? L[k] - 0.5 * D * (1.0 + limits::kWallMargin) : L[k];
    }
  }
};

// Random sequential addition into x (n x d); false when it gives up.
bool place_rsa(const Geometry& g, std::size_t n, Draws& pos, std::vector<double>& x) {
  const int d = g.d;
  int nc[3] = {1, 1, 1};
  double cw[3] = {1, 1, 1};
  std::size_t total = 1;
  limits::capped_cell_counts(d, g.L, g.D, limits::max_cells(n), nc);  // cells >= D, at most max_cells(n) of them
  for (int k = 0; k < d; ++k) {
    cw[k] = g.L[k] / nc[k];
    total *= static_cast<std::size_t>(nc[k]);
  }
  std::vector<std::vector<int>> cells(total);
  const double min2 = g.D * g.D * (1.0 + limits::kMinGap);
  const std::size_t max_tries = 1000 * n + 100000;
  const int noff = d == 1 ? 3 : d == 2 ? 9 : 27;
  std::size_t tries = 0;
  for (std::size_t i = 0; i < n; ++i) {
    for (;;) {
      if (++tries >= max_tries) return false;
      double p[3];
      int cc[3];
      for (int k = 0; k < d; ++k) {
        p[k] = g.lo[k] + (g.hi[k] - g.lo[k]) * pos.u();
        if (p[k] >= g.L[k]) p[k] = 0.0;
        cc[k] = std::min(nc[k] - 1, static_cast<int>(p[k] / cw[k]));
      }
      bool ok = true;
      for (int o = 0; o < noff && ok; ++o) {  // the 3^d cells around, periodic images included
        int rem = o;
        std::size_t id = 0, stride = 1;
        double sh[3] = {0, 0, 0};
        bool in = true;
        for (int k = 0; k < d; ++k) {
          int ck = cc[k] + rem % 3 - 1;
          rem /= 3;
          if (ck < 0 || ck >= nc[k]) {
            if (g.wall[k] || nc[k] < 3) { in = false; break; }
            if (ck < 0) { ck += nc[k]; sh[k] = -g.L[k]; } else { ck -= nc[k]; sh[k] = g.L[k]; }
          }
          id += static_cast<std::size_t>(ck) * stride;
          stride *= static_cast<std::size_t>(nc[k]);
        }
        if (!in) continue;
        for (int j : cells[id]) {
          double r2 = 0.0;
          for (int k = 0; k < d; ++k) {
            const double dx = p[k] - (x[j * d + k] + sh[k]);
            r2 += dx * dx;
          }
          if (r2 < min2) { ok = false; break; }
        }
      }
      if (!ok) continue;
      std::size_t id = 0, stride = 1;
      for (int k = 0; k < d; ++k) {
        x[i * d + k] = p[k];
        id += static_cast<std::size_t>(cc[k]) * stride;
        stride *= static_cast<std::size_t>(nc[k]);
      }
      cells[id].push_back(static_cast<int>(i));
      break;
    }
  }
  return true;
}

// The nearest-site distance of a crystal of spacings a[0..d): square (1D/2D) or
// face-centred cubic (3D: min(a1, |(a1, a2)| / 2) over the two smallest spacings, written
// so that a cube gives a / sqrt(2) to the bit).
double nearest_site(int d, const double* a) {
  double s0 = a[0], s1 = d > 1 ? a[1] : a[0];  // the two smallest spacings, s0 <= s1
  if (s1 < s0) std::swap(s0, s1);
  if (d < 3) return s0;
  if (a[2] < s0) {
    s1 = s0;
    s0 = a[2];
  } else if (a[2] < s1) {
    s1 = a[2];
  }
  const double r = s1 / s0;
  return std::min(s0, s0 / std::sqrt(2.0) * std::sqrt(0.5 * (1.0 + r * r)));
}

// A jittered crystal into x (n x d); false when the sites are closer than D. `tight`: on a
// walled axis the outer layers lie on the walls' margins (spacing (hi - lo) / (m - 1/2) in 3D,
// (hi - lo) / (m - 1) in 2D, against (hi - lo) / m with half a layer's gap at each wall): the
// last resort of a dense walled start (issue 58: spheres-3d, 1000 spheres with walls on z, did
// not fit above volume fraction 0.6). It is tried only when the other placements fail, so every
// start that fitted before is the same, bit for bit.
bool place_crystal(const Geometry& g, std::size_t n, Draws* pos, std::vector<double>* x, bool tight) {
  const int d = g.d;
  const int basis = d == 3 ? 4 : 1;
  int m[3] = {1, 1, 1};
  auto sites_of = [&] {
    std::size_t s = static_cast<std::size_t>(basis);
    for (int k = 0; k < d; ++k) s *= static_cast<std::size_t>(m[k]);
    return s;
  };
  bool cube = true;
  for (int k = 1; k < d; ++k) cube = cube && g.L[k] == g.L[0];
  double ak[3] = {1.0, 1.0, 1.0};
  // layer spans of a cell along an axis: the sites' offsets are 0 and 1/2 (3D) or 0 (2D) tight
  const double last = d == 3 ? 0.5 : 0.0;
  auto spacing = [&](int k, int mk) {
    const bool t = tight && g.wall[k] && mk + last > 1.0;
    return (g.hi[k] - g.lo[k]) / (t ? mk - 1 + last : mk);
  };
  // The cell counts per axis that hold N: `same`, the same m on every axis (what random_state
  // always did in a cube); else refine the axis whose refined spacing stays widest (ties: the
  // lowest axis), the counts that hold N with the largest smallest spacing. True when the
  // nearest sites are then at least D apart.
  auto counts = [&](bool same) {
    m[0] = m[1] = m[2] = 1;
    while (sites_of() < n) {
      if (same) {
        for (int k = 0; k < d; ++k) ++m[k];
        continue;
      }
      int best = 0;
      for (int k = 1; k < d; ++k)
        if (spacing(k, m[k] + 1) > spacing(best, m[best] + 1)) best = k;
      ++m[best];
    }
    for (int k = 0; k < d; ++k) ak[k] = spacing(k, m[k]);
    return nearest_site(d, ak) >= g.D * (1.0 + limits::kLatticeGap);
  };
  // a cube whose equal counts crowd the sites (walls shrink the usable box: 1000 spheres at
  // volume fraction 0.45 in a walled cube) takes unequal counts (6 x 6 x 7 cells there)
  if (!counts(cube) && !(cube && counts(false))) return false;
  if (pos == nullptr) return true;  // whether it fits, placing nothing (densest_crystal)
  const double nearest = nearest_site(d, ak);
  const double jitter = 0.49 * (nearest - g.D) / std::sqrt(static_cast<double>(d));
  static constexpr double fcc[4][3] = {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}};
  const std::size_t sites = sites_of();
  std::vector<std::size_t> idx(sites);
  std::iota(idx.begin(), idx.end(), std::size_t{0});
  for (std::size_t i = 0; i < n; ++i) {  // partial Fisher-Yates
    const std::size_t j = i + static_cast<std::size_t>(pos->u() * static_cast<double>(sites - i));
    std::swap(idx[i], idx[std::min(j, sites - 1)]);
  }
  std::sort(idx.begin(), idx.begin() + static_cast<std::ptrdiff_t>(n));
  for (std::size_t i = 0; i < n; ++i) {
    std::size_t q = idx[i];
    const std::size_t b = q % static_cast<std::size_t>(basis);
    q /= static_cast<std::size_t>(basis);
    for (int k = 0; k < d; ++k) {
      const int ck = static_cast<int>(q % static_cast<std::size_t>(m[k]));
      q /= static_cast<std::size_t>(m[k]);
      const bool t = tight && g.wall[k] && m[k] + last > 1.0;
      const double off = t ? (d == 3 ? fcc[b][k] : 0.0) : d == 3 ? fcc[b][k] + 0.25 : 0.5;
      double p = g.lo[k] + (ck + off) * ak[k] + jitter * (2.0 * pos->u() - 1.0);
      p = std::clamp(p, g.lo[k], g.hi[k]);
      if (p >= g.L[k]) p -= g.L[k];
      (*x)[i * d + k] = p;
    }
  }
  return true;
}

// Velocities into v (n x d): see init.hpp.
void draw_velocities(int d, std::size_t n, std::uint64_t seed, double energy, bool equal_speeds,
                     std::vector<double>& v) {
  Draws vel(0xFFFFFF01u, seed);
  if (equal_speeds) {
    for (std::size_t i = 0; i < n; ++i) {
      double nrm2 = 0.0;
      do {
        nrm2 = 0.0;
        for (int k = 0; k < d; ++k) {
          v[i * d + k] = vel.normal();
          nrm2 += v[i * d + k] * v[i * d + k];
        }
      } while (!(nrm2 > 0.0));
      const double nrm = std::sqrt(nrm2);
      for (int k = 0; k < d; ++k) v[i * d + k] /= nrm;
    }
  } else {
    for (auto& q : v) q = vel.normal();
    if (n > 1)
      for (int k = 0; k < d; ++k) {
        double mean = 0.0;
        for (std::size_t i = 0; i < n; ++i) mean += v[i * d + k];
        mean /= static_cast<double>(n);
        for (std::size_t i = 0; i < n; ++i) v[i * d + k] -= mean;
      }
  }
  double e = 0.0;
  for (double q : v) e += 0.5 * q * q;
  require(e > 0.0, "drawn velocities have zero kinetic energy (N = 1 with zero momentum?)");
  const double target = energy > 0.0 ? energy : 0.5 * static_cast<double>(n) * d;
  require(std::isfinite(target), "kinetic energy must be finite");
  const double scale = std::sqrt(target / e);
  for (auto& q : v) q *= scale;
}

// Unequal masses (c.masses): each velocity divided by sqrt(m) (equipartition), the centre of
// mass brought to rest (sum m v = 0), the kinetic energy sum m v^2 / 2 rescaled to the target.
void weigh_velocities(const Config& c, std::size_t n, double energy, std::vector<double>& v) {
  if (c.masses.empty()) return;
  const int d = c.dim;
  require(c.masses.size() == n, [&] {
    return "masses must have one entry per particle (" + std::to_string(n) + "), got " + std::to_string(c.masses.size());
  });
  double total = 0.0;
  for (const double m : c.masses) {
    require(std::isfinite(m) && m > 0.0, "every mass must be finite and > 0");
    total += m;
  }
  for (std::size_t i = 0; i < n; ++i)
    for (int k = 0; k < d; ++k) v[i * d + k] /= std::sqrt(c.masses[i]);
  if (n > 1)
    for (int k = 0; k < d; ++k) {
      double p = 0.0;
      for (std::size_t i = 0; i < n; ++i) p += c.masses[i] * v[i * d + k];
      for (std::size_t i = 0; i < n; ++i) v[i * d + k] -= p / total;
    }
  double e = 0.0;
  for (std::size_t i = 0; i < n; ++i)
    for (int k = 0; k < d; ++k) e += 0.5 * c.masses[i] * v[i * d + k] * v[i * d + k];
  require(e > 0.0, "drawn velocities have zero kinetic energy (N = 1 with zero momentum?)");
  const double scale = std::sqrt((energy > 0.0 ? energy : 0.5 * static_cast<double>(n) * d) / e);
  for (auto& q : v) q *= scale;
}

// The packing fraction (3 significant digits, rounded down) of the densest box of c's shape
// and boundaries, scaled alike on every axis, in which a crystal of n fits (either placement).
double densest_crystal(const Config& c, std::size_t n) {
  auto fits = [&](double scale) {
    Config s = c;
    for (int k = 0; k < c.dim; ++k) s.box[k] = c.box[k] * scale;
    const Geometry g(s);
    return place_crystal(g, n, nullptr, nullptr, false) || place_crystal(g, n, nullptr, nullptr, true);
  };
  double lo = 1.0, hi = 2.0;  // fits(hi): the box twice as long on every axis
  while (!fits(hi) && hi < 1e6) hi *= 2.0;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (fits(mid) ? hi : lo) = mid;
  }
  double vol = 1.0;
  for (int k = 0; k < c.dim; ++k) vol *= c.box[k] * hi;
  const double phi = static_cast<double>(n) * particle_volume(c.dim, c.diameter) / vol;
  return std::floor(phi * 1000.0) / 1000.0;
}

// The start in c's box (validated by the caller): the preferred placement, then under
// `fallback` the other one; each placement restarts the position stream.
InitialState start_in_box(const Config& c, std::size_t n, std::uint64_t seed, double energy, bool rsa,
                          bool fallback, bool equal_speeds) {
  const Geometry g(c);
  InitialState s;
  s.x.assign(n * c.dim, 0.0);
  s.v.assign(n * c.dim, 0.0);
  auto place = [&](bool use_rsa, bool tight = false) {
    Draws pos(0xFFFFFF00u, seed);
    return use_rsa ? place_rsa(g, n, pos, s.x) : place_crystal(g, n, &pos, &s.x, tight);
  };
  bool walled = false;
  for (int k = 0; k < c.dim; ++k) walled = walled || g.wall[k];
  if (!place(rsa) && !(fallback && place(!rsa)) && !((!rsa || fallback) && walled && place(false, true))) {
    if (rsa && !fallback)
      throw InvalidArgument("random sequential addition did not place every particle; use init='crystal'");
    throw InvalidArgument(std::to_string(n) + " particles of diameter " + num(c.diameter) +
                          " do not fit on a crystal in this box (nearest sites closer than D)" +
                          (fallback ? ", nor by random sequential addition" : "") +
                          ": make the box larger or the packing fraction lower (with these boundaries a crystal of " +
                          std::to_string(n) + " fits up to a packing fraction of " + num(densest_crystal(c, n)) + ")");
  }
  draw_velocities(c.dim, n, seed, energy, equal_speeds, s.v);
  weigh_velocities(c, n, energy, s.v);
  s.config = c;
  return s;
}

// The relaxed start in c's box (validated by the caller): centres uniform in their ranges at
// their own diameters (c.diameters, or c.diameter for every particle), the overlaps relaxed
// away (init_relax.hpp), velocities as start_in_box's.
InitialState relax_in_box(const Config& c, std::size_t n, std::uint64_t seed, double energy, bool equal_speeds,
                          const InterruptCheck& interrupt) {
  const int d = c.dim;
  const std::vector<double> diam = c.diameters.empty() ? std::vector<double>(n, c.diameter) : c.diameters;
  double vol = 1.0, own = 0.0;
  for (int k = 0; k < d; ++k) vol *= c.box[k];
  for (const double q : diam) own += limits::particle_volume(d, q);
  const double phi = own / vol;
  require(phi <= limits::max_relax_fraction(d), [&] {
    return "packing fraction " + num(phi) + " is above what a relaxed random start reaches (" +
           num(limits::max_relax_fraction(d)) + " in " + std::to_string(d) + "D)";
  });
  detail::RelaxBox box;
  box.d = d;
  for (int k = 0; k < d; ++k) {  // (the caller checked the largest diameter against the walls)
    box.L[k] = c.box[k];
    box.wall[k] = has_walls(c.boundary[k]);
  }
  InitialState s;
  s.x.assign(n * d, 0.0);
  s.v.assign(n * d, 0.0);
  Draws pos(0xFFFFFF00u, seed);
  for (std::size_t i = 0; i < n; ++i)
    for (int k = 0; k < d; ++k) {
      const double m = box.wall[k] ? 0.5 * diam[i] * (1.0 + limits::kWallMargin) : 0.0;
      double p = m + (c.box[k] - 2.0 * m) * pos.u();
      if (!box.wall[k] && p >= c.box[k]) p = 0.0;
      s.x[i * d + k] = p;
    }
  const detail::RelaxResult r = detail::relax_overlaps(box, diam, s.x, limits::kRelaxSteps, interrupt);
  if (!r.done)
    throw InvalidArgument("the overlaps of a random placement did not relax away in " + std::to_string(r.steps) +
                          " steps at packing fraction " + num(phi) + " (the largest left: " + num(r.overlap) +
                          " of a contact distance): it is at or near this gas's jamming (random packings of "
                          "equal spheres jam near 0.64, of a 1:1 mixture of size ratio 1.4 near 0.65 in 3D and "
                          "0.84 in 2D); make the packing fraction lower");
  draw_velocities(d, n, seed, energy, equal_speeds, s.v);
  weigh_velocities(c, n, energy, s.v);
  s.config = c;
  return s;
}

void check_energy(double energy) {
  // 0 asks for the default (kT = 1); NaN or a negative energy was taken as the default silently (issue 17)
  require(std::isfinite(energy) && energy >= 0.0,
          "kinetic energy must be finite and > 0 (or omitted for kT = 1), got " + num(energy));
}

void check_common(const Config& c, std::size_t n, std::uint64_t seed) {
  require(c.dim >= limits::kMinDim && c.dim <= limits::kMaxDim, "dim must be 1, 2 or 3");
  require(n > 0, "no particles (N = 0)");
  // before anything n-sized is allocated
  require(n <= limits::max_particles(c.dim), [&] { return limits::too_many_particles(c.dim, n); });
  require(std::isfinite(c.diameter) && c.diameter > 0.0, "diameter must be finite and > 0");
  require(seed <= limits::kMaxSeed, "seed must be < 2^32");
}

}  // namespace

Placement parse_placement(const std::string& s) {
  if (s == "auto") return Placement::automatic;
  if (s == "rsa") return Placement::rsa;
  // "lattice" is the crystal's old name, still read ("lattice" names the integer engine now)
  if (s == "crystal" || s == "lattice") return Placement::crystal;
  if (s == "relax") return Placement::relax;
  throw InvalidArgument("init must be 'auto', 'rsa', 'crystal' or 'relax', got '" + s + "'");
}

double particle_volume(int d, double D) { return limits::particle_volume(d, D); }

double box_fraction(const Config& c, std::size_t n) {
  double vol = 1.0;
  for (int k = 0; k < c.dim; ++k) vol *= c.box[k];
  return static_cast<double>(n) * limits::particle_volume(c.dim, c.diameter) / vol;
}

InitialState random_start(const Config& config, std::size_t n, std::uint64_t seed, double energy,
                          const std::string& init, bool equal_speeds, const InterruptCheck& interrupt) {
  Config c = config;
  const bool mixed = !c.diameters.empty();
  if (mixed) {  // each particle's own diameter; the checks below take the largest
    require(c.diameters.size() == n, [&] {
      return "diameters must have one entry per particle (" + std::to_string(n) + "), got " +
             std::to_string(c.diameters.size());
    });
    for (const double q : c.diameters) require(std::isfinite(q) && q > 0.0, "every diameter must be finite and > 0");
    c.diameter = *std::max_element(c.diameters.begin(), c.diameters.end());
  }
  check_common(c, n, seed);
  check_energy(energy);
  const Placement how = parse_placement(init);
  const int d = c.dim;
  const double D = c.diameter;
  for (int k = 0; k < d; ++k) {
    const double L = c.box[k];
    const std::string axis = "axis " + std::to_string(k) + " has length " + num(L);
    require(std::isfinite(L) && L > 0.0, "box length on " + axis + ": must be finite and > 0");
    require(limits::box_ratio_fits(L, D), "box length on " + axis + ": more than 2^30 diameters of " + num(D));
    if (has_walls(c.boundary[k]))
      require(L > D * (1.0 + limits::kWallMargin),
              "diameter " + num(D) + " is too large for the box: " + axis + " (walls need L > D)");
    else
      require(limits::periodic_axis_fits(L, D), "periodic box too small for the neighbour lists: " + axis +
                                                    " < 3 diameters");
  }
  if (how == Placement::relax) return relax_in_box(c, n, seed, energy, equal_speeds, interrupt);
  // a mixture's automatic start: as spheres of the largest diameter (rsa or crystal) when they
  // fit, else relaxed at the particles' own diameters (so every start that fitted is unchanged)
  const bool or_relax = mixed && how == Placement::automatic;
  const double phi = box_fraction(c, n);
  if (phi > limits::max_fraction(d)) {
    if (or_relax) return relax_in_box(c, n, seed, energy, equal_speeds, interrupt);
    throw InvalidArgument(std::to_string(n) + " particles of diameter " + num(D) +
                          " do not fit in this box: packing fraction " + num(phi) +
                          " above what the initialiser reaches (" + num(limits::max_fraction(d)) + " in " +
                          std::to_string(d) + "D; init='relax' places them at random, overlaps relaxed away)");
  }
  const bool rsa = how == Placement::rsa || (how == Placement::automatic && phi <= limits::rsa_fraction(d));
  if (!or_relax) return start_in_box(c, n, seed, energy, rsa, how == Placement::automatic, equal_speeds);
  try {
    return start_in_box(c, n, seed, energy, rsa, true, equal_speeds);
  } catch (const InvalidArgument&) {
    return relax_in_box(c, n, seed, energy, equal_speeds, interrupt);
  }
}

namespace {

// A mixture's start (random_state with diameters): the cube of the particles' own volumes at
// phi, placed as spheres of the largest diameter.
InitialState mixture_state(Config c, std::size_t n, double phi, std::uint64_t seed, double energy,
                           const std::string& init, bool equal_speeds, const InterruptCheck& interrupt) {
  require(c.diameters.size() == n, [&] {
    return "diameters must have one entry per particle (" + std::to_string(n) + "), got " +
           std::to_string(c.diameters.size());
  });
  double dmax = 0.0, vol = 0.0;
  for (const double q : c.diameters) {
    require(std::isfinite(q) && q > 0.0, "every diameter must be finite and > 0");
    dmax = std::max(dmax, q);
  }
  // (the size ratio is the engine's to check: each engine names its own limit)
  for (const double q : c.diameters) vol += limits::particle_volume(c.dim, q);
  require(std::isfinite(phi) && phi > 0.0, "packing fraction must be finite and > 0");
  c.diameter = dmax;
  const double L = std::pow(vol / phi, 1.0 / static_cast<double>(c.dim));
  require(std::isfinite(L) && L > 0.0 && limits::box_ratio_fits(L, dmax), [&] {
    return "the box for this mixture at packing fraction " + num(phi) + " is not representable (length " + num(L) + ")";
  });
  for (int k = 0; k < 3; ++k) c.box[k] = k < c.dim ? L : 1.0;
  try {
    return random_start(c, n, seed, energy, init, equal_speeds, interrupt);
  } catch (const InvalidArgument& e) {
    const Placement how = parse_placement(init);  // (a bad name is thrown from here, as it is)
    if (how == Placement::automatic || how == Placement::relax) throw;  // each names its own problem
    const double as_largest = static_cast<double>(n) * limits::particle_volume(c.dim, dmax) / vol * phi;
    throw InvalidArgument("a mixture's random start places every particle as one of the largest (diameter " +
                          num(dmax) + "), which at packing fraction " + num(phi) + " would fill " + num(as_largest) +
                          " of the box: " + e.what());
  }
}

}  // namespace

InitialState random_state(Config c, std::size_t n, double phi, std::uint64_t seed, double energy,
                          const std::string& init, bool equal_speeds, const InterruptCheck& interrupt) {
  if (!c.diameters.empty()) {
    check_common(c, n, seed);
    return mixture_state(std::move(c), n, phi, seed, energy, init, equal_speeds, interrupt);
  }
  check_common(c, n, seed);
  check_energy(energy);
  require(std::isfinite(phi) && phi > 0.0, "packing fraction must be finite and > 0");
  const Placement how = parse_placement(init);
  const int d = c.dim;
  // (a relaxed start goes past the crystal's bound to its own, as in a given box)
  const double maxphi = how == Placement::relax ? limits::max_relax_fraction(d) : limits::max_fraction(d);
  require(phi <= maxphi, "packing fraction " + num(phi) + " above what the initialiser reaches (" +
                             num(maxphi) + " in " + std::to_string(d) + "D)");
  const double L = std::pow(static_cast<double>(n) * limits::particle_volume(d, c.diameter) / phi, 1.0 / d);
  // a tiny diameter underflows the particle volume and the box to 0 (issue 17)
  require(std::isfinite(L) && L > 0.0 && limits::box_ratio_fits(L, c.diameter), [&] {
    return "the box for " + std::to_string(n) + " particles of diameter " + num(c.diameter) +
           " at packing fraction " + num(phi) + " is not representable (length " + num(L) +
           "): choose a diameter between 1e-100 and 1e100";
  });
  for (int k = 0; k < 3; ++k) c.box[k] = k < d ? L : 1.0;
  if (how == Placement::relax) return relax_in_box(c, n, seed, energy, equal_speeds, interrupt);
  // "auto" decides on the phi asked for, not on the cube's (which differs in the last bits)
  const bool rsa = how == Placement::rsa || (how == Placement::automatic && phi <= limits::rsa_fraction(d));
  return start_in_box(c, n, seed, energy, rsa, how == Placement::automatic, equal_speeds);
}

}  // namespace revcol::engine
