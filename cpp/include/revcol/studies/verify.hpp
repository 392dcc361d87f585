// The paper's Reversal Illustrations (§5.1) as a self-check: N_c collisions of one pair with
// momentum and energy computed once and held, velocities negated after each collision, then
// all reversed with the random number generator stepping back; compare with the start.
#pragma once
#include <array>
#include <chrono>
#include <concepts>
#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include "revcol/collide/common.hpp"
#include "revcol/error.hpp"
#include "revcol/fixed_point.hpp"
#include "revcol/interrupt.hpp"
#include "revcol/rng/clcg4.hpp"
#include "revcol/rng/philox.hpp"

namespace revcol {

/// What to run.
struct VerifyConfig {
  std::string case_name = "pair2d";      ///< pair1d | pair2d
  Mode mode = Mode::exact;               ///< exact | paper
  Law law = Law::flux;                   ///< exact mode's law
  std::string rng = "clcg4";             ///< clcg4 | philox
  std::uint64_t seed = 0;                ///< CLCG4 stream index / Philox key word 1
  std::uint64_t collisions = 1000000;    ///< N_c
  int bits = FixedPoint::default_bits;   ///< K
  bool printed_reverse = false;          ///< paper mode: the printed (faulty) Procedure 2
  std::vector<double> velocities;        ///< initial (v_i, v_j) flattened; empty: the default
  std::vector<double> normal;            ///< contact normal r_21; empty: the paper's (1, 1)
  InterruptCheck interrupt;              ///< polled in the loops: true stops with Interrupted (Ctrl-C)
};

/// What it found. Velocities are flattened (v_i then v_j).
struct VerifyResult {
  VerifyConfig config;                   ///< the configuration that ran
  bool passed = false;                   ///< rng restored, error <= 1e-9, log empty, exact: bit_exact
  bool bit_exact = false;                ///< exact: equals the quantized start; else equals the start
  double max_rel_error = 0.0;            ///< max |v_end - v_0| / max |v_0|
  std::uint64_t collisions = 0;          ///< collisions carried out forward: N_c, or fewer when the chain stopped early (see error)
  double forward_s = 0.0, reverse_s = 0.0;             ///< wall time of each loop
  double forward_per_s = 0.0, reverse_per_s = 0.0;     ///< collisions per second
  std::uint64_t log_bytes = 0;           ///< rare log bytes at the turn (after forward)
  std::uint64_t log_entries = 0;         ///< rare log entries at the turn
  std::uint64_t random_numbers_drawn = 0;   ///< next() calls forward
  std::uint64_t random_numbers_undone = 0;  ///< prev() calls in reverse
  bool rng_restored = false;             ///< the generator is back at its start
  std::string error;                     ///< why the reversal stopped early; empty if it did not
  std::vector<double> initial, final_velocities, reference;  ///< start, end, quantized start
};

/// Runs the illustration. Throws InvalidArgument on a bad configuration.
VerifyResult verify(const VerifyConfig& config);

/// The case names verify() knows, for a mode ("pair1d", "pair2d", then each family's).
std::vector<std::string> verify_cases(Mode mode);

namespace detail {
/// The generator config.rng names ("clcg4" | "philox"), started at config.seed: the one
/// place the rng string is parsed. Throws InvalidArgument on another name.
using Generator = std::variant<rng::CLCG4, rng::Philox>;
Generator make_generator(const VerifyConfig& config);

// Families of cases, one source file each (cpp/src/verify_<family>.cpp). Each returns false
// when it does not know config.case_name for config.mode; otherwise it sets r.initial and
// r.reference and runs reversal_chain (below) over its operator, and verify() derives
// max_rel_error, bit_exact and passed from the result.
bool run_exact_case(const VerifyConfig& config, Generator& gen, VerifyResult& r);  ///< verify_exact.cpp
bool run_paper_case(const VerifyConfig& config, Generator& gen, VerifyResult& r);  ///< verify_paper.cpp
/// run_exact_case / run_paper_case with the generator config.rng names.
bool run_exact_case(const VerifyConfig& config, VerifyResult& r);
bool run_paper_case(const VerifyConfig& config, VerifyResult& r);  ///< (as above)
std::vector<std::string> exact_case_names();                        ///< verify_exact.cpp
std::vector<std::string> paper_case_names();                        ///< verify_paper.cpp
/// Whether the case's reversal promises bit-exactness (exact mode and pair1d do).
bool promises_bit_exact(const VerifyConfig& config);

/// What reversal_chain needs of an operator (one adapter per operator signature):
///   using State;                                          the velocities of one collision
///   static constexpr bool stops_early;                    a forward step may refuse the state the
///                                                         previous one left (the paper's §4.5)
///   std::size_t draws() const;                            d_n
///   void forward(State&, const double* g, RareLog&, std::uint64_t t) const;   collision t, in
///   void reverse(State&, const double* g, RareLog&, std::uint64_t t) const;   place; throws
///                                                         InvalidArgument and changes nothing
///   void negate(State&) const;  std::vector<double> flat(const State&) const;
template <class A>
concept ChainOperator = requires(const A& a, typename A::State& v, const double* g, RareLog& log) {
  { A::stops_early } -> std::convertible_to<bool>;
  { a.draws() } -> std::convertible_to<std::size_t>;
  a.forward(v, g, log, std::uint64_t{0});
  a.reverse(v, g, log, std::uint64_t{0});
  a.negate(v);
  { a.flat(v) } -> std::convertible_to<std::vector<double>>;
};

/// The reversal illustration's loop, for every case: from the validated start v, N_c
/// collisions forward (d_n draws each, the velocities negated after each to make the next),
/// then all of them back (negate, step the generator back d_n, reverse). Fills r's timings,
/// counts, log size at the turn, final velocities, rng_restored, error and passed (log empty
/// and every collision taken). A reverse step that throws (a wrong reversal hands the next
/// step an invalid state) ends the reversal with `error` saying where. With
/// A::stops_early, a forward step that throws ends the chain: the step before it is taken
/// back (its pre state kept, its draws stepped back) and the steps before that reversed;
/// otherwise the exception propagates.
template <ChainOperator A, class Gen>
void reversal_chain(const A& a, typename A::State v, Gen& gen, const VerifyConfig& c, VerifyResult& r) {
  using Clock = std::chrono::steady_clock;
  auto since = [](Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); };
  const std::size_t k = a.draws();
  const Gen start = gen;
  RareLog log;
  std::vector<double> g(k > 0 ? k : 1);
  typename A::State last_pre = v, pre = v;  // the pre state of the last step (to take it back)

  InterruptPoll poll(c.interrupt);
  auto t0 = Clock::now();
  std::uint64_t done = 0;
  try {
    for (; done < c.collisions; ++done) {
      poll.tick();
      for (std::size_t j = 0; j < k; ++j) g[j] = gen.next();
      if constexpr (A::stops_early) pre = v;
      try {
        a.forward(v, g.data(), log, done);
      } catch (...) {
        for (std::size_t j = 0; j < k; ++j) (void)gen.prev();  // this collision did not happen
        throw;
      }
      if constexpr (A::stops_early) last_pre = pre;
      a.negate(v);  // reverse the velocities to create the next collision
    }
  } catch (const InvalidArgument& e) {
    if (!A::stops_early) throw;
    // step `done + 1` refused the state that step `done` left: that step's post state does not
    // separate. Take step `done` back too and reverse the steps before it.
    r.error = "forward step " + std::to_string(done) + " of " + std::to_string(c.collisions) +
              " produced a post-collision state that the next step refuses (" + e.what() +
              "); stopped, that step taken back, the " + std::to_string(done - 1) +
              " steps before it reversed";
    if (done > 0) {
      for (std::size_t j = 0; j < k; ++j) (void)gen.prev();
      v = last_pre;
      --done;
    }
  }
  r.forward_s = since(t0);
  r.collisions = done;  // the rates are per collision actually taken
  r.log_bytes = log.bytes();
  r.log_entries = log.size();
  r.random_numbers_drawn = done * k;

  t0 = Clock::now();
  std::uint64_t undone = 0;
  try {
    for (; undone < done; ++undone) {
      poll.tick();
      a.negate(v);
      for (std::size_t j = k; j-- > 0;) g[j] = gen.prev();
      a.reverse(v, g.data(), log, done - 1 - undone);
    }
  } catch (const InvalidArgument& e) {
    r.error += (r.error.empty() ? "" : "; ") + std::string("reverse step ") +
               std::to_string(undone + 1) + " of " + std::to_string(done) + ": " + e.what();
    ++undone;  // its numbers were stepped back
  }
  r.reverse_s = since(t0);
  r.random_numbers_undone = undone * k;
  r.final_velocities = a.flat(v);
  r.rng_restored = gen == start;
  r.passed = log.size() == 0 && done == c.collisions;
}
}  // namespace detail

/// The result as a JSON object (one line).
std::string to_json(const VerifyResult& r);

}  // namespace revcol
