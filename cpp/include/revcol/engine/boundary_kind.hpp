// The kinds of boundary an axis of the box can have, shared by both engines: their names
// (scenes, Python, checkpoints), the one parser, and whether a kind has walls. The float
// engine's axis types (engine/boundary.hpp) and the lattice engine's reflection (its units'
// per-axis walls and bounce flags, lattice/units.hpp) implement each kind.
#pragma once
#include <array>
#include <cstdint>
#include <string>

namespace revcol::engine {

/// Boundary condition of one axis: reflecting (specular) walls at 0 and L, periodic, or
/// bounce-back (no-slip) walls at 0 and L, which reverse the whole velocity (the axis types
/// are in engine/boundary.hpp). The values are the checkpoint's per-axis entries.
enum class Boundary { wall = 0, periodic = 1, bounce = 2 };

/// Every boundary kind, in the order of their values (parsing and checkpoints read it).
inline constexpr std::array<Boundary, 3> kBoundaries{Boundary::wall, Boundary::periodic, Boundary::bounce};
/// "wall" / "periodic" / "bounce".
inline const char* to_string(Boundary b) {
  switch (b) {
    case Boundary::wall: return "wall";
    case Boundary::periodic: return "periodic";
    case Boundary::bounce: return "bounce";
  }
  return "?";
}
/// Whether an axis of kind b has walls at 0 and L (every kind but periodic).
inline bool has_walls(Boundary b) { return b != Boundary::periodic; }
/// Parses a name of kBoundaries ("wall", "periodic", "bounce"); throws InvalidArgument otherwise.
Boundary parse_boundary(const std::string& s);
/// The kind whose value (a checkpoint's per-axis entry) is v; throws InvalidArgument otherwise.
Boundary boundary_from_value(std::int64_t v);

}  // namespace revcol::engine
