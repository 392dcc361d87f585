// Binding of the paper-mode operators of §4.3-4.5 (Pair3DPaper, Triple1DPaper,
// Triple2DPaper): numpy arrays in and out, nothing else. A single collision is a batch of
// one; the shape of the input is kept in the output. The measurements are paper_study.cpp.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstdio>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "args.hpp"
#include "arrays.hpp"
#include "bindings.hpp"
#include "revcol/collide/batch.hpp"
#include "revcol/collide/pair3d_paper.hpp"
#include "revcol/collide/triple1d_paper.hpp"
#include "revcol/collide/triple2d_paper.hpp"
#include "revcol/studies/paper_study.hpp"

namespace py = pybind11;

namespace revcol::bind {
namespace {

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
  rows = rows_of(v, Conv<Op>::vshape(), "velocities");
  std::vector<typename Op::State> out(rows.count);
  const std::size_t es = entry_size(Conv<Op>::vshape());
  for (std::size_t b = 0; b < rows.count; ++b) out[b] = Conv<Op>::state(v.data() + b * es);
  return out;
}

template <class Op>
Array states_to(const std::vector<typename Op::State>& s, const Rows& rows) {
  Array out(rows.batched ? batched(Conv<Op>::vshape(), s.size()) : Conv<Op>::vshape());
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

// forward or reverse with exactly one source of random numbers.
template <class Op>
Array run(Holder<Op>& h, const ArrayArg& velocities_arg, const ArrayArg& geometry_arg, const char* geometry_name,
          const py::object& rng, const std::optional<ArrayArg>& g_arg, const std::optional<ArrayArg>& momentum_arg,
          const std::optional<ArrayArg>& energy_arg, batch::Dir dir) {
  const Array velocities = to_array(velocities_arg, "velocities"), geometry = to_array(geometry_arg, geometry_name);
  const auto g = to_array(g_arg, "g"), momentum = to_array(momentum_arg, "momentum");
  const auto energy = to_array(energy_arg, "energy");
  Rows rows{};
  std::vector<typename Op::State> v = states_from<Op>(velocities, rows);
  const auto x = geometries_from<Op>(geometry, v.size());
  const auto inv = invariants_from<Op::dim>(momentum, energy, v.size());
  const typename Op::Inv* ip = inv ? inv->data() : nullptr;
  const std::size_t B = v.size();
  const bool fwd = dir == batch::Dir::forward;
  with_draws(rng, g.has_value(), [&](auto gen) {
    if constexpr (std::is_null_pointer_v<decltype(gen)>) {
      const std::vector<double> gv = draws_from(*g, rows, Op::draws);
      if (fwd) forward_batch(h.op, v.data(), x.data(), B, gv.data(), h.log, ip);
      else reverse_batch(h.op, v.data(), x.data(), B, gv.data(), h.log, ip);
    } else {
      if (fwd) forward_batch(h.op, v.data(), x.data(), B, *gen, h.log, ip);
      else reverse_batch(h.op, v.data(), x.data(), B, *gen, h.log, ip);
    }
  });
  return states_to<Op>(v, rows);
}

// Registers forward, reverse, the log and draws on a class of Holder<Op>.
template <class Op, class Cls>
void common_methods(Cls& cls, const char* geometry_name) {
  cls.def("forward",
          [geometry_name](Holder<Op>& h, const ArrayArg& v, const ArrayArg& x, py::object rng, std::optional<ArrayArg> g,
             std::optional<ArrayArg> momentum, std::optional<ArrayArg> energy) {
            return run<Op>(h, v, x, geometry_name, rng, g, momentum, energy, batch::Dir::forward);
          },
          py::arg("velocities"), py::arg(geometry_name), py::kw_only(), py::arg("rng") = py::none(),
          py::arg("g") = py::none(), py::arg("momentum") = py::none(), py::arg("energy") = py::none(),
          "Pre -> post. Exactly one of rng (drawn in entry order, d_n per entry) or g (draws in\n"
          "[0,1]); momentum= and energy= hold the invariants. Every entry is validated first;\n"
          "on error nothing changes.")
      .def("reverse",
           [geometry_name](Holder<Op>& h, const ArrayArg& v, const ArrayArg& x, py::object rng, std::optional<ArrayArg> g,
              std::optional<ArrayArg> momentum, std::optional<ArrayArg> energy) {
             return run<Op>(h, v, x, geometry_name, rng, g, momentum, energy, batch::Dir::reverse);
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
  Shape out_shape;
  if (m->batched) out_shape.push_back(static_cast<py::ssize_t>(m->count));
  if (out_per_entry > 1) out_shape.push_back(out_per_entry);
  Array out(out_shape);
  const std::size_t es = entry_size(inner);
  for (std::size_t b = 0; b < m->count; ++b) f(a.data() + b * es, out.mutable_data() + b * out_per_entry);
  return out;
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

// --- 2 particles, 3D
void register_pair3d(py::module_& m) {
  py::class_<Holder<Pair3DPaper>> p3(m, "Pair3DPaper", kPair3DDoc);
  p3.def(py::init([](bool printed) { return Holder<Pair3DPaper>{Pair3DPaper(printed), {}}; }),
         py::kw_only(), py::arg("printed_reverse") = false);
  common_methods<Pair3DPaper>(p3, "normal");
  p3.def_property_readonly("printed_reverse", [](const Holder<Pair3DPaper>& h) { return h.op.printed_reverse(); })
      .def_static("angles",
                  [](const ArrayArg& v_arg) {
                    const auto v = to_array(v_arg, "velocities");
                    return map_entries(v, {2, 3}, "velocities", 2, [](const double* p, double* out) {
                      const auto a = Pair3DPaper::angles(Conv<Pair3DPaper>::state(p));
                      out[0] = a[0];
                      out[1] = a[1];
                    });
                  },
                  py::arg("velocities"), "V-to-Phi: (phi1 in [0, pi], phi2 in [0, 2 pi)) per entry.")
      .def_static("psi",
                  [](const ArrayArg& g_arg) {
                    const auto g = to_array(g_arg, "g");
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
}

// --- 3 particles, 1D
void register_triple1d(py::module_& m) {
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
                  [](const ArrayArg& v_arg, const ArrayArg& x_arg) {
                    const auto v = to_array(v_arg, "velocities");
                    const auto x = to_array(x_arg, "positions");
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
           [](const Holder<Triple1DPaper>& h, const ArrayArg& g_arg) {
             const auto g = to_array(g_arg, "g");
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
}

// --- 3 particles, 2D
void register_triple2d(py::module_& m) {
  py::class_<Holder<Triple2DPaper>> t2(m, "Triple2DPaper", kTriple2DDoc);
  t2.def(py::init([]() { return Holder<Triple2DPaper>{Triple2DPaper(), {}}; }));
  common_methods<Triple2DPaper>(t2, "positions");
  t2.def_static("angles",
                [](const ArrayArg& v_arg, const ArrayArg& x_arg) {
                  const auto v = to_array(v_arg, "velocities");
                  const auto x = to_array(x_arg, "positions");
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
                  [](const ArrayArg& x_arg) {
                    const auto x = to_array(x_arg, "positions");
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
           [](const Holder<Triple2DPaper>& h, const ArrayArg& g_arg) {
             const auto g = to_array(g_arg, "g");
             return map_entries(g, {3}, "g", 3, [&](const double* p, double* out) {
               const auto psi = h.op.sampler().psi({p[0], p[1], p[2]});
               for (int k = 0; k < 3; ++k) out[k] = psi[k];
             });
           },
           py::arg("g"), "G-to-Psi (Procedure 5): (psi1, psi2, psi3) per entry of g (3,) or (B, 3).")
      .def("__repr__", [](const Holder<Triple2DPaper>&) { return std::string("revcol.Triple2DPaper()"); });
}

}  // namespace

void register_paper(py::module_& m) {
  register_pair3d(m);
  register_triple1d(m);
  register_triple2d(m);
}

}  // namespace revcol::bind
