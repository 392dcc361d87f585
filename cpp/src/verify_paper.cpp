// verify() cases of the paper family (see verify.hpp, namespace detail): the paper's Reversal
// Illustrations (§5.1) for the paper-mode operators of §4.3-4.5. Momentum and energy are
// computed once and held; after each collision every velocity is negated to make the next
// one; then all collisions are reversed with the generator stepping back d_n numbers each.
//
//   pair3d        2 particles in 3D, normal (1, 1, 1), start v_i = (0.25, -0.5, 0.1),
//                 v_j = (1, 0.75, 0.6) (§4.3; 2 draws per collision)
//   triple1d      3 particles in a row at 0, 1, 2, start (0.75, 0.25, -0.5): the paper's
//                 "Reversal Illustration for 3-Particle Collisions in 1 Dimension" (1 draw;
//                 G-to-Psi by the paper's Simpson + bisection, cosine tolerance 1e-8)
//   triple2d-c1   disks at (0,0), (1,0), (0.5, sqrt3/2), start (0.5, 0.3), (-0.5, 0.25), (0.05, -0.6)
//   triple2d-c2   its mirror image: (0,0), (1,0), (0.5, -sqrt3/2), start (0.5, -0.3), (-0.5, -0.25), (0.05, 0.6)
//   triple2d-c3   (0,0), (1,0), (1 + sqrt3/2, -1/2): theta = 5pi/6; start (0.5, 0), (-0.25, 0.1), (-0.9, 0.4)
//   triple2d-c4   (0,0), (1,0), (-sqrt3/2, 1/2): theta = -pi/6 from P1; start (0.3, 0), (-0.4, 0), (0.5, -0.4)
// (3 draws per collision). Each start approaches at every contact. VerifyConfig::velocities
// overrides the start; VerifyConfig::normal the pair3d normal (the triples keep their
// positions). printed_reverse selects the printed reverse test of pair3d and triple1d.
// A forward step that hands the next one an invalid state (the printed procedures of §4.5 can
// produce a post state that does not separate) stops the forward loop: that step is taken
// back (its pre state kept, its draws stepped back), the steps before it are reversed, and
// `error` says where it stopped. The chain cannot go on: the paper's illustration has no
// valid next collision. Failure rates over 10^6 collisions: paper_study.hpp.
#include <chrono>

#include "paper_adapt.hpp"
#include "revcol/rng/streams.hpp"
#include "revcol/verify.hpp"

namespace revcol::detail {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

template <class Op, class Gen>
void run_chain(const Op& op, Gen& gen, const paper::PaperCase& pc, const VerifyConfig& c,
               VerifyResult& r) {
  using A = paper::adapt::Adapter<Op>;
  typename Op::State v = A::state(c.velocities.empty() ? pc.velocities : c.velocities);
  std::vector<double> geom = pc.geometry;
  if (!c.normal.empty()) {
    require(pc.name == "pair3d", "only pair3d takes a contact normal; the triples keep their positions");
    geom = c.normal;
  }
  const typename Op::Geometry x = A::geometry(geom);
  const typename Op::Inv inv = A::invariants(v);
  op.check_pre(v, x, &inv);  // a bad start throws here, before anything runs
  const Gen start_state = gen;
  r.initial = A::flat(v);
  r.reference = r.initial;  // paper mode promises the start itself (to 1e-9)
  RareLog log;
  typename Op::Draws g;

  auto t0 = Clock::now();
  std::uint64_t done = 0;
  typename Op::State last_pre = v;  // the pre state of the last step (to take it back)
  try {
    for (; done < c.collisions; ++done) {
      for (double& gk : g) gk = gen.next();
      try {
        const typename Op::State next = op.forward(v, x, g, log, &inv);
        last_pre = v;
        v = next;
      } catch (...) {
        for (std::size_t k = 0; k < g.size(); ++k) (void)gen.prev();  // this collision did not happen
        throw;
      }
      A::negate(v);  // reverse the velocities to create the next collision
    }
  } catch (const InvalidArgument& e) {
    // step `done + 1` refused the state that step `done` left: that step's post state does not
    // separate (the printed procedures of §4.5 produce such states). Take step `done` back too
    // (its pre state was kept, its draws are stepped back) and reverse the steps before it.
    r.error = "forward step " + std::to_string(done) + " of " + std::to_string(c.collisions) +
              " produced a post-collision state that the next step refuses (" + e.what() +
              "); stopped, that step taken back, the " + std::to_string(done - 1) +
              " steps before it reversed";
    if (done > 0) {
      for (std::size_t k = 0; k < g.size(); ++k) (void)gen.prev();
      v = last_pre;
      --done;
    }
  }
  r.forward_s = seconds_since(t0);
  r.collisions = done;  // the rates are per collision actually taken
  r.log_bytes = log.bytes();
  r.log_entries = log.size();
  r.random_numbers_drawn = done * Op::draws;

  t0 = Clock::now();
  std::uint64_t undone = 0;
  try {
    for (; undone < done; ++undone) {
      A::negate(v);
      for (std::size_t k = g.size(); k-- > 0;) g[k] = gen.prev();
      v = op.reverse(v, x, g, log, &inv);
    }
  } catch (const InvalidArgument& e) {
    // a wrong reversal hands the next step an invalid state
    r.error += (r.error.empty() ? "" : "; ") + std::string("reverse step ") +
               std::to_string(undone + 1) + " of " + std::to_string(done) + ": " + e.what();
    ++undone;  // its numbers were stepped back
  }
  r.reverse_s = seconds_since(t0);
  r.random_numbers_undone = undone * Op::draws;
  r.final_velocities = A::flat(v);
  r.rng_restored = gen == start_state;
  r.passed = log.size() == 0 && done == c.collisions;
}

template <class Gen>
bool run_case(const VerifyConfig& c, VerifyResult& r) {
  const paper::PaperCase& pc = paper::paper_case(c.case_name);
  Gen gen = rng::make_generator<Gen>(0, c.seed, 1);
  paper::StudyConfig sc;
  sc.printed_reverse = c.printed_reverse;
  if (pc.name == "pair3d") {
    run_chain(paper::adapt::Adapter<Pair3DPaper>::make(sc), gen, pc, c, r);
  } else if (pc.name == "triple1d") {
    run_chain(paper::adapt::Adapter<Triple1DPaper>::make(sc), gen, pc, c, r);
  } else {
    run_chain(paper::adapt::Adapter<Triple2DPaper>::make(sc), gen, pc, c, r);
  }
  return true;
}

}  // namespace

bool run_paper_case(const VerifyConfig& config, VerifyResult& r) {
  if (config.mode != Mode::paper) return false;
  bool known = false;
  for (const std::string& n : paper_case_names()) known = known || n == config.case_name;
  if (!known) return false;
  if (config.rng == "clcg4") return run_case<rng::CLCG4>(config, r);
  if (config.rng == "philox") return run_case<rng::Philox>(config, r);
  throw InvalidArgument("rng must be 'clcg4' or 'philox', got '" + config.rng + "'");
}

std::vector<std::string> paper_case_names() {
  std::vector<std::string> out;
  for (const paper::PaperCase& c : paper::paper_cases()) out.push_back(c.name);
  return out;
}

}  // namespace revcol::detail
