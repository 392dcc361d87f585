// The observation's binding (revcol/engine/observe.hpp): its config from named Python
// arguments and its results as a dict. The Engine class (engine.cpp) registers the methods.
#pragma once
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

}  // namespace revcol::bind
