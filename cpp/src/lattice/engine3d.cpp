// The 3D lattice engine (lattice/engine.hpp, issue 14): the explicit instantiation of the event
// machinery (engine_core.hpp, its definitions engine_impl.hpp) over the exact 3D pair operator LatticePair3D, in a file of its own
// so that the 2D and 3D engines compile in parallel.
#include "revcol/lattice/engine.hpp"

#include "engine_impl.hpp"

namespace revcol::lattice {

template class BasicEngine<LatticePair3D, BitsBack>;

}  // namespace revcol::lattice
