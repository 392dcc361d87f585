// G-to-Psi of the paper for 3 particles in 2 dimensions (Perumalla & Protopopescu 2013,
// §4.5 "Sampling the Psi Phase Space", Procedure 5 with s = 4): the parameters
// (psi_1, psi_2, psi_3) of a point on the hyper-ellipsoid H_4 of eq. 3sphere-2dim-ellipsoid,
//     x_1 = l_1 cos psi_1, x_2 = l_2 sin psi_1 cos psi_2,
//     x_3 = l_3 sin psi_1 sin psi_2 cos psi_3, x_4 = l_4 sin psi_1 sin psi_2 sin psi_3,
// with (x_1..x_4) = (a-bar, d-bar, b-bar - sqrt2 alpha/3, e-bar - sqrt2 beta/3) and
// (l_1..l_4) = r (1, 1, 1/sqrt3, 1/sqrt3), the same order as the paper's phi parametrization
// (eq. 3sphere-2dim-ellipsoid-space), so psi_k adds to phi_k. (The printed Output line has
// prod_{j=1}^{s} for x_s; it must be prod_{j=1}^{s-1}.)
//
// Procedure 5, k = 4: psi_1 is the latitude, from the pole of x_1, of the calotte of H_4
// whose surface area is G_1 A_4; k = 3: the opening of that calotte is the 3D ellipsoid
// H_3 with axes sin(psi_1) (l_2, l_3, l_4), and psi_2 is the latitude, from the pole of x_2,
// of its calotte of area G_2 A_3; k = 2: the opening is the ellipse with axes
// sin psi_1 sin psi_2 (l_3, l_4) - a circle, since l_3 = l_4 - sampled by arc length as in
// §4.4, which on a circle is exactly psi_3 = 2 pi G_3. Exactly 3 numbers.
//
// Calotte areas. An ellipsoid Lambda S (Lambda = diag(l), S the unit sphere) has the surface
// element det(Lambda) |Lambda^-1 u| dsigma(u), u on S. For the two shapes (scale drops out):
//   H_4: |Lambda^-1 u|^2 = 1 + 2 sin^2 psi_1 sin^2 psi_2, dsigma = sin^2 psi_1 sin psi_2 dpsi,
//        cap(psi) ~ int_0^psi sin^2 t I(t) dt,  I(t) = int_0^pi sin s sqrt(1 + 2 sin^2 t sin^2 s) ds
//   H_3: |Lambda^-1 u|^2 = 1 + 2 sin^2 psi_2,  cap(psi) ~ int_0^psi sin t sqrt(1 + 2 sin^2 t) dt
// Both shapes are fixed up to scale, so each cap fraction F(psi) = cap(psi)/cap(pi) is
// computed once by GSL Gauss-Legendre quadrature (gsl_integration_glfixed, 10 nodes per cell) on
// 2048 cells of [0, pi] and interpolated by cubic Hermite with the exact density as slope (both
// counts are arguments of CalotteTable::build, for measuring them: docs/tradeoff.md); the tables are
// built on first use (function-local statics: thread-safe, and never built by a scene that
// samples no 2D triple). psi = F^-1(G) by bisection on the interpolant, as the paper says.
//
// What this samples (measured in docs/paper-findings.md): psi_1 has exactly the marginal of
// the surface measure of H_4, but psi_2 given psi_1 follows the area of the opening H_3,
// not the conditional of H_4's surface measure (whose element also carries the tilt
// |Lambda^-1 u|), and H_4's surface measure is in any case not the uniform measure on the
// velocities: in the orthonormal Jacobi coordinates of the relative velocities the phi's are
// the hyperspherical angles of a ROUND 3-sphere (DESIGN.md §3).
#pragma once
#include <array>
#include <vector>

#include "revcol/error.hpp"

namespace revcol::paper {

/// Calotte-area fraction F(psi) of one of the paper's two ellipsoid shapes, tabulated.
class CalotteTable {
 public:
  /// Default cells of the table on [0, pi].
  static constexpr int cells = 2048;
  /// Default Gauss-Legendre nodes per cell of the cap integral.
  static constexpr int quadrature_nodes = 10;

  /// H_4 = (1, 1, 1/sqrt3, 1/sqrt3) (built on first call).
  static const CalotteTable& h4();
  /// H_3 = (1, 1/sqrt3, 1/sqrt3) (built on first call).
  static const CalotteTable& h3();

  /// F(psi) for psi in [0, pi], by the table.
  double fraction(double psi) const;
  /// F^-1(g), g in [0, 1]: bisection on the interpolant (bracket below 1e-15).
  double inverse(double g) const;
  /// dF/dpsi, exact (by quadrature for H_4).
  double density(double psi) const;
  /// Unnormalized cap(pi) (the whole surface over det(Lambda), omitting 2 pi for H_4 and H_3).
  double total() const { return total_; }
  /// Dimension s of the ellipsoid (4 or 3).
  int dim() const { return s_; }

  /// Cells of this table.
  int table_cells() const { return n_; }
  /// Gauss-Legendre nodes per cell this table was integrated with.
  int nodes() const { return nodes_; }

  /// F(psi) by direct GSL quadrature, no table (for tests).
  static double fraction_direct(int s, double psi);
  /// A table of shape s (4: H_4, 3: H_3) with `cells` cells (in [16, 2^20]) integrated with
  /// `nodes` Gauss-Legendre nodes per cell (in [1, 64]), built now (not shared). With the
  /// defaults it equals h4() / h3() bit for bit. For measuring the knobs
  /// (`revcol-bench --bench tradeoff/calotte`); the sampler uses h4() and h3().
  static CalotteTable build(int s, int cells, int nodes);

 private:
  CalotteTable(int s, int n, int nodes);
  double hermite(int k, double u) const;
  int s_;
  int n_ = cells, nodes_ = quadrature_nodes;
  double total_;
  std::vector<double> F_, dF_;  // at psi_k = k pi / cells
};

/// Procedure 5 with s = 4 for the paper's H_4: exactly 3 random numbers -> (psi_1, psi_2, psi_3).
class HyperEllipsoidSampler {
 public:
  /// Fetches (and on first use builds) the two tables.
  HyperEllipsoidSampler() : h4_(&CalotteTable::h4()), h3_(&CalotteTable::h3()) {}
  /// psi_1 in [0, pi], psi_2 in [0, pi], psi_3 in [0, 2 pi]; throws unless every g is in [0, 1].
  std::array<double, 3> psi(const std::array<double, 3>& g) const {
    require(g[0] >= 0.0 && g[0] <= 1.0 && g[1] >= 0.0 && g[1] <= 1.0 && g[2] >= 0.0 && g[2] <= 1.0,
            "random numbers must be in [0,1]");
    return {h4_->inverse(g[0]), h3_->inverse(g[1]),
            6.283185307179586476925286766559005768 * g[2]};
  }

 private:
  const CalotteTable* h4_;
  const CalotteTable* h3_;
};

}  // namespace revcol::paper
