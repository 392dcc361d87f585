// Binding of revcol/studies/ecmc.hpp, the event-chain sampler: numpy in and out, the sums as a dict.
// No physics here (python/revcol/ecmc.py drives it).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstdint>
#include <cstring>
#include <optional>
#include <vector>

#include "args.hpp"
#include "bindings.hpp"
#include "revcol/error.hpp"
#include "revcol/studies/ecmc.hpp"

namespace py = pybind11;

namespace revcol::bind {
namespace {

using ecmc::ChainSums;
using ecmc::EventChain;

py::dict sums_dict(const ChainSums& s) {
  py::dict d;
  d["chains"] = s.chains;
  d["displacement"] = s.displacement;
  d["lift_dx"] = s.lift_dx;
  d["lifts"] = s.lifts;
  d["crossings"] = s.crossings;
  d["z"] = s.compressibility();
  return d;
}

}  // namespace

void register_ecmc(py::module_& m) {
  py::class_<EventChain>(m, "EventChain",
                         "Event-chain Monte Carlo of hard spheres in a periodic box (revcol/studies/ecmc.hpp): "
                         "an independent sampler of the equilibrium configurations and their pressure.")
      .def(py::init([](const std::vector<double>& box, const py::array_t<double, py::array::c_style | py::array::forcecast>& x,
                       const std::optional<PyReal>& diameter, PyInt seed, const py::object& diameters) {
             const auto d = static_cast<py::ssize_t>(box.size());
             require(x.ndim() == 2 && x.shape(1) == d, [&] {
               std::string shape;
               for (py::ssize_t k = 0; k < x.ndim(); ++k) shape += (k ? ", " : "") + std::to_string(x.shape(k));
               return "positions must be an (n, " + std::to_string(d) + ") array, got shape (" + shape + ")";
             });
             std::vector<double> xs(x.data(), x.data() + x.size());
             const auto sd = to_int<std::uint64_t>(seed, "seed");
             if (!diameters.is_none()) {
               require(!diameter, "give diameter (one size) or diameters (one per sphere), not both");
               const auto ds = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(diameters);
               require(ds && ds.ndim() == 1 && ds.shape(0) == x.shape(0), [&] {
                 return "diameters must be a 1-d array of one diameter per sphere (" + std::to_string(x.shape(0)) +
                        ")";
               });
               return EventChain(box, std::move(xs), std::vector<double>(ds.data(), ds.data() + ds.size()), sd);
             }
             const double one = to_real(diameter, "diameter").value_or(1.0);
             return EventChain(box, std::move(xs), one, sd);
           }),
           py::arg("box"), py::arg("positions"), py::kw_only(), py::arg("diameter") = py::none(), py::arg("seed") = 1,
           py::arg("diameters") = py::none())
      .def(
          "run",
          [](EventChain& s, PyInt chains, PyReal ell) {
            const auto n = to_int<std::uint64_t>(chains, "chains");
            const double l = to_real(ell, "chain_length");
            ChainSums out;
            {
              py::gil_scoped_release release;
              out = s.run(n, l, released_signal_check());
            }
            return sums_dict(out);
          },
          py::arg("chains"), py::arg("chain_length"),
          "Runs `chains` chains of length `chain_length`; returns their sums (chains, displacement, lift_dx, "
          "lifts, crossings) and z = 1 + lift_dx / displacement, beta P V / N of these chains. Ctrl-C stops "
          "between chains (totals keep the chains that finished).")
      .def_property_readonly(
          "positions",
          [](const EventChain& s) {
            const auto& x = s.positions();
            py::array_t<double> out({static_cast<py::ssize_t>(s.size()), static_cast<py::ssize_t>(s.dim())});
            if (!x.empty()) std::memcpy(out.mutable_data(), x.data(), x.size() * sizeof(double));
            return out;
          },
          "Positions, (n, d), each coordinate in [0, L_k).")
      .def_property_readonly("box", [](const EventChain& s) { return py::array(py::cast(s.box())); }, "Box lengths.")
      .def_property_readonly("dim", &EventChain::dim, "Dimension d.")
      .def_property_readonly("n", &EventChain::size, "Number of spheres.")
      .def_property_readonly("diameter", &EventChain::diameter, "Diameter D (a mixture's largest).")
      .def_property_readonly(
          "diameters",
          [](const EventChain& s) -> py::object {
            if (s.radii().empty()) return py::none();
            py::array_t<double> out(static_cast<py::ssize_t>(s.radii().size()));
            for (std::size_t i = 0; i < s.radii().size(); ++i) out.mutable_data()[i] = 2.0 * s.radii()[i];
            return out;
          },
          "A mixture's diameters by sphere; None for one diameter.")
      .def_property_readonly("packing_fraction", &EventChain::packing_fraction, "The spheres' volumes over V.")
      .def_property_readonly("totals", [](const EventChain& s) { return sums_dict(s.totals()); },
                             "The sums over every run so far, as run() returns them.")
      .def("min_distance", &EventChain::min_distance,
           "The smallest centre distance (nearest image) in contact distances (diameters for one size) over the "
           "pairs in neighbouring cells, which hold every pair closer than the largest diameter; inf when none.");
}

}  // namespace revcol::bind
