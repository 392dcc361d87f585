// The slabs family of revcol-bench: what cutting a lattice gas into K slabs along x would ask of
// a parallel run, measured on the sequential engine (set_regions; the inputs of the parallel
// engine's performance model, issue 55). One run of n collisions per K, each from the same
// warmed-up state (a collision per particle), with the slabs' neutral events on:
//   migrations_K<K>   particles entering another slab, per collision (each a message);
//   cross_K<K>        fraction of collisions whose particles sit in different slabs (at the
//                     tick before: a pair two logical processes share);
//   near_K<K>         fraction of collisions with a particle within one reach of a face (sigma +
//                     4 vmax: a collision whose outcome a neighbour's ghost copies must follow);
//   rate_K<K>         the forward rate with the slabs over the rate without (the neutral events'
//                     cost), each run timed from the same restored state (the pairs are counted on
//                     a fifth of the run again, from its event records);
// and forward_per_s without slabs, n, phi.
//
//   revcol-bench --bench slabs/ --collisions 1000000
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <string>
#include <type_traits>
#include <vector>

#include "bench.hpp"
#include "revcol/lattice/engine.hpp"

namespace revcol::bench {
namespace {

namespace la = revcol::lattice;

template <std::size_t D>
using EngineOf = std::conditional_t<D == 2, la::LatticeEngine, la::LatticeEngine3D>;

struct SlabCase {
  std::size_t n;
  double phi;
};

template <std::size_t D>
std::vector<Metric> run_slabs(const SlabCase& c, std::uint64_t nc) {
  la::LatticeConfigN<D> cfg;
  cfg.seed = 1;
  const la::LatticeStartN<D> st = la::random_start(cfg, c.n, c.phi, 1, D == 2 && c.phi > 0.35 ? "crystal" : "auto");
  EngineOf<D> e(st.units, st.x, st.v, cfg.seed, la::operator_for(st.units));
  e.run(c.n, la::tick_limit - 1);  // warm up
  const la::SnapshotN<D> s0 = e.snapshot();
  const std::int64_t L = s0.units.L[0];
  const double reach = static_cast<double>(s0.units.sigma) + 4.0 * static_cast<double>(s0.units.vmax);
  using clock = std::chrono::steady_clock;
  // the rate without slabs from the same restored state as every K below: a restore builds the
  // engine's structures afresh, and at N = 10^6 that alone ran 1.3x the warm-up's rate (3D), which
  // a base taken straight after the warm-up had counted as the slabs' doing
  e.restore(s0);
  auto t0 = clock::now();
  e.run(nc, la::tick_limit - 1);
  const double base = static_cast<double>(nc) / seconds_since(t0);
  std::vector<Metric> out{{"forward_per_s", base}};
  for (int k : {2, 4, 8, 16, 64, 256, 1024}) {
    std::vector<std::int64_t> faces;
    for (int s = 0; s < k; ++s) faces.push_back(static_cast<std::int64_t>(static_cast<__int128>(L) * s / k));
    // timed, nothing recorded but the migrations (a vector's push per migration)
    e.restore(s0);
    e.set_regions(0, faces);
    std::vector<std::array<std::int64_t, 4>> moves;
    e.migrations = &moves;
    t0 = clock::now();
    const std::uint64_t done = e.run(nc, la::tick_limit - 1);
    const double seconds = seconds_since(t0);
    const double migrations = static_cast<double>(moves.size()) / static_cast<double>(done);
    // the pairs, from the event records of a fifth of the run again
    e.restore(s0);
    std::vector<la::EventRecordN<D>> events;
    e.events = &events;
    std::uint64_t recorded = 0, cross = 0, near = 0, pairs = 0;
    while (recorded < std::max<std::uint64_t>(1, nc / 5)) {  // in chunks: the event records stay small
      events.clear();
      recorded += e.run(std::min<std::uint64_t>(nc / 5 - recorded, 20000) + (nc / 5 == 0 ? 1 : 0), la::tick_limit - 1);
      for (const auto& r : events) {
        if (r.kind == la::EventRecordN<D>::wall) continue;
        ++pairs;
        bool different = false, close = false;
        int first = -1;
        for (const auto& x : r.x) {  // post points at the tick (the tick before differs by < vmax)
          const std::int64_t xi = ((x[0] % L) + L) % L;
          const auto it = std::upper_bound(faces.begin(), faces.end(), xi);
          const int slab = static_cast<int>(it - faces.begin()) - 1;
          different = different || (first >= 0 && slab != first);
          if (first < 0) first = slab;
          const std::int64_t lo = faces[static_cast<std::size_t>(slab)];
          const std::int64_t hi = slab + 1 < k ? faces[static_cast<std::size_t>(slab + 1)] : L;
          close = close || static_cast<double>(std::min(xi - lo, hi - xi)) < reach;
        }
        cross += different ? 1 : 0;
        near += close ? 1 : 0;
      }
    }
    e.migrations = nullptr;
    e.events = nullptr;
    const std::string tag = "_K" + std::to_string(k);
    out.push_back({"migrations" + tag, migrations});
    out.push_back({"cross" + tag, static_cast<double>(cross) / static_cast<double>(pairs)});
    out.push_back({"near" + tag, static_cast<double>(near) / static_cast<double>(pairs)});
    out.push_back({"rate" + tag, static_cast<double>(done) / seconds / base});
    e.set_regions(0, {});
  }
  out.push_back({"n", static_cast<double>(c.n)});
  out.push_back({"phi", c.phi});
  return out;
}

}  // namespace

void add_slabs_benches(std::vector<Bench>& out) {
  struct Named {
    const char* name;
    int dim;
    SlabCase c;
  };
  static const Named named[] = {{"slabs/d2/n10000/phi0.5", 2, {10000, 0.5}},
                                {"slabs/d2/n1000000/phi0.5", 2, {1000000, 0.5}},
                                {"slabs/d3/n10000/phi0.3", 3, {10000, 0.3}},
                                {"slabs/d3/n1000000/phi0.3", 3, {1000000, 0.3}}};
  for (const Named& m : named) {
    const SlabCase c = m.c;
    const int dim = m.dim;
    out.push_back({m.name, "collisions/s", [c, dim](std::uint64_t k) { return dim == 3 ? run_slabs<3>(c, k) : run_slabs<2>(c, k); }});
  }
}

}  // namespace revcol::bench
