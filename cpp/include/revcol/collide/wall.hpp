// Collision of one particle with the walls of the box (paper §2.2): the velocity component
// normal to a wall changes sign. A particle at an edge or a corner touches several walls
// and reflects on every one it touches and approaches; a touched wall with zero normal
// velocity (grazing) is left alone. Reverse flips the components that recede from touched
// walls, so reverse(forward(v)) = v. One state is refused: touching a wall while moving away
// from it. It is not a collision with that wall, and it makes forward two-to-one ((-1, 2, 3)
// and (-1, 2, -3) at an x-lo/y-hi/z-lo corner both give (1, -2, 3)), so no memoryless
// reverse could tell them apart; in an event-driven run it means the wall was met in an
// earlier event, and the engine reverses events one by one. No random number.
#pragma once
#include <array>
#include <cmath>
#include <string>

#include "revcol/collide/common.hpp"

namespace revcol {

/// A rectangular box [lo_k, hi_k] per axis, d = 1..3.
struct Box {
  int dim = 2;                    ///< number of axes
  std::array<double, 3> lo{};     ///< lower walls
  std::array<double, 3> hi{};     ///< upper walls
};

/// Wall reflection of one particle. A Wall holds its box (what Python's revcol.Wall is); the
/// static forms take the box as an argument, for callers that keep boxes of their own.
class Wall {
 public:
  static constexpr int draws = 0;  ///< random numbers per collision

  /// The walls of `box`.
  explicit Wall(const Box& box) : box_(box) {}
  /// The box whose walls these are.
  const Box& box() const noexcept { return box_; }
  /// forward(box(), x, v, radius, tol).
  std::array<double, 3> forward(const std::array<double, 3>& x, const std::array<double, 3>& v, double radius,
                                double tol = 1e-9) const {
    return forward(box_, x, v, radius, tol);
  }
  /// reverse(box(), x, v, radius, tol).
  std::array<double, 3> reverse(const std::array<double, 3>& x, const std::array<double, 3>& v, double radius,
                                double tol = 1e-9) const {
    return reverse(box_, x, v, radius, tol);
  }

  /// Reflects v on every wall the particle (centre x, radius) touches, within tol, and
  /// approaches. Returns the new velocity; throws InvalidArgument when it touches no wall
  /// or approaches none of those it touches.
  static std::array<double, 3> forward(const Box& box, const std::array<double, 3>& x,
                                       const std::array<double, 3>& v, double radius,
                                       double tol = 1e-9) {
    return flip(box, x, v, radius, tol, /*approaching=*/true);
  }
  /// One axis of the reflection, as the event-driven engine applies it: flips v when the
  /// centre x is within tol of, or past, the wall it approaches (lo + radius when v < 0,
  /// hi - radius when v > 0); returns whether it flipped. One-sided on purpose: a centre
  /// that round-off put a hair beyond the wall still reflects. Self-inverse on the flipped
  /// component, so the engine undoes a flip by flipping again (its wall-mask log says which).
  static bool reflect_axis(double lo, double hi, double x, double& v, double radius, double tol) {
    if ((v < 0.0 && x - (lo + radius) <= tol) || (v > 0.0 && (hi - radius) - x <= tol)) {
      v = -v;
      return true;
    }
    return false;
  }
  /// Whether the centre x touches (within tol, or is past) either wall of the axis.
  static bool touches_axis(double lo, double hi, double x, double radius, double tol) {
    return x - (lo + radius) <= tol || (hi - radius) - x <= tol;
  }

  /// Post -> pre: flips the components receding from touched walls.
  static std::array<double, 3> reverse(const Box& box, const std::array<double, 3>& x,
                                       const std::array<double, 3>& v, double radius,
                                       double tol = 1e-9) {
    return flip(box, x, v, radius, tol, /*approaching=*/false);
  }

 private:
  Box box_;

  static std::array<double, 3> flip(const Box& box, const std::array<double, 3>& x,
                                    const std::array<double, 3>& v, double radius, double tol,
                                    bool approaching) {
    require(box.dim >= 1 && box.dim <= 3, "box dimension must be 1, 2 or 3");
    require(std::isfinite(radius) && radius >= 0.0, "radius must be finite and >= 0");
    require(std::isfinite(tol) && tol >= 0.0, "tolerance must be finite and >= 0");
    std::array<double, 3> out = v;
    bool touched = false;
    int flipped = 0;
    for (int k = 0; k < box.dim; ++k) {
      require(std::isfinite(x[k]) && std::isfinite(v[k]),
              "position and velocity must be finite");
      require(box.hi[k] - box.lo[k] > 2.0 * radius, [&] { return std::string("box is narrower than a particle on axis " + std::to_string(k)); });
      const bool at_lo = std::fabs(x[k] - (box.lo[k] + radius)) <= tol;
      const bool at_hi = std::fabs(x[k] - (box.hi[k] - radius)) <= tol;
      if (!at_lo && !at_hi) continue;
      touched = true;
      // moving towards the touched wall: v < 0 at the lower, v > 0 at the upper one
      const bool towards = (at_lo && v[k] < 0.0) || (at_hi && v[k] > 0.0);
      const bool away = (at_lo && v[k] > 0.0) || (at_hi && v[k] < 0.0);
      require(!(at_lo && at_hi), [&] { return std::string("particle touches both walls of axis " + std::to_string(k)); });
      // before (forward) a touched wall may be approached or grazed, never left; after
      // (reverse) it may be left or grazed, never approached
      require(approaching ? !away : !towards, [&] { return std::string(std::string(approaching ? "pre" : "post") +
                  "-collision particle touches the " + (at_lo ? "lower" : "upper") +
                  " wall of axis " + std::to_string(k) + " while moving " +
                  (approaching ? "away from" : "towards") +
                  " it: not one reversible wall event"); });
      if (approaching ? towards : away) {
        out[k] = -v[k];
        ++flipped;
      }
    }
    require(touched, "particle does not touch any wall");
    require(flipped > 0, approaching ? "particle does not approach any wall it touches"
                                     : "particle does not recede from any wall it touches");
    return out;
  }
};

}  // namespace revcol
