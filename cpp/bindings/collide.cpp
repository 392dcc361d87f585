// Binding of the collision operators: numpy arrays in and out, nothing else. A single
// collision is a batch of one; the shapes of the input are kept in the output.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <optional>
#include <type_traits>
#include <vector>

#include "args.hpp"
#include "arrays.hpp"
#include "bindings.hpp"
#include "revcol/collide/pair1d.hpp"
#include "revcol/collide/pair2d.hpp"
#include "revcol/collide/wall.hpp"

namespace py = pybind11;

namespace revcol::bind {
namespace {

// velocities: (2, 2) or (B, 2, 2) -> B pairs; `rows` tells which.
std::vector<PairV<2>> pairs_from(const Array& v, Rows& rows) {
  rows = rows_of(v, {2, 2}, "velocities");
  std::vector<PairV<2>> out(rows.count);
  const double* p = v.data();
  for (std::size_t b = 0; b < rows.count; ++b, p += 4) out[b] = {{p[0], p[1]}, {p[2], p[3]}};
  return out;
}

Array pairs_to(const std::vector<PairV<2>>& v, const Rows& rows) {
  Array out(rows.batched ? batched({2, 2}, v.size()) : Shape{2, 2});
  double* p = out.mutable_data();
  for (const PairV<2>& x : v) {
    *p++ = x.i[0]; *p++ = x.i[1]; *p++ = x.j[0]; *p++ = x.j[1];
  }
  return out;
}

// normal: (2,) broadcast to all B, or (B, 2).
std::vector<std::array<double, 2>> normals_from(const Array& n, std::size_t B) {
  std::vector<std::array<double, 2>> out(B);
  const auto p = per_entry(n, {2}, B, "normal");
  for (std::size_t b = 0; b < B; ++b) out[b] = {p[b][0], p[b][1]};
  return out;
}

// Runs forward or reverse with exactly one source of random numbers.
Array run_pair2d(Pair2D& op, const ArrayArg& velocities_arg, const ArrayArg& normal_arg, const py::object& rng,
                 const std::optional<ArrayArg>& g_arg, const std::optional<ArrayArg>& momentum_arg,
                 const std::optional<ArrayArg>& energy_arg, batch::Dir dir) {
  const Array velocities = to_array(velocities_arg, "velocities"), normal = to_array(normal_arg, "normal");
  const auto g = to_array(g_arg, "g"), momentum = to_array(momentum_arg, "momentum");
  const auto energy = to_array(energy_arg, "energy");
  Rows rows{};
  std::vector<PairV<2>> v = pairs_from(velocities, rows);
  const auto n = normals_from(normal, v.size());
  const auto inv = invariants_from<2>(momentum, energy, v.size());
  const Invariants<2>* ip = inv ? inv->data() : nullptr;
  const bool fwd = dir == batch::Dir::forward;
  with_draws(rng, g.has_value(), [&](auto gen) {
    if constexpr (std::is_null_pointer_v<decltype(gen)>) {
      const std::vector<double> gv = draws_from(*g, rows, Pair2D::draws);
      if (fwd) op.forward(v.data(), n.data(), v.size(), gv.data(), ip);
      else op.reverse(v.data(), n.data(), v.size(), gv.data(), ip);
    } else {
      if (fwd) op.forward(v.data(), n.data(), v.size(), *gen, ip);
      else op.reverse(v.data(), n.data(), v.size(), *gen, ip);
    }
  });
  return pairs_to(v, rows);
}

const char* kPair2DDoc = R"(Pair collisions in 2 dimensions, reversible.

mode="exact" (default): the post-collision relative velocity w = v_i - v_j is drawn
exactly from `law` over the permitted half circle {a.w > 0} (a: unit contact normal from
particle j to particle i) by a measure-preserving chart c onto [0, 1) and a K-bit torus
shift c = c' + G (mod 1): law="flux" (default) has density ~ a.w (cos of the angle to
the normal), law="uniform" is uniform in angle. mode="paper": the paper's Procedures 1/2
(uniform), with the reverse testing the candidate pre angle (printed_reverse=True keeps
the printed, faulty test). One random number per collision. Momentum and energy are
conserved; give momentum= and energy= to hold them (the paper's illustrations).

Example:
    >>> import numpy as np, revcol
    >>> op, g = revcol.Pair2D(), revcol.CLCG4()
    >>> v = np.array([[1.0, 0.0], [-1.0, 0.0]])   # rows: particle i, particle j
    >>> post = op.forward(v, normal=[-1.0, 0.0], rng=g)
    >>> back = op.reverse(post, normal=[-1.0, 0.0], rng=g)   # g steps back
)";

void register_pair2d(py::module_& m) {
  py::class_<Pair2D>(m, "Pair2D", kPair2DDoc)
      .def(py::init([](PyStr mode, PyStr law, PyInt bits, bool printed) {
             return Pair2D(parse_mode(to_str(mode, "mode")), parse_law(to_str(law, "law")),
                           to_int<int>(bits, "bits", FixedPoint::min_bits, FixedPoint::max_bits), printed);
           }),
           py::kw_only(), py::arg("mode") = "exact", py::arg("law") = "flux",
           py::arg("bits") = FixedPoint::default_bits, py::arg("printed_reverse") = false)
      .def("forward",
           [](Pair2D& op, const ArrayArg& v, const ArrayArg& n, py::object rng, std::optional<ArrayArg> g,
              std::optional<ArrayArg> momentum, std::optional<ArrayArg> energy) {
             return run_pair2d(op, v, n, rng, g, momentum, energy, batch::Dir::forward);
           },
           py::arg("velocities"), py::arg("normal"), py::kw_only(), py::arg("rng") = py::none(),
           py::arg("g") = py::none(), py::arg("momentum") = py::none(), py::arg("energy") = py::none(),
           "Pre -> post. velocities (2, 2) or (B, 2, 2) [rows: particle i, particle j]; normal (2,) or\n"
           "(B, 2) from j to i; exactly one of rng (drawn in entry order) or g (draws in [0,1]).\n"
           "Every entry is validated first; on error nothing changes.")
      .def("reverse",
           [](Pair2D& op, const ArrayArg& v, const ArrayArg& n, py::object rng, std::optional<ArrayArg> g,
              std::optional<ArrayArg> momentum, std::optional<ArrayArg> energy) {
             return run_pair2d(op, v, n, rng, g, momentum, energy, batch::Dir::reverse);
           },
           py::arg("velocities"), py::arg("normal"), py::kw_only(), py::arg("rng") = py::none(),
           py::arg("g") = py::none(), py::arg("momentum") = py::none(), py::arg("energy") = py::none(),
           "Post -> pre with the draws forward used (rng steps back, last entry first).")
      .def("quantize",
           [](const Pair2D& op, const ArrayArg& v_arg, const ArrayArg& n_arg, std::optional<ArrayArg> momentum_arg,
              std::optional<ArrayArg> energy_arg) {
             const auto v = to_array(v_arg, "velocities");
             const auto n = to_array(n_arg, "normal");
             const auto momentum = to_array(momentum_arg, "momentum");
             const auto energy = to_array(energy_arg, "energy");
             Rows rows{};
             std::vector<PairV<2>> pv = pairs_from(v, rows);
             const auto nv = normals_from(n, pv.size());
             const auto inv = invariants_from<2>(momentum, energy, pv.size());
             std::vector<PairV<2>> out(pv.size());
             for (std::size_t b = 0; b < pv.size(); ++b)
               out[b] = op.quantize(pv[b], nv[b], inv ? &(*inv)[b] : nullptr);
             return pairs_to(out, rows);
           },
           py::arg("velocities"), py::arg("normal"), py::kw_only(), py::arg("momentum") = py::none(),
           py::arg("energy") = py::none(),
           "The pre state as reversal restores it: exact mode decodes its chart cell at the centre.")
      .def("chart",
           [](const Pair2D& op, const ArrayArg& v_arg, const ArrayArg& n_arg) {
             const auto v = to_array(v_arg, "velocities");
             const auto n = to_array(n_arg, "normal");
             Rows rows{};
             std::vector<PairV<2>> pv = pairs_from(v, rows);
             const auto nv = normals_from(n, pv.size());
             py::array_t<double> out(static_cast<py::ssize_t>(pv.size()));
             for (std::size_t b = 0; b < pv.size(); ++b) {
               try {
                 out.mutable_data()[b] = op.chart(pv[b], nv[b]);
               } catch (const InvalidArgument& e) {
                 throw InvalidArgument((rows.batched ? "entry " + std::to_string(b) + ": " : std::string()) + e.what());
               }
             }
             return out;
           },
           py::arg("velocities"), py::arg("normal"),
           "Exact mode's chart coordinate in [0, 1] of post states (uniform under the law), one per entry.\n"
           "Defined on a.w >= 0 (w = v_i - v_j; grazing gives 0 or 1): an approaching state, a zero\n"
           "relative velocity or a non-finite one raises InvalidArgument (a ValueError) naming the entry.")
      .def_property_readonly("mode", [](const Pair2D& op) { return to_string(op.mode()); })
      .def_property_readonly("law", [](const Pair2D& op) { return to_string(op.law()); })
      .def_property_readonly("bits", &Pair2D::bits)
      .def_property_readonly("printed_reverse", &Pair2D::printed_reverse)
      .def_property_readonly_static("draws", [](py::object) { return Pair2D::draws; },
                                    "random numbers per collision")
      .def_property_readonly("log_size", [](const Pair2D& op) { return op.log().size(); },
                             "entries on the rare log")
      .def_property_readonly("log_bytes", [](const Pair2D& op) { return op.log().bytes(); })
      .def_property_readonly("log_pushed", [](const Pair2D& op) { return op.log().pushed(); },
                             "entries ever pushed")
      .def("clear_log", [](Pair2D& op) { op.log().clear(); })
      .def("__repr__", [](const Pair2D& op) {
        return std::string("revcol.Pair2D(mode='") + to_string(op.mode()) + "', law='" +
               to_string(op.law()) + "', bits=" + std::to_string(op.bits()) + ")";
      });
}

// Pair1D forward (dir > 0) or reverse on (2,) or (B, 2) velocities, every entry validated first.
Array run_pair1d(const Array& v, const Array& n, int dir) {
  const bool batched = v.ndim() == 2;
  require((v.ndim() == 1 && v.shape(0) == 2) || (v.ndim() == 2 && v.shape(1) == 2),
          [&] { return "velocities must have shape (2,) or (B, 2), got " + shape_of(v); });
  const std::size_t B = batched ? v.shape(0) : 1;
  require((n.ndim() == 0) || (n.ndim() == 1 && static_cast<std::size_t>(n.shape(0)) == B),
          [&] { return "normal must be a number or have shape (B,), got " + shape_of(n); });
  const Pair1D op;
  std::vector<PairV<1>> out(B);
  for (std::size_t b = 0; b < B; ++b) {  // validate all before returning anything
    const PairV<1> x{{v.data()[2 * b]}, {v.data()[2 * b + 1]}};
    const double nb = n.data()[n.ndim() == 0 ? 0 : b];
    try {
      out[b] = dir > 0 ? op.forward(x, nb) : op.reverse(x, nb);
    } catch (const InvalidArgument& e) {
      throw InvalidArgument((batched ? "entry " + std::to_string(b) + ": " : std::string()) + e.what());
    }
  }
  Array res(std::vector<py::ssize_t>(v.shape(), v.shape() + v.ndim()));
  for (std::size_t b = 0; b < B; ++b) {
    res.mutable_data()[2 * b] = out[b].i[0];
    res.mutable_data()[2 * b + 1] = out[b].j[0];
  }
  return res;
}

void register_pair1d(py::module_& m) {
  py::class_<Pair1D>(m, "Pair1D",
                     "Pair collisions in 1 dimension: the velocities are exchanged (no random number).\n"
                     "velocities (2,) or (B, 2) = (v_i, v_j); normal = sign of x_i - x_j.")
      .def(py::init<>())
      .def("forward", [](const Pair1D&, const ArrayArg& v_arg, const ArrayArg& n_arg) {
        const auto v = to_array(v_arg, "velocities");
        const auto n = to_array(n_arg, "normal"); return run_pair1d(v, n, +1); },
           py::arg("velocities"), py::arg("normal"), "Pre -> post (the pair must approach).")
      .def("reverse", [](const Pair1D&, const ArrayArg& v_arg, const ArrayArg& n_arg) {
        const auto v = to_array(v_arg, "velocities");
        const auto n = to_array(n_arg, "normal"); return run_pair1d(v, n, -1); },
           py::arg("velocities"), py::arg("normal"), "Post -> pre (the pair must separate).")
      .def_property_readonly_static("draws", [](py::object) { return Pair1D::draws; });
}

// Wall forward (dir > 0) or reverse of one particle: position and velocity of shape (d,).
Array run_wall(const Wall& w, const Array& x, const Array& v, double radius, double tol, int dir) {
  const Box& box = w.box();
  require(x.ndim() == 1 && v.ndim() == 1 && x.shape(0) == box.dim && v.shape(0) == box.dim,
          [&] { return "position and velocity must have shape (" + std::to_string(box.dim) + ",)"; });
  std::array<double, 3> xa{}, va{};
  for (int k = 0; k < box.dim; ++k) { xa[k] = x.data()[k]; va[k] = v.data()[k]; }
  const auto out = dir > 0 ? w.forward(xa, va, radius, tol) : w.reverse(xa, va, radius, tol);
  Array res(box.dim);
  for (int k = 0; k < box.dim; ++k) res.mutable_data()[k] = out[k];
  return res;
}

void register_wall(py::module_& m) {
  py::class_<Wall>(m, "Wall",
                  "Reflection on the walls of the box [lo, hi] (d = 1..3): every wall the particle\n"
                  "touches (within tol) and approaches flips its normal velocity component. A particle\n"
                  "leaving a touched wall is refused (not one reversible event).")
      .def(py::init([](const ArrayArg& lo_arg, const ArrayArg& hi_arg) {
        const auto lo = to_array(lo_arg, "lo");
        const auto hi = to_array(hi_arg, "hi");
             require(lo.ndim() == 1 && hi.ndim() == 1 && lo.shape(0) == hi.shape(0) &&
                         lo.shape(0) >= 1 && lo.shape(0) <= 3,
                     "lo and hi must have the same shape (d,), d = 1, 2 or 3");
             Box b;
             b.dim = static_cast<int>(lo.shape(0));
             for (int k = 0; k < b.dim; ++k) {
               require(std::isfinite(lo.data()[k]) && std::isfinite(hi.data()[k]) && hi.data()[k] > lo.data()[k],
                       "box walls must be finite with hi > lo on every axis");
               b.lo[k] = lo.data()[k];
               b.hi[k] = hi.data()[k];
             }
             return Wall(b);
           }),
           py::arg("lo"), py::arg("hi"))
      .def("forward", [](const Wall& w, const ArrayArg& x_arg, const ArrayArg& v_arg, double r, double tol) {
        const auto x = to_array(x_arg, "positions");
        const auto v = to_array(v_arg, "velocities"); return run_wall(w, x, v, r, tol, +1); },
           py::arg("position"), py::arg("velocity"), py::arg("radius"), py::arg("tol") = 1e-9)
      .def("reverse", [](const Wall& w, const ArrayArg& x_arg, const ArrayArg& v_arg, double r, double tol) {
        const auto x = to_array(x_arg, "positions");
        const auto v = to_array(v_arg, "velocities"); return run_wall(w, x, v, r, tol, -1); },
           py::arg("position"), py::arg("velocity"), py::arg("radius"), py::arg("tol") = 1e-9)
      .def_property_readonly_static("draws", [](py::object) { return Wall::draws; });
}

}  // namespace

void register_collide(py::module_& m) {
  register_pair2d(m);
  register_pair1d(m);
  register_wall(m);
}

}  // namespace revcol::bind
