// The compiled module revcol._core: it only converts types and registers; all physics is
// in the core library. One register_<area>() per area.
#include <pybind11/pybind11.h>

#include <exception>

#include "bindings.hpp"
#include "revcol/error.hpp"
#include "revcol/interrupt.hpp"

#define REVCOL_STR2(x) #x
#define REVCOL_STR(x) REVCOL_STR2(x)

PYBIND11_MODULE(_core, m) {
  m.doc() = "revcol core (private): use the revcol package";
  pybind11::register_exception<revcol::InvalidArgument>(m, "InvalidArgument", PyExc_ValueError);
  // a study stopped by its interrupt check (revcol/interrupt.hpp, bind::released_signal_check):
  // the check left the KeyboardInterrupt pending; raise it (a bare one if none is)
  pybind11::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const revcol::Interrupted&) {
      if (!PyErr_Occurred()) PyErr_SetNone(PyExc_KeyboardInterrupt);
    }
  });
  // what built this module, stamped into checkpoints (python/revcol/_io.py)
  m.attr("build") = "gcc " __VERSION__ ", pybind11 " REVCOL_STR(PYBIND11_VERSION_MAJOR) "." REVCOL_STR(
      PYBIND11_VERSION_MINOR) "." REVCOL_STR(PYBIND11_VERSION_PATCH)
#ifdef NDEBUG
      ", release";
#else
      ", debug";
#endif
  // the instruction set it was compiled for (CMake REVCOL_ISA): speed only, the same bits
  m.attr("isa") = REVCOL_ISA_NAME;
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
  revcol::bind::register_ecmc(m);
}
