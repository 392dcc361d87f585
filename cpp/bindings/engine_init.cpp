// Binding of the engine's random start and limits (revcol/engine/init.hpp, limits.hpp):
// numpy out, a dict of limits. No physics here.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstring>
#include <string>
#include <vector>

#include "args.hpp"
#include "bindings.hpp"
#include "revcol/engine/engine.hpp"
#include "revcol/engine/init.hpp"
#include "revcol/engine/limits.hpp"
#include "revcol/error.hpp"
#include "revcol/rng/streams.hpp"

namespace py = pybind11;

namespace revcol::bind {
namespace {

namespace en = revcol::engine;
namespace lim = revcol::engine::limits;

py::array_t<double> rows(const std::vector<double>& v, std::size_t n, int d) {
  py::array_t<double> out({static_cast<py::ssize_t>(n), static_cast<py::ssize_t>(d)});
  if (!v.empty()) std::memcpy(out.mutable_data(), v.data(), v.size() * sizeof(double));
  return out;
}

py::dict engine_limits() {
  py::dict d;
  py::dict maxf, rsaf, maxn, relf;
  for (int k = lim::kMinDim; k <= lim::kMaxDim; ++k) {
    maxn[py::int_(k)] = lim::max_particles(k);
    maxf[py::int_(k)] = lim::max_fraction(k);
    relf[py::int_(k)] = lim::max_relax_fraction(k);
    rsaf[py::int_(k)] = lim::rsa_fraction(k);
  }
  py::list paper;
  for (int k = lim::kMinDim; k <= lim::kMaxDim; ++k)
    if (lim::paper_mode_allowed(k)) paper.append(k);
  d["dimensions"] = py::make_tuple(lim::kMinDim, lim::kMaxDim);
  d["max_particles"] = maxn;
  d["max_fraction"] = maxf;
  d["rsa_fraction"] = rsaf;
  d["max_relax_fraction"] = relf;
  d["min_periodic_cells"] = lim::kMinPeriodicCells;
  d["bits"] = py::make_tuple(lim::kMinBits, lim::kMaxBits);
  d["max_seed"] = lim::kMaxSeed;
  d["max_group_tol"] = lim::kMaxGroupTol;
  d["wall_margin"] = lim::kWallMargin;
  d["paper_mode_dimensions"] = py::tuple(paper);
  py::list boundaries;
  for (const en::Boundary b : en::kBoundaries) boundaries.append(en::to_string(b));
  d["boundaries"] = py::tuple(boundaries);
  d["generators"] = py::make_tuple(en::to_string(en::Generator::philox), en::to_string(en::Generator::clcg4));
  d["streams"] = py::make_tuple(std::string(rng::to_string(rng::StreamPolicy::per_particle)),
                                std::string(rng::to_string(rng::StreamPolicy::single)));
  return d;
}

}  // namespace

void register_engine_init(py::module_& m) {
  m.def("engine_limits", &engine_limits,
        "The engine's limits (revcol/engine/limits.hpp) as a dict: dimensions, max_particles, max_fraction, "
        "rsa_fraction and max_relax_fraction per d, min_periodic_cells, bits, max_seed, max_group_tol, wall_margin, "
        "paper_mode_dimensions, and the names of boundaries, generators and streams.");
  m.def("engine_particle_volume", &lim::particle_volume, py::arg("dim"), py::arg("diameter"),
        "The volume (length in 1D, area in 2D) of one particle of diameter D in d dimensions.");
  m.def(
      "engine_random_start",
      [](std::size_t n, const std::vector<double>& box, const std::vector<std::string>& boundary, double diameter,
         std::uint64_t seed, double energy, const std::string& init, bool equal_speeds, std::vector<double> masses,
         std::vector<double> diameters) {
        const int dim = static_cast<int>(box.size());
        require(dim >= lim::kMinDim && dim <= lim::kMaxDim,
                [&] { return "box must have 1, 2 or 3 lengths, got " + std::to_string(dim); });
        require(boundary.size() == 1 || boundary.size() == box.size(), "boundary must be one name or one per axis");
        en::Config c;
        c.dim = dim;
        for (int k = 0; k < dim; ++k) {
          c.box[k] = box[k];
          c.boundary[k] = en::parse_boundary(boundary.size() == 1 ? boundary[0] : boundary[k]);
        }
        c.diameter = diameter;
        c.masses = std::move(masses);  // velocities / sqrt(m), the centre of mass at rest
        c.diameters = std::move(diameters);  // a mixture: as the largest, or relaxed at its own sizes
        const en::InitialState s = en::random_start(c, n, seed, energy, init, equal_speeds, held_signal_check());
        return py::make_tuple(rows(s.x, n, dim), rows(s.v, n, dim));
      },
      py::arg("n"), py::arg("box"), py::arg("boundary"), py::arg("diameter"), py::arg("seed"),
      py::arg("energy") = 0.0, py::arg("init") = "auto", py::arg("equal_speeds") = false, py::arg("masses") = std::vector<double>{},
      py::arg("diameters") = std::vector<double>{},
      "A random start of n particles in the box (engine/init.hpp): (positions, velocities), each (n, dim). "
      "diameters (one per particle): a mixture, placed as the largest or (init 'relax', or 'auto' when they do not "
      "fit so) at random at its own sizes with the overlaps relaxed away.");
}

}  // namespace revcol::bind
