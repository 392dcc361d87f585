// Neighbour lists of the lattice engine (lattice/neighbour_lists.hpp).
#include <algorithm>
#include <cmath>

#include "revcol/error.hpp"
#include "revcol/lattice/neighbour_lists.hpp"

namespace revcol::lattice {

template <std::size_t Dim>
void NeighbourListsN<Dim>::build(const UnitsN<Dim>& u, std::int64_t h, const std::vector<Vec>& centres) {
  require(h >= 1 && h <= u.sigma, "lattice neighbour lists: the ball radius must be in [1, sigma] lattice units");
  for (std::size_t k = 0; k < Dim; ++k) {
    L_[k] = u.L[k];
    wall_[k] = u.wall[k];
  }
  h_ = h;
  reach_ = u.sigma + 2 * h + 8 * u.vmax + 8;
  h2_ = static_cast<u128>(h) * static_cast<u128>(h);
  reach2_ = static_cast<double>(reach_) * static_cast<double>(reach_);
  const std::size_t n = centres.size();
  c_ = centres;
  grid_.build(u, n, (reach_ + 1) / 2, 2);  // 5^D cells of R/2: half the candidates of 3^D cells of R
  for (std::size_t p = 0; p < n; ++p) grid_.insert(static_cast<int>(p), grid_.cell_id(c_[p]));
  count_.assign(n, 0);
  ids_.assign(n * cap_, -1);
  dc_.assign(n * cap_ * Dim, 0.0);
  for (std::size_t p = 0; p < n; ++p) scan(static_cast<int>(p), false);
}

template <std::size_t Dim>
void NeighbourListsN<Dim>::scan(int p, bool both) {
  const Vec& c = c_[static_cast<std::size_t>(p)];
  // only the cells that reach within R of c (the rest could hold no entry: the same lists)
  grid_.for_neighbours_within(grid_.cell_of_particle(p), c, static_cast<double>(reach_), [&](int q) {
    if (q == p) return;
    const Vec& cq = c_[static_cast<std::size_t>(q)];
    double d[Dim], dd = 0.0;
    for (std::size_t k = 0; k < Dim; ++k) {
      d[k] = static_cast<double>(wall_[k] ? c[k] - cq[k] : min_image(c[k] - cq[k], L_[k]));
      dd += d[k] * d[k];
    }
    if (dd >= reach2_) return;
    add(p, q, d);
    if (both) {
      for (std::size_t k = 0; k < Dim; ++k) d[k] = -d[k];
      add(q, p, d);
    }
  });
}

template <std::size_t Dim>
void NeighbourListsN<Dim>::renew(int p, const Vec& c) {
  for_each(p, [&](int q) { drop(q, p); });
  count_[static_cast<std::size_t>(p)] = 0;
  c_[static_cast<std::size_t>(p)] = c;
  const int id = grid_.cell_id(c);
  if (grid_.cell_of_particle(p) != id) {
    grid_.remove(p);
    grid_.insert(p, id);
  }
  scan(p, true);
}

template <std::size_t Dim>
void NeighbourListsN<Dim>::add(int p, int q, const double* d) {
  if (static_cast<std::size_t>(count_[static_cast<std::size_t>(p)]) == cap_) grow();
  const std::size_t slot = static_cast<std::size_t>(p) * cap_ + static_cast<std::size_t>(count_[static_cast<std::size_t>(p)]++);
  ids_[slot] = q;
  std::copy_n(d, Dim, &dc_[slot * Dim]);
}

template <std::size_t Dim>
void NeighbourListsN<Dim>::drop(int p, int q) {
  const std::size_t base = static_cast<std::size_t>(p) * cap_;
  std::int32_t& n = count_[static_cast<std::size_t>(p)];
  for (std::int32_t k = 0; k < n; ++k)
    if (ids_[base + k] == q) {
      --n;
      ids_[base + k] = ids_[base + n];
      std::copy_n(&dc_[(base + n) * Dim], Dim, &dc_[(base + k) * Dim]);
      return;
    }
}

template <std::size_t Dim>
void NeighbourListsN<Dim>::grow() {
  const std::size_t cap = 2 * cap_;
  std::vector<int> wider(count_.size() * cap, -1);
  std::vector<double> wider_dc(count_.size() * cap * Dim, 0.0);
  for (std::size_t p = 0; p < count_.size(); ++p) {
    std::copy_n(&ids_[p * cap_], count_[p], &wider[p * cap]);
    std::copy_n(&dc_[p * cap_ * Dim], count_[p] * Dim, &wider_dc[p * cap * Dim]);
  }
  ids_.swap(wider);
  dc_.swap(wider_dc);
  cap_ = cap;
}

template <std::size_t Dim>
typename NeighbourListsN<Dim>::Vec NeighbourListsN<Dim>::diff(const Vec& a, const Vec& b) const noexcept {
  Vec r;
  for (std::size_t k = 0; k < Dim; ++k) r[k] = wall_[k] ? a[k] - b[k] : min_image(a[k] - b[k], L_[k]);
  return r;
}

template <std::size_t Dim>
bool NeighbourListsN<Dim>::inside(int p, const Vec& x) const noexcept {
  const Vec d = diff(x, c_[static_cast<std::size_t>(p)]);
  double f = 0.0;
  for (std::size_t k = 0; k < Dim; ++k) {
    if (d[k] > h_ || d[k] < -h_) return false;
    f += static_cast<double>(d[k]) * static_cast<double>(d[k]);
  }
  const double h2d = static_cast<double>(h_) * static_cast<double>(h_);
  if (f < h2d * (1.0 - 1e-9)) return true;  // surely (the double's error is ~1e-15 of h^2)
  if (f > h2d * (1.0 + 1e-9)) return false;
  return norm2(d) <= h2_;
}

template <std::size_t Dim>
std::int64_t NeighbourListsN<Dim>::exit_ticks(int p, const Vec& x, const Vec& v) const noexcept {
  const Vec d = diff(x, c_[static_cast<std::size_t>(p)]);
  double A = 0.0, B = 0.0, C = 0.0;
  for (std::size_t k = 0; k < Dim; ++k) {
    const double dk = static_cast<double>(d[k]), vk = static_cast<double>(v[k]);
    A += vk * vk;
    B += dk * vk;
    C += dk * dk;
  }
  if (A == 0.0) return -1;
  C -= static_cast<double>(h_) * static_cast<double>(h_);
  // the larger root of A t^2 + 2 B t + C = 0 (C <= 0 up to rounding), without cancellation
  const double s = std::sqrt(std::max(0.0, B * B - A * C));
  const double root = B > 0.0 ? -C / (B + s) : (s - B) / A;
  // rounded down with room for the double's error, then made sure with the exact predicate:
  // inside at 0 (the caller's precondition) and at tg means inside on [0, tg] (a ball is convex)
  std::int64_t tg = static_cast<std::int64_t>(std::clamp(std::floor(root * (1.0 - 1e-9)) - 1.0, 0.0, 0x1p61));
  const double h2d = static_cast<double>(h_) * static_cast<double>(h_);
  auto in_at = [&](std::int64_t t) {
    // surely inside in double (its error is ~1e-15 of h^2), else decided exactly
    double f = 0.0;
    for (std::size_t k = 0; k < Dim; ++k) {
      const double y = static_cast<double>(d[k]) + static_cast<double>(v[k]) * static_cast<double>(t);
      f += y * y;
    }
    if (f < h2d * (1.0 - 1e-9)) return true;
    constexpr i128 big = i128{1} << 62;
    Vec y;
    for (std::size_t k = 0; k < Dim; ++k) {
      const i128 yk = static_cast<i128>(d[k]) + static_cast<i128>(v[k]) * t;
      if (yk > h_ || yk < -h_ || yk >= big || yk <= -big) return false;
      y[k] = static_cast<std::int64_t>(yk);
    }
    return norm2(y) <= h2_;
  };
  while (tg > 0 && !in_at(tg)) tg /= 2;
  return tg + 1;
}

template <std::size_t Dim>
std::size_t NeighbourListsN<Dim>::memory_bytes() const noexcept {
  return grid_.memory_bytes() + c_.capacity() * sizeof(Vec) + ids_.capacity() * sizeof(int) + dc_.capacity() * sizeof(double) +
         count_.capacity() * 4;
}

template class NeighbourListsN<2>;
template class NeighbourListsN<3>;

}  // namespace revcol::lattice
