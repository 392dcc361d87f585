// The paper-mode cases (geometry and default start of each Reversal Illustration) and the
// measurement of how often a printed procedure fails to reverse: forward one collision,
// reverse it with the same draws, compare with the pre state, 10^6 times.
//
// pre = "chain": the verify chain (post negated becomes the next pre, momentum and energy
//   held), restarted from a fresh "uniform" pre state whenever the forward step produced a
//   post state that does not separate (the chain cannot go on from it);
// pre = "uniform": every pre state fresh, velocities i.i.d. standard normal conditioned on
//   approaching at every contact (so the relative velocities are uniform on the pre cone).
// A collision fails when the forward post state does not separate (invalid_post), when the
// reverse step throws (reverse_threw: its output was not a valid state, or the log was
// empty), or when it returns a state farther than 1e-9 (relative) from the pre state (wrong).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "revcol/collide/ellipse_arc.hpp"
#include "revcol/interrupt.hpp"

namespace revcol::paper {

/// A paper-mode case: geometry and the default start of its reversal illustration.
struct PaperCase {
  std::string name;                ///< pair3d | triple1d | triple2d-c1 .. triple2d-c4
  int n = 0, d = 0;                ///< particles, dimension
  std::vector<double> geometry;    ///< pair3d: normal r21 (3); triple1d: positions (3); triple2d: positions (3 x 2)
  std::vector<double> velocities;  ///< default start, n x d by particle id; approaches at every contact
  std::string description;         ///< one line
};

/// The paper-mode cases, in a stable order.
const std::vector<PaperCase>& paper_cases();
/// The case called `name`; throws InvalidArgument listing the known names otherwise.
const PaperCase& paper_case(const std::string& name);

/// What to measure.
struct StudyConfig {
  std::string case_name = "triple1d";     ///< a paper case
  std::uint64_t collisions = 1000000;     ///< collisions to try
  std::uint64_t seed = 0;                 ///< CLCG4 stream of the draws; also seeds fresh pre states
  std::string pre = "chain";              ///< chain | uniform
  bool printed_reverse = false;           ///< pair3d, triple1d: the printed reverse test
  double cos_tol = 1e-8;                  ///< triple1d: the cosine tolerance
  ArcMethod arc = ArcMethod::simpson;     ///< triple1d: G-to-Psi method
  ArcAngle angle = ArcAngle::parametric;  ///< triple1d: which angle psi is
  InterruptCheck interrupt;               ///< polled in the loops: true stops with Interrupted (Ctrl-C)
};

/// What it found.
struct StudyResult {
  StudyConfig config;                ///< what ran
  std::uint64_t collisions = 0;      ///< collisions tried
  std::uint64_t ok = 0;              ///< reversed within 1e-9
  std::uint64_t invalid_post = 0;    ///< forward gave a post state that does not separate
  std::uint64_t reverse_threw = 0;   ///< reverse threw InvalidArgument
  std::uint64_t wrong = 0;           ///< reverse returned another state
  std::uint64_t restarts = 0;        ///< chain: fresh starts after an invalid post state
  std::uint64_t logged = 0;          ///< rare-log pushes (pair3d)
  double failure_rate = 0.0;         ///< (invalid_post + reverse_threw + wrong) / collisions
  double max_ok_error = 0.0;         ///< largest relative error among the ok round trips
  std::string first_failure;         ///< the first failing collision, in words
};

/// Runs the measurement. Throws InvalidArgument on a bad configuration.
StudyResult study(const StudyConfig& config);

/// Throughput of one case's operator (for revcol-bench): the chain of `study` in blocks of
/// 4096 collisions, forward timed over every collision, reverse over the valid post states.
struct Throughput {
  double forward_per_s = 0.0;  ///< forward collisions per second
  double reverse_per_s = 0.0;  ///< reverse collisions per second (valid post states only)
  double valid_fraction = 0.0; ///< post states that separate
};
/// Measures config.collisions collisions of config.case_name.
Throughput throughput(const StudyConfig& config);
/// The result as a JSON object (one line).
std::string to_json(const StudyResult& r);

}  // namespace revcol::paper
