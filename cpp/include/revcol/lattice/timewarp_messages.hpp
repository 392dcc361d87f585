// The parallel lattice engine's messages (timewarp.hpp): after each event an LP processed, what
// it tells the others. A collision's authority (the LP that owned the key particle before it)
// sends each particle's whole post state to every other LP whose band held it before or holds
// it after, and refuses a group that reaches beyond its band; any other LP keeps its own result
// as a guess for the authority's message to confirm. After a crossing or a wall, an owned
// particle entering another band is sent there. Lazy cancellation: a message the LP sent before
// a rollback and sends again, the same bits at the same key, stands (no anti-message).
// Included at the end of timewarp.hpp: TimeWarp's out-of-class members.
#pragma once
#include <cstdint>
#include <string>
#include <utility>

#include "revcol/lattice/timewarp.hpp"

namespace revcol::lattice {

template <class Engine>
void TimeWarp<Engine>::after_event(Lp& lp) {
  const EventKey k = lp.notes.key;
  if (obs_ && sv_.owner(region_before(lp, k.id)) != lp.me) lp.seen.drop_event(k);  // only the authority's calls count
  if (lp.notes.type == LpNotes::coll) {
    const int key_owner = sv_.owner(region_before(lp, k.id));
    if (key_owner == lp.me) {
      check_reach(lp, k);
      for (int id : lp.notes.ids) {
        const std::uint64_t to = (sv_.views(region_before(lp, id)) | sv_.views(lp.eng.region(id))) & ~(std::uint64_t{1} << lp.me);
        if (to != 0) send(lp, k, id, to);
      }
    } else {
      for (int id : lp.notes.ids) lp.guesses[{k, id}] = lp.eng.record(id);
    }
  } else {
    // a crossing or a wall: an owned particle entering another band is sent there
    for (int id : moved(lp)) {
      if (sv_.owner(region_before(lp, id)) != lp.me) continue;
      const std::uint64_t to = sv_.views(lp.eng.region(id)) & ~sv_.views(region_before(lp, id)) & ~(std::uint64_t{1} << lp.me);
      if (to != 0) send(lp, k, id, to);
    }
  }
  park_leavers(lp, k);
}

// a collision this LP is the authority of: every member must be far enough inside its band
// that all the bodies the event read are held
template <class Engine>
void TimeWarp<Engine>::check_reach(Lp& lp, const EventKey& k) {
  if (lp.notes.ids.size() <= 2) return;  // a pair of an owned key particle: within reach by W
  const auto& u = lp.eng.units();
  for (int id : lp.notes.ids) {
    const std::int64_t x = record_at(lp.eng.record(id), k.t, u)[static_cast<std::size_t>(c_.axis)];
    if (sv_.outside(lp.me, x) > sv_.band() - reach_)
      lp.refused[k] = "a group collision of " + std::to_string(lp.notes.ids.size()) + " particles at tick " + std::to_string(k.t) +
                      " reaches beyond logical process " + std::to_string(lp.me) + "'s band (use fewer logical processes)";
  }
}

template <class Engine>
void TimeWarp<Engine>::send(Lp& lp, const EventKey& k, int id, std::uint64_t to) {
  const Record r = lp.eng.record(id);
  for (int y = 0; y < c_.lps; ++y) {
    if ((to >> y & 1u) == 0) continue;
    // lazy cancellation: the same message sent before the rollback stands
    auto it = lp.lazy.lower_bound(MKey{k, 0});
    while (it != lp.lazy.end() && it->first.first == k && !(it->second.id == id && it->second.to == y && it->second.rec == r)) ++it;
    if (it != lp.lazy.end() && it->first.first == k) {
      ++lp.st.reused;
      lp.sent.insert(lp.lazy.extract(it));
      continue;
    }
    Message m{k, id, y, (static_cast<std::uint64_t>(lp.me) << 48) + ++lp.nsent, false, r};
    lp.sent.emplace(MKey{k, m.serial}, m);
    ++lp.st.messages;
    post(std::move(m));
  }
}

}  // namespace revcol::lattice
