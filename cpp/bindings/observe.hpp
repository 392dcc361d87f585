// The observation's binding (revcol/engine/observe.hpp): its config from named Python
// arguments and its results as a dict. The Engine class (engine.cpp) registers the methods.
#pragma once
#include <algorithm>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "args.hpp"
#include "revcol/engine/observe.hpp"

namespace revcol::bind {

/// An ObserveConfig from the Python arguments, each converted and range-checked by name.
engine::ObserveConfig observe_config(const PyReal& block_time, const PyInt& min_blocks, const PyInt& slab_axis,
                                     const PyInt& slabs, const PyInt& speed_bins, const PyReal& speed_max,
                                     const PyInt& pair_bins, const PyReal& pair_rmax);

/// The results as a dict: estimates as {"value", "error"}, profiles as {"edges", "value", "error"} arrays.
pybind11::dict observation_dict(const engine::Observation& o);

/// Registers observe / observation / stop_observing / observing on a class whose engine
/// (get(self): the float engine's Simulation or a lattice engine) has the observer's API.
template <class Self, class... Extra, class Get>
void def_observe(pybind11::class_<Self, Extra...>& cls, Get get) {
  namespace py = pybind11;
  cls.def(
         "observe",
         [get](Self& s, PyReal block_time, PyInt min_blocks, PyInt slab_axis, PyInt slabs, PyInt speed_bins,
               PyReal speed_max, PyInt pair_bins, PyReal pair_rmax) {
           get(s).observe(
               observe_config(block_time, min_blocks, slab_axis, slabs, speed_bins, speed_max, pair_bins, pair_rmax));
         },
         py::arg("block_time") = 0.0, py::arg("min_blocks") = 16, py::arg("slab_axis") = 0, py::arg("slabs") = 0,
         py::arg("speed_bins") = 0, py::arg("speed_max") = 0.0, py::arg("pair_bins") = 0, py::arg("pair_rmax") = 0.0)
      .def("observation",
           [get](Self& s) -> py::object {
             const engine::Observer* o = get(s).observer();
             if (o == nullptr) return py::none();
             return observation_dict(o->results());
           })
      .def("observed_positions",
           [get](Self& s) -> py::object {
             const engine::Observer* o = get(s).observer();
             if (o == nullptr || !get(s).observing()) return py::none();
             double t;  // the engine's clock in the observer's units (the lattice's ticks as time)
             if constexpr (requires { get(s).time_of(get(s).clock()); }) t = get(s).time_of(get(s).clock());
             else t = get(s).time();
             const std::vector<double> u = o->unwrapped(t);
             const auto n = static_cast<py::ssize_t>(o->size());
             py::array_t<double> a({n, static_cast<py::ssize_t>(u.size()) / n});
             std::copy(u.begin(), u.end(), a.mutable_data());
             return a;
           })
      .def("stop_observing", [get](Self& s) { get(s).stop_observing(); })
      .def_property_readonly("observing", [get](Self& s) { return get(s).observing(); });
}

}  // namespace revcol::bind
