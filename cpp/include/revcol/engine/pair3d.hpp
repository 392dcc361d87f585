// The engine's 3D pair operator, behind one alias: Pair3DExact (revcol/collide/
// pair3d_exact.hpp: Pair2DExact's interface with PairV<3>, a 3-vector normal and 2 draws).
// Pair3DViaExact, the general ExactCollision built per collision (n = 2, d = 3, one contact),
// is kept as the alternative and for comparison; in a gas it does not reverse: its rare-log
// test includes a quarter-cell offset check on the recovered chart coordinates, and the
// reversed run hands it post velocities that differ from forward's by about one cell (each
// later collision restores its pre state to its cell centre), so that check disagrees
// between the directions about half the time (measured: O(1) round-trip errors after
// ~10 collisions at N = 100). Pair3DExact's test is a recovery bound only.
#pragma once
#include <array>

#include "revcol/collide/common.hpp"
#include "revcol/collide/exact.hpp"
#include "revcol/collide/pair.hpp"
#include "revcol/collide/pair3d_exact.hpp"

namespace revcol::engine {

/// Two spheres in 3D through ExactCollision, with Pair3DExact's interface.
class Pair3DViaExact {
 public:
  static constexpr int dim = 3;        ///< d
  static constexpr int particles = 2;  ///< n
  static constexpr int draws = 2;      ///< d_n = 2

  /// The target law and the chart bits K.
  explicit Pair3DViaExact(Law law = Law::flux, int bits = 40) : law_(law), bits_(bits) {}

  /// Pre -> post; normal from j to i.
  PairV<3> forward(const PairV<3>& pre, const std::array<double, 3>& normal,
                   const std::array<double, 2>& g, RareLog& log) const {
    const ExactCollision op(2, 3, {{0, 1}}, {normal[0], normal[1], normal[2]}, law_, bits_);
    const double in[6] = {pre.i[0], pre.i[1], pre.i[2], pre.j[0], pre.j[1], pre.j[2]};
    double out[6];
    op.forward(in, g.data(), out, log);
    return PairV<3>{{out[0], out[1], out[2]}, {out[3], out[4], out[5]}};
  }
  /// Post -> pre with the draws forward used.
  PairV<3> reverse(const PairV<3>& post, const std::array<double, 3>& normal,
                   const std::array<double, 2>& g, RareLog& log) const {
    const ExactCollision op(2, 3, {{0, 1}}, {normal[0], normal[1], normal[2]}, law_, bits_);
    const double in[6] = {post.i[0], post.i[1], post.i[2], post.j[0], post.j[1], post.j[2]};
    double out[6];
    op.reverse(in, g.data(), out, log);
    return PairV<3>{{out[0], out[1], out[2]}, {out[3], out[4], out[5]}};
  }

  /// The pre state as a reversal restores it (its cells decoded at their centres).
  PairV<3> quantize(const PairV<3>& pre, const std::array<double, 3>& normal) const {
    const ExactCollision op(2, 3, {{0, 1}}, {normal[0], normal[1], normal[2]}, law_, bits_);
    const double in[6] = {pre.i[0], pre.i[1], pre.i[2], pre.j[0], pre.j[1], pre.j[2]};
    double out[6];
    op.quantize(in, out);
    return PairV<3>{{out[0], out[1], out[2]}, {out[3], out[4], out[5]}};
  }

 private:
  Law law_;
  int bits_;
};

/// The operator the engine uses for 3D pairs (the define is for measuring the alternative).
#ifdef REVCOL_ENGINE_PAIR3D_VIA_EXACT
using EnginePair3D = Pair3DViaExact;
#else
using EnginePair3D = Pair3DExact;
#endif

}  // namespace revcol::engine
