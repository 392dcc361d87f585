// Neighbour lists with a shell, built from a cell grid of list centres.
//
// Each particle i keeps a list centre c_i (where it was at its last list renewal) and the
// ids of the particles whose centres lie within D + shell of c_i, each with its periodic
// image: the lists are symmetric (j on i's iff i on j's, with mirrored image codes) and a
// pure function of the centres (a snapshot keeps the centres, a restore rebuilds the lists).
// The engine renews i's list when i is h = (shell - 1e-3 D) / 2 from its centre, so a pair
// off each other's lists is more than D (1 + 1e-3) apart and a prediction scans the list
// alone. The cell grid (cells at least D + shell wide) holds the centres and is read by
// the renewals only. Ids on a list are sorted: a canonical order, the same after a restore.
// (The float engine's "ids" here are its storage slots: it may re-sort them in space,
// permute_centres, and build the lists again; see EngineImpl::sort_storage.)
//
// Image codes: 2 bits per axis, 0: x_j, 1: x_j + L, 2: x_j - L (the nearest image of j's
// centre seen from i's; Boundaries::image). With L >= 2 (D + shell) each listed pair has one
// nearest image (the engine keeps the shell below L / 2 - D). A list entry is one 32-bit
// word, j << 2d | code (kCodeBits): one load per neighbour, 4 bytes a slot instead of an id
// and a code byte in two arrays. It holds ids below 2^(32 - 2d) (2^26 in 3D), the engine's
// limit on N (limits::max_particles). Entries sort as their ids do.
//
// 1D (walls, or a periodic ring of 3 rods or more): rods keep their order, so each lists
// the rods beside it for the whole run ("adjacent" mode: no cell grid, no renewals; on a
// ring the engine's wrap event recodes the images of the rods beside a wrapped rod).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "revcol/engine/boundary.hpp"
#include "revcol/engine/limits.hpp"
#include "revcol/engine/prefetch.hpp"

namespace revcol::engine {

/// Moves a[i] to a[to[i]] for every i (`to` a permutation of 0 .. a.size() - 1) in place: one
/// element held at a time, each cycle of the permutation followed once (no copy of the array:
/// a re-sort of a large engine's storage does not raise its peak memory).
template <class T>
void permute_in_place(std::vector<T>& a, const std::vector<std::int32_t>& to) {
  std::vector<bool> done(a.size(), false);
  for (std::size_t j = 0; j < a.size(); ++j) {
    if (done[j]) continue;
    T held = a[j];
    std::size_t k = j;
    do {
      const auto d = static_cast<std::size_t>(to[k]);
      done[k] = true;
      std::swap(held, a[d]);
      k = d;
    } while (k != j);
  }
}

/// Symmetric neighbour lists over list centres, per dimension d.
template <int Dim>
class NeighbourLists {
 public:
  using Vec = std::array<double, Dim>;  ///< a d-vector

  /// A renewal's new list on the stack. Listed centres are within D + shell of c_i, so their
  /// particles (disjoint spheres) are within D + shell + h of it: at most ((1.5 D + shell +
  /// h) / (D / 2))^d of them: 101 in 3D at the smallest shell (0.55 D), 45 in 2D at the shell
  /// of phi 0.3 (1.1 D). A sparse gas takes a wider shell, and a dense cluster in it can
  /// overflow: the slower path for more is the safety net.
  static constexpr int kMaxList = 128;
  /// Whether a renewal skips the cells out of reach (scan_cells). In 3D it reads a quarter
  /// fewer centres: at phi 0.05, 389 -> 332 L1 misses and 315 -> 229 mispredicted branches
  /// per collision for 5% more instructions. In 2D it skips little and cost 2% more
  /// instructions at phi 0.5 (cachegrind; docs/peers.md, session 21). Cells half the reach
  /// wide (5^d scanned, fewer centres but ~84 mostly empty heads) measured 16% more
  /// instructions at phi 0.3 and 55% more at 0.05.
  static constexpr bool kCull = Dim == 3;
  /// Low bits of a list entry that hold the image code (2 per axis); the id is above them.
  static constexpr int kCodeBits = 2 * Dim;
  /// Ids a list entry can hold: 0 .. kMaxIds - 1.
  static constexpr std::uint64_t kMaxIds = std::uint64_t{1} << (32 - kCodeBits);

  /// Sets the geometry: n particles, the box, and the list reach D + shell; `adjacent`
  /// chooses the 1D mode. Lists are empty until build().
  void setup(std::size_t n, const Boundaries<Dim>& box, double reach, bool adjacent) {
    n_ = n;
    box_ = box;
    list_r2_ = reach * reach;
    adj_ = Dim == 1 && adjacent;
    total_cells_ = 1;
    cells_code_images_ = true;
    // floor(L_k / reach) cells per axis, fewer (wider) in a box so sparse that they would
    // exceed limits::max_list_cells(n): the same grid for every gas below that (issue 59)
    double lengths[Dim];
    for (int k = 0; k < Dim; ++k) lengths[k] = box.length(k);
    limits::capped_cell_counts(Dim, lengths, reach, limits::max_list_cells(n), nc_.data());
    for (int k = 0; k < Dim; ++k) {
      const double L = box.length(k);
      cw_[k] = L / nc_[k];
      if (box.periodic(k) && nc_[k] < 3) cells_code_images_ = false;
      stride_[k] = total_cells_;
      total_cells_ *= nc_[k];
      shift_tab_[k][0] = 0.0;
      shift_tab_[k][1] = L;
      shift_tab_[k][2] = -L;
      shift_tab_[k][3] = 0.0;
    }
    for (unsigned code = 0; code < shift_vec_.size(); ++code)
      for (int k = 0; k < Dim; ++k) shift_vec_[code][k] = shift_tab_[k][(code >> (2 * k)) & 3u];
  }

  /// Whether the lists are 1D's rods-beside-each-other (a constant false in 2D and 3D).
  bool adjacent() const { return Dim == 1 && adj_; }
  /// The list centres (n x dim).
  void set_centres(const std::vector<double>& c) {
    cn_.assign(n_, Centre{});
    for (std::size_t i = 0; i < n_; ++i)
      for (int k = 0; k < Dim; ++k) cn_[i].c[k] = c[i * Dim + k];
  }
  /// i's list centre.
  const double* centre(int i) const { return cn_[i].c; }
  /// i's list centre, to move (then renew(i)).
  double* centre(int i) { return cn_[i].c; }
  /// Cell coordinates of every centre (n x dim; zeros in 1D's adjacent mode).
  const std::vector<int>& cells() const { return cell_; }
  /// Cells in the grid.
  std::size_t cell_count() const { return static_cast<std::size_t>(total_cells_); }
  /// The grid's (row-major) index of the cell of i's centre, from the centre (lists or not).
  int cell_key(int i) const {
    int c = 0;
    for (int k = 0; k < Dim; ++k) c += cell_of(cn_[i].c[k], k) * stride_[k];
    return c;
  }
  /// Moves centre i to slot to[i] (the engine re-sorts its storage); build() follows.
  void permute_centres(const std::vector<std::int32_t>& to) { permute_in_place(cn_, to); }

  /// Every list from the centres (construction, restore). pos(j): rod j's position now
  /// (1D's adjacent mode only).
  template <class Pos>
  void build(Pos&& pos) {
    cell_.assign(n_ * Dim, 0);
    if (adjacent()) {
      build_adjacent(pos);
      return;
    }
    for (std::size_t i = 0; i < n_; ++i) place(static_cast<int>(i));
    link_all();
    // a rebuild (the engine's storage re-sort) keeps the lists' capacity: the store is not
    // allocated again beside the old one, and the peak memory stays where it was
    const bool rebuild = !nb_.empty() && nb_.size() == n_ * static_cast<std::size_t>(nbcap_);
    if (!rebuild) nbcap_ = 16;
    nb_.assign(n_ * nbcap_, 0);
    nbn_.assign(n_, 0);
    for (std::size_t i = 0; i < n_; ++i)
      for_cells(static_cast<int>(i), [&](int j) {
        unsigned code;
        if (near(static_cast<int>(i), j, code)) list_insert(static_cast<int>(i), j, code);
      });
    // 8 slots of room above the longest list: a run's fluctuations pass the start's longest
    // soon, and a capacity grown then would grow the store (and the peak memory) mid-run. A
    // rebuild keeps the room it has (it grows, as a renewal does, only when a list fills it)
    const int longest = n_ > 0 ? *std::max_element(nbn_.begin(), nbn_.end()) : 0;
    if (!rebuild && nbcap_ < longest + 8) grow_lists(longest + 8);
  }

  /// i's centre has moved: i goes to its new cell and its list is rebuilt from there, with
  /// i on the lists of its old and new neighbours (cell-grid mode).
  void renew(int i) {
    unlink(i);  // from the cell it was linked in (cell_ still holds it)
    place(i);
    link(i);
    rebuild_list(i);
  }

  /// Calls f(j, shift) for every particle j on i's list; shift is the image offset to add to
  /// x_j. prefetch(j) is called for every j first: the scan's branches (approaching or not)
  /// are unpredictable, and a mispredicted one would otherwise serialize the cache misses.
  /// This is the engine's inner loop: measure before changing.
  template <class F, class Prefetch>
  void for_neighbours(int i, F&& f, Prefetch&& prefetch) const {
    for_neighbour_pairs(
        i, [&](int j0, const Vec& s0, int j1, const Vec& s1) { f(j0, s0), f(j1, s1); }, f, prefetch);
  }

  /// for_neighbours two entries at a time, in list order: f2(j0, s0, j1, s1) for each
  /// consecutive pair of entries and f(j, s) for an odd last one (the prediction's two-lane
  /// scan, FloatKinematics::pair_test2).
  template <class F2, class F, class Prefetch>
  void for_neighbour_pairs(int i, F2&& f2, F&& f, Prefetch&& prefetch) const {
    const std::uint32_t* e = nb_.data() + static_cast<std::size_t>(i) * nbcap_;
    const int m = nbn_[i];
    for (int u = 0; u < m; ++u) prefetch(id_of(e[u]));
    int u = 0;
    for (; u + 1 < m; u += 2) f2(id_of(e[u]), shift_of(e[u]), id_of(e[u + 1]), shift_of(e[u + 1]));
    if (u < m) f(id_of(e[u]), shift_of(e[u]));
  }

  /// Image shift s of the pair (a, b), with r = x_a - x_b - s, from the centres (or, in 1D's
  /// adjacent mode, from a's list).
  Vec pair_shift(int a, int b) const {
    if (adjacent()) {
      const std::size_t base = static_cast<std::size_t>(a) * nbcap_;
      for (int u = 0; u < nbn_[a]; ++u)
        if (id_of(nb_[base + u]) == b) return shift_of(nb_[base + u]);
    }
    unsigned code;
    near(a, b, code);
    return shift_of(code);
  }

  /// 1D ring: i has gone past an end of the box and been moved by L: the images of its
  /// pairs with the rods beside it are recoded. pos(j): rod j's position now.
  template <class Pos>
  void recode_beside(int i, Pos&& pos) {
    const int r = right_[i], l = left_[i];
    const unsigned cr = right_code(i, r, pos), cl = right_code(l, i, pos);
    list_recode(i, r, cr);
    list_recode(r, i, mirror(cr));
    list_recode(l, i, cl);
    list_recode(i, l, mirror(cl));
  }

  /// Whether j's centre is within D + shell of i's, with j's nearest image code seen from i.
  /// Symmetric to the bit: near(j, i) gives the same answer and the mirrored code.
  bool near(int i, int j, unsigned& code) const {
    code = 0;
    double d2 = 0.0;
    for (int k = 0; k < Dim; ++k) {
      unsigned ck;
      const double d = box_.image(k, cn_[i].c[k] - cn_[j].c[k], ck);
      code |= ck << (2 * k);
      d2 += d * d;
    }
    return d2 < list_r2_;
  }
  /// The code of the mirrored pair (1 <-> 2 on every axis).
  static unsigned mirror(unsigned code) { return ((code & 0x15u) << 1) | ((code >> 1) & 0x15u); }
  /// The image offset of a code (or of a list entry: its low kCodeBits).
  Vec shift_of(std::uint32_t code) const { return shift_vec_[code & (shift_vec_.size() - 1)]; }

  /// Starts loading i's list (ids, codes, count) into the cache; for_neighbour_pairs would
  /// otherwise wait on its first line.
  void prefetch_list(int i) const {
    const std::size_t base = static_cast<std::size_t>(i) * nbcap_;
    const char* ids = reinterpret_cast<const char*>(nb_.data() + base);
    const std::size_t bytes = static_cast<std::size_t>(nbcap_) * sizeof(std::uint32_t);
    for (std::size_t off = 0; off < bytes; off += 64) prefetch(ids + off);
    prefetch(nbn_.data() + i);
  }
  /// Number of particles on i's list.
  int count(int i) const { return nbn_[i]; }
  /// Bytes held.
  std::size_t memory_bytes() const {
    return cell_.capacity() * sizeof(int) + head_.capacity() * sizeof(int) + cn_.capacity() * sizeof(Centre) +
           nbn_.capacity() * sizeof(int) + nb_.capacity() * sizeof(std::uint32_t) +
           (left_.capacity() + right_.capacity()) * sizeof(int);
  }

  /// Checks the lists against their definition: symmetric with mirrored codes, sorted, and
  /// (cell-grid mode) exactly the pairs whose centres are within reach, by brute force.
  /// O(n^2): for tests and REVCOL_VALIDATE builds on small systems.
  bool valid() const {
    for (std::size_t i = 0; i < n_; ++i) {
      const std::size_t base = i * nbcap_;
      for (int u = 0; u < nbn_[i]; ++u) {
        const int j = id_of(nb_[base + u]);
        if (u > 0 && id_of(nb_[base + u - 1]) >= j) return false;
        const std::size_t bj = static_cast<std::size_t>(j) * nbcap_;
        int w = 0;
        while (w < nbn_[j] && id_of(nb_[bj + w]) != static_cast<int>(i)) ++w;
        if (w == nbn_[j] || code_of(nb_[bj + w]) != mirror(code_of(nb_[base + u]))) return false;
      }
      if (adjacent()) continue;
      int listed = 0;
      for (std::size_t j = 0; j < n_; ++j) {
        if (j == i) continue;
        unsigned code;
        if (!near(static_cast<int>(i), static_cast<int>(j), code)) continue;
        ++listed;
        int u = 0;
        while (u < nbn_[i] && id_of(nb_[base + u]) != static_cast<int>(j)) ++u;
        if (u == nbn_[i] || code_of(nb_[base + u]) != code) return false;
      }
      if (listed != nbn_[i]) return false;
    }
    return true;
  }

 private:
  static int id_of(std::uint32_t e) { return static_cast<int>(e >> kCodeBits); }
  static unsigned code_of(std::uint32_t e) { return e & ((1u << kCodeBits) - 1); }
  static std::uint32_t entry(int j, unsigned code) { return (static_cast<std::uint32_t>(j) << kCodeBits) | code; }

  // A list centre with the links of its cell's chain: the renewal's scan reads one line each.
  struct alignas(Dim == 3 ? 32 : 8) Centre {
    double c[Dim] = {};
    int next = -1, prev = -1;
  };

  int cell_of(double x, int k) const {
    int c = static_cast<int>(std::floor(x / cw_[k]));
    return std::clamp(c, 0, nc_[k] - 1);
  }
  int cell_index(std::size_t i) const {
    int c = 0;
    for (int k = 0; k < Dim; ++k) c += cell_[i * Dim + k] * stride_[k];
    return c;
  }
  void place(int i) {
    for (int k = 0; k < Dim; ++k) cell_[i * Dim + k] = cell_of(cn_[i].c[k], k);
  }
  void link_all() {
    head_.assign(total_cells_, -1);
    for (std::size_t i = 0; i < n_; ++i) link(static_cast<int>(i));
  }
  void link(int i) {
    const int c = cell_index(i);
    cn_[i].next = head_[c];
    cn_[i].prev = -1;
    if (head_[c] >= 0) cn_[head_[c]].prev = i;
    head_[c] = i;
  }
  void unlink(int i) {
    if (cn_[i].prev >= 0) cn_[cn_[i].prev].next = cn_[i].next;
    else head_[cell_index(i)] = cn_[i].next;
    if (cn_[i].next >= 0) cn_[cn_[i].next].prev = cn_[i].prev;
  }

  // Calls f(j) for every particle j != i whose centre is in the 3^d cells around i's
  // (every cell of a periodic axis with fewer than 3, each once), but for cells out of
  // reach (see scan_cells).
  template <class F>
  void for_cells(int i, F&& f) const {
    scan_cells<false>(i, f);
  }
  // The same scan; Coded: f(j, code) with the image code of j's cell seen from i's (a
  // neighbouring cell reached across a periodic axis's end: j + L or j - L). With at least 3
  // cells on every periodic axis (cells_code_images_) this is the code of j's nearest image
  // whenever j is within reach of i: that image lies in one of the 3 cells around i's,
  // which are then distinct.
  //
  // In 3D (kCull), a cell none of whose points is within reach of i's centre is skipped
  // (about a quarter of the 27). Its distance from the centre is summed from the
  // per-axis gaps between the centre and the cell's faces, each less a margin (1e-9 L) far
  // above the rounding of cell_of's placement and of nc cells of L / nc: no centre near()
  // would list is ever in a skipped cell (tests/cpp/test_neighbours.cpp).
  template <bool Coded, class F>
  void scan_cells(int i, F&& f) const {
    int idx[3][3];
    unsigned icode[3][3] = {};
    double gap2[3][3] = {};
    int cnt[3] = {1, 1, 1};
    idx[1][0] = idx[2][0] = 0;
    for (int k = 0; k < Dim; ++k) {
      const int c0 = cell_[i * Dim + k];
      const bool per = box_.periodic(k);
      cnt[k] = 0;
      if (per && nc_[k] < 3) {
        for (int c = 0; c < nc_[k]; ++c) idx[k][cnt[k]++] = c * stride_[k];
        continue;
      }
      // the centre's distances to its cell's lower and upper faces, less the margin
      double below = 0.0, above = 0.0;
      if constexpr (kCull) {
        const double x = cn_[i].c[k], margin = 1e-9 * box_.length(k);
        below = std::max(0.0, x - c0 * cw_[k] - margin);
        above = std::max(0.0, (c0 + 1) * cw_[k] - x - margin);
      }
      for (int off = -1; off <= 1; ++off) {
        int ck = c0 + off;
        unsigned code = 0;
        if (ck < 0 || ck >= nc_[k]) {
          if (!per) continue;
          code = ck < 0 ? 2u : 1u;  // below 0: j's image at x_j - L; past the end: x_j + L
          ck += ck < 0 ? nc_[k] : -nc_[k];
        }
        if constexpr (kCull) gap2[k][cnt[k]] = off < 0 ? below * below : off > 0 ? above * above : 0.0;
        icode[k][cnt[k]] = code << (2 * k);
        idx[k][cnt[k]++] = ck * stride_[k];
      }
    }
    // the chains are walked side by side, one link of each per round: their loads are
    // independent, so the cache misses overlap (measured faster than one chain at a time)
    int cur[27];
    unsigned cur_code[27];
    int m = 0;
    for (int c = 0; c < cnt[2]; ++c)
      for (int b = 0; b < cnt[1]; ++b) {
        const int base = idx[1][b] + idx[2][c];
        const unsigned code_bc = icode[1][b] | icode[2][c];
        if constexpr (kCull) {
          const double g_bc = gap2[1][b] + gap2[2][c];
          if (g_bc > list_r2_) continue;
          // without a branch: whether a cell is empty or out of reach is a coin toss
          for (int a = 0; a < cnt[0]; ++a) {
            const int h = head_[idx[0][a] + base];
            cur_code[m] = code_bc | icode[0][a];
            cur[m] = h;
            m += (h >= 0) & (g_bc + gap2[0][a] <= list_r2_);
          }
        } else {
          for (int a = 0; a < cnt[0]; ++a) {
            const int h = head_[idx[0][a] + base];
            if (h >= 0) {
              cur_code[m] = code_bc | icode[0][a];
              cur[m++] = h;
            }
          }
        }
      }
    while (m > 0) {
      int live = 0;
      for (int q = 0; q < m; ++q) {
        const int j = cur[q];
        if (j != i) {
          if constexpr (Coded) f(j, cur_code[q]);
          else f(j);
        }
        // kept without a branch (live <= q: the slot is read already): chains are ~2 links
        // long, so whether one goes on is a coin toss a branch predictor loses
        const int nx = cn_[j].next;
        cur_code[live] = cur_code[q];
        cur[live] = nx;
        live += nx >= 0 ? 1 : 0;
      }
      m = live;
    }
  }
  // near() for a pair whose image code is known (scan_cells<true>): the same separations,
  // bit for bit (d - L, d + L or d - 0 = d), with no test of the axis kind.
  bool near_coded(int i, int j, unsigned code) const {
    double d2 = 0.0;
    for (int k = 0; k < Dim; ++k) {
      const double d = (cn_[i].c[k] - cn_[j].c[k]) - shift_tab_[k][(code >> (2 * k)) & 3u];
      d2 += d * d;
    }
    return d2 < list_r2_;
  }

  void list_insert(int i, int j, unsigned code) {
    if (nbn_[i] == nbcap_) grow_lists();
    const std::size_t base = static_cast<std::size_t>(i) * nbcap_;
    const std::uint32_t e = entry(j, code);
    int m = nbn_[i]++;
    while (m > 0 && nb_[base + m - 1] > e) {  // entries sort as their ids
      nb_[base + m] = nb_[base + m - 1];
      --m;
    }
    nb_[base + m] = e;
  }
  void list_recode(int i, int j, unsigned code) {
    const std::size_t base = static_cast<std::size_t>(i) * nbcap_;
    int u = 0;
    while (id_of(nb_[base + u]) != j) ++u;
    nb_[base + u] = entry(j, code);
  }
  void list_erase(int i, int j) {
    const std::size_t base = static_cast<std::size_t>(i) * nbcap_;
    const int m = nbn_[i];
    int u = 0;
    while (u < m && id_of(nb_[base + u]) != j) ++u;
    for (; u + 1 < m; ++u) nb_[base + u] = nb_[base + u + 1];
    --nbn_[i];
  }
  // Every list's capacity, to hold `least` (at least one more than now), in steps of 4: the
  // longest list sets the stride of all, and it is a tail of the density's fluctuations
  // (3D, phi 0.3, shell 0.6 D: ~9.4 listed on average, the longest past 16 in a long run;
  // a stride of 20, 8 above the start's longest, held 10^7 collisions at N = 10^4 without
  // growing), so doubling would leave most of the store empty. Steps of 8 made it 24.
  void grow_lists(int least = 0) {
    const int cap = (std::max(least, nbcap_ + 1) + 3) / 4 * 4;
    std::vector<std::uint32_t> nb(n_ * cap);
    for (std::size_t i = 0; i < n_; ++i)
      for (int u = 0; u < nbn_[i]; ++u) nb[i * cap + u] = nb_[i * nbcap_ + u];
    nb_.swap(nb);
    nbcap_ = cap;
  }

  // 1D: the rods in order of position (a rotation of the ring's order on a periodic axis),
  // each listed with the rods beside it.
  template <class Pos>
  void build_adjacent(Pos& pos) {
    nbcap_ = 2;
    nb_.assign(n_ * nbcap_, 0);
    nbn_.assign(n_, 0);
    left_.assign(n_, -1);
    right_.assign(n_, -1);
    std::vector<int> order(n_);
    std::vector<double> x(n_);
    for (std::size_t i = 0; i < n_; ++i) {
      order[i] = static_cast<int>(i);
      x[i] = pos(static_cast<int>(i));
    }
    std::sort(order.begin(), order.end(), [&](int a, int b) { return x[a] < x[b] || (x[a] == x[b] && a < b); });
    const std::size_t pairs = box_.periodic(0) ? n_ : (n_ > 0 ? n_ - 1 : 0);
    for (std::size_t u = 0; u < pairs; ++u) {
      const int a = order[u], b = order[(u + 1) % n_];  // b is the rod to the right of a
      right_[a] = b;
      left_[b] = a;
      const unsigned code = right_code(a, b, pos);
      list_insert(a, b, code);
      list_insert(b, a, mirror(code));
    }
  }
  // The image of b, the rod to the right of a, seen from a: b itself (code 0) when it lies
  // to the right, else b + L (code 1). Unambiguous: stored positions are within a quarter
  // of the smallest diameter of the box, and b lies between its contact distance (at least
  // the smallest diameter) and L less two smallest diameters to the right of a on the ring.
  template <class Pos>
  unsigned right_code(int a, int b, Pos& pos) const {
    if (!box_.periodic(0)) return 0u;
    return pos(b) > pos(a) ? 0u : 1u;
  }

  // i's list from its (new) centre, and i on the lists of its old and new neighbours: a
  // merge of the old and new sorted lists, so that only the lists whose entry for i changes
  // are touched (most neighbours stay, and keep their image unless i was wrapped).
  void rebuild_list(int i) {
    int fresh[kMaxList];
    unsigned char fcode[kMaxList];
    int nf = 0;
    bool spill = false;
    const auto listed = [&](int j, unsigned code) {
      if (nf == kMaxList) {
        spill = true;
        return;
      }
      int m = nf++;
      while (m > 0 && fresh[m - 1] > j) {
        fresh[m] = fresh[m - 1];
        fcode[m] = fcode[m - 1];
        --m;
      }
      fresh[m] = j;
      fcode[m] = static_cast<unsigned char>(code);
    };
    if (cells_code_images_) {
      scan_cells<true>(i, [&](int j, unsigned code) {
        if (near_coded(i, j, code)) listed(j, code);
      });
    } else {
      for_cells(i, [&](int j) {
        unsigned code;
        if (near(i, j, code)) listed(j, code);
      });
    }
    if (spill) {  // beyond kMaxList (not reached, see there): the slow way
      for (int u = 0; u < nbn_[i]; ++u) list_erase(id_of(nb_[static_cast<std::size_t>(i) * nbcap_ + u]), i);
      nbn_[i] = 0;
      for_cells(i, [&](int j) {
        unsigned code;
        if (!near(i, j, code)) return;
        list_insert(i, j, code);
        list_insert(j, i, mirror(code));
      });
      return;
    }
    int u = 0, w = 0;
    const int no = nbn_[i];
    while (u < no || w < nf) {
      const std::size_t base = static_cast<std::size_t>(i) * nbcap_;  // list_insert may grow the lists
      const int jo = u < no ? id_of(nb_[base + u]) : std::numeric_limits<int>::max();
      const int jn = w < nf ? fresh[w] : std::numeric_limits<int>::max();
      if (jo < jn) {
        list_erase(jo, i);
        ++u;
      } else if (jn < jo) {
        list_insert(jn, i, mirror(fcode[w]));
        ++w;
      } else {
        if (code_of(nb_[base + u]) != fcode[w]) list_recode(jn, i, mirror(fcode[w]));
        ++u;
        ++w;
      }
    }
    if (nf > nbcap_) grow_lists(nf);
    const std::size_t b2 = static_cast<std::size_t>(i) * nbcap_;
    for (int w2 = 0; w2 < nf; ++w2) nb_[b2 + w2] = entry(fresh[w2], fcode[w2]);
    nbn_[i] = nf;
  }

  std::size_t n_ = 0;
  Boundaries<Dim> box_;
  double list_r2_ = 0.0;
  std::array<double, Dim> cw_{};
  std::array<int, Dim> nc_{}, stride_{};
  int total_cells_ = 1;
  bool cells_code_images_ = true;        // every periodic axis has >= 3 cells (scan_cells<true>)
  double shift_tab_[Dim][4] = {};        // one axis's 2-bit image code -> shift
  // the whole code -> the shift vector, one load per neighbour in the prediction scan instead
  // of an unpacking per axis (4^Dim entries: 1.5 KB in 3D)
  std::array<Vec, (1u << (2 * Dim))> shift_vec_{};
  std::vector<int> cell_, head_;         // cells of the list centres, heads of their chains
  std::vector<Centre> cn_;
  bool adj_ = false;                     // 1D: rods beside each other, no cell grid
  std::vector<int> left_, right_;        // 1D: the rods beside, -1 at a wall
  std::vector<std::uint32_t> nb_;        // lists (nbcap_ entries each: id << kCodeBits | image code)
  std::vector<int> nbn_;                 // their lengths
  int nbcap_ = 16;
};

}  // namespace revcol::engine
