#!/usr/bin/env bash
# The main job: set up, then `revcol run` -- the default scene (a 2D hard-disk gas, N = 1000,
# area fraction 0.3, walls, exact mode, CLCG4) forward and back, with its report; exit 0
# when the round trip passes. Arguments go to `revcol run` (a scene file, --plot DIR,
# --json FILE, --trajectory FILE, --horizon; docs/run.md).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
exec .venv/bin/revcol run "$@"
