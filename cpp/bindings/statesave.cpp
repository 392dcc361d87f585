// Binding of the state-saving study (revcol/studies/statesave.hpp): keyword arguments in, a dict
// out, snapshots as (N, 4) float64 arrays (x, y, vx, vy). Type conversion only.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstdint>
#include <string>

#include "args.hpp"
#include "bindings.hpp"
#include "revcol/error.hpp"
#include "revcol/studies/statesave.hpp"

namespace py = pybind11;

namespace revcol::bind {
namespace {

namespace ss = revcol::statesave;

// Every argument converted where its name is known (args.hpp): a wrong type or range names it.
ss::Config config_from(const PyInt& particles, const PyInt& collisions, const PyStr& variant,
                       const PyStr& transport, const PyStr& mode, const PyStr& law, const PyInt& bits,
                       const PyStr& rng, const PyInt& seed, const PyReal& mean_dt, const PyReal& grazing_tol,
                       const PyInt& budget_bytes, bool prefault, bool capture) {
  ss::Config c;
  c.particles = to_int<std::uint64_t>(particles, "particles");
  c.collisions = to_int<std::uint64_t>(collisions, "collisions");
  c.variant = ss::parse_variant(to_str(variant, "variant"));
  c.transport = ss::parse_transport(to_str(transport, "transport"));
  c.mode = parse_mode(to_str(mode, "mode"));
  c.law = parse_law(to_str(law, "law"));
  c.bits = to_int<int>(bits, "bits");
  c.rng = to_str(rng, "rng");
  c.seed = to_int<std::uint64_t>(seed, "seed");
  c.mean_dt = to_real(mean_dt, "mean_dt");
  c.grazing_tol = to_real(grazing_tol, "grazing_tol");
  c.budget_bytes = to_int<std::uint64_t>(budget_bytes, "budget_bytes");
  c.prefault = prefault;
  c.capture = capture;
  return c;
}

py::array_t<double> snapshot_array(const ss::Snapshot& s) {
  const auto n = static_cast<py::ssize_t>(s.x.size());
  py::array_t<double> out({n, py::ssize_t{4}});
  double* p = out.mutable_data();
  for (py::ssize_t k = 0; k < n; ++k) {
    *p++ = s.x[k];
    *p++ = s.y[k];
    *p++ = s.vx[k];
    *p++ = s.vy[k];
  }
  return out;
}

#define REVCOL_STATESAVE_ARGS                                                                       \
  py::kw_only(), py::arg("particles") = 1000, py::arg("collisions") = 1000, py::arg("variant") = "rc", \
      py::arg("transport") = "eager", py::arg("mode") = "exact", py::arg("law") = "flux",            \
      py::arg("bits") = 40, py::arg("rng") = "clcg4", py::arg("seed") = 0, py::arg("mean_dt") = 1e-5, \
      py::arg("grazing_tol") = 1e-11, py::arg("budget_bytes") = static_cast<std::int64_t>(ss::default_budget_bytes), \
      py::arg("prefault") = true, py::arg("capture") = false

}  // namespace

void register_statesave(py::module_& m) {
  m.def(
      "statesave_run",
      [](PyInt particles, PyInt collisions, PyStr variant, PyStr transport, PyStr mode, PyStr law, PyInt bits,
         PyStr rng, PyInt seed, PyReal mean_dt, PyReal grazing_tol, PyInt budget_bytes, bool prefault, bool capture) {
        ss::Config c = config_from(particles, collisions, variant, transport, mode, law, bits, rng, seed,
                                   mean_dt, grazing_tol, budget_bytes, prefault, capture);
        c.interrupt = released_signal_check();
        ss::Result r;
        {
          py::gil_scoped_release release;
          r = ss::run(c);
        }
        py::dict d;
        d["particles"] = c.particles;
        d["collisions"] = c.collisions;
        d["variant"] = ss::to_string(c.variant);
        d["transport"] = ss::to_string(c.transport);
        d["mode"] = to_string(c.mode);
        d["law"] = to_string(c.law);
        d["bits"] = c.bits;
        d["rng"] = c.rng;
        d["seed"] = c.seed;
        d["mean_dt"] = c.mean_dt;
        d["grazing_tol"] = c.grazing_tol;
        d["budget_bytes"] = c.budget_bytes;
        d["prefault"] = c.prefault;
        d["skipped"] = r.skipped;
        d["projected_bytes"] = r.projected_bytes;
        d["record_bytes"] = r.record_bytes;
        d["bytes_saved"] = r.bytes_saved;
        d["state_bytes"] = r.state_bytes;
        d["forward_s"] = r.forward_s;
        d["rollback_s"] = r.rollback_s;
        d["rss_before_bytes"] = r.rss_before_bytes;
        d["peak_rss_bytes"] = r.peak_rss_bytes;
        d["rare_log_entries"] = r.rare_log_entries;
        d["decision_log_entries"] = r.decision_log_entries;
        d["pre_log_entries"] = r.pre_log_entries;
        d["log_bytes"] = r.log_bytes;
        d["grazes"] = r.grazes;
        d["draws"] = r.draws;
        d["draws_undone"] = r.draws_undone;
        d["rng_restored"] = r.rng_restored;
        d["clock_restored"] = r.clock_restored;
        d["bit_exact"] = r.bit_exact;
        d["max_rel_error_x"] = r.max_rel_error_x;
        d["max_rel_error_v"] = r.max_rel_error_v;
        d["max_rel_error"] = r.max_rel_error;
        d["restored"] = r.restored;
        d["error"] = r.error;
        if (c.capture && !r.skipped) {
          d["start"] = snapshot_array(r.start);
          d["turn"] = snapshot_array(r.turn);
          d["end"] = snapshot_array(r.end);
          d["turn_ticks"] = r.turn.ticks;
        }
        return d;
      },
      REVCOL_STATESAVE_ARGS, "One run of the state-saving study (see revcol.statesave.run).");
  m.def(
      "statesave_projected_bytes",
      [](PyInt particles, PyInt collisions, PyStr variant, PyStr transport, PyStr mode, PyStr law, PyInt bits,
         PyStr rng, PyInt seed, PyReal mean_dt, PyReal grazing_tol, PyInt budget_bytes, bool prefault, bool capture) {
        const ss::Config c = config_from(particles, collisions, variant, transport, mode, law, bits, rng, seed,
                                         mean_dt, grazing_tol, budget_bytes, prefault, capture);
        py::dict d;
        d["projected_bytes"] = ss::projected_bytes(c);
        d["record_bytes"] = ss::record_bytes(c);
        d["over_budget"] = ss::over_budget(c);
        return d;
      },
      REVCOL_STATESAVE_ARGS, "Saved bytes a run needs (validates the configuration).");
  m.def(
      "statesave_variants",
      [](const std::string& transport) { return ss::variant_names(ss::parse_transport(transport)); },
      py::arg("transport") = "eager", "The variants a transport supports, in report order.");
}

}  // namespace revcol::bind

#undef REVCOL_STATESAVE_ARGS
