// The compiled module revcol._core: it only converts types and registers; all physics is
// in the core library. One register_<area>() per area.
#include <pybind11/pybind11.h>

#include "bindings.hpp"
#include "revcol/error.hpp"

namespace revcol::bind {
void register_randomness(pybind11::module_& m);  ///< randomness.cpp: the randomness study's word stream
}  // namespace revcol::bind

PYBIND11_MODULE(_core, m) {
  m.doc() = "revcol core (private): use the revcol package";
  pybind11::register_exception<revcol::InvalidArgument>(m, "InvalidArgument", PyExc_ValueError);
  revcol::bind::register_rng(m);
  revcol::bind::register_collide(m);
  revcol::bind::register_verify(m);
  revcol::bind::register_exact(m);
  revcol::bind::register_paper(m);
  revcol::bind::register_paper_study(m);
  revcol::bind::register_statesave(m);
  revcol::bind::register_engine(m);
  revcol::bind::register_engine_init(m);
  revcol::bind::register_lattice(m);
  revcol::bind::register_randomness(m);
}
