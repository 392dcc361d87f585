// The slabs of the parallel lattice engine and the bands about them (timewarp.hpp): K slabs
// [F_m, F_m+1) along one axis (the last wraps round to the first on a periodic axis), each
// widened by W on both sides into its LP's band. The slab faces and the band faces cut the axis
// into fine regions, each with one owner (the slab that holds it) and a set of bands (a bit per
// LP): ownership and views are functions of a centre's position along the axis, and the engine's
// regions (set_regions(axis, faces())) keep each particle's fine region at the keys at which it
// changes.
#pragma once
#include <algorithm>
#include <cstdint>
#include <vector>

#include "revcol/error.hpp"

namespace revcol::lattice {

class SlabViews {
 public:
  SlabViews() = default;
  /// K equal slabs of an axis of length L (walls or periodic), bands W wider on each side.
  SlabViews(int k, std::int64_t L, bool wall, std::int64_t W) : k_(k), L_(L), W_(W), wall_(wall) {
    require(k >= 1 && k <= 64, "parallel lattice engine: 1 to 64 logical processes");
    require(L / k >= 1, "parallel lattice engine: more logical processes than lattice units along the slabs' axis");
    for (int m = 0; m < k; ++m) slab_.push_back(static_cast<std::int64_t>(static_cast<__int128>(L) * m / k));
    std::vector<std::int64_t> f{0};
    for (int m = 0; m < k; ++m)
      for (std::int64_t d : {std::int64_t{0}, -W, W}) {
        const std::int64_t y = slab_[static_cast<std::size_t>(m)] + d;
        if (!wall) f.push_back(((y % L) + L) % L);
        else if (y > 0 && y < L) f.push_back(y);
      }
    std::sort(f.begin(), f.end());
    f.erase(std::unique(f.begin(), f.end()), f.end());
    fine_ = f;
    for (std::int64_t g : f) {
      owner_.push_back(slab_of(g));
      std::uint64_t mask = 0;
      for (int m = 0; m < k; ++m)
        if (in_band(m, g)) mask |= std::uint64_t{1} << m;
      views_.push_back(mask);
    }
  }
  /// The fine regions' lower faces, ascending (set_regions' faces).
  const std::vector<std::int64_t>& faces() const noexcept { return fine_; }
  /// The LP owning fine region r.
  int owner(int r) const { return owner_[static_cast<std::size_t>(r)]; }
  /// The bands holding fine region r, a bit per LP.
  std::uint64_t views(int r) const { return views_[static_cast<std::size_t>(r)]; }
  /// Whether LP m's band holds fine region r.
  bool in_view(int m, int r) const { return (views(r) >> m & 1u) != 0; }
  /// A centre's distance along the axis outside slab m (0 inside).
  std::int64_t outside(int m, std::int64_t x) const {
    const std::int64_t lo = lo_of(m), hi = hi_of(m);
    if (x >= lo && x < hi) return 0;
    if (wall_) return x < lo ? lo - x : x - hi + 1;
    return std::min(((lo - x) % L_ + L_) % L_, ((x - hi) % L_ + L_) % L_ + 1);
  }
  std::int64_t band() const noexcept { return W_; }  ///< W

 private:
  std::int64_t lo_of(int m) const { return slab_[static_cast<std::size_t>(m)]; }
  std::int64_t hi_of(int m) const { return m + 1 < k_ ? slab_[static_cast<std::size_t>(m + 1)] : L_; }
  int slab_of(std::int64_t x) const {
    int r = 0;
    for (int m = 0; m < k_; ++m)
      if (x >= lo_of(m)) r = m;
    return r;
  }
  bool in_band(int m, std::int64_t x) const {
    const std::int64_t lo = lo_of(m) - W_, width = hi_of(m) - lo_of(m) + 2 * W_;
    if (width >= L_) return true;
    if (wall_) return x >= lo && x < lo + width;
    return ((x - lo) % L_ + L_) % L_ < width;
  }
  int k_ = 1;
  std::int64_t L_ = 1, W_ = 0;
  bool wall_ = false;
  std::vector<std::int64_t> slab_, fine_;
  std::vector<int> owner_;
  std::vector<std::uint64_t> views_;
};

}  // namespace revcol::lattice
