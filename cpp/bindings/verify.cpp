// Binding of verify(): keyword arguments in, a dict out.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "args.hpp"
#include "bindings.hpp"
#include "revcol/studies/verify.hpp"

namespace py = pybind11;

namespace revcol::bind {

void register_verify(py::module_& m) {
  m.def(
      "verify",
      [](const std::string& case_name, const std::string& mode, const std::string& law,
         const std::string& rng, PyInt seed_arg, PyInt collisions_arg, PyInt bits_arg,
         bool printed_reverse, std::vector<double> velocities, std::vector<double> normal) {
        const auto seed = to_int<std::uint64_t>(seed_arg, "seed");
        const auto collisions = to_int<std::uint64_t>(collisions_arg, "collisions");
        const int bits = to_int<int>(bits_arg, "bits");
        VerifyConfig c;
        c.case_name = case_name;
        c.mode = parse_mode(mode);
        c.law = parse_law(law);
        c.rng = rng;
        c.seed = seed;
        c.collisions = collisions;
        c.bits = bits;
        c.printed_reverse = printed_reverse;
        c.velocities = std::move(velocities);
        c.normal = std::move(normal);
        c.interrupt = released_signal_check();
        VerifyResult r;
        {
          py::gil_scoped_release release;
          r = verify(c);
        }
        py::dict d;
        d["case"] = c.case_name;
        d["mode"] = to_string(c.mode);
        d["law"] = to_string(c.law);
        d["rng"] = c.rng;
        d["seed"] = c.seed;
        d["bits"] = c.bits;
        d["printed_reverse"] = c.printed_reverse;
        d["passed"] = r.passed;
        d["bit_exact"] = r.bit_exact;
        d["max_rel_error"] = r.max_rel_error;
        d["collisions"] = r.collisions;
        d["forward_per_s"] = r.forward_per_s;
        d["reverse_per_s"] = r.reverse_per_s;
        d["forward_s"] = r.forward_s;
        d["reverse_s"] = r.reverse_s;
        d["log_bytes"] = r.log_bytes;
        d["log_entries"] = r.log_entries;
        d["random_numbers_drawn"] = r.random_numbers_drawn;
        d["random_numbers_undone"] = r.random_numbers_undone;
        d["rng_restored"] = r.rng_restored;
        d["error"] = r.error;
        d["initial"] = r.initial;
        d["final"] = r.final_velocities;
        d["reference"] = r.reference;
        return d;
      },
      py::kw_only(), py::arg("case") = "pair2d", py::arg("mode") = "exact", py::arg("law") = "flux",
      py::arg("rng") = "clcg4", py::arg("seed") = 0, py::arg("collisions") = 1000000,
      py::arg("bits") = 40, py::arg("printed_reverse") = false,
      py::arg("velocities") = std::vector<double>{}, py::arg("normal") = std::vector<double>{},
      "The paper's reversal illustration (see revcol.verify).");
  m.def("verify_cases", [](const std::string& mode) { return verify_cases(parse_mode(mode)); },
        py::arg("mode") = "exact", "Case names verify() knows for a mode.");
}

}  // namespace revcol::bind
