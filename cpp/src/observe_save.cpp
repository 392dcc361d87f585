// The observer's snapshots: save() and the constructor that resumes a saved observation (the
// layout of the reals and counts is in revcol/engine/observe.hpp).
#include "revcol/engine/observe.hpp"

#include <cmath>
#include <string>

#include "observe_inline.hpp"
#include "revcol/error.hpp"

namespace revcol::engine {

void Observer::save(std::vector<double>& reals, std::vector<std::uint64_t>& counts) const {
  const ObserveConfig& c = cfg_;
  reals = {static_cast<double>(dim_), static_cast<double>(n_), c.block_time, static_cast<double>(c.min_blocks),
           static_cast<double>(c.slab_axis), static_cast<double>(c.slabs), static_cast<double>(c.speed_bins),
           c.speed_max, static_cast<double>(c.pair_bins), c.pair_rmax, block_time_, t_start_, t_now_, speed_max_,
           static_cast<double>(blocks_.size()), static_cast<double>(msd_.size()), v2_sum_, speed_sum_};
  for (const Segment& s : seg_) {
    reals.insert(reals.end(), s.x, s.x + dim_);
    reals.insert(reals.end(), s.v, s.v + dim_);
    reals.push_back(s.t0);
    if (cfg_.slabs > 0) reals.push_back(std::round(s.lo / slab_w_));  // its cell
  }
  reals.insert(reals.end(), start_.begin(), start_.end());
  reals.insert(reals.end(), pair_t_.begin(), pair_t_.end());
  counts.clear();
  auto block = [&](const Block& b) {
    for (double q : {b.t0, b.t1, b.k2, b.w, b.w_wall, b.dist, b.wall_dp[0], b.wall_dp[1], b.wall_dp[2]})
      reals.push_back(q);
    for (int half = 0; half < 2; ++half)  // the times, then the v^2 times
      for (std::size_t u = 0; u < b.slab.size(); u += 2) reals.push_back(b.slab[u + half]);
    reals.insert(reals.end(), b.speed.begin(), b.speed.end() - 1);  // not the overflow bin
    reals.insert(reals.end(), b.pair.begin(), b.pair.end());
    for (std::uint64_t q : {b.pairs, b.groups, b.parts, b.walls}) counts.push_back(q);
  };
  for (const Block& b : blocks_) block(b);
  block(cur_);
  reals.insert(reals.end(), msd_t_.begin(), msd_t_.end());
  reals.insert(reals.end(), msd_.begin(), msd_.end());
  if (!start_v_.empty()) {  // the velocity autocorrelation (absent in older snapshots)
    reals.insert(reals.end(), start_v_.begin(), start_v_.end());
    reals.insert(reals.end(), vacf_.begin(), vacf_.end());
  }
  if (!start_v_.empty() && helf_kept_) {  // the Helfand moment (absent in older snapshots; never without the VACF)
    reals.insert(reals.end(), helf_.begin(), helf_.begin() + hc_);
    reals.insert(reals.end(), vv_off_.begin(), vv_off_.begin() + hc_);
    reals.insert(reals.end(), helf_rec_.begin(), helf_rec_.end());
    if (ns_ > 0) {  // the species' sums (a mixture's; absent for one species and in older snapshots)
      reals.push_back(static_cast<double>(ns_));
      reals.insert(reals.end(), v2_sp_.begin(), v2_sp_.end());
      for (const Block& b : blocks_) reals.insert(reals.end(), b.sp.begin(), b.sp.end());
      reals.insert(reals.end(), cur_.sp.begin(), cur_.sp.end());
      reals.insert(reals.end(), msd_sp_.begin(), msd_sp_.end());
    }
    if (gamma_ != 0.0) save_shear(reals);  // shear's sums (observe_shear.cpp; absent without shear)
    if (fax_ >= 0) save_field(reals);      // a field's (observe_field.cpp)
  }
}

Observer::Observer(const std::vector<double>& reals, const std::vector<std::uint64_t>& counts, int dim,
                   const std::vector<double>& v, double t, const std::array<double, 3>& box,
                   const std::array<bool, 3>& walls, double diameter)
    : dim_(dim), n_(0), box_(box), walls_(walls), diameter_(diameter) {
  require(dim >= 1 && dim <= 3 && !v.empty() && v.size() % static_cast<std::size_t>(dim) == 0,
          "snapshot: observer: the particles' velocities must be n x dim");
  n_ = v.size() / static_cast<std::size_t>(dim);
  require(reals.size() >= kHeader, "snapshot: observer holds fewer values than its header");
  for (double q : reals) require(std::isfinite(q), "snapshot: observer values must be finite");
  auto whole = [&](std::size_t k, double lo, double hi, const char* name) {
    const double q = reals[k];
    require(q >= lo && q <= hi && q == std::floor(q),
            [&] { return std::string("snapshot: observer ") + name + " must be a whole number in range, got " +
                         num(q); });
    return static_cast<std::int64_t>(q);
  };
  require(whole(0, 1, 3, "dim") == dim && whole(1, 1, 1e15, "n") == static_cast<std::int64_t>(n_),
          "snapshot: observer was taken of another number of particles or dimensions");
  cfg_.block_time = reals[2];
  cfg_.min_blocks = static_cast<int>(whole(3, 2, 64, "min_blocks"));
  cfg_.slab_axis = static_cast<int>(whole(4, 0, 2, "slab_axis"));
  cfg_.slabs = static_cast<int>(whole(5, 0, kMaxBins, "slabs"));
  cfg_.speed_bins = static_cast<int>(whole(6, 0, kMaxBins, "speed_bins"));
  cfg_.speed_max = reals[7];
  cfg_.pair_bins = static_cast<int>(whole(8, 0, kMaxBins, "pair_bins"));
  cfg_.pair_rmax = reals[9];
  check_config(cfg_, dim, n_, walls);
  block_time_ = reals[10];
  t_start_ = reals[11];
  t_now_ = reals[12];
  speed_max_ = reals[13];
  require(block_time_ > 0.0 && speed_max_ > 0.0, "snapshot: observer block time and speed_max must be > 0");
  require(t_start_ <= t_now_ && t_now_ <= t, "snapshot: observer times must be ordered: start <= last update <= clock");
  const auto nb = static_cast<std::size_t>(whole(14, 0, kMaxBlocks - 1, "block count"));
  const auto nm = static_cast<std::size_t>(whole(15, 0, 1e12, "MSD count"));
  const std::size_t d = static_cast<std::size_t>(dim), np = cfg_.pair_bins > 0 ? n_ * n_ : 0;
  const std::size_t per_block = kBlockReals + 2 * cfg_.slabs + cfg_.speed_bins + cfg_.pair_bins;
  const std::size_t per_particle = 3 * d + 1 + (cfg_.slabs > 0 ? 1 : 0);
  const std::size_t size = kHeader + n_ * per_particle + np + (nb + 1) * per_block + 2 * nm;
  hc_ = dim * (dim - 1) / 2;
  const std::size_t hc = static_cast<std::size_t>(hc_), vacf = size + n_ * d + nm, helf = vacf + hc * (2 + nm);
  // with the VACF and the Helfand moment (and a mixture's species sums), with the VACF only, or
  // neither (older snapshots)
  // then a mixture's species sums (S >= 1 first), then shear's (-1 first; observe_shear.cpp)
  std::size_t species = 0, shear = 0;
  if (reals.size() > helf && reals[helf] >= 0.0) {
    ns_saved_ = static_cast<int>(whole(helf, 1, kMaxSpecies, "species count"));
    species = static_cast<std::size_t>(ns_saved_) * (2 * (nb + 1) + nm + 1) + 1;
  }
  // then shear's section (-1 first; observe_shear.cpp) or a field's (-2 first; observe_field.cpp)
  const std::size_t sheared = helf + species;
  std::size_t field = 0;
  if (reals.size() > sheared) {
    require(reals[sheared] == -1.0 || reals[sheared] == -2.0, "snapshot: observer: an unknown section follows the Helfand moment");
    if (reals[sheared] == -1.0)
      shear = 9 + 5 * static_cast<std::size_t>(ns_saved_) + (nb + 1) * (1 + static_cast<std::size_t>(cfg_.slabs));
    else
      field = 10 + 2 * static_cast<std::size_t>(ns_saved_);
  }
  require(reals.size() == sheared + shear + field || reals.size() == vacf || reals.size() == size,
          "snapshot: observer: its size does not match its header (particles, bins, blocks, MSD points, species, shear, field)");
  // under shear a segment moves in the image it is in: its flow velocity is the particle's plus
  // a whole number of times the images' relative speed; in a field its velocity was the
  // particle's at its start, g (t - t0) from the particle's now along the field's axis
  const double image_speed = shear > 0 ? reals[sheared + 1] * box[1] : 0.0;
  require(shear == 0 || (image_speed != 0.0 && std::isfinite(image_speed)), "snapshot: observer: its shear rate must be nonzero");
  const int fax = field > 0 ? static_cast<int>(whole(sheared + 1, 0, dim - 1, "field axis")) : -1;
  const double fg = field > 0 ? reals[sheared + 2] : 0.0;
  require(counts.size() == (nb + 1) * kBlockCounts, "snapshot: observer_counts must hold 4 counts per block");
  bin_scale_ = cfg_.speed_bins / speed_max_;
  bin_cap_ = cfg_.speed_bins;
  set_geometry(box);
  slab_w_ = cfg_.slabs > 0 ? box_[cfg_.slab_axis] / cfg_.slabs : 0.0;
  std::size_t u = kHeader;
  seg_.resize(n_);
  for (std::size_t i = 0; i < n_; ++i) {
    Segment& s = seg_[i];
    for (int k = 0; k < 3; ++k) s.x[k] = s.v[k] = 0.0;
    s.v2 = s.speed = 0.0;
    for (std::size_t k = 0; k < d; ++k) s.x[k] = reals[u++];
    double sv[3] = {0.0, 0.0, 0.0};
    for (std::size_t k = 0; k < d; ++k) sv[k] = reals[u++];
    s.t0 = reals[u++];
    for (std::size_t k = 0; k < d; ++k) {
      const double now = static_cast<int>(k) == fax ? sv[k] + fg * (t - s.t0) : sv[k];
      const double off = now - v[i * d + k], m = k == 0 && shear > 0 ? std::nearbyint(off / image_speed) : 0.0;
      const double tol = 1e-9 * (std::fabs(now) + std::fabs(v[i * d + k]) + std::fabs(fg * (t - s.t0)));
      require(k == 0 && shear > 0 ? std::fabs(off - m * image_speed) <= tol : static_cast<int>(k) == fax ? std::fabs(off) <= tol
                                                                                                       : off == 0.0,
              "snapshot: observer: a segment's velocity is not its particle's");
    }
    require(s.t0 >= t_start_ && s.t0 <= t, "snapshot: observer: a segment starts outside the observed time");
    if (cfg_.slabs > 0) {
      const double cell = reals[u++];
      require(cell == std::floor(cell) && std::fabs(cell) < 1e15 &&
                  (!walls_[cfg_.slab_axis] || (cell >= 0.0 && cell < cfg_.slabs)),
              "snapshot: observer: a segment's slab cell must be a whole number (in [0, slabs) between walls)");
      set_cell(s, cell);
    }
    set_velocity<0>(static_cast<int>(i), sv);  // (the particle's, but under shear)
  }
  auto take = [&](std::vector<double>& out, std::size_t m) {
    out.assign(reals.begin() + static_cast<std::ptrdiff_t>(u), reals.begin() + static_cast<std::ptrdiff_t>(u + m));
    u += m;
  };
  take(start_, n_ * d);
  take(pair_t_, np);
  auto block = [&](std::size_t b) {
    Block k = empty_block(reals[u]);
    k.t1 = reals[u + 1];
    k.k2 = reals[u + 2];
    k.w = reals[u + 3];
    k.w_wall = reals[u + 4];
    k.dist = reals[u + 5];
    for (int a = 0; a < 3; ++a) k.wall_dp[a] = reals[u + 6 + a];
    require(k.t0 >= t_start_ && k.t1 >= k.t0 && k.t1 <= t, "snapshot: observer: a block outside the observed time");
    u += kBlockReals;
    for (int half = 0; half < 2; ++half)
      for (std::size_t w = 0; w < k.slab.size(); w += 2) k.slab[w + half] = reals[u++];
    take(k.speed, k.speed.size() - 1);
    k.speed.push_back(0.0);  // the overflow bin (never reported, not saved)
    take(k.pair, k.pair.size());
    k.pairs = counts[b * kBlockCounts];
    k.groups = counts[b * kBlockCounts + 1];
    k.parts = counts[b * kBlockCounts + 2];
    k.walls = counts[b * kBlockCounts + 3];
    return k;
  };
  for (std::size_t b = 0; b < nb; ++b) blocks_.push_back(block(b));
  cur_ = block(nb);
  take(msd_t_, nm);
  take(msd_, nm);
  if (u < reals.size()) {  // the velocity autocorrelation (a snapshot without it resumes none)
    take(start_v_, n_ * d);
    take(vacf_, nm);
  }
  helf_kept_ = reals.size() >= helf;  // the Helfand moment (a snapshot without it resumes none)
  if (helf_kept_) {
    for (std::size_t c = 0; c < hc; ++c) helf_[c] = reals[u + c];
    for (std::size_t c = 0; c < hc; ++c) vv_off_[c] = reals[u + hc + c];  // the running sums as they were
    u += 2 * hc;
    take(helf_rec_, nm * hc);
  }
  if (ns_saved_ > 0) {  // the species' sums: set_species turns them on
    const auto ns = static_cast<std::size_t>(ns_saved_);
    ++u;  // the count, read above
    take(v2_sp_, ns);
    for (Block& b : blocks_) take(b.sp, 2 * ns);
    take(cur_.sp, 2 * ns);
    take(msd_sp_, nm * ns);
  }
  take(shear_saved_, shear);  // set_shear reads it
  take(field_saved_, field);  // set_field reads it
  resumed_ = true;
  v2_sum_ = reals[16];  // the running sums as they were (set_velocity above rebuilt them afresh)
  speed_sum_ = reals[17];
  set_fast_until();
}

}  // namespace revcol::engine
