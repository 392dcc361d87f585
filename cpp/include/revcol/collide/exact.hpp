// The exact collision operator for n particles in d dimensions (DESIGN.md §3-4): one code
// path for every contact set with at most 3 independent contacts.
//
// 1. Relative velocities in an orthonormal basis of the zero-momentum subspace (Helmert
//    rows h_k, k = 1..n-1: x = (H (x) I_d) v, dimension D = (n-1)d); |x|^2 = E - |M|^2/n.
// 2. Contact (i, j) with unit normal r (from j to i) is the constraint a.x > 0 after the
//    collision, a = (H e_i - H e_j) (x) r / sqrt(2); P = {x : a_k.x > 0}, pre set -P.
// 3. QR of A = [a_1..a_m] gives an orthonormal basis: V = span(a_k) (dim m), W (dim f = D-m);
//    x = rho (cos(eta) Q_V y + sin(eta) Q_W z), |y| = |z| = 1.
// 4. The chart maps P one-to-one and measure-preservingly onto [0,1)^(D-1):
//    y: m = 1 a point; m = 2 the normalized angle along the arc T; m = 3 Arvo's
//       area-preserving map of the spherical triangle T (J. Arvo, "Stratified sampling of
//       spherical triangles", SIGGRAPH 1995), written here in half-angle form:
//       tan(Omega'/2) = g tau / ((1+k) + bt tau) with tau = tan(theta/2), theta the arc length
//       from vertex A along edge AC, so both directions are closed forms without the
//       sqrt(1 - q^2) cancellation, and the arc from B uses chords:
//       u2 = (|P - B| / |C' - B|)^2.
//    eta: density cos^A sin^B on [0, pi/2], A = m - 1 (+1 for flux), B = f - 1
//       (sin^2 eta ~ Beta(f/2, m/2) or Beta(f/2, (m+1)/2)); when f = 1, z = +-1 merges with
//       eta into a signed angle with density cos^A.
//    z: hyperspherical angles phi_j of S^(f-1), densities sin^(f-2-j), the last uniform on
//       [0, 2 pi).
// 5. Forward: U' = cells(chart(-x_pre)); U = U' + G (mod 2^K each); x_post = chart^-1(U).
//    Reverse: U = cells(chart(x_post)); U' = U - G; x_pre = -chart^-1(U').
// The rare log: where a post coordinate cannot be recovered to a quarter cell (the centre of
// mass is fast next to the relative speed, or the point is near a singular set of the
// chart: eta near 0 or pi/2, z near a pole, y near the triangle's apex B), forward pushes U'
// and reverse pops it; the test is computed from the post velocities alone, identically in
// both directions.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "revcol/eigen.hpp"

#include "revcol/collide/common.hpp"
#include "revcol/collide/trig_cdf.hpp"
#include "revcol/fixed_point.hpp"

namespace revcol {

/// A contact between particles i and j of a collision; its normal points from j to i.
struct Contact {
  int i;  ///< the particle the normal points to
  int j;  ///< the particle the normal points from
};

/// Momentum and energy held by the caller (the paper's illustrations): energy = sum |v|^2.
struct Held {
  const double* momentum;  ///< d components
  double energy;           ///< sum of squared speeds
};

/// The exact collision operator for one collision geometry.
class ExactCollision {
 public:
  /// Largest supported relative dimension D = (n-1) d.
  static constexpr int max_dim = 27;

  /// n particles in d dimensions, contacts and their normals (m x d, row-major, any
  /// non-zero length). Throws InvalidArgument on a bad geometry.
  ExactCollision(int n, int d, std::vector<Contact> contacts, const std::vector<double>& normals,
                 Law law = Law::flux, int bits = FixedPoint::default_bits);

  /// The same from positions (n x d) and the diameter: each listed pair must touch, i.e.
  /// | |x_i - x_j| - diameter | <= tol * diameter; the normals are x_i - x_j.
  static ExactCollision from_positions(int n, int d, std::vector<Contact> contacts,
                                       const std::vector<double>& positions, double diameter,
                                       Law law = Law::flux, int bits = FixedPoint::default_bits,
                                       double tol = 1e-9);

  int particles() const { return n_; }           ///< n
  int dim() const { return d_; }                 ///< d
  int relative_dim() const { return D_; }        ///< D = (n-1) d
  int contacts() const { return m_; }            ///< m
  int free_dim() const { return f_; }            ///< f = D - m
  int draws() const { return D_ - 1; }           ///< random numbers per collision, d_n
  Law law() const { return law_; }               ///< the target law
  int bits() const { return fp_.bits(); }        ///< K
  const std::vector<Contact>& contact_list() const { return contacts_; }  ///< the contacts

  /// Pre -> post (n x d each, row-major) with d_n draws g in [0,1]. Throws InvalidArgument on
  /// a bad pre state, before anything changes; pushes D-1 cells onto `log` when needed.
  void forward(const double* pre, const double* g, double* post, RareLog& log,
               const Held* held = nullptr) const;
  /// Post -> pre with the draws forward used; pops the log when forward pushed.
  void reverse(const double* post, const double* g, double* pre, RareLog& log,
               const Held* held = nullptr) const;

  /// Throws InvalidArgument unless `pre` is a valid pre-collision state: finite, every
  /// contact approaching or at rest (normal relative velocity <= 0), at least one approaching.
  void check_pre(const double* pre, const Held* held = nullptr) const;
  /// Throws InvalidArgument unless `post` is a valid post-collision state (every contact
  /// separating, unless the rare log serves it).
  void check_post(const double* post, const Held* held = nullptr) const;
  /// Whether reversing `post` pops the rare log (D-1 cells).
  bool logs(const double* post) const;

  /// The bound, in cells, on how far each chart coordinate of `post` can move when its
  /// velocities are rounded (the rare log fires above 1/4).
  std::vector<double> recovery_bound(const double* post) const;
  /// Chart coordinates in [0,1] of a post state (D-1 values; uniform under the law). The
  /// chart is defined on the closed cone P of post states, every contact separating or grazing
  /// (normal relative velocity >= 0, to the state's own rounding); throws InvalidArgument for a
  /// contact that approaches beyond it,
  /// and as every operator does for a velocity that is not finite or a zero relative speed.
  std::vector<double> chart(const double* post) const;
  /// chart() without the cone check: the randomness study's reading of every post state its
  /// chain accepts, including one the rare log serves with a contact rounded a hair inside.
  std::vector<double> chart_unchecked(const double* post) const;
  /// The pre state as a reversal restores it: its cells decoded at their centres.
  void quantize(const double* pre, double* out, const Held* held = nullptr) const;
  /// Normal relative velocities r_k . (v_i - v_j) of a state, from the differences (exactly
  /// zero for particles at rest relative to each other).
  std::vector<double> normal_speeds(const double* v) const;

 private:
  using Vec = Eigen::VectorXd;
  struct Point {  // chart coordinates of a point of P and their conditioning
    std::array<double, max_dim> c{};
    std::array<double, max_dim> amp{};  // bound on |dc| / (|dx| / |x|)
  };
  using Cells = std::array<std::uint64_t, max_dim>;

  Vec relative(const double* v) const;                       // x = (H (x) I) v
  void velocities(const Vec& x, const double* cm, double* v) const;  // v = cm + (H^T (x) I) x
  void centre(const double* v, const Held* held, double* cm) const;
  double radius(const Vec& x, const Held* held) const;
  struct Energy {
    double hi, lo;  // a double-double: hi + lo
  };
  Energy relative_energy(const double* v, const double* cm, const Held* held) const;
  void check_common(const double* v, const Held* held) const;
  void encode(const Vec& x, Point& p) const;
  Vec decode(const Cells& u) const;  // unit vector in P
  void arvo_inverse(const Eigen::Vector3d& P, double& u1, double& u2, double& amp1,
                    double& amp2) const;
  Eigen::Vector3d arvo_forward(double u1, double u2) const;
  bool needs_log(const double* post) const;
  double relative_error(const double* post, double rho) const;
  void build(const double* pre_or_post, const Cells& cells, double sign, const Held* held,
             double* out) const;

  int n_, d_, D_, m_, f_;
  Law law_;
  FixedPoint fp_;
  std::vector<Contact> contacts_;
  Eigen::MatrixXd H_;   // (n-1) x n Helmert rows
  Eigen::MatrixXd Aa_;  // D x m constraint vectors a_k (unit)
  std::vector<double> normals_;  // m x d unit normals, for exact normal speeds
  Eigen::MatrixXd Q_;   // D x D: V basis (m columns) then W basis (f columns)
  double ysign_ = 1.0;  // m = 1: the side of V's basis vector inside P
  // m = 2: arc from p1 towards q, length omega
  Eigen::Vector2d p1_, q_;
  double omega_ = 0.0;
  // m = 3: triangle A, B (apex), C; tangent T at A towards C; constants of the area map
  Eigen::Vector3d A_, B_, C_, T_, nAC_, mid_;
  double k_ = 0.0, bt_ = 0.0, g_ = 0.0, Omega_ = 0.0, hB_ = 0.0;
  trig::QuarterLaw eta_;
  trig::SignedLaw signed_;
  std::vector<trig::HalfLaw> zlaws_;  // f-2 laws of the hyperspherical angles
};

}  // namespace revcol
