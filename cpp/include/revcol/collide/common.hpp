// Types shared by the collision operators: modes, laws, the rare log, pair invariants.
#pragma once
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "revcol/error.hpp"

namespace revcol {

/// paper: the paper's procedures as printed (with its typos fixed); exact: DESIGN.md §3;
/// specular: the deterministic elastic reflection (collide/specular.hpp; the engine only:
/// parse_mode refuses it, revcol::engine::parse_engine_mode accepts it).
enum class Mode { paper, exact, specular };
/// The target law of the exact operator on the permitted set P (DESIGN.md "Which law").
/// flux: density proportional to the separation rate a.x (the default: keeps an
/// event-driven gas in equilibrium); uniform: uniform over P (the paper's requirement).
enum class Law { flux, uniform };

/// "paper" / "exact".
inline const char* to_string(Mode m) {
  return m == Mode::paper ? "paper" : m == Mode::specular ? "specular" : "exact";
}
/// "flux" / "uniform".
inline const char* to_string(Law l) { return l == Law::flux ? "flux" : "uniform"; }
/// Parses "paper" / "exact"; throws InvalidArgument naming the allowed values.
inline Mode parse_mode(const std::string& s) {
  if (s == "paper") return Mode::paper;
  if (s == "exact") return Mode::exact;
  throw InvalidArgument("mode must be 'exact' or 'paper', got '" + s + "'");
}
/// Parses "flux" / "uniform"; throws InvalidArgument naming the allowed values.
inline Law parse_law(const std::string& s) {
  if (s == "flux") return Law::flux;
  if (s == "uniform") return Law::uniform;
  throw InvalidArgument("law must be 'flux' or 'uniform', got '" + s + "'");
}

/// The speed range of the operators (issue 17). A collision's relative speed |w| must lie in
/// [kMinRelativeSpeed, kMaxSpeed] and every velocity component in [-kMaxSpeed, kMaxSpeed]:
/// below, squares and the chart's products of |w| underflow (a round trip of 1e-5 at 1e-160,
/// NaN at 1e-170); above, energies and the chart's products overflow (NaN at 1e150 for 9 of the
/// 15 named cases). Inside, every named case's round trip is the same as at speed 1
/// (tests/python/test_hardening.py: at the limits and just outside them).
inline constexpr double kMinRelativeSpeed = 0x1.0p-480;  // about 1.0e-144
/// Upper end of the speed range (see kMinRelativeSpeed).
inline constexpr double kMaxSpeed = 0x1.0p+450;  // about 2.9e135

/// Throws InvalidArgument unless the largest |velocity component| and the relative speed's scale
/// (its largest |component|, which never underflows as |w|^2 does) lie in the operators' speed
/// range [kMinRelativeSpeed, kMaxSpeed]; a zero relative speed has its own message.
inline void check_speed_range(double max_component, double relative_scale) {
  require(max_component <= kMaxSpeed, "velocities too large: a component exceeds 2^450 (about 2.9e135)");
  require(relative_scale > 0.0, "zero relative speed: the particles cannot collide");
  require(relative_scale >= kMinRelativeSpeed,
          "relative speed too small: below 2^-480 (about 1.0e-144), where the chart underflows");
}

/// The largest |x_k| of n values (0 for n = 0).
inline double max_abs(const double* x, int n) {
  double m = 0.0;
  for (int k = 0; k < n; ++k) m = std::fmax(m, std::fabs(x[k]));
  return m;
}

/// The rare log (DESIGN.md §4): a stack of pre-collision chart cells that the post state
/// cannot give back to half a cell. Forward pushes, reverse pops, in LIFO order.
class RareLog {
 public:
  /// Pushes one K-bit chart cell.
  void push(std::uint64_t cell) { cells_.push_back(cell); ++pushed_; }
  /// Pops the most recent cell; throws InvalidArgument when empty (a reversal the log
  /// cannot serve: the post state was not produced by this operator's forward step).
  std::uint64_t pop() {
    require(!cells_.empty(), "rare log is empty: this post-collision state needs a logged "
                             "coordinate that was never recorded");
    const std::uint64_t c = cells_.back();
    cells_.pop_back();
    return c;
  }
  /// Entries now on the stack.
  std::size_t size() const { return cells_.size(); }
  /// Bytes now held (8 per entry).
  std::size_t bytes() const { return cells_.size() * sizeof(std::uint64_t); }
  /// Entries ever pushed (a rate: pushed / collisions).
  std::uint64_t pushed() const { return pushed_; }
  /// Empties the stack and the counter.
  void clear() { cells_.clear(); pushed_ = 0; }
  /// The stack, oldest first (for checkpoints).
  const std::vector<std::uint64_t>& cells() const { return cells_; }

 private:
  std::vector<std::uint64_t> cells_;
  std::uint64_t pushed_ = 0;
};

/// Momentum and energy of a colliding group, computed once and held (the paper's
/// Reversal Illustrations compute them before the loop). energy = sum |v_i|^2 (no 1/2).
/// The relative speed they imply, sqrt(2E - |M|^2), cancels when the centre of mass is fast:
/// at |cm| / |w| ~ 1e6 no double precision (E, M) carries it at all. Held invariants are
/// therefore for the paper's illustrations; the engine recomputes w as a difference.
template <int Dim>
struct Invariants {
  double momentum[Dim];  ///< sum of the velocities
  double energy;         ///< sum of the squared speeds
};

/// True when every value is finite.
inline bool all_finite(const double* x, int n) {
  for (int k = 0; k < n; ++k)
    if (!std::isfinite(x[k])) return false;
  return true;
}

}  // namespace revcol
