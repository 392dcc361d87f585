// The boundary seam of the engine: what each axis of the box [0, L_k] does to a particle,
// one type per kind of boundary, chosen per axis (Config::boundary).
//
// Every axis type answers the same questions (static, so that the engine's switch on the
// axis's kind inlines them):
//   periodic            whether pairs see each other's images across the axis;
//   image(d, L, code)   the nearest image of a separation d of two list centres and its code
//                       (0: as is, 1: x_j + L, 2: x_j - L); shift(code, L) the offset;
//   wrap(x, c, L)       a stored position whose line has left [0, L) moved back by L;
//   wall_at(up, ...)    the centre's position at the wall ahead (upper if up) or none;
//   touches / reflect   the contact of a centre with the axis's walls (within tol, or past)
//                       and the reflection of the velocity component (revcol/collide/wall.hpp,
//                       the wall operator's per-axis form).
// WallAxis: reflecting walls at 0 and L (the paper §2.2). PeriodicAxis: the axis wraps.
//
// To add a boundary type: a new Boundary value (engine.hpp, with to_string / parse), an
// axis type here with the questions above and its case in Boundaries' switches, and its
// validation in engine.cpp (ARCHITECTURE.md "To add a boundary type").
#pragma once
#include <array>
#include <cmath>

#include "revcol/collide/wall.hpp"
#include "revcol/engine/engine.hpp"

namespace revcol::engine {

/// Reflecting walls at 0 and L on one axis.
struct WallAxis {
  static constexpr bool periodic = false;  ///< no images
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
  /// Flips v when x touches the wall v approaches; returns whether it flipped.
  static bool reflect(double x, double& v, double L, double radius, double tol) {
    return Wall::reflect_axis(0.0, L, x, v, radius, tol);
  }
};

/// A periodic axis of length L.
struct PeriodicAxis {
  static constexpr bool periodic = true;  ///< pairs see images across the axis
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
  /// No walls.
  static bool touches(double, double, double, double) { return false; }
  /// No walls: nothing flips.
  static bool reflect(double, double&, double, double, double) { return false; }
};

/// The box's axes: each one's kind and length, and the questions above per axis.
template <int Dim>
class Boundaries {
 public:
  Boundaries() = default;
  /// From a configuration: kinds, lengths, D / 2 and the contact tolerance group_tol D.
  explicit Boundaries(const Config& c) : radius_(0.5 * c.diameter), tol_(c.group_tol * c.diameter) {
    for (int k = 0; k < Dim; ++k) {
      kind_[k] = c.boundary[k];
      L_[k] = c.box[k];
    }
  }
  /// Axis k's kind.
  Boundary kind(int k) const { return kind_[k]; }
  /// Axis k's length L_k.
  double length(int k) const { return L_[k]; }
  /// Whether axis k is periodic.
  bool periodic(int k) const { return kind_[k] == Boundary::periodic; }
  /// Whether axis k has walls.
  bool walls(int k) const { return kind_[k] == Boundary::wall; }
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
  /// The centre's position at axis k's wall ahead (walls only).
  double wall_at(int k, int up) const { return WallAxis::wall_at(up, L_[k], radius_); }
  /// Whether the centre x touches axis k's wall ahead (walls only).
  bool touches_ahead(int k, double x, int up) const { return WallAxis::touches_ahead(x, up, L_[k], radius_, tol_); }
  /// Whether the centre x touches a wall of axis k.
  bool touches(int k, double x) const { return walls(k) && WallAxis::touches(x, L_[k], radius_, tol_); }
  /// Reflects v on axis k if x touches the wall it approaches; returns whether it flipped.
  bool reflect(int k, double x, double& v) const { return walls(k) && WallAxis::reflect(x, v, L_[k], radius_, tol_); }

 private:
  std::array<Boundary, Dim> kind_{};
  std::array<double, Dim> L_{};
  double radius_ = 0.5, tol_ = 0.0;
};

}  // namespace revcol::engine
