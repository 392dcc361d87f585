// Binding of revcol/studies/randomness.hpp: the word stream of the randomness study (type
// conversion and registration only; python/revcol/randomness.py drives it).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstdint>
#include <string>

#include "args.hpp"
#include "bindings.hpp"
#include "revcol/error.hpp"
#include "revcol/studies/randomness.hpp"

namespace py = pybind11;

namespace revcol::bind {

void register_randomness(py::module_& m) {
  using randomness::WordStream;
  py::class_<WordStream>(m, "WordStream",
                         "A chain of collisions whose post-state chart coordinates are 32-bit words "
                         "(see revcol.randomness).")
      .def(py::init([](PyStr case_name, PyStr mode, PyStr law, PyStr cdf_law, PyStr rng, PyInt seed, PyInt bits,
                       PyInt particles, PyReal fraction, PyReal warmup) {
             randomness::StreamConfig c;
             c.case_name = to_str(case_name, "case");
             c.mode = parse_mode(to_str(mode, "mode"));
             c.law = parse_law(to_str(law, "law"));
             c.cdf_law = parse_law(to_str(cdf_law, "cdf_law"));
             c.rng = to_str(rng, "rng");
             c.seed = to_int<std::uint64_t>(seed, "seed");
             c.bits = to_int<int>(bits, "bits");
             c.gas_particles = to_int<std::size_t>(particles, "particles");
             c.gas_fraction = to_real(fraction, "fraction");
             c.gas_warmup = to_real(warmup, "warmup");
             return WordStream(c);
           }),
           py::kw_only(), py::arg("case"), py::arg("mode") = "exact", py::arg("law") = "flux",
           py::arg("cdf_law") = "flux", py::arg("rng") = "philox", py::arg("seed") = 0,
           py::arg("bits") = FixedPoint::default_bits, py::arg("particles") = 1000, py::arg("fraction") = 0.2,
           py::arg("warmup") = 5.0)
      .def("words",
           [](WordStream& s, PyInt n_arg) {
             const auto n = to_int<std::int64_t>(n_arg, "n", 0, std::int64_t{1} << 40);
             py::array_t<std::uint32_t> out(static_cast<py::ssize_t>(n));
             std::uint32_t* p = out.mutable_data();
             {
               py::gil_scoped_release release;
               s.fill(p, static_cast<std::size_t>(n), released_signal_check());
             }
             return out;
           },
           py::arg("n"), "The next n words (numpy uint32).")
      .def("write",
           [](WordStream& s, PyStr path_arg, PyInt n_arg) {
             const std::string path = to_str(path_arg, "path");
             const auto n = to_int<std::int64_t>(n_arg, "n", 0);
             py::gil_scoped_release release;
             s.write(path, static_cast<std::uint64_t>(n), released_signal_check());
           },
           py::arg("path"), py::arg("n"), "Appends the next n words to a raw file (dieharder -g 201).")
      .def_property_readonly("width", &WordStream::width, "Words per collision (d_n; 1 for 'raw').")
      .def_property_readonly("collisions", &WordStream::collisions, "Collisions (or raw draws) so far.")
      .def_property_readonly("emitted", &WordStream::words, "Words emitted so far.")
      .def_property_readonly("restarts", &WordStream::restarts, "Paper mode: chain restarts after a failed step.")
      .def_property_readonly("skipped", &WordStream::skipped, "Gas: group collisions (they give no word).");
  m.def("stream_cases", [](const std::string& mode) { return randomness::stream_cases(parse_mode(mode)); },
        py::arg("mode"), "The cases a WordStream knows for a mode ('raw' first).");
}

}  // namespace revcol::bind
