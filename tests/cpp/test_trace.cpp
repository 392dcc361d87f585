// The collision trace (revcol/engine/trace.hpp): its grid on made-up sums, and the float
// engine's run_back finding (or not finding) a divergence.
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "check.hpp"
#include "revcol/engine/engine.hpp"
#include "revcol/engine/init.hpp"
#include "revcol/engine/trace.hpp"
#include "revcol/error.hpp"

using namespace revcol;
using namespace revcol::engine;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr std::uint64_t kAll = std::numeric_limits<std::uint64_t>::max();

// A trace driven by a made-up sequence: collision k has signature sig(k). Forward to `to`,
// then back to 0 with signature bad(k) in place of sig(k) for the collisions that `wrong` says.
template <class Wrong>
CollisionTrace drive(std::int64_t to, Wrong wrong) {
  CollisionTrace t(0, /*start=*/true);
  const auto sig = [](std::int64_t k) { return static_cast<std::uint64_t>(k) * 0x9E3779B97F4A7C15ull + 1; };
  for (std::int64_t m = 1; m <= to; ++m) {
    t.apply(sig(m), false);
    if (t.on_grid(m)) t.record(m, static_cast<double>(m));
  }
  for (std::int64_t m = to; m >= 1; --m) {
    t.apply(wrong(m) ? sig(m) ^ 1 : sig(m), true);
    if (t.on_grid(m - 1)) t.check(m - 1, static_cast<double>(m));
  }
  t.check_start(0);
  return t;
}

// A periodic gas of n particles in dimension d, ready to run.
std::unique_ptr<Simulation> gas(int d, std::size_t n, std::uint64_t seed, Boundary b = Boundary::periodic) {
  Config c;
  c.dim = d;
  c.boundary = {b, b, b};
  const InitialState st = random_state(c, n, 0.3, seed);
  return make_simulation(st.config, st.x, st.v);
}

// Whether restoring snap throws InvalidArgument whose message contains `what`.
bool refused_with(const Snapshot& snap, const std::string& what) {
  try {
    restore_simulation(snap);
  } catch (const InvalidArgument& e) {
    return std::string(e.what()).find(what) != std::string::npos;
  }
  return false;
}

}  // namespace

TEST_CASE("trace: the same collisions undone find nothing, whatever the length") {
  for (std::int64_t to : {10, 1000, 100000}) {
    const CollisionTrace t = drive(to, [](std::int64_t) { return false; });
    CHECK(t.reason() == Divergence::none);
    CHECK(t.diverged_at() == CollisionTrace::kNever);
    CHECK(t.reorderings() == 0);
    CHECK(t.points() <= CollisionTrace::kCapacity);
    CHECK(t.clock_deviation() == 0.0);
    if (to >= 1000) CHECK(t.verified_at() == 0);
  }
  // 10^5 collisions at stride 128 would be 781 points: the grid thinned and its stride doubled
  CHECK(drive(100000, [](std::int64_t) { return false; }).stride() == 512);
}

TEST_CASE("trace: a wrong collision is a divergence, dated at the first point that sees it") {
  // collision 5000 undone with another signature: every point at or below 4999 is off
  const CollisionTrace t = drive(20000, [](std::int64_t k) { return k == 5000; });
  CHECK(t.reason() == Divergence::sequence);
  CHECK(t.diverged_at() <= 4999);
  CHECK(t.diverged_at() > 4999 - 3 * static_cast<std::int64_t>(t.stride()));
  CHECK(t.verified_at() >= 5000);
}

TEST_CASE("trace: a wrong collision just above the start is caught by the start's check") {
  const CollisionTrace t = drive(5000, [](std::int64_t k) { return k == 3; });
  CHECK(t.reason() == Divergence::sequence);
}

TEST_CASE("trace: collisions undone in another order are a reordering, not a divergence") {
  // collisions 1140 and 1220 swap on the way back: the points between (1152, 1216; points are
  // 64 apart at stride 128) are off, two in a row, and 1088 is on again
  CollisionTrace t(0, true);
  const auto sig = [](std::int64_t k) { return static_cast<std::uint64_t>(k) * 0x9E3779B97F4A7C15ull + 1; };
  for (std::int64_t m = 1; m <= 4000; ++m) {
    t.apply(sig(m), false);
    if (t.on_grid(m)) t.record(m, 0.0);
  }
  for (std::int64_t m = 4000; m >= 1; --m) {
    const std::int64_t k = m == 1140 ? 1220 : m == 1220 ? 1140 : m;
    t.apply(sig(k), true);
    if (t.on_grid(m - 1)) t.check(m - 1, 0.0);
  }
  t.check_start(0);
  CHECK(t.reason() == Divergence::none);
  CHECK(t.reorderings() == 1);
}

TEST_CASE("trace: save and load round trip; load names what is wrong") {
  const CollisionTrace t = drive(3000, [](std::int64_t k) { return k == 2000; });
  const auto a = t.save();
  const CollisionTrace u = CollisionTrace::load(a, 0);
  CHECK(u.save() == a);
  auto bad = a;
  bad.pop_back();
  CHECK_THROWS_AS(CollisionTrace::load(bad, 0), InvalidArgument);
  bad = a;
  bad[1] = 100;  // stride not a power of two
  CHECK_THROWS_AS(CollisionTrace::load(bad, 0), InvalidArgument);
  bad = a;
  bad[5] = 9;  // reason
  CHECK_THROWS_AS(CollisionTrace::load(bad, 0), InvalidArgument);
  bad = a;
  bad[9] = 7;  // first point not on the grid
  CHECK_THROWS_AS(CollisionTrace::load(bad, 0), InvalidArgument);
}

TEST_CASE("engine: a round trip within the horizon finds nothing, one far beyond it diverges") {
  for (int d : {2, 3}) {
    auto s = gas(d, 300, 4);
    s->run(600, kInf);  // 4 collisions per particle: within the horizon
    auto clone = restore_simulation(s->snapshot());
    const RunResult r = clone->run_back(kAll, clone->start_time());
    CHECK(!r.diverged);
    CHECK(clone->diagnostics().divergence == Divergence::none);
    CHECK(clone->diagnostics().verified_at == 0);
    s->run(30000 - 600, kInf);  // 200 per particle: far beyond
    const RunResult b = s->run_back(kAll, s->start_time());
    CHECK(b.diverged);
    const Diagnostics g = s->diagnostics();
    CHECK(g.divergence == Divergence::sequence);
    CHECK(g.diverged_at > 0);
    CHECK(g.diverged_at < 30000);
    CHECK(s->time() == s->start_time());  // without stop_on_divergence the run goes on to the target
  }
}

TEST_CASE("engine: stop_on_divergence stops where the divergence is found") {
  auto s = gas(2, 300, 4);
  s->run(30000, kInf);
  const RunResult b = s->run_back(kAll, s->start_time(), {}, /*stop_on_divergence=*/true);
  CHECK(b.diverged);
  CHECK(s->time() > s->start_time());
  const Diagnostics g = s->diagnostics();
  CHECK(g.net_collisions <= g.diverged_at);
  CHECK(g.net_collisions > 0);
}

TEST_CASE("engine: a velocity changed at the turn is refused, whatever its energy says") {
  auto s = gas(2, 200, 6);
  s->run(2000, kInf);
  Snapshot snap = s->snapshot();
  snap.v[0] *= 1.001;  // a forged checkpoint: its energy is not energy0
  CHECK_THROWS_AS(restore_simulation(snap), InvalidArgument);
  // forged with a consistent energy0 and momentum0: particle 0's scheduled events no longer fit
  double e = 0.0, p0 = 0.0, p1 = 0.0;
  for (std::size_t i = 0; i < snap.n; ++i) {
    e += 0.5 * (snap.v[2 * i] * snap.v[2 * i] + snap.v[2 * i + 1] * snap.v[2 * i + 1]);
    p0 += snap.v[2 * i];
    p1 += snap.v[2 * i + 1];
  }
  snap.energy0 = e;
  snap.momentum0 = {p0, p1, 0.0};
  CHECK(refused_with(snap, "does not fit the particles"));
}

TEST_CASE("engine: forged draws load, and the run back they mislead says it diverged") {
  for (int d : {2, 3}) {
    auto s = gas(d, 200, 6);
    s->run(1000, kInf);
    for (std::size_t k = 0; k < 200; k += 20) {
      Snapshot snap = s->snapshot();
      snap.rng[k] += 1;  // one stream one draw on: nothing in the state can tell
      auto t = restore_simulation(snap);
      CHECK(t->fault().empty());
      const RunResult r = t->run_back(kAll, t->start_time());
      CHECK(r.diverged);  // the trace, or particles overlapping where it ended
      const Divergence why = t->diagnostics().divergence;
      CHECK(why == Divergence::sequence || why == Divergence::overlap);
      if (why == Divergence::overlap) CHECK(!t->fault().empty());
    }
  }
}

TEST_CASE("engine: a schedule or list centres that do not fit the particles are refused, naming the fault") {
  for (int d : {2, 3}) {
    auto s = gas(d, 300, 9, Boundary::wall);
    s->run(1500, kInf);
    const Snapshot good = s->snapshot();
    CHECK(s->fault().empty());
    // a live scheduled collision moved later: the pair meets before it
    Snapshot a = good;
    for (std::size_t i = 0; i < a.n; ++i)
      if (a.ev_kind[i] == 2 && a.ev_t[i] < kInf) {
        const auto j = static_cast<std::size_t>(a.ev_partner[i]);
        a.ev_t[i] += 0.5;
        if (a.ev_kind[j] == 2 && static_cast<std::size_t>(a.ev_partner[j]) == i) a.ev_t[j] += 0.5;
        break;
      }
    CHECK(refused_with(a, "does not fit the particles"));
    // a list centre a diameter off its particle
    Snapshot b = good;
    b.centre[0] += good.config.diameter * (b.centre[0] < 0.5 * good.config.box[0] ? 1.0 : -1.0);
    CHECK(refused_with(b, "beyond its reach"));
    // two particles' positions swapped (their schedules trusted): refused
    Snapshot c = good;
    for (int k = 0; k < d; ++k) std::swap(c.x[k], c.x[static_cast<std::size_t>(d) * 7 + k]);
    CHECK(refused_with(c, "snapshot:"));
    // every event of every particle at infinity: nothing would ever happen
    Snapshot e = good;
    for (auto& t : e.ev_t) t = kInf;
    CHECK(refused_with(e, "before its scheduled event"));
  }
}

TEST_CASE("engine: every state a run reaches passes the check, forward and back (no false refusal)") {
  for (int d : {2, 3}) {
    Config c;
    c.dim = d;
    c.boundary = {Boundary::wall, Boundary::periodic, Boundary::bounce};
    const InitialState st = random_state(c, 200, d == 2 ? 0.45 : 0.3, 12);
    auto s = make_simulation(st.config, st.x, st.v);
    int refused = 0;
    for (int step = 0; step < 300; ++step) {
      s->run(7, kInf);
      if (!s->fault().empty()) ++refused;
      auto r = restore_simulation(s->snapshot());
      CHECK(r->snapshot().ev_t == s->snapshot().ev_t);
    }
    for (int step = 0; step < 100; ++step) {
      s->run_back(5, -kInf);
      if (!s->fault().empty()) ++refused;
    }
    CHECK(refused == 0);
    CHECK(s->diagnostics().divergence == Divergence::none);
  }
}

TEST_CASE("engine: the trace survives a checkpoint (walled box), and one without it starts a new one") {
  auto s = gas(3, 200, 8, Boundary::wall);
  s->run(1500, kInf);
  Snapshot snap = s->snapshot();
  auto r = restore_simulation(snap);
  CHECK(r->snapshot().trace == snap.trace);
  r->run_back(kAll, r->start_time());
  CHECK(r->diagnostics().verified_at == 0);
  snap.trace.clear();
  auto old = restore_simulation(snap);
  old->run_back(kAll, old->start_time());
  CHECK(old->diagnostics().divergence == Divergence::none);
  CHECK(old->diagnostics().verified_at == CollisionTrace::kNever);  // nothing kept below the checkpoint
}

int main() { return check::run_all(); }
