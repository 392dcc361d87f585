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
#include "observe.hpp"
#include "revcol/error.hpp"
#include "revcol/lattice/engine.hpp"

namespace py = pybind11;

namespace revcol::bind {
namespace {

namespace la = revcol::lattice;
using IArray = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;
using FArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

// An (n, D) integer entry: its dtype checked first (forcecast would take floats and NaN).
IArray int_array(py::handle obj, const char* what) {
  (void)checkpoint_array<std::int64_t>(obj, what);  // integers of int64 range, or a named error
  return IArray::ensure(obj);
}
template <std::size_t D>
std::vector<la::VecN<D>> vecs(const IArray& a, const char* what) {
  const auto bad = [&] { return std::string(what) + " must be an (n, " + std::to_string(D) + ") integer array"; };
  require(static_cast<bool>(a), bad);  // ensure() failed
  require(a.ndim() == 2 && a.shape(1) == static_cast<py::ssize_t>(D), bad);
  std::vector<la::VecN<D>> out(static_cast<std::size_t>(a.shape(0)));
  if (!out.empty()) std::memcpy(out.data(), a.data(), out.size() * sizeof(la::VecN<D>));
  return out;
}
template <std::size_t D>
py::array_t<std::int64_t> vec_array(const std::vector<la::VecN<D>>& v) {
  py::array_t<std::int64_t> out({static_cast<py::ssize_t>(v.size()), static_cast<py::ssize_t>(D)});
  if (!v.empty()) std::memcpy(out.mutable_data(), v.data(), v.size() * sizeof(la::VecN<D>));
  return out;
}
// a tuple of the D entries of an array
template <class T, std::size_t D>
py::tuple tuple_of(const std::array<T, D>& a) {
  py::tuple t(D);
  for (std::size_t k = 0; k < D; ++k) t[k] = py::cast(a[k]);
  return t;
}
template <class T>
py::array_t<T> flat_array(const T* p, std::size_t n) {
  py::array_t<T> out(static_cast<py::ssize_t>(n));
  if (n > 0) std::memcpy(out.mutable_data(), p, n * sizeof(T));
  return out;
}
template <class T>
std::vector<T> get_flat(const py::dict& d, const char* key) {
  require(d.contains(key), [&] { return std::string("lattice checkpoint is missing '") + key + "'"; });
  return checkpoint_array<T>(d[key], key);
}
template <class T>
T get(const py::dict& d, const char* key) {
  require(d.contains(key), [&] { return std::string("lattice checkpoint is missing '") + key + "'"; });
  return checkpoint_field<T>(d[key], key);
}

template <std::size_t D>
py::dict units_dict(const la::UnitsN<D>& u) {
  py::dict d;
  d["S"] = u.S;
  d["sigma"] = u.sigma;
  d["L"] = tuple_of(u.L);
  py::tuple kinds(D);  // each axis's kind by name (engine/boundary_kind.hpp)
  for (std::size_t k = 0; k < D; ++k) kinds[k] = engine::to_string(la::boundary_of(u, k));
  d["boundary"] = kinds;
  d["wall"] = tuple_of(u.wall);
  d["vmax"] = u.vmax;
  d["length_unit"] = u.length_unit;
  d["tick"] = u.tick;
  d["tick_bits"] = u.tick_bits;
  d["cell_bits"] = u.cell_bits;
  return d;
}
template <std::size_t D>
la::UnitsN<D> units_from(const py::dict& d) {
  la::UnitsN<D> u;
  u.S = get<int>(d, "S");
  u.sigma = get<std::int64_t>(d, "sigma");
  const auto L = get<std::vector<std::int64_t>>(d, "L");
  const auto w = get<std::vector<bool>>(d, "wall");
  require(L.size() == D && w.size() == D, D == 2 ? "lattice units: L and wall need two entries each"
                                                 : "lattice units: L and wall need three entries each (3D)");
  for (std::size_t k = 0; k < D; ++k) {
    u.L[k] = L[k];
    u.wall[k] = w[k];
  }
  // each axis's kind by name; units written before bounce-back walls hold the wall flags only
  if (d.contains("boundary")) {
    const auto b = get<std::vector<std::string>>(d, "boundary");
    require(b.size() == D, D == 2 ? "lattice units: boundary needs two names" : "lattice units: boundary needs three names (3D)");
    for (std::size_t k = 0; k < D; ++k) {
      la::set_boundary(u, k, engine::parse_boundary(b[k]));
      require(u.wall[k] == w[k], "lattice units: boundary and wall disagree");
    }
  }
  u.vmax = get<std::int64_t>(d, "vmax");
  u.length_unit = get<double>(d, "length_unit");
  u.tick = get<double>(d, "tick");
  // the float scales every reading goes through (positions = x length_unit, times = ticks tick)
  require(std::isfinite(u.length_unit) && u.length_unit > 0.0, "lattice units: length_unit must be finite and > 0");
  require(std::isfinite(u.tick) && u.tick > 0.0, "lattice units: tick must be finite and > 0");
  // tick_bits arrived with the finer-tick option; units without it are the default 20
  u.tick_bits = d.contains("tick_bits") ? get<int>(d, "tick_bits") : la::legacy_tick_bits;
  // cell_bits arrived with the coarser direction cells; units without it ran 2^20 cells
  u.cell_bits = d.contains("cell_bits") ? get<int>(d, "cell_bits") : la::max_units_cell_bits;
  la::validate(u);
  return u;
}

template <std::size_t D>
py::dict start_dict(const la::LatticeStartN<D>& s) {
  py::dict d;
  d["units"] = units_dict(s.units);
  d["x"] = vec_array(s.x);
  d["v"] = vec_array(s.v);
  d["radius"] = flat_array(s.radius.data(), s.radius.size());  // (empty: one diameter)
  d["max_position_error"] = s.max_position_error;
  d["max_velocity_error"] = s.max_velocity_error;
  return d;
}

// ---- checkpoints: the engine's state written and read by a loop over its fields ----------
// (la::SnapshotN::visit, la::Counters::visit): one overload per field type below; a new field
// needs its line in visit_fields and, for a new type, an overload here.

template <std::size_t D>
void put(py::dict& d, const char* key, const la::UnitsN<D>& u) { d[key] = units_dict(u); }
void put(py::dict& d, const char* key, revcol::Law law) { d[key] = to_string(law); }
void put(py::dict& d, const char* key, revcol::Mode mode) { d[key] = to_string(mode); }
template <class T>
  requires std::is_integral_v<T>
void put(py::dict& d, const char* key, T v) { d[key] = v; }
template <std::size_t D>
void put(py::dict& d, const char* key, const std::vector<la::VecN<D>>& v) { d[key] = vec_array(v); }
template <class T, std::size_t K>
void put(py::dict& d, const char* key, const std::array<T, K>& a) { d[key] = flat_array(a.data(), K); }
void put(py::dict& d, const char* key, const std::vector<std::uint64_t>& v) { d[key] = flat_array(v.data(), v.size()); }
void put(py::dict& d, const char* key, const std::vector<double>& v) { d[key] = flat_array(v.data(), v.size()); }
// a mixture's radii (lattice units, by particle id): no entry for a gas of one diameter
void put(py::dict& d, const char* key, const std::vector<std::int64_t>& v) {
  if (!v.empty()) d[key] = flat_array(v.data(), v.size());
}
// the rare log as three arrays: log_particle (the drawer), log_count (its collision count
// after the collision) and log_redraws
void put(py::dict& d, const char*, const std::vector<la::LogEntry>& log) {
  std::vector<std::uint64_t> lp, lc, lr;
  for (const auto& e : log) {
    lp.push_back(e.particle);
    lc.push_back(e.count);
    lr.push_back(e.redraws);
  }
  d["log_particle"] = flat_array(lp.data(), lp.size());
  d["log_count"] = flat_array(lc.data(), lc.size());
  d["log_redraws"] = flat_array(lr.data(), lr.size());
}
// the group entries as seven arrays: group_drawer, group_draws, group_size, group_members,
// group_counts (per member, its count after the group), group_kind (0 bounce, 1 resolve) and
// group_v (the pre velocities of the resolves)
template <std::size_t D>
void put(py::dict& d, const char*, const std::vector<la::GroupEntryN<D>>& groups) {
  std::vector<std::uint64_t> gn, gc;
  std::vector<std::int64_t> gd, gs, gm, gk;
  std::vector<la::VecN<D>> gv;
  for (const auto& g : groups) {
    gd.push_back(g.drawer);
    gn.push_back(g.draws);
    gs.push_back(static_cast<std::int64_t>(g.members.size()));
    gk.push_back(g.pre_v.empty() ? 0 : 1);
    for (int m : g.members) gm.push_back(m);
    gc.insert(gc.end(), g.counts.begin(), g.counts.end());
    gv.insert(gv.end(), g.pre_v.begin(), g.pre_v.end());
  }
  d["group_drawer"] = flat_array(gd.data(), gd.size());
  d["group_draws"] = flat_array(gn.data(), gn.size());
  d["group_size"] = flat_array(gs.data(), gs.size());
  d["group_members"] = flat_array(gm.data(), gm.size());
  d["group_counts"] = flat_array(gc.data(), gc.size());
  d["group_kind"] = flat_array(gk.data(), gk.size());
  d["group_v"] = vec_array(gv);
}

template <std::size_t D>
void take(const py::dict& d, const char* key, la::UnitsN<D>& u) { u = units_from<D>(get<py::dict>(d, key)); }
void take(const py::dict& d, const char* key, revcol::Law& law) { law = parse_law(get<std::string>(d, key)); }
// the lattice's modes: exact (the randomized operator) or specular (a checkpoint without the key is exact)
revcol::Mode parse_lattice_mode(const std::string& s) {
  if (s == "exact") return revcol::Mode::exact;
  if (s == "specular") return revcol::Mode::specular;
  throw revcol::InvalidArgument("lattice mode must be 'exact' or 'specular', got '" + s + "'");
}
void take(const py::dict& d, const char* key, revcol::Mode& mode) {
  mode = d.contains(key) ? parse_lattice_mode(get<std::string>(d, key)) : revcol::Mode::exact;
}
template <class T>
  requires std::is_integral_v<T>
void take(const py::dict& d, const char* key, T& v) { v = get<T>(d, key); }
template <std::size_t D>
void take(const py::dict& d, const char* key, std::vector<la::VecN<D>>& v) {
  require(d.contains(key), [&] { return std::string("lattice checkpoint is missing '") + key + "'"; });
  v = checkpoint_entry(key, [&] { return vecs<D>(int_array(d[key], key), key); });
}
void take(const py::dict& d, const char* key, std::vector<std::uint64_t>& v) { v = get_flat<std::uint64_t>(d, key); }
void take(const py::dict& d, const char* key, std::vector<double>& v) { v = get_flat<double>(d, key); }
void take(const py::dict& d, const char* key, std::vector<std::int64_t>& v) {
  if (d.contains(key)) v = get_flat<std::int64_t>(d, key);  // absent: one diameter (and every older checkpoint)
}

// a running observation's entries: written only while one runs, absent in older checkpoints
bool observer_entry(const char* key) { return std::strcmp(key, "observer") == 0 || std::strcmp(key, "observer_counts") == 0; }
template <class T, std::size_t K>
void take(const py::dict& d, const char* key, std::array<T, K>& a) {
  const auto v = get_flat<T>(d, key);
  require(v.size() == K, [&] {
    return std::string("lattice checkpoint: ") + key + " " + std::to_string(K) + " words expected, got " +
           std::to_string(v.size());
  });
  for (std::size_t k = 0; k < K; ++k) a[k] = v[k];
}
void take(const py::dict& d, const char*, std::vector<la::LogEntry>& log) {
  const auto lp = get_flat<std::uint64_t>(d, "log_particle");
  const auto lc = get_flat<std::uint64_t>(d, "log_count");
  const auto lr = get_flat<std::uint64_t>(d, "log_redraws");
  require(lp.size() == lc.size() && lp.size() == lr.size(), "lattice checkpoint: log_particle, log_count and log_redraws differ in length");
  for (std::size_t k = 0; k < lp.size(); ++k) {
    require(lp[k] <= 0xFFFFFFFFull && lr[k] <= 0xFFFFFFFFull, "lattice checkpoint: a rare-log entry out of range");
    log.push_back(la::LogEntry{static_cast<std::uint32_t>(lp[k]), lc[k], static_cast<std::uint32_t>(lr[k])});
  }
}
template <std::size_t D>
void take(const py::dict& d, const char*, std::vector<la::GroupEntryN<D>>& groups) {
  const auto gd = get_flat<std::int64_t>(d, "group_drawer");
  const auto gn = get_flat<std::uint64_t>(d, "group_draws");
  const auto gs = get_flat<std::int64_t>(d, "group_size");
  const auto gm = get_flat<std::int64_t>(d, "group_members");
  const auto gc = get_flat<std::uint64_t>(d, "group_counts");
  const auto gk = get_flat<std::int64_t>(d, "group_kind");
  require(d.contains("group_v"), "lattice checkpoint is missing 'group_v'");
  const auto gv = checkpoint_entry("group_v", [&] { return vecs<D>(int_array(d["group_v"], "group_v"), "group_v"); });
  require(gd.size() == gn.size() && gd.size() == gs.size() && gd.size() == gk.size(), "lattice checkpoint: group arrays differ in length");
  require(gm.size() == gc.size(), "lattice checkpoint: group_members and group_counts differ in length");
  std::size_t at = 0, atv = 0;
  for (std::size_t k = 0; k < gd.size(); ++k) {
    require(gs[k] >= 2 && at + static_cast<std::size_t>(gs[k]) <= gm.size(), "lattice checkpoint: group_members too short");
    require(gk[k] == 0 || gk[k] == 1, "lattice checkpoint: group_kind must be 0 (bounce) or 1 (resolve)");
    require(gd[k] >= 0 && gd[k] <= 0x7FFFFFFF && gn[k] <= 0xFFFFFFFFull, "lattice checkpoint: a group entry out of range");
    for (std::size_t q = at; q < at + static_cast<std::size_t>(gs[k]); ++q)
      require(gm[q] >= 0 && gm[q] <= 0x7FFFFFFF, "lattice checkpoint: a group member out of range");
    la::GroupEntryN<D> e;
    e.drawer = static_cast<int>(gd[k]);
    e.draws = static_cast<std::uint32_t>(gn[k]);
    e.members.assign(gm.begin() + static_cast<std::ptrdiff_t>(at), gm.begin() + static_cast<std::ptrdiff_t>(at + gs[k]));
    e.counts.assign(gc.begin() + static_cast<std::ptrdiff_t>(at), gc.begin() + static_cast<std::ptrdiff_t>(at + gs[k]));
    if (gk[k] == 1) {
      require(atv + static_cast<std::size_t>(gs[k]) <= gv.size(), "lattice checkpoint: group_v too short");
      e.pre_v.assign(gv.begin() + static_cast<std::ptrdiff_t>(atv), gv.begin() + static_cast<std::ptrdiff_t>(atv + gs[k]));
      atv += static_cast<std::size_t>(gs[k]);
    }
    at += static_cast<std::size_t>(gs[k]);
    groups.push_back(std::move(e));
  }
  require(at == gm.size() && atv == gv.size(), "lattice checkpoint: group_members or group_v longer than the groups");
}

py::dict counters_dict(const la::Counters& c) {
  py::dict d;
  c.visit([&](const char* key, const auto& v) {
    if constexpr (std::is_integral_v<std::decay_t<decltype(v)>>) {
      d[key] = v;
    } else {  // redraws, by reason
      py::dict r;
      for (int k = 1; k < 8; ++k) r[la::redraw_names[k]] = v[k];
      d[key] = r;
    }
  });
  return d;
}

template <std::size_t D>
py::dict snapshot_dict(const la::SnapshotN<D>& s) {
  py::dict d;
  d["engine"] = "lattice";
  if constexpr (D == 3) d["dim"] = 3;  // (a 2D checkpoint has no dim key, as before)
  s.visit([&](const char* key, const auto& v) {
    if (observer_entry(key) && s.observer.empty()) return;  // no observation running: no entries
    put(d, key, v);
  });
  return d;
}

template <std::size_t D>
la::SnapshotN<D> snapshot_from(const py::dict& d) {
  la::SnapshotN<D> s;
  if constexpr (D == 3) require(get<int>(d, "dim") == 3, "lattice checkpoint: dim must be 3 for the 3D engine");
  // before per-particle state (revcol 0.x: one global bits-back integer, the rare log keyed by
  // the global collision index) a checkpoint cannot resume bit for bit: the draws it would make
  // and the keys its reverse would read are not the ones its bits describe
  require(!d.contains("log_index"),
          "lattice checkpoint: written by an older revcol (one bits-back integer for the whole gas, the rare log keyed by the "
          "global collision index); this version keeps them per particle and cannot resume it bit for bit. Start a new run "
          "from its positions and velocities (revcol.lattice.restart_from_legacy)");
  s.visit([&](const char* key, auto& v) {
    if (observer_entry(key) && !d.contains(key)) return;  // none running (or an older checkpoint)
    take(d, key, v);
  });
  return s;
}

/// The engine, guarded against calls from other threads while a run is under way.
template <class Engine>
struct PyLattice {
  Engine e;
  std::optional<std::thread::id> runner{};  ///< the thread whose run/run_back is under way (GIL held to touch)

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

// lattice_random_start (2D) and lattice3d_random_start
template <std::size_t D>
py::dict random_start_d(PyInt n_arg, PyReal phi_arg, std::vector<std::string> boundary, PyReal diameter_arg, PyInt seed_arg,
                        const std::string& init, PyInt tick_bits_arg, PyInt cell_bits_arg, std::vector<double> diameters) {
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
  return start_dict(la::random_start(c, n, phi, seed, init));
}

// lattice_quantize (2D) and lattice3d_quantize
template <std::size_t D>
py::dict quantize_d(const FArray& x, const FArray& v, std::vector<double> box, std::vector<std::string> boundary, PyReal diameter_arg,
                    PyInt tick_bits_arg, PyInt cell_bits_arg, std::vector<double> diameters) {
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
        py::arg("diameters") = std::vector<double>{},
        "A random 2D start as engine_random_state, quantized once: {units, x, v, errors}.");
  m.def("lattice3d_random_start", &random_start_d<3>, py::arg("n"), py::arg("phi"), py::arg("boundary"), py::arg("diameter"),
        py::arg("seed"), py::arg("init"), py::arg("tick_bits") = la::default_tick_bits, py::arg("cell_bits") = la::default_cell_bits,
        py::arg("diameters") = std::vector<double>{},
        "A random 3D start (spheres) as engine_random_state, quantized once: {units, x, v, errors}.");
  m.def("lattice_quantize", &quantize_d<2>, py::arg("x"), py::arg("v"), py::arg("box"), py::arg("boundary"), py::arg("diameter"),
        py::arg("tick_bits") = la::default_tick_bits, py::arg("cell_bits") = la::default_cell_bits,
        py::arg("diameters") = std::vector<double>{},
        "Units from the box and rms speed, and one quantization: {units, x, v, errors}.");
  m.def("lattice3d_quantize", &quantize_d<3>, py::arg("x"), py::arg("v"), py::arg("box"), py::arg("boundary"), py::arg("diameter"),
        py::arg("tick_bits") = la::default_tick_bits, py::arg("cell_bits") = la::default_cell_bits,
        py::arg("diameters") = std::vector<double>{},
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
