// Binding of the lattice engine, 2D (LatticeEngine) and 3D (LatticeEngine3D, issue 14): numpy
// int64 arrays in and out, dicts for starts, diagnostics and checkpoints. No physics here
// (revcol/lattice/engine.hpp). Every conversion is one template on the dimension D; the 2D
// names, arguments, messages and checkpoint keys are as they were, and a 3D checkpoint carries
// the same keys with (n, 3) arrays, three-entry L and wall, six momentum0 words, and dim = 3.
//
// Threads (issue 19): run and run_back release the GIL for the event loop and take it back for
// the Ctrl-C poll only; while a run is under way, a call on the same engine from another thread
// raises RuntimeError instead of racing with the loop (PyLattice::engine()).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <type_traits>

#include "args.hpp"
#include "bindings.hpp"
#include "lattice_parallel.hpp"
#include "lattice_state.hpp"
#include "observe.hpp"
#include "revcol/error.hpp"
#include "revcol/lattice/engine.hpp"

namespace py = pybind11;

namespace revcol::bind {
namespace {

/// The engine, guarded against calls from other threads while a run is under way.
template <class Engine>
struct PyLattice {
  Engine e;
  std::optional<std::thread::id> runner{};  ///< the thread whose run/run_back is under way (GIL held to touch)
  std::vector<std::array<std::int64_t, 3>> trace{};  ///< set_trace(True): the forward collisions (tick, i, j) since take_trace

  /// The engine; a RuntimeError when a run is under way (its loop runs without the GIL).
  Engine& engine() {
    if (runner) throw std::runtime_error("this LatticeSimulation is running in another thread: wait for its run to return");
    return e;
  }
  /// As engine(), read-only.
  const Engine& engine() const { return const_cast<PyLattice*>(this)->engine(); }

  /// f(engine) with the GIL released, the Ctrl-C poll taking it back; others' calls raise meanwhile.
  template <class F>
  auto run_released(F&& f) {
    Engine& eng = engine();
    runner = std::this_thread::get_id();
    struct Clear {
      std::optional<std::thread::id>& r;
      ~Clear() { r.reset(); }
    } clear{runner};
    const auto poll = [] {
      py::gil_scoped_acquire gil;
      return poll_signals();
    };
    py::gil_scoped_release nogil;
    return f(eng, poll);
  }
};

// one boundary name, or one per axis (engine::parse_boundary, the one parser), into a config
template <std::size_t D>
void set_boundaries(la::LatticeConfigN<D>& c, const std::vector<std::string>& boundary) {
  require(boundary.size() == 1 || boundary.size() == D,
          D == 2 ? "boundary must be one name or 2, one per axis (2D)" : "boundary must be one name or 3, one per axis (3D)");
  for (std::size_t k = 0; k < D; ++k) {
    const engine::Boundary b = engine::parse_boundary(boundary.size() == 1 ? boundary[0] : boundary[k]);
    c.wall[k] = engine::has_walls(b);
    c.bounce[k] = b == engine::Boundary::bounce;
  }
}

// a uniform field's acceleration per axis (empty: none)
template <std::size_t D>
void set_gravity(la::LatticeConfigN<D>& c, const std::vector<double>& g) {
  if (g.empty()) return;
  require(g.size() == D, D == 2 ? "lattice: gravity needs two components (2D)" : "lattice: gravity needs three components (3D)");
  for (std::size_t k = 0; k < D; ++k) c.gravity[k] = g[k];
}

// lattice_random_start (2D) and lattice3d_random_start
template <std::size_t D>
py::dict random_start_d(PyInt n_arg, PyReal phi_arg, std::vector<std::string> boundary, PyReal diameter_arg, PyInt seed_arg,
                        const std::string& init, PyInt tick_bits_arg, PyInt cell_bits_arg, std::vector<double> diameters,
                        std::vector<double> gravity, PyReal shear_rate_arg) {
  const auto n = to_int<std::size_t>(n_arg, "n");
  const double phi = to_real(phi_arg, "phi"), diameter = to_real(diameter_arg, "diameter");
  const auto seed = to_int<std::uint64_t>(seed_arg, "seed", 0, 0xFFFFFFFFull);
  const int tick_bits = to_int<int>(tick_bits_arg, "tick_bits");
  la::LatticeConfigN<D> c;
  set_boundaries(c, boundary);
  c.diameter = diameter;
  c.seed = static_cast<std::uint32_t>(seed);
  c.tick_bits = tick_bits;
  c.cell_bits = to_int<int>(cell_bits_arg, "cell_bits");
  c.diameters = std::move(diameters);
  set_gravity(c, gravity);
  c.shear_rate = to_real(shear_rate_arg, "shear_rate");
  return start_dict(la::random_start(c, n, phi, seed, init, held_signal_check()));
}

// lattice_quantize (2D) and lattice3d_quantize
template <std::size_t D>
py::dict quantize_d(const FArray& x, const FArray& v, std::vector<double> box, std::vector<std::string> boundary, PyReal diameter_arg,
                    PyInt tick_bits_arg, PyInt cell_bits_arg, std::vector<double> diameters, std::vector<double> gravity,
                    PyReal shear_rate_arg) {
  const double diameter = to_real(diameter_arg, "diameter");
  const int tick_bits = to_int<int>(tick_bits_arg, "tick_bits");
  require(box.size() == D, D == 2 ? "lattice: box needs two lengths (2D)" : "lattice: box needs three lengths (3D)");
  const auto nd = static_cast<py::ssize_t>(D);
  require(x.ndim() == 2 && x.shape(1) == nd && v.ndim() == 2 && v.shape(1) == nd,
          D == 2 ? "lattice: positions and velocities must be (n, 2)" : "lattice: positions and velocities must be (n, 3)");
  la::LatticeConfigN<D> c;
  for (std::size_t k = 0; k < D; ++k) c.box[k] = box[k];
  set_boundaries(c, boundary);
  c.diameter = diameter;
  c.tick_bits = tick_bits;
  c.cell_bits = to_int<int>(cell_bits_arg, "cell_bits");
  c.diameters = std::move(diameters);
  set_gravity(c, gravity);
  c.shear_rate = to_real(shear_rate_arg, "shear_rate");
  return start_dict(la::quantize_start(c, std::vector<double>(x.data(), x.data() + x.size()),
                                       std::vector<double>(v.data(), v.data() + v.size())));
}

// the engine class LatticeEngine (2D) or LatticeEngine3D
template <class Engine>
void register_engine(py::module_& m, const char* name, const char* doc) {
  constexpr std::size_t D = Engine::D;
  using P = PyLattice<Engine>;
  py::class_<P> cls(m, name, doc);
  // observation: the float engine's observer (revcol/engine/observe.hpp)
  def_observe(cls, [](P& p) -> Engine& { return p.engine(); });
  def_parallel<Engine, P>(cls);
  cls
      .def(py::init([](const py::dict& units, const IArray& x, const IArray& v, PyInt seed_arg, const std::string& law,
                       PyInt clock_arg, const std::string& mode, const std::optional<IArray>& radius) {
             const auto seed = to_int<std::uint64_t>(seed_arg, "seed", 0, 0xFFFFFFFFull);
             const auto clock = to_int<std::int64_t>(clock_arg, "clock");
             const la::UnitsN<D> u = units_from<D>(units);
             const revcol::Law lw = parse_law(law);
             const revcol::Mode md = parse_lattice_mode(mode);
             if (!radius || radius->size() == 0)  // one diameter
               return P{Engine(u, vecs<D>(x, "x"), vecs<D>(v, "v"), static_cast<std::uint32_t>(seed), la::operator_for(u, lw), clock, md)};
             return P{Engine(u, vecs<D>(x, "x"), vecs<D>(v, "v"), std::vector<std::int64_t>(radius->data(), radius->data() + radius->size()),
                             static_cast<std::uint32_t>(seed), la::operator_for(u, lw), clock, md)};
           }),
           py::arg("units"), py::arg("x"), py::arg("v"), py::arg("seed"), py::arg("law"), py::arg("clock") = 0,
           py::arg("mode") = "exact", py::arg("radius") = py::none())
      .def_static(
          "from_snapshot",
          [](const py::dict& d) {
            const la::SnapshotN<D> s = snapshot_from<D>(d);
            return P{Engine(s, la::operator_for(s.units, s.law))};
          },
          py::arg("snapshot"), "Rebuilds an engine from snapshot(); it resumes bit for bit.")
      .def(
          "run",
          [](P& p, std::optional<PyInt> collisions_arg, std::optional<PyInt> until_arg) {
            const auto collisions = to_int<std::uint64_t>(collisions_arg, "collisions");
            const auto until = to_int<std::int64_t>(until_arg, "until");
            const std::uint64_t done = p.run_released([&](Engine& e, const auto& poll) {
              return e.run(collisions.value_or(std::numeric_limits<std::uint64_t>::max()),
                           until.value_or(la::tick_limit - 1), poll);
            });
            if (PyErr_Occurred()) throw py::error_already_set();  // Ctrl-C: stopped at a valid tick
            return done;
          },
          py::arg("collisions") = py::none(), py::arg("until") = py::none(),
          "Forward: until that many more collisions or the tick `until`; returns the collisions done.")
      .def(
          "set_trace",
          [](P& p, bool on) {
            Engine& e = p.engine();
            e.trace = on ? &p.trace : nullptr;
            if (!on) std::vector<std::array<std::int64_t, 3>>().swap(p.trace);
          },
          py::arg("on"),
          "Keeps (True) or stops keeping (False, freeing it) every forward collision of the sequential engine as "
          "(tick, i, j), i < j particle ids, until take_trace (a parallel run's collisions are not kept).")
      .def(
          "take_trace",
          [](P& p) {
            (void)p.engine();
            py::array_t<std::int64_t> a({static_cast<py::ssize_t>(p.trace.size()), py::ssize_t{3}});
            std::int64_t* out = a.mutable_data();
            for (const auto& t : p.trace) out = std::copy(t.begin(), t.end(), out);
            p.trace.clear();
            return a;
          },
          "The collisions kept since set_trace(True) or the last take_trace, (k, 3) int64 (tick, i, j); clears them.")
      .def(
          "run_back",
          [](P& p, std::optional<PyInt> to_collisions_arg, std::optional<PyInt> to_tick_arg) {
            const auto to_collisions = to_int<std::uint64_t>(to_collisions_arg, "to_collisions");
            const auto to_tick = to_int<std::int64_t>(to_tick_arg, "to_tick");
            const std::int64_t origin = p.engine().origin();
            p.run_released([&](Engine& e, const auto& poll) {
              e.run_back(to_collisions.value_or(0), to_tick.value_or(origin), poll);
              return 0;
            });
            if (PyErr_Occurred()) throw py::error_already_set();
          },
          py::arg("to_collisions") = py::none(), py::arg("to_tick") = py::none(),
          "Back to collision count `to_collisions` or tick `to_tick` (default: the start).")
      // ---- the processed-event journal (BasicEngine::keep_journal, rollback.hpp) ----
      .def(
          "keep_journal",
          [](P& p, bool on, const std::string& by) {
            la::Rollback how = la::Rollback::reverse;
            if (by == "save_all") how = la::Rollback::save_all;
            else if (by == "save_changes") how = la::Rollback::save_changes;
            else require(by == "reverse", "rollback by must be 'reverse', 'save_all' (SS1) or 'save_changes' (SS2), not '" + by + "'");
            p.engine().keep_journal(on, how);
          },
          py::arg("on"), py::arg("by") = "reverse",
          "Keeps (or stops keeping) the journal of processed events from the state on: rollback undoes them, by "
          "reverse computation or (the comparison) by state saving.")
      .def_property_readonly("journal_bytes", [](const P& p) { return p.engine().journal_bytes(); })
      .def_property_readonly("journaling", [](const P& p) { return p.engine().journaling(); })
      .def_property_readonly("journal_start", [](const P& p) { return p.engine().journal_start(); },
                             "The collision count at the journal's start (the earliest state rollback reaches).")
      .def_property_readonly("journal_start_tick", [](const P& p) { return p.engine().journal_start_tick(); })
      .def_property_readonly("journal_size", [](const P& p) { return p.engine().journal_size(); })
      .def(
          "rollback",
          [](P& p, std::optional<PyInt> to_collisions_arg, std::optional<PyInt> to_tick_arg) {
            const auto to_collisions = to_int<std::uint64_t>(to_collisions_arg, "to_collisions");
            const auto to_tick = to_int<std::int64_t>(to_tick_arg, "to_tick");
            require(to_collisions.has_value() != to_tick.has_value(), "rollback needs one of to_collisions= and to_tick=");
            if (to_collisions) p.engine().rollback(*to_collisions);
            else p.engine().rollback_to_tick(*to_tick);
          },
          py::arg("to_collisions") = py::none(), py::arg("to_tick") = py::none(),
          "Undoes the journal's latest events: back to right after collision `to_collisions`, or to tick `to_tick`.")
      .def(
          "commit", [](P& p, PyInt collisions) { p.engine().commit(to_int<std::uint64_t>(collisions, "collisions")); },
          py::arg("collisions"), "Forgets the journal up to that collision count (rollback goes no further back).")
      .def("snapshot", [](const P& p) { return snapshot_dict(p.engine().snapshot()); })
      .def_property_readonly("positions", [](const P& p) { return vec_array(p.engine().positions()); })
      .def_property_readonly("velocities", [](const P& p) { return vec_array(p.engine().velocities()); })
      .def_property_readonly("clock", [](const P& p) { return p.engine().clock(); })
      .def_property_readonly("origin", [](const P& p) { return p.engine().origin(); })
      .def_property_readonly("collisions", [](const P& p) { return p.engine().collisions(); })
      .def_property_readonly("units", [](const P& p) { return units_dict(p.engine().units()); })
      .def_property_readonly("n", [](const P& p) { return p.engine().size(); })
      .def_property_readonly("radius", [](const P& p) {
        const auto r = p.engine().radii();
        return flat_array(r.data(), r.size());
      }, "A mixture's radii in lattice units, by particle id (empty: one diameter, units['sigma']).")
      .def_property_readonly("law", [](const P& p) { return std::string(to_string(p.engine().law())); })
      .def_property_readonly("mode", [](const P& p) { return std::string(to_string(p.engine().mode())); })
      // ---- the neighbour search (BasicEngine::set_list_shell): never changes which collisions happen ----
      .def(
          "set_search", [](P& p, PyReal shell) { p.engine().set_list_shell(to_real(shell, "shell")); }, py::arg("shell"),
          "The neighbour search: shell 0 the cell grid, in [0.02, 2] neighbour lists with that shell in diameters, "
          "< 0 automatic (lists in 3D, cells in 2D). The state, trace and bits are the same whichever.")
      .def_property_readonly("list_shell", [](const P& p) { return p.engine().list_shell(); },
                             "The shell in use, in diameters (0: the cell grid).")
      .def_property_readonly("neighbour_search", [](const P& p) { return p.engine().neighbour_search(); },
                             "The search in use: 0 the cell grid, 1 lists (each pair's relative vector imaged), "
                             "2 lists with the centre offsets.")
      .def("diagnostics", [](const P& p) {
        const la::DiagnosticsN<D> g = la::diagnostics(p.engine());
        py::dict d = counters_dict(p.engine().counters());
        d["energy_drift"] = g.energy_drift;
        d["energy_drift_units"] = g.energy_drift_units;
        d["momentum_drift"] = tuple_of(g.momentum_drift);
        d["bits_length"] = g.bits_length;
        d["log_entries"] = g.log_entries;
        d["group_log_entries"] = p.engine().group_log_size();
        d["collisions"] = g.collisions;
        d["clock"] = g.clock;
        d["time"] = g.time;
        d["memory_bytes"] = g.memory_bytes;
        return d;
      });
}

}  // namespace

void register_lattice(py::module_& m) {
  m.def("lattice_random_start", &random_start_d<2>, py::arg("n"), py::arg("phi"), py::arg("boundary"), py::arg("diameter"),
        py::arg("seed"), py::arg("init"), py::arg("tick_bits") = la::default_tick_bits, py::arg("cell_bits") = la::default_cell_bits,
        py::arg("diameters") = std::vector<double>{}, py::arg("gravity") = std::vector<double>{}, py::arg("shear_rate") = 0.0,
        "A random 2D start as engine_random_state, quantized once: {units, x, v, errors}.");
  m.def("lattice3d_random_start", &random_start_d<3>, py::arg("n"), py::arg("phi"), py::arg("boundary"), py::arg("diameter"),
        py::arg("seed"), py::arg("init"), py::arg("tick_bits") = la::default_tick_bits, py::arg("cell_bits") = la::default_cell_bits,
        py::arg("diameters") = std::vector<double>{}, py::arg("gravity") = std::vector<double>{}, py::arg("shear_rate") = 0.0,
        "A random 3D start (spheres) as engine_random_state, quantized once: {units, x, v, errors}.");
  m.def("lattice_quantize", &quantize_d<2>, py::arg("x"), py::arg("v"), py::arg("box"), py::arg("boundary"), py::arg("diameter"),
        py::arg("tick_bits") = la::default_tick_bits, py::arg("cell_bits") = la::default_cell_bits,
        py::arg("diameters") = std::vector<double>{}, py::arg("gravity") = std::vector<double>{}, py::arg("shear_rate") = 0.0,
        "Units from the box and rms speed, and one quantization: {units, x, v, errors}.");
  m.def("lattice3d_quantize", &quantize_d<3>, py::arg("x"), py::arg("v"), py::arg("box"), py::arg("boundary"), py::arg("diameter"),
        py::arg("tick_bits") = la::default_tick_bits, py::arg("cell_bits") = la::default_cell_bits,
        py::arg("diameters") = std::vector<double>{}, py::arg("gravity") = std::vector<double>{}, py::arg("shear_rate") = 0.0,
        "3D units from the box and rms speed, and one quantization of (n, 3) arrays: {units, x, v, errors}.");
  m.def(
      "lattice_initial_bits",
      [](PyInt n_arg, PyInt seed_arg) {
        const auto n = to_int<std::uint64_t>(n_arg, "n", 0, 0x7FFFFFFFull);
        const auto seed = to_int<std::uint64_t>(seed_arg, "seed", 0, 0xFFFFFFFFull);
        std::vector<std::uint64_t> bits, size;
        for (std::uint64_t p = 0; p < n; ++p) {
          const auto w = la::initial_bits(static_cast<std::uint32_t>(p), static_cast<std::uint32_t>(seed));
          bits.insert(bits.end(), w.begin(), w.end());
          size.push_back(w.size());
        }
        py::dict d;
        put(d, "bits", bits);
        put(d, "bits_size", size);
        return d;
      },
      py::arg("n"), py::arg("seed"),
      "The n particles' initial bits-back integers for a seed, as a checkpoint holds them: {bits, bits_size}.");
  register_engine<la::LatticeEngine>(m, "LatticeEngine", "The 2D lattice engine (revcol/lattice/engine.hpp).");
  register_engine<la::LatticeEngine3D>(m, "LatticeEngine3D", "The 3D lattice engine, spheres (revcol/lattice/engine.hpp).");
}

}  // namespace revcol::bind
