// Binding of the general exact operator (revcol.Collision) and the named cases: numpy in
// and out, nothing else.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <optional>
#include <type_traits>

#include "args.hpp"
#include "arrays.hpp"
#include "bindings.hpp"
#include "revcol/collide/cases.hpp"
#include "revcol/collide/collision.hpp"

namespace py = pybind11;

namespace revcol::bind {
namespace {

std::vector<Contact> contacts_from(const std::vector<std::pair<int, int>>& pairs) {
  std::vector<Contact> out;
  for (const auto& p : pairs) out.push_back({p.first, p.second});
  return out;
}

// (n, d) or (B, n, d)
Rows rows_for(const ExactCollision& op, const Array& v) {
  return rows_of(v, {op.particles(), op.dim()}, "velocities");
}

// momentum= and energy= as ExactCollision's Held, or none.
std::optional<std::vector<Held>> held_for(const ExactCollision& op, const std::optional<Array>& momentum,
                                          const std::optional<Array>& energy, std::size_t B) {
  const auto h = held_from(momentum, energy, B, op.dim());
  if (!h) return std::nullopt;
  std::vector<Held> out;
  for (std::size_t b = 0; b < B; ++b) out.push_back(Held{h->momentum[b], h->energy[b]});
  return out;
}

Array run(Collision& c, const ArrayArg& v_arg, const py::object& rng, const std::optional<ArrayArg>& g_arg,
          const std::optional<ArrayArg>& momentum_arg, const std::optional<ArrayArg>& energy_arg, batch::Dir dir) {
  const Array v = to_array(v_arg, "velocities");
  const auto g = to_array(g_arg, "g"), momentum = to_array(momentum_arg, "momentum");
  const auto energy = to_array(energy_arg, "energy");
  const ExactCollision& op = c.op();
  const Rows rows = rows_for(op, v);
  const auto held = held_for(op, momentum, energy, rows.count);
  const Held* hp = held ? held->data() : nullptr;
  Array out(shape(v));
  double* o = out.mutable_data();
  const bool fwd = dir == batch::Dir::forward;
  with_draws(rng, g.has_value(), [&](auto gen) {
    if constexpr (std::is_null_pointer_v<decltype(gen)>) {
      const std::vector<double> gv = draws_from(*g, rows, op.draws());
      if (fwd) c.forward(v.data(), rows.count, gv.data(), o, hp);
      else c.reverse(v.data(), rows.count, gv.data(), o, hp);
    } else {
      if (fwd) c.forward(v.data(), rows.count, *gen, o, hp);
      else c.reverse(v.data(), rows.count, *gen, o, hp);
    }
  });
  return out;
}

const char* kDoc = R"(The exact collision operator for n particles in d dimensions (d = 1..3) with at
most 3 independent contacts.

The relative velocities, in orthonormal (Helmert) coordinates x of the zero-momentum
subspace (dimension D = (n-1) d), lie on the sphere |x| = rho; each contact (i, j), with
normal r from j to i, must separate after the collision: r . (v_i - v_j) > 0. The post state
is drawn exactly from `law` over that permitted cone: "flux" (default; density ~ the
separation rate, cos(eta) of the angle to the contacts' span) or "uniform". A
measure-preserving chart maps the cone onto [0,1)^(D-1); a K-bit torus shift by the
d_n = D - 1 random numbers moves the pre state's cell to the post state's, so reverse()
recovers the pre state exactly (after its first quantization) with the same numbers.

    >>> import numpy as np, revcol
    >>> op = revcol.Collision.named("triple1d")          # 3 particles in a row, 1D
    >>> g = revcol.CLCG4()
    >>> v = np.array([[1.0], [0.0], [0.0]])               # Newton's cradle
    >>> post = op.forward(v, rng=g)
    >>> np.allclose(op.reverse(post, rng=g), v)
    True
)";

// Collision(n, d, contacts, normals= or positions=, ...): the constructor's checks and conversions.
Collision make_collision(PyInt n_arg, PyInt d_arg, const std::vector<std::pair<int, int>>& contacts,
                         std::optional<ArrayArg> normals_arg, std::optional<ArrayArg> positions_arg,
                         PyReal diameter_arg, PyStr law_arg, PyInt bits_arg, PyReal tol_arg) {
  const std::string law = to_str(law_arg, "law");
  const auto normals = to_array(normals_arg, "normals");
  const auto positions = to_array(positions_arg, "positions");
  const int n = to_int<int>(n_arg, "n"), d = to_int<int>(d_arg, "d");
  const int bits = to_int<int>(bits_arg, "bits", FixedPoint::min_bits, FixedPoint::max_bits);
  const double diameter = to_real(diameter_arg, "diameter"), tol = to_real(tol_arg, "tol");
  require(normals.has_value() != positions.has_value(),
          "give exactly one of normals= (m x d) or positions= (n x d)");
  if (positions) {
    require(positions->ndim() == 2 && positions->shape(0) == n && positions->shape(1) == d,
            [&] { return "positions must have shape (" + std::to_string(n) + ", " + std::to_string(d) + "), got " + shape_of(*positions); });
    std::vector<double> p(positions->data(), positions->data() + n * d);
    return Collision(ExactCollision::from_positions(n, d, contacts_from(contacts), p,
                                                    diameter, parse_law(law), bits, tol));
  }
  require(normals->ndim() == 2 && normals->shape(1) == d &&
              normals->shape(0) == static_cast<py::ssize_t>(contacts.size()),
          [&] { return "normals must have shape (" + std::to_string(contacts.size()) + ", " + std::to_string(d) + "), got " + shape_of(*normals); });
  std::vector<double> nv(normals->data(), normals->data() + normals->size());
  return Collision(ExactCollision(n, d, contacts_from(contacts), nv, parse_law(law), bits));
}

void register_collision(py::module_& m) {
  py::class_<Collision>(m, "Collision", kDoc)
      .def(py::init(&make_collision),
           py::arg("n"), py::arg("d"), py::arg("contacts"), py::kw_only(),
           py::arg("normals") = py::none(), py::arg("positions") = py::none(),
           py::arg("diameter") = 1.0, py::arg("law") = "flux", py::arg("bits") = 40,
           py::arg("tol") = 1e-9)
      .def_static("named",
                  [](PyStr name, PyStr law, PyInt bits) {
                    return Collision(exact_operator(named_case(to_str(name, "name")), parse_law(to_str(law, "law")),
                                                    to_int<int>(bits, "bits", FixedPoint::min_bits, FixedPoint::max_bits)));
                  },
                  py::arg("name"), py::kw_only(), py::arg("law") = "flux", py::arg("bits") = 40,
                  "The operator of a named case (see revcol.named_cases()).")
      .def("forward",
           [](Collision& c, const ArrayArg& v, py::object rng, std::optional<ArrayArg> g,
              std::optional<ArrayArg> mo, std::optional<ArrayArg> en) { return run(c, v, rng, g, mo, en, batch::Dir::forward); },
           py::arg("velocities"), py::kw_only(), py::arg("rng") = py::none(), py::arg("g") = py::none(),
           py::arg("momentum") = py::none(), py::arg("energy") = py::none(),
           "Pre -> post. velocities (n, d) or (B, n, d); exactly one of rng or g ((d_n,) or (B, d_n)).")
      .def("reverse",
           [](Collision& c, const ArrayArg& v, py::object rng, std::optional<ArrayArg> g,
              std::optional<ArrayArg> mo, std::optional<ArrayArg> en) { return run(c, v, rng, g, mo, en, batch::Dir::reverse); },
           py::arg("velocities"), py::kw_only(), py::arg("rng") = py::none(), py::arg("g") = py::none(),
           py::arg("momentum") = py::none(), py::arg("energy") = py::none(),
           "Post -> pre with the draws forward used (rng steps back).")
      .def("chart",
           [](const Collision& c, const ArrayArg& v_arg) {
             const auto v = to_array(v_arg, "velocities");
             const ExactCollision& op = c.op();
             const Rows rows = rows_for(op, v);
             const std::size_t B = rows.count, nd = op.particles() * op.dim(), k = op.draws();
             Array out(rows.batched ? batched({op.draws()}, B) : Shape{op.draws()});
             for (std::size_t b = 0; b < B; ++b) {
               try {
                 const std::vector<double> cb = op.chart(v.data() + b * nd);
                 std::copy(cb.begin(), cb.end(), out.mutable_data() + b * k);
               } catch (const InvalidArgument& e) {
                 throw InvalidArgument((rows.batched ? "entry " + std::to_string(b) + ": " : std::string()) + e.what());
               }
             }
             return out;
           },
           py::arg("velocities"),
           "Chart coordinates in [0, 1] of post states: uniform under the law. Defined where every contact\n"
           "separates or grazes: an approaching contact, a zero relative speed or a non-finite velocity\n"
           "raises InvalidArgument (a ValueError) naming the entry and the contact.")
      .def("quantize",
           [](const Collision& c, const ArrayArg& v_arg, std::optional<ArrayArg> mo_arg, std::optional<ArrayArg> en_arg) {
             const auto v = to_array(v_arg, "velocities");
             const auto mo = to_array(mo_arg, "momentum");
             const auto en = to_array(en_arg, "energy");
             const ExactCollision& op = c.op();
             const std::size_t B = rows_for(op, v).count, nd = op.particles() * op.dim();
             const auto held = held_for(op, mo, en, B);
             Array out(shape(v));
             for (std::size_t b = 0; b < B; ++b)
               op.quantize(v.data() + b * nd, out.mutable_data() + b * nd, held ? &(*held)[b] : nullptr);
             return out;
           },
           py::arg("velocities"), py::kw_only(), py::arg("momentum") = py::none(), py::arg("energy") = py::none(),
           "The pre state as reversal restores it (its cells decoded at the centre).")
      .def("normal_speeds",
           [](const Collision& c, const ArrayArg& v_arg) {
             const auto v = to_array(v_arg, "velocities");
             const ExactCollision& op = c.op();
             require(!rows_for(op, v).batched, "one state of shape (n, d)");
             return op.normal_speeds(v.data());
           },
           py::arg("velocities"), "r_k . (v_i - v_j) for each contact (< 0 approaching).")
      .def_property_readonly("particles", [](const Collision& c) { return c.op().particles(); })
      .def_property_readonly("dim", [](const Collision& c) { return c.op().dim(); })
      .def_property_readonly("relative_dim", [](const Collision& c) { return c.op().relative_dim(); })
      .def_property_readonly("free_dim", [](const Collision& c) { return c.op().free_dim(); })
      .def_property_readonly("draws", [](const Collision& c) { return c.op().draws(); })
      .def_property_readonly("contacts", [](const Collision& c) {
        std::vector<std::pair<int, int>> out;
        for (const Contact& k : c.op().contact_list()) out.emplace_back(k.i, k.j);
        return out;
      })
      .def_property_readonly("law", [](const Collision& c) { return to_string(c.op().law()); })
      .def_property_readonly("bits", [](const Collision& c) { return c.op().bits(); })
      .def_property_readonly("log_size", [](const Collision& c) { return c.log().size(); })
      .def_property_readonly("log_bytes", [](const Collision& c) { return c.log().bytes(); })
      .def_property_readonly("log_pushed", [](const Collision& c) { return c.log().pushed(); })
      .def("clear_log", [](Collision& c) { c.log().clear(); })
      .def("__repr__", [](const Collision& c) {
        return "revcol.Collision(n=" + std::to_string(c.op().particles()) + ", d=" +
               std::to_string(c.op().dim()) + ", contacts=" + std::to_string(c.op().contacts()) +
               ", law='" + to_string(c.op().law()) + "')";
      });
}

void register_named_cases(py::module_& m) {
  m.def("named_cases", [] {
    py::list out;
    for (const NamedCase& c : named_cases()) {
      py::dict d;
      d["name"] = c.name;
      d["n"] = c.n;
      d["d"] = c.d;
      std::vector<std::pair<int, int>> pairs;
      for (const Contact& k : c.contacts) pairs.emplace_back(k.i, k.j);
      d["contacts"] = pairs;
      Array pos({static_cast<py::ssize_t>(c.n), static_cast<py::ssize_t>(c.d)});
      std::copy(c.positions.begin(), c.positions.end(), pos.mutable_data());
      d["positions"] = pos;
      d["description"] = c.description;
      out.append(d);
    }
    return out;
  }, "The named collision geometries (the paper's configurations and beyond).");
}

}  // namespace

void register_exact(py::module_& m) {
  register_collision(m);
  register_named_cases(m);
}

}  // namespace revcol::bind
