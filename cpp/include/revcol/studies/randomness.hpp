// The paper's randomness experiment (§5.2) as a word stream: a chain of collisions whose
// post-collision chart coordinates, mapped through their law's CDF, become 32-bit words for
// a Diehard-class battery (dieharder reads them raw: `dieharder -g 201 -f FILE`).
//
// The chain is the paper's Reversal Illustration run forward only: momentum and energy held,
// the post velocities negated to make the next collision (a post state separates, so its
// negation approaches). After collision t the post state x_t gives D - 1 coordinates
//     u = F(x_t) in [0,1)^(D-1),
// F the measure-preserving chart of the law (DESIGN.md §3: each coordinate is the CDF value
// of one one-dimensional law of the chart, trig_cdf.hpp). Under the right law u is uniform
// on the cube, so the words w = floor(u 2^32) are uniform 32-bit integers; a wrong law (the
// operator's law and the mapping's differ) or a biased operator makes them non-uniform.
//
// Exact mode: the operator's own chart maps the post state (Pair2DExact, Pair3DExact, or
// ExactCollision for every other named case), so u is the post cell decoded at its centre
// and w is its top 32 bits: u_t = u_(t-1) + G_t (mod 1) per coordinate, exactly, because
// the next pre state is the negated post state and chart(-x_pre) = chart(x_post).
// Paper mode: the paper's stated law is uniform on the permitted set (uniform in its angles
// on a round circle for pair2d and triple1d), so the exact operator's uniform-law chart of
// the same geometry maps the paper operator's post states; the words show its bias.
// A paper step that fails (a post state that does not separate, or a pre state the
// operator refuses; §4.5's printed procedures can) emits nothing: the chain restarts from
// the case's start and counts a restart.
//
// Generators: "clcg4", "philox" (the project's reversible ones), and two bad controls:
// "randu" (IBM's x <- 65539 x mod 2^31, whose triples lie on 15 planes) and
// "philox-repeat100" (Philox, but every 100th draw repeats the one before it).
// case "raw": the generator's own draws as words, floor(G 2^32) (the battery's controls).
//
// The engine's collisions in a gas ("gas2d", "gas3d"; exact mode, rng philox or clcg4): a
// periodic cube of gas_particles spheres at gas_fraction (engine::random_state, seed), run
// gas_warmup collisions per particle, then each pair collision gives d - 1 words from its
// post relative velocity w about the contact normal a (the observer's collision record,
// engine/observe.hpp). The operator's law does not depend on the pre state, so these CDF
// values are uniform: 2D the signed angle eta from a, flux CDF (1 + sin eta) / 2, uniform
// eta / pi + 1/2; 3D the polar angle eta about a and the azimuth phi (pair3d_exact.hpp's
// frame), flux CDF sin^2(eta) (density cos(eta) sin(eta)), uniform 1 - cos(eta), phi / (2 pi)
// for both. A group collision (three or more in contact) gives no word and is counted
// (skipped()). `law` is the engine's, `cdf_law` the CDF's; the generator draws nothing here
// (the engine's own streams do, keyed by seed).
#pragma once
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "revcol/collide/common.hpp"
#include "revcol/fixed_point.hpp"
#include "revcol/interrupt.hpp"

namespace revcol::randomness {

/// What to stream.
struct StreamConfig {
  std::string case_name = "pair2d";  ///< a named case with d_n >= 1, or "raw"
  Mode mode = Mode::exact;           ///< exact | paper
  Law law = Law::flux;               ///< exact mode: the operator's law
  Law cdf_law = Law::flux;           ///< the law whose chart maps post states to words
  std::string rng = "philox";        ///< clcg4 | philox | randu | philox-repeat100
  std::uint64_t seed = 0;            ///< stream index / key / RANDU start (made odd)
  int bits = FixedPoint::default_bits;  ///< exact mode: K
  std::size_t gas_particles = 1000;  ///< gas2d / gas3d: N
  double gas_fraction = 0.2;         ///< gas2d / gas3d: packing fraction of the periodic cube
  double gas_warmup = 5.0;           ///< gas2d / gas3d: collisions per particle before the first word
};

/// The cases stream_words knows for a mode ("raw" first).
std::vector<std::string> stream_cases(Mode mode);

/// A chain of collisions emitting 32-bit words, resumable: successive calls continue it.
class WordStream {
 public:
  /// Builds the chain; throws InvalidArgument on an unknown case, mode, rng or bits.
  explicit WordStream(const StreamConfig& config);
  ~WordStream();                                    ///< frees the chain
  WordStream(WordStream&&) noexcept;                ///< moves the chain (not copyable)
  WordStream& operator=(WordStream&&) noexcept;     ///< moves the chain

  /// The configuration it runs.
  const StreamConfig& config() const;
  /// Words per collision: d_n (1 for "raw": one per draw).
  int width() const;
  /// Writes the next n words to out. `interrupt` is checked every 2^16 words; when it says
  /// stop, Interrupted is thrown and the stream stays after the words written so far
  /// (words() counts them).
  void fill(std::uint32_t* out, std::size_t n, const InterruptCheck& interrupt = {});
  /// Appends the next n words to the file `path` (raw, native little-endian uint32);
  /// throws InvalidArgument if it cannot be written. Interrupted: the file holds exactly the
  /// words the stream moved past.
  void write(const std::string& path, std::uint64_t n, const InterruptCheck& interrupt = {});
  /// Collisions taken so far (draws for "raw").
  std::uint64_t collisions() const;
  /// Words emitted so far.
  std::uint64_t words() const;
  /// Paper mode: chain restarts after a failed step.
  std::uint64_t restarts() const;
  /// Gas: group collisions seen (they give no word).
  std::uint64_t skipped() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// A chart coordinate as a word: floor(u 2^32), u clamped to [0, 1).
inline std::uint32_t to_word(double u) {
  const double s = std::floor(u * 4294967296.0);
  if (!(s > 0.0)) return 0;
  return s >= 4294967295.0 ? 4294967295u : static_cast<std::uint32_t>(s);
}

}  // namespace revcol::randomness
