// The observer's results: totals over the observed time and block errors (the definitions
// are in revcol/engine/observe.hpp).
#include <cmath>
#include <limits>
#include <vector>

#include "revcol/engine/observe.hpp"

namespace revcol::engine {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double sample_sd(const std::vector<double>& x) {
  const double n = static_cast<double>(x.size());
  double m = 0.0;
  for (double q : x) m += q;
  m /= n;
  double s = 0.0;
  for (double q : x) s += (q - m) * (q - m);
  return std::sqrt(s / (n - 1.0));
}

}  // namespace

Observation Observer::results() const {
  Observation o;
  o.dim = dim_;
  o.n = n_;
  o.t_start = t_start_;
  o.t_end = t_now_;
  Block tot = empty_block(t_start_);
  for (const Block& b : blocks_) tot.add(b);
  Block open = cur_;
  if (gamma_ != 0.0) open.pyx = pyx_ - pyx_open_;  // (a complete block's is set at its end)
  tot.add(open);
  tot.t1 = t_now_;
  o.pair_collisions = tot.pairs;
  o.group_collisions = tot.groups;
  o.particle_collisions = tot.parts;
  o.wall_reflections = tot.walls;
  // the blocks of the errors: complete ones, merged down to [min_blocks, 2 min_blocks)
  std::vector<Block> bl = blocks_;
  while (bl.size() >= 2 * static_cast<std::size_t>(cfg_.min_blocks)) {
    std::vector<Block> m;
    for (std::size_t u = 0; u + 1 < bl.size(); u += 2) {
      m.push_back(bl[u]);
      m.back().add(bl[u + 1]);
    }
    bl = std::move(m);
  }
  o.blocks = static_cast<int>(bl.size());
  o.block_time = bl.empty() ? 0.0 : bl[0].t1 - bl[0].t0;
  const double N = static_cast<double>(n_), d = dim_;
  auto est = [&](auto f) {
    Estimate e;
    const double tau = tot.t1 - tot.t0;
    e.value = tau > 0.0 ? f(tot, tau) : kNaN;
    if (bl.size() >= 2) {
      std::vector<double> vals;
      for (const Block& b : bl) vals.push_back(f(b, b.t1 - b.t0));
      e.error = sample_sd(vals) / std::sqrt(static_cast<double>(vals.size()));
    }
    return e;
  };
  auto ratio = [](double a, double b) { return b != 0.0 ? a / b : kNaN; };
  o.temperature = est([&](const Block& b, double tau) { return b.k2 / (d * N * tau); });
  o.pressure_virial = est([&](const Block& b, double tau) { return (b.k2 + b.w) / (d * volume_ * tau); });
  o.compressibility = est([&](const Block& b, double) { return 1.0 + ratio(b.w, b.k2); });
  o.collision_rate = est([&](const Block& b, double tau) { return static_cast<double>(b.parts) / (N * tau); });
  o.mean_free_time = est([&](const Block& b, double tau) { return ratio(N * tau, static_cast<double>(b.parts)); });
  o.mean_free_path = est([&](const Block& b, double) { return ratio(b.dist, static_cast<double>(b.parts)); });
  o.virial_balance = est([&](const Block& b, double) { return ratio(b.k2 + b.w + b.w_wall, b.k2); });
  for (int k = 0; k < dim_; ++k) {
    if (!walls_[k]) continue;
    const double area = volume_ / box_[k];
    o.pressure_wall[k] = est([&](const Block& b, double tau) { return b.wall_dp[k] / (2.0 * tau * area); });
  }
  auto profile = [&](int bins, double width, auto f) {
    Profile p;
    for (int u = 0; u <= bins; ++u) p.edges.push_back(u * width);
    for (int u = 0; u < bins; ++u) {
      const Estimate e = est([&](const Block& b, double tau) { return f(b, tau, u); });
      p.value.push_back(e.value);
      p.error.push_back(e.error);
    }
    return p;
  };
  if (cfg_.slabs > 0) {
    const double w = box_[cfg_.slab_axis] / cfg_.slabs, vol = volume_ / cfg_.slabs;
    o.slab_density = profile(cfg_.slabs, w, [&](const Block& b, double tau, int u) { return b.slab[2 * u] / (tau * vol); });
    if (gamma_ == 0.0) {
      o.slab_temperature =
          profile(cfg_.slabs, w, [&](const Block& b, double, int u) { return ratio(b.slab[2 * u + 1], d * b.slab[2 * u]); });
    } else {  // shear: the box frame's, less the slab's mean flow (observe_shear.cpp)
      o.slab_temperature = profile(cfg_.slabs, w, [&](const Block& b, double, int u) {
        const double t = b.slab[2 * u], vx = b.slab_vx[u];
        return ratio(b.slab[2 * u + 1] - ratio(vx * vx, t), d * t);
      });
      o.slab_velocity = profile(cfg_.slabs, w, [&](const Block& b, double, int u) { return ratio(b.slab_vx[u], b.slab[2 * u]); });
    }
  }
  if (gamma_ != 0.0) {
    o.shear_rate = gamma_;
    o.shear_stress = est([&](const Block& b, double tau) { return b.pyx / (volume_ * tau); });
    o.viscosity = est([&](const Block& b, double tau) { return -b.pyx / (volume_ * tau * gamma_); });
  }
  if (cfg_.speed_bins > 0) {
    const double h = speed_max_ / cfg_.speed_bins;
    o.speed = profile(cfg_.speed_bins, h, [&](const Block& b, double tau, int u) { return b.speed[u] / (N * tau * h); });
  }
  if (cfg_.pair_bins > 0) {
    const double h = cfg_.pair_rmax / cfg_.pair_bins, np = 0.5 * N * (N - 1.0);
    o.pair_distance =
        profile(cfg_.pair_bins, h, [&](const Block& b, double tau, int u) { return b.pair[u] / (np * tau * h); });
  }
  o.msd_time = msd_t_;
  o.msd = msd_;
  o.vacf = vacf_;
  o.helfand_components = hc_;
  o.helfand = helf_rec_;
  if (ns_ > 0) {
    o.species_diameter.assign(static_cast<std::size_t>(ns_), 0.0);
    o.species_mass.assign(static_cast<std::size_t>(ns_), 1.0);
    o.species_count = sp_count_;
    for (std::size_t i = 0; i < n_; ++i) {
      o.species_diameter[static_cast<std::size_t>(label_[i])] = 2.0 * radius_[i];
      o.species_mass[static_cast<std::size_t>(label_[i])] = mass_of(static_cast<int>(i));
    }
    for (std::size_t u = 0; u < static_cast<std::size_t>(ns_); ++u) {
      const double Ns = static_cast<double>(o.species_count[u]);
      o.species_temperature.push_back(est([&](const Block& b, double tau) { return b.sp[2 * u] / (d * Ns * tau); }));
      o.species_pressure.push_back(
          est([&](const Block& b, double tau) { return (b.sp[2 * u] + b.sp[2 * u + 1]) / (d * volume_ * tau); }));
    }
    o.species_msd = msd_sp_;
  }
  return o;
}

}  // namespace revcol::engine
