// The paper's performance study (§6, \label{sec:performance}): state saving (SS1, SS2)
// against reverse computation (RC) on a closed system of N particles in 2D, and the same
// study with lazy transport, which the paper did not do.
//
// Workload (one "step" = one collision). The start: positions uniform in the unit box
// [0,1)^2, velocity components uniform in [-1,1), both a pure function of (seed, particle)
// through Philox, so the check after rollback regenerates the start instead of keeping a
// copy (a copy would count against RC's memory). Step k = 0..N_c-1 draws exactly three
// numbers from the reversible generator, in this order:
//   u_pair  ordered pair i != j:  m = floor(u_pair N(N-1)) (clamped to N(N-1) - 1),
//           i = m div (N-1), j = m mod (N-1), j += (j >= i)       (exact for N <= 2^26)
//   u_time  dt = T ticks, T = floor(-ln(max(u_time, 2^-53)) 2^32), 1 tick = mean_dt 2^-32:
//           an exponential inter-collision time with mean mean_dt, held as an integer so
//           that the clock t = ticks * tick comes back exactly
//   G       the pair operator's one draw (Pair2DExact, Pair2DPaper: d_n = 1)
// then moves every particle, x += v dt (eager transport), and collides (i, j) with the
// contact normal n = +-(x_i - x_j) (the paper's workload ignores geometry: the pair need not
// touch). Reverse step: G, u_time, u_pair = prev() three times (the reverse order), the same
// pair and dt from the same values, the reverse operator at the current positions, then
// x -= v dt. x -= v dt is not the exact inverse of x += v dt in floating point: positions
// come back to about 1e-16 per step, and the measured error is reported.
//
// Orientation. p = n.(v_i - v_j), w = v_i - v_j. Forward uses the normal s n with s = -sign(p),
// so that the pair approaches (the operators need normal.w < 0 before, > 0 after). In
// reverse the post state separates along exactly one of +-n: s = sign(p'). Grazing rule:
// when |p| <= tau |n||w| (tau = 1e-6; also a zero normal, a zero relative velocity or a
// non-finite value) the pair grazes and the step changes no velocity (G is still drawn);
// reverse applies the same test to the post state. Reverse sees positions and velocities
// that differ from forward's by rounding (and by exact mode's quantization, below), so
// forward records its decision (the *decision log*, 8 bytes: step, kind) wherever reverse
// could decide otherwise: a graze with |p| > tau/2 |n||w|, or a collision whose post state
// separates by less than 2 tau |n||w_post|. Unlogged decisions are then robust to relative
// perturbations below tau/2. Both cases have probability ~tau per step.
//
// Exact mode's quantization (the *pre log*). Exact mode restores a pre state at the centre
// of its K-bit chart cell, not the pre state itself: every collision of the N-particle run is
// a "first quantization" (verify's bit-exactness is for one pair reusing its own outputs).
// The flux chart c = (1 + sin eta)/2 is wide in angle near grazing: the restored direction
// is off by up to 2^-K / cos(eta), so each velocity by up to |w| 2^-(K+1) / cos(eta) (the
// uniform chart: |w| pi 2^-(K+2), never large). Forward therefore logs the pair's pre
// velocities (40 bytes: step + 4 doubles, restored bit for bit) when that bound exceeds
// grazing_tol max|v_0|; grazing_tol = inf turns it off. Paper mode needs no pre log.
// Errors also *grow* under the flux law: reversal maps an angle error of the post state
// onto the pre state stretched by cos(eta_post) / cos(eta_pre), and here the pre angles are
// uniform (a random pair, whatever its approach speed) while flux posts lean to cos ~ 1, so
// the mean log-stretch is E log cos_post - E log cos_pre = (log 2 - 1) + log 2 = 0.39 per
// collision along a particle's history, seeded at the cell size. Measured (docs/statesave.md):
// with grazing_tol = 1e-11 (about 3% of collisions logged) the round trip stays near 1e-10
// at about 2 collisions per particle (N_c = 1000, N >= 1000), while beyond about 4 per
// particle exact/flux misses 1e-9 (7e-8 at 10, 3e-2 at 20, O(1) at 200). The uniform law
// (an isometric chart) and paper mode do not stretch: 3e-11 after 200 per particle.
//
// Lazy transport (beyond the paper). Each particle stores x0 = x - v t, its position
// extrapolated to time zero, so a step touches only its pair: O(1) instead of O(N). At a
// collision at time t the positions are x0 + v t; the velocity change keeps the position:
// x0 += (v_old - v_new) t. Reverse applies x0 -= (v_pre - v_post) t, with t exact (ticks).
//
// Variants and what each saves per step (before the step; bytes counted exactly):
//   ss1  all positions and velocities (32 N) + clock (8) + generator state (16)
//   ss2  all positions (16 N) + pair indices (8) + the pair's pre velocities (32) + 8 + 16
//   ssp  lazy only, the best state saving lazy transport allows: pair indices (8) + the
//        pair's x0 and velocities (64) + 8 + 16
//   rc   nothing; rollback by reverse computation. Memory: the operator's rare log + the
//        decision log + the pre log, reported as bytes_saved (expected ~0).
// State saving rolls back step by step (the last step first, restoring its record), as an
// optimistic simulator undoes events one by one; restoring only the first record would be
// a single copy. Runs whose saved bytes would exceed budget_bytes are not attempted.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "revcol/collide/common.hpp"
#include "revcol/fixed_point.hpp"
#include "revcol/interrupt.hpp"

namespace revcol::statesave {

/// ss1: save everything; ss2: positions + the pair's velocities; ssp: the pair (lazy); rc: nothing.
enum class Variant { ss1, ss2, ssp, rc };
/// eager: every step moves every particle (the paper); lazy: x0 = x - v t, O(1) per step.
enum class Transport { eager, lazy };

/// "ss1", "ss2", "ssp", "rc".
const char* to_string(Variant v);
/// "eager", "lazy".
const char* to_string(Transport t);
/// Parses a variant name; throws InvalidArgument naming the allowed values.
Variant parse_variant(const std::string& s);
/// Parses a transport name; throws InvalidArgument naming the allowed values.
Transport parse_transport(const std::string& s);
/// The variants a transport supports, in report order (eager: ss1 ss2 rc; lazy: ss1 ss2 ssp rc).
std::vector<std::string> variant_names(Transport t);

/// Random draws per step: pair, time, the operator's G.
inline constexpr int draws_per_step = 3;
/// Largest N: N(N-1) must stay below 2^53 so that the pair draw is exact.
inline constexpr std::uint64_t max_particles = std::uint64_t{1} << 26;
/// Grazing band of the orientation rule (see the header comment).
inline constexpr double grazing_band = 1e-6;
/// The default memory budget for saved state: 8 GiB.
inline constexpr std::uint64_t default_budget_bytes = std::uint64_t{8} << 30;

/// What to run.
struct Config {
  std::uint64_t particles = 1000;        ///< N
  std::uint64_t collisions = 1000;       ///< N_c (steps forward, then as many back)
  Variant variant = Variant::rc;         ///< ss1 | ss2 | ssp | rc
  Transport transport = Transport::eager;  ///< eager | lazy
  Mode mode = Mode::exact;               ///< exact (Pair2DExact) | paper (Pair2DPaper)
  Law law = Law::flux;                   ///< exact mode's law
  int bits = FixedPoint::default_bits;   ///< exact mode's K
  std::string rng = "clcg4";             ///< clcg4 (stream seed) | philox (key {0, seed})
  std::uint64_t seed = 0;                ///< picks the generator and the start; < 2^32
  double mean_dt = 1e-5;                 ///< mean inter-collision time (box 1, speeds ~1)
  double grazing_tol = 1e-11;            ///< exact mode's pre log threshold (inf: off)
  std::uint64_t budget_bytes = default_budget_bytes;  ///< skip runs that would save more
  bool prefault = true;                  ///< ss: touch the records' pages before the clock starts
  bool capture = false;                  ///< keep the start, the turn and the end (tests)
  InterruptCheck interrupt;              ///< polled about every 2^20 particle updates: true stops with Interrupted
};

/// Particle arrays (structure of arrays). Positions are at the snapshot's time (lazy: x0 + v t).
struct Snapshot {
  std::vector<double> x, y, vx, vy;      ///< positions and velocities
  std::uint64_t ticks = 0;               ///< the clock, in ticks of mean_dt 2^-32
};

/// What a run found. Times in seconds; bytes exact.
struct Result {
  Config config;                         ///< what ran
  bool skipped = false;                  ///< not attempted: projected_bytes > budget_bytes
  std::uint64_t projected_bytes = 0;     ///< saved bytes the run needs (rc: 0; its logs are not known ahead)
  std::uint64_t record_bytes = 0;        ///< saved bytes per step (rc: 0)
  std::uint64_t bytes_saved = 0;         ///< counted at the turn: records (ss) or logs (rc)
  std::uint64_t state_bytes = 0;         ///< the particle arrays themselves (32 N)
  double forward_s = 0.0;                ///< N_c steps forward, saving included
  double rollback_s = 0.0;               ///< N_c steps back
  std::uint64_t rss_before_bytes = 0;    ///< resident set before the run allocated anything
  std::uint64_t peak_rss_bytes = 0;      ///< the process's peak resident set (VmHWM) after the run
  std::uint64_t rare_log_entries = 0;    ///< the operator's rare log at the turn (8 bytes each)
  std::uint64_t decision_log_entries = 0;  ///< decision log at the turn (8 bytes each)
  std::uint64_t pre_log_entries = 0;     ///< pre log at the turn (40 bytes each)
  std::uint64_t log_bytes = 0;           ///< the three logs' bytes at the turn (rc's memory)
  std::uint64_t grazes = 0;              ///< steps whose pair grazed (no velocity change)
  std::uint64_t draws = 0;               ///< next() calls forward (3 N_c)
  std::uint64_t draws_undone = 0;        ///< prev() calls in rollback (rc: 3 N_c)
  bool rng_restored = false;             ///< the generator is back at its start
  bool clock_restored = false;           ///< ticks back to 0
  bool bit_exact = false;                ///< every position and velocity equals the start bit for bit
  double max_rel_error_x = 0.0;          ///< max |x_end - x_0| / box (box = 1)
  double max_rel_error_v = 0.0;          ///< max |v_end - v_0| / max |v_0|
  double max_rel_error = 0.0;            ///< the larger of the two
  bool restored = false;                 ///< ss: bit_exact; rc: max_rel_error <= 1e-9; both: rng, clock, logs
  std::string error;                     ///< why the rollback stopped early; empty if it did not
  Snapshot start, turn, end;             ///< with capture only
};

/// Throws InvalidArgument naming the problem unless the configuration can run.
void validate(const Config& c);
/// Saved bytes per step for the configuration's variant (rc: 0).
std::uint64_t record_bytes(const Config& c);
/// Saved bytes the run needs: record_bytes * collisions (rc: 0).
std::uint64_t projected_bytes(const Config& c);
/// Whether the run would be skipped for its memory budget.
inline bool over_budget(const Config& c) { return projected_bytes(c) > c.budget_bytes; }
/// Validates, then runs forward and rolls back (or skips), and checks the start came back.
Result run(const Config& c);

/// The process's peak resident set in bytes (VmHWM; getrusage as a fallback).
std::uint64_t peak_rss_bytes();
/// The process's current resident set in bytes (VmRSS; 0 if unknown).
std::uint64_t current_rss_bytes();

}  // namespace revcol::statesave
