// Neighbour lists with a shell for the lattice engine (D = 2 or 3), exact in integers.
//
// Each particle p keeps a list centre c_p (its position at its last renewal) and stays within a
// ball of radius h about it: its line leaves the ball at an integer tick, the renewal tick, and
// the engine then renews p (a neutral event, like a cell crossing; cell_grid.hpp). Lists are
// symmetric (q on p's list iff p on q's) and a pure function of the centres: q is listed iff
// |c_p - c_q|^2 < R^2 (minimum image on periodic axes, exact 128-bit integers), with the reach
//   R = sigma + 2 h + margin,  margin = 8 vmax + 8.
// Why that is enough. At every tick the engine looks at, each particle is within h of its centre
// (a renewal event sorts before every collision and wall of its tick). Two particles that overlap
// at tick a are closer than sigma, so their centres are closer than sigma + 2 h: each is on the
// other's list at the later of their last predictions, which therefore saw the pair (the cell
// grid's argument, with the list for the 3^D cells). The acceptance scan looks for third bodies
// within sigma + 4 vmax of a post point, which is within 2 vmax of its owner's pre point
// (engine_core.hpp, post_reason), so a third body it must see is within sigma + 2 h + 6 vmax of
// the owner's centre: on the owner's list. The wall and group scans look at points within vmax of
// the members' lines: covered by the same margin.
// The renewal tick is conservative, not exact: a double root of |d + v tau|^2 = h^2 (d = the
// anchor minus the centre), rounded down and checked with the exact integer predicate (halved
// until it holds). An early renewal is harmless: renewals change no physical state, so the
// collisions, the state and the bits are those of the cell grid's engine (tests compare them).
// The centres live in a cell grid (cells at least R wide, 3^D of them scanned) read only by the
// renewals; a cell's members are a chain through the particles' nodes (a node holds the centre
// and the next member: one cache line per candidate, and a few bytes per cell for the sparse
// cells, where flat member slots took 1 MB at N = 10^4). The list test
// |c_p - c_q|^2 < R^2 is taken in double from the exact minimum-image differences: symmetric and
// deterministic (the same values in either order), and R's margin is far beyond its rounding.
// With at least 5 cells on every periodic axis the image of a neighbouring cell is known from
// its offset (scan_coded): a listed pair's minimum image is the one in the neighbouring cell, so
// the differences, the test and the codes are those of the minimum-image scan, bit for bit,
// without a branch per axis; the cells' chains are walked side by side (their misses overlap).
// Each entry also keeps the image code of the pair (one byte): the periodic shift s with
// c_p - c_q = (its minimum image) + s, from which the engine's prediction builds the relative
// vector without looking for an image (engine_core.hpp). A renewal touches a neighbour's list
// only where the neighbour joins, leaves or changes its code (rare), not at every neighbour:
// the lists are a memory-bound part of the engine (measure before changing).
// A uniform field (set_field) bends the lines along one axis, and a parabola can leave a ball and
// come back, so a renewal tick checked at its end would prove nothing. There the region about the
// centre is the cube of half-width w = floor(h / sqrt(D)) inside the ball: per axis an interval
// left at an exact tick (a linear one, or field.hpp's exact quadratic), so the ball's argument holds
// unchanged, at more renewals (the cube is the ball's 1 / sqrt(D) in width).
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "revcol/lattice/cell_grid.hpp"
#include "revcol/lattice/geometry.hpp"
#include "revcol/lattice/units.hpp"

namespace revcol::lattice {

/// Symmetric neighbour lists over list centres, with integer ball renewals.
template <std::size_t Dim>
class NeighbourListsN {
 public:
  using Vec = VecN<Dim>;  ///< an integer position or velocity

  /// Every list from the centres (construction, restore, reversal): ball radius h >= 1 lattice
  /// units; the reach is sigma + 2 h + 8 vmax + 8.
  void build(const UnitsN<Dim>& u, std::int64_t h, const std::vector<Vec>& centres);
  /// Moves p's centre to c (a wrapped position) and renews p's list and its neighbours' entries.
  void renew(int p, const Vec& c);
  /// Takes p out: off every list and out of the centres' grid (a logical process parks it).
  void remove(int p);
  /// Puts a removed p back with centre c (a wrapped position): its list and its neighbours'.
  void insert(int p, const Vec& c);
  /// A uniform field along `axis` (half its acceleration, h = g / 2, per tick^2; field.hpp): the
  /// region about each centre is then the cube inside the ball (see the header comment). Before build.
  void set_field(int axis, std::int64_t half_g) noexcept { fax_ = axis, fh_ = half_g; }
  /// True when x (a wrapped position) is within h of p's centre (in a field: in its cube), exactly.
  bool inside(int p, const Vec& x) const noexcept;
  /// Ticks tau >= 1 such that the line x + v t (in a field, + h t^2 along its axis) stays within h
  /// of p's centre (in its cube) for t in [0, tau - 1] (x inside; conservative, see the header
  /// comment); -1 if it never leaves.
  std::int64_t exit_ticks(int p, const Vec& x, const Vec& v) const noexcept;
  /// Calls f(q) for every q on p's list.
  template <class F>
  void for_each(int p, F&& f) const {
    const int* a = &ids_[static_cast<std::size_t>(p) * cap_];
    for (std::int32_t k = 0, e = count_[static_cast<std::size_t>(p)]; k < e; ++k) f(a[k]);
  }
  /// p's list: its size() entries.
  const int* ids(int p) const noexcept { return &ids_[static_cast<std::size_t>(p) * cap_]; }
  /// The image codes of p's list, one per entry in the order of ids(p): bits 2k, 2k + 1 give the
  /// shift s_k of axis k in c_p - c_q = min_image(c_p - c_q) + s (0: none, 1: +L_k, 2: -L_k).
  const std::uint8_t* codes(int p) const noexcept { return &codes_[static_cast<std::size_t>(p) * cap_]; }
  /// The code of the mirrored pair (q, p): +L and -L swapped on every axis.
  static constexpr std::uint8_t mirror(std::uint8_t code) noexcept {
    return static_cast<std::uint8_t>(((code & 0x15u) << 1) | ((code >> 1) & 0x15u));
  }
  /// p's list centre.
  const Vec& centre(int p) const noexcept { return node_[static_cast<std::size_t>(p)].c; }
  /// Entries on p's list.
  int size(int p) const noexcept { return count_[static_cast<std::size_t>(p)]; }
  /// The ball radius h and the reach R, lattice units.
  std::int64_t radius() const noexcept { return h_; }
  /// The reach R (lists hold centres closer than R), lattice units.
  std::int64_t reach() const noexcept { return reach_; }
  /// Bytes held by the lists and the grid of centres.
  std::size_t memory_bytes() const noexcept;
  /// Whether the scans know each neighbouring cell's image (>= 5 cells on every periodic axis).
  bool coded() const noexcept { return coded_; }
  /// Tests only, before build: every scan by the minimum-image test, as in a small periodic box.
  void use_minimum_image_scan() noexcept { minimum_image_ = true; }

 private:
  Vec diff(const Vec& a, const Vec& b) const noexcept;
  void add(int p, int q, std::uint8_t code);     // q onto p's list
  void drop(int p, int q);                         // q off p's list
  void recode(int p, int q, std::uint8_t code);   // q's code on p's list
  template <class F>
  void scan(int p, F&& f) const;                   // f(q, code) for every q within R of p's centre
  template <class F>
  void scan_coded(int p, F&& f) const;             // scan, each cell's image known (coded_)
  bool coded_ = false;  // no periodic axis takes every cell as a neighbour (>= 5 cells on each)
  bool minimum_image_ = false;  // use_minimum_image_scan
  void grow();
  std::array<std::int64_t, Dim> L_{};
  std::array<bool, Dim> wall_{};
  std::int64_t h_ = 0, reach_ = 0;
  int fax_ = -1;                          // a field's axis (set_field), -1 without
  std::int64_t fh_ = 0, w_ = 0;           // half its acceleration; the cube's half-width
  std::int64_t exit_cube(const Vec& d, const Vec& v) const noexcept;
  u128 h2_ = 0;
  double reach2_ = 0.0;  // R^2 in double: a symmetric, deterministic test (R holds a margin)
  void link(int p, int cell);    // p at the head of cell's chain
  void unlink(int p);            // p out of its cell's chain
  CellGridN<Dim> grid_;          // the geometry of the centres' cells, >= R wide, span 1
  struct alignas(32) Node {
    Vec c;          // p's centre
    int next = -1;  // the next member of p's cell, -1 at the end
    int cell = -1;  // p's cell
  };
  std::vector<Node> node_;
  std::vector<int> head_;        // per cell: its first member, -1 if empty
  std::size_t cap_ = 16;      // entries per list (doubles, for every list, when one is full)
  std::vector<int> ids_;      // p's list: ids_[p * cap_ .. + count_[p]]
  std::vector<std::uint8_t> codes_;  // their image codes
  std::vector<std::int32_t> count_;
  // renew's scratch: p's new list, and per particle the renewal that last saw it on p's old list
  struct Mark {
    std::uint32_t stamp = 0;
    std::uint8_t code = 0;
    bool kept = false;
  };
  std::vector<Mark> mark_;
  std::uint32_t stamp_ = 0;
  std::vector<int> fresh_;
  std::vector<std::uint8_t> fresh_codes_;
};

}  // namespace revcol::lattice
