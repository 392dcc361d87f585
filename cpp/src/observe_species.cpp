// The observer's species (mixtures; the definitions are in revcol/engine/observe.hpp):
// set_species (the sums live in the hooks, end_block and results).
#include <algorithm>
#include <array>
#include <string>
#include <utility>

#include "observe_inline.hpp"
#include "revcol/error.hpp"

namespace revcol::engine {

void Observer::set_species(const std::vector<int>& label, const std::vector<double>& radius) {
  require(fax_ < 0 && gamma_ == 0.0, "observe: set_species must come before set_field and set_shear");
  require((label.empty() || label.size() == n_) && radius.size() == n_, [&] {
    return "observe: species need a label and a radius per particle (" + std::to_string(n_) + "), got " +
           std::to_string(label.size()) + " and " + std::to_string(radius.size());
  });
  int ns = 0;
  for (std::size_t i = 0; i < n_; ++i) {
    require(std::isfinite(radius[i]) && radius[i] > 0.0 && radius[i] <= 0.5 * diameter_ * (1.0 + 1e-12), [&] {
      return "observe: particle " + std::to_string(i) + "'s radius " + num(radius[i]) +
             " must be positive and at most half the largest diameter";
    });
    if (label.empty()) continue;
    require(label[i] >= 0 && label[i] < kMaxSpecies, [&] {
      return "observe: particle " + std::to_string(i) + "'s species label " + std::to_string(label[i]) +
             " is outside [0, " + std::to_string(kMaxSpecies) + ")";
    });
    ns = std::max(ns, label[i] + 1);
  }
  if (label.empty()) {  // radii only (the walls' contact planes); a resumed observation's sums stay off
    radius_ = radius;
    return;
  }
  std::vector<std::size_t> count(static_cast<std::size_t>(ns), 0);
  for (const int l : label) ++count[static_cast<std::size_t>(l)];
  for (int u = 0; u < ns; ++u)
    require(count[static_cast<std::size_t>(u)] > 0,
            [&] { return "observe: species " + std::to_string(u) + " has no particle (labels must be 0..S-1)"; });
  if (resumed_) {
    // the sums come from the snapshot, or it kept none (then none are kept now)
    require(ns_saved_ == 0 || ns_saved_ == ns, [&] {
      return "snapshot: observer kept " + std::to_string(ns_saved_) + " species, the particles have " +
             std::to_string(ns);
    });
    ns_ = ns_saved_;
  } else {
    require(blocks_.empty() && cur_.parts == 0 && cur_.walls == 0 && t_now_ == t_start_,
            "observe: set_species must come before the first event");
    ns_ = ns;
    v2_sp_.assign(static_cast<std::size_t>(ns), 0.0);
    for (std::size_t i = 0; i < n_; ++i) v2_sp_[static_cast<std::size_t>(label[i])] += seg_[i].v2;
    cur_.sp.assign(2 * static_cast<std::size_t>(ns), 0.0);
  }
  label_ = label;
  radius_ = radius;
  sp_count_ = count;
}

void Observer::set_masses(const std::vector<double>& mass) {
  require(mass.size() == n_, [&] {
    return "observe: masses need one entry per particle (" + std::to_string(n_) + "), got " + std::to_string(mass.size());
  });
  for (std::size_t i = 0; i < n_; ++i)
    require(std::isfinite(mass[i]) && mass[i] > 0.0,
            [&] { return "observe: particle " + std::to_string(i) + "'s mass must be finite and > 0"; });
  require(resumed_ || (blocks_.empty() && cur_.parts == 0 && cur_.walls == 0 && t_now_ == t_start_ && ns_ == 0),
          "observe: set_masses must come before the first event and before set_species");
  require(fax_ < 0 && gamma_ == 0.0, "observe: set_masses must come before set_field and set_shear");
  mass_ = mass;
  // each segment's m v^2; a fresh observation's running sums with the masses (a resumed one's
  // are its snapshot's)
  double v2_sum = 0.0;
  std::array<double, 3> vv{};
  for (std::size_t i = 0; i < n_; ++i) {
    Segment& s = seg_[i];
    double v2 = s.v[0] * s.v[0];
    for (int k = 1; k < dim_; ++k) v2 += s.v[k] * s.v[k];
    s.v2 = mass[i] * v2;
    v2_sum += s.v2;
    if (dim_ >= 2) vv[0] += mass[i] * (s.v[0] * s.v[1]);
    if (dim_ >= 3) {
      vv[1] += mass[i] * (s.v[0] * s.v[2]);
      vv[2] += mass[i] * (s.v[1] * s.v[2]);
    }
  }
  if (!resumed_) {
    v2_sum_ = v2_sum;
    vv_off_ = vv;
  }
}

void Observer::set_sizes(const std::vector<double>& radius) {
  require(radius.size() == n_, [&] {
    return "observe: sizes need a radius per particle (" + std::to_string(n_) + "), got " + std::to_string(radius.size());
  });
  std::vector<std::pair<double, double>> kinds(n_);  // (radius, mass)
  for (std::size_t q = 0; q < n_; ++q) kinds[q] = {radius[q], mass_of(static_cast<int>(q))};
  std::vector<std::pair<double, double>> sorted(kinds);
  std::sort(sorted.begin(), sorted.end());
  sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
  const bool species = sorted.size() <= static_cast<std::size_t>(kMaxSpecies);
  std::vector<int> label(species ? n_ : 0);
  if (species)
    for (std::size_t q = 0; q < n_; ++q)
      label[q] = static_cast<int>(std::lower_bound(sorted.begin(), sorted.end(), kinds[q]) - sorted.begin());
  set_species(label, radius);
}

}  // namespace revcol::engine
