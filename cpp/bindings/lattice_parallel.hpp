// Binding of the parallel lattice run (revcol/lattice/parallel_run.hpp): LatticeEngine's and
// LatticeEngine3D's run_parallel, the GIL released for the run (the worker threads never take
// it; the calling thread takes it back for the Ctrl-C poll at GVT), the report as a dict.
// Included by lattice.cpp (P: its PyLattice).
#pragma once
#include <pybind11/pybind11.h>

#include <limits>
#include <optional>
#include <string>

#include "args.hpp"
#include "revcol/error.hpp"
#include "revcol/lattice/parallel_run.hpp"

namespace revcol::bind {

/// The report of a parallel run: collisions by engine, the Time Warp counts, per-LP events.
inline pybind11::dict parallel_report_dict(const lattice::ParallelReport& r) {
  pybind11::dict d;
  const lattice::TimeWarpStats& s = r.stats;
  d["collisions"] = r.collisions;
  d["parallel_collisions"] = r.parallel;
  d["sequential_collisions"] = r.sequential;
  d["overshoot"] = r.overshoot;
  d["chunks"] = r.chunks;
  d["stopped"] = r.stopped;
  d["events"] = s.events;
  d["stale"] = s.stale;
  d["rollbacks"] = s.rollbacks;
  d["undone"] = s.undone;
  d["messages"] = s.messages;
  d["anti_messages"] = s.anti;
  d["confirmed"] = s.confirmed;
  d["written"] = s.written;
  d["blocked"] = s.blocked;
  d["reused"] = s.reused;
  d["gvts"] = s.gvts;
  d["gvt_s"] = s.gvt_seconds;  // seconds in the GVT step (worker 0 alone)
  d["journal_peak_bytes"] = s.journal_peak_bytes;  // the LPs' journals together, at their largest a GVT found
  d["journal_bytes_per_entry"] = s.journal_entries_at_gvts == 0 ? 0.0 : static_cast<double>(s.journal_bytes_at_gvts) / static_cast<double>(s.journal_entries_at_gvts);
  d["lp_events"] = s.lp_events;
  d["build_s"] = r.build_s;
  d["parallel_s"] = r.parallel_s;
  d["assemble_s"] = r.assemble_s;
  d["sequential_s"] = r.sequential_s;
  return d;
}

/// The parallel engine's configuration from run_parallel's keyword arguments (validated).
template <class Engine>
typename lattice::TimeWarp<Engine>::Config parallel_config(PyInt lps, PyInt workers, PyInt axis, const std::string& by, bool lazy, PyInt window,
                                                           PyInt gvt_every, PyInt batch, PyInt fuzz) {
  namespace la = revcol::lattice;
  typename la::TimeWarp<Engine>::Config c;
  c.lps = to_int<int>(lps, "lps", 1, 64);
  c.workers = to_int<int>(workers, "workers", 1, 64);
  require(c.workers <= c.lps, "workers must be at most lps (the logical processes), got workers=" +
                                  std::to_string(c.workers) + " > lps=" + std::to_string(c.lps));
  c.axis = to_int<int>(axis, "axis", 0, static_cast<int>(Engine::D) - 1);
  if (by == "save_all") c.how = la::Rollback::save_all;
  else if (by == "save_changes") c.how = la::Rollback::save_changes;
  else require(by == "reverse", "rollback must be 'reverse', 'save_all' (SS1) or 'save_changes' (SS2), not '" + by + "'");
  c.lazy = lazy;
  c.window = to_int<std::int64_t>(window, "window", 0);
  c.gvt_every = to_int<std::uint64_t>(gvt_every, "gvt_every", 1);
  c.batch = to_int<int>(batch, "batch", 1);
  c.fuzz = to_int<std::uint64_t>(fuzz, "fuzz", 0);
  require(c.workers == 1 || c.fuzz == 0, "fuzz (a random schedule) runs on one worker");
  return c;
}

/// One parallel run method on the binding's class: `name(a, b, lps, workers, ...)`, a and b its
/// two optional stops (a count and a tick), run(e, a, b, config, poll, small) the run.
template <class Engine, class P, class Cls, class Run>
void def_parallel_run(Cls& cls, const char* name, const char* a, const char* b, Run run, const char* doc) {
  namespace py = pybind11;
  cls.def(
      name,
      [run, a, b](P& p, std::optional<PyInt> a_arg, std::optional<PyInt> b_arg, PyInt lps, PyInt workers, PyInt axis, const std::string& by,
                  bool lazy, PyInt window, PyInt gvt_every, PyInt batch, PyInt fuzz, PyInt small) {
        const auto c = parallel_config<Engine>(lps, workers, axis, by, lazy, window, gvt_every, batch, fuzz);
        const auto t = to_int<std::uint64_t>(small, "small", 0);
        const auto x = to_int<std::uint64_t>(a_arg, a);
        const auto y = to_int<std::int64_t>(b_arg, b);
        const lattice::ParallelReport r = p.run_released([&](Engine& e, const auto& poll) { return run(e, x, y, c, poll, t); });
        if (PyErr_Occurred()) throw py::error_already_set();  // Ctrl-C: stopped at a whole tick
        return parallel_report_dict(r);
      },
      py::arg(a) = py::none(), py::arg(b) = py::none(), py::arg("lps") = 2, py::arg("workers") = 2, py::arg("axis") = 0,
      py::arg("rollback") = "reverse", py::arg("lazy") = true, py::arg("window") = 0, py::arg("gvt_every") = 512, py::arg("batch") = 64,
      py::arg("fuzz") = 0, py::arg("small") = 0, doc);
}

/// LatticeEngine(3D).run_parallel(collisions, until, lps, workers, ...) and
/// run_back_parallel(to_collisions, to_tick, ...) on the binding's class.
template <class Engine, class P, class Cls>
void def_parallel(Cls& cls) {
  namespace la = revcol::lattice;
  using Config = typename la::TimeWarp<Engine>::Config;
  def_parallel_run<Engine, P>(
      cls, "run_parallel", "collisions", "until",
      [](Engine& e, std::optional<std::uint64_t> n, std::optional<std::int64_t> until, const Config& c, const auto& poll, std::uint64_t t) {
        return la::run_parallel(e, n.value_or(std::numeric_limits<std::uint64_t>::max()), until.value_or(la::tick_limit - 1), c, poll, t);
      },
      "Forward on `lps` logical processes and `workers` threads (the parallel engine, Time Warp): the state "
      "run(collisions, until) reaches, bit for bit. Returns the run's report.");
  def_parallel_run<Engine, P>(
      cls, "run_back_parallel", "to_collisions", "to_tick",
      [](Engine& e, std::optional<std::uint64_t> n, std::optional<std::int64_t> tick, const Config& c, const auto& poll, std::uint64_t t) {
        return la::run_parallel_back(e, n.value_or(0), tick.value_or(e.origin()), c, poll, t);
      },
      "Back on `lps` logical processes and `workers` threads (the parallel engine in run_back's reversed frame; "
      "rollback by reverse computation whatever `rollback` says): the state run_back(to_collisions, to_tick) "
      "reaches, bit for bit. Returns the run's report.");
}

}  // namespace revcol::bind
