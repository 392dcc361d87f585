#include "bindings.hpp"

namespace revcol::bind {
void register_verify(pybind11::module_& m) { (void)m; }
}  // namespace revcol::bind
