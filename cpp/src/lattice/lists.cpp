// Neighbour lists of the lattice engine (lattice/neighbour_lists.hpp).
#include <algorithm>
#include <cmath>

#include "revcol/error.hpp"
#include "revcol/lattice/field.hpp"
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
  w_ = static_cast<std::int64_t>(std::sqrt(static_cast<double>(h) * static_cast<double>(h) / static_cast<double>(Dim)));
  while (w_ > 0 && static_cast<u128>(Dim) * static_cast<u128>(w_) * static_cast<u128>(w_) > h2_) --w_;  // the cube inside the ball, exactly
  while (static_cast<u128>(Dim) * static_cast<u128>(w_ + 1) * static_cast<u128>(w_ + 1) <= h2_) ++w_;
  const std::size_t n = centres.size();
  // 3^D cells of R (measured against 5^D cells of R / 2, which hold half the candidates, at 3D
  // N = 10^4: 1.11 / 1.07x the collisions per second at volume fraction 0.1, 1.05x at 0.3, level
  // at 0.45, as most of the smaller cells are empty; at N = 10^5 level at 0.3, 0.97-0.98x at 0.45,
  // where the extra candidates miss the caches: docs/lattice.md "Speed against the float engine (3D)")
  grid_.build(u, n, reach_, 1, false);
  coded_ = !minimum_image_ && grid_.shifted();
  std::size_t cells = 1;
  for (std::size_t k = 0; k < Dim; ++k) cells *= static_cast<std::size_t>(grid_.count(static_cast<int>(k)));
  head_.assign(cells, -1);
  node_.assign(n, Node{});
  for (std::size_t p = 0; p < n; ++p) {
    node_[p].c = centres[p];
    link(static_cast<int>(p), grid_.cell_id(centres[p]));
  }
  count_.assign(n, 0);
  ids_.assign(n * cap_, -1);
  codes_.assign(n * cap_, 0);
  mark_.assign(n, Mark{});
  stamp_ = 0;
  for (std::size_t p = 0; p < n; ++p) scan(static_cast<int>(p), [&](int q, std::uint8_t code) { add(static_cast<int>(p), q, code); });
}

template <std::size_t Dim>
template <class F>
void NeighbourListsN<Dim>::scan_coded(int p, F&& f) const {
  const Node& np = node_[static_cast<std::size_t>(p)];
  const std::array<int, Dim> at = grid_.coords(np.cell);
  // per axis, the neighbouring cells (index, the centre's image shift and its code bits, the
  // squared gap from the centre to the cell); a cell whose points are all at least R (1 + 1e-9)
  // + 2 away is skipped (for_cells_within's margin: it could hold no entry)
  int idx[Dim][3], cnt[Dim];
  std::int64_t shift[Dim][3];
  unsigned bits[Dim][3];
  double gap2[Dim][3];
  const double lim = static_cast<double>(reach_) * (1.0 + 1e-9) + 2.0, lim2 = lim * lim;
  for (std::size_t k = 0; k < Dim; ++k) {
    const int nc = grid_.count(static_cast<int>(k)), c = at[k];
    const std::int64_t x = np.c[k], lo = grid_.boundary(static_cast<int>(k), c), hi = grid_.boundary(static_cast<int>(k), c + 1);
    cnt[k] = 0;
    for (int off = -1; off <= 1; ++off) {
      int a = c + off;
      std::int64_t s = 0;
      unsigned b = 0;
      if (a < 0 || a >= nc) {
        if (wall_[k]) continue;
        // across the end: the cell's members seen at c_q - L (below 0) or c_q + L (past the
        // end), that is c_p - c_q = m - L (code 2) or m + L (code 1) with m the difference used
        s = a < 0 ? L_[k] : -L_[k];
        b = (a < 0 ? 2u : 1u) << (2 * k);
        a += a < 0 ? nc : -nc;
      }
      const std::int64_t gap = off < 0 ? x - (lo - 1) : off > 0 ? hi - x : 0;
      const double g = static_cast<double>(gap);
      idx[k][cnt[k]] = a;
      shift[k][cnt[k]] = s;
      bits[k][cnt[k]] = b;
      gap2[k][cnt[k]++] = g * g;
    }
  }
  // the live cells: their first member, the centre moved to their image (modulo 2^64: c + L can
  // pass 2^63 in a box near the coordinates' limit; the difference below is exact), the code
  int cur[27], which[27], m = 0;
  std::uint64_t cs[27][Dim];
  unsigned code[27];
  const auto cell = [&](const int (&i)[Dim]) {
    double g = 0.0;
    int flat = 0;
    for (std::size_t k = 0; k < Dim; ++k) {
      g += gap2[k][i[k]];
      flat = flat * grid_.count(static_cast<int>(k)) + idx[k][i[k]];
    }
    const int h = head_[static_cast<std::size_t>(flat)];
    if (h < 0 || g >= lim2) return;
    unsigned b = 0;
    for (std::size_t k = 0; k < Dim; ++k) {
      cs[m][k] = static_cast<std::uint64_t>(np.c[k]) + static_cast<std::uint64_t>(shift[k][i[k]]);
      b |= bits[k][i[k]];
    }
    code[m] = b;
    which[m] = m;
    cur[m++] = h;
  };
  if constexpr (Dim == 2) {
    for (int a = 0; a < cnt[0]; ++a)
      for (int b = 0; b < cnt[1]; ++b) cell({a, b});
  } else {
    for (int a = 0; a < cnt[0]; ++a)
      for (int b = 0; b < cnt[1]; ++b)
        for (int e = 0; e < cnt[2]; ++e) cell({a, b, e});
  }
  // the chains side by side, one link of each per round (the float engine's neighbours.hpp)
  while (m > 0) {
    int live = 0;
    for (int u = 0; u < m; ++u) {
      const int q = cur[u], w = which[u];
      const Node& nq = node_[static_cast<std::size_t>(q)];
      if (q != p) {
        double dd = 0.0;
        for (std::size_t k = 0; k < Dim; ++k) {
          // c_p + s - c_q is in (-L, L): the difference modulo 2^64 read as signed is exact
          const double d = static_cast<double>(static_cast<std::int64_t>(cs[w][k] - static_cast<std::uint64_t>(nq.c[k])));
          dd += d * d;
        }
        if (dd < reach2_) f(q, static_cast<std::uint8_t>(code[w]));
      }
      cur[live] = nq.next;
      which[live] = w;
      live += nq.next >= 0 ? 1 : 0;
    }
    m = live;
  }
}

template <std::size_t Dim>
template <class F>
void NeighbourListsN<Dim>::scan(int p, F&& f) const {
  if (coded_) {
    scan_coded(p, f);
    return;
  }
  const Node& np = node_[static_cast<std::size_t>(p)];
  const Vec& c = np.c;
  // only the cells that reach within R of c (the rest could hold no entry: the same lists)
  grid_.for_cells_within(np.cell, c, static_cast<double>(reach_), [&](std::size_t cell) {
    for (int q = head_[cell]; q >= 0;) {
      const Node& nq = node_[static_cast<std::size_t>(q)];
      if (q != p) {
        double dd = 0.0;
        unsigned code = 0;
        for (std::size_t k = 0; k < Dim; ++k) {
          const std::int64_t raw = c[k] - nq.c[k];
          const std::int64_t m = wall_[k] ? raw : min_image(raw, L_[k]);
          if (m != raw) code |= (m < raw ? 1u : 2u) << (2 * k);  // raw = m + L or m - L
          const double d = static_cast<double>(m);
          dd += d * d;
        }
        if (dd < reach2_) f(q, static_cast<std::uint8_t>(code));
      }
      q = nq.next;
    }
  });
}

template <std::size_t Dim>
void NeighbourListsN<Dim>::renew(int p, const Vec& c) {
  // mark the old list (the stamp tells this renewal's marks from older ones)
  if (++stamp_ == 0) {
    for (Mark& m : mark_) m.stamp = 0;
    stamp_ = 1;
  }
  const std::size_t base = static_cast<std::size_t>(p) * cap_;
  for (std::int32_t e = 0, ne = count_[static_cast<std::size_t>(p)]; e < ne; ++e)
    mark_[static_cast<std::size_t>(ids_[base + e])] = Mark{stamp_, codes_[base + e], false};
  node_[static_cast<std::size_t>(p)].c = c;
  const int id = grid_.cell_id(c);
  if (node_[static_cast<std::size_t>(p)].cell != id) {
    unlink(p);
    link(p, id);
  }
  // the new list; a neighbour's own list changes only where p joins it, leaves it or changes code
  fresh_.clear();
  fresh_codes_.clear();
  scan(p, [&](int q, std::uint8_t code) {
    fresh_.push_back(q);
    fresh_codes_.push_back(code);
    Mark& m = mark_[static_cast<std::size_t>(q)];
    if (m.stamp == stamp_) {
      m.kept = true;
      if (m.code != code) recode(q, p, mirror(code));
    } else {
      add(q, p, mirror(code));
    }
  });
  for (std::int32_t e = 0, ne = count_[static_cast<std::size_t>(p)]; e < ne; ++e) {
    const int q = ids_[static_cast<std::size_t>(p) * cap_ + e];
    if (!mark_[static_cast<std::size_t>(q)].kept) drop(q, p);
  }
  count_[static_cast<std::size_t>(p)] = 0;
  for (std::size_t e = 0; e < fresh_.size(); ++e) add(p, fresh_[e], fresh_codes_[e]);
}

template <std::size_t Dim>
void NeighbourListsN<Dim>::remove(int p) {
  const std::size_t base = static_cast<std::size_t>(p) * cap_;
  for (std::int32_t e = 0, ne = count_[static_cast<std::size_t>(p)]; e < ne; ++e) drop(ids_[base + e], p);
  count_[static_cast<std::size_t>(p)] = 0;
  if (node_[static_cast<std::size_t>(p)].cell >= 0) unlink(p);
}

template <std::size_t Dim>
void NeighbourListsN<Dim>::insert(int p, const Vec& c) {
  require(node_[static_cast<std::size_t>(p)].cell < 0, "lattice neighbour lists: the particle is already listed");
  node_[static_cast<std::size_t>(p)].c = c;
  link(p, grid_.cell_id(c));
  scan(p, [&](int q, std::uint8_t code) {
    add(p, q, code);
    add(q, p, mirror(code));
  });
}

template <std::size_t Dim>
void NeighbourListsN<Dim>::link(int p, int cell) {
  Node& n = node_[static_cast<std::size_t>(p)];
  n.cell = cell;
  n.next = head_[static_cast<std::size_t>(cell)];
  head_[static_cast<std::size_t>(cell)] = p;
}

template <std::size_t Dim>
void NeighbourListsN<Dim>::unlink(int p) {
  Node& n = node_[static_cast<std::size_t>(p)];
  int* at = &head_[static_cast<std::size_t>(n.cell)];  // the link that points at p
  while (*at != p) at = &node_[static_cast<std::size_t>(*at)].next;
  *at = n.next;
  n.next = n.cell = -1;
}

template <std::size_t Dim>
void NeighbourListsN<Dim>::add(int p, int q, std::uint8_t code) {
  if (static_cast<std::size_t>(count_[static_cast<std::size_t>(p)]) == cap_) grow();
  const std::size_t slot = static_cast<std::size_t>(p) * cap_ + static_cast<std::size_t>(count_[static_cast<std::size_t>(p)]++);
  ids_[slot] = q;
  codes_[slot] = code;
}

template <std::size_t Dim>
void NeighbourListsN<Dim>::drop(int p, int q) {
  const std::size_t base = static_cast<std::size_t>(p) * cap_;
  std::int32_t& n = count_[static_cast<std::size_t>(p)];
  for (std::int32_t k = 0; k < n; ++k)
    if (ids_[base + k] == q) {
      --n;
      ids_[base + k] = ids_[base + n];
      codes_[base + k] = codes_[base + n];
      return;
    }
}

template <std::size_t Dim>
void NeighbourListsN<Dim>::recode(int p, int q, std::uint8_t code) {
  const std::size_t base = static_cast<std::size_t>(p) * cap_;
  for (std::int32_t k = 0, n = count_[static_cast<std::size_t>(p)]; k < n; ++k)
    if (ids_[base + k] == q) {
      codes_[base + k] = code;
      return;
    }
}

template <std::size_t Dim>
void NeighbourListsN<Dim>::grow() {
  const std::size_t cap = 2 * cap_;
  std::vector<int> wider(count_.size() * cap, -1);
  std::vector<std::uint8_t> wider_codes(count_.size() * cap, 0);
  for (std::size_t p = 0; p < count_.size(); ++p) {
    std::copy_n(&ids_[p * cap_], count_[p], &wider[p * cap]);
    std::copy_n(&codes_[p * cap_], count_[p], &wider_codes[p * cap]);
  }
  ids_.swap(wider);
  codes_.swap(wider_codes);
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
  const Vec d = diff(x, node_[static_cast<std::size_t>(p)].c);
  if (fax_ >= 0) [[unlikely]] {  // a field: the cube
    for (std::size_t k = 0; k < Dim; ++k)
      if (d[k] > w_ || d[k] < -w_) return false;
    return true;
  }
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
  const Vec d = diff(x, node_[static_cast<std::size_t>(p)].c);
  if (fax_ >= 0) [[unlikely]] return exit_cube(d, v);
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

// A field's renewal tick: the first tick n >= 1 at which d + v n (+ fh_ n^2 on the field's axis)
// leaves the cube [-w, w]^D, each axis exactly (d inside: inside(), the caller's precondition).
template <std::size_t Dim>
std::int64_t NeighbourListsN<Dim>::exit_cube(const Vec& d, const Vec& v) const noexcept {
  std::int64_t best = -1;
  for (std::size_t k = 0; k < Dim; ++k) {
    std::int64_t n;
    if (static_cast<int>(k) == fax_) n = field_exit_ticks(d[k], v[k], fh_, -w_, w_ + 1, false, false);
    else if (v[k] > 0) n = (w_ - d[k]) / v[k] + 1;  // d + v n > w first
    else if (v[k] < 0) n = (d[k] + w_) / -v[k] + 1;  // d + v n < -w first
    else continue;
    if (n >= 0 && (best < 0 || n < best)) best = n;
  }
  return best;
}

template <std::size_t Dim>
std::size_t NeighbourListsN<Dim>::memory_bytes() const noexcept {
  return grid_.memory_bytes() + node_.capacity() * sizeof(Node) + head_.capacity() * sizeof(int) + ids_.capacity() * sizeof(int) + codes_.capacity() +
         count_.capacity() * 4 + mark_.capacity() * sizeof(Mark) + fresh_.capacity() * sizeof(int) + fresh_codes_.capacity();
}

template class NeighbourListsN<2>;
template class NeighbourListsN<3>;

}  // namespace revcol::lattice
