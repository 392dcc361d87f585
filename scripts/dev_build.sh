#!/usr/bin/env bash
# Developer build: configure + build into DIR (default build-dev), C++ tests included, and
# stage an importable package under DIR/pkg. Use:  PYTHONPATH=DIR/pkg python -m pytest tests/python
# Extra arguments go to cmake (e.g. -DREVCOL_SANITIZE=ON).
set -euo pipefail
cd "$(dirname "$0")/.."
dir=${1:-build-dev}; shift || true
py=${PYTHON:-python3}
cmake -S . -B "$dir" -G Ninja -DREVCOL_BUILD_TESTS=ON \
  -DPython_EXECUTABLE="$(command -v "$py")" \
  -Dpybind11_DIR="$("$py" -m pybind11 --cmakedir)" "$@" >/dev/null
cmake --build "$dir" -j"$(nproc)"
# the whole package tree (revcol.studies, revcol.cli, revcol.sweep ...), nothing left of an older layout
rm -rf "$dir/pkg/revcol" && mkdir -p "$dir/pkg"
cp -r python/revcol "$dir/pkg/"
[ -f "$dir/_core"*.so ] 2>/dev/null || true
cp "$dir"/_core*.so "$dir/pkg/revcol/" 2>/dev/null || true
echo "staged: $dir/pkg"
