// The observer's species (mixtures; the definitions are in revcol/engine/observe.hpp):
// set_species (the sums live in the hooks, end_block and results).
#include <algorithm>
#include <string>

#include "observe_inline.hpp"
#include "revcol/error.hpp"

namespace revcol::engine {

void Observer::set_species(const std::vector<int>& label, const std::vector<double>& radius) {
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

void Observer::set_sizes(const std::vector<double>& radius) {
  std::vector<double> sizes(radius);
  std::sort(sizes.begin(), sizes.end());
  sizes.erase(std::unique(sizes.begin(), sizes.end()), sizes.end());
  const bool species = sizes.size() <= static_cast<std::size_t>(kMaxSpecies);
  std::vector<int> label(species ? radius.size() : 0);
  if (species)
    for (std::size_t q = 0; q < radius.size(); ++q)
      label[q] = static_cast<int>(std::lower_bound(sizes.begin(), sizes.end(), radius[q]) - sizes.begin());
  set_species(label, radius);
}

}  // namespace revcol::engine
