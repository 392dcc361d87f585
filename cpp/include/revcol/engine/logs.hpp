// The engine's keyed logs: the little it must remember for a reversed run, each entry
// keyed by something both directions recover exactly, pushed forward and popped in reverse
// (LIFO). Both are empty in a gas almost always.
//
// WallLog (walls at a collision's instant). A particle of a collision that touches a wall
// (within group_tol D) and approaches it reflects before the collision operator (W1), and
// again after it if the operator sends it into a touched wall (W2). What W1 and W2 did
// (a Reflection: the components flipped, or v -> -v; revcol/engine/boundary.hpp) cannot be
// read off the post state (the wall operator's two-to-one case), so the forward run keeps
// the masks of a collision at a wall, keyed by (smallest id,
// that particle's net collision count before the collision), with its members, their net
// counts and its time. The reversed collision pops them: undoes W2, reverses the operator,
// undoes W1. A reversed run schedules no standalone wall event for a particle touching a
// wall unless the entry of its next reversed collision says W2 applied that wall's
// reflection at this instant (`entry`).
//
// KeyedStack. The common shape of such a log: entries pushed forward under a key both
// directions recover exactly and popped in reverse when the key on top is the current one
// (LIFO); where keys increase as they are pushed, an undone forward run drops the entries
// pushed after a key. The float engine's exact-pre log is one (keyed by stream and counter);
// the lattice engine keeps its redraw log and its group log so, keyed by the collision index
// (lattice/engine_core.hpp).
//
// ExactPreLog. At singular points of a chart (a 3D pair almost head-on, groups with resting
// contacts) a pre state's K-bit cell spans up to ~2^(-K/2); when its centre is off by more
// than 1e-10 (relative), the forward run keeps the pre velocities, keyed by (stream,
// generator counter before the collision's draws), which names the collision uniquely, and
// the reversed collision restores them when the key on top matches.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <utility>
#include <vector>

namespace revcol::engine {

/// A log of entries pushed forward under a key and popped in reverse (see above).
template <class Key, class Entry>
class KeyedStack {
 public:
  using Item = std::pair<Key, Entry>;  ///< a key and its entry
  /// Forward: keeps e under key (for truncate_after, greater than every key held: increasing()).
  void push(Key key, Entry e) { items_.emplace_back(key, std::move(e)); }
  /// Reverse: the top entry if its key is `key`, else null (nothing of this key is held).
  Entry* top(Key key) noexcept { return !items_.empty() && items_.back().first == key ? &items_.back().second : nullptr; }
  /// Removes the top entry.
  void pop() { items_.pop_back(); }
  /// Drops the entries pushed after `key` (an undone forward run).
  void truncate_after(Key key) {
    while (!items_.empty() && key < items_.back().first) items_.pop_back();
  }
  /// The entries, bottom (oldest) first.
  const std::vector<Item>& items() const noexcept { return items_; }
  /// Entries now held.
  std::size_t size() const noexcept { return items_.size(); }
  /// Removes every entry.
  void clear() noexcept { items_.clear(); }
  /// Whether the keys increase strictly from bottom to top (a snapshot's log must).
  bool increasing() const {
    for (std::size_t k = 1; k < items_.size(); ++k)
      if (!(items_[k - 1].first < items_[k].first)) return false;
    return true;
  }

 private:
  std::vector<Item> items_;
};

/// The wall-mask log (see above). Masks: W1 | W2 << 8 per member, each a Reflection of
/// revcol/engine/boundary.hpp (bit k: component k flipped; 1 << 7: v -> -v).
class WallLog {
 public:
  /// Forward: keeps the masks of a collision at a wall: its smallest id, that id's net
  /// count before (key), its time, and per member (in the collision's order) the id, its
  /// net count before (netc[u] for member u) and the masks.
  void push(int id, std::int64_t key, double t, int n, const int* ids, const std::int64_t* netc, const unsigned* w1,
            const unsigned* w2) {
    keys_.push_back(static_cast<std::uint64_t>(id));
    keys_.push_back(static_cast<std::uint64_t>(key));
    times_.push_back(t);
    sizes_.push_back(static_cast<std::uint64_t>(n));
    for (int u = 0; u < n; ++u) {
      ids_.push_back(static_cast<std::uint64_t>(ids[u]));
      netc_.push_back(netc[u]);
      masks_.push_back(w1[u] | (w2[u] << 8));
    }
  }
  /// Reverse: the masks of the collision keyed (id, key) with n members, popped; zeros
  /// (nothing popped) when the top entry is another collision's.
  void pop(int id, std::int64_t key, int n, unsigned* w1, unsigned* w2) {
    for (int u = 0; u < n; ++u) w1[u] = w2[u] = 0;
    if (sizes_.empty()) return;
    const std::size_t e = sizes_.size() - 1;
    if (keys_[2 * e] != static_cast<std::uint64_t>(id) || keys_[2 * e + 1] != static_cast<std::uint64_t>(key) ||
        sizes_[e] != static_cast<std::uint64_t>(n))
      return;
    const std::size_t at = masks_.size() - n;
    for (int u = 0; u < n; ++u) {
      w1[u] = static_cast<unsigned>(masks_[at + u] & 0xffu);
      w2[u] = static_cast<unsigned>(masks_[at + u] >> 8);
    }
    masks_.resize(at);
    ids_.resize(at);
    netc_.resize(at);
    sizes_.pop_back();
    times_.pop_back();
    keys_.resize(keys_.size() - 2);
  }
  /// Reverse: the member slot of particle i (net count netc_i now) in the entry of its next
  /// reversed collision if that collision is at time tnow (relative 1e-9), else -1. The
  /// log is short: at most 64 entries are searched.
  long entry(int i, std::int64_t netc_i, double tnow) const {
    if (sizes_.empty()) return -1;
    std::size_t off = masks_.size();
    std::size_t e = sizes_.size();
    for (int seen = 0; e > 0 && seen < 64; ++seen) {
      --e;
      off -= sizes_[e];
      for (std::size_t u = off; u < off + sizes_[e]; ++u) {
        if (ids_[u] != static_cast<std::uint64_t>(i)) continue;
        if (netc_[u] != netc_i - 1) return -1;
        return std::fabs(times_[e] - tnow) <= 1e-9 * (std::fabs(tnow) + 1.0) ? static_cast<long>(u) : -1;
      }
    }
    return -1;
  }
  /// The masks (W1 | W2 << 8) of member slot m.
  std::uint64_t mask(long m) const { return masks_[m]; }
  /// Clears bits of member slot m's masks (a W2 flip undone by a standalone wall event).
  void clear(long m, std::uint64_t bits) { masks_[m] &= ~bits; }
  /// Entries now held.
  std::size_t entries() const { return sizes_.size(); }
  /// Bytes now held.
  std::size_t bytes() const {
    return (keys_.size() + 2 * sizes_.size() + 3 * masks_.size()) * sizeof(std::uint64_t);
  }

  /// The log's arrays, for snapshots: (smallest id, key) per entry, members per entry, masks,
  /// member ids and net counts per member, time per entry.
  template <class Self, class F>
  static void fields(Self& s, F&& f) {
    f("wall_keys", s.keys_);
    f("wall_sizes", s.sizes_);
    f("wall_masks", s.masks_);
    f("wall_ids", s.ids_);
    f("wall_netc", s.netc_);
    f("wall_times", s.times_);
  }
  /// Whether the arrays fit together (sizes add up, ids below n).
  bool consistent(std::size_t n) const {
    std::uint64_t m = 0;
    for (auto q : sizes_) m += q;
    if (keys_.size() != 2 * sizes_.size() || times_.size() != sizes_.size()) return false;
    if (m != masks_.size() || m != ids_.size() || m != netc_.size()) return false;
    return std::all_of(ids_.begin(), ids_.end(), [&](std::uint64_t q) { return q < n; });
  }

 private:
  std::vector<std::uint64_t> keys_, sizes_, masks_, ids_;
  std::vector<std::int64_t> netc_;
  std::vector<double> times_;
};

/// The exact-pre log (see above): a KeyedStack of pre velocities keyed (stream, counter).
class ExactPreLog {
 public:
  /// Whether b differs from a by more than 1e-10 of a's largest component (n values).
  static bool off_by(const double* a, const double* b, int n) {
    double amax = 0.0, d = 0.0;
    for (int k = 0; k < n; ++k) {
      amax = std::fmax(amax, std::fabs(a[k]));
      d = std::fmax(d, std::fabs(a[k] - b[k]));
    }
    return d > 1e-10 * amax;
  }
  /// Forward: keeps the pre velocities a (n values; and b, n more, for a pair) under the
  /// key (stream, generator counter before the draws).
  void push(int stream, std::uint64_t key, const double* a, const double* b, int n) {
    std::vector<double> v(a, a + n);
    if (b) v.insert(v.end(), b, b + n);
    log_.push({static_cast<std::uint64_t>(stream), key}, std::move(v));
    ++pushed_;
  }
  /// Reverse: a (and b, the second half of a pair) are the pre velocities the reverse
  /// computed; replaced by the kept ones, popped, when the top entry is this key's.
  void pop(int stream, std::uint64_t key, double* a, double* b) {
    const std::vector<double>* e = log_.top({static_cast<std::uint64_t>(stream), key});
    if (e == nullptr) return;
    const std::size_t n = e->size();
    if (b) {
      std::copy(e->begin(), e->begin() + static_cast<std::ptrdiff_t>(n / 2), a);
      std::copy(e->begin() + static_cast<std::ptrdiff_t>(n / 2), e->end(), b);
    } else {
      std::copy(e->begin(), e->end(), a);
    }
    log_.pop();
  }
  /// Entries now held.
  std::size_t entries() const { return log_.size(); }
  /// Entries ever pushed.
  std::uint64_t pushed() const { return pushed_; }
  /// Bytes now held (the values, and three words per entry: its key and size).
  std::size_t bytes() const {
    std::size_t b = 0;
    for (const auto& item : log_.items()) b += item.second.size() * sizeof(double) + 3 * sizeof(std::uint64_t);
    return b;
  }
  /// The log as a snapshot's arrays and counter: keys (stream, counter) per entry, values per
  /// entry, the values, entries ever pushed. Written from a const log, read into a log (the
  /// snapshot's arrays validated before: sizes add up, 2 keys per entry).
  template <class Self, class F>
  static void fields(Self& s, F&& f) {
    std::vector<std::uint64_t> keys, sizes;
    std::vector<double> vals;
    if constexpr (std::is_const_v<Self>) {
      for (const auto& [k, v] : s.log_.items()) {
        keys.push_back(k.first);
        keys.push_back(k.second);
        sizes.push_back(v.size());
        vals.insert(vals.end(), v.begin(), v.end());
      }
    }
    f("pre_keys", keys);
    f("pre_sizes", sizes);
    f("pre_vals", vals);
    f("pre_pushed", s.pushed_);
    if constexpr (!std::is_const_v<Self>) {
      s.log_.clear();
      std::size_t at = 0;
      for (std::size_t e = 0; e < sizes.size() && 2 * e + 1 < keys.size() && at + sizes[e] <= vals.size(); ++e) {
        const auto from = vals.begin() + static_cast<std::ptrdiff_t>(at);
        s.log_.push({keys[2 * e], keys[2 * e + 1]}, std::vector<double>(from, from + static_cast<std::ptrdiff_t>(sizes[e])));
        at += sizes[e];
      }
    }
  }

 private:
  KeyedStack<std::pair<std::uint64_t, std::uint64_t>, std::vector<double>> log_;
  std::uint64_t pushed_ = 0;
};

}  // namespace revcol::engine
