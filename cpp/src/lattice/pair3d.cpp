// The exact 3D lattice pair operator (revcol/lattice/pair3d.hpp): faces, the normal frame, the
// azimuth rows, the polar table, forward, reverse and the pair level.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "revcol/error.hpp"
#include "revcol/lattice/pair3d.hpp"

namespace revcol::lattice {
namespace {

constexpr i64 kMaxComp = LatticePair3D::max_component;
constexpr i64 kMaxVel = 1LL << 59;
constexpr int kPhiShift = kCellBits - LatticePair3D::phi_bits;  // azimuth cell = 4 fine cells
constexpr std::int64_t kPhiMask = (1LL << LatticePair3D::phi_bits) - 1;
constexpr int kTotBits = LatticePair3D::theta_total_bits;
constexpr std::uint64_t kThetaTotal = 1ULL << kTotBits;
constexpr std::uint64_t kThetaMask = kThetaTotal - 1;
// tan(pi / 2^18): half an azimuth cell (only a first guess of a row's ends).
const double kTanHalfPhi = std::tan(std::numbers::pi / static_cast<double>(1LL << LatticePair3D::phi_bits));

inline i128 sq(i64 a) { return static_cast<i128>(a) * a; }
inline i128 norm2(const Vec3& v) { return sq(v[0]) + sq(v[1]) + sq(v[2]); }
inline bool small(i64 v, i64 bound) { return v > -bound && v < bound; }
inline bool small(const Vec3& v, i64 bound) { return small(v[0], bound) && small(v[1], bound) && small(v[2], bound); }
inline i64 iabs(i64 v) { return v < 0 ? -v : v; }
inline i128 cross(const IVec& b, const IVec& v) { return static_cast<i128>(b.x) * v.y - static_cast<i128>(b.y) * v.x; }
// Wrapping (mod 2^64) arithmetic for positions: no signed overflow, two's complement result.
inline i64 wadd(i64 a, i64 b) { return static_cast<i64>(static_cast<std::uint64_t>(a) + static_cast<std::uint64_t>(b)); }
inline i64 wsub(i64 a, i64 b) { return static_cast<i64>(static_cast<std::uint64_t>(a) - static_cast<std::uint64_t>(b)); }

// An azimuth cell: its centre as a rotation (fine cells 4 phi + 2) and its two boundaries.
struct AzCell {
  std::int64_t phi = 0;
  RotCoef c{};
  IVec b0{}, b1{};
  // v (!= 0) lies in the cell (exact; the same decision as in_coarse_cell(v, phi, 2))
  bool holds(const IVec& v) const {
    const auto cr = [&](const IVec& b) { return static_cast<i128>(b.x) * v.y - static_cast<i128>(b.y) * v.x; };
    return cr(b0) >= 0 && cr(b1) < 0;
  }
};
inline RotCoef az_centre(std::int64_t phi) { return rot_coef((phi << kPhiShift) + (1LL << (kPhiShift - 1))); }
AzCell az_cell(std::int64_t phi) {
  phi &= kPhiMask;
  return {phi, az_centre(phi), boundary((2 * phi) << kPhiShift), boundary((2 * phi + 2) << kPhiShift)};
}
std::optional<std::array<i64, 2>> row_of(const AzCell& az, i64 xa);

// A state's column in its face frame and the column's normal frame.
struct Column {
  int face;
  i64 xc, yc, pz;  // the inside point in the face frame
  i64 zmin, zin;   // the face's lowest and the sphere's highest point of the column
  RotCoef cphi, ctheta;  // L: by -Kphi in (x, y), then by -Ktheta in (z, x)
};

Column make_column(const Vec3& p, i128 sigma2, std::int64_t sigma) {
  Column c;
  c.face = LatticePair3D::face_of(p);
  const Vec3 pf = LatticePair3D::to_face(p, c.face);
  c.xc = pf[0];
  c.yc = pf[1];
  c.pz = pf[2];
  c.zmin = LatticePair3D::zmin_of(c.face, c.xc, c.yc);
  const i128 r2 = sq(c.xc) + sq(c.yc);
  c.zin = static_cast<i64>(isqrt(static_cast<u128>(sigma2 - r2 - 1)));
  std::int64_t kphi = 0, ktheta = 0;
  if (r2 != 0) {
    // the nearest fine cell to atan2(yc, xc): the fine cell, or the next from its half-cell point on
    kphi = ((half_cell(c.xc, c.yc) + 1) >> 1) & (kCells - 1);
    ktheta = kQuarterTurn - normal_cell(static_cast<i64>(isqrt(static_cast<u128>(r2))), sigma);
  }
  c.cphi = rot_coef(kphi);
  c.ctheta = rot_coef(ktheta);
  return c;
}

// L(v) and its exact inverse.
Vec3 to_normal(const Vec3& v, const Column& c) {
  const IVec t = rotate_inv({v[0], v[1]}, c.cphi);
  const IVec s = rotate_inv({v[2], t.x}, c.ctheta);
  return {s.y, t.y, s.x};
}
Vec3 from_normal(const Vec3& v, const Column& c) {
  const IVec s = rotate({v[2], v[0]}, c.ctheta);
  const IVec t = rotate({s.y, v[1]}, c.cphi);
  return {t.x, t.y, s.x};
}
inline Vec3 neg(const Vec3& v) { return {-v[0], -v[1], -v[2]}; }

// The lowest pre phase of the column for inward W (face frame), or nullopt if not an interval.
std::optional<i64> lo_pre3(i128 sigma2, const Column& c, const Vec3& W) {
  return LatticePair3D::lo_pre(sigma2, c.xc, c.yc, c.zmin, c.zin, W);
}

// The lowest post phase for outgoing W2, or nullopt.
std::optional<i64> lo_post3(i128 sigma2, const Column& c, const Vec3& W) {
  i128 lo = c.zmin;
  const i128 d = sigma2 - sq(c.xc + W[0]) - sq(c.yc + W[1]);
  if (d > 0) {
    const i128 z = isqrt_ceil(static_cast<u128>(d));
    if (-z - W[2] >= c.zmin) return std::nullopt;
    lo = std::max(lo, z - W[2]);
  }
  return static_cast<i64>(std::min<i128>(lo, static_cast<i128>(c.zin) + 1));
}

// Polar cells are centred on multiples of the cell angle D = 2 pi 2^shift / 2^20: cell j holds
// the angles [(j - 1/2) D, (j + 1/2) D) of the plane vector (uz, xa) (half-cell boundaries of
// cells.hpp), so the pole (xa = 0, angle 0) is the centre of cell 0 and a head-on pre state
// rotates onto a cell's centre, never onto a boundary. Cells 0 and quarter are half cells.
std::int64_t polar_cell(i64 uz, i64 xa, int shift) {
  const std::int64_t h = half_cell(uz, xa);
  return (h + (std::int64_t{1} << shift)) >> (shift + 1);
}
// The plane vector (uz, xa) is in polar cell j (and in the quarter plane uz > 0, xa >= 0).
bool in_polar_cell(const IVec& v, std::int64_t j, int shift) {
  if (v.x <= 0 || v.y < 0) return false;
  return (j == 0 || cross(boundary((2 * j - 1) << shift), v) >= 0) && cross(boundary((2 * j + 1) << shift), v) < 0;
}

// A direction u (normal frame, outward) in the chart: azimuth cell, aligned (xa, y), polar cell.
struct Chart {
  AzCell az;
  std::int64_t phi = 0, cell = 0;
  i64 xa = 0, y = 0, uz = 0;
};

// The chart of u, or the refusal (out_of_domain, not_approaching).
// The pole (u along the normal, u_xy = 0) is azimuth cell 0 at xa = y = 0 (row(0, 0) = {0}).
Refusal chart_of(const Vec3& u, int shift, Chart& ch) {
  if (u[0] == 0 && u[1] == 0) {
    ch.phi = 0;
    ch.az = az_cell(0);
    ch.xa = ch.y = 0;
  } else {
    ch.phi = coarse_cell(u[0], u[1], kPhiShift, ch.az.b0, ch.az.b1);  // dir_cell(u) >> kPhiShift
    ch.az.phi = ch.phi;
    ch.az.c = az_centre(ch.phi);
    const IVec al = rotate_inv({u[0], u[1]}, ch.az.c);
    ch.xa = al.x;
    ch.y = al.y;
  }
  ch.uz = u[2];
  if (ch.uz <= 0) return Refusal::not_approaching;
  if (ch.xa < 0) return Refusal::out_of_domain;
  ch.cell = polar_cell(ch.uz, ch.xa, shift);  // in [0, quarter]: 0 <= angle < pi/2
  return Refusal::none;
}

}  // namespace

int LatticePair3D::face_of(const Vec3& p) {
  const i64 ax = iabs(p[0]), ay = iabs(p[1]), az = iabs(p[2]);
  int axis;
  if (az >= ax && az >= ay) axis = 2;
  else if (ay >= ax) axis = 1;
  else axis = 0;
  return 2 * axis + (p[static_cast<std::size_t>(axis)] < 0 ? 1 : 0);
}

Vec3 LatticePair3D::to_face(const Vec3& v, int f) {
  Vec3 r;
  switch (f >> 1) {
    case 0: r = {v[1], v[2], v[0]}; break;
    case 1: r = {v[2], v[0], v[1]}; break;
    default: r = v;
  }
  if (f & 1) r = {r[0], -r[1], -r[2]};  // a half turn about the frame's first axis
  return r;
}

Vec3 LatticePair3D::from_face(const Vec3& v, int f) {
  const Vec3 r = (f & 1) ? Vec3{v[0], -v[1], -v[2]} : v;
  switch (f >> 1) {
    case 0: return {r[2], r[0], r[1]};
    case 1: return {r[1], r[2], r[0]};
    default: return r;
  }
}

std::optional<std::array<i64, 2>> LatticePair3D::row(std::int64_t phi, i64 xa) { return row_of(az_cell(phi), xa); }

i64 LatticePair3D::zmin_of(int face, i64 xc, i64 yc) {
  const int axis = face >> 1;  // strict ties where the frame axis has priority (z > y > x)
  const int sx = axis == 2 ? 0 : 1, sy = axis == 0 ? 1 : 0;
  return std::max({i64{1}, iabs(xc) + sx, iabs(yc) + sy});
}

std::optional<i64> LatticePair3D::lo_pre(i128 sigma2, i64 xc, i64 yc, i64 zmin, i64 zin, const Vec3& W) {
  i128 lo = zmin;
  const i128 d = sigma2 - sq(xc - W[0]) - sq(yc - W[1]);
  if (d > 0) {
    const i128 z = isqrt_ceil(static_cast<u128>(d));
    if (W[2] - z >= zmin) return std::nullopt;  // points below the sphere too
    lo = std::max(lo, W[2] + z);
  }
  return static_cast<i64>(std::min<i128>(lo, static_cast<i128>(zin) + 1));
}

namespace {

std::optional<std::array<i64, 2>> row_of(const AzCell& az, i64 xa) {
  if (xa < 0 || xa >= kMaxComp) return std::nullopt;
  if (xa == 0) return az.phi == 0 ? std::optional<std::array<i64, 2>>{{0, 0}} : std::nullopt;  // the pole
  auto member = [&](i64 y) { return az.holds(rotate({xa, y}, az.c)); };
  constexpr int kSteps = 16;  // the lifting moves a point by about a unit: a guess is this close
  // The member farthest in direction dir from the guess `start`: outward while members. A guess
  // off the row is beyond the edge (the first member inward is the edge) or, for a short row
  // sitting off centre, before it (the first member outward, then on outward).
  auto edge = [&](i64 start, i64 dir) -> std::optional<i64> {
    i64 y = start;
    if (!member(y)) {
      for (int n = 1; n <= kSteps; ++n)
        if (member(start - n * dir)) return start - n * dir;
      int n = 1;
      while (!member(start + n * dir))
        if (++n > kSteps) return std::nullopt;
      y = start + n * dir;
    }
    while (member(y + dir)) y += dir;
    return y;
  };
  const i64 est = static_cast<i64>(std::floor(static_cast<double>(xa) * kTanHalfPhi));
  const auto hi = edge(est, 1);
  if (!hi) return std::nullopt;
  const auto lo = edge(-est, -1);
  if (!lo || *lo > *hi) return std::nullopt;
  return std::array<i64, 2>{*lo, *hi};
}

}  // namespace

LatticePair3D::LatticePair3D(std::int64_t sigma, Law law, int cell_bits)
    : sigma_(sigma), sigma2_(static_cast<i128>(sigma) * sigma), law_(law), shift_(kCellBits - cell_bits) {
  require(sigma >= 2 && sigma <= (1LL << 60), "LatticePair3D: sigma must be in [2, 2^60] lattice units");
  require(cell_bits >= min_cell_bits && cell_bits <= max_cell_bits,
          "LatticePair3D: cell_bits must be in [12, 20] (2^cell_bits polar cells per turn)");
  quarter_ = std::int64_t{1} << (cell_bits - 2);
}

std::uint64_t LatticePair3D::cum(std::int64_t b) const {
  if (b <= 0) return 0;
  if (b > quarter_) return kThetaTotal;
  const std::uint64_t scale = kThetaTotal - static_cast<std::uint64_t>(quarter_ + 1);
  const std::int64_t h = (2 * b - 1) << shift_;  // cell b starts at (b - 1/2) cells
  u128 q;  // sin^2 (flux) or 1 - cos (uniform) of the boundary angle, 62-bit fixed point
  if (law_ == Law::flux) {
    const u128 y = static_cast<u128>(boundary_y(h));
    q = (y * y) >> kFixBits;
  } else {
    q = (static_cast<u128>(1) << kFixBits) - static_cast<u128>(boundary_x(h));
  }
  return static_cast<std::uint64_t>(b) + static_cast<std::uint64_t>((scale * q + (static_cast<u128>(1) << (kFixBits - 1))) >> kFixBits);
}

std::int64_t LatticePair3D::decode(std::uint64_t s, std::uint64_t& c, std::uint64_t& f) const {
  const double u = static_cast<double>(s) / static_cast<double>(kThetaTotal);
  // the guess: asin(sqrt(u)) (flux) or acos(1 - u) (uniform) as atan2 of the two legs
  const double th = law_ == Law::flux ? atan2_guess(std::sqrt(u), std::sqrt(1.0 - u))
                                      : atan2_guess(std::sqrt(std::max(0.0, u * (2.0 - u))), 1.0 - u);
  std::int64_t b = static_cast<std::int64_t>(th / (std::numbers::pi / 2) * static_cast<double>(quarter_) + 0.5);
  b = std::clamp<std::int64_t>(b, 0, quarter_);
  std::uint64_t lo = cum(b);
  while (lo > s) lo = cum(--b);  // cum(0) = 0 <= s stops it
  std::uint64_t hi = cum(b + 1);
  while (hi <= s) {  // cum(quarter + 1) = 2^30 > s stops it
    lo = hi;
    hi = cum(++b + 1);
  }
  c = lo;
  f = hi - lo;
  return b;
}

Refusal LatticePair3D::check_pre(const Vec3& q, const Vec3& w) const {
  require(small(q, kMaxComp) && small(w, kMaxComp), "LatticePair3D: |q|, |w| components must be below 2^61");
  const Vec3 p{q[0] + w[0], q[1] + w[1], q[2] + w[2]};
  require(norm2(q) >= sigma2_, "LatticePair3D::forward: q must be outside (|q|^2 >= sigma^2)");
  require(norm2(p) < sigma2_, "LatticePair3D::forward: q + w must be inside (|q+w|^2 < sigma^2)");
  if (p[0] == 0 && p[1] == 0 && p[2] == 0) return Refusal::out_of_domain;
  const Column col = make_column(p, sigma2_, sigma_);
  const Vec3 W = to_face(w, col.face);
  if (!lo_pre3(sigma2_, col, W)) return Refusal::out_of_domain;
  Chart ch;
  const Refusal r = chart_of(neg(to_normal(W, col)), shift_, ch);
  if (r != Refusal::none) return r;
  const auto rw = row_of(ch.az, ch.xa);
  if (!rw || ch.y < (*rw)[0] || ch.y > (*rw)[1]) return Refusal::out_of_domain;
  return Refusal::none;
}

Refusal LatticePair3D::forward(const Vec3& q, const Vec3& w, std::uint64_t g, const BitsBack& X, Vec3& q2,
                               Vec3& w2, BitsBack& X_out, Trace3* trace) const {
  require(g < BitsBack::rans_total, "LatticePair3D::forward: g must be below 2^48");
  require(&X != &X_out, "LatticePair3D::forward: X_out must not be X");
  require(small(q, kMaxComp) && small(w, kMaxComp), "LatticePair3D: |q|, |w| components must be below 2^61");
  const Vec3 p{q[0] + w[0], q[1] + w[1], q[2] + w[2]};
  require(norm2(q) >= sigma2_, "LatticePair3D::forward: q must be outside (|q|^2 >= sigma^2)");
  require(norm2(p) < sigma2_, "LatticePair3D::forward: q + w must be inside (|q+w|^2 < sigma^2)");
  Trace3 tr;
  auto refuse = [&](Refusal r) {
    X_out = X;
    if (trace) *trace = tr;
    return r;
  };
  if (p[0] == 0 && p[1] == 0 && p[2] == 0) return refuse(Refusal::out_of_domain);
  const Column col = make_column(p, sigma2_, sigma_);
  tr.face = col.face;
  const Vec3 W = to_face(w, col.face);
  // 2. pre phases
  const auto lo = lo_pre3(sigma2_, col, W);
  if (!lo) return refuse(Refusal::out_of_domain);
  tr.m = col.zin - *lo + 1;
  // 3-4. normal frame, pre chart, pre row
  Chart ch;
  const Refusal r0 = chart_of(neg(to_normal(W, col)), shift_, ch);
  if (r0 != Refusal::none) return refuse(r0);
  tr.phi = ch.phi;
  tr.a = ch.cell;
  const auto r = row_of(ch.az, ch.xa);
  if (!r || ch.y < (*r)[0] || ch.y > (*r)[1]) return refuse(Refusal::out_of_domain);
  const std::array<i64, 2> rw = *r;
  tr.row = rw[1] - rw[0] + 1;
  X_out = X;
  X_out.push_uniform(static_cast<std::uint64_t>(col.pz - *lo), static_cast<std::uint64_t>(tr.m));
  X_out.push_uniform(static_cast<std::uint64_t>(ch.y - rw[0]), static_cast<std::uint64_t>(tr.row));
  // 5-6. the joint symbol (Phi, a), the torus shift
  const std::uint64_t ca = cum(ch.cell);
  X_out.push_rans((static_cast<std::uint64_t>(ch.phi) << kTotBits) + ca, cum(ch.cell + 1) - ca);
  X_out.add_low48(g);
  // 7. post symbol, polar rotation, post row
  const std::uint64_t s = X_out.low48();
  std::uint64_t cb, fb;
  tr.phi2 = static_cast<std::int64_t>(s >> kTotBits);
  tr.b = decode(s & kThetaMask, cb, fb);
  X_out.pop_rans((static_cast<std::uint64_t>(tr.phi2) << kTotBits) + cb, fb);
  const IVec t2 = rotate({ch.uz, ch.xa}, rot_coef((tr.b - ch.cell) << shift_));
  if (!in_polar_cell(t2, tr.b, shift_)) return refuse(Refusal::cell_readback);
  const AzCell az2 = az_cell(tr.phi2);
  const auto r2 = row_of(az2, t2.y);
  if (!r2) return refuse(Refusal::empty_post);
  tr.row2 = (*r2)[1] - (*r2)[0] + 1;
  const i64 y2 = (*r2)[0] + static_cast<i64>(X_out.pop_uniform(static_cast<std::uint64_t>(tr.row2)));
  const IVec uxy = rotate({t2.y, y2}, az2.c);
  const bool pole = uxy.x == 0 && uxy.y == 0;  // read back as azimuth cell 0
  if (pole ? tr.phi2 != 0 : !az2.holds(uxy)) return refuse(Refusal::cell_readback);
  const Vec3 W2 = from_normal({uxy.x, uxy.y, t2.x}, col);
  if (!small(W2, kMaxComp)) return refuse(Refusal::out_of_domain);
  // 8. post phase
  const auto lo2 = lo_post3(sigma2_, col, W2);
  if (!lo2) return refuse(Refusal::out_of_domain);
  tr.m2 = col.zin - *lo2 + 1;
  if (tr.m2 <= 0) return refuse(Refusal::empty_post);
  const i64 z2 = *lo2 + static_cast<i64>(X_out.pop_uniform(static_cast<std::uint64_t>(tr.m2)));
  const Vec3 qf{col.xc + W2[0], col.yc + W2[1], z2 + W2[2]};
  if (!small(qf, kMaxComp)) return refuse(Refusal::out_of_domain);
  q2 = from_face(qf, col.face);
  w2 = from_face(W2, col.face);
  if (trace) *trace = tr;
  return Refusal::none;
}

void LatticePair3D::reverse(const Vec3& q2, const Vec3& w2, std::uint64_t g, BitsBack& X, Vec3& q, Vec3& w) const {
  require(g < BitsBack::rans_total, "LatticePair3D::reverse: g must be below 2^48");
  require(small(q2, kMaxComp) && small(w2, kMaxComp), "LatticePair3D: |q2|, |w2| components must be below 2^61");
  const Vec3 p{q2[0] - w2[0], q2[1] - w2[1], q2[2] - w2[2]};
  require(norm2(q2) >= sigma2_, "LatticePair3D::reverse: q2 must be outside (|q2|^2 >= sigma^2)");
  require(norm2(p) < sigma2_, "LatticePair3D::reverse: q2 - w2 must be inside (|q2-w2|^2 < sigma^2)");
  require(p[0] != 0 || p[1] != 0 || p[2] != 0, "LatticePair3D::reverse: q2 - w2 is the origin (no face)");
  const Column col = make_column(p, sigma2_, sigma_);
  const Vec3 W2 = to_face(w2, col.face);
  const auto lo2 = lo_post3(sigma2_, col, W2);
  require(lo2.has_value(), "LatticePair3D::reverse: post phases do not form an interval (not a forward's output)");
  const i64 m2 = col.zin - *lo2 + 1, idx2 = col.pz - *lo2;
  require(idx2 >= 0 && idx2 < m2, "LatticePair3D::reverse: post phase outside its interval");
  Chart ch;
  require(chart_of(to_normal(W2, col), shift_, ch) == Refusal::none,
          "LatticePair3D::reverse: w2 is not outgoing about the normal (not a forward's output)");
  const auto r2 = row_of(ch.az, ch.xa);
  require(r2 && ch.y >= (*r2)[0] && ch.y <= (*r2)[1], "LatticePair3D::reverse: post azimuth off its row");
  const std::array<i64, 2> rw2 = *r2;
  const std::uint64_t row2 = static_cast<std::uint64_t>(rw2[1] - rw2[0] + 1);
  const std::uint64_t cb = cum(ch.cell), fb = cum(ch.cell + 1) - cb;
  const std::uint64_t csym = (static_cast<std::uint64_t>(ch.phi) << kTotBits) + cb;
  X.push_uniform(static_cast<std::uint64_t>(idx2), static_cast<std::uint64_t>(m2));
  X.push_uniform(static_cast<std::uint64_t>(ch.y - rw2[0]), row2);
  X.push_rans(csym, fb);
  X.sub_low48(g);
  const std::uint64_t s = X.low48();
  std::uint64_t ca, fa;
  const std::int64_t phi = static_cast<std::int64_t>(s >> kTotBits);
  const std::int64_t a = decode(s & kThetaMask, ca, fa);
  const std::uint64_t casym = (static_cast<std::uint64_t>(phi) << kTotBits) + ca;
  X.pop_rans(casym, fa);
  auto fail = [&](std::uint64_t pushed_row, std::uint64_t row_len, const char* why) {
    if (row_len) X.push_uniform(pushed_row, row_len);
    X.push_rans(casym, fa);  // undo: X is left as it came in
    X.add_low48(g);
    X.pop_rans(csym, fb);
    X.pop_uniform(row2);
    X.pop_uniform(static_cast<std::uint64_t>(m2));
    require(false, why);
  };
  const IVec t = rotate_inv({ch.uz, ch.xa}, rot_coef((ch.cell - a) << shift_));
  if (t.x <= 0 || t.y < 0) fail(0, 0, "LatticePair3D::reverse: no pre state maps to this post state (not a forward's output)");
  const AzCell az = az_cell(phi);
  const auto r = row_of(az, t.y);
  if (!r) fail(0, 0, "LatticePair3D::reverse: the pre azimuth row is empty (not a forward's output)");
  const std::uint64_t row_len = static_cast<std::uint64_t>((*r)[1] - (*r)[0] + 1);
  const std::uint64_t row_idx = X.pop_uniform(row_len);
  const i64 y = (*r)[0] + static_cast<i64>(row_idx);
  const IVec uxy = rotate({t.y, y}, az.c);
  const Vec3 W = from_normal(neg(Vec3{uxy.x, uxy.y, t.x}), col);
  const auto lo = small(W, kMaxComp) ? lo_pre3(sigma2_, col, W) : std::nullopt;
  const i64 m = lo ? col.zin - *lo + 1 : 0;
  if (m <= 0) fail(row_idx, row_len, "LatticePair3D::reverse: no pre state maps to this post state (not a forward's output)");
  const i64 z = *lo + static_cast<i64>(X.pop_uniform(static_cast<std::uint64_t>(m)));
  q = from_face({col.xc - W[0], col.yc - W[1], z - W[2]}, col.face);
  w = from_face(W, col.face);
}

Refusal LatticePair3D::pair_forward(const Vec3& xi, const Vec3& xj, const Vec3& vi, const Vec3& vj, std::uint64_t g,
                                    const BitsBack& X, Vec3& xi2, Vec3& xj2, Vec3& vi2, Vec3& vj2, BitsBack& X_out,
                                    Trace3* trace) const {
  require(small(vi, kMaxVel) && small(vj, kMaxVel), "LatticePair3D::pair_forward: velocity components must be below 2^59");
  Vec3 r, c, d, s, r2, d2;
  for (std::size_t e = 0; e < 3; ++e) {
    r[e] = wsub(xi[e], xj[e]);
    c[e] = wadd(xj[e], r[e] >> 1);
    d[e] = vi[e] - vj[e];
    s[e] = vj[e] + (d[e] >> 1);
  }
  const Refusal why = forward(r, d, g, X, r2, d2, X_out, trace);
  if (why != Refusal::none) return why;
  Vec3 nvi, nvj;
  for (std::size_t e = 0; e < 3; ++e) {
    nvj[e] = s[e] - (d2[e] >> 1);
    nvi[e] = nvj[e] + d2[e];
  }
  if (!small(nvi, kMaxVel) || !small(nvj, kMaxVel)) {  // the reverse would refuse these velocities
    X_out = X;
    return Refusal::out_of_domain;
  }
  for (std::size_t e = 0; e < 3; ++e) {
    xj2[e] = wsub(wadd(c[e], s[e]), r2[e] >> 1);
    xi2[e] = wadd(xj2[e], r2[e]);
  }
  vi2 = nvi;
  vj2 = nvj;
  return Refusal::none;
}

void LatticePair3D::pair_reverse(const Vec3& xi2, const Vec3& xj2, const Vec3& vi2, const Vec3& vj2, std::uint64_t g,
                                 BitsBack& X, Vec3& xi, Vec3& xj, Vec3& vi, Vec3& vj) const {
  require(small(vi2, kMaxVel) && small(vj2, kMaxVel), "LatticePair3D::pair_reverse: velocity components must be below 2^59");
  Vec3 r2, c, d2, s, r, d;
  for (std::size_t e = 0; e < 3; ++e) {
    r2[e] = wsub(xi2[e], xj2[e]);
    d2[e] = vi2[e] - vj2[e];
    s[e] = vj2[e] + (d2[e] >> 1);
    c[e] = wsub(wadd(xj2[e], r2[e] >> 1), s[e]);
  }
  reverse(r2, d2, g, X, r, d);
  for (std::size_t e = 0; e < 3; ++e) {
    xj[e] = wsub(c[e], r[e] >> 1);
    xi[e] = wadd(xj[e], r[e]);
    vj[e] = s[e] - (d[e] >> 1);
    vi[e] = vj[e] + d[e];
  }
}

}  // namespace revcol::lattice
