// Shared pieces of the paper-mode operators for 3 particles (triple1d_paper.hpp,
// triple2d_paper.hpp): the velocity type, angle wrapping, held invariants of a triple.
#pragma once
#include <array>
#include <cmath>
#include <limits>
#include <string>

#include "revcol/collide/common.hpp"

namespace revcol::paper {

/// Velocities of three particles, by particle id (index 0 = the smallest id).
template <int Dim>
using Triple = std::array<std::array<double, Dim>, 3>;

inline constexpr double kPi = 3.141592653589793238462643383279502884;  ///< pi
inline constexpr double kTwoPi = 2.0 * kPi;                              ///< 2 pi

/// x mod period, in [0, period) (fmod is exact; a tiny negative plus period can round up).
inline double wrap(double x, double period = kTwoPi) {
  double r = std::fmod(x, period);
  if (r < 0.0) r += period;
  if (r >= period) r -= period;
  return r;
}

/// Throws InvalidArgument unless every component of a Triple<Dim> is finite.
template <class TripleT>
inline void require_finite(const TripleT& v) {
  bool ok = true;
  for (const auto& p : v) ok = ok && all_finite(p.data(), static_cast<int>(p.size()));
  require(ok, "velocities must be finite (got a NaN or infinity)");
}

/// Throws InvalidArgument unless the triple's speeds lie in the operators' range
/// (check_speed_range): every |component| and the largest pairwise relative component.
template <class TripleT>
inline void require_speed_range(const TripleT& v) {
  double top = 0.0, rel = 0.0;
  for (std::size_t i = 0; i < v.size(); ++i)
    for (std::size_t k = 0; k < v[i].size(); ++k) {
      top = std::fmax(top, std::fabs(v[i][k]));
      for (std::size_t j = i + 1; j < v.size(); ++j) rel = std::fmax(rel, std::fabs(v[i][k] - v[j][k]));
    }
  check_speed_range(top, rel);
}

/// Radius rho of the relative-velocity sphere of a triple from held invariants,
/// rho^2 = E - |M|^2 / 3, checked against the velocities' own |x| = `x_norm` within 1e-8
/// relative plus the rounding of that difference.
template <int Dim>
inline double checked_radius(const Invariants<Dim>& inv, double x_norm) {
  require(all_finite(inv.momentum, Dim) && std::isfinite(inv.energy), "invariants must be finite");
  double m2 = 0.0;
  for (int k = 0; k < Dim; ++k) m2 += inv.momentum[k] * inv.momentum[k];
  const double r2 = inv.energy - m2 / 3.0;
  require(r2 > 0.0, "invariants leave no relative kinetic energy (E <= |M|^2 / 3)");
  const double cancel = 16.0 * std::numeric_limits<double>::epsilon() * inv.energy;
  require(std::fabs(x_norm * x_norm - r2) <= 1e-8 * r2 + cancel, [&] {
    return std::string("velocities are inconsistent with the given energy and momentum (radius ") +
           std::to_string(x_norm) + " vs " + std::to_string(std::sqrt(r2)) + ")";
  });
  return std::sqrt(r2);
}

}  // namespace revcol::paper
