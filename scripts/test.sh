#!/usr/bin/env bash
# All tests: set up, then the C++ tests (ctest), the C++ tests again under AddressSanitizer
# and UndefinedBehaviorSanitizer, the stub check, and the Python tests (pytest) against the
# installed package.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
export PATH="$PWD/.venv/bin:$PATH"
jobs=$(nproc)

echo "== C++ tests =="
cmake -S . -B build-test -G Ninja -DREVCOL_BUILD_TESTS=ON -DREVCOL_BUILD_PYTHON=OFF \
  -DREVCOL_BUILD_BENCH=OFF >/dev/null
cmake --build build-test -j"$jobs"
ctest --test-dir build-test -L cpp --output-on-failure -j"$jobs"

echo "== C++ tests under ASan + UBSan =="
cmake -S . -B build-sanitize -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DREVCOL_SANITIZE=ON \
  -DREVCOL_BUILD_TESTS=ON -DREVCOL_BUILD_PYTHON=OFF -DREVCOL_BUILD_BENCH=OFF >/dev/null
cmake --build build-sanitize -j"$jobs"
ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir build-sanitize -L cpp --output-on-failure -j"$jobs"

echo "== Stubs: python/revcol/_core.pyi against the binding (mypy.stubtest) =="
# every name on both sides; tests/python/test_stubs.py compares the signatures, which
# stubtest cannot read from pybind11
.venv/bin/python -m mypy.stubtest revcol._core

echo "== Python tests =="
# the installed package is what is tested (the sources live in python/, not on sys.path)
exec .venv/bin/python -m pytest -q tests/python -p no:cacheprovider
