// The particle sizes of a lattice gas (equal masses): one diameter sigma (units.hpp), or a
// mixture, particle p of radius r_p lattice units in [sigma / 32, sigma / 2] (validate_radii),
// binary, ternary or polydisperse. A pair's contact distance is r_i + r_j, an integer, so every
// overlap test stays exact; a centre keeps r_p from a wall. sigma, the largest diameter, bounds
// every reach of the search (cell widths, list reach, the acceptance scan's far test, the
// parallel engine's bands), so those proofs hold unchanged; the pair operators are made per
// pair for r_i + r_j (a few words, no tables). A one-size gas reads no radius on its hot paths
// (BasicEngine::scan<false>): docs/mixtures.md quotes its instruction count against the engine
// before mixtures.
#pragma once
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "revcol/error.hpp"
#include "revcol/lattice/geometry.hpp"

namespace revcol::lattice {

/// Per local index, each particle's radius (empty: one diameter).
class Sizes {
 public:
  /// One diameter sigma, or a mixture: radius_by_id[q] for particle q, stored at local index p
  /// holding particle gid(p).
  template <class Gid>
  void set(std::int64_t sigma, const std::vector<std::int64_t>& radius_by_id, Gid gid) {
    half_ = sigma / 2;
    one2_ = contact2(sigma);
    rad_.assign(radius_by_id.size(), 0);
    for (std::size_t p = 0; p < rad_.size(); ++p) rad_[p] = radius_by_id[static_cast<std::size_t>(gid(static_cast<int>(p)))];
  }
  bool mixed() const noexcept { return !rad_.empty(); }  ///< a mixture
  /// p's radius (a one-size gas: sigma / 2).
  std::int64_t rad(int p) const noexcept { return rad_.empty() ? half_ : rad_[static_cast<std::size_t>(p)]; }
  /// The pair's contact distance squared, exact.
  u128 sig2(int p, int q) const noexcept { return rad_.empty() ? one2_ : contact2(rad(p) + rad(q)); }
  /// The radii by particle id (empty: one diameter), `local(q)` the local index of id q.
  template <class Local>
  std::vector<std::int64_t> by_id(Local local) const {
    std::vector<std::int64_t> r(rad_.size());
    for (std::size_t q = 0; q < rad_.size(); ++q) r[q] = rad_[local(static_cast<int>(q))];
    return r;
  }
  /// The pair's operator (a pair operator or specular map): `one` (made for sigma) in a one-size
  /// gas, else one made for r_i + r_j in tmp.
  template <class O>
  const O& pair_op(const O& one, int i, int j, std::optional<O>& tmp) const {
    if (rad_.empty()) return one;
    tmp.emplace(made(one, rad(i) + rad(j)));
    return *tmp;
  }
  /// Whether operators like `one` can be made for another contact distance (a mixture needs it).
  template <class O>
  static constexpr bool resizable() noexcept {
    return requires(const O& one, std::int64_t s) { O(s, one.law(), one.cell_bits()); } || requires(std::int64_t s) { O(s); };
  }
  /// Throws InvalidArgument unless resizable<O>() (a test's operator of one diameter).
  template <class O>
  static void require_resizable() {
    if constexpr (!resizable<O>()) throw InvalidArgument("lattice: this pair operator has one diameter (no mixtures)");
  }
  std::vector<std::int64_t>& data() noexcept { return rad_; }  ///< (a re-sort permutes it with the particles)
  void clear() { std::vector<std::int64_t>().swap(rad_); }     ///< frees the radii (BasicEngine::release)

 private:
  std::vector<std::int64_t> rad_;
  std::int64_t half_ = 0;
  u128 one2_ = 0;
  template <class O>
  static O made(const O& one, std::int64_t s) {  // (require_resizable<O>() was checked at the load)
    if constexpr (requires { O(s, one.law(), one.cell_bits()); }) return O(s, one.law(), one.cell_bits());
    else if constexpr (requires { O(s); }) return O(s);
    else return one;
  }
};

}  // namespace revcol::lattice
