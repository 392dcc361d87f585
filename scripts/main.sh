#!/usr/bin/env bash
# The main job: set up, then `revcol run` -- the default scene (a 2D hard-disk gas on the
# lattice engine, N = 1000, area fraction 0.3, walls, flux law, Philox per-particle streams)
# 10^6 collisions forward and back, with its report; exit 0 when positions, velocities, RNG
# counters, the bits-back integer and the clock are restored bit for bit. Arguments go to
# `revcol run` (a scene file, --plot DIR, --json FILE, --trajectory FILE, --horizon,
# --engine float|lattice; docs/run.md).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
exec .venv/bin/revcol run "$@"
