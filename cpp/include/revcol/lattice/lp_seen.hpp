// Observation on the parallel lattice engine (timewarp.hpp): the observer's calls an LP's engine
// makes for the events it processes are kept, not made (lp_view.hpp). An LP keeps an event's
// calls only when it is the event's authority (its result is the sequential engine's once its
// view is right); a rollback drops the calls of the events it undoes; at each GVT the calls of the
// committed events, from every LP, go to one observer in key order. The observer so sees the
// sequential engine's calls in the sequential engine's order, and its results are the sequential
// run's bit for bit (test_lattice_timewarp, test_parallel.py).
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <tuple>
#include <vector>

#include "revcol/engine/observe.hpp"
#include "revcol/lattice/lp.hpp"

namespace revcol::lattice {

/// The observer's calls of one LP's processed events, in processing (key) order.
struct LpSeen {
  enum Kind : std::uint8_t { pair, group, wall };
  struct Call {
    EventKey key;            // the event's
    double t = 0.0;          // the observer's time of it
    Kind kind = pair;
    unsigned axes = 0;       // a wall's axes
    std::uint32_t n = 0;     // the particles: ids at [at, at + n), positions and velocities at [at D, (at + n) D)
    std::size_t at = 0;
  };
  int dim = 2;
  std::vector<Call> calls;
  std::vector<int> ids;
  std::vector<double> x, v;

  /// The event at key k called the observer (kind) at time t with n particles.
  void add(const EventKey& k, Kind kind, double t, unsigned axes, std::size_t n, const int* id, const double* xs, const double* vs) {
    calls.push_back(Call{k, t, kind, axes, static_cast<std::uint32_t>(n), ids.size()});
    ids.insert(ids.end(), id, id + n);
    x.insert(x.end(), xs, xs + n * static_cast<std::size_t>(dim));
    v.insert(v.end(), vs, vs + n * static_cast<std::size_t>(dim));
  }
  /// Drops the calls of events after key k (a rollback undid them).
  void drop_after(const EventKey& k) {
    std::size_t m = calls.size();
    while (m > 0 && k < calls[m - 1].key) --m;
    cut(m);
  }
  /// Drops the calls of the event at key k, the last processed (the LP was not its authority).
  void drop_event(const EventKey& k) {
    std::size_t m = calls.size();
    while (m > 0 && calls[m - 1].key == k) --m;
    cut(m);
  }
  /// The calls before key k (committed).
  std::size_t before(const EventKey& k) const {
    return static_cast<std::size_t>(std::lower_bound(calls.begin(), calls.end(), k, [](const Call& c, const EventKey& y) { return c.key < y; }) -
                                    calls.begin());
  }
  /// Forgets the first m calls (fed to the observer).
  void forget(std::size_t m) {
    if (m == 0) return;
    const std::size_t base = m < calls.size() ? calls[m].at : ids.size(), d = static_cast<std::size_t>(dim);
    calls.erase(calls.begin(), calls.begin() + static_cast<std::ptrdiff_t>(m));
    ids.erase(ids.begin(), ids.begin() + static_cast<std::ptrdiff_t>(base));
    x.erase(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(base * d));
    v.erase(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(base * d));
    for (Call& c : calls) c.at -= base;
  }
  /// Makes call c to the observer.
  void replay(const Call& c, engine::Observer& o) const {
    const std::size_t d = static_cast<std::size_t>(dim);
    const double *xs = x.data() + c.at * d, *vs = v.data() + c.at * d;
    if (c.kind == pair) o.pair_at(c.t, ids[c.at], ids[c.at + 1], xs, xs + d, vs, vs + d);
    else if (c.kind == group) o.group_at(c.t, static_cast<int>(c.n), ids.data() + c.at, xs, vs);
    else o.wall_at(c.t, ids[c.at], xs, vs, c.axes);
  }

 private:
  void cut(std::size_t m) {
    if (m == calls.size()) return;
    const std::size_t base = calls[m].at, d = static_cast<std::size_t>(dim);
    calls.resize(m);
    ids.resize(base);
    x.resize(base * d);
    v.resize(base * d);
  }
};

/// Feeds observer o the calls before key k of every LP, in key order (an event's calls from one
/// LP, the authority's), and forgets them.
inline void feed_committed(const std::vector<LpSeen*>& lps, const EventKey& k, engine::Observer& o) {
  std::vector<std::tuple<EventKey, std::size_t, std::size_t>> order;  // (key, LP, call)
  for (std::size_t m = 0; m < lps.size(); ++m)
    for (std::size_t c = 0, e = lps[m]->before(k); c < e; ++c) order.emplace_back(lps[m]->calls[c].key, m, c);
  std::sort(order.begin(), order.end());
  for (const auto& [key, m, c] : order) lps[m]->replay(lps[m]->calls[c], o);
  for (LpSeen* s : lps) s->forget(s->before(k));
}

}  // namespace revcol::lattice
