#include "bindings.hpp"

namespace revcol::bind {
void register_statesave(pybind11::module_& m) { (void)m; }
}  // namespace revcol::bind
