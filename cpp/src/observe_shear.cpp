// The observer under Lees-Edwards shear (Observer::set_shear; the lattice engine's sheared gas,
// docs/shear.md "Observables").
//
// Frames. The engine gives each particle's position in the box and its velocity there, which
// jumps by -+ gamma L_1 along the flow when the particle crosses a gradient face. The observer
// holds every particle unwrapped in the sheared lattice of images instead: the image m boxes up
// the gradient of a box point x with velocity v is at x + m (delta(t), L_1) and moves at
// v + m gamma L_1 e_0, delta(t) = gamma L_1 t mod L_0. A free flight is then one straight line
// whatever faces it crosses (no event at a crossing), and each hook finds the image nearest the
// particle's own flight (place_sheared).
//
// Peculiar velocities. The imposed flow at height y is gamma (y - L_1 / 2) e_0; the peculiar
// velocity u = v - gamma (y - L_1 / 2) e_0 is the same in every image. Along a flight u_x falls
// at gamma v_y, so the sums of the kinetic terms over the particles are polynomials in the time
// between two events: with a0 = sum u^2, a1 = sum u_x v_y, a2 = sum v_y^2 (and b = sum u_x v_z,
// c = sum v_y v_z in 3D) at the last update, after h
//     sum u^2 = a0 - 2 gamma a1 h + gamma^2 a2 h^2,   sum u_x v_y = a1 - gamma a2 h,
// integrated exactly (accumulate_sheared) and moved on; an event takes its members' terms out
// at the instant (shear_terms) and puts the new ones in. The temperature, the pressure's
// kinetic part and the species' sums are the peculiar ones. The shear stress is the x momentum
// carried across planes of constant y: pyx_ integrates sum u_x u_y and adds each collision's
// r_y Delta p_x, so its increment over a block is V P_yx tau (kinetic plus collisional), and
// eta = -P_yx / gamma. It is what the boundary's work measures: over free flight the peculiar
// energy falls at gamma sum u_x v_y, and a collision, which keeps the energy in the frame of
// its pair, changes the peculiar one by -gamma (y_a - y_b) Delta p_a,x; so the peculiar energy
// changes by exactly -gamma V P_yx dt. (The Helfand moment keeps r_x Delta p_y, a < b: a
// randomized law's impulse is not central, so only the specular gas's stress is symmetric.) A segment's peculiar speed |u(h)| is the root of a quadratic: the speed
// histogram takes the exact time below each bin edge (time_below) and the distance flown the
// exact integral (quadratic_distance) when the segment closes.
//
// Slabs (along the gradient axis only): a stretch of a flight in unwrapped cell c is in the
// image floor(c / slabs) boxes up, where its velocity in the box is v - floor(c / slabs) gamma
// L_1 e_0: each slab keeps its time, its box-frame v^2 and v_x times time, so the velocity
// profile is exact and the slab temperature is the box-frame one less the slab's mean flow,
// (<v^2> - <v_x>^2) / d (which keeps the flow's spread inside the slab, gamma^2 w^2 / (12 d)).
#include <algorithm>
#include <cmath>
#include <string>

#include "observe_inline.hpp"
#include "revcol/engine/observe.hpp"
#include "revcol/error.hpp"

namespace revcol::engine {

double Observer::offset(double t) const {
  const double d = std::fmod(image_speed_ * t, box_[0]);
  return d < 0.0 ? d + box_[0] : d;
}

// r (a difference of two points) to the nearest image through the moving images: n (a whole
// number) is how many boxes up the gradient the image taken lies from the second point.
void Observer::fold_sheared(double* r, double t, double& n) const {
  n = std::nearbyint(r[1] * inv_box_[1]);
  r[1] -= n * box_[1];
  r[0] -= n * offset(t);
  r[0] -= box_[0] * std::nearbyint(r[0] * inv_box_[0]);
  if (dim_ == 3 && !walls_[2]) r[2] -= box_[2] * std::nearbyint(r[2] * inv_box_[2]);
}

// i's segment (closed at t) moves to the image of the box point x nearest its own flight; the
// image's index m (its velocity there is the box's plus m gamma L_1 e_0).
int Observer::place_sheared(int i, const double* x, double t) {
  Segment& s = seg_[i];
  const double m = std::nearbyint((s.x[1] - x[1]) * inv_box_[1]);
  double d0 = x[0] + m * offset(t) - s.x[0];
  d0 -= box_[0] * std::nearbyint(d0 * inv_box_[0]);
  s.x[0] += d0;
  s.x[1] = x[1] + m * box_[1];
  if (dim_ == 3) {
    double d2 = x[2] - s.x[2];
    if (!walls_[2]) d2 -= box_[2] * std::nearbyint(d2 * inv_box_[2]);
    s.x[2] += d2;
  }
  if (cfg_.slabs > 0) set_cell(s, std::floor(s.x[1] / slab_w_));
  return static_cast<int>(m);
}

// i's terms of the running sums at t_now_ (its segment closed there) in (sign 1) or out (-1).
void Observer::shear_terms(int i, double sign) {
  const Segment& s = seg_[i];
  const double ux = s.v[0] - gamma_ * (s.x[1] - yref_), vy = s.v[1], vz = s.v[2];
  const ShearSums d{ux * ux + vy * vy + vz * vz, ux * vy, vy * vy, ux * vz, vy * vz};
  auto add = [&](ShearSums& q) {
    q.a0 += sign * d.a0;
    q.a1 += sign * d.a1;
    q.a2 += sign * d.a2;
    q.b += sign * d.b;
    q.c += sign * d.c;
  };
  add(shs_);
  if (ns_ > 0) add(shs_sp_[static_cast<std::size_t>(label_[i])]);
}

// The sums' integrals over the next dt (to the open block and the Helfand moment), then the
// sums at its end.
void Observer::accumulate_sheared(double h) {
  const double g = gamma_;
  auto step = [&](ShearSums& q, double& k2) {
    k2 += h * (q.a0 - g * h * (q.a1 - g * h * q.a2 / 3.0));  // a0 h - g a1 h^2 + g^2 a2 h^3 / 3
    q.a0 += g * h * (g * h * q.a2 - 2.0 * q.a1);
  };
  const double kin = h * (shs_.a1 - 0.5 * g * h * shs_.a2);  // integral of sum u_x v_y
  helf_[0] += kin;
  pyx_ += kin;
  helf_[1] += h * (shs_.b - 0.5 * g * h * shs_.c);
  helf_[2] += h * shs_.c;
  step(shs_, cur_.k2);
  shs_.a1 -= g * h * shs_.a2;
  shs_.b -= g * h * shs_.c;
  for (int u = 0; u < ns_; ++u) {
    ShearSums& q = shs_sp_[static_cast<std::size_t>(u)];
    step(q, cur_.sp[2 * static_cast<std::size_t>(u)]);
    q.a1 -= g * h * q.a2;
    q.b -= g * h * q.c;
  }
}

// close() under shear: the segment's peculiar speeds to the histogram and the distance, its
// stretches to the slabs, its position on to t.
void Observer::close_sheared(int i, double t) {
  Segment& s = seg_[i];
  const double dt = t - s.t0;
  if (dt > 0.0) {
    const double ux0 = s.v[0] - gamma_ * (s.x[1] - yref_), g = gamma_ * s.v[1];
    const double p2 = s.v[1] * s.v[1] + s.v[2] * s.v[2];
    cur_.dist += quadratic_distance(ux0, g, p2, dt);
    if (cfg_.speed_bins > 0) speed_sheared(ux0, g, p2, dt);
    if (cfg_.slabs > 0) slab_sheared(s, t, dt);
  }
  fly<3>(s, t, dt);
}

// The time |u(h)| spends in each speed bin over [0, span], |u|^2 = (ux0 - g h)^2 + p2; speeds
// from speed_max up to the overflow bin.
void Observer::speed_sheared(double ux0, double g, double p2, double span) {
  const double a = g * g, b = -g * ux0, c = ux0 * ux0 + p2, end = (ux0 - g * span) * (ux0 - g * span) + p2;
  double lo2 = std::min(c, end);
  if (a > 0.0 && ux0 / g > 0.0 && ux0 / g < span) lo2 = p2;  // the least speed inside
  const double hi2 = std::max(c, end), h = speed_max_ / cfg_.speed_bins;
  const int nb = cfg_.speed_bins;
  const int k0 = std::min(nb, static_cast<int>(std::sqrt(lo2) / h)), k1 = std::min(nb, static_cast<int>(std::sqrt(hi2) / h));
  double below = k0 > 0 ? time_below(a, b, c, (k0 * h) * (k0 * h), span) : 0.0;
  for (int k = k0; k <= k1; ++k) {
    const double up = k < nb && k < k1 ? time_below(a, b, c, ((k + 1) * h) * ((k + 1) * h), span) : span;
    cur_.speed[static_cast<std::size_t>(k)] += up - below;
    below = up;
  }
}

// The stretches of s's flight over [t0, t] to the slabs along the gradient: each with its time,
// its box-frame v^2 and v_x (the image it is in: floor(cell / slabs) boxes up).
void Observer::slab_sheared(Segment& s, double t, double dt) {
  const int ns = cfg_.slabs;
  double cell = std::nearbyint(s.lo / slab_w_);
  auto credit = [&](double span) {
    const double m = std::floor(cell / ns), vx = s.v[0] - m * image_speed_;
    const auto sl = static_cast<std::size_t>(cell - m * ns);
    cur_.slab[2 * sl] += span;
    cur_.slab[2 * sl + 1] += (vx * vx + s.v[1] * s.v[1] + s.v[2] * s.v[2]) * span;
    cur_.slab_vx[sl] += vx * span;
  };
  const double vy = s.v[1], end = s.x[1] + vy * dt;
  if (in_cell(s, end)) return credit(dt);
  const double step = slab_w_ / std::fabs(vy);
  double from = s.t0, edge = s.t0 + ((vy > 0.0 ? s.lo + slab_w_ : s.lo) - s.x[1]) / vy;
  while (true) {
    const double until = std::min(t, std::max(from, edge));
    credit(until - from);
    from = until;
    if (!(t > edge)) break;
    cell += vy > 0.0 ? 1.0 : -1.0;
    edge += step;
  }
  set_cell(s, std::floor(end / slab_w_));
}

void Observer::pair_sheared(double t, int a, int b, const double* xa, const double* xb, const double* va,
                            const double* vb) {
  reach(t);
  close_sheared(a, t);
  close_sheared(b, t);
  shear_terms(a, -1.0);
  shear_terms(b, -1.0);
  double r[3] = {0.0, 0.0, 0.0}, n = 0.0;
  for (int k = 0; k < dim_; ++k) r[k] = xa[k] - xb[k];
  fold_sheared(r, t, n);  // a less the image of b nearest it (n boxes up from b)
  double ua[3] = {0.0, 0.0, 0.0}, ub[3] = {0.0, 0.0, 0.0};  // the velocities in the images the segments are in
  const int ma = place_sheared(a, xa, t), mb = place_sheared(b, xb, t);
  for (int k = 0; k < dim_; ++k) {
    ua[k] = va[k] + (k == 0 ? ma * image_speed_ : 0.0);
    ub[k] = vb[k] + (k == 0 ? mb * image_speed_ : 0.0);
  }
  double w = 0.0, dp[3];
  for (int k = 0; k < dim_; ++k) {
    dp[k] = ua[k] - seg_[a].v[k];  // (the same in every image; masses are 1 under shear)
    w += r[k] * dp[k];
  }
  cur_.w += w;
  if (ns_ > 0) species_pair_virial(a, b, w);
  helfand_add<0>(r, dp);
  pyx_ += r[1] * dp[0];  // the flux of x momentum across y
  if (cfg_.collision_record) [[unlikely]] {  // the normal, and w = v_a less the velocity of b's image
    double rr = 0.0;
    for (int k = 0; k < dim_; ++k) rr += r[k] * r[k];
    const double inv = 1.0 / std::sqrt(rr);
    for (int k = 0; k < dim_; ++k) record_.push_back(r[k] * inv);
    for (int k = 0; k < dim_; ++k) record_.push_back(va[k] - vb[k] - (k == 0 ? n * image_speed_ : 0.0));
  }
  set_velocity<0>(a, ua);
  set_velocity<0>(b, ub);
  shear_terms(a, 1.0);
  shear_terms(b, 1.0);
  ++cur_.pairs;
  cur_.parts += 2;
}

// x: each member's own position (its velocity's frame); the virial's positions are taken
// image-consistent about the first member here.
void Observer::group_sheared(double t, int n, const int* ids, const double* x, const double* v) {
  reach(t);
  const auto d = static_cast<std::size_t>(dim_), nn = static_cast<std::size_t>(n);
  std::vector<double> xc(nn * d), vu(nn * d);
  for (std::size_t u = 0; u < nn; ++u) {
    close_sheared(ids[u], t);
    shear_terms(ids[u], -1.0);
    double r[3] = {0.0, 0.0, 0.0}, img = 0.0;
    for (std::size_t k = 0; k < d; ++k) r[k] = x[u * d + k] - x[k];
    if (u > 0) fold_sheared(r, t, img);
    for (std::size_t k = 0; k < d; ++k) xc[u * d + k] = x[k] + r[k];
    const int m = place_sheared(ids[u], x + u * d, t);
    for (std::size_t k = 0; k < d; ++k) vu[u * d + k] = v[u * d + k] + (k == 0 ? m * image_speed_ : 0.0);
  }
  if (ns_ > 0) species_group_virial(n, ids, xc.data(), vu.data());
  for (std::size_t u = 0; u < nn; ++u) {
    pyx_ += xc[u * d + 1] * (vu[u * d] - seg_[ids[u]].v[0]);  // the flux of x momentum across y
    group_virial(ids[u], xc.data() + u * d, vu.data() + u * d);
  }
  for (std::size_t u = 0; u < nn; ++u) {
    set_velocity<0>(ids[u], vu.data() + u * d);
    shear_terms(ids[u], 1.0);
  }
  ++cur_.groups;
  cur_.parts += nn;
}

// Walls lie across axis 2 only (axes 0 and 1 are periodic under shear).
void Observer::wall_sheared(double t, int i, const double* x, const double* v, unsigned axes) {
  reach(t);
  close_sheared(i, t);
  shear_terms(i, -1.0);
  const double r = radius_of(i);
  if (dim_ == 3 && (axes >> 2 & 1u) && walls_[2]) {
    const double dv = v[2] - seg_[i].v[2];
    cur_.wall_dp[2] += std::fabs(dv);
    cur_.w_wall += (v[2] > 0.0 ? r : box_[2] - r) * dv;
  }
  const int m = place_sheared(i, x, t);
  double vu[3] = {0.0, 0.0, 0.0};
  for (int k = 0; k < dim_; ++k) vu[k] = v[k] + (k == 0 ? m * image_speed_ : 0.0);
  set_velocity<0>(i, vu);
  shear_terms(i, 1.0);
  ++cur_.walls;
}

void Observer::set_shear(double rate) {
  require(std::isfinite(rate) && rate != 0.0, [&] { return "observe: the shear rate must be finite and nonzero, got " + num(rate); });
  require(dim_ >= 2 && !walls_[0] && !walls_[1], "observe: shear needs periodic axes 0 (the flow) and 1 (the gradient)");
  require(mass_.empty(), "observe: shear with unequal masses is not built");
  require(cfg_.slabs == 0 || cfg_.slab_axis == 1,
          "observe: under shear the slabs lie along the gradient (slab_axis 1): the velocity profile's axis");
  require(fax_ < 0, "observe: shear with a field is not built");
  gamma_ = rate;
  curved_ = true;
  image_speed_ = rate * box_[1];
  yref_ = 0.5 * box_[1];
  shs_sp_.assign(static_cast<std::size_t>(ns_), ShearSums{});
  const auto slabs = static_cast<std::size_t>(cfg_.slabs);
  if (!resumed_) {
    require(blocks_.empty() && cur_.pairs == 0 && cur_.groups == 0 && cur_.walls == 0,
            "observe: set_shear must come before the first event");
    for (std::size_t i = 0; i < n_; ++i) {
      if (!start_v_.empty()) start_v_[i * static_cast<std::size_t>(dim_)] -= gamma_ * (seg_[i].x[1] - yref_);
      shear_terms(static_cast<int>(i), 1.0);
    }
    cur_.slab_vx.assign(slabs, 0.0);
    pyx_open_ = pyx_;
    return;
  }
  // a resumed observation: the section save_shear wrote (the loader checked its size)
  const std::vector<double>& q = shear_saved_;
  require(!q.empty(), "snapshot: observer: it was taken of a gas that was not sheared");
  require(q[1] == rate, [&] { return "snapshot: observer: it was taken at shear rate " + num(q[1]) + ", not " + num(rate); });
  std::size_t u = 2;
  auto sums = [&](ShearSums& z) {
    z = ShearSums{q[u], q[u + 1], q[u + 2], q[u + 3], q[u + 4]};
    u += 5;
  };
  sums(shs_);
  for (ShearSums& z : shs_sp_) sums(z);
  pyx_ = q[u++];
  pyx_open_ = q[u++];
  auto block = [&](Block& b) {
    b.pyx = q[u++];
    b.slab_vx.assign(q.begin() + static_cast<std::ptrdiff_t>(u), q.begin() + static_cast<std::ptrdiff_t>(u + slabs));
    u += slabs;
  };
  for (Block& b : blocks_) block(b);
  block(cur_);
  cur_.pyx = 0.0;
  shear_saved_.clear();
}

// The shear section of a snapshot (observe.hpp, save): -1 (its mark), the rate, the sums (5),
// each species' (5 each), pyx_, pyx_open_, and per block (the complete ones, then the open one)
// its pyx and slab_vx.
void Observer::save_shear(std::vector<double>& reals) const {
  reals.push_back(-1.0);
  reals.push_back(gamma_);
  auto sums = [&](const ShearSums& z) { reals.insert(reals.end(), {z.a0, z.a1, z.a2, z.b, z.c}); };
  sums(shs_);
  for (const ShearSums& z : shs_sp_) sums(z);
  reals.push_back(pyx_);
  reals.push_back(pyx_open_);
  for (const Block& b : blocks_) {
    reals.push_back(b.pyx);
    reals.insert(reals.end(), b.slab_vx.begin(), b.slab_vx.end());
  }
  reals.push_back(0.0);
  reals.insert(reals.end(), cur_.slab_vx.begin(), cur_.slab_vx.end());
}

}  // namespace revcol::engine
