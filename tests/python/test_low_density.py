"""Low density (issue 59): cell grids sized by N, not by the box. Ten particles at packing
fraction 1e-9 and 1e-12 start, run and come back on both engines in 2D and 3D, each case in a
child process whose peak RSS stays below 100 MB (before the fix phi = 1e-7 took 1.8 GB in the
random start's placement grid and phi <= 1e-8 ended in std::bad_alloc)."""
import json
import os
import subprocess
import sys

import pytest

_CHILD = r"""
import json, sys
import numpy as np
import revcol, revcol.lattice

engine, dim, phi = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
out = {}
if engine == "float":
    sim = revcol.Simulation.random(10, dim, phi, seed=5)
    x0 = sim.positions.copy()
    r = sim.run(collisions=100, time=1e4)  # collisions are rarer than one per 1e8 time units here
    out["time"] = r["time"]
    sim.run_back()
    out["back"] = bool(sim.time == 0.0 and np.allclose(sim.positions, x0, rtol=0.0, atol=1e-6))
else:
    cls = revcol.lattice.LatticeSimulation if dim == 2 else revcol.lattice.LatticeSimulation3D
    try:
        sim = cls.random(10, phi=phi, seed=5)
    except ValueError as e:  # the lattice's own limit on the box (positions of 2^-40 diameters)
        out["refused"] = str(e)
    else:
        s0 = sim.snapshot()
        r = sim.run(collisions=100, time=1e4)
        out["time"] = r["time"]
        sim.run_back()
        s1 = sim.snapshot()
        out["back"] = all(np.array_equal(np.asarray(s0[k]), np.asarray(s1[k]))
                          for k in ("clock", "collisions", "x", "v", "streams", "bits", "bits_size"))
# this process's peak RSS: VmHWM belongs to the address space exec made (ru_maxrss is kept across
# fork and exec, so it would report a large parent's RSS at the fork: the whole suite's pytest)
out["maxrss_kb"] = next(int(line.split()[1]) for line in open("/proc/self/status") if line.startswith("VmHWM:"))
print(json.dumps(out))
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="VmHWM is read from Linux's /proc/self/status")
@pytest.mark.parametrize("phi", [1e-9, 1e-12])
@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("engine", ["float", "lattice"])
def test_sparse_gas_memory_is_small(engine, dim, phi):
    p = subprocess.run([sys.executable, "-c", _CHILD, engine, str(dim), repr(phi)], capture_output=True, text=True,
                       env=dict(os.environ), timeout=120)
    assert p.returncode == 0, p.stderr
    out = json.loads(p.stdout.strip().splitlines()[-1])
    assert out["maxrss_kb"] < 100 * 1024, out
    if engine == "lattice" and dim == 2 and phi == 1e-12:
        # 2.8e6 diameters per axis: past the 2D lattice's 2^21, a named refusal (not a bad_alloc)
        assert "too long for the lattice" in out["refused"]
        return
    assert out["time"] == pytest.approx(1e4) and out["back"], out
