#!/usr/bin/env bash
# The main job: set up, then run the paper's 2-particle reversal experiment (10^6
# collisions forward and back, exact mode). Arguments go to `revcol verify pair2d`.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
exec .venv/bin/revcol verify pair2d "$@"
