// Random initial states for the engine: random sequential addition or a jittered lattice,
// Gaussian (or equal-speed) velocities. Draws come from Philox keys {stream, seed} with
// streams 0xFFFFFF00+ (never a particle id the engine uses for collisions).
#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include "revcol/engine/engine.hpp"
#include "revcol/error.hpp"
#include "revcol/rng/philox.hpp"

namespace revcol::engine {
namespace {

constexpr double kPi = 3.141592653589793238462643383279502884;

struct Draws {
  rng::Philox gen;
  explicit Draws(std::uint32_t stream, std::uint64_t seed)
      : gen({stream, static_cast<std::uint32_t>(seed)}, 0) {}
  double u() { return gen.next(); }
  double normal() {  // Box-Muller, one value per call (the other discarded: simple, deterministic)
    const double a = u(), b = u();
    return std::sqrt(-2.0 * std::log(a)) * std::cos(2.0 * kPi * b);
  }
};

}  // namespace

double particle_volume(int d, double D) {
  if (d == 1) return D;
  if (d == 2) return kPi * D * D / 4.0;
  return kPi * D * D * D / 6.0;
}

InitialState random_state(Config c, std::size_t n, double phi, std::uint64_t seed, double energy,
                          const std::string& init, bool equal_speeds) {
  require(c.dim >= 1 && c.dim <= 3, "dim must be 1, 2 or 3");
  require(n > 0, "no particles (N = 0)");
  require(std::isfinite(phi) && phi > 0.0, "packing fraction must be finite and > 0");
  require(std::isfinite(c.diameter) && c.diameter > 0.0, "diameter must be finite and > 0");
  require(seed <= 0xFFFFFFFFu, "seed must be < 2^32");
  require(init == "auto" || init == "rsa" || init == "lattice",
          "init must be 'auto', 'rsa' or 'lattice', got '" + init + "'");
  const int d = c.dim;
  const double maxphi = d == 1 ? 0.95 : d == 2 ? 0.75 : 0.7;
  require(phi <= maxphi, "packing fraction " + std::to_string(phi) + " above what the initialiser reaches (" +
                             std::to_string(maxphi) + " in " + std::to_string(d) + "D)");
  const double D = c.diameter;
  const double L = std::pow(static_cast<double>(n) * particle_volume(d, D) / phi, 1.0 / d);
  for (int k = 0; k < 3; ++k) c.box[k] = k < d ? L : 1.0;
  const double rsa_max = d == 1 ? 0.3 : d == 2 ? 0.35 : 0.2;
  const bool rsa = init == "rsa" || (init == "auto" && phi <= rsa_max);
  InitialState s;
  s.x.assign(n * d, 0.0);
  s.v.assign(n * d, 0.0);
  Draws vel(0xFFFFFF01u, seed);
  // per-axis allowed centre range
  double lo[3], hi[3];
  for (int k = 0; k < d; ++k) {
    const bool wall = c.boundary[k] == Boundary::wall;
    // a margin of 1e-6 D from the walls: a particle touching a wall at the start would be
    // at an event at t0, which a reversed run cannot tell from a departure (engine.hpp)
    lo[k] = wall ? 0.5 * D * (1.0 + 2e-6) : 0.0;
    hi[k] = wall ? L - 0.5 * D * (1.0 + 2e-6) : L;
  }
  // positions: the preferred method, and under "auto" the other one if it fails
  auto place = [&](bool use_rsa) {
    Draws pos(0xFFFFFF00u, seed);
    if (use_rsa) {
      const int nc = std::max(1, static_cast<int>(std::floor(L / D)));
      const double cw = L / nc;
      std::size_t total = 1;
      for (int k = 0; k < d; ++k) total *= static_cast<std::size_t>(nc);
      std::vector<std::vector<int>> cells(total);
      const double min2 = D * D * (1.0 + 1e-12);
      const std::size_t max_tries = 1000 * n + 100000;
      std::size_t tries = 0;
      for (std::size_t i = 0; i < n; ++i) {
        for (;;) {
          require(++tries < max_tries, "random sequential addition did not place every particle; use init='lattice'");
          double p[3];
          int cc[3];
          for (int k = 0; k < d; ++k) {
            p[k] = lo[k] + (hi[k] - lo[k]) * pos.u();
            if (p[k] >= L) p[k] = 0.0;
            cc[k] = std::min(nc - 1, static_cast<int>(p[k] / cw));
          }
          bool ok = true;
          const int noff = d == 1 ? 3 : d == 2 ? 9 : 27;
          for (int o = 0; o < noff && ok; ++o) {
            int rem = o;
            std::size_t id = 0, stride = 1;
            double sh[3] = {0, 0, 0};
            bool in = true;
            for (int k = 0; k < d; ++k) {
              int ck = cc[k] + rem % 3 - 1;
              rem /= 3;
              if (ck < 0 || ck >= nc) {
                if (c.boundary[k] == Boundary::wall || nc < 3) { in = false; break; }
                if (ck < 0) { ck += nc; sh[k] = -L; } else { ck -= nc; sh[k] = L; }
              }
              id += static_cast<std::size_t>(ck) * stride;
              stride *= static_cast<std::size_t>(nc);
            }
            if (!in) continue;
            for (int j : cells[id]) {
              double r2 = 0.0;
              for (int k = 0; k < d; ++k) {
                const double dx = p[k] - (s.x[j * d + k] + sh[k]);
                r2 += dx * dx;
              }
              if (r2 < min2) { ok = false; break; }
            }
          }
          if (!ok) continue;
          std::size_t id = 0, stride = 1;
          for (int k = 0; k < d; ++k) {
            s.x[i * d + k] = p[k];
            id += static_cast<std::size_t>(cc[k]) * stride;
            stride *= static_cast<std::size_t>(nc);
          }
          cells[id].push_back(static_cast<int>(i));
          break;
        }
      }
    } else {
      // a lattice of `sites` >= n sites (square in 1D/2D, face-centred cubic in 3D: 4 per
      // cubic cell), a random subset of n of them, each displaced by up to `jitter` per axis
      const int basis = d == 3 ? 4 : 1;
      int m = 1;
      while (std::pow(static_cast<double>(m), d) * basis < static_cast<double>(n)) ++m;
      // spacing per axis: the lattice spans [lo, hi] (walls: centres stay D/2 inside)
      double a = L;
      double ak[3];
      for (int k = 0; k < d; ++k) {
        ak[k] = (hi[k] - lo[k]) / m;
        a = std::min(a, ak[k]);
      }
      const double nearest = d == 3 ? a / std::sqrt(2.0) : a;
      require(nearest >= D * (1.0 + 1e-9), "packing fraction too high for a lattice start");
      const double jitter = 0.49 * (nearest - D) / std::sqrt(static_cast<double>(d));
      static constexpr double fcc[4][3] = {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}};
      std::size_t sites = basis;
      for (int k = 0; k < d; ++k) sites *= static_cast<std::size_t>(m);
      std::vector<std::size_t> idx(sites);
      std::iota(idx.begin(), idx.end(), std::size_t{0});
      for (std::size_t i = 0; i < n; ++i) {  // partial Fisher-Yates
        const std::size_t j = i + static_cast<std::size_t>(pos.u() * static_cast<double>(sites - i));
        std::swap(idx[i], idx[std::min(j, sites - 1)]);
      }
      std::sort(idx.begin(), idx.begin() + static_cast<std::ptrdiff_t>(n));
      for (std::size_t i = 0; i < n; ++i) {
        std::size_t q = idx[i];
        const std::size_t b = q % static_cast<std::size_t>(basis);
        q /= static_cast<std::size_t>(basis);
        for (int k = 0; k < d; ++k) {
          const int ck = static_cast<int>(q % static_cast<std::size_t>(m));
          q /= static_cast<std::size_t>(m);
          const double off = d == 3 ? fcc[b][k] + 0.25 : 0.5;
          double p = lo[k] + (ck + off) * ak[k] + jitter * (2.0 * pos.u() - 1.0);
          p = std::clamp(p, lo[k], hi[k]);
          if (p >= L) p -= L;
          s.x[i * d + k] = p;
        }
      }
    }
  };
  if (init != "auto") {
    place(rsa);
  } else {
    try {
      place(rsa);
    } catch (const InvalidArgument&) {
      place(!rsa);
    }
  }
  // velocities
  if (equal_speeds) {
    for (std::size_t i = 0; i < n; ++i) {
      double nrm2 = 0.0;
      do {
        nrm2 = 0.0;
        for (int k = 0; k < d; ++k) {
          s.v[i * d + k] = vel.normal();
          nrm2 += s.v[i * d + k] * s.v[i * d + k];
        }
      } while (!(nrm2 > 0.0));
      const double nrm = std::sqrt(nrm2);
      for (int k = 0; k < d; ++k) s.v[i * d + k] /= nrm;
    }
  } else {
    for (auto& q : s.v) q = vel.normal();
    if (n > 1)
      for (int k = 0; k < d; ++k) {
        double m = 0.0;
        for (std::size_t i = 0; i < n; ++i) m += s.v[i * d + k];
        m /= static_cast<double>(n);
        for (std::size_t i = 0; i < n; ++i) s.v[i * d + k] -= m;
      }
  }
  double e = 0.0;
  for (double q : s.v) e += 0.5 * q * q;
  require(e > 0.0, "drawn velocities have zero kinetic energy (N = 1 with zero momentum?)");
  const double target = energy > 0.0 ? energy : 0.5 * static_cast<double>(n) * d;
  require(std::isfinite(target), "kinetic energy must be finite");
  const double scale = std::sqrt(target / e);
  for (auto& q : s.v) q *= scale;
  s.config = c;
  return s;
}

}  // namespace revcol::engine
