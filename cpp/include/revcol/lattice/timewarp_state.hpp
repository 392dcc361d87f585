// The committed state of a parallel lattice run (timewarp.hpp), assembled from its logical
// processes' engines as the sequential engine's snapshot: each particle from the LP that owns it,
// the rare log and the group entries the union of the LPs' (an entry two LPs hold must be the
// same), the collision count from the particles' counts. A run back's LPs (the reversed frame,
// Config::back): each record read in the forward frame, and the log and group entries of collisions
// the run took back (keyed by counts above their particles' counts: an LP that did not hold the
// particles then still has them) left out.
#pragma once
#include <algorithm>
#include <cstdint>
#include <map>
#include <stdexcept>
#include <utility>
#include <vector>

#include "revcol/lattice/field.hpp"
#include "revcol/lattice/geometry.hpp"
#include "revcol/lattice/slab_views.hpp"
#include "revcol/lattice/state.hpp"

namespace revcol::lattice {

/// A particle record's point at tick t (wrapped on periodic axes).
template <class Record, std::size_t D>
VecN<D> record_at(const Record& r, std::int64_t t, const UnitsN<D>& u) {
  VecN<D> x;
  for (std::size_t k = 0; k < D; ++k) {
    const __int128 y = field_point(r.x[k], r.v[k], u.gravity[k] / 2, t - r.ta);  // (a line without a field: h = 0)
    x[k] = u.wall[k] ? static_cast<std::int64_t>(y) : wrap(y, u.L[k]);
  }
  return x;
}

/// The velocity of a record's line at tick t (a field's changes by g per tick along its axis).
template <class Record, std::size_t D>
VecN<D> record_velocity(const Record& r, std::int64_t t, const UnitsN<D>& u) {
  VecN<D> v = r.v;
  for (std::size_t k = 0; k < D; ++k)
    if (u.gravity[k] != 0) v[k] += u.gravity[k] * (t - r.ta);
  return v;
}

/// The state at tick `clock` of LPs (their engines, LP m's at m) that have processed every event
/// up to it and none after, by particle id; `back`: LPs of a run back (clock in their frame).
/// Its counters are zero but a field's wall momentum (a physical sum, the column's weight): the
/// state's `base` (the counters the LPs were built with) and what each LP added to it since.
template <class Engine>
auto committed_state(const std::vector<const Engine*>& lps, const SlabViews& sv, std::int64_t clock, bool back = false,
                     const typename Engine::Snapshot* base = nullptr) {
  using Snapshot = typename Engine::Snapshot;
  constexpr std::size_t D = Engine::D;
  Snapshot s = lps.front()->snapshot();
  const std::size_t n = s.x.size();
  s.clock = back ? -clock : clock;
  s.bits.clear();
  std::vector<int> from(n, -1);
  std::vector<std::vector<std::uint64_t>> words(n);
  for (std::size_t m = 0; m < lps.size(); ++m)
    for (std::size_t id = 0; id < n; ++id) {
      const Engine& e = *lps[m];
      const int i = static_cast<int>(id);
      if (!e.held(i) || sv.owner(e.region(i)) != static_cast<int>(m)) continue;
      if (from[id] >= 0) throw std::logic_error("parallel lattice engine: a particle owned by two LPs (a bug)");
      from[id] = static_cast<int>(m);
      const auto r = e.record(i);
      s.x[id] = record_at(r, clock, s.units);
      s.v[id] = back ? neg(record_velocity(r, clock, s.units)) : record_velocity(r, clock, s.units);
      s.streams[id] = r.ctr;
      s.particle_collisions[id] = r.pc;
      const auto w = r.X.words();
      words[id].assign(w.begin(), w.end());
    }
  for (std::size_t id = 0; id < n; ++id) {
    if (from[id] < 0) throw std::logic_error("parallel lattice engine: a particle no LP owns (a bug)");
    s.bits.insert(s.bits.end(), words[id].begin(), words[id].end());
    s.bits_size[id] = words[id].size();
  }
  std::map<std::pair<std::uint32_t, std::uint64_t>, LogEntry> log;
  std::map<std::pair<int, std::uint64_t>, GroupEntryN<D>> groups;
  auto merge = [](auto& map, const auto& key, const auto& value) {
    const auto [it, fresh] = map.emplace(key, value);
    if (!fresh && !(it->second == value)) throw std::logic_error("parallel lattice engine: two LPs disagree on a rare-log entry (a bug)");
  };
  for (const Engine* e : lps) {
    const Snapshot t = e->snapshot();
    for (const LogEntry& x : t.log)
      if (x.count <= s.particle_collisions[x.particle]) merge(log, std::make_pair(x.particle, x.count), x);
    for (const GroupEntryN<D>& g : t.groups) {
      const auto at = static_cast<std::size_t>(std::find(g.members.begin(), g.members.end(), g.drawer) - g.members.begin());
      if (g.counts[at] <= s.particle_collisions[static_cast<std::size_t>(g.drawer)]) merge(groups, std::make_pair(g.drawer, g.counts[at]), g);
    }
  }
  s.log.clear();
  for (const auto& [k, x] : log) s.log.push_back(x);
  s.groups.clear();
  for (const auto& [k, g] : groups) s.groups.push_back(g);
  // the collision count: every pair adds one to two counts, a group of m to m
  std::uint64_t sum = 0;
  for (std::uint64_t pc : s.particle_collisions) sum += pc;
  for (const auto& g : s.groups) sum -= g.members.size() - 2;
  s.collisions = sum / 2;
  s.counters = Counters{};
  if (base != nullptr) {  // (each LP's own rollbacks took off what they undid: field_impulse)
    const auto& b = base->counters.field_wall_impulse;
    auto& w = s.counters.field_wall_impulse;
    for (std::size_t at : {std::size_t{0}, std::size_t{2}}) {
      const unsigned __int128 b0 = (static_cast<unsigned __int128>(b[at + 1]) << 64) | b[at];
      unsigned __int128 sum = b0;
      for (const Engine* e : lps) {
        const auto& c = e->counters().field_wall_impulse;
        sum += ((static_cast<unsigned __int128>(c[at + 1]) << 64) | c[at]) - b0;  // (modular: exact)
      }
      w[at] = static_cast<std::uint64_t>(sum);
      w[at + 1] = static_cast<std::uint64_t>(sum >> 64);
    }
  }
  return s;
}

}  // namespace revcol::lattice
