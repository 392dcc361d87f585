// Binding of the paper-mode operators of §4.3-4.5 (Pair3DPaper, Triple1DPaper,
// Triple2DPaper) and of the paper-mode measurements: numpy arrays in and out, nothing else.
// A single collision is a batch of one; the shape of the input is kept in the output.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "revcol/collide/calotte.hpp"
#include "revcol/collide/ellipse_arc.hpp"
#include "revcol/collide/pair3d_paper.hpp"
#include "revcol/collide/paper_batch.hpp"
#include "revcol/collide/paper_study.hpp"
#include "revcol/collide/triple1d_paper.hpp"
#include "revcol/collide/triple2d_paper.hpp"
#include "revcol/rng/clcg4.hpp"
#include "revcol/rng/philox.hpp"

namespace py = pybind11;

namespace revcol::bind {
namespace {

using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;
using Shape = std::vector<py::ssize_t>;

std::string shape_str(const Shape& s) {
  std::string out = "(";
  for (std::size_t k = 0; k < s.size(); ++k) out += (k ? ", " : "") + std::to_string(s[k]);
  return out + (s.size() == 1 ? ",)" : ")");
}
std::string shape_of(const Array& a) { return shape_str(Shape(a.shape(), a.shape() + a.ndim())); }

// Whether `a` has shape `inner` (one entry) or (B, *inner) (B entries).
struct Rows {
  std::size_t count;
  bool batched;
};
std::optional<Rows> match(const Array& a, const Shape& inner) {
  const auto n = static_cast<py::ssize_t>(inner.size());
  auto tail = [&](py::ssize_t off) {
    for (py::ssize_t k = 0; k < n; ++k)
      if (a.shape(off + k) != inner[k]) return false;
    return true;
  };
  if (a.ndim() == n && tail(0)) return Rows{1, false};
  if (a.ndim() == n + 1 && tail(1)) return Rows{static_cast<std::size_t>(a.shape(0)), true};
  return std::nullopt;
}
std::size_t entry_size(const Shape& inner) {
  std::size_t s = 1;
  for (py::ssize_t k : inner) s *= static_cast<std::size_t>(k);
  return s;
}
// `a` for B entries: shape inner (broadcast) or (B, *inner); returns each entry's data pointer.
std::vector<const double*> per_entry(const Array& a, const Shape& inner, std::size_t B, const char* name) {
  const auto m = match(a, inner);
  require(m && (!m->batched || m->count == B), [&] {
    Shape many{static_cast<py::ssize_t>(B)};
    many.insert(many.end(), inner.begin(), inner.end());
    return std::string(name) + " must have shape " + shape_str(inner) + " or " + shape_str(many) +
           ", got " + shape_of(a);
  });
  std::vector<const double*> out(B);
  for (std::size_t b = 0; b < B; ++b) out[b] = a.data() + (m->batched ? b * entry_size(inner) : 0);
  return out;
}

// Per-operator type conversions.
template <class Op> struct Conv;
template <>
struct Conv<Pair3DPaper> {
  static Shape vshape() { return {2, 3}; }
  static Shape xshape() { return {3}; }
  static const char* xname() { return "normal"; }
  static Pair3DPaper::State state(const double* p) { return {{p[0], p[1], p[2]}, {p[3], p[4], p[5]}}; }
  static void put(const Pair3DPaper::State& s, double* p) {
    for (int k = 0; k < 3; ++k) { p[k] = s.i[k]; p[3 + k] = s.j[k]; }
  }
  static Pair3DPaper::Geometry geometry(const double* p) { return {p[0], p[1], p[2]}; }
};
template <>
struct Conv<Triple1DPaper> {
  static Shape vshape() { return {3}; }
  static Shape xshape() { return {3}; }
  static const char* xname() { return "positions"; }
  static Triple1DPaper::State state(const double* p) { return {{{p[0]}, {p[1]}, {p[2]}}}; }
  static void put(const Triple1DPaper::State& s, double* p) {
    for (int k = 0; k < 3; ++k) p[k] = s[k][0];
  }
  static Triple1DPaper::Geometry geometry(const double* p) { return {p[0], p[1], p[2]}; }
};
template <>
struct Conv<Triple2DPaper> {
  static Shape vshape() { return {3, 2}; }
  static Shape xshape() { return {3, 2}; }
  static const char* xname() { return "positions"; }
  static Triple2DPaper::State state(const double* p) { return {{{p[0], p[1]}, {p[2], p[3]}, {p[4], p[5]}}}; }
  static void put(const Triple2DPaper::State& s, double* p) {
    for (int r = 0; r < 3; ++r) { p[2 * r] = s[r][0]; p[2 * r + 1] = s[r][1]; }
  }
  static Triple2DPaper::Geometry geometry(const double* p) { return {{{p[0], p[1]}, {p[2], p[3]}, {p[4], p[5]}}}; }
};

// An operator with its own rare log: what Python holds.
template <class Op>
struct Holder {
  Op op;
  RareLog log;
};

template <class Op>
std::vector<typename Op::State> states_from(const Array& v, Rows& rows) {
  const auto m = match(v, Conv<Op>::vshape());
  require(m.has_value(), [&] {
    std::string many = "(B";
    for (py::ssize_t k : Conv<Op>::vshape()) many += ", " + std::to_string(k);
    return "velocities must have shape " + shape_str(Conv<Op>::vshape()) + " or " + many + "), got " + shape_of(v);
  });
  rows = *m;
  std::vector<typename Op::State> out(rows.count);
  const std::size_t es = entry_size(Conv<Op>::vshape());
  for (std::size_t b = 0; b < rows.count; ++b) out[b] = Conv<Op>::state(v.data() + b * es);
  return out;
}

template <class Op>
Array states_to(const std::vector<typename Op::State>& s, const Rows& rows) {
  Shape shape = Conv<Op>::vshape();
  if (rows.batched) shape.insert(shape.begin(), static_cast<py::ssize_t>(s.size()));
  Array out(shape);
  const std::size_t es = entry_size(Conv<Op>::vshape());
  for (std::size_t b = 0; b < s.size(); ++b) Conv<Op>::put(s[b], out.mutable_data() + b * es);
  return out;
}

template <class Op>
std::vector<typename Op::Geometry> geometries_from(const Array& x, std::size_t B) {
  const auto p = per_entry(x, Conv<Op>::xshape(), B, Conv<Op>::xname());
  std::vector<typename Op::Geometry> out(B);
  for (std::size_t b = 0; b < B; ++b) out[b] = Conv<Op>::geometry(p[b]);
  return out;
}

template <class Op>
std::vector<typename Op::Draws> draws_from(const Array& g, const Rows& rows) {
  constexpr int d = Op::draws;
  const std::size_t B = rows.count;
  // (d,) for one entry, (B, d) for a batch; with one draw also () and (B,)
  const bool one = !rows.batched && ((g.ndim() == 1 && g.shape(0) == d) || (d == 1 && g.ndim() == 0));
  const bool many = rows.batched && ((g.ndim() == 2 && static_cast<std::size_t>(g.shape(0)) == B && g.shape(1) == d) ||
                                     (d == 1 && g.ndim() == 1 && static_cast<std::size_t>(g.shape(0)) == B));
  require(one || many, [&] {
    return std::string("g must have shape ") + (rows.batched ? "(" + std::to_string(B) + ", " + std::to_string(d) + ")"
                                                            : "(" + std::to_string(d) + ",)") +
           (d == 1 ? (rows.batched ? " or (" + std::to_string(B) + ",)" : " or ()") : "") + ", got " + shape_of(g);
  });
  std::vector<typename Op::Draws> out(B);
  for (std::size_t b = 0; b < B; ++b)
    for (int k = 0; k < d; ++k) out[b][k] = g.data()[b * d + k];
  return out;
}

template <class Op>
std::optional<std::vector<typename Op::Inv>> invariants_from(const std::optional<Array>& momentum,
                                                             const std::optional<Array>& energy,
                                                             std::size_t B) {
  require(momentum.has_value() == energy.has_value(),
          "give both momentum and energy (held invariants), or neither");
  if (!momentum) return std::nullopt;
  constexpr int d = Op::dim;
  const auto m = per_entry(*momentum, {d}, B, "momentum");
  const auto e = per_entry(*energy, {}, B, "energy");
  std::vector<typename Op::Inv> out(B);
  for (std::size_t b = 0; b < B; ++b) {
    for (int k = 0; k < d; ++k) out[b].momentum[k] = m[b][k];
    out[b].energy = *e[b];
  }
  return out;
}

// forward (dir = +1) or reverse (dir = -1) with exactly one source of random numbers.
template <class Op>
Array run(Holder<Op>& h, const Array& velocities, const Array& geometry, py::object rng,
          std::optional<Array> g, std::optional<Array> momentum, std::optional<Array> energy, int dir) {
  Rows rows{};
  std::vector<typename Op::State> v = states_from<Op>(velocities, rows);
  const auto x = geometries_from<Op>(geometry, v.size());
  const auto inv = invariants_from<Op>(momentum, energy, v.size());
  const typename Op::Inv* ip = inv ? inv->data() : nullptr;
  require(rng.is_none() != !g.has_value(), "give exactly one of rng= (a generator) or g= (draws)");
  const std::size_t B = v.size();
  if (g) {
    const auto gv = draws_from<Op>(*g, rows);
    if (dir > 0) paper::forward_batch(h.op, v.data(), x.data(), B, gv.data(), h.log, ip);
    else paper::reverse_batch(h.op, v.data(), x.data(), B, gv.data(), h.log, ip);
  } else if (py::isinstance<rng::CLCG4>(rng)) {
    auto& gen = rng.cast<rng::CLCG4&>();
    if (dir > 0) paper::forward_batch(h.op, v.data(), x.data(), B, gen, h.log, ip);
    else paper::reverse_batch(h.op, v.data(), x.data(), B, gen, h.log, ip);
  } else if (py::isinstance<rng::Philox>(rng)) {
    auto& gen = rng.cast<rng::Philox&>();
    if (dir > 0) paper::forward_batch(h.op, v.data(), x.data(), B, gen, h.log, ip);
    else paper::reverse_batch(h.op, v.data(), x.data(), B, gen, h.log, ip);
  } else {
    throw InvalidArgument("rng must be a revcol.CLCG4 or revcol.Philox");
  }
  return states_to<Op>(v, rows);
}

// Registers forward, reverse, the log and draws on a class of Holder<Op>.
template <class Op, class Cls>
void common_methods(Cls& cls, const char* geometry_name) {
  cls.def("forward",
          [](Holder<Op>& h, const Array& v, const Array& x, py::object rng, std::optional<Array> g,
             std::optional<Array> momentum, std::optional<Array> energy) {
            return run<Op>(h, v, x, std::move(rng), std::move(g), std::move(momentum), std::move(energy), +1);
          },
          py::arg("velocities"), py::arg(geometry_name), py::kw_only(), py::arg("rng") = py::none(),
          py::arg("g") = py::none(), py::arg("momentum") = py::none(), py::arg("energy") = py::none(),
          "Pre -> post. Exactly one of rng (drawn in entry order, d_n per entry) or g (draws in\n"
          "[0,1]); momentum= and energy= hold the invariants. Every entry is validated first;\n"
          "on error nothing changes.")
      .def("reverse",
           [](Holder<Op>& h, const Array& v, const Array& x, py::object rng, std::optional<Array> g,
              std::optional<Array> momentum, std::optional<Array> energy) {
             return run<Op>(h, v, x, std::move(rng), std::move(g), std::move(momentum), std::move(energy), -1);
           },
           py::arg("velocities"), py::arg(geometry_name), py::kw_only(), py::arg("rng") = py::none(),
           py::arg("g") = py::none(), py::arg("momentum") = py::none(), py::arg("energy") = py::none(),
           "Post -> pre with the draws forward used (rng steps back, last entry first).")
      .def_property_readonly_static("draws", [](py::object) { return Op::draws; },
                                    "random numbers per collision, d_n")
      .def_property_readonly("log_size", [](const Holder<Op>& h) { return h.log.size(); },
                             "entries on the rare log")
      .def_property_readonly("log_bytes", [](const Holder<Op>& h) { return h.log.bytes(); })
      .def_property_readonly("log_pushed", [](const Holder<Op>& h) { return h.log.pushed(); },
                             "entries ever pushed")
      .def("clear_log", [](Holder<Op>& h) { h.log.clear(); });
}

// Applies f to each entry of `a` (shape inner or (B, *inner)); returns (..., out) values.
template <class F>
Array map_entries(const Array& a, const Shape& inner, const char* name, int out_per_entry, F f) {
  const auto m = match(a, inner);
  require(m.has_value(), [&] { return std::string(name) + " has the wrong shape " + shape_of(a); });
  Shape shape;
  if (m->batched) shape.push_back(static_cast<py::ssize_t>(m->count));
  if (out_per_entry > 1) shape.push_back(out_per_entry);
  Array out(shape);
  const std::size_t es = entry_size(inner);
  for (std::size_t b = 0; b < m->count; ++b) f(a.data() + b * es, out.mutable_data() + b * out_per_entry);
  return out;
}

py::dict study_dict(const paper::StudyResult& r) {
  py::dict d;
  d["case"] = r.config.case_name;
  d["pre"] = r.config.pre;
  d["seed"] = r.config.seed;
  d["printed_reverse"] = r.config.printed_reverse;
  d["cos_tol"] = r.config.cos_tol;
  d["arc"] = paper::to_string(r.config.arc);
  d["angle"] = paper::to_string(r.config.angle);
  d["collisions"] = r.collisions;
  d["ok"] = r.ok;
  d["invalid_post"] = r.invalid_post;
  d["reverse_threw"] = r.reverse_threw;
  d["wrong"] = r.wrong;
  d["restarts"] = r.restarts;
  d["logged"] = r.logged;
  d["failure_rate"] = r.failure_rate;
  d["max_ok_error"] = r.max_ok_error;
  d["first_failure"] = r.first_failure;
  return d;
}

const char* kPair3DDoc = R"(Paper mode: 2 particles in 3 dimensions (Perumalla & Protopopescu 2013, §4.3), as printed.

v_i = M/2 + R (sin phi1 sin phi2, sin phi1 cos phi2, cos phi1), v_j = M - v_i, R = |v_i - v_j|/2
(V-to-Phi / Phi-to-V). Two draws: psi1 = acos(1 - 2 G1), psi2 = 2 pi G2 (a uniform point on
the sphere). Forward: phi1 += psi1, phi2 += psi2 (mod 2 pi); if the post state approaches
along the normal (from particle j to i), phi1 += pi. phi2' is logged only when the post
phi1 = 0. Reverse subtracts psi and tests the candidate (printed_reverse=True: the post angle).
NOT INVERTIBLE as printed: the forward phi1 leaves [0, pi] about half the time, and V-to-Phi
cannot see that (measured: docs/paper-findings.md). Velocities (2, 3) or (B, 2, 3), rows
particle i, particle j; normal (3,) or (B, 3).

Example:
    >>> import numpy as np, revcol
    >>> op, g = revcol.Pair3DPaper(), revcol.CLCG4()
    >>> v = np.array([[0.25, -0.5, 0.1], [1.0, 0.75, 0.6]])
    >>> post = op.forward(v, [1.0, 1.0, 1.0], rng=g)       # draws 2 numbers
    >>> back = op.reverse(post, [1.0, 1.0, 1.0], rng=g)    # steps back 2: v, or not
)";

const char* kTriple1DDoc = R"(Paper mode: 3 particles in 1 dimension (§4.4, Procedures 3 and 4).

With a, b, c the velocities of the left, centre and right particle (by position),
a - b = lambda cos phi, b - c = lambda cos(phi - 2pi/3), lambda = sqrt2 sqrt(delta - alpha^2/3):
phi is the angle on the round circle of the relative velocities. Pre: phi' in (pi/6, pi/2)
(a > b > c); post: phi in (7pi/6, 3pi/2). One draw: psi = L^-1(G L(2pi)) by arc length on the
ellipse with d_y = d_x/sqrt3, computed by arc="simpson" (the paper: Simpson + bisection, 1e-9),
"elliptic" (GSL E(phi, k) + Newton) or "table" (built once); angle="parametric" (default) or
"polar" says which angle psi is. Procedure 3: phi = phi' + psi, + pi if in R1..R3, then
-+ 2pi/3 into S1. Procedure 4 as printed tests the post angle in its Step 2 and never undoes
the + pi; the default tests the candidate (printed_reverse=True keeps the printed test).
cos_tol: the paper's tolerance for "a cosine is positive". Velocities (3,) or (B, 3) by id;
positions (3,) or (B, 3) (only their order matters).

Example:
    >>> import numpy as np, revcol
    >>> op, g = revcol.Triple1DPaper(arc="table"), revcol.CLCG4()
    >>> v, x = np.array([0.75, 0.25, -0.5]), np.array([0.0, 1.0, 2.0])
    >>> post = op.forward(v, x, rng=g)                  # left < centre < right after
    >>> np.allclose(op.reverse(post, x, rng=g), v)
    True
)";

const char* kTriple2DDoc = R"(Paper mode: 3 particles in 2 dimensions (§4.5, Procedures 5, 6, 7), as printed.

The positions decide the canonical configuration (C1/C2: three contacts, P3 on either side;
C3/C4: P3 touches P2 or P1 at angle theta), reached by rotating the velocities (C2 by a
mirror). In that frame x = ((a-b)/sqrt2, (d-e)/sqrt2, (a+b-2c)/sqrt6, (d+e-2f)/sqrt6) =
|x| (cos phi1, sin phi1 cos phi2, sin phi1 sin phi2 cos phi3, sin phi1 sin phi2 sin phi3).
Three draws: (psi1, psi2, psi3) from the hyper-ellipsoid calotte areas (Procedure 5, s = 4,
tables built once by GSL quadrature). Procedure 6: phi1 = (phi1' - pi/2 + psi1) mod pi/2,
phi2 and phi3 shifted and folded into their bounds. NOT A BIJECTION as printed: the post
state may approach, and the reverse often returns another state (docs/paper-findings.md).
Velocities (3, 2) or (B, 3, 2) by id; positions (3, 2) or (B, 3, 2) by id.

Example:
    >>> import numpy as np, revcol
    >>> op, g = revcol.Triple2DPaper(), revcol.CLCG4()
    >>> x = np.array([[0.0, 0.0], [1.0, 0.0], [0.5, 3 ** 0.5 / 2]])   # C1
    >>> v = np.array([[0.5, 0.3], [-0.5, 0.25], [0.05, -0.6]])
    >>> post = op.forward(v, x, rng=g)                  # 3 numbers drawn
    >>> op.configuration(x)["config"]
    'C1'
)";

}  // namespace

void register_paper(py::module_& m) {
  // --- 2 particles, 3D
  py::class_<Holder<Pair3DPaper>> p3(m, "Pair3DPaper", kPair3DDoc);
  p3.def(py::init([](bool printed) { return Holder<Pair3DPaper>{Pair3DPaper(printed), {}}; }),
         py::kw_only(), py::arg("printed_reverse") = false);
  common_methods<Pair3DPaper>(p3, "normal");
  p3.def_property_readonly("printed_reverse", [](const Holder<Pair3DPaper>& h) { return h.op.printed_reverse(); })
      .def_static("angles",
                  [](const Array& v) {
                    return map_entries(v, {2, 3}, "velocities", 2, [](const double* p, double* out) {
                      const auto a = Pair3DPaper::angles(Conv<Pair3DPaper>::state(p));
                      out[0] = a[0];
                      out[1] = a[1];
                    });
                  },
                  py::arg("velocities"), "V-to-Phi: (phi1 in [0, pi], phi2 in [0, 2 pi)) per entry.")
      .def_static("psi",
                  [](const Array& g) {
                    return map_entries(g, {2}, "g", 2, [](const double* p, double* out) {
                      require(p[0] >= 0 && p[0] <= 1 && p[1] >= 0 && p[1] <= 1, "random numbers must be in [0,1]");
                      out[0] = Pair3DPaper::psi1(p[0]);
                      out[1] = Pair3DPaper::psi2(p[1]);
                    });
                  },
                  py::arg("g"), "G-to-Psi: (psi1, psi2) per entry of g (2,) or (B, 2).")
      .def("__repr__", [](const Holder<Pair3DPaper>& h) {
        return std::string("revcol.Pair3DPaper(printed_reverse=") + (h.op.printed_reverse() ? "True" : "False") + ")";
      });

  // --- 3 particles, 1D
  py::class_<Holder<Triple1DPaper>> t1(m, "Triple1DPaper", kTriple1DDoc);
  t1.def(py::init([](const std::string& arc, double cos_tol, bool printed, const std::string& angle) {
           return Holder<Triple1DPaper>{
               Triple1DPaper(paper::parse_arc_method(arc), cos_tol, printed, paper::parse_arc_angle(angle)), {}};
         }),
         py::kw_only(), py::arg("arc") = "simpson", py::arg("cos_tol") = Triple1DPaper::paper_cos_tol,
         py::arg("printed_reverse") = false, py::arg("angle") = "parametric");
  common_methods<Triple1DPaper>(t1, "positions");
  t1.def_property_readonly("arc", [](const Holder<Triple1DPaper>& h) { return paper::to_string(h.op.arc().method()); })
      .def_property_readonly("angle", [](const Holder<Triple1DPaper>& h) { return paper::to_string(h.op.arc().angle()); })
      .def_property_readonly("cos_tol", [](const Holder<Triple1DPaper>& h) { return h.op.cos_tol(); })
      .def_property_readonly("printed_reverse", [](const Holder<Triple1DPaper>& h) { return h.op.printed_reverse(); })
      .def_static("angle_of",
                  [](const Array& v, const Array& x) {
                    Rows rows{};
                    const auto s = states_from<Triple1DPaper>(v, rows);
                    const auto xs = geometries_from<Triple1DPaper>(x, s.size());
                    Shape shape;
                    if (rows.batched) shape.push_back(static_cast<py::ssize_t>(s.size()));
                    Array out(shape);
                    for (std::size_t b = 0; b < s.size(); ++b) out.mutable_data()[b] = Triple1DPaper::angle(s[b], xs[b]);
                    return out;
                  },
                  py::arg("velocities"), py::arg("positions"), "V-to-Phi: phi in [0, 2 pi) per entry.")
      .def("psi",
           [](const Holder<Triple1DPaper>& h, const Array& g) {
             Array out(Shape(g.shape(), g.shape() + g.ndim()));
             for (py::ssize_t k = 0; k < g.size(); ++k) out.mutable_data()[k] = h.op.arc().psi(g.data()[k]);
             return out;
           },
           py::arg("g"), "G-to-Psi by this operator's arc method and angle, elementwise.")
      .def("__repr__", [](const Holder<Triple1DPaper>& h) {
        char tol[32];
        std::snprintf(tol, sizeof tol, "%.17g", h.op.cos_tol());
        return std::string("revcol.Triple1DPaper(arc='") + paper::to_string(h.op.arc().method()) +
               "', cos_tol=" + tol + ", printed_reverse=" +
               (h.op.printed_reverse() ? "True" : "False") + ", angle='" + paper::to_string(h.op.arc().angle()) + "')";
      });

  // --- 3 particles, 2D
  py::class_<Holder<Triple2DPaper>> t2(m, "Triple2DPaper", kTriple2DDoc);
  t2.def(py::init([]() { return Holder<Triple2DPaper>{Triple2DPaper(), {}}; }));
  common_methods<Triple2DPaper>(t2, "positions");
  t2.def_static("angles",
                [](const Array& v, const Array& x) {
                  Rows rows{};
                  const auto s = states_from<Triple2DPaper>(v, rows);
                  const auto xs = geometries_from<Triple2DPaper>(x, s.size());
                  Shape shape;
                  if (rows.batched) shape.push_back(static_cast<py::ssize_t>(s.size()));
                  shape.push_back(3);
                  Array out(shape);
                  for (std::size_t b = 0; b < s.size(); ++b) {
                    const auto a = Triple2DPaper::angles(s[b], xs[b]);
                    for (int k = 0; k < 3; ++k) out.mutable_data()[3 * b + k] = a[k];
                  }
                  return out;
                },
                py::arg("velocities"), py::arg("positions"),
                "V-to-Phi in the canonical frame: (phi1, phi2, phi3) per entry.")
      .def_static("configuration",
                  [](const Array& x) {
                    const auto xs = geometries_from<Triple2DPaper>(x, 1);
                    const paper::Canonical cf = paper::canonical(xs[0]);
                    py::dict d;
                    d["config"] = paper::to_string(cf.config);
                    d["ids"] = py::make_tuple(cf.id[0], cf.id[1], cf.id[2]);
                    d["theta"] = cf.theta;
                    d["contacts"] = cf.contacts;
                    py::list rows;
                    for (int r = 0; r < 2; ++r) rows.append(py::make_tuple(cf.R(r, 0), cf.R(r, 1)));
                    d["frame"] = rows;
                    return d;
                  },
                  py::arg("positions"),
                  "The canonical configuration of positions (3, 2): config, ids of P1 P2 P3, theta, frame rows.")
      .def("psi",
           [](const Holder<Triple2DPaper>& h, const Array& g) {
             return map_entries(g, {3}, "g", 3, [&](const double* p, double* out) {
               const auto psi = h.op.sampler().psi({p[0], p[1], p[2]});
               for (int k = 0; k < 3; ++k) out[k] = psi[k];
             });
           },
           py::arg("g"), "G-to-Psi (Procedure 5): (psi1, psi2, psi3) per entry of g (3,) or (B, 3).")
      .def("__repr__", [](const Holder<Triple2DPaper>&) { return std::string("revcol.Triple2DPaper()"); });

  // --- measurements and tables
  m.def(
      "paper_study",
      [](const std::string& case_name, std::uint64_t collisions, std::uint64_t seed, const std::string& pre,
         bool printed_reverse, double cos_tol, const std::string& arc, const std::string& angle) {
        paper::StudyConfig c;
        c.case_name = case_name;
        c.collisions = collisions;
        c.seed = seed;
        c.pre = pre;
        c.printed_reverse = printed_reverse;
        c.cos_tol = cos_tol;
        c.arc = paper::parse_arc_method(arc);
        c.angle = paper::parse_arc_angle(angle);
        paper::StudyResult r;
        {
          py::gil_scoped_release release;
          r = paper::study(c);
        }
        return study_dict(r);
      },
      py::kw_only(), py::arg("case"), py::arg("collisions") = 1000000, py::arg("seed") = 0,
      py::arg("pre") = "chain", py::arg("printed_reverse") = false, py::arg("cos_tol") = 1e-8,
      py::arg("arc") = "simpson", py::arg("angle") = "parametric",
      "Reversal failure rate of a paper-mode case (see revcol.paper.failure_rate).");
  m.def("paper_cases", [] {
    py::list out;
    for (const paper::PaperCase& c : paper::paper_cases()) {
      py::dict d;
      d["name"] = c.name;
      d["n"] = c.n;
      d["d"] = c.d;
      d["geometry"] = c.geometry;
      d["velocities"] = c.velocities;
      d["description"] = c.description;
      out.append(d);
    }
    return out;
  }, "The paper-mode cases: name, n, d, geometry, default velocities, description.");
  m.def("arc_reference",
        [](double g, double aspect) {
          require(g >= 0.0 && g <= 1.0, "random number must be in [0,1]");
          return static_cast<double>(paper::EllipseArc::reference_parametric(g, aspect));
        },
        py::arg("g"), py::arg("aspect") = paper::kPaperAspect,
        "High-precision parametric angle at arc length g L(2 pi) (long double; slow).");
  m.def("calotte_fraction",
        [](int s, double psi, bool direct) {
          if (direct) return paper::CalotteTable::fraction_direct(s, psi);
          require(s == 3 || s == 4, "calotte tables exist for s = 3 and s = 4");
          return (s == 4 ? paper::CalotteTable::h4() : paper::CalotteTable::h3()).fraction(psi);
        },
        py::arg("s"), py::arg("psi"), py::arg("direct") = false,
        "Calotte-area fraction F(psi) of the paper's H_4 (s = 4) or H_3 (s = 3) shape.");
}

}  // namespace revcol::bind
