// Binding of the event-driven engine: to be filled.
#include "bindings.hpp"

namespace revcol::bind {

void register_engine(pybind11::module_& m) { (void)m; }

}  // namespace revcol::bind
