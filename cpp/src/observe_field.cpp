// The observer in a uniform field (Observer::set_field; the lattice engine's gas under gravity,
// docs/engine.md "Gravity").
//
// Flights are parabolas: with acceleration g along the field's axis f, a segment started at t0
// is at x0 + v (t - t0) + g (t - t0)^2 / 2 e_f with velocity v + g (t - t0) e_f, which the lattice
// engine's lines are exactly between events (its ticks lie on them). Closing a segment moves its
// position and its velocity on to the instant; every event's velocity change is then taken from
// the velocity the segment has at that instant.
//
// Running sums. With a0 = sum v^2, m_k = sum v_k and vv_ab = sum v_a v_b (the Helfand moment's
// pairs) at the last update, after h: sum v^2 = a0 + 2 g m_f h + g^2 N h^2, m_f grows by g N h, and
// vv_ab by g h m_b when a = f (or m_a when b = f), so their integrals are polynomials in h
// (accumulate_field); an event takes its members' terms out at the instant (field_terms) and puts
// the new ones in. The temperature is then the time average of the kinetic energy the particles
// have (which the field exchanges with the potential), the Helfand moment integrates the true
// v_a v_b, and the species' sums likewise.
//
// A segment's speed |v(h)| is the root of a quadratic: the speed histogram takes the exact time
// below each bin edge, the distance the exact integral (quadratic_distance and speed_sheared, the
// same quadratic as shear's). Slabs along the field's axis: the flight is split at its turning point into
// monotone pieces and each cell crossing solved from the quadratic; along another axis the motion
// is a line. Each stretch gets its time and the exact integral of v^2 over it.
#include <algorithm>
#include <cmath>
#include <string>

#include "observe_inline.hpp"
#include "revcol/engine/observe.hpp"
#include "revcol/error.hpp"

namespace revcol::engine {

// i's terms of the running sums at t_now_ (its segment closed there) in (sign 1) or out (-1).
void Observer::field_terms(int i, double sign) {
  const Segment& s = seg_[i];
  const double w = sign * mass_of(i);  // (1 x: the same bits for unit masses)
  double v2 = 0.0;
  for (int k = 0; k < 3; ++k) {
    v2 += s.v[k] * s.v[k];
    fs_.m[k] += w * s.v[k];
  }
  fs_.a0 += w * v2;
  fs_.vv[0] += w * s.v[0] * s.v[1];
  fs_.vv[1] += w * s.v[0] * s.v[2];
  fs_.vv[2] += w * s.v[1] * s.v[2];
  if (ns_ > 0) {
    double* q = &fsp_[2 * static_cast<std::size_t>(label_[i])];
    q[0] += w * v2;
    q[1] += w * s.v[fax_];
  }
}

void Observer::accumulate_field(double h) {
  const double g = g_, N = fs_.total;  // sum m
  const int f = fax_;
  // sum v^2: a0 + 2 g m_f h' + g^2 N h'^2 over [0, h]
  cur_.k2 += h * (fs_.a0 + g * h * (fs_.m[f] + g * N * h / 3.0));
  constexpr int A[3] = {0, 0, 1}, B[3] = {1, 2, 2};
  for (int c = 0; c < 3; ++c) {  // sum v_a v_b grows at g m_b (a = f) or g m_a (b = f)
    const double rate = A[c] == f ? g * fs_.m[B[c]] : B[c] == f ? g * fs_.m[A[c]] : 0.0;
    helf_[c] += h * (fs_.vv[c] + 0.5 * rate * h);
    fs_.vv[c] += rate * h;
  }
  for (int u = 0; u < ns_; ++u) {
    double* q = &fsp_[2 * static_cast<std::size_t>(u)];
    const double Ns = fs_.species_mass[static_cast<std::size_t>(u)];
    cur_.sp[2 * static_cast<std::size_t>(u)] += h * (q[0] + g * h * (q[1] + g * Ns * h / 3.0));
    q[0] += g * h * (2.0 * q[1] + g * Ns * h);
    q[1] += g * Ns * h;
  }
  fs_.a0 += g * h * (2.0 * fs_.m[f] + g * N * h);
  fs_.m[f] += g * N * h;
}

// close() in a field: the segment's speeds to the histogram and the distance, its stretches to
// the slabs, its position and velocity on to t.
void Observer::close_field(int i, double t) {
  Segment& s = seg_[i];
  const double dt = t - s.t0;
  if (dt > 0.0) {
    const int f = fax_;
    double p2 = 0.0;  // the speed across the field (constant)
    for (int k = 0; k < 3; ++k)
      if (k != f) p2 += s.v[k] * s.v[k];
    cur_.dist += quadratic_distance(s.v[f], -g_, p2, dt);
    if (cfg_.speed_bins > 0) speed_sheared(s.v[f], -g_, p2, dt);
    if (cfg_.slabs > 0) slab_field(s, mass_of(i), dt);
  }
  for (int k = 0; k < 3; ++k) s.x[k] += s.v[k] * dt;
  s.x[fax_] += 0.5 * g_ * dt * dt;
  s.v[fax_] += g_ * dt;
  s.t0 = t;
  // the quantities set_velocity derives from the velocity, for the velocity now (a resumed
  // snapshot rebuilds them so: the same bits either way)
  const double v2 = s.v[0] * s.v[0] + s.v[1] * s.v[1] + s.v[2] * s.v[2];
  s.v2 = mass_of(i) * v2;  // m v^2, as set_velocity; the speed is |v|
  s.speed = root(v2);
  s.bin = static_cast<int>(std::min(s.speed * bin_scale_, bin_cap_));
}

// The stretches of s's flight (mass m) over [t0, t0 + dt] to the slabs: each cell it passes gets
// its time and the integral of m v^2 over it. z(h) = z0 + w h + a h^2 / 2 along the slab axis (a = g on the
// field's axis, else 0), split at its turning point into monotone pieces.
void Observer::slab_field(Segment& s, double m, double dt) {
  const int ax = cfg_.slab_axis, ns = cfg_.slabs, f = fax_;
  const double z0 = s.x[ax], w = s.v[ax], a = ax == f ? g_ : 0.0, W = slab_w_;
  const double v2 = s.v[0] * s.v[0] + s.v[1] * s.v[1] + s.v[2] * s.v[2], vf = s.v[f], g = g_;
  auto k2 = [&](double h) { return m * (h * (v2 + g * h * (vf + g * h / 3.0))); };  // integral of m v^2 over [0, h]
  auto z = [&](double h) { return z0 + h * (w + 0.5 * a * h); };
  double cell = std::nearbyint(s.lo / W);
  auto credit = [&](double h0, double h1) {
    if (!(h1 > h0)) return;
    double c = cell;
    if (walls_[ax]) c = std::min(static_cast<double>(ns - 1), std::max(0.0, c));
    const double m = std::fmod(c, static_cast<double>(ns));
    const auto sl = static_cast<std::size_t>(m < 0.0 ? m + ns : m);
    cur_.slab[2 * sl] += h1 - h0;
    cur_.slab[2 * sl + 1] += k2(h1) - k2(h0);
  };
  // the time in [from, to] at which z reaches `edge` on a monotone piece that crosses it: the
  // root nearest the piece (inside it but for round-off), clamped to it
  auto reach_edge = [&](double from, double to, double edge) {
    const double c0 = z0 - edge;
    double h = to;
    if (a == 0.0) {
      if (w != 0.0) h = -c0 / w;
    } else {  // a h^2 / 2 + w h + c0 = 0 (the stable form of the roots)
      const double disc = std::max(0.0, w * w - 2.0 * a * c0);
      const double q = -(w + std::copysign(std::sqrt(disc), w));
      const double r1 = q / a, r2 = q != 0.0 ? 2.0 * c0 / q : r1;
      auto off = [&](double r) { return std::max({from - r, r - to, 0.0}); };
      h = off(r2) < off(r1) ? r2 : r1;
    }
    return std::min(to, std::max(from, h));
  };
  const double turn = a != 0.0 ? -w / a : -1.0;
  const double pieces[3] = {0.0, turn > 0.0 && turn < dt ? turn : dt, dt};
  for (int p = 0; p < 2; ++p) {
    double from = pieces[p];
    const double to = pieces[p + 1];
    if (!(to > from)) continue;
    const double dir = z(to) >= z(from) ? 1.0 : -1.0;
    while (true) {
      const double edge = (dir > 0.0 ? cell + 1.0 : cell) * W;
      const bool crosses = dir > 0.0 ? z(to) >= edge : z(to) < edge;
      const double until = crosses ? reach_edge(from, to, edge) : to;
      credit(from, until);
      from = until;
      if (!crosses || !(to > from)) break;
      cell += dir;
    }
  }
  set_cell(s, std::floor(z(dt) / W));
}

void Observer::set_field(int axis, double g) {
  require(axis >= 0 && axis < dim_ && walls_[axis], "observe: a field lies along an axis with walls");
  require(std::isfinite(g) && g != 0.0, [&] { return "observe: the field must be finite and nonzero, got " + num(g); });
  require(gamma_ == 0.0, "observe: shear with a field is not built");
  fax_ = axis;
  g_ = g;
  curved_ = true;
  set_fast_until();  // the float engine's pair hook takes pair_general (the flights are parabolas)
  fsp_.assign(2 * static_cast<std::size_t>(ns_), 0.0);
  fs_.total = 0.0;
  fs_.species_mass.assign(static_cast<std::size_t>(ns_), 0.0);
  for (std::size_t i = 0; i < n_; ++i) {
    fs_.total += mass_of(static_cast<int>(i));
    if (ns_ > 0) fs_.species_mass[static_cast<std::size_t>(label_[i])] += mass_of(static_cast<int>(i));
  }
  if (!resumed_) {
    require(blocks_.empty() && cur_.pairs == 0 && cur_.groups == 0 && cur_.walls == 0,
            "observe: set_field must come before the first event");
    for (std::size_t i = 0; i < n_; ++i) field_terms(static_cast<int>(i), 1.0);
    return;
  }
  const std::vector<double>& q = field_saved_;
  require(!q.empty(), "snapshot: observer: it was taken of a gas without a field");
  require(q[1] == axis && q[2] == g, [&] {
    return "snapshot: observer: it was taken in a field of " + num(q[2]) + " along axis " + num(q[1]) + ", not " +
           num(g) + " along " + std::to_string(axis);
  });
  fs_.a0 = q[3];
  for (int k = 0; k < 3; ++k) {
    fs_.m[k] = q[4 + k];
    fs_.vv[k] = q[7 + k];
  }
  std::copy(q.begin() + 10, q.end(), fsp_.begin());
  field_saved_.clear();
}

// The field section of a snapshot (observe.hpp, save): -2 (its mark), the axis, g, a0, m (3),
// vv (3), and per species sum v^2 and sum v_f.
void Observer::save_field(std::vector<double>& reals) const {
  reals.insert(reals.end(), {-2.0, static_cast<double>(fax_), g_, fs_.a0});
  reals.insert(reals.end(), fs_.m.begin(), fs_.m.end());
  reals.insert(reals.end(), fs_.vv.begin(), fs_.vv.end());
  reals.insert(reals.end(), fsp_.begin(), fsp_.end());
}

}  // namespace revcol::engine
