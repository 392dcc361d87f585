// The lattice binding's conversions (revcol/lattice/engine.hpp's types to and from numpy and
// dicts) and its checkpoints: the engine's state written and read by a loop over its fields.
// Included by lattice.cpp only.
#pragma once
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include "args.hpp"
#include "bindings.hpp"
#include "revcol/error.hpp"
#include "revcol/lattice/engine.hpp"

namespace revcol::bind {
namespace py = pybind11;

namespace la = revcol::lattice;
using IArray = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;
using FArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

// An (n, D) integer entry: its dtype checked first (forcecast would take floats and NaN).
inline IArray int_array(py::handle obj, const char* what) {
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
  d["gravity"] = tuple_of(u.gravity);  // lattice units per tick^2 (even; zero: no field)
  d["shear"] = u.shear;                // Lees-Edwards: lattice units per tick (zero: none)
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
  // gravity arrived with the uniform field; units without it have none
  if (d.contains("gravity")) {
    const auto g = get<std::vector<std::int64_t>>(d, "gravity");
    require(g.size() == D, D == 2 ? "lattice units: gravity needs two entries" : "lattice units: gravity needs three entries (3D)");
    for (std::size_t k = 0; k < D; ++k) u.gravity[k] = g[k];
  }
  // shear arrived with Lees-Edwards; units without it have none
  if (d.contains("shear")) u.shear = get<std::int64_t>(d, "shear");
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
  d["gravity_error"] = s.gravity_error;  // a field: |g_lattice - g| / |g| (0: none)
  d["shear_error"] = s.shear_error;      // shear: |s_lattice - s| / |s| (0: none)
  return d;
}

// ---- checkpoints: the engine's state written and read by a loop over its fields ----------
// (la::SnapshotN::visit, la::Counters::visit): one overload per field type below; a new field
// needs its line in visit_fields and, for a new type, an overload here.

template <std::size_t D>
void put(py::dict& d, const char* key, const la::UnitsN<D>& u) { d[key] = units_dict(u); }
inline void put(py::dict& d, const char* key, revcol::Law law) { d[key] = to_string(law); }
inline void put(py::dict& d, const char* key, revcol::Mode mode) { d[key] = to_string(mode); }
template <class T>
  requires std::is_integral_v<T>
void put(py::dict& d, const char* key, T v) { d[key] = v; }
template <std::size_t D>
void put(py::dict& d, const char* key, const std::vector<la::VecN<D>>& v) { d[key] = vec_array(v); }
template <class T, std::size_t K>
void put(py::dict& d, const char* key, const std::array<T, K>& a) { d[key] = flat_array(a.data(), K); }
inline void put(py::dict& d, const char* key, const std::vector<std::uint64_t>& v) { d[key] = flat_array(v.data(), v.size()); }
inline void put(py::dict& d, const char* key, const std::vector<double>& v) { d[key] = flat_array(v.data(), v.size()); }
// a mixture's radii (lattice units, by particle id): no entry for a gas of one diameter
inline void put(py::dict& d, const char* key, const std::vector<std::int64_t>& v) {
  if (!v.empty()) d[key] = flat_array(v.data(), v.size());
}
// the rare log as three arrays: log_particle (the drawer), log_count (its collision count
// after the collision) and log_redraws
inline void put(py::dict& d, const char*, const std::vector<la::LogEntry>& log) {
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
inline void take(const py::dict& d, const char* key, revcol::Law& law) { law = parse_law(get<std::string>(d, key)); }
// the lattice's modes: exact (the randomized operator) or specular (a checkpoint without the key is exact)
inline revcol::Mode parse_lattice_mode(const std::string& s) {
  if (s == "exact") return revcol::Mode::exact;
  if (s == "specular") return revcol::Mode::specular;
  throw revcol::InvalidArgument("lattice mode must be 'exact' or 'specular', got '" + s + "'");
}
inline void take(const py::dict& d, const char* key, revcol::Mode& mode) {
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
inline void take(const py::dict& d, const char* key, std::vector<std::uint64_t>& v) { v = get_flat<std::uint64_t>(d, key); }
inline void take(const py::dict& d, const char* key, std::vector<double>& v) { v = get_flat<double>(d, key); }
inline void take(const py::dict& d, const char* key, std::vector<std::int64_t>& v) {
  if (d.contains(key)) v = get_flat<std::int64_t>(d, key);  // absent: one diameter (and every older checkpoint)
}

// a running observation's entries: written only while one runs, absent in older checkpoints
inline bool observer_entry(const char* key) { return std::strcmp(key, "observer") == 0 || std::strcmp(key, "observer_counts") == 0; }
template <class T, std::size_t K>
void take(const py::dict& d, const char* key, std::array<T, K>& a) {
  const auto v = get_flat<T>(d, key);
  require(v.size() == K, [&] {
    return std::string("lattice checkpoint: ") + key + " " + std::to_string(K) + " words expected, got " +
           std::to_string(v.size());
  });
  for (std::size_t k = 0; k < K; ++k) a[k] = v[k];
}
inline void take(const py::dict& d, const char*, std::vector<la::LogEntry>& log) {
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

inline py::dict counters_dict(const la::Counters& c) {
  py::dict d;
  c.visit([&](const char* key, const auto& v) {
    using V = std::decay_t<decltype(v)>;
    if constexpr (std::is_integral_v<V>) {
      d[key] = v;
    } else if constexpr (std::tuple_size_v<V> == 4) {  // a field's wall impulse: (lower, upper), 128 bits each
      auto word128 = [](std::uint64_t lo, std::uint64_t hi) { return (py::int_(hi).attr("__lshift__")(64)).attr("__or__")(py::int_(lo)); };
      d[key] = py::make_tuple(word128(v[0], v[1]), word128(v[2], v[3]));
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

}  // namespace revcol::bind
