// The parallel family of revcol-bench: the parallel lattice engine (timewarp.hpp) against the
// sequential engine on the same collisions, from one warmed-up state (a collision per
// particle): every variant runs to the tick of the n-th collision of the sequential run and must
// end on its state bit for bit (same_<variant> = 1). The variants run interleaved, `rounds`
// times (REVCOL_PARALLEL=rounds=R), each timed from a fresh engine:
//   seq             the sequential engine, its default search (lists in 3D);
//   seq_cells       the sequential engine on the cell grid;
//   K<k>_w<w>       k logical processes on w worker threads (lazy cancellation, no window),
//                   rolled back by reverse computation; K<k>_w<w>_ss1 / _ss2 the same rolled back
//                   by state saving (how=rc:ss1:ss2: SS1 the touched particles' whole records,
//                   SS2 the lines and X an event changes; the paper's comparison); the LPs search as
//                   seq does (lists in 3D), or (search=auto:cells) _cells: on the cell grid;
// reported as medians with their ranges: <variant>_per_s (collisions per second), speedup_<v>
// (over seq, the same round), and from the last round events_per_collision_<v> (events processed
// per collision), rollbacks_per_1k_<v>, undone_per_collision_<v>, messages_per_collision_<v>,
// collisions_per_event_<v> (committed collisions over the LPs' events processed, crossings too),
// stale_per_collision_<v>, gvts_<v> (GVT computations), gvt_s_per_collision_<v> (seconds in
// the GVT step, worker 0 alone, from the last round), journal_peak_bytes_<v> and
// journal_bytes_per_entry_<v> (the LPs' journals as the GVTs found them: the most bytes, and bytes
// per entry held, state saving's saved states included), worker_imbalance_<v> (the busiest
// worker's events over the mean: its LPs as workers.hpp's share_of gives them) and seconds_<v> (the
// median run time); band_over_L (the band W over the slabs' axis) and ticks, for the
// performance model (bench/parallel_model.py).
// back=1: every variant also runs back, from the forward run's end to its start tick (seq:
// run_back, which flips its frame and rebuilds its search twice; K<k>_w<w>: the parallel engine in
// run_back's frame, Config::back), right after its forward run, and must end on seq's state bit
// for bit (same_back_<v>): <v>_back_per_s, speedup_back_<v> (over seq's run_back, the same round),
// speedup_back_net_<v> (over seq's run_back less its two rebuilds, seconds_seq_flips, timed on a
// run back of no collision), seconds_back_<v>, events_back_per_collision_<v>,
// rollbacks_back_per_1k_<v>, undone_back_per_collision_<v>.
// Settings: REVCOL_PARALLEL=rounds=3,lps=2:4,workers=1:2,window=0,gvt=512,batch=64,lazy=1,how=rc,
// search=auto,observe=0,back=0 (lps, workers, how, search: colon-separated lists; every pair with
// workers <= lps is a variant); observe=1: every variant observes the run (an observer started at
// the warmed state; its end checked bit for bit too).
//
//   revcol-bench --bench parallel/d2/n1000000/phi0.5 --collisions 2000000
#include <algorithm>
#include <chrono>
#include <map>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "bench.hpp"
#include "revcol/lattice/engine.hpp"
#include "revcol/lattice/timewarp.hpp"

namespace revcol::bench {
namespace {

namespace la = revcol::lattice;

template <std::size_t D>
using EngineOf = std::conditional_t<D == 2, la::LatticeEngine, la::LatticeEngine3D>;

struct ParCase {
  std::size_t n;
  double phi;
};

std::vector<std::string> split_list(const std::string& v) {
  std::vector<std::string> out;
  std::size_t at = 0;
  while (at <= v.size()) {
    const std::size_t end = std::min(v.find(':', at), v.size());
    out.push_back(v.substr(at, end - at));
    at = end + 1;
  }
  return out;
}

la::Rollback rollback_of(const std::string& h) {
  if (h == "ss1") return la::Rollback::save_all;
  if (h == "ss2") return la::Rollback::save_changes;
  if (h != "rc") throw std::invalid_argument("REVCOL_PARALLEL how: rc, ss1 or ss2, not '" + h + "'");
  return la::Rollback::reverse;
}

std::vector<int> int_list(const std::string& v) {
  std::vector<int> out;
  for (const std::string& x : split_list(v)) out.push_back(std::stoi(x));
  return out;
}

template <std::size_t D>
std::vector<Metric> run_parallel(const ParCase& c, std::uint64_t nc) {
  int rounds = 3, gvt = 512, batch = 64, lazy = 1, observe = 0, back = 0;
  std::int64_t window = 0;
  std::vector<int> lps{2, 4}, workers{1, 2};
  std::vector<std::string> hows{"rc"}, searches{"auto"};
  apply_settings("REVCOL_PARALLEL", "rounds, lps, workers, window, gvt, batch, lazy, how, search, observe, back", [&](const std::string& k, const std::string& v) {
    if (k == "rounds") rounds = std::stoi(v);
    else if (k == "lps") lps = int_list(v);
    else if (k == "workers") workers = int_list(v);
    else if (k == "window") window = std::stoll(v);
    else if (k == "gvt") gvt = std::stoi(v);
    else if (k == "batch") batch = std::stoi(v);
    else if (k == "lazy") lazy = std::stoi(v);
    else if (k == "how") hows = split_list(v);
    else if (k == "search") searches = split_list(v);
    else if (k == "observe") observe = std::stoi(v);
    else if (k == "back") back = std::stoi(v);
    else return false;
    return true;
  });
  la::LatticeConfigN<D> cfg;
  cfg.seed = 1;
  const la::LatticeStartN<D> st = la::random_start(cfg, c.n, c.phi, 1, D == 2 && c.phi > 0.35 ? "crystal" : "auto");
  EngineOf<D> e(st.units, st.x, st.v, cfg.seed, la::operator_for(st.units));
  e.run(c.n, la::tick_limit - 1);  // warm up
  if (observe != 0) e.observe(revcol::engine::ObserveConfig{});  // every variant observes (committed events, in parallel)
  const la::SnapshotN<D> s0 = e.snapshot();
  e.run(nc, la::tick_limit - 1);
  const std::int64_t until = e.clock();
  e.run(~std::uint64_t{0}, until);
  const la::SnapshotN<D> want = e.snapshot();
  using clock = std::chrono::steady_clock;

  struct Variant {
    Variant(std::string s, int k_, int w_, la::Rollback h = la::Rollback::reverse, double sh = -1.0)
        : name(std::move(s)), k(k_), w(w_), how(h), shell(sh) {}
    std::string name;
    int k = 0, w = 0;  // k = 0: sequential (w = 1: cells)
    la::Rollback how = la::Rollback::reverse;
    double shell = -1.0;  // the LPs' search: -1 the sequential engine's (automatic), 0 cells
    std::vector<double> rate{}, speedup{};
    bool same = true;
    la::TimeWarpStats st{};
    std::vector<double> seconds{};
    std::vector<double> back_rate{}, back_speedup{}, back_net{}, back_seconds{};  // back=1
    bool back_same = true;
    la::TimeWarpStats back_st{};
  };
  la::SnapshotN<D> want_back;  // seq's run back (back=1)
  bool have_back = false;
  std::vector<double> flips;  // seq: a run back of no collision (its two rebuilds), seconds
  std::vector<Variant> vs{{"seq", 0, 0}, {"seq_cells", 0, 1}};
  double band = 0.0;
  for (int k : lps)
    for (int w : workers)
      for (const std::string& h : hows)
        for (const std::string& sr : searches) {
          if (sr != "auto" && sr != "cells") throw std::invalid_argument("REVCOL_PARALLEL search: auto or cells, not '" + sr + "'");
          if (w <= k)
            vs.push_back({"K" + std::to_string(k) + "_w" + std::to_string(w) + (h == "rc" ? "" : "_" + h) + (sr == "auto" ? "" : "_cells"), k, w,
                          rollback_of(h), sr == "auto" ? -1.0 : 0.0});
        }
  const auto config = [&](const Variant& v, bool back_run) {
    typename la::TimeWarp<EngineOf<D>>::Config tc;
    tc.lps = v.k;
    tc.workers = v.w;
    tc.window = window;
    tc.gvt_every = static_cast<std::uint64_t>(gvt);
    tc.batch = batch;
    tc.lazy = lazy != 0;
    tc.how = back_run ? la::Rollback::reverse : v.how;  // (a run back rolls back by reverse computation)
    tc.shell = v.shell;
    tc.back = back_run;
    return tc;
  };
  for (int r = 0; r < rounds; ++r) {
    double base = 0.0, base_back = 0.0, base_net = 0.0;
    for (Variant& v : vs) {
      double seconds = 0.0;
      if (v.k == 0) {
        EngineOf<D> s(s0, la::operator_for(s0.units, s0.law));
        if (v.w == 1) s.set_list_shell(0.0);
        const auto t0 = clock::now();
        s.run(~std::uint64_t{0}, until);
        seconds = seconds_since(t0);
        v.same = v.same && la::same_state(s.snapshot(), want) && s.snapshot().observer == want.observer;
      } else {
        la::TimeWarp<EngineOf<D>> tw(s0, config(v, false));
        const auto t0 = clock::now();
        tw.run_until(until);
        seconds = seconds_since(t0);
        const la::SnapshotN<D> got = tw.snapshot();
        EngineOf<D> synced(got, la::operator_for(got.units, got.law));  // (as run_parallel: the observation synced at the end)
        synced.sync_observation();
        v.same = v.same && la::same_state(got, want) && synced.snapshot().observer == want.observer;
        v.st = tw.stats();
        band = static_cast<double>(tw.band());
      }
      v.seconds.push_back(seconds);
      const double rate = static_cast<double>(want.collisions - s0.collisions) / seconds;
      if (v.name == "seq") base = rate;
      v.rate.push_back(rate);
      v.speedup.push_back(rate / base);
      if (back == 0) continue;
      // back, from the forward run's end to its start tick
      la::SnapshotN<D> got;
      if (v.k == 0) {
        EngineOf<D> s(want, la::operator_for(want.units, want.law));
        if (v.w == 1) s.set_list_shell(0.0);
        auto t0 = clock::now();
        s.run_back(0, s0.clock);
        seconds = seconds_since(t0);
        got = s.snapshot();
        if (v.name == "seq") {
          EngineOf<D> f(want, la::operator_for(want.units, want.law));
          t0 = clock::now();
          f.run_back(0, want.clock);  // (no collision: the two flips, each a rebuild of the search)
          flips.push_back(seconds_since(t0));
        }
      } else {
        la::TimeWarp<EngineOf<D>> tw(want, config(v, true));
        const auto t0 = clock::now();
        tw.run_until(-s0.clock);
        seconds = seconds_since(t0);
        got = tw.snapshot();
        v.back_st = tw.stats();
      }
      if (!have_back) want_back = got, have_back = true;
      v.back_same = v.back_same && la::same_state(got, want_back);
      v.back_seconds.push_back(seconds);
      const double brate = static_cast<double>(want.collisions - got.collisions) / seconds;
      if (v.name == "seq") base_back = brate, base_net = static_cast<double>(want.collisions - got.collisions) / (seconds - flips.back());
      v.back_rate.push_back(brate);
      v.back_speedup.push_back(brate / base_back);
      v.back_net.push_back(brate / base_net);
    }
  }
  std::vector<Metric> out;
  const auto add_spread = [&out](const std::string& name, const std::vector<double>& x) {  // median, _min, _max
    out.push_back({name, median(x)});
    out.push_back({name + "_min", *std::min_element(x.begin(), x.end())});
    out.push_back({name + "_max", *std::max_element(x.begin(), x.end())});
  };
  const double coll = static_cast<double>(want.collisions - s0.collisions);
  for (const Variant& v : vs) {
    add_spread(v.name + "_per_s", v.rate);
    add_spread("speedup_" + v.name, v.speedup);
    out.push_back({"same_" + v.name, v.same ? 1.0 : 0.0});
    out.push_back({"seconds_" + v.name, median(v.seconds)});
    if (v.k == 0) continue;
    out.push_back({"events_per_collision_" + v.name, static_cast<double>(v.st.events) / coll});
    out.push_back({"rollbacks_per_1k_" + v.name, 1000.0 * static_cast<double>(v.st.rollbacks) / coll});
    out.push_back({"undone_per_collision_" + v.name, static_cast<double>(v.st.undone) / coll});
    out.push_back({"messages_per_collision_" + v.name, static_cast<double>(v.st.messages) / coll});
    out.push_back({"anti_per_collision_" + v.name, static_cast<double>(v.st.anti) / coll});
    out.push_back({"collisions_per_event_" + v.name, coll / static_cast<double>(v.st.events)});
    out.push_back({"stale_per_collision_" + v.name, static_cast<double>(v.st.stale) / coll});
    out.push_back({"gvts_" + v.name, static_cast<double>(v.st.gvts)});
    out.push_back({"gvt_s_per_collision_" + v.name, v.st.gvt_seconds / coll});
    out.push_back({"journal_peak_bytes_" + v.name, static_cast<double>(v.st.journal_peak_bytes)});
    out.push_back({"journal_bytes_per_entry_" + v.name, v.st.journal_entries_at_gvts == 0 ? 0.0 : static_cast<double>(v.st.journal_bytes_at_gvts) / static_cast<double>(v.st.journal_entries_at_gvts)});
    std::map<int, double> per_worker;  // by the first LP of the worker's share
    for (int m = 0; m < v.k; ++m) per_worker[la::share_of(m, v.w, v.k).first] += static_cast<double>(v.st.lp_events[static_cast<std::size_t>(m)]);
    double busiest = 0.0;
    for (const auto& [first, events] : per_worker) busiest = std::max(busiest, events);
    out.push_back({"worker_imbalance_" + v.name, busiest * v.w / static_cast<double>(v.st.events)});
  }
  const double coll_back = have_back ? static_cast<double>(want.collisions - want_back.collisions) : 0.0;
  for (const Variant& v : vs) {
    if (back == 0) break;
    add_spread(v.name + "_back_per_s", v.back_rate);
    add_spread("speedup_back_" + v.name, v.back_speedup);
    add_spread("speedup_back_net_" + v.name, v.back_net);
    out.push_back({"same_back_" + v.name, v.back_same ? 1.0 : 0.0});
    out.push_back({"seconds_back_" + v.name, median(v.back_seconds)});
    if (v.k == 0) continue;
    out.push_back({"events_back_per_collision_" + v.name, static_cast<double>(v.back_st.events) / coll_back});
    out.push_back({"rollbacks_back_per_1k_" + v.name, 1000.0 * static_cast<double>(v.back_st.rollbacks) / coll_back});
    out.push_back({"undone_back_per_collision_" + v.name, static_cast<double>(v.back_st.undone) / coll_back});
  }
  if (back != 0) {
    out.push_back({"seconds_seq_flips", median(flips)});
    out.push_back({"collisions_back", coll_back});
  }
  out.push_back({"band_over_L", band / static_cast<double>(s0.units.L[0])});
  out.push_back({"ticks", static_cast<double>(until - s0.clock)});
  out.push_back({"n", static_cast<double>(c.n)});
  out.push_back({"phi", c.phi});
  out.push_back({"collisions", coll});
  out.push_back({"rounds", static_cast<double>(rounds)});
  out.push_back({"observed", static_cast<double>(observe)});
  return out;
}

}  // namespace

void add_parallel_benches(std::vector<Bench>& out) {
  struct Named {
    const char* name;
    int dim;
    ParCase c;
  };
  static const Named named[] = {{"parallel/d2/n10000/phi0.5", 2, {10000, 0.5}},   {"parallel/d2/n100000/phi0.5", 2, {100000, 0.5}},
                                {"parallel/d2/n1000000/phi0.5", 2, {1000000, 0.5}}, {"parallel/d3/n10000/phi0.3", 3, {10000, 0.3}},
                                {"parallel/d3/n100000/phi0.3", 3, {100000, 0.3}},   {"parallel/d3/n1000000/phi0.3", 3, {1000000, 0.3}}};
  for (const Named& m : named) {
    const ParCase c = m.c;
    const int dim = m.dim;
    out.push_back({m.name, "collisions/s", [c, dim](std::uint64_t k) { return dim == 3 ? run_parallel<3>(c, k) : run_parallel<2>(c, k); }});
  }
}

}  // namespace revcol::bench
