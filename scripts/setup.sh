#!/usr/bin/env bash
# Installs everything revcol needs, on a fresh Debian machine as root, and is cheap to run
# again: Debian packages (compiler, Eigen 3, GSL, Python, dieharder) only when missing, then a virtual
# environment .venv with the build tools from PyPI and revcol itself (an incremental build).
set -euo pipefail
cd "$(dirname "$0")/.."

missing=()
command -v g++ >/dev/null 2>&1 || missing+=(g++)
command -v make >/dev/null 2>&1 || missing+=(make)
[ -f /usr/include/eigen3/Eigen/Core ] || missing+=(libeigen3-dev)
[ -f /usr/include/gsl/gsl_sf_ellint.h ] || missing+=(libgsl-dev)
command -v dieharder >/dev/null 2>&1 || missing+=(dieharder)  # the randomness battery (docs/randomness.md)
command -v python3 >/dev/null 2>&1 || missing+=(python3 python3-dev python3-venv)
if command -v python3 >/dev/null 2>&1 && ! python3 -c 'import venv, ensurepip' >/dev/null 2>&1; then
  missing+=(python3-venv)
fi
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing Debian packages: ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" python3-dev >/dev/null
fi

if [ ! -x .venv/bin/python ]; then
  python3 -m venv .venv
fi
py=.venv/bin/python
t0=$SECONDS
echo "setup: Python packages into .venv (the first time about a minute; then a check)"
$py -m pip install -q --disable-pip-version-check --upgrade pip >/dev/null
$py -m pip install -q --disable-pip-version-check \
  "scikit-build-core>=0.11" "pybind11>=2.12" "cmake>=3.20" ninja numpy "scipy>=1.8" "pytest>=7" "matplotlib>=3.5" "tqdm>=4.60" "gsd>=3" "ase>=3.22" "freud-analysis>=3" "mypy>=1.10" "hypothesis>=6.80" "dask[distributed]>=2024.1"
# no build isolation: the tools above are in .venv; build/{wheel_tag} is reused between runs
# (pyproject sets no build-dir, so a plain `pip wheel .` builds out of tree)
echo "setup: building revcol, its C++ core and Python module (the first time 2-5 minutes on 2 cores; then only what changed)"
$py -m pip install -q --disable-pip-version-check --no-build-isolation --no-deps -C build-dir=build/{wheel_tag} .
echo "setup: ok ($($py -c 'import revcol, sys; print("revcol", revcol.__version__, "python", sys.version.split()[0])'), $((SECONDS - t0)) s)"
