// Binding of the event-driven engine: numpy in and out, dicts for results, diagnostics and
// checkpoints. No physics here (revcol/engine/engine.hpp).
//
// Threads (issue 19): run and run_back release the GIL for the event loop, so other Python
// threads go on while the engine works; the progress callback and the Ctrl-C poll take the GIL
// back while they call Python (RunGuard below). While a run is under way, a call on the same
// engine from another thread raises RuntimeError instead of racing with the loop; the run's own
// progress callback (same thread, between events) may read the state as before.
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstring>
#include <limits>
#include <type_traits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <thread>

#include "bindings.hpp"
#include "args.hpp"
#include "observe.hpp"
#include "revcol/engine/engine.hpp"
#include "revcol/engine/init.hpp"
#include "revcol/engine/limits.hpp"
#include "revcol/error.hpp"

namespace py = pybind11;

namespace revcol::bind {
namespace {

namespace en = revcol::engine;
using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;

std::vector<double> flat(const Array& a, const char* what, int& n, int& d) {
  require(a.ndim() == 2, [&] { return std::string(what) + " must be a 2-d array (n, dim), got " + std::to_string(a.ndim()) + " dimensions"; });
  n = static_cast<int>(a.shape(0));
  d = static_cast<int>(a.shape(1));
  return std::vector<double>(a.data(), a.data() + a.size());
}

py::array_t<double> to_array(const std::vector<double>& v, std::size_t n, int d) {
  py::array_t<double> out({static_cast<py::ssize_t>(n), static_cast<py::ssize_t>(d)});
  std::memcpy(out.mutable_data(), v.data(), v.size() * sizeof(double));
  return out;
}

template <class T>
py::array_t<T> vec_array(const std::vector<T>& v) {
  py::array_t<T> out(static_cast<py::ssize_t>(v.size()));
  if (!v.empty()) std::memcpy(out.mutable_data(), v.data(), v.size() * sizeof(T));
  return out;
}

template <class T>
std::vector<T> array_vec(const py::dict& d, const char* key) {
  require(d.contains(key), [&] { return std::string("checkpoint is missing '") + key + "'"; });
  return checkpoint_array<T>(d[key], key);
}

en::Config make_config(int dim, const std::vector<double>& box, const std::vector<std::string>& boundary,
                       double diameter, const std::string& mode, const std::string& law, std::uint64_t seed,
                       int bits, bool groups, double group_tol, const std::string& generator,
                       const std::string& streams) {
  en::Config c;
  c.dim = dim;
  require(dim >= 1 && dim <= 3, [&] { return "dim must be 1, 2 or 3, got " + std::to_string(dim); });
  require(static_cast<int>(box.size()) == dim, [&] {
    return "box must have one length per axis (" + std::to_string(dim) + "), got " + std::to_string(box.size());
  });
  require(boundary.size() == 1 || static_cast<int>(boundary.size()) == dim,
          "boundary must be one name or one per axis");
  for (int k = 0; k < dim; ++k) {
    c.box[k] = box[k];
    c.boundary[k] = en::parse_boundary(boundary.size() == 1 ? boundary[0] : boundary[k]);
  }
  c.diameter = diameter;
  c.mode = en::parse_engine_mode(mode);
  c.law = parse_law(law);
  require(seed <= 0xFFFFFFFFull, "seed must be < 2^32");
  c.seed = static_cast<std::uint32_t>(seed);
  c.generator = en::parse_generator(generator);
  c.streams = en::parse_engine_streams(streams);
  c.bits = bits;
  c.groups = groups;
  c.group_tol = group_tol;
  return c;
}

py::dict counters_dict(const en::Counters& c) {
  py::dict d;
  c.visit([&](const char* name, std::uint64_t q) { d[name] = q; });
  return d;
}

template <class T>
struct is_vector : std::false_type {};
template <class T>
struct is_vector<std::vector<T>> : std::true_type {};

py::dict run_dict(const en::RunResult& r) {
  py::dict d;
  d["collisions"] = r.collisions;
  d["events"] = r.events;
  d["time"] = r.time;
  d["interrupted"] = r.interrupted;
  d["diverged"] = r.diverged;
  return d;
}

/// The Ctrl-C poll of a loop that runs with the GIL released: takes the GIL for the check.
bool poll_signals_released() {
  py::gil_scoped_acquire gil;
  return poll_signals();
}

class PyEngine {
 public:
  explicit PyEngine(std::unique_ptr<en::Simulation> s) : s_(std::move(s)) {}

  /// Marks the engine as running on this thread for its lifetime (set and cleared with the GIL
  /// held, so a plain member is race-free): another thread's call then raises, see sim().
  class RunGuard {
   public:
    explicit RunGuard(PyEngine& e) : e_(e) {
      e_.sim();  // raises if another thread is running it
      // a run started from its own progress callback would re-enter the event loop mid-event
      if (e_.runner_) throw std::runtime_error("run/run_back called from inside this Simulation's own run");
      e_.runner_ = std::this_thread::get_id();
    }
    ~RunGuard() { e_.runner_.reset(); }
    RunGuard(const RunGuard&) = delete;
    RunGuard& operator=(const RunGuard&) = delete;

   private:
    PyEngine& e_;
  };

  py::dict run(std::optional<PyInt> collisions_arg, std::optional<PyReal> time_arg,
               std::optional<std::function<bool(std::uint64_t)>> cb, PyInt every_arg) {
    const auto collisions = to_int<std::uint64_t>(collisions_arg, "collisions");
    const auto every = to_int<std::uint64_t>(every_arg, "every", 1);
    const auto time = to_real(time_arg, "time");
    require(collisions.has_value() || time.has_value(), "give collisions, time, or both");
    const std::uint64_t nc = collisions.value_or(std::numeric_limits<std::uint64_t>::max());
    const double te = time.value_or(std::numeric_limits<double>::infinity());
    require(!time || *time >= sim().time(), "run: end time is earlier than the current time (use run_back)");
    en::Progress p;
    if (cb) {
      p = [&cb](std::uint64_t done) {  // Python code: with the GIL
        py::gil_scoped_acquire gil;
        return (*cb)(done);
      };
    }
    const RunGuard busy(*this);
    en::RunResult r;
    {
      py::gil_scoped_release nogil;
      r = s_->run(nc, te, p, cb ? every : 0, poll_signals_released);
    }
    if (PyErr_Occurred()) throw py::error_already_set();  // Ctrl-C: the run stopped between events
    return run_dict(r);
  }
  py::dict run_back(std::optional<PyInt> collisions_arg, std::optional<PyReal> time_arg, bool stop_on_divergence) {
    const auto collisions = to_int<std::uint64_t>(collisions_arg, "collisions");
    const auto time = to_real(time_arg, "time");
    const std::uint64_t nc = collisions.value_or(std::numeric_limits<std::uint64_t>::max());
    // collisions alone: never past the start (the reversed dynamics goes on forever before it);
    // pass a time to go earlier
    const double tt = time.value_or(sim().start_time());
    require(!time || std::isfinite(*time), "run_back: time must be finite");
    const RunGuard busy(*this);
    en::RunResult r;
    {
      py::gil_scoped_release nogil;
      r = s_->run_back(nc, tt, poll_signals_released, stop_on_divergence);
    }
    if (PyErr_Occurred()) throw py::error_already_set();
    return run_dict(r);
  }
  py::array_t<double> positions() const { return to_array(sim().positions(), sim().size(), sim().config().dim); }
  py::array_t<double> velocities() const { return to_array(sim().velocities(), sim().size(), sim().config().dim); }
  py::array_t<std::uint64_t> collision_counts() const { return vec_array(sim().collision_counts()); }

  py::dict diagnostics() const {
    const en::Diagnostics g = sim().diagnostics();
    py::dict d;
    d["energy"] = g.energy;
    d["potential"] = g.potential;
    d["momentum"] = std::vector<double>(g.momentum.begin(), g.momentum.begin() + sim().config().dim);
    d["energy_drift"] = g.energy_drift;
    d["momentum_drift"] = g.momentum_drift;
    d["log_bytes"] = g.log_bytes;
    d["log_pushed"] = g.log_pushed;
    d["exact_pre_pushed"] = g.exact_pre_pushed;
    d["exact_pre_entries"] = g.exact_pre_entries;
    d["wall_log_entries"] = g.wall_log_entries;
    d["collisions_per_particle"] = g.collisions_per_particle;
    d["net_collisions"] = g.net_collisions;
    // the collision trace (revcol/engine/trace.hpp): None where nothing was found yet
    const auto count = [](std::int64_t m) -> py::object {
      return m == en::CollisionTrace::kNever ? py::object(py::none()) : py::object(py::int_(m));
    };
    d["divergence"] = g.divergence == en::Divergence::none ? py::object(py::none())
                                                           : py::object(py::str(en::to_string(g.divergence)));
    d["diverged_at"] = count(g.diverged_at);
    d["verified_at"] = count(g.verified_at);
    d["trace_reorderings"] = g.trace_reorderings;
    d["trace_stride"] = g.trace_stride;
    d["trace_points"] = g.trace_points;
    d["clock_deviation"] = g.clock_deviation;
    d["storage_resorts"] = g.storage_resorts;
    d["memory_bytes"] = sim().memory_bytes();
    d["events"] = counters_dict(g.counters);
    return d;
  }

  py::dict snapshot() const {
    const en::Snapshot s = sim().snapshot();
    py::dict d;
    const en::Config& c = s.config;
    d["format"] = 1;
    d["dim"] = c.dim;
    d["box"] = vec_array(std::vector<double>(c.box.begin(), c.box.begin() + c.dim));
    std::vector<std::int64_t> bnd;
    // each axis's kind by its value (0 wall, 1 periodic, 2 bounce: engine/boundary_kind.hpp);
    // checkpoints written before this name held the same values as "periodic"
    for (int k = 0; k < c.dim; ++k) bnd.push_back(static_cast<std::int64_t>(c.boundary[k]));
    d["boundary"] = vec_array(bnd);
    d["diameter"] = c.diameter;
    if (!c.diameters.empty()) d["diameters"] = vec_array(c.diameters);  // a mixture
    if (!c.masses.empty()) d["masses"] = vec_array(c.masses);
    if (c.gravity != std::array<double, 3>{}) d["gravity"] = vec_array(std::vector<double>(c.gravity.begin(), c.gravity.begin() + c.dim));
    d["mode"] = std::string(to_string(c.mode));
    d["law"] = std::string(to_string(c.law));
    d["seed"] = c.seed;
    d["generator"] = std::string(en::to_string(c.generator));
    d["streams"] = std::string(rng::to_string(c.streams));
    d["bits"] = c.bits;
    d["groups"] = c.groups;
    d["group_tol"] = c.group_tol;
    s.visit([&](const char* key, const auto& field) {
      using T = std::decay_t<decltype(field)>;
      if constexpr (is_vector<T>::value) {
        // no observation running: no observer entries (the file reads as one written before them)
        if (field.empty() && (std::strcmp(key, "observer") == 0 || std::strcmp(key, "observer_counts") == 0)) return;
        d[key] = vec_array(field);
      } else {
        d[key] = field;
      }
    });
    std::vector<std::uint64_t> counters;
    s.counters.visit([&](const char*, std::uint64_t q) { counters.push_back(q); });
    d["counters"] = vec_array(counters);
    d["momentum0"] = vec_array(std::vector<double>(s.momentum0.begin(), s.momentum0.end()));
    return d;
  }

  static PyEngine from_snapshot(const py::dict& d) {
    auto get = [&](const char* key) {
      require(d.contains(key), [&] { return std::string("checkpoint is missing '") + key + "'"; });
      return d[key];
    };
    require(checkpoint_field<int>(get("format"), "format") == 1, "checkpoint format must be 1");
    en::Snapshot s;
    en::Config& c = s.config;
    c.dim = checkpoint_field<int>(get("dim"), "dim");
    require(c.dim >= 1 && c.dim <= 3, "checkpoint: dim must be 1, 2 or 3");
    const auto box = array_vec<double>(d, "box");
    require(d.contains("boundary") || d.contains("periodic"), "checkpoint is missing 'boundary'");
    const auto per = array_vec<std::int64_t>(d, d.contains("boundary") ? "boundary" : "periodic");
    require(static_cast<int>(box.size()) == c.dim && static_cast<int>(per.size()) == c.dim,
            "checkpoint: box and boundary need one entry per axis");
    for (int k = 0; k < c.dim; ++k) {
      c.box[k] = box[k];
      c.boundary[k] = en::boundary_from_value(per[k]);  // every kind of en::kBoundaries, by value
    }
    c.diameter = checkpoint_field<double>(get("diameter"), "diameter");
    if (d.contains("diameters")) c.diameters = array_vec<double>(d, "diameters");  // a mixture
    if (d.contains("masses")) c.masses = array_vec<double>(d, "masses");
    if (d.contains("gravity")) {
      const auto g = array_vec<double>(d, "gravity");
      require(static_cast<int>(g.size()) == c.dim, "checkpoint: gravity needs one component per axis");
      for (std::size_t k = 0; k < g.size(); ++k) c.gravity[k] = g[k];
    }
    c.mode = en::parse_engine_mode(checkpoint_field<std::string>(get("mode"), "mode"));
    c.law = parse_law(checkpoint_field<std::string>(get("law"), "law"));
    c.seed = checkpoint_field<std::uint32_t>(get("seed"), "seed");
    // absent in checkpoints written before the generator choice existed: Philox per particle
    c.generator = d.contains("generator") ? en::parse_generator(checkpoint_field<std::string>(d["generator"], "generator"))
                                          : en::Generator::philox;
    c.streams = d.contains("streams") ? en::parse_engine_streams(checkpoint_field<std::string>(d["streams"], "streams"))
                                      : rng::StreamPolicy::per_particle;
    c.bits = checkpoint_field<int>(get("bits"), "bits");
    c.groups = checkpoint_field<bool>(get("groups"), "groups");
    c.group_tol = checkpoint_field<double>(get("group_tol"), "group_tol");
    s.visit([&](const char* key, auto& field) {
      using T = std::decay_t<decltype(field)>;
      // absent in checkpoints written before the neighbour lists: centres from x, events predicted anew
      if (std::strcmp(key, "centre") == 0 && !d.contains(key)) return;
      // absent in checkpoints written before the collision trace: a new trace starts here
      if (std::strcmp(key, "trace") == 0 && !d.contains(key)) return;
      // absent in checkpoints written before snapshots kept observations: none resumes
      if ((std::strcmp(key, "observer") == 0 || std::strcmp(key, "observer_counts") == 0) && !d.contains(key)) return;
      if constexpr (is_vector<T>::value) field = array_vec<typename T::value_type>(d, key);
      else field = checkpoint_field<T>(get(key), key);
    });
    const auto k = array_vec<std::uint64_t>(d, "counters");
    std::size_t nk = 0;
    s.counters.visit([&](const char*, std::uint64_t) { ++nk; });
    require(k.size() == nk, "checkpoint: counters must have " + std::to_string(nk) + " entries");
    std::size_t u = 0;
    s.counters.visit([&](const char*, std::uint64_t& q) { q = k[u++]; });
    const auto p0 = array_vec<double>(d, "momentum0");
    require(p0.size() == 3, "checkpoint: momentum0 must have 3 entries");
    for (int k2 = 0; k2 < 3; ++k2) s.momentum0[k2] = p0[k2];
    return PyEngine(en::restore_simulation(s));
  }

  /// The engine; a RuntimeError when another thread is running it (its loop has no GIL).
  en::Simulation& sim() {
    check_runner();
    return *s_;
  }
  /// As sim(), read-only.
  const en::Simulation& sim() const {
    check_runner();
    return *s_;
  }

 private:
  void check_runner() const {
    if (runner_ && *runner_ != std::this_thread::get_id())
      throw std::runtime_error("this Simulation is running in another thread: wait for its run to return");
  }

  std::unique_ptr<en::Simulation> s_;
  std::optional<std::thread::id> runner_;  ///< the thread whose run/run_back is under way
};

}  // namespace

void register_engine(py::module_& m) {
  py::class_<PyEngine> engine_class(m, "Engine", "The event-driven engine (revcol/engine/engine.hpp); use revcol.Simulation.");
  engine_class
      .def(py::init([](const Array& x, const Array& v, const std::vector<double>& box,
                       const std::vector<std::string>& boundary, PyReal diameter_arg, PyStr mode_arg,
                       PyStr law_arg, PyInt seed_arg, PyInt bits_arg, bool groups, PyReal group_tol_arg,
                       PyReal time_arg, PyStr generator_arg, PyStr streams_arg, std::vector<double> diameters,
                       std::vector<double> masses, std::vector<double> gravity) {
             const std::string mode = to_str(mode_arg, "mode"), law = to_str(law_arg, "law");
             const std::string generator = to_str(generator_arg, "generator"), streams = to_str(streams_arg, "streams");
             const double diameter = to_real(diameter_arg, "diameter"), group_tol = to_real(group_tol_arg, "group_tol");
             const double time = to_real(time_arg, "time");
             const auto seed = to_int<std::uint64_t>(seed_arg, "seed", 0, en::limits::kMaxSeed);
             const auto bits = to_int<int>(bits_arg, "bits", en::limits::kMinBits, en::limits::kMaxBits);
             int n = 0, d = 0, nv = 0, dv = 0;
             auto xs = flat(x, "positions", n, d);
             auto vs = flat(v, "velocities", nv, dv);
             require(n == nv && d == dv, "positions and velocities must have the same shape");
             en::Config c = make_config(d, box, boundary, diameter, mode, law, seed, bits, groups, group_tol, generator,
                                       streams);
             c.diameters = std::move(diameters);  // a mixture (validated with the state)
             c.masses = std::move(masses);
             require(gravity.empty() || static_cast<int>(gravity.size()) == d, [&] {
               return "gravity must have one component per axis (" + std::to_string(d) + "), got " +
                      std::to_string(gravity.size());
             });
             for (std::size_t k = 0; k < gravity.size(); ++k) c.gravity[k] = gravity[k];
             return PyEngine(en::make_simulation(c, xs, vs, time));
           }),
           py::arg("positions"), py::arg("velocities"), py::arg("box"), py::arg("boundary"), py::arg("diameter"),
           py::arg("mode"), py::arg("law"), py::arg("seed"), py::arg("bits"), py::arg("groups"),
           py::arg("group_tol"), py::arg("time"), py::arg("generator") = "philox",
           py::arg("streams") = "per_particle", py::arg("diameters") = std::vector<double>{},
           py::arg("masses") = std::vector<double>{}, py::arg("gravity") = std::vector<double>{})
      .def_static("from_snapshot", &PyEngine::from_snapshot, py::arg("snapshot"))
      .def("run", &PyEngine::run, py::arg("collisions") = py::none(), py::arg("time") = py::none(),
           py::arg("callback") = py::none(), py::arg("every") = 10000)
      .def("run_back", &PyEngine::run_back, py::arg("collisions") = py::none(), py::arg("time") = py::none(),
           py::arg("stop_on_divergence") = false)
      .def_property_readonly("positions", &PyEngine::positions)
      .def_property_readonly("velocities", &PyEngine::velocities)
      .def_property_readonly("collision_counts", &PyEngine::collision_counts)
      .def_property_readonly("time", [](const PyEngine& e) { return e.sim().time(); })
      .def_property_readonly("start_time", [](const PyEngine& e) { return e.sim().start_time(); })
      .def_property_readonly("n", [](const PyEngine& e) { return e.sim().size(); })
      .def_property_readonly("diameter", [](const PyEngine& e) { return e.sim().config().diameter; })
      .def_property_readonly(
          "diameters", [](const PyEngine& e) { return e.sim().config().diameters; },
          "A mixture's diameters, one per particle (empty: one size, `diameter`).")
.def_property_readonly(
          "gravity",
          [](const PyEngine& e) {
            const auto& c = e.sim().config();
            return std::vector<double>(c.gravity.begin(), c.gravity.begin() + c.dim);
          },
          "The uniform field (acceleration), one component per axis.")
      .def_property_readonly(
          "masses", [](const PyEngine& e) { return e.sim().config().masses; },
          "The particles' masses, one per particle (empty: all 1).")
      .def_property_readonly("dim", [](const PyEngine& e) { return e.sim().config().dim; })
      .def_property_readonly("box",
                             [](const PyEngine& e) {
                               const auto& c = e.sim().config();
                               return std::vector<double>(c.box.begin(), c.box.begin() + c.dim);
                             })
      .def_property_readonly("boundary",
                             [](const PyEngine& e) {
                               const auto& c = e.sim().config();
                               std::vector<std::string> b;
                               for (int k = 0; k < c.dim; ++k) b.emplace_back(en::to_string(c.boundary[k]));
                               return b;
                             })
      .def_property_readonly("periodic",
                             [](const PyEngine& e) {
                               const auto& c = e.sim().config();
                               std::vector<bool> p;
                               for (int k = 0; k < c.dim; ++k) p.push_back(c.boundary[k] == en::Boundary::periodic);
                               return p;
                             })
      .def("diagnostics", &PyEngine::diagnostics)
      .def("snapshot", &PyEngine::snapshot)
      .def(
          "fault", [](const PyEngine& e) { return e.sim().fault(); },
          "The first way the state fails the event loop's invariants at the clock (particles overlap, one beyond its "
          "list's reach, a missed event), or ''; load refuses a snapshot with one, and save a state with one.");
  // ---- observation (observe.cpp, revcol/engine/observe.hpp) ----
  def_observe(engine_class, [](PyEngine& e) -> en::Simulation& { return e.sim(); });

  m.def(
      "engine_random_state",
      [](PyInt dim_arg, PyInt n_arg, PyReal phi_arg, const std::vector<std::string>& boundary, PyReal diameter_arg,
         PyInt seed_arg, PyReal energy_arg, PyStr init_arg, bool equal_speeds, std::vector<double> diameters,
         std::vector<double> masses) {
        const std::string init = to_str(init_arg, "init");
        const double phi = to_real(phi_arg, "phi"), diameter = to_real(diameter_arg, "diameter");
        const double energy = to_real(energy_arg, "energy");
        const int dim = to_int<int>(dim_arg, "dim", en::limits::kMinDim, en::limits::kMaxDim);
        const auto n = to_int<std::size_t>(n_arg, "n", 1, std::size_t{1} << 31);
        const auto seed = to_int<std::uint64_t>(seed_arg, "seed", 0, en::limits::kMaxSeed);
        en::Config c;
        c.dim = dim;
        require(dim >= 1 && dim <= 3, [&] { return "dim must be 1, 2 or 3, got " + std::to_string(dim); });
        require(boundary.size() == 1 || static_cast<int>(boundary.size()) == dim,
                "boundary must be one name or one per axis");
        for (int k = 0; k < dim; ++k) c.boundary[k] = en::parse_boundary(boundary.size() == 1 ? boundary[0] : boundary[k]);
        c.diameter = diameter;
        c.diameters = std::move(diameters);  // a mixture: random_state sets diameter to the largest
        c.masses = std::move(masses);        // velocities / sqrt(m), the centre of mass at rest
        const en::InitialState s = en::random_state(c, n, phi, seed, energy, init, equal_speeds, held_signal_check());
        return py::make_tuple(to_array(s.x, n, dim), to_array(s.v, n, dim),
                              std::vector<double>(s.config.box.begin(), s.config.box.begin() + dim));
      },
      py::arg("dim"), py::arg("n"), py::arg("phi"), py::arg("boundary"), py::arg("diameter"), py::arg("seed"),
      py::arg("energy"), py::arg("init"), py::arg("equal_speeds"), py::arg("diameters") = std::vector<double>{},
      py::arg("masses") = std::vector<double>{});
  // the counted Ctrl-C (revcol.progress.Interrupt) that both engines' polls read (args.hpp)
  m.def(
      "request_stop", [](bool on) { stop_requested() = on; }, py::arg("on"),
      "True: every run under way, and every run started until it is set False again, stops at its next poll.");
  m.def(
      "stop_requested", [] { return stop_requested(); }, "Whether request_stop(True) is in force.");
}

}  // namespace revcol::bind
