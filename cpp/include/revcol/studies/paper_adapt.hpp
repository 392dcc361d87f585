// The paper-mode operators behind one interface, for the studies that drive all three (the
// paper study, the paper verify cases, the randomness study and the tradeoff bench): state from
// a flat vector, flatten, negate, held invariants, the approach/separation predicates, and a
// small deterministic normal generator.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "revcol/collide/pair3d_paper.hpp"
#include "revcol/collide/triple1d_paper.hpp"
#include "revcol/collide/triple2d_paper.hpp"
#include "revcol/rng/normal.hpp"
#include "revcol/studies/paper_study.hpp"

namespace revcol::paper::adapt {

using Normal = rng::SplitMixNormal;  // revcol/rng/normal.hpp

/// One paper-mode operator seen through the studies' interface (specialised per operator).
template <class Op> struct Adapter;

/// The 3D pair: a 6-component state, the contact normal as geometry.
template <>
struct Adapter<Pair3DPaper> {
  using Op = Pair3DPaper;
  static Op::State state(const std::vector<double>& v) {
    require(v.size() == 6, "pair3d needs 6 initial velocity components");
    return {{v[0], v[1], v[2]}, {v[3], v[4], v[5]}};
  }
  static Op::Geometry geometry(const std::vector<double>& g) {
    require(g.size() == 3, "pair3d needs a 3-component normal");
    return {g[0], g[1], g[2]};
  }
  static std::vector<double> flat(const Op::State& v) {
    return {v.i[0], v.i[1], v.i[2], v.j[0], v.j[1], v.j[2]};
  }
  static void negate(Op::State& v) {
    for (int k = 0; k < 3; ++k) { v.i[k] = -v.i[k]; v.j[k] = -v.j[k]; }
  }
  static Op::Inv invariants(const Op::State& v) {
    Op::Inv inv{{0, 0, 0}, 0.0};
    for (int k = 0; k < 3; ++k) {
      inv.momentum[k] = v.i[k] + v.j[k];
      inv.energy += v.i[k] * v.i[k] + v.j[k] * v.j[k];
    }
    return inv;
  }
  struct Pred {
    std::array<double, 3> n;
    explicit Pred(const Op::Geometry& g) : n(g) {}
    double speed(const Op::State& v) const {
      return n[0] * (v.i[0] - v.j[0]) + n[1] * (v.i[1] - v.j[1]) + n[2] * (v.i[2] - v.j[2]);
    }
    bool approaches(const Op::State& v) const { return speed(v) < 0.0; }
    bool separates(const Op::State& v) const { return speed(v) > 0.0; }
  };
  static Op make(const StudyConfig& c) { return Op(c.printed_reverse); }
};

/// What the two triples share: a 3 x Dim state, flattened particle by particle.
template <int Dim>
struct TripleCommon {
  using State = Triple<Dim>;
  static State state(const std::vector<double>& v) {
    require(v.size() == 3 * Dim, Dim == 1 ? "triple1d needs 3 initial velocity components"
                                          : "triple2d needs 6 initial velocity components");
    State s;
    for (int p = 0; p < 3; ++p)
      for (int k = 0; k < Dim; ++k) s[p][k] = v[p * Dim + k];
    return s;
  }
  static std::vector<double> flat(const State& v) {
    std::vector<double> out;
    for (const auto& p : v) out.insert(out.end(), p.begin(), p.end());
    return out;
  }
  static void negate(State& v) {
    for (auto& p : v)
      for (double& x : p) x = -x;
  }
  static Invariants<Dim> invariants(const State& v) {
    Invariants<Dim> inv{};
    inv.energy = 0.0;
    for (int k = 0; k < Dim; ++k) inv.momentum[k] = 0.0;
    for (const auto& p : v)
      for (int k = 0; k < Dim; ++k) {
        inv.momentum[k] += p[k];
        inv.energy += p[k] * p[k];
      }
    return inv;
  }
};

/// The 1D triple: three positions as geometry.
template <>
struct Adapter<Triple1DPaper> : TripleCommon<1> {
  using Op = Triple1DPaper;
  static Op::Geometry geometry(const std::vector<double>& g) {
    require(g.size() == 3, "triple1d needs 3 positions");
    return {g[0], g[1], g[2]};
  }
  struct Pred {
    std::array<int, 3> o;
    explicit Pred(const Op::Geometry& x) : o{0, 1, 2} {
      std::sort(o.begin(), o.end(), [&](int a, int b) { return x[a] < x[b]; });
    }
    bool approaches(const Op::State& v) const {
      return v[o[0]][0] - v[o[1]][0] > 0.0 && v[o[1]][0] - v[o[2]][0] > 0.0;
    }
    bool separates(const Op::State& v) const {
      return v[o[0]][0] - v[o[1]][0] < 0.0 && v[o[1]][0] - v[o[2]][0] < 0.0;
    }
  };
  static Op make(const StudyConfig& c) { return Op(c.arc, c.cos_tol, c.printed_reverse, c.angle); }
};

/// The 2D triple: three 2D positions as geometry (predicates in its canonical frame).
template <>
struct Adapter<Triple2DPaper> : TripleCommon<2> {
  using Op = Triple2DPaper;
  static Op::Geometry geometry(const std::vector<double>& g) {
    require(g.size() == 6, "triple2d needs 3 x 2 positions");
    return {{{g[0], g[1]}, {g[2], g[3]}, {g[4], g[5]}}};
  }
  struct Pred {
    Canonical cf;
    explicit Pred(const Op::Geometry& x) : cf(canonical(x)) {}
    bool approaches(const Op::State& v) const {
      const auto s = Op::normal_speeds(v, cf);
      for (int k = 0; k < cf.contacts; ++k)
        if (!(s[k] < 0.0)) return false;
      return true;
    }
    bool separates(const Op::State& v) const {
      const auto s = Op::normal_speeds(v, cf);
      for (int k = 0; k < cf.contacts; ++k)
        if (!(s[k] > 0.0)) return false;
      return true;
    }
  };
  static Op make(const StudyConfig& c) {
    require(!c.printed_reverse, "printed_reverse applies to pair3d and triple1d only: "
                                "Procedures 6 and 7 of triple2d always run as printed");
    return Op();
  }
};

/// Max |a - b| / max |b|.
inline double rel_error(const std::vector<double>& a, const std::vector<double>& b) {
  double scale = 0.0, err = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    scale = std::fmax(scale, std::fabs(b[k]));
    err = std::fmax(err, std::fabs(a[k] - b[k]));
  }
  return scale > 0.0 ? err / scale : err;
}

/// A fresh pre state: velocities i.i.d. standard normal, conditioned on approaching.
template <class Op>
typename Op::State fresh_pre(Normal& N, const typename Adapter<Op>::Pred& pred) {
  std::vector<double> v(Op::particles * Op::dim);
  for (int attempt = 0; attempt < 10000000; ++attempt) {
    for (double& x : v) x = N();
    const typename Op::State s = Adapter<Op>::state(v);
    if (pred.approaches(s)) return s;
  }
  throw InvalidArgument("no approaching state found for this geometry");
}

}  // namespace revcol::paper::adapt
