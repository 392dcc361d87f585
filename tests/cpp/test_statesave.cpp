// The state-saving study's workload (revcol/studies/statesave.hpp), at small N and N_c: every
// variant comes back to the start (state saving bit for bit, RC within 1e-9), the draw count
// is fixed, lazy transport agrees with eager, over-budget runs are skipped, bad input throws.
#include "revcol/studies/statesave.hpp"

#include <cmath>
#include <limits>
#include <string>

#include "check.hpp"

using namespace revcol;
using namespace revcol::statesave;

namespace {
Config small(Variant v, Transport t, Mode m = Mode::exact, const std::string& rng = "clcg4") {
  Config c;
  c.particles = 200;
  c.collisions = 400;  // about 4 collisions per particle
  c.variant = v;
  c.transport = t;
  c.mode = m;
  c.rng = rng;
  return c;
}
double max_abs_diff(const std::vector<double>& a, const std::vector<double>& b) {
  double m = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) m = std::fmax(m, std::fabs(a[k] - b[k]));
  return m;
}
}  // namespace

TEST_CASE("RC restores the start within 1e-9: eager and lazy, both modes, both generators") {
  for (Transport t : {Transport::eager, Transport::lazy}) {
    for (Mode m : {Mode::exact, Mode::paper}) {
      for (const char* g : {"clcg4", "philox"}) {
        const Result r = run(small(Variant::rc, t, m, g));
        CHECK(r.error.empty());
        CHECK(r.restored);
        CHECK(r.max_rel_error <= 1e-9);
        CHECK(r.rng_restored);
        CHECK(r.clock_restored);
        CHECK(!r.skipped);
        if (m == Mode::paper) CHECK(r.max_rel_error <= 1e-13);  // no quantization
      }
    }
  }
}

TEST_CASE("state saving restores the start bit for bit and counts its bytes") {
  for (Transport t : {Transport::eager, Transport::lazy}) {
    for (const std::string& v : variant_names(t)) {
      if (v == "rc") continue;
      for (bool prefault : {true, false}) {
        Config c = small(parse_variant(v), t);
        c.prefault = prefault;
        const Result r = run(c);
        CHECK(r.restored);
        CHECK(r.bit_exact);
        CHECK(r.max_rel_error == 0.0);
        CHECK(r.rng_restored);
        CHECK(r.clock_restored);
        CHECK(r.bytes_saved == record_bytes(c) * c.collisions);
        CHECK(r.bytes_saved == r.projected_bytes);
      }
    }
  }
}

TEST_CASE("record sizes: SS1 32N + 24, SS2 16N + 64, SS-pair 96, RC 0") {
  Config c;
  c.particles = 1000;
  c.collisions = 7;
  c.variant = Variant::ss1;
  CHECK(record_bytes(c) == 32 * 1000 + 24);
  c.variant = Variant::ss2;
  CHECK(record_bytes(c) == 16 * 1000 + 64);
  c.variant = Variant::rc;
  CHECK(record_bytes(c) == 0);
  CHECK(projected_bytes(c) == 0);
  c.transport = Transport::lazy;
  c.variant = Variant::ssp;
  CHECK(record_bytes(c) == 96);
  CHECK(projected_bytes(c) == 96 * 7);
}

TEST_CASE("fixed draw count: 3 per step forward, 3 per step undone, generator back at its start") {
  for (Transport t : {Transport::eager, Transport::lazy}) {
    for (const std::string& v : variant_names(t)) {
      const Config c = small(parse_variant(v), t, Mode::paper, "philox");
      const Result r = run(c);
      CHECK(r.draws == draws_per_step * c.collisions);
      if (v == "rc") CHECK(r.draws_undone == draws_per_step * c.collisions);
      CHECK(r.rng_restored);
    }
  }
}

TEST_CASE("lazy transport gives eager's state at the turn, to rounding") {
  for (Mode m : {Mode::exact, Mode::paper}) {
    Config e = small(Variant::rc, Transport::eager, m);
    e.capture = true;
    Config l = e;
    l.transport = Transport::lazy;
    const Result re = run(e), rl = run(l);
    REQUIRE(re.turn.x.size() == e.particles);
    REQUIRE(rl.turn.x.size() == e.particles);
    CHECK(re.turn.ticks == rl.turn.ticks);
    CHECK(re.turn.ticks > 0);
    CHECK(max_abs_diff(re.turn.x, rl.turn.x) <= 1e-12);
    CHECK(max_abs_diff(re.turn.y, rl.turn.y) <= 1e-12);
    CHECK(max_abs_diff(re.turn.vx, rl.turn.vx) <= 1e-9);
    CHECK(max_abs_diff(re.turn.vy, rl.turn.vy) <= 1e-9);
    // the start is the same, and the state at the turn has moved away from it
    CHECK(re.start.x == rl.start.x);
    CHECK(max_abs_diff(re.start.vx, re.turn.vx) > 0.1);
  }
}

TEST_CASE("deterministic: the same configuration gives the same bits") {
  for (Transport t : {Transport::eager, Transport::lazy}) {
    Config c = small(Variant::rc, t);
    c.capture = true;
    const Result a = run(c), b = run(c);
    CHECK(a.turn.x == b.turn.x);
    CHECK(a.turn.vx == b.turn.vx);
    CHECK(a.end.vy == b.end.vy);
    CHECK(a.max_rel_error == b.max_rel_error);
    c.seed = 1;
    const Result d = run(c);
    CHECK(!(d.turn.vx == a.turn.vx));
  }
}

TEST_CASE("exact mode's pre log: used by exact/flux, never by paper mode, off with grazing_tol = inf") {
  Config c = small(Variant::rc, Transport::lazy);
  const Result flux = run(c);
  CHECK(flux.pre_log_entries > 0);
  CHECK(flux.log_bytes >= 40 * flux.pre_log_entries);
  CHECK(flux.bytes_saved == flux.log_bytes);
  c.grazing_tol = std::numeric_limits<double>::infinity();
  CHECK(run(c).pre_log_entries == 0);
  c.mode = Mode::paper;
  c.grazing_tol = 1e-11;
  const Result paper = run(c);
  CHECK(paper.pre_log_entries == 0);
  CHECK(paper.restored);
}

TEST_CASE("edge cases: two particles (the same pair every step), a single collision") {
  for (Mode m : {Mode::exact, Mode::paper}) {
    Config c = small(Variant::rc, Transport::eager, m);
    c.particles = 2;  // the same pair every step, N - 1 = 1
    c.collisions = 300;
    CHECK(run(c).restored);
    c.particles = 50;
    c.collisions = 1;
    CHECK(run(c).restored);
  }
}

TEST_CASE("runs over the memory budget are skipped with their projection, not attempted") {
  Config c;
  c.particles = 1000000;
  c.collisions = 1000;
  c.variant = Variant::ss1;
  const Result r = run(c);  // would need 32 GB: returns at once
  CHECK(r.skipped);
  CHECK(r.projected_bytes == std::uint64_t{32000024000});
  CHECK(r.bytes_saved == 0);
  CHECK(r.forward_s == 0.0);
  CHECK(over_budget(c));
  c.variant = Variant::rc;
  CHECK(!over_budget(c));
  Config s = small(Variant::ss2, Transport::eager);
  s.budget_bytes = record_bytes(s) * s.collisions;  // exactly at the budget: runs
  CHECK(!run(s).skipped);
  s.budget_bytes -= 1;
  CHECK(run(s).skipped);
}

TEST_CASE("bad configurations throw InvalidArgument naming the problem") {
  auto bad = [](auto change) {
    Config c = small(Variant::rc, Transport::eager);
    change(c);
    CHECK_THROWS_AS(run(c), InvalidArgument);
    CHECK_THROWS_AS(projected_bytes(c), InvalidArgument);
  };
  bad([](Config& c) { c.particles = 1; });
  bad([](Config& c) { c.particles = max_particles + 1; });
  bad([](Config& c) { c.collisions = 0; });
  bad([](Config& c) { c.variant = Variant::ssp; });  // eager
  bad([](Config& c) { c.rng = "mt19937"; });
  bad([](Config& c) { c.seed = std::uint64_t{1} << 32; });
  bad([](Config& c) { c.mean_dt = 0.0; });
  bad([](Config& c) { c.mean_dt = std::nan(""); });
  bad([](Config& c) { c.grazing_tol = 0.0; });
  bad([](Config& c) { c.bits = 60; });
  CHECK_THROWS_AS(parse_variant("ss3"), InvalidArgument);
  CHECK_THROWS_AS(parse_transport("fast"), InvalidArgument);
  try {
    Config c = small(Variant::ssp, Transport::eager);
    run(c);
    CHECK(false);
  } catch (const InvalidArgument& e) {
    CHECK(std::string(e.what()).find("lazy") != std::string::npos);
  }
  try {
    Config c = small(Variant::rc, Transport::eager);
    c.particles = 1;
    run(c);
    CHECK(false);
  } catch (const InvalidArgument& e) {
    CHECK(std::string(e.what()).find("particles") != std::string::npos);
  }
}

TEST_CASE("names round-trip") {
  for (Transport t : {Transport::eager, Transport::lazy}) {
    CHECK(parse_transport(to_string(t)) == t);
    for (const std::string& v : variant_names(t)) CHECK(to_string(parse_variant(v)) == v);
  }
  CHECK(variant_names(Transport::eager).size() == 3);
  CHECK(variant_names(Transport::lazy).size() == 4);
}

TEST_CASE("resident set readings are plausible") {
  CHECK(peak_rss_bytes() > 0);
  CHECK(current_rss_bytes() <= peak_rss_bytes());
}

CHECK_MAIN()
