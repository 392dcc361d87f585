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
