// Binding of the paper-mode measurements and tables: the reversal-failure study, the
// paper's cases, the high-precision arc reference and the calotte fractions. Dicts and
// numbers in and out, nothing else; the operators are paper.cpp.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstdint>
#include <string>

#include "args.hpp"
#include "bindings.hpp"
#include "revcol/collide/calotte.hpp"
#include "revcol/collide/ellipse_arc.hpp"
#include "revcol/studies/paper_study.hpp"

namespace py = pybind11;

namespace revcol::bind {
namespace {

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

}  // namespace

void register_paper_study(py::module_& m) {
  m.def(
      "paper_study",
      [](PyStr case_name, PyInt collisions, PyInt seed, PyStr pre, bool printed_reverse, PyReal cos_tol, PyStr arc,
         PyStr angle) {
        paper::StudyConfig c;
        c.case_name = to_str(case_name, "case");
        c.collisions = to_int<std::uint64_t>(collisions, "collisions");
        c.seed = to_int<std::uint64_t>(seed, "seed");
        c.pre = to_str(pre, "pre");
        c.printed_reverse = printed_reverse;
        c.cos_tol = to_real(cos_tol, "cos_tol");
        c.arc = paper::parse_arc_method(to_str(arc, "arc"));
        c.angle = paper::parse_arc_angle(to_str(angle, "angle"));
        c.interrupt = released_signal_check();
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
