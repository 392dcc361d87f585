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
#include <variant>

#include "revcol/studies/paper_adapt.hpp"
#include "revcol/studies/verify.hpp"

namespace revcol::detail {
namespace {

// A paper-mode operator in the chain, momentum and energy held; its forward step may refuse
// the state the previous one left (§4.5), which stops the chain.
template <class Op>
struct PaperChain {
  using A = paper::adapt::Adapter<Op>;
  using State = typename Op::State;
  static constexpr bool stops_early = true;
  const Op& op;
  typename Op::Geometry x;
  typename Op::Inv inv;
  std::size_t draws() const { return static_cast<std::size_t>(Op::draws); }
  void forward(State& v, const double* g, RareLog& log, std::uint64_t) const { v = op.forward(v, x, draws_of(g), log, &inv); }
  void reverse(State& v, const double* g, RareLog& log, std::uint64_t) const { v = op.reverse(v, x, draws_of(g), log, &inv); }
  void negate(State& v) const { A::negate(v); }
  std::vector<double> flat(const State& v) const { return A::flat(v); }
  static typename Op::Draws draws_of(const double* g) {
    typename Op::Draws d;
    for (std::size_t k = 0; k < d.size(); ++k) d[k] = g[k];
    return d;
  }
};

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
  const PaperChain<Op> chain{op, A::geometry(geom), A::invariants(v)};
  op.check_pre(v, chain.x, &chain.inv);  // a bad start throws here, before anything runs
  r.initial = A::flat(v);
  r.reference = r.initial;  // paper mode promises the start itself (to 1e-9)
  reversal_chain(chain, v, gen, c, r);
}

template <class Gen>
void run_case(const VerifyConfig& c, Gen& gen, VerifyResult& r) {
  const paper::PaperCase& pc = paper::paper_case(c.case_name);
  paper::StudyConfig sc;
  sc.printed_reverse = c.printed_reverse;
  if (pc.name == "pair3d") {
    run_chain(paper::adapt::Adapter<Pair3DPaper>::make(sc), gen, pc, c, r);
  } else if (pc.name == "triple1d") {
    run_chain(paper::adapt::Adapter<Triple1DPaper>::make(sc), gen, pc, c, r);
  } else {
    run_chain(paper::adapt::Adapter<Triple2DPaper>::make(sc), gen, pc, c, r);
  }
}

}  // namespace

bool run_paper_case(const VerifyConfig& config, Generator& gen, VerifyResult& r) {
  if (config.mode != Mode::paper) return false;
  bool known = false;
  for (const std::string& n : paper_case_names()) known = known || n == config.case_name;
  if (!known) return false;
  std::visit([&](auto& g) { run_case(config, g, r); }, gen);
  return true;
}

std::vector<std::string> paper_case_names() {
  std::vector<std::string> out;
  for (const paper::PaperCase& c : paper::paper_cases()) out.push_back(c.name);
  return out;
}

}  // namespace revcol::detail
