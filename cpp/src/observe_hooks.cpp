// The observer's hooks other than the float engine's pair hook (observe.cpp): group
// collisions, wall reflections, the *_at hooks of engines whose events move centres (the
// lattice engine), the sync at a run's end and the collision record.
#include "revcol/engine/observe.hpp"

#include <cmath>

#include "observe_inline.hpp"
#include "revcol/error.hpp"

namespace revcol::engine {

void Observer::group(double t, int n, const int* ids, const double* x, const double* v) {
  reach(t);
  for (int u = 0; u < n; ++u) {  // the members closed first: in a field their velocities move on to t
    const int i = ids[u];
    close<3>(i, t);
    close_pairs(i, t);
    if (fax_ >= 0) [[unlikely]] field_terms(i, -1.0);
  }
  if (ns_ > 0) species_group_virial(n, ids, x, v);
  for (int u = 0; u < n; ++u) group_virial(ids[u], x + u * dim_, v + u * dim_);
  for (int u = 0; u < n; ++u) {
    set_velocity<0>(ids[u], v + u * dim_);
    if (fax_ >= 0) [[unlikely]] field_terms(ids[u], 1.0);
  }
  ++cur_.groups;
  cur_.parts += static_cast<std::uint64_t>(n);
}

// A group member i at x (image-consistent) going to velocity v: x . Delta p to the virial,
// x_a Delta p_b to the Helfand moment (their sums over members are the same for any image).
void Observer::group_virial(int i, const double* x, const double* v) {
  double dp[3];
  for (int k = 0; k < dim_; ++k) {
    dp[k] = mass_of(i) * (v[k] - seg_[i].v[k]);
    cur_.w += x[k] * dp[k];
  }
  helfand_add<0>(x, dp);
}

// A group's virial by species (before its velocities change): member u's (x_u - c) . Delta p_u
// to its species, c the members' centroid. Their sum is the group's virial (sum Delta p_u = 0),
// and each share, unlike x_u . Delta p_u, does not depend on where the origin or the image is
// (for two members it is the pair's half and half).
void Observer::species_group_virial(int n, const int* ids, const double* x, const double* v) {
  double c[3] = {0.0, 0.0, 0.0};
  for (int u = 0; u < n; ++u)
    for (int k = 0; k < dim_; ++k) c[k] += x[u * dim_ + k];
  for (int k = 0; k < dim_; ++k) c[k] /= n;
  for (int u = 0; u < n; ++u) {
    const int i = ids[u];
    double share = 0.0;
    for (int k = 0; k < dim_; ++k) share += (x[u * dim_ + k] - c[k]) * (mass_of(i) * (v[u * dim_ + k] - seg_[i].v[k]));
    cur_.sp[2 * static_cast<std::size_t>(label_[i]) + 1] += share;
  }
}

void Observer::wall(double t, int i, const double* v) {
  reach(t);
  close<3>(i, t);
  close_pairs(i, t);
  if (fax_ >= 0) [[unlikely]] field_terms(i, -1.0);
  const double r = radius_of(i), tol = 1e-6 * diameter_;
  for (int k = 0; k < dim_; ++k) {
    const double dv = mass_of(i) * (v[k] - seg_[i].v[k]), xk = seg_[i].x[k];  // Delta p
    if (!walls_[k] || dv == 0.0) continue;
    if (std::fabs(xk - r) > tol && std::fabs(xk - (box_[k] - r)) > tol) continue;  // a tangential flip (v -> -v)
    cur_.wall_dp[k] += std::fabs(dv);
    cur_.w_wall += xk * dv;
  }
  set_velocity<0>(i, v);
  if (fax_ >= 0) [[unlikely]] field_terms(i, 1.0);
  ++cur_.walls;
}

// The *_at hooks (engines whose events move centres, the lattice engine): i's segment,
// closed at the event, moves to the position x the engine gives, by the nearest image of
// the difference on periodic axes (its position stays unwrapped), and takes the slab cell
// of its new position.
void Observer::place(int i, const double* x) {
  Segment& s = seg_[i];
  for (int k = 0; k < dim_; ++k) {
    double d = x[k] - s.x[k];
    if (!walls_[k]) d -= box_[k] * std::nearbyint(d * inv_box_[k]);
    s.x[k] += d;
  }
  if (cfg_.slabs > 0) set_cell(s, std::floor(s.x[cfg_.slab_axis] / slab_w_));
}

void Observer::pair_at(double t, int a, int b, const double* xa, const double* xb, const double* va,
                       const double* vb) {
  if (gamma_ != 0.0) [[unlikely]] return pair_sheared(t, a, b, xa, xb, va, vb);
  reach(t);
  close<3>(a, t);
  close<3>(b, t);
  close_pairs(a, t);
  close_pairs(b, t);
  if (fax_ >= 0) [[unlikely]] {  // a field's running sums: the pair's terms out, in after (observe_field.cpp)
    field_terms(a, -1.0);
    field_terms(b, -1.0);
  }
  double w = 0.0, r[3], dp[3];
  for (int k = 0; k < dim_; ++k) {
    r[k] = xa[k] - xb[k];
    if (!walls_[k]) r[k] -= box_[k] * std::nearbyint(r[k] * inv_box_[k]);  // the nearest image
    dp[k] = mass_of(a) * (va[k] - seg_[a].v[k]);
    w += r[k] * dp[k];
  }
  cur_.w += w;
  if (ns_ > 0) species_pair_virial(a, b, w);
  helfand_add<0>(r, dp);
  place(a, xa);
  place(b, xb);
  if (cfg_.collision_record) [[unlikely]] record_pair(a, b, va, vb);
  set_velocity<0>(a, va);
  set_velocity<0>(b, vb);
  if (fax_ >= 0) [[unlikely]] {
    field_terms(a, 1.0);
    field_terms(b, 1.0);
  }
  ++cur_.pairs;
  cur_.parts += 2;
}

void Observer::group_at(double t, int n, const int* ids, const double* x, const double* v) {
  if (gamma_ != 0.0) [[unlikely]] return group_sheared(t, n, ids, x, v);
  reach(t);
  if (ns_ > 0) species_group_virial(n, ids, x, v);
  for (int u = 0; u < n; ++u) {
    const int i = ids[u];
    close<3>(i, t);
    close_pairs(i, t);
    if (fax_ >= 0) [[unlikely]] field_terms(i, -1.0);
    group_virial(i, x + u * dim_, v + u * dim_);
  }
  for (int u = 0; u < n; ++u) {
    place(ids[u], x + u * dim_);
    set_velocity<0>(ids[u], v + u * dim_);
    if (fax_ >= 0) [[unlikely]] field_terms(ids[u], 1.0);
  }
  ++cur_.groups;
  cur_.parts += static_cast<std::uint64_t>(n);
}

void Observer::wall_at(double t, int i, const double* x, const double* v, unsigned axes) {
  if (gamma_ != 0.0) [[unlikely]] return wall_sheared(t, i, x, v, axes);
  reach(t);
  close<3>(i, t);
  close_pairs(i, t);
  if (fax_ >= 0) [[unlikely]] field_terms(i, -1.0);
  const double r = radius_of(i);
  for (int k = 0; k < dim_; ++k) {
    if (!(axes >> k & 1u) || !walls_[k]) continue;
    const double dv = mass_of(i) * (v[k] - seg_[i].v[k]);  // Delta p
    cur_.wall_dp[k] += std::fabs(dv);
    cur_.w_wall += (v[k] > 0.0 ? r : box_[k] - r) * dv;  // the contact plane it left from
  }
  place(i, x);
  set_velocity<0>(i, v);
  if (fax_ >= 0) [[unlikely]] field_terms(i, 1.0);
  ++cur_.walls;
}

void Observer::sync(double t) {
  reach(t);
  for (std::size_t i = 0; i < n_; ++i) {
    close<3>(static_cast<int>(i), t);
    close_pairs(static_cast<int>(i), t);
  }
}

// The collision record's entry of a pair at the positions just closed (header comment).
void Observer::record_pair(int a, int b, const double* va, const double* vb) {
  double r[3] = {0.0, 0.0, 0.0}, rr = 0.0;
  for (int k = 0; k < dim_; ++k) {
    r[k] = seg_[a].x[k] - seg_[b].x[k];
    if (!walls_[k]) r[k] -= box_[k] * std::nearbyint(r[k] * inv_box_[k]);  // the nearest image
    rr += r[k] * r[k];
  }
  const double inv = 1.0 / std::sqrt(rr);
  for (int k = 0; k < dim_; ++k) record_.push_back(r[k] * inv);
  for (int k = 0; k < dim_; ++k) record_.push_back(va[k] - vb[k]);
}

}  // namespace revcol::engine
