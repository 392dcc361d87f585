// The velocities of a colliding pair and its contact frame, shared by the pair operators.
#pragma once
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <type_traits>

#include "revcol/collide/common.hpp"

namespace revcol {

/// Velocities of a colliding pair: particle i and particle j. The contact normal points
/// from j to i, so the pair approaches when normal . (v_i - v_j) < 0 and separates when > 0.
template <int Dim>
struct PairV {
  std::array<double, Dim> i;  ///< velocity of particle i (the paper's particle 1, smaller id)
  std::array<double, Dim> j;  ///< velocity of particle j
  friend bool operator==(const PairV&, const PairV&) = default;
};

/// Relative velocity w = v_i - v_j, computed as a difference (DESIGN.md §4: never as
/// velocity minus half the momentum, which cancels when the centre of mass moves fast).
template <int Dim>
inline std::array<double, Dim> relative(const PairV<Dim>& v) {
  std::array<double, Dim> w;
  for (int k = 0; k < Dim; ++k) w[k] = v.i[k] - v.j[k];
  return w;
}

/// Throws InvalidArgument unless every velocity component is finite.
template <int Dim>
inline void require_finite(const PairV<Dim>& v) {
  require(all_finite(v.i.data(), Dim) && all_finite(v.j.data(), Dim),
          "velocities must be finite (got a NaN or infinity)");
}

/// Throws InvalidArgument unless every velocity component is finite (require_finite's
/// message) and the pair's speeds lie in the operators' range (check_speed_range).
template <int Dim>
inline void require_speed_range(const PairV<Dim>& v, const std::type_identity_t<std::array<double, Dim>>& w) {
  // fast path (hot in the engine): sum v^2 <= 2^900 bounds every |component| by 2^450, and
  // |w|^2 >= 2^-958 makes the largest |w_k| at least 2^-958 / Dim >= 2^-960 squared: both limits hold.
  // It also proves every component finite (an infinity makes the sum infinite, a NaN makes the
  // comparison false), so the finiteness test runs only on the cold path.
  double e2 = 0.0, n2 = 0.0;
  for (int k = 0; k < Dim; ++k) {
    e2 += v.i[k] * v.i[k] + v.j[k] * v.j[k];
    n2 += w[k] * w[k];
  }
  if (e2 <= 0x1.0p+900 && n2 >= 0x1.0p-958) [[likely]] return;
  require_finite(v);
  check_speed_range(std::fmax(max_abs(v.i.data(), Dim), max_abs(v.j.data(), Dim)), max_abs(w.data(), Dim));
}

/// require_speed_range for a caller that has |w|^2 (n2) and the half sum cm = (v_i + v_j) / 2
/// at hand: the same acceptance and messages (the cold path is the same), a cheaper hot path.
/// |v_k| <= |cm| + |w| / 2, so |cm|^2 <= 2^898 and |w|^2 <= 2^898 bound every component by
/// 2^449 + 2^448 < 2^450, and |w|^2 >= 2^-958 keeps the largest |w_k| above 2^-480; any
/// state passing here passes require_speed_range's own hot path too (|v_i|^2 + |v_j|^2 =
/// 2 |cm|^2 + |w|^2 / 2 <= 2^900). An infinity or NaN anywhere makes cm or n2 fail.
template <int Dim>
inline void require_speed_range(const PairV<Dim>& v, const std::type_identity_t<std::array<double, Dim>>& w,
                                double n2, const double* cm) {
  double m2 = 0.0;
  for (int k = 0; k < Dim; ++k) m2 += cm[k] * cm[k];
  if (m2 <= 0x1.0p+898 && n2 <= 0x1.0p+898 && n2 >= 0x1.0p-958) [[likely]] return;
  require_finite(v);
  check_speed_range(std::fmax(max_abs(v.i.data(), Dim), max_abs(v.j.data(), Dim)), max_abs(w.data(), Dim));
}

/// Unit contact normal a and, in 2D, its tangent t = (-a_y, a_x): an orthonormal frame
/// decided by the contact geometry alone.
struct Frame2 {
  double a[2];  ///< unit normal, from j to i
  double t[2];  ///< unit tangent, a rotated by +90 degrees
  double x[2];  ///< the normal as given (scaled by its largest component on the cold path)
  double len;   ///< |x|, its square root rounded once: a = x / len up to the reciprocal's rounding

  /// Builds the frame from any non-zero finite normal; throws InvalidArgument otherwise.
  /// |a| is 1 to a few roundings, not exactly: the operators take |a|^2 - 1 into account
  /// (Pair2DExact's scale), and t = (-a_y, a_x) has |t| = |a| and a.t = 0 exactly.
  explicit Frame2(const std::array<double, 2>& normal) {
    double x0 = normal[0], x1 = normal[1];
    double s2 = x0 * x0 + x1 * x1;
    // a square root and one reciprocal (std::hypot cost ~11 ns, a fifth of the exact
    // operator); a normal whose squares would underflow or overflow is first scaled by its
    // largest component. An s2 inside the range also proves the normal finite.
    if (!(s2 >= 0x1.0p-900 && s2 <= 0x1.0p+900)) [[unlikely]] {
      require(std::isfinite(x0) && std::isfinite(x1), "contact normal must be finite");
      const double m = std::fmax(std::fabs(x0), std::fabs(x1));
      require(m > 0.0, "contact normal is zero");
      x0 /= m;
      x1 /= m;
      s2 = x0 * x0 + x1 * x1;
    }
    x[0] = x0;
    x[1] = x1;
    len = std::sqrt(s2);
    const double r = 1.0 / len;
    a[0] = x0 * r;
    a[1] = x1 * r;
    t[0] = -a[1];
    t[1] = a[0];
  }
  /// Component of w along the normal.
  double normal_part(const std::array<double, 2>& w) const { return w[0] * a[0] + w[1] * a[1]; }
  /// Component of w along the tangent.
  double tangent_part(const std::array<double, 2>& w) const { return w[0] * t[0] + w[1] * t[1]; }
};

/// Relative speed squared |v_i - v_j|^2 implied by held invariants: 2E - |M|^2.
template <int Dim>
inline double relative_speed2(const Invariants<Dim>& inv) {
  double m2 = 0.0;
  for (int k = 0; k < Dim; ++k) m2 += inv.momentum[k] * inv.momentum[k];
  return 2.0 * inv.energy - m2;
}

/// Checks held invariants against the velocities: finite, 2E > |M|^2, and |v_i - v_j|^2
/// equal to 2E - |M|^2 within 1e-8 relative plus the rounding of that difference, which
/// cancels when the centre of mass is fast (the momentum itself is not compared: the
/// paper's illustrations negate the velocities but hold the momentum).
template <int Dim>
inline double checked_relative_speed(const Invariants<Dim>& inv, double w_norm) {
  require(all_finite(inv.momentum, Dim) && std::isfinite(inv.energy),
          "invariants must be finite");
  const double r2 = relative_speed2(inv);
  require(r2 > 0.0, "invariants leave no relative kinetic energy (2E <= |M|^2)");
  const double rho = std::sqrt(r2);
  const double cancel = 16.0 * std::numeric_limits<double>::epsilon() * (2.0 * inv.energy);
  require(std::fabs(w_norm * w_norm - r2) <= 1e-8 * r2 + cancel, [&] { return std::string("velocities are inconsistent with the given energy and momentum (relative speed " +
              std::to_string(w_norm) + " vs " + std::to_string(rho) + ")"); });
  return rho;
}

}  // namespace revcol
