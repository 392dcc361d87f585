// What a logical process (LP) of the parallel lattice engine and its engine say to each other
// (ARCHITECTURE.md "The parallel engine"; timewarp.hpp runs the LPs): an event's key, one
// particle's whole state as a message carries it, and the notes the engine leaves on each event
// it processes for an LP; the counts of a parallel run.
#pragma once
#include <array>
#include <compare>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "revcol/lattice/geometry.hpp"

namespace revcol::lattice {

struct LpSeen;

/// An event's key in the engine's total order (forward): its tick, its queue kind (0 crossings,
/// 1 walls, 2 + lo a collision of the pair whose lower id is lo) and the id of the particle whose
/// slot came up (a collision's lo). A message is keyed by the event that wrote it.
struct EventKey {
  std::int64_t t = 0;
  std::int32_t kind = 0;
  std::int32_t id = 0;
  friend auto operator<=>(const EventKey&, const EventKey&) = default;
  /// The least key after this one.
  EventKey next() const noexcept { return EventKey{t, kind, id + 1}; }
  /// The least key of tick t (before every event at t).
  static constexpr EventKey tick_start(std::int64_t t) noexcept {
    return EventKey{t, std::numeric_limits<std::int32_t>::min(), std::numeric_limits<std::int32_t>::min()};
  }
  /// A key after every event's ("none").
  static constexpr EventKey never() noexcept { return EventKey{std::numeric_limits<std::int64_t>::max(), 0, 0}; }
  bool is_never() const noexcept { return t == std::numeric_limits<std::int64_t>::max(); }
};

/// One particle's whole state: its line (anchor point, velocity, anchor tick), the one-tick cache
/// of its last reflection (the line before it, and its tick), its Philox counter, its bits-back
/// integer and its collision count. Two records of one state are equal field by field (the lines
/// anchored alike: both written by the same event).
template <std::size_t D, class Bits>
struct ParticleRecordN {
  VecN<D> x{}, v{};
  std::int64_t ta = 0;
  VecN<D> pre_x{}, pre_v{};
  std::int64_t pre_ta = 0, wall_tick = 0;
  Bits X;
  std::uint64_t ctr = 0, pc = 0;
  friend bool operator==(const ParticleRecordN&, const ParticleRecordN&) = default;
};

/// What the engine noted about the event an LP's run has just processed, and how that run stops.
struct LpNotes {
  enum Type : std::uint8_t { none = 0, cross = 1, wall = 2, coll = 3 };
  EventKey key;
  Type type = none;                                   ///< none: a stale slot recomputed
  std::vector<int> ids;                               ///< a collision's particles by id (a group's members)
  std::vector<std::array<std::int64_t, 4>> migrations;  ///< (tick, id, from, to) region changes in the event
  void (*after)(void*) = nullptr;  ///< called after each event (the notes filled), between two events
  void* ctx = nullptr;             ///< after's argument
  EventKey stop;                   ///< lp_run: stop before this key
  std::size_t max = 1, done = 0;   ///< lp_run: stop after max events; the events done
  std::string error;               ///< lp_run: an engine error at `key` (the event undone, the run stopped there)
  std::array<std::size_t, 7> marks{};  ///< (the engine's journal sizes before the event under way)
  bool in_after = false;           ///< (after is running: its exceptions are not the engine's)
  LpSeen* seen = nullptr;          ///< an observed run: where the engine keeps its observer calls (lp_seen.hpp)
  const std::vector<std::uint8_t>* mine = nullptr;  ///< per fine region: this LP owns it (a field's wall momentum counts only the owner's reflections)
};

/// The counts of a parallel run (all LPs).
struct TimeWarpStats {
  std::uint64_t events = 0;     ///< queue pops that changed a state (rolled back ones too)
  std::uint64_t stale = 0;      ///< queue pops of stale slots
  std::uint64_t rollbacks = 0;  ///< rollbacks (stragglers and cancellations)
  std::uint64_t undone = 0;     ///< journal entries they undid
  std::uint64_t messages = 0;   ///< messages sent
  std::uint64_t anti = 0;       ///< anti-messages sent
  std::uint64_t confirmed = 0;  ///< messages that confirmed a guess
  std::uint64_t written = 0;    ///< messages written into a view
  std::uint64_t blocked = 0;    ///< writes that left a view inconsistent (the LP waited for a rollback)
  std::uint64_t reused = 0;     ///< messages a re-execution sent again as they were (lazy cancellation)
  std::uint64_t gvts = 0;       ///< GVT computations
  double gvt_seconds = 0.0;     ///< seconds in the GVT step (worker 0 alone, the others at the barrier)
  /// The LPs' journals together as each GVT found them, before it freed what it committed: the
  /// most bytes, and the sums of bytes and of entries over the GVTs (bytes per entry held: the
  /// memory an event costs until it is committed, state saving's saved states included).
  std::uint64_t journal_peak_bytes = 0, journal_bytes_at_gvts = 0, journal_entries_at_gvts = 0;
  std::vector<std::uint64_t> lp_events;  ///< per LP: events processed
  void add(const TimeWarpStats& o) {
    events += o.events, stale += o.stale, rollbacks += o.rollbacks, undone += o.undone, messages += o.messages;
    anti += o.anti, confirmed += o.confirmed, written += o.written, blocked += o.blocked, reused += o.reused;
  }
};

}  // namespace revcol::lattice
