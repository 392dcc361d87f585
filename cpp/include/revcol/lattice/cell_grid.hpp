// The integer cell grid of the lattice engine (D = 2 or 3) and its flat walls (LATTICE.md §6).
//
// Cells. Per axis, nc cells with integer boundaries b(c) = floor(c L / nc); a particle belongs to
// the cell holding its position at its last event, and leaves it at an exact integer tick (the
// first tick at which x_a + v (t - t_a) is outside [b(c), b(c+1))), a neutral event. Pair
// predictions look at the 3 x 3 neighbouring cells: a pair that overlaps at tick a is at distance
// < sigma + |w| <= sigma + 2 vmax at tick a-1, so with a cell width >= w_min = sigma + 2 vmax + 2
// it is in neighbouring cells at a-1 and was predicted at the later of its two last events.
// On a periodic axis the grid needs nc >= 5, so that a neighbouring cell's image is the minimum
// image; a smaller periodic axis uses 8 cells for the crossings (rechecks every L/8) and takes every
// cell as a neighbour (the minimum image between rechecks then moves by < L/4; L >= 4.5 sigma).
//
// Walls. On a wall axis the centres live in [h, H] = [sigma/2, L - sigma/2]. A flat wall reflects the
// normal component on a tick transition, exactly and as a bijection: the pre phases at tick a-1
// toward the lower wall, {x >= h, x + v < h}, are |v| integers, and so are the post phases at tick
// a, {x' >= h, x' - v' < h} with v' = -v; the mirror x' = h + (|v| - 1 - (x - h)) maps one onto
// the other, and read backwards (velocities negated) it is the same map. The upper wall is the
// mirror image. Two walls within one tick (a corner) are the two axes' mirrors at once (in 3D,
// up to three).
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "revcol/lattice/units.hpp"

namespace revcol::lattice {

/// Wall mirror on one axis: pre phase x at tick a-1 (x + v beyond the wall) -> post x' at tick a;
/// returns false (nothing changed) when x + v stays inside [h, H].
inline bool wall_mirror(std::int64_t& x, std::int64_t& v, std::int64_t h, std::int64_t H) noexcept {
  if (v < 0 && x + v < h) {
    x = h + (-v - 1 - (x - h));
    v = -v;
    return true;
  }
  if (v > 0 && x + v > H) {
    x = H - (v - 1 - (H - x));
    v = -v;
    return true;
  }
  return false;
}

/// Ticks from an anchor x0 until the line x0 + v dt is first beyond [h, H] on its way out; -1 if
/// never. An anchor already beyond, moving out, gives 0: its reflection belongs to this very
/// tick. Such anchors arise (1) in the forward, when a neutral event (cell crossing, list
/// renewal: kind 0) falls on the reflection's tick and re-anchors the line before the wall event
/// (kind 1), and (2) in the reverse, when it undoes a collision that came right after a
/// reflection on the same tick (the restored pre line is the reflected one, whose point at the
/// reverse's tick is beyond the wall; its reflection comes after the tick's collisions, as the
/// forward's came before them). Giving 1 there delayed the reflection by a tick.
inline std::int64_t wall_ticks(std::int64_t x0, std::int64_t v, std::int64_t h, std::int64_t H) noexcept {
  if (v < 0) return x0 < h ? 0 : (x0 - h) / -v + 1;
  if (v > 0) return x0 > H ? 0 : (H - x0) / v + 1;
  return -1;
}

/// The cell grid in Dim dimensions: geometry per axis and the members of each cell.
template <std::size_t Dim>
class CellGridN {
 public:
  /// A grid for these units over n particles, cells at least wmin wide (0: sigma + 2 vmax + 2,
  /// the prediction's width) whose neighbours are the cells within `span` (1 or 2) per axis:
  /// anything closer than span * wmin is in them (neighbour_lists.hpp asks for half its reach
  /// and span 2: 5^D cells of (R/2)^D hold ~half the candidates of 3^D cells of R^D).
  /// members = false: the geometry and the neighbour cells only, no member storage (insert,
  /// remove, for_neighbours* and cell_of_particle are then not to be used: the caller keeps its own).
  void build(const UnitsN<Dim>& u, std::size_t n, std::int64_t wmin = 0, int span = 1, bool members = true);
  /// Number of cells along axis k.
  int count(int k) const noexcept { return nc_[k]; }
  /// Lower boundary of cell c (0 <= c <= nc) on axis k: floor(c L / nc).
  std::int64_t boundary(int k, int c) const noexcept { return bounds_[k][static_cast<std::size_t>(c)]; }
  /// The cell index on axis k of a position in [0, L): a double guess, corrected exactly against
  /// the integer boundaries.
  int cell_of(int k, std::int64_t x) const noexcept {
    int c = static_cast<int>(static_cast<double>(x) * scale_[k]);
    c = c < 0 ? 0 : c >= nc_[k] ? nc_[k] - 1 : c;
    while (c > 0 && x < boundary(k, c)) --c;
    while (c + 1 < nc_[k] && x >= boundary(k, c + 1)) ++c;
    return c;
  }
  /// Ticks from an anchor x0 in cell c of axis k until the line x0 + v dt leaves the cell; -1 if never.
  std::int64_t exit_ticks(int k, int c, std::int64_t x0, std::int64_t v) const noexcept;
  /// Flat cell id of a particle at position x (the last axis fastest).
  int cell_id(const VecN<Dim>& x) const noexcept {
    int id = cell_of(0, x[0]);
    for (std::size_t k = 1; k < Dim; ++k) id = id * nc_[k] + cell_of(static_cast<int>(k), x[k]);
    return id;
  }
  /// The per-axis cell indices of flat cell id.
  std::array<int, Dim> coords(int id) const noexcept {
    std::array<int, Dim> c{};
    for (std::size_t k = Dim; k-- > 1;) {
      c[k] = id % nc_[k];
      id /= nc_[k];
    }
    c[0] = id;
    return c;
  }
  /// Calls f(member) for every particle in the cells neighbouring (and including) flat cell id.
  template <class F>
  void for_neighbours(int id, F&& f) const {
    // the distinct neighbour cells per axis, tabulated by build (axis_range)
    if constexpr (Dim == 2) {
      const int c0 = id / nc_[1], c1 = id % nc_[1];
      const int* a0 = &nbr_[0][static_cast<std::size_t>(c0) * 8];
      const int* a1 = &nbr_[1][static_cast<std::size_t>(c1) * 8];
      const int n0 = nbrn_[0][static_cast<std::size_t>(c0)], n1 = nbrn_[1][static_cast<std::size_t>(c1)];
      for (int i = 0; i < n0; ++i)
        for (int j = 0; j < n1; ++j)
          for (std::size_t id2 = static_cast<std::size_t>(a0[i]) * nc_[1] + a1[j], k = 0, e = count_[id2]; k < e; ++k)
            f(slots_[id2 * cap_ + k]);
    } else {
      const std::array<int, Dim> c = coords(id);
      const int* a0 = &nbr_[0][static_cast<std::size_t>(c[0]) * 8];
      const int* a1 = &nbr_[1][static_cast<std::size_t>(c[1]) * 8];
      const int* a2 = &nbr_[2][static_cast<std::size_t>(c[2]) * 8];
      const int n0 = nbrn_[0][static_cast<std::size_t>(c[0])], n1 = nbrn_[1][static_cast<std::size_t>(c[1])];
      const int n2 = nbrn_[2][static_cast<std::size_t>(c[2])];
      for (int i = 0; i < n0; ++i)
        for (int j = 0; j < n1; ++j) {
          const std::size_t row = (static_cast<std::size_t>(a0[i]) * nc_[1] + a1[j]) * nc_[2];
          for (int l = 0; l < n2; ++l)
            for (std::size_t id2 = row + a2[l], k = 0, e = count_[id2]; k < e; ++k) f(slots_[id2 * cap_ + k]);
        }
    }
  }
  /// for_neighbours in a sheared box (shear.hpp; span 1): a cell next to a gradient face (axis 1)
  /// takes, beyond the face, every cell of the far row along the flow (axis 0), whose images move
  /// past it; elsewhere the neighbours of for_neighbours.
  template <class F>
  void for_neighbours_sheared(int id, F&& f) const {
    const std::array<int, Dim> c = coords(id);
    const int* a1 = &nbr_[1][static_cast<std::size_t>(c[1]) * 8];
    const int n1 = nbrn_[1][static_cast<std::size_t>(c[1])];
    const int* a0 = &nbr_[0][static_cast<std::size_t>(c[0]) * 8];
    const int n0 = nbrn_[0][static_cast<std::size_t>(c[0])];
    const int last = nc_[1] - 1;
    for (int j = 0; j < n1; ++j) {
      const bool across = (c[1] == 0 && a1[j] == last) || (c[1] == last && a1[j] == 0);
      const int m0 = across ? nc_[0] : n0;
      for (int i = 0; i < m0; ++i) {
        const int x0 = across ? i : a0[i];
        const std::size_t row = static_cast<std::size_t>(x0) * nc_[1] + a1[j];
        if constexpr (Dim == 2) {
          for (std::size_t k = 0, e = count_[row]; k < e; ++k) f(slots_[row * cap_ + k]);
        } else {
          const int* a2 = &nbr_[2][static_cast<std::size_t>(c[2]) * 8];
          const int n2 = nbrn_[2][static_cast<std::size_t>(c[2])];
          for (int l = 0; l < n2; ++l)
            for (std::size_t id2 = row * nc_[2] + a2[l], k = 0, e = count_[id2]; k < e; ++k) f(slots_[id2 * cap_ + k]);
        }
      }
    }
  }
  /// Whether no periodic axis takes every cell as a neighbour (each has >= 2 span + 3 cells): a
  /// neighbouring cell's members are then seen at one image, for_neighbours_shifted's.
  bool shifted() const noexcept {
    bool ok = true;
    for (std::size_t k = 0; k < Dim; ++k) ok = ok && !all_[k];
    return ok;
  }
  /// for_neighbours (span 1, shifted()) with each cell's image: f(member, s), s[k] in {0, L_k,
  /// -L_k}, so that x + s - x_member is the member's nearest image seen from a point x of cell id
  /// (any point within two cells of x on every axis is nearer than L_k / 2 with >= 5 cells).
  template <class F>
  [[gnu::always_inline]] void for_neighbours_shifted(int id, F&& f) const {
    // for_neighbours' tables, with the shift of each neighbouring cell beside its index
    VecN<Dim> s{};
    if constexpr (Dim == 2) {
      const int c0 = id / nc_[1], c1 = id % nc_[1];
      const int* a0 = &nbr_[0][static_cast<std::size_t>(c0) * 8];
      const int* a1 = &nbr_[1][static_cast<std::size_t>(c1) * 8];
      const std::int64_t* s0 = &nbs_[0][static_cast<std::size_t>(c0) * 8];
      const std::int64_t* s1 = &nbs_[1][static_cast<std::size_t>(c1) * 8];
      const int n0 = nbrn_[0][static_cast<std::size_t>(c0)], n1 = nbrn_[1][static_cast<std::size_t>(c1)];
      for (int i = 0; i < n0; ++i)
        for (int j = 0; j < n1; ++j) {
          s = {s0[i], s1[j]};
          for (std::size_t id2 = static_cast<std::size_t>(a0[i]) * nc_[1] + a1[j], k = 0, e = count_[id2]; k < e; ++k)
            f(slots_[id2 * cap_ + k], s);
        }
    } else {
      const std::array<int, Dim> c = coords(id);
      const int* a0 = &nbr_[0][static_cast<std::size_t>(c[0]) * 8];
      const int* a1 = &nbr_[1][static_cast<std::size_t>(c[1]) * 8];
      const int* a2 = &nbr_[2][static_cast<std::size_t>(c[2]) * 8];
      const std::int64_t* s0 = &nbs_[0][static_cast<std::size_t>(c[0]) * 8];
      const std::int64_t* s1 = &nbs_[1][static_cast<std::size_t>(c[1]) * 8];
      const std::int64_t* s2 = &nbs_[2][static_cast<std::size_t>(c[2]) * 8];
      const int n0 = nbrn_[0][static_cast<std::size_t>(c[0])], n1 = nbrn_[1][static_cast<std::size_t>(c[1])];
      const int n2 = nbrn_[2][static_cast<std::size_t>(c[2])];
      for (int i = 0; i < n0; ++i)
        for (int j = 0; j < n1; ++j) {
          const std::size_t row = (static_cast<std::size_t>(a0[i]) * nc_[1] + a1[j]) * nc_[2];
          for (int l = 0; l < n2; ++l) {
            s = {s0[i], s1[j], s2[l]};
            for (std::size_t id2 = row + a2[l], k = 0, e = count_[id2]; k < e; ++k) f(slots_[id2 * cap_ + k], s);
          }
        }
    }
  }
  /// As for_neighbours, but skips the neighbour cells that lie wholly beyond distance r of the
  /// point x (a position in [0, L) of flat cell id): a cell is skipped only when its exact
  /// integer bounds put every point of it at least r (1 + 1e-9) + 2 lattice units away (nearest
  /// image on periodic axes), so a caller that keeps members closer than r (in double, from the
  /// exact differences) sees exactly what for_neighbours would give it, in the same order.
  template <class F>
  void for_neighbours_within(int id, const VecN<Dim>& x, double r, F&& f) const {
    for_cells_within(id, x, r, [&](std::size_t id2) {
      for (std::size_t k = 0, e = static_cast<std::size_t>(count_[id2]); k < e; ++k) f(slots_[id2 * cap_ + k]);
    });
  }
  /// The cells of for_neighbours_within, in its order: f(flat cell id) for each neighbour cell of
  /// flat cell id that is not wholly beyond distance r of x (for a caller that keeps its own
  /// members per cell).
  template <class F>
  void for_cells_within(int id, const VecN<Dim>& x, double r, F&& f) const {
    const std::array<int, Dim> c = coords(id);
    const double lim = r * (1.0 + 1e-9) + 2.0, lim2 = lim * lim;
    // per axis: the squared distance from x to each neighbour cell (0 for its own cell)
    std::array<std::array<double, 8>, Dim> d2{};
    std::array<const int*, Dim> a{};
    std::array<int, Dim> n{};
    for (std::size_t k = 0; k < Dim; ++k) {
      a[k] = &nbr_[k][static_cast<std::size_t>(c[k]) * 8];
      n[k] = nbrn_[k][static_cast<std::size_t>(c[k])];
      for (int i = 0; i < n[k]; ++i) {
        const std::int64_t lo = bounds_[k][static_cast<std::size_t>(a[k][i])];
        const std::int64_t hi = bounds_[k][static_cast<std::size_t>(a[k][i]) + 1];  // exclusive
        std::int64_t gap = 0;  // the exact distance from x[k] to [lo, hi - 1], nearest image
        if (x[k] < lo || x[k] >= hi) {
          std::int64_t below = lo - x[k], above = x[k] - (hi - 1);  // one of them is > 0
          if (!wall_[k]) {  // periodic: the other image may be nearer
            below = below < 0 ? below + L_[k] : below;
            above = above < 0 ? above + L_[k] : above;
          }
          gap = below > 0 && (above <= 0 || below < above) ? below : above;
          if (gap < 0) gap = 0;
        }
        const double g = static_cast<double>(gap);
        d2[k][static_cast<std::size_t>(i)] = g * g;
      }
    }
    if constexpr (Dim == 2) {
      for (int i = 0; i < n[0]; ++i)
        for (int j = 0; j < n[1]; ++j) {
          if (d2[0][static_cast<std::size_t>(i)] + d2[1][static_cast<std::size_t>(j)] >= lim2) continue;
          f(static_cast<std::size_t>(a[0][i]) * nc_[1] + a[1][j]);
        }
    } else {
      for (int i = 0; i < n[0]; ++i) {
        const double di = d2[0][static_cast<std::size_t>(i)];
        if (di >= lim2) continue;
        for (int j = 0; j < n[1]; ++j) {
          const double dij = di + d2[1][static_cast<std::size_t>(j)];
          if (dij >= lim2) continue;
          const std::size_t row = (static_cast<std::size_t>(a[0][i]) * nc_[1] + a[1][j]) * nc_[2];
          for (int l = 0; l < n[2]; ++l) {
            if (dij + d2[2][static_cast<std::size_t>(l)] >= lim2) continue;
            f(row + a[2][l]);
          }
        }
      }
    }
  }
  /// Puts particle p into flat cell id.
  void insert(int p, int id);
  /// Removes particle p from its cell.
  void remove(int p);
  /// The flat cell of particle p.
  int cell_of_particle(int p) const noexcept { return where_[p]; }
  /// Bytes held by the grid.
  std::size_t memory_bytes() const noexcept;

 private:
  static_assert(Dim == 2 || Dim == 3, "the lattice cell grid is for 2 or 3 dimensions");
  // the distinct neighbour cells of c on axis k into out[8] (returns their count)
  int axis_range(int k, int c, int* out) const noexcept;
  std::array<std::int64_t, Dim> L_{};
  std::array<int, Dim> nc_{};
  std::array<std::vector<std::int64_t>, Dim> bounds_;  // b(c) = floor(c L / nc), c = 0..nc
  std::array<double, Dim> scale_{};                    // nc / L: cell_of's first guess
  std::array<std::vector<int>, Dim> nbr_;              // per axis and cell: its neighbour cells (8 slots)
  std::array<std::vector<std::uint8_t>, Dim> nbrn_;    // per axis and cell: how many
  std::array<std::vector<std::int64_t>, Dim> nbs_;     // per axis and cell: each neighbour's image shift
  std::array<bool, Dim> all_{};  // small periodic axis: every cell is a neighbour
  int span_ = 1;                 // neighbours: the cells within span_ per axis
  std::array<bool, Dim> wall_{};
  // members stored flat (measure before changing: the neighbour scan is bound by memory loads):
  // cell id's members are slots_[id * cap_ .. + count_[id]]; cap_ starts at min(8, the most disks
  // whose centres fit one cell without overlapping, plus 2) and doubles when a cell is full
  void grow();
  std::size_t cap_ = 6;
  std::vector<int> slots_;
  std::vector<std::int32_t> count_;
  std::vector<int> where_, slot_;
};
/// The 2D cell grid.
using CellGrid = CellGridN<2>;

}  // namespace revcol::lattice
