// The paper-mode verify cases (verify_paper.cpp) and the failure-rate measurement
// (paper_study.hpp), on reduced counts: the 10^6-collision runs are quoted in
// docs/paper-findings.md, not run here.
#include "revcol/studies/paper_study.hpp"

#include <algorithm>
#include <string>

#include "check.hpp"
#include "revcol/studies/verify.hpp"

using namespace revcol;

namespace {
VerifyResult run(const std::string& name, std::uint64_t n, bool printed = false, const std::string& rng = "clcg4") {
  VerifyConfig c;
  c.case_name = name;
  c.mode = Mode::paper;
  c.collisions = n;
  c.printed_reverse = printed;
  c.rng = rng;
  return verify(c);
}
}  // namespace

TEST_CASE("verify knows the paper cases in paper mode only") {
  const auto paper_cases = verify_cases(Mode::paper);
  for (const char* n : {"pair3d", "triple1d", "triple2d-c1", "triple2d-c2", "triple2d-c3", "triple2d-c4"})
    CHECK(std::find(paper_cases.begin(), paper_cases.end(), n) != paper_cases.end());
  VerifyConfig c;
  c.case_name = "triple1d";
  c.mode = Mode::exact;
  VerifyResult r;
  CHECK(!detail::run_paper_case(c, r));
}

TEST_CASE("triple1d (the paper's illustration) passes, with one draw per collision") {
  for (const char* g : {"clcg4", "philox"}) {
    const VerifyResult r = run("triple1d", 3000, false, g);
    CHECK(r.passed);
    CHECK(r.error.empty());
    CHECK(r.rng_restored);
    CHECK(r.random_numbers_drawn == 3000 && r.random_numbers_undone == 3000);
    CHECK(r.max_rel_error <= 1e-12);
    CHECK(r.reference == r.initial);
  }
  const VerifyResult p = run("triple1d", 3000, true);  // the printed Procedure 4
  CHECK(!p.passed);
}

TEST_CASE("pair3d runs through but does not come back (2 draws per collision)") {
  const VerifyResult r = run("pair3d", 2000);
  CHECK(!r.passed);
  CHECK(r.random_numbers_drawn == 4000);
  CHECK(r.max_rel_error > 1e-3);
}

TEST_CASE("triple2d cases stop where the printed forward step leaves an invalid state") {
  for (const char* n : {"triple2d-c1", "triple2d-c2", "triple2d-c3", "triple2d-c4"}) {
    const VerifyResult r = run(n, 1000);
    CHECK(!r.passed);
    CHECK(r.error.find("forward step") != std::string::npos);
    CHECK(r.random_numbers_drawn % 3 == 0);
  }
  VerifyConfig c;
  c.case_name = "triple2d-c1";
  c.mode = Mode::paper;
  c.printed_reverse = true;
  CHECK_THROWS_AS(verify(c), InvalidArgument);
  c.case_name = "triple1d";
  c.printed_reverse = false;
  c.normal = {1.0};
  CHECK_THROWS_AS(verify(c), InvalidArgument);
  c.normal = {};
  c.velocities = {0.0, 0.5, 1.0};  // not approaching
  CHECK_THROWS_AS(verify(c), InvalidArgument);
}

TEST_CASE("failure rates: triple1d none; pair3d about half; printed triple1d about half") {
  paper::StudyConfig c;
  c.collisions = 20000;
  c.case_name = "triple1d";
  c.arc = paper::ArcMethod::table;
  for (const char* pre : {"chain", "uniform"}) {
    c.pre = pre;
    const auto r = paper::study(c);
    CHECK(r.failure_rate == 0.0);
    CHECK(r.ok == 20000);
    CHECK(r.max_ok_error < 1e-12);
  }
  c.printed_reverse = true;
  const auto p = paper::study(c);
  CHECK(p.failure_rate > 0.4 && p.failure_rate < 0.6);
  CHECK(p.invalid_post == 0);
  c.printed_reverse = false;
  c.case_name = "pair3d";
  const auto q = paper::study(c);
  CHECK(q.failure_rate > 0.35 && q.failure_rate < 0.55);
  CHECK(q.invalid_post == 0 && q.wrong > 0);
  c.case_name = "triple2d-c3";
  const auto t = paper::study(c);
  CHECK(t.invalid_post > 0 && t.failure_rate > 0.5);
  CHECK(!t.first_failure.empty());
  CHECK(paper::to_json(t).find("\"failure_rate\"") != std::string::npos);
  c.pre = "sideways";
  CHECK_THROWS_AS(paper::study(c), InvalidArgument);
  CHECK_THROWS_AS(paper::paper_case("pair4d"), InvalidArgument);
}

CHECK_MAIN()
