// The lattice engine's definitions: BasicEngine (declared in revcol/lattice/engine_core.hpp)
// in its parts, one file each. Included only where an engine is instantiated: the 2D and 3D
// engines (engine.cpp, engine3d.cpp) and the white-box tests that run the machinery over a
// test operator. Users include revcol/lattice/engine.hpp, whose engines are instantiated here.
#pragma once
#include "revcol/lattice/engine_core.hpp"
#include "state.hpp"    // snapshots, restore, rebuild, flip, the undo journal
#include "predict.hpp"  // a particle's next event: the filter and the exact search
#include "loop.hpp"     // run, run_back, the event loop, wall reflections
#include "collide.hpp"  // pair collisions: acceptance, redraws, the rare log, the reverse
#include "group.hpp"    // a third body within one tick: group collisions
#include "rollback.hpp"  // the journal: the latest events undone one by one
#include "observe.hpp"  // the observer's hooks
#include "lp_view.hpp"  // a logical process's view: messages written, particles parked
