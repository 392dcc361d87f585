// The observation's binding: argument conversion and the results dict (no physics here:
// revcol/engine/observe.hpp). The Engine methods that use it are in engine.cpp.
#include "observe.hpp"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <cstring>
#include <vector>

namespace py = pybind11;

namespace revcol::bind {
namespace {

py::dict estimate(const engine::Estimate& e) {
  py::dict d;
  d["value"] = e.value;
  d["error"] = e.error;
  return d;
}

py::array_t<double> array(const std::vector<double>& v) {
  py::array_t<double> out(static_cast<py::ssize_t>(v.size()));
  if (!v.empty()) std::memcpy(out.mutable_data(), v.data(), v.size() * sizeof(double));
  return out;
}

py::object profile(const engine::Profile& p) {
  if (p.value.empty()) return py::none();
  py::dict d;
  d["edges"] = array(p.edges);
  d["value"] = array(p.value);
  d["error"] = array(p.error);
  return d;
}

}  // namespace

engine::ObserveConfig observe_config(const PyReal& block_time, const PyInt& min_blocks, const PyInt& slab_axis,
                                     const PyInt& slabs, const PyInt& speed_bins, const PyReal& speed_max,
                                     const PyInt& pair_bins, const PyReal& pair_rmax) {
  engine::ObserveConfig c;
  c.block_time = to_real(block_time, "block_time");
  c.min_blocks = to_int<int>(min_blocks, "min_blocks", 2, 64);
  c.slab_axis = to_int<int>(slab_axis, "slab_axis", 0, 2);
  c.slabs = to_int<int>(slabs, "slabs", 0, 1 << 20);
  c.speed_bins = to_int<int>(speed_bins, "speed_bins", 0, 1 << 20);
  c.speed_max = to_real(speed_max, "speed_max");
  c.pair_bins = to_int<int>(pair_bins, "pair_bins", 0, 1 << 20);
  c.pair_rmax = to_real(pair_rmax, "pair_rmax");
  return c;
}

py::dict observation_dict(const engine::Observation& o) {
  py::dict d;
  d["dim"] = o.dim;
  d["n"] = o.n;
  d["t_start"] = o.t_start;
  d["t_end"] = o.t_end;
  d["blocks"] = o.blocks;
  d["block_time"] = o.block_time;
  d["pair_collisions"] = o.pair_collisions;
  d["group_collisions"] = o.group_collisions;
  d["particle_collisions"] = o.particle_collisions;
  d["wall_reflections"] = o.wall_reflections;
  d["temperature"] = estimate(o.temperature);
  d["pressure_virial"] = estimate(o.pressure_virial);
  d["compressibility"] = estimate(o.compressibility);
  d["collision_rate"] = estimate(o.collision_rate);
  d["mean_free_time"] = estimate(o.mean_free_time);
  d["mean_free_path"] = estimate(o.mean_free_path);
  d["virial_balance"] = estimate(o.virial_balance);
  py::list walls;
  for (int k = 0; k < o.dim; ++k) walls.append(estimate(o.pressure_wall[k]));
  d["pressure_wall"] = walls;
  d["slab_density"] = profile(o.slab_density);
  d["slab_temperature"] = profile(o.slab_temperature);
  d["speed"] = profile(o.speed);
  d["pair_distance"] = profile(o.pair_distance);
  d["slab_velocity"] = profile(o.slab_velocity);  // (shear only)
  if (o.shear_rate != 0.0) {  // a sheared gas: the rate, P_xy and -P_xy / rate
    d["shear_rate"] = o.shear_rate;
    d["shear_stress"] = estimate(o.shear_stress);
    d["viscosity"] = estimate(o.viscosity);
  }
  d["msd_time"] = array(o.msd_time);
  d["msd"] = array(o.msd);
  d["vacf"] = array(o.vacf);
  // the Helfand moment: (block ends, components), at msd_time
  const auto hc = static_cast<py::ssize_t>(o.helfand_components);
  py::array_t<double> h({hc > 0 ? static_cast<py::ssize_t>(o.helfand.size()) / hc : 0, hc});
  if (!o.helfand.empty()) std::memcpy(h.mutable_data(), o.helfand.data(), o.helfand.size() * sizeof(double));
  d["helfand"] = h;
  // a mixture's species (empty for one species): the estimates per species, the MSD (block ends, S)
  d["species_diameter"] = array(o.species_diameter);
  d["species_mass"] = array(o.species_mass);
  py::array_t<std::uint64_t> counts(static_cast<py::ssize_t>(o.species_count.size()));
  for (std::size_t u = 0; u < o.species_count.size(); ++u) counts.mutable_data()[u] = o.species_count[u];
  d["species_count"] = counts;
  py::list temps, press;
  for (const auto& e : o.species_temperature) temps.append(estimate(e));
  for (const auto& e : o.species_pressure) press.append(estimate(e));
  d["species_temperature"] = temps;
  d["species_pressure"] = press;
  const auto ns = static_cast<py::ssize_t>(o.species_count.size());
  py::array_t<double> sm({ns > 0 ? static_cast<py::ssize_t>(o.species_msd.size()) / ns : 0, ns});
  if (!o.species_msd.empty()) std::memcpy(sm.mutable_data(), o.species_msd.data(), o.species_msd.size() * sizeof(double));
  d["species_msd"] = sm;
  return d;
}

}  // namespace revcol::bind
