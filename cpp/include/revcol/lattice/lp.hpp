// What a logical process (LP) of the parallel lattice engine and its engine say to each other
// (ARCHITECTURE.md "The parallel engine"; timewarp.hpp runs the LPs): an event's key, one
// particle's whole state as a message carries it, and the notes the engine leaves on each event
// it processes for an LP.
#pragma once
#include <array>
#include <compare>
#include <cstdint>
#include <string>
#include <vector>

#include "revcol/lattice/geometry.hpp"

namespace revcol::lattice {

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
  std::array<std::size_t, 6> marks{};  ///< (the engine's journal sizes before the event under way)
  bool in_after = false;           ///< (after is running: its exceptions are not the engine's)
};

}  // namespace revcol::lattice
