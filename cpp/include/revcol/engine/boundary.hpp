// The boundary seam of the engine: what each axis of the box [0, L_k] does to a particle,
// one type per kind of boundary, chosen per axis (Config::boundary).
//
// Every axis type answers the same questions (static, so that Boundaries' switch on the
// axis's kind, `visit`, inlines them):
//   periodic, walls     whether pairs see each other's images across the axis; whether it
//                       has walls at 0 and L (the engine predicts wall events on it);
//   image(d, L, code)   the nearest image of a separation d of two list centres and its code
//                       (0: as is, 1: x_j + L, 2: x_j - L); shift(code, L) the offset;
//   wrap(x, c, L)       a stored position whose line has left [0, L) moved back by L;
//   wall_at(up, ...)    the centre's position at the wall ahead (upper if up);
//   touches, meets      the contact of a centre with the axis's walls (within tol, or past),
//                       and whether it meets the wall its velocity component approaches
//                       (the wall operator's per-axis test, revcol/collide/wall.hpp);
//   whole               whether its reflection acts on the whole velocity (then it takes
//                       precedence at a corner, below);
//   reflect(k, v)       what the axis's wall does to the velocity v (all its components) of
//                       a particle that meets it; returns the Reflection applied.
// WallAxis: reflecting walls at 0 and L (the paper §2.2): v_k -> -v_k. PeriodicAxis: the
// axis wraps, no walls. BounceAxis: bounce-back (no-slip) walls at 0 and L, Maxwell's
// rough wall of kinetic theory and lattice Boltzmann: v -> -v, the whole velocity. It keeps
// the energy, draws nothing, and takes away the tangential momentum (a channel with
// periodic x and bounce y walls relaxes its x momentum towards 0; specular y walls keep it).
//
// A Reflection is what a wall did to a velocity, as a mask: bit k, component k flipped; or
// kReversed, every component negated (v -> -v). The engine's wall-mask log keeps these
// masks (W1, W2 at a collision: revcol/engine/logs.hpp), and apply() re-applies one: each
// is its own inverse, so the reversed run undoes a reflection by applying its mask again.
//
// Walls at one instant. A standalone wall event on axis k (Boundaries::reflect_at) applies
// axis k's own reflection, whatever other walls the particle touches: for any velocity v,
// with R_k that reflection and T(v) = -v the time reversal, T(R_k(v)) meets wall k again
// (R_k turned v's approach into a retreat; T turns it back) and R_k(T(R_k(v))) = T(v), so
// the reversed run's event at the same wall restores the state, one event at a time. At an
// exact corner the events of one instant (lowest axis first) compose to the corner rule
// below. One guard (reflect_at): after v -> -v a wall the particle is at or past and now
// approaches flips its component at once, or two bounce walls of an exact corner would hand
// a particle back and forth at one instant forever (a state only a collision in the corner
// makes; it is not reversed exactly: docs/engine.md, "Not done"). The walls a particle meets at a collision's instant (W1, W2: Boundaries::reflect)
// are the corner rule itself: the walls it meets (touches within tol, or is past, and
// approaches) are found first; if one of them acts on the whole velocity, the first such
// (lowest axis) applies alone, once; otherwise every met wall applies (each flips its own
// component). Then a wall the particle touches and now approaches (possible only after a
// whole-velocity reflection, at a corner within tol) flips its own component, so that the
// particle leaves the instant receding from every wall it touches (no further wall event
// at the collision's instant: the reversal protocol of engine.hpp relies on it). The
// result is returned as one mask (-v then flips on J is the flips on the other axes), which
// the log keeps, so that instant is reversed from the log, not recomputed.
//
// To add a boundary type (ARCHITECTURE.md "To add a boundary type"): a new Boundary value
// (engine.hpp: the enum, to_string, kBoundaries), an axis type here with the questions
// above and its case in Boundaries::visit, its parsing and validation in engine.cpp, tests.
#pragma once
#include <array>
#include <bit>
#include <cmath>
#include <limits>

#include "revcol/collide/wall.hpp"
#include "revcol/engine/engine.hpp"

namespace revcol::engine {

/// A reflection's mask: bit k (k < 3) component k flipped, or kReversed (v -> -v).
using Reflection = unsigned;
/// The mask of v -> -v (fits the 8 bits a WallLog mask has per reflection).
inline constexpr Reflection kReversed = 1u << 7;

/// Applies a reflection's mask to v (each mask is its own inverse).
template <int Dim>
void apply(Reflection mask, std::array<double, Dim>& v) {
  for (int k = 0; k < Dim; ++k)
    if ((mask & kReversed) || (mask >> k & 1u)) v[k] = -v[k];
}
/// The wall reflections a mask counts: one for kReversed, one per flipped component.
inline int reflections(Reflection mask) { return (mask & kReversed) ? 1 : std::popcount(mask); }

/// Reflecting walls at 0 and L on one axis.
struct WallAxis {
  static constexpr bool periodic = false;  ///< no images
  static constexpr bool walls = true;      ///< walls at 0 and L
  static constexpr bool whole = false;     ///< reflects its own component only
  /// Nearest image of a separation d: d itself (code 0).
  static double image(double d, double /*L*/, unsigned& code) {
    code = 0;
    return d;
  }
  /// Never moves a stored position.
  static bool wrap(double& /*x*/, double /*c*/, double /*L*/) { return false; }
  /// The centre's position at the wall ahead: L - r above, r below.
  static double wall_at(int up, double L, double radius) { return up ? L - radius : radius; }
  /// Whether the centre x touches the wall ahead (upper if up) within tol (or is past it).
  static bool touches_ahead(double x, int up, double L, double radius, double tol) {
    return (up ? (L - radius) - x : x - radius) <= tol;
  }
  /// Whether the centre x touches either wall within tol.
  static bool touches(double x, double L, double radius, double tol) {
    return Wall::touches_axis(0.0, L, x, radius, tol);
  }
  /// Whether the centre x meets the wall its velocity component vk approaches: within tol
  /// of it, or past it (the wall operator's per-axis test).
  static bool meets(double x, double vk, double L, double radius, double tol) {
    return Wall::reflect_axis(0.0, L, x, vk, radius, tol);  // flips its copy of vk only
  }
  /// The reflection of axis k's wall: v_k -> -v_k (bit k).
  template <int Dim>
  static Reflection reflect(int k, std::array<double, Dim>& v) {
    v[k] = -v[k];
    return 1u << k;
  }
};

/// Bounce-back walls at 0 and L on one axis: the walls of WallAxis (position, contact),
/// but a particle that meets one reverses its whole velocity. Under time reversal T(v) = -v
/// it is its own inverse: T(-v) = v meets the same wall again, and -T(-v) = -v = T(v). At a
/// corner it takes precedence (whole): the particle reverses once, whatever else it meets.
struct BounceAxis : WallAxis {
  static constexpr bool whole = true;  ///< reflects the whole velocity
  /// The reflection of a bounce-back wall: v -> -v (kReversed).
  template <int Dim>
  static Reflection reflect(int /*k*/, std::array<double, Dim>& v) {
    for (int j = 0; j < Dim; ++j) v[j] = -v[j];
    return kReversed;
  }
};

/// A periodic axis of length L.
struct PeriodicAxis {
  static constexpr bool periodic = true;  ///< pairs see images across the axis
  static constexpr bool walls = false;    ///< no walls
  static constexpr bool whole = false;    ///< (no reflection)
  /// Nearest image of a separation d (|d| <= L / 2 after), code 1: x_j + L, 2: x_j - L.
  static double image(double d, double L, unsigned& code) {
    code = 0;
    if (d > 0.5 * L) {
      code = 1;
      return d - L;
    }
    if (d < -0.5 * L) {
      code = 2;
      return d + L;
    }
    return d;
  }
  /// A stored position x whose line is at c, outside [0, L), moved by L; returns whether.
  static bool wrap(double& x, double c, double L) {
    if (!(c >= L || c < 0.0)) return false;
    x += c < 0.0 ? L : -L;
    return true;
  }
  /// No wall: never reached.
  static double wall_at(int, double, double) { return std::numeric_limits<double>::infinity(); }
  /// No walls.
  static bool touches_ahead(double, int, double, double, double) { return false; }
  /// No walls.
  static bool touches(double, double, double, double) { return false; }
  /// No walls: nothing is met.
  static bool meets(double, double, double, double, double) { return false; }
  /// No walls: nothing changes.
  template <int Dim>
  static Reflection reflect(int, std::array<double, Dim>&) {
    return 0u;
  }
};

/// The box's axes: each one's kind and length, and the questions above per axis.
template <int Dim>
class Boundaries {
 public:
  using Vec = std::array<double, Dim>;  ///< a d-vector

  Boundaries() = default;
  /// From a configuration: kinds, lengths, D / 2 and the contact tolerance group_tol D.
  explicit Boundaries(const Config& c) : radius_(0.5 * c.diameter), tol_(c.group_tol * c.diameter) {
    for (int k = 0; k < Dim; ++k) {
      kind_[k] = c.boundary[k];
      L_[k] = c.box[k];
    }
  }
  /// Calls f with an axis-type value of axis k's kind (the one switch over the kinds).
  template <class F>
  [[gnu::always_inline]] decltype(auto) visit(int k, F&& f) const {
    switch (kind_[k]) {
      case Boundary::wall: return f(WallAxis{});
      case Boundary::bounce: return f(BounceAxis{});
      case Boundary::periodic: break;
    }
    return f(PeriodicAxis{});
  }

  /// Axis k's kind.
  Boundary kind(int k) const { return kind_[k]; }
  /// Axis k's length L_k.
  double length(int k) const { return L_[k]; }
  /// Whether axis k is periodic.
  bool periodic(int k) const { return kind_[k] == Boundary::periodic; }
  /// Whether axis k has walls.
  bool walls(int k) const {
    return visit(k, [](auto a) { return decltype(a)::walls; });
  }
  /// Whether any axis has walls.
  bool any_walls() const {
    for (int k = 0; k < Dim; ++k)
      if (walls(k)) return true;
    return false;
  }

  /// Nearest image of a separation d of list centres on axis k, with its code.
  double image(int k, double d, unsigned& code) const {
    return periodic(k) ? PeriodicAxis::image(d, L_[k], code) : WallAxis::image(d, L_[k], code);
  }
  /// The offset of image code (0, 1, 2) on axis k: 0, L, -L.
  double shift(int k, unsigned code) const { return code == 1 ? L_[k] : code == 2 ? -L_[k] : 0.0; }
  /// Moves a stored position x (line at c) by L when c has left a periodic axis.
  bool wrap(int k, double& x, double c) const { return periodic(k) && PeriodicAxis::wrap(x, c, L_[k]); }
  // Every question about a particle's contact with a wall takes its radius r; kOwn (the
  // default) is the configuration's D / 2 (a mixture passes each particle's own; the contact
  // tolerance stays group_tol times the largest diameter).
  static constexpr double kOwn = -1.0;
  /// The centre's position at axis k's wall ahead (walls only).
  [[gnu::always_inline]] double wall_at(int k, int up, double r = kOwn) const {
    return visit(k, [&](auto a) __attribute__((always_inline)) { return decltype(a)::wall_at(up, L_[k], rad(r)); });
  }
  /// Whether the centre x touches axis k's wall ahead (walls only).
  [[gnu::always_inline]] bool touches_ahead(int k, double x, int up, double r = kOwn) const {
    return visit(k, [&](auto a) __attribute__((always_inline)) { return decltype(a)::touches_ahead(x, up, L_[k], rad(r), tol_); });
  }
  /// Whether the centre x touches a wall of axis k.
  [[gnu::always_inline]] bool touches(int k, double x, double r = kOwn) const {
    return visit(k, [&](auto a) __attribute__((always_inline)) { return decltype(a)::touches(x, L_[k], rad(r), tol_); });
  }
  /// Whether the centre x meets the wall of axis k that the component vk approaches.
  [[gnu::always_inline]] bool meets(int k, double x, double vk, double r = kOwn) const {
    return visit(k, [&](auto a) __attribute__((always_inline)) { return decltype(a)::meets(x, vk, L_[k], rad(r), tol_); });
  }
  /// Whether axis k's reflection acts on the whole velocity.
  bool whole(int k) const {
    return visit(k, [](auto a) { return decltype(a)::whole; });
  }

  /// The walls met by a particle at x with velocity v at one instant (a collision's): the
  /// corner rule above. Changes v; returns the mask applied (0: no wall met).
  Reflection reflect(const Vec& x, Vec& v, double r = kOwn) const {
    unsigned met = 0;
    int first_whole = -1;
    for (int k = 0; k < Dim; ++k)
      if (meets(k, x[k], v[k], r)) {
        met |= 1u << k;
        if (first_whole < 0 && whole(k)) first_whole = k;
      }
    if (met == 0) return 0u;
    if (first_whole < 0) {
      Reflection applied = 0;
      for (int k = 0; k < Dim; ++k)
        if (met >> k & 1u) applied |= axis_reflect(k, v);
      return applied;
    }
    const Reflection applied = axis_reflect(first_whole, v);
    if (!(applied & kReversed)) return applied;
    unsigned again = 0;  // touched walls that -v approaches: each flips its own component
    for (int k = 0; k < Dim; ++k)
      if (meets(k, x[k], v[k], r)) {
        v[k] = -v[k];
        again |= 1u << k;
      }
    return again == 0 ? kReversed : ((1u << Dim) - 1u) & ~again;
  }
  /// A standalone wall event on axis k of a particle at x: axis k's own reflection (see
  /// above). After a whole-velocity reflection, a wall the particle is at or past (tol 0)
  /// and now approaches flips its own component too: its event would come at this very
  /// instant, and at an exact corner two bounce walls would hand the particle back and forth
  /// forever. Changes v; returns the mask applied.
  Reflection reflect_at(int k, const Vec& x, Vec& v, double r = kOwn) const {
    const Reflection applied = axis_reflect(k, v);
    if (!(applied & kReversed)) return applied;
    unsigned again = 0;
    for (int j = 0; j < Dim; ++j)
      if (j != k && v[j] != 0.0 && walls(j) && touches_ahead_within(j, x[j], v[j] > 0.0 ? 1 : 0, 0.0, r)) {
        v[j] = -v[j];
        again |= 1u << j;
      }
    return again == 0 ? kReversed : ((1u << Dim) - 1u) & ~again;
  }

 private:
  bool touches_ahead_within(int k, double x, int up, double tol, double r) const {
    return visit(k, [&](auto a) __attribute__((always_inline)) { return decltype(a)::touches_ahead(x, up, L_[k], rad(r), tol); });
  }
  double rad(double r) const { return r < 0.0 ? radius_ : r; }
  Reflection axis_reflect(int k, Vec& v) const {
    return visit(k, [&](auto a) __attribute__((always_inline)) { return decltype(a)::template reflect<Dim>(k, v); });
  }

  std::array<Boundary, Dim> kind_{};
  std::array<double, Dim> L_{};
  double radius_ = 0.5, tol_ = 0.0;
};

}  // namespace revcol::engine
