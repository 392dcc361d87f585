#include "revcol/collide/exact.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "revcol/double_double.hpp"
#include "revcol/error.hpp"

namespace revcol {
namespace {

constexpr double kPi = trig::kPi;
constexpr double kU = std::numeric_limits<double>::epsilon() / 2;  // unit roundoff

std::string str(double x) { return std::to_string(x); }

using dd::DD;
using dd::two_prod;
using dd::two_sum;

}  // namespace

ExactCollision::ExactCollision(int n, int d, std::vector<Contact> contacts,
                               const std::vector<double>& normals, Law law, int bits)
    : n_(n), d_(d), law_(law), fp_(bits), contacts_(std::move(contacts)) {
  require(n >= 2, [&] { return "a collision needs n >= 2 particles, got " + std::to_string(n); });
  require(d >= 1 && d <= 3, [&] { return "dimension must be 1, 2 or 3, got " + std::to_string(d); });
  D_ = (n - 1) * d;
  require(D_ <= max_dim, [&] {
    return "too many particles: (n-1) d = " + std::to_string(D_) + " exceeds " + std::to_string(max_dim);
  });
  m_ = static_cast<int>(contacts_.size());
  require(m_ >= 1, "a collision needs at least one contact");
  require(m_ <= 3, [&] {
    return "at most 3 independent contacts are supported, got " + std::to_string(m_) + " contacts";
  });
  require(static_cast<int>(normals.size()) == m_ * d, [&] {
    return "normals must have " + std::to_string(m_) + " x " + std::to_string(d) + " values, got " +
           std::to_string(normals.size());
  });
  for (int k = 0; k < m_; ++k) {
    const Contact& c = contacts_[k];
    require(c.i >= 0 && c.i < n && c.j >= 0 && c.j < n, [&] {
      return "contact " + std::to_string(k) + " names particle outside 0.." + std::to_string(n - 1);
    });
    require(c.i != c.j, [&] { return "contact " + std::to_string(k) + " pairs a particle with itself"; });
    for (int l = 0; l < k; ++l) {
      const Contact& o = contacts_[l];
      require(!((o.i == c.i && o.j == c.j) || (o.i == c.j && o.j == c.i)), [&] {
        return "contacts " + std::to_string(l) + " and " + std::to_string(k) + " are the same pair";
      });
    }
  }
  // m contacts constrain an (n-1)d-dimensional relative space; more contacts than that
  // are dependent by counting (checked here, before the QR reads an m x m block)
  require(m_ <= D_, [&] {
    return std::to_string(m_) + " contacts among " + std::to_string(n) + " particles in " + std::to_string(d) +
           "D are linearly dependent (only " + std::to_string(D_) +
           " relative degrees of freedom); at most 3 independent contacts are supported";
  });
  f_ = D_ - m_;

  // Helmert rows: h_k = (1, .., 1, -k, 0, ..) / sqrt(k (k+1)), k = 1..n-1
  H_ = Eigen::MatrixXd::Zero(n - 1, n);
  for (int k = 1; k < n; ++k) {
    const double s = 1.0 / std::sqrt(static_cast<double>(k) * (k + 1));
    for (int i = 0; i < k; ++i) H_(k - 1, i) = s;
    H_(k - 1, k) = -k * s;
  }
  // constraint vectors a_k = (H e_i - H e_j) (x) r / sqrt 2
  Aa_ = Eigen::MatrixXd::Zero(D_, m_);
  for (int k = 0; k < m_; ++k) {
    double r[3] = {0, 0, 0}, len2 = 0.0;
    for (int a = 0; a < d; ++a) {
      r[a] = normals[k * d + a];
      require(std::isfinite(r[a]), [&] { return "normal of contact " + std::to_string(k) + " is not finite"; });
      len2 += r[a] * r[a];
    }
    require(len2 > 0.0, [&] { return "normal of contact " + std::to_string(k) + " is zero"; });
    const double len = std::sqrt(len2);
    for (int a = 0; a < d; ++a) normals_.push_back(r[a] / len);
    for (int row = 0; row < n - 1; ++row) {
      const double h = H_(row, contacts_[k].i) - H_(row, contacts_[k].j);
      for (int a = 0; a < d; ++a) Aa_(row * d + a, k) = h * (r[a] / len) / std::sqrt(2.0);
    }
  }
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(Aa_);
  Q_ = qr.householderQ();
  const Eigen::MatrixXd R = qr.matrixQR().topRows(m_).triangularView<Eigen::Upper>();
  for (int k = 0; k < m_; ++k) {
    require(std::fabs(R(k, k)) > 1e-9, [&] {
      return "contacts are linearly dependent (contact " + std::to_string(k) +
             " adds no new constraint); at most 3 independent contacts are supported";
    });
  }
  // the cone in V coordinates: {y : b_k . y > 0}, b_k = R.col(k)
  if (m_ == 1) {
    ysign_ = R(0, 0) > 0 ? 1.0 : -1.0;
  } else if (m_ == 2) {
    const Eigen::Vector2d b1 = R.col(0), b2 = R.col(1);
    Eigen::Vector2d e1(-b1.y(), b1.x()), e2(-b2.y(), b2.x());  // edges: b1.y = 0, b2.y = 0
    if (b2.dot(e1) < 0) e1 = -e1;
    if (b1.dot(e2) < 0) e2 = -e2;
    p1_ = e1.normalized();
    const Eigen::Vector2d e2n = e2.normalized();
    q_ = (e2n - e2n.dot(p1_) * p1_).normalized();
    omega_ = std::atan2(e2n.dot(q_), e2n.dot(p1_));
    require(omega_ > 1e-9, "the contacts leave no room to separate (the cone is empty)");
  } else {
    const Eigen::Vector3d b1 = R.col(0), b2 = R.col(1), b3 = R.col(2);
    Eigen::Vector3d v1 = b2.cross(b3), v2 = b3.cross(b1), v3 = b1.cross(b2);
    if (b1.dot(v1) < 0) v1 = -v1;
    if (b2.dot(v2) < 0) v2 = -v2;
    if (b3.dot(v3) < 0) v3 = -v3;
    A_ = v1.normalized();
    B_ = v2.normalized();  // the apex: the map's singular vertex
    C_ = v3.normalized();
    T_ = (C_ - C_.dot(A_) * A_).normalized();
    k_ = A_.dot(B_);
    bt_ = B_.dot(T_);
    g_ = std::fabs(A_.dot(B_.cross(T_)));
    Omega_ = 2.0 * std::atan2(std::fabs(A_.dot(B_.cross(C_))), 1.0 + A_.dot(B_) + B_.dot(C_) + C_.dot(A_));
    nAC_ = A_.cross(C_).normalized();
    mid_ = A_ + C_;
    hB_ = std::fabs(B_.dot(nAC_));
    require(Omega_ > 1e-9 && hB_ > 1e-9, "the contacts leave no room to separate (the cone is empty)");
  }
  const int flux = law == Law::flux ? 1 : 0;
  eta_ = trig::QuarterLaw(m_ - 1 + flux, std::max(f_ - 1, 0));
  signed_ = trig::SignedLaw(m_ - 1 + flux);
  for (int j = 0; j + 2 < f_; ++j) zlaws_.emplace_back(f_ - 2 - j);
}

ExactCollision ExactCollision::from_positions(int n, int d, std::vector<Contact> contacts,
                                              const std::vector<double>& positions, double diameter,
                                              Law law, int bits, double tol) {
  require(n >= 2 && d >= 1 && d <= 3, "a collision needs n >= 2 particles in d = 1, 2 or 3");
  require(static_cast<int>(positions.size()) == n * d, [&] {
    return "positions must have " + std::to_string(n) + " x " + std::to_string(d) + " values";
  });
  require(std::isfinite(diameter) && diameter > 0.0, "diameter must be finite and > 0");
  require(std::isfinite(tol) && tol >= 0.0, "tolerance must be finite and >= 0");
  std::vector<double> normals;
  for (std::size_t k = 0; k < contacts.size(); ++k) {
    const Contact& c = contacts[k];
    require(c.i >= 0 && c.i < n && c.j >= 0 && c.j < n, [&] {
      return "contact " + std::to_string(k) + " names particle outside 0.." + std::to_string(n - 1);
    });
    double dist2 = 0.0;
    for (int a = 0; a < d; ++a) {
      const double r = positions[c.i * d + a] - positions[c.j * d + a];
      require(std::isfinite(r), "positions must be finite");
      normals.push_back(r);
      dist2 += r * r;
    }
    const double dist = std::sqrt(dist2);
    require(std::fabs(dist - diameter) <= tol * diameter, [&] {
      return "particles " + std::to_string(c.i) + " and " + std::to_string(c.j) +
             " do not touch: distance " + str(dist) + ", diameter " + str(diameter);
    });
  }
  return ExactCollision(n, d, std::move(contacts), normals, law, bits);
}

ExactCollision::Vec ExactCollision::relative(const double* v) const {
  // Each Helmert row sums to zero, so x is a combination of velocity differences.
  Vec x = Vec::Zero(D_);
  for (int k = 0; k < n_ - 1; ++k)
    for (int i = 0; i <= k + 1; ++i)
      for (int a = 0; a < d_; ++a) x(k * d_ + a) += H_(k, i) * v[i * d_ + a];
  return x;
}

void ExactCollision::velocities(const Vec& x, const double* cm, double* v) const {
  for (int i = 0; i < n_; ++i)
    for (int a = 0; a < d_; ++a) {
      double s = 0.0;
      for (int k = std::max(i - 1, 0); k < n_ - 1; ++k) s += H_(k, i) * x(k * d_ + a);
      v[i * d_ + a] = cm[a] + s;
    }
}

void ExactCollision::centre(const double* v, const Held* held, double* cm) const {
  for (int a = 0; a < d_; ++a) {
    double s = 0.0;
    if (held) s = held->momentum[a];
    else for (int i = 0; i < n_; ++i) s += v[i * d_ + a];
    cm[a] = s / n_;
  }
}

double ExactCollision::radius(const Vec& x, const Held* held) const {
  const double norm = x.norm();
  if (!held) return norm;
  double m2 = 0.0;
  for (int a = 0; a < d_; ++a) m2 += held->momentum[a] * held->momentum[a];
  const double r2 = held->energy - m2 / n_;
  require(r2 > 0.0, "invariants leave no relative kinetic energy (E <= |M|^2 / n)");
  const double cancel = 16.0 * std::numeric_limits<double>::epsilon() * held->energy;
  require(std::fabs(norm * norm - r2) <= 1e-8 * r2 + cancel, [&] {
    return "velocities are inconsistent with the given energy and momentum (relative speed " +
           str(norm) + " vs " + str(std::sqrt(r2)) + ")";
  });
  return std::sqrt(r2);
}

ExactCollision::Energy ExactCollision::relative_energy(const double* v, const double* cm, const Held* held) const {
  // sum |v_i - cm|^2 (or E - |M|^2 / n from held invariants) to double-double accuracy:
  // v - cm exactly by TwoSum, its square exactly by TwoProd, the sum compensated
  DD r{0.0, 0.0};
  if (held) {
    DD m2{0.0, 0.0};
    for (int a = 0; a < d_; ++a) m2 = dd::add(m2, two_prod(held->momentum[a], held->momentum[a]));
    const DD q = dd::div(m2, {static_cast<double>(n_), 0.0});
    r = dd::add({held->energy, 0.0}, {-q.hi, -q.lo});
  } else {
    for (int i = 0; i < n_; ++i)
      for (int a = 0; a < d_; ++a) r = dd::add(r, dd::square(two_sum(v[i * d_ + a], -cm[a])));
  }
  return {r.hi, r.lo};
}

void ExactCollision::check_common(const double* v, const Held* held) const {
  for (int k = 0; k < n_ * d_; ++k) require(std::isfinite(v[k]), "velocities must be finite (got a NaN or infinity)");
  double rel = 0.0;  // the largest relative component over the contacts: the collision's speed scale
  for (const auto& c : contacts_)
    for (int a = 0; a < d_; ++a) rel = std::fmax(rel, std::fabs(v[c.i * d_ + a] - v[c.j * d_ + a]));
  check_speed_range(max_abs(v, n_ * d_), rel);
  if (held) {
    require(std::isfinite(held->energy), "energy must be finite");
    for (int a = 0; a < d_; ++a) require(std::isfinite(held->momentum[a]), "momentum must be finite");
  }
}

std::vector<double> ExactCollision::normal_speeds(const double* v) const {
  // r . (v_i - v_j) from the differences: a pair at rest gives exactly 0, where the same
  // number through the Helmert coordinates carries rounding of either sign (and would
  // misclassify a resting contact of Newton's cradle as separating)
  std::vector<double> out(m_);
  for (int k = 0; k < m_; ++k) {
    double p = 0.0;
    for (int a = 0; a < d_; ++a)
      p += normals_[k * d_ + a] * (v[contacts_[k].i * d_ + a] - v[contacts_[k].j * d_ + a]);
    out[k] = p;
  }
  return out;
}

void ExactCollision::check_pre(const double* pre, const Held* held) const {
  check_common(pre, held);
  const std::vector<double> sp = normal_speeds(pre);
  bool approaching = false;
  for (int k = 0; k < m_; ++k) {
    const double p = sp[k];
    require(p <= 0.0, [&] {
      return "contact " + std::to_string(k) + " (" + std::to_string(contacts_[k].i) + ", " +
             std::to_string(contacts_[k].j) + ") separates before the collision (normal relative velocity " +
             str(p) + " > 0): a separating contact is not part of the collision";
    });
    approaching = approaching || p < 0.0;
  }
  require(approaching, "no contact approaches: nothing collides (zero relative speed along every normal)");
  radius(relative(pre), held);
}

void ExactCollision::check_post(const double* post, const Held* held) const {
  check_common(post, held);
  const Vec x = relative(post);
  radius(x, held);
  if (needs_log(post)) return;
  const std::vector<double> sp = normal_speeds(post);
  for (int k = 0; k < m_; ++k) {
    require(sp[k] > 0.0, [&] {
      return "post-collision contact " + std::to_string(k) + " does not separate (normal relative velocity " +
             str(sp[k]) + " <= 0)";
    });
  }
}

// --- the chart -------------------------------------------------------------------------

void ExactCollision::arvo_inverse(const Eigen::Vector3d& P, double& u1, double& u2,
                                  double& amp1, double& amp2) const {
  // Conditioning: moving P by dy turns the great circle BP by dy / |P - B| and so moves C'
  // along edge AC by about dy |C' - B| / (|P - B| sin psi), psi the angle between the two
  // great circles at C'. The sub-area changes by at most that arc length, so
  // du1 <= dy |C'-B| / (Omega |P-B| sin psi); u2 = (|P-B| / |C'-B|)^2 moves by at most
  // 2 dy (1 + 1/sin psi) / |C' - B|. (Checked against measured errors: test_exact.)
  const double dPB = (P - B_).norm();
  const Eigen::Vector3d bp = B_.cross(P);
  const double bpn = bp.norm();
  if (bpn == 0.0) {  // P is the apex itself (only a pre state on the boundary can be)
    u1 = 0.0;
    u2 = 0.0;
    amp1 = amp2 = std::numeric_limits<double>::infinity();
    return;
  }
  Eigen::Vector3d Cp = bp.cross(nAC_).normalized();  // great circle BP meets edge AC
  if (Cp.dot(mid_) < 0.0) Cp = -Cp;
  const double sinpsi = std::max((bp / bpn).cross(nAC_).norm(), 1e-300);
  const double dCB = (Cp - B_).norm();
  const double tau = (Cp - A_).norm() / (Cp + A_).norm();  // tan(theta/2)
  // dOmega'/dtheta from Omega' = 2 atan(g tau / ((1+k) + bt tau)), dtau/dtheta = (1+tau^2)/2
  const double num = g_ * tau, den = (1.0 + k_) + bt_ * tau;
  const double darea = g_ * (1.0 + k_) * (1.0 + tau * tau) / (num * num + den * den);
  amp1 = darea * dCB / (Omega_ * std::max(dPB, 1e-300) * sinpsi);
  amp2 = 2.0 * (1.0 + 1.0 / sinpsi) / dCB;
  u1 = 2.0 * std::atan2(g_ * tau, (1.0 + k_) + bt_ * tau) / Omega_;
  const double ratio = dPB / dCB;
  u2 = ratio * ratio;
}

Eigen::Vector3d ExactCollision::arvo_forward(double u1, double u2) const {
  const double half = 0.5 * u1 * Omega_;
  const double sh = std::sin(half), ch = std::cos(half);
  const double theta = 2.0 * std::atan2(sh * (1.0 + k_), g_ * ch - bt_ * sh);
  const Eigen::Vector3d Cp = std::cos(theta) * A_ + std::sin(theta) * T_;
  const double chord = (Cp - B_).norm();
  const double dist = 2.0 * std::asin(std::min(1.0, std::sqrt(u2) * 0.5 * chord));
  const Eigen::Vector3d N = (Cp - Cp.dot(B_) * B_).normalized();
  return std::cos(dist) * B_ + std::sin(dist) * N;
}

void ExactCollision::encode(const Vec& x, Point& p) const {
  const Vec xv = Q_.leftCols(m_).transpose() * x;
  const Vec xw = Q_.rightCols(f_).transpose() * x;
  const double rv = xv.norm(), rw = xw.norm();
  const double rho = std::hypot(rv, rw);
  const double ce = rv / rho, se = rw / rho;  // cos(eta), sin(eta)
  // a relative perturbation e of x moves y by <= e / cos(eta) and z by <= e / sin(eta)
  const double ay = 1.0 / std::max(ce, 1e-300), az = 1.0 / std::max(se, 1e-300);
  int k = 0;
  if (m_ == 2) {
    const Eigen::Vector2d y = xv / rv;
    // the arc spans angles [0, omega] from p1, omega < pi; a boundary point may round a hair
    // outside, and the cell encoding clamps it
    p.c[k] = std::atan2(y.dot(q_), y.dot(p1_)) / omega_;
    p.amp[k++] = ay / omega_;
  } else if (m_ == 3) {
    const Eigen::Vector3d P = xv / rv;
    double amp1, amp2;
    arvo_inverse(P, p.c[k], p.c[k + 1], amp1, amp2);
    p.amp[k++] = ay * amp1;
    p.amp[k++] = ay * amp2;
  }
  if (f_ == 1) {
    p.c[k] = signed_.cdf_sc(xw(0) / rho, ce);
    p.amp[k++] = signed_.max_density();
  } else if (f_ >= 2) {
    p.c[k] = eta_.cdf_sc(se, ce);
    p.amp[k++] = eta_.max_density();
    // hyperspherical angles of z = xw / rw; tails |z_{j..}| from the end
    std::array<double, max_dim + 1> tail{};
    tail[f_] = 0.0;
    for (int j = f_ - 1; j >= 0; --j) tail[j] = std::hypot(tail[j + 1], xw(j));
    // angle j is recovered to |dz| / (sin phi_0 ... sin phi_{j-1}) = |dz| |z| / tail[j]
    for (int j = 0; j + 2 < f_; ++j) {
      // phi_j = atan2(|z_{j+1..}|, z_j) in [0, pi]
      const double r = tail[j];
      const double s = r > 0 ? tail[j + 1] / r : 0.0, c = r > 0 ? xw(j) / r : 1.0;
      p.c[k] = zlaws_[j].cdf_sc(s, c);
      p.amp[k++] = zlaws_[j].max_density() * az * rw / std::max(r, 1e-300);
    }
    // the last angle, uniform on [0, 2 pi)
    double phi = std::atan2(xw(f_ - 1), xw(f_ - 2));
    if (phi < 0.0) phi += 2.0 * kPi;
    p.c[k] = phi / (2.0 * kPi);
    p.amp[k++] = az * rw / (2.0 * kPi * std::max(tail[f_ - 2], 1e-300));
  }
}

ExactCollision::Vec ExactCollision::decode(const Cells& u) const {
  int k = 0;
  Vec yv(m_);
  if (m_ == 1) {
    yv(0) = ysign_;
  } else if (m_ == 2) {
    const double t = fp_.decode(u[k++]) * omega_;
    const Eigen::Vector2d y = std::cos(t) * p1_ + std::sin(t) * q_;
    yv = y;
  } else {
    const double u1 = fp_.decode(u[k++]);
    const double u2 = fp_.decode(u[k++]);
    yv = arvo_forward(u1, u2);
  }
  Vec x = Q_.leftCols(m_) * yv;
  if (f_ == 0) return x;
  double se, ce;
  Vec zv(f_);
  if (f_ == 1) {
    signed_.inverse_sc(fp_.decode(u[k++]), se, ce);  // signed sine
    zv(0) = 1.0;
  } else {
    const double eta = eta_.inverse(fp_.decode(u[k++]));
    se = std::sin(eta);
    ce = std::cos(eta);
    double prod = 1.0;  // sin phi_0 ... sin phi_{j-1}
    for (int j = 0; j + 2 < f_; ++j) {
      double sj, cj;
      zlaws_[j].inverse_sc(fp_.decode(u[k++]), sj, cj);
      zv(j) = prod * cj;
      prod *= sj;
    }
    const double phi = 2.0 * kPi * fp_.decode(u[k++]);
    zv(f_ - 2) = prod * std::cos(phi);
    zv(f_ - 1) = prod * std::sin(phi);
  }
  return ce * x + se * (Q_.rightCols(f_) * zv);
}

std::vector<double> ExactCollision::recovery_bound(const double* post) const {
  check_common(post, nullptr);
  std::vector<double> out(D_ - 1);
  const Vec x = relative(post);
  Point p;
  encode(x, p);
  const double e = relative_error(post, x.norm());
  for (int k = 0; k < D_ - 1; ++k) out[k] = p.amp[k] * e * fp_.cells();
  return out;
}

double ExactCollision::relative_error(const double* post, double rho) const {
  // Rounding v = cm + (H^T (x) I) x to doubles moves each component by u |v_ik|, hence x by
  // at most u sum |v|; computing x, its V/W components and the chart adds a few roundings
  // per dimension relative to |x|.
  double sum = 0.0;
  for (int k = 0; k < n_ * d_; ++k) sum += std::fabs(post[k]);
  return kU * (2.0 * sum / rho + 2.0 * D_ + 8.0);
}

bool ExactCollision::needs_log(const double* post) const {
  // A relative perturbation e of x moves chart coordinate k by at most amp_k e (the
  // bounds in encode; test_exact measures actual errors at <= 0.7 of it). Log when that
  // can reach a quarter cell, or when the recovered coordinate is not within a quarter
  // cell of a cell centre: a safety net, so that a wrong recovery needs an error three
  // times the bound. Both directions evaluate this on
  // the same post velocities. Measure before changing: it decides the log's size.
  const Vec x = relative(post);
  const double rho = x.norm();
  if (!(rho > 0.0) || !std::isfinite(rho)) return true;
  const double e = relative_error(post, rho);
  Point p;
  encode(x, p);
  for (int k = 0; k < D_ - 1; ++k) {
    if (p.amp[k] * e * fp_.cells() > 0.25) return true;
    const double off = fp_.offset_in_cell(p.c[k]);
    if (off < 0.25 || off > 0.75) return true;
  }
  return false;
}

bool ExactCollision::logs(const double* post) const { return needs_log(post); }

std::vector<double> ExactCollision::chart(const double* post) const {
  check_common(post, nullptr);
  const std::vector<double> sp = normal_speeds(post);
  // a contact approaches when its normal speed is below the state's own rounding (a post state
  // the operator wrote at a centre-of-mass speed of 1e12 carries ~1e-4 of it: the stability study)
  const double rho = relative(post).norm(), tol = 2.0 * relative_error(post, rho) * rho;
  for (int k = 0; k < m_; ++k) {
    require(sp[k] >= -tol, [&] {
      return "chart: contact " + std::to_string(k) + " (" + std::to_string(contacts_[k].i) + ", " +
             std::to_string(contacts_[k].j) + ") approaches (normal relative velocity " + str(sp[k]) +
             " < 0, beyond the state's rounding): the chart is defined on post-collision states, every contact "
             "separating or grazing";
    });
  }
  return chart_unchecked(post);
}

std::vector<double> ExactCollision::chart_unchecked(const double* post) const {
  check_common(post, nullptr);
  Point p;
  encode(relative(post), p);
  return std::vector<double>(p.c.begin(), p.c.begin() + (D_ - 1));
}

void ExactCollision::build(const double* v, const Cells& cells, double sign, const Held* held,
                           double* out) const {
  double cm[3];
  centre(v, held, cm);
  // h = (H^T (x) I) u for the decoded unit direction u, scaled so that sum |h_i|^2 is the
  // relative energy R itself: the rounded Helmert entries make H H^T = I + E with a fixed
  // E, and sum |h_i|^2 = 1 + u^T E u lies within an ulp of 1, where a double rounds it to
  // 1 exactly. Both sums are therefore formed in double-double and the scale
  // sqrt(R / sum |h|^2) is applied as hi * h + lo * h; without this, every collision scaled
  // the relative energy by the same 1 + O(eps/3), a drift linear in the number of
  // collisions (measured 3-8e-17 per collision, 3-7e-11 after 1e6).
  const Energy e = relative_energy(v, cm, held);
  const Vec u = decode(cells);
  std::array<double, 3 * (max_dim + 3)> h{};
  const Vec zero_cm = Vec::Zero(3);
  velocities(u, zero_cm.data(), h.data());
  DD s2{0.0, 0.0};
  for (int k = 0; k < n_ * d_; ++k) s2 = dd::add(s2, two_prod(h[k], h[k]));
  const DD scale = dd::sqrt(dd::div({e.hi, e.lo}, s2));
  const double hi = sign * scale.hi, lo = sign * scale.lo;
  for (int i = 0; i < n_; ++i)
    for (int a = 0; a < d_; ++a) {
      const double x = h[i * d_ + a];
      out[i * d_ + a] = cm[a] + (hi * x + lo * x);
    }
}

void ExactCollision::forward(const double* pre, const double* g, double* post, RareLog& log,
                             const Held* held) const {
  check_pre(pre, held);
  for (int k = 0; k < D_ - 1; ++k)
    require(g[k] >= 0.0 && g[k] <= 1.0, "random numbers must be in [0,1]");
  Point p;
  encode(-relative(pre), p);  // -x_pre lies in (the closure of) P
  Cells pre_cells{}, cells{};
  for (int k = 0; k < D_ - 1; ++k) {
    pre_cells[k] = fp_.encode(p.c[k]);
    cells[k] = fp_.add(pre_cells[k], fp_.shift(g[k]));
  }
  std::array<double, 3 * (max_dim + 3)> out{};
  build(pre, cells, +1.0, held, out.data());
  const bool logged = needs_log(out.data());
  std::copy(out.begin(), out.begin() + n_ * d_, post);
  if (logged)
    for (int k = 0; k < D_ - 1; ++k) log.push(pre_cells[k]);
}

void ExactCollision::reverse(const double* post, const double* g, double* pre, RareLog& log,
                             const Held* held) const {
  check_post(post, held);
  for (int k = 0; k < D_ - 1; ++k)
    require(g[k] >= 0.0 && g[k] <= 1.0, "random numbers must be in [0,1]");
  Cells pre_cells{};
  if (needs_log(post)) {
    require(log.size() >= static_cast<std::size_t>(D_ - 1),
            "rare log is empty: this post-collision state needs a logged coordinate");
    for (int k = D_ - 2; k >= 0; --k) pre_cells[k] = log.pop();
  } else {
    Point p;
    encode(relative(post), p);
    for (int k = 0; k < D_ - 1; ++k) pre_cells[k] = fp_.sub(fp_.encode(p.c[k]), fp_.shift(g[k]));
  }
  std::array<double, 3 * (max_dim + 3)> out{};
  build(post, pre_cells, -1.0, held, out.data());
  std::copy(out.begin(), out.begin() + n_ * d_, pre);
}

void ExactCollision::quantize(const double* pre, double* out, const Held* held) const {
  check_pre(pre, held);
  Point p;
  encode(-relative(pre), p);
  Cells cells{};
  for (int k = 0; k < D_ - 1; ++k) cells[k] = fp_.encode(p.c[k]);
  std::array<double, 3 * (max_dim + 3)> tmp{};
  build(pre, cells, -1.0, held, tmp.data());
  std::copy(tmp.begin(), tmp.begin() + n_ * d_, out);
}

}  // namespace revcol
