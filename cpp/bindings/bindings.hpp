// One registration function per area; module.cpp calls each. arrays.hpp holds the helpers
// they share (shapes, generator arguments, held invariants).
#pragma once
#include <pybind11/pybind11.h>

namespace revcol::bind {
void register_rng(pybind11::module_& m);
void register_collide(pybind11::module_& m);
void register_verify(pybind11::module_& m);
void register_exact(pybind11::module_& m);      ///< exact.cpp: the general exact operator
void register_paper(pybind11::module_& m);      ///< paper.cpp: paper-mode 3D pair and triples
void register_paper_study(pybind11::module_& m);  ///< paper_study.cpp: paper-mode measurements, tables
void register_statesave(pybind11::module_& m);  ///< statesave.cpp: the SS1/SS2/RC study
void register_engine(pybind11::module_& m);     ///< engine.cpp: the event-driven engine (Simulation)
void register_engine_init(pybind11::module_& m);  ///< engine_init.cpp: the engine's random start and limits
void register_lattice(pybind11::module_& m);     ///< lattice.cpp: the 2D lattice engine
void register_randomness(pybind11::module_& m);  ///< randomness.cpp: the randomness study's word stream
void register_ecmc(pybind11::module_& m);        ///< ecmc.cpp: the event-chain Monte Carlo sampler
}  // namespace revcol::bind
