// Batches of the paper-mode operators with several draws (Pair3DPaper, Triple1DPaper,
// Triple2DPaper): the one batch template of batch.hpp (revcol::paper::forward_batch and
// reverse_batch are revcol::forward_batch and reverse_batch). Kept so that includers of
// this name keep working.
#pragma once
#include "revcol/collide/batch.hpp"
