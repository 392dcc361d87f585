"""The benchmark binary's command line: counts in float notation, bad values refused."""
import os
import subprocess
import sys
from pathlib import Path

import pytest


def _bench_binary():
    for c in (os.environ.get("REVCOL_BENCH"), str(Path(sys.executable).parent / "revcol-bench")):
        if c and Path(c).is_file():
            return c
    pytest.skip("revcol-bench not found (set REVCOL_BENCH or install the package)")


@pytest.mark.parametrize("value", ["1.2e7x", "1.5", "-3", "abc", "", "2e19"])
def test_bad_counts_are_refused_by_name(value):
    # std::stoull alone read "1.2e7" as 1: a lockstep check of 1.2e7 collisions compared one
    r = subprocess.run([_bench_binary(), "--bench", "lattice3d/lockstep/n1000/phi0.45", "--collisions", value],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 2
    assert "bad value" in r.stderr and "--collisions" in r.stderr


def test_float_notation_is_the_count():
    r = subprocess.run([_bench_binary(), "--bench", "lattice3d/lockstep/n1000/phi0.45", "--collisions", "2e3"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    got = {line.split()[1]: line.split()[2] for line in r.stdout.splitlines() if len(line.split()) == 3}
    assert got["first_difference"] == "-1" and int(float(got["collisions_compared"])) == 2000
