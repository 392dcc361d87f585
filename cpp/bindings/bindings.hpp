// One registration function per area; module.cpp calls each.
#pragma once
#include <pybind11/pybind11.h>

namespace revcol::bind {
void register_rng(pybind11::module_& m);
void register_collide(pybind11::module_& m);
void register_verify(pybind11::module_& m);
}  // namespace revcol::bind
