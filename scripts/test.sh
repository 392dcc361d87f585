#!/usr/bin/env bash
# All tests: set up, then the C++ tests (ctest), the C++ tests again under AddressSanitizer
# and UndefinedBehaviorSanitizer with the Python tests that reach C++ (fuzz, checkpoints,
# hardening) against the sanitized module, the stub check, and the Python tests (pytest)
# against the installed package.
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

echo "== C++ tests under ASan + UBSan, built for the baseline instruction set =="
# the first build is for this machine's level (REVCOL_ISA=auto: x86-64-v3 where it runs);
# this one is for the baseline, so test_engine_hash checks its constants both ways: the
# instruction set must not change a bit (CMakeLists.txt, revcol/eigen.hpp)
cmake -S . -B build-sanitize -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DREVCOL_SANITIZE=ON -DREVCOL_ISA=baseline \
  -DREVCOL_BUILD_TESTS=ON -DREVCOL_BUILD_PYTHON=ON -DREVCOL_BUILD_BENCH=OFF \
  -DPython_EXECUTABLE="$PWD/.venv/bin/python" -Dpybind11_DIR="$(.venv/bin/python -m pybind11 --cmakedir)" >/dev/null
cmake --build build-sanitize -j"$jobs"
ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir build-sanitize -L cpp --output-on-failure -j"$jobs"

echo "== Python tests that reach C++ (fuzz suite, crafted checkpoints, hardening), against the ASan + UBSan module =="
# the sanitized module beside the Python sources; Python itself is not instrumented, so the
# runtimes are preloaded and leak checking is off (the interpreter keeps its objects at exit)
rm -rf build-sanitize/pkg && mkdir -p build-sanitize/pkg && cp -r python/revcol build-sanitize/pkg/
cp build-sanitize/_core*.so build-sanitize/pkg/revcol/
mkdir -p build-sanitize/pkg/revcol/scenes && cp scenes/*.toml scenes/*.npz build-sanitize/pkg/revcol/scenes/
LD_PRELOAD="$(gcc -print-file-name=libasan.so) $(gcc -print-file-name=libubsan.so)" \
  ASAN_OPTIONS=detect_leaks=0 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 PYTHONPATH=build-sanitize/pkg \
  .venv/bin/python -m pytest -q -p no:cacheprovider tests/python/test_fuzz.py tests/python/test_checkpoints.py \
  tests/python/test_hardening.py tests/python/test_trace.py tests/python/test_interrupt.py

echo "== Stubs: python/revcol/_core.pyi against the binding (mypy.stubtest) =="
# every name on both sides; tests/python/test_stubs.py compares the signatures, which
# stubtest cannot read from pybind11
.venv/bin/python -m mypy.stubtest revcol._core

echo "== Python tests =="
# the installed package is what is tested (the sources live in python/, not on sys.path)
exec .venv/bin/python -m pytest -q tests/python -p no:cacheprovider
