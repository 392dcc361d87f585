// The paper's Reversal Illustrations (§5.1) as a self-check: N_c collisions of one pair with
// momentum and energy computed once and held, velocities negated after each collision, then
// all reversed with the random number generator stepping back; compare with the start.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "revcol/collide/common.hpp"
#include "revcol/fixed_point.hpp"

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
// Families of cases, one source file each (cpp/src/verify_<family>.cpp). Each returns false
// when it does not know config.case_name for config.mode; otherwise it fills r (initial,
// final_velocities, reference, timings, draws, rng_restored, error, and passed = false when
// its own checks fail) and verify() derives max_rel_error, bit_exact and passed from it.
bool run_exact_case(const VerifyConfig& config, VerifyResult& r);  ///< verify_exact.cpp
bool run_paper_case(const VerifyConfig& config, VerifyResult& r);  ///< verify_paper.cpp
std::vector<std::string> exact_case_names();                        ///< verify_exact.cpp
std::vector<std::string> paper_case_names();                        ///< verify_paper.cpp
/// Whether the case's reversal promises bit-exactness (exact mode and pair1d do).
bool promises_bit_exact(const VerifyConfig& config);
}  // namespace detail

/// The result as a JSON object (one line).
std::string to_json(const VerifyResult& r);

}  // namespace revcol
