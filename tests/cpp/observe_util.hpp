// Shared pieces of the observer's tests (test_observe_shear.cpp, test_observe_field.cpp,
// test_lattice_shear_observe.cpp, test_lattice_field_observe.cpp): a config, flights flattened
// to the constructor's arrays, an observer's whole saved state, and the speed histogram's
// normalization and mean.
#pragma once
#include <cstdint>
#include <utility>
#include <vector>

#include "revcol/engine/observe.hpp"

namespace observe_test {

/// A config with blocks of `block_time`, `slabs` slabs along `axis`, `bins` speed bins up to `speed_max`.
inline revcol::engine::ObserveConfig config(double block_time, int slabs, int axis, int bins, double speed_max = 0.0) {
  revcol::engine::ObserveConfig c;
  c.block_time = block_time;
  c.slabs = slabs;
  c.slab_axis = axis;
  c.speed_bins = bins;
  c.speed_max = speed_max;
  return c;
}

/// Flights' starting points and velocities (members x0[], v[]) as n x d arrays.
template <class F>
std::pair<std::vector<double>, std::vector<double>> starts(const std::vector<F>& f, int d) {
  std::vector<double> x, v;
  for (const F& q : f) {
    x.insert(x.end(), q.x0, q.x0 + d);
    v.insert(v.end(), q.v, q.v + d);
  }
  return {x, v};
}

/// An observer's whole saved state: its reals, then its counts.
inline std::vector<double> saved(const revcol::engine::Observer& o) {
  std::vector<double> r;
  std::vector<std::uint64_t> c;
  o.save(r, c);
  for (std::uint64_t q : c) r.push_back(static_cast<double>(q));
  return r;
}

/// The speed histogram's integral (1 for a density) and its mean speed (bin centres).
inline std::pair<double, double> speed_moments(const revcol::engine::Observation& r, const revcol::engine::ObserveConfig& c) {
  double norm = 0.0, mean = 0.0;
  const double h = c.speed_max / c.speed_bins;
  for (int k = 0; k < c.speed_bins; ++k) {
    norm += r.speed.value[static_cast<std::size_t>(k)] * h;
    mean += r.speed.value[static_cast<std::size_t>(k)] * h * (k + 0.5) * h;
  }
  return {norm, mean};
}

}  // namespace observe_test
