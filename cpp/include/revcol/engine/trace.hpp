// The collision trace: how the float engine's run_back knows, without a log, that the
// trajectory it reverses is no longer the forward one.
//
// A reversed run retraces the forward one only within the round-off horizon (docs/engine.md).
// Past it, the reversed trajectory is another trajectory of the same dynamics: every operator
// still conserves energy and momentum, and nothing in the state says that the collisions
// being undone are not the ones that were done. The trace detects it with a few KiB:
//
//  - Each collision has a signature h(n; id_0, ..., id_{n-1}) of its n members (in id order).
//    S, the sum of the signatures of the collisions done (mod 2^64), grows forward and shrinks
//    in reverse. At net collision count m, S is then a function of the multiset of member
//    sets of collisions 1..m: two disjoint collisions processed in either order give the same
//    S once both are done. (The members' collision counts would date each collision too, but
//    they cost 4 mixes more per collision and a wrong multiset is what a divergence makes.)
//  - Forward, S is kept at net counts m on a grid of stride s (a power of two, at least N so
//    that the O(N) conservation check below costs O(1) per collision), and again at m + kOffset.
//    At most kCapacity points are kept: when full, every other one is dropped and s doubles,
//    so the points stay spread evenly over a run of any length.
//  - In reverse, at those counts, S must equal the kept value. A wrong partner, a collision
//    found or missed, a wall mask or a log entry restored into the wrong collision: each
//    changes S (a wrong match has probability 2^-64). Collisions undone in another order than
//    they were done change S between them only, and they do not change the outcome (each
//    collision draws from its own particle's stream at that particle's count): near the
//    horizon a reversed collision's time can move by a fraction of a mean free time, past
//    hundreds of others (measured: 2D, phi = 0.6, walls, two checks 448 collisions apart off
//    and then on again). So a mismatch is a suspect, kConfirm in a row are a divergence,
//    dated at the first, and a run of fewer is counted as a reordering.
//  - The grid point m also keeps the clock of collision m + 1; a reversed run, back at m, has
//    just undone that collision, and its clock's deviation |t - t_kept| measures how far the
//    reversed trajectory has drifted while the collisions are still the same ones (the
//    round-trip error in positions is about v_max |t - t_kept|). The start (m = 0, S = 0) is a
//    grid point from construction: a run back to it compares the whole set at once, where
//    no reordering can hide a wrong collision, so a mismatch there is a divergence at once.
//  - Also in reverse, at each grid point: the energy, and the momentum on periodic axes, must
//    keep their start values within kConserveTol (relative), and an operator that refuses to
//    reverse a post state is a divergence at once.
//
// Forward, a grid point drops every point above it: only the trajectory that led to the
// current state is kept. A forward run never checks (retracing after a reversal diverges
// from the first forward run beyond the horizon, as any run would).
#pragma once
#include <algorithm>
#include <bit>
#include <cstdint>
#include <string>
#include <vector>

#include "revcol/error.hpp"

namespace revcol::engine {

/// Why a reversed run was found off the forward trajectory.
enum class Divergence : std::int64_t {
  none = 0,       ///< not found
  sequence = 1,   ///< the collisions undone are not those done (the trace's sum)
  operator_ = 2,  ///< the operator refused a post state (it can only come from elsewhere)
  energy = 3,     ///< energy off its start value
  momentum = 4,   ///< momentum on a periodic axis off its start value
  overlap = 5,    ///< particles overlap where a reversed run ended (it left the forward path)
};

/// "none", "collision sequence", "operator refused", "energy", "momentum", "particles overlap".
inline const char* to_string(Divergence d) {
  switch (d) {
    case Divergence::sequence: return "collision sequence";
    case Divergence::operator_: return "operator refused";
    case Divergence::energy: return "energy";
    case Divergence::momentum: return "momentum";
    case Divergence::overlap: return "particles overlap";
    default: return "none";
  }
}

/// The collision trace of one simulation (see the header comment).
class CollisionTrace {
 public:
  static constexpr std::int64_t kOffset = 64;      ///< the confirming point's distance above a grid point
  static constexpr std::size_t kCapacity = 256;    ///< grid points kept at most
  static constexpr std::uint64_t kMinStride = 128; ///< the grid's smallest stride
  static constexpr double kConserveTol = 1e-8;     ///< relative energy / momentum change that is a divergence
  static constexpr std::uint64_t kConfirm = 3;     ///< mismatches in a row that are a divergence
  static constexpr std::int64_t kNever = INT64_MIN;  ///< diverged_at / verified_at: not yet

  /// A trace for n particles (stride the power of two >= max(kMinStride, n)); with a start,
  /// net count 0 with S = 0 is kept as a grid point.
  explicit CollisionTrace(std::size_t n = 0, bool start = false)
      : stride_(std::bit_ceil(std::max<std::uint64_t>(kMinStride, n))) {
    if (start) points_.push_back({0, 0, 0, 1, 0.0});
  }

  /// The signature of a collision of n members (ids ascending): one mix for a pair.
  static std::uint64_t signature(const int* ids, int n) {
    const auto id = [&](int u) { return static_cast<std::uint64_t>(static_cast<std::uint32_t>(ids[u])); };
    if (n == 2) return mix((id(0) << 32 | id(1)) + 0x9E3779B97F4A7C15ull);
    std::uint64_t h = mix(static_cast<std::uint64_t>(n));  // groups (n > 2): a chain over the members
    for (int u = 0; u < n; ++u) h = mix(h ^ id(u));
    return h;
  }

  /// Adds (forward) or removes (reversed) one collision's signature.
  void apply(std::uint64_t sig, bool reversed) { sum_ += reversed ? 0 - sig : sig; }

  /// Whether net count m is a grid point, a confirming point or just above a grid point
  /// (where record() and check() do something).
  bool on_grid(std::int64_t m) const {
    const std::uint64_t mask = stride_ - 1;
    const auto u = static_cast<std::uint64_t>(m);
    return (u & mask) == 0 || ((u - kOffset) & mask) == 0 || ((u - 1) & mask) == 0;
  }

  /// Forward, the collision that took the net count to m done at time t (call when
  /// on_grid(m)): keeps S at m, S at a confirming point, or t for the grid point m - 1.
  void record(std::int64_t m, double t);

  /// Reversed, the collision m + 1 undone at time t (call when on_grid(m)): compares S and the
  /// clock with the kept values; returns whether m is a grid point, where the caller checks
  /// conservation.
  bool check(std::int64_t m, double t);

  /// At the end of a reversed run at net count m: a mismatch at a grid point that is the
  /// start (0) of the kept trajectory is a divergence without confirmation.
  void check_start(std::int64_t m);

  /// Marks a divergence found at net count m for `why` (the first one found is kept).
  void diverge(std::int64_t m, Divergence why) {
    if (reason_ != Divergence::none) return;
    reason_ = why;
    diverged_at_ = m;
  }

  /// Net count of the first point found off (kNever if none).
  std::int64_t diverged_at() const { return diverged_at_; }
  /// Net count of the last point found on in a reversed run (kNever if none).
  std::int64_t verified_at() const { return verified_at_; }
  /// Why it diverged (none if it has not).
  Divergence reason() const { return reason_; }
  /// Runs of mismatches shorter than kConfirm (collisions undone in another order).
  std::uint64_t reorderings() const { return reorderings_; }
  /// Largest |t - t_kept| at the grid points of the current reversed pass (0: none checked).
  double clock_deviation() const { return clock_dev_; }
  /// The grid's stride now.
  std::uint64_t stride() const { return stride_; }
  /// Grid points kept.
  std::size_t points() const { return points_.size(); }
  /// Bytes held.
  std::size_t bytes() const { return points_.capacity() * sizeof(Point); }

  /// The trace as one array (the checkpoint's `trace`): a header of kHeader words, then
  /// kWords per point.
  std::vector<std::uint64_t> save() const;
  /// The trace from save()'s array; throws InvalidArgument naming what is wrong (nothing changes).
  static CollisionTrace load(const std::vector<std::uint64_t>& a, std::size_t n);

 private:
  struct Point {
    std::int64_t m = 0;              ///< a grid point (a multiple of the stride)
    std::uint64_t at = 0, above = 0; ///< S at m and at m + kOffset
    std::uint64_t have = 0;          ///< bit 0: at kept, bit 1: above kept, bit 2: t_next kept
    double t_next = 0.0;             ///< the time of collision m + 1
  };
  static constexpr std::size_t kHeader = 9;
  static constexpr std::size_t kWords = 5;

  /// splitmix64's finaliser: a bijection of 64-bit words that mixes every bit.
  static std::uint64_t mix(std::uint64_t z) {
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  /// The point at grid count g, or nullptr.
  Point* find(std::int64_t g);
  /// One comparison's outcome.
  void verdict(std::int64_t m, bool same);

  std::uint64_t sum_ = 0;
  std::uint64_t stride_;
  std::vector<Point> points_;  // ascending m
  std::int64_t suspect_ = kNever;  // the first mismatch of the current run of them
  std::uint64_t misses_ = 0;       // mismatches in a row
  std::uint64_t reorderings_ = 0;
  Divergence reason_ = Divergence::none;
  std::int64_t diverged_at_ = kNever, verified_at_ = kNever;
  double clock_dev_ = 0.0;
};

}  // namespace revcol::engine
