"""The parallel lattice engine end to end from Python: ``LatticeSimulation.run(collisions=C)``
with ``set_parallel(workers)`` against the sequential engine, interleaved (seq, K1, K2, seq,
K1, K2, ...), from one warmed state; each run's end state compared with the sequential one bit
for bit. What it measures beyond ``revcol-bench --bench parallel/...`` (the engine alone): the
probe and the tail a stop at a collision count costs, building the K views, and restoring the
committed state into the simulation.

    PYTHONPATH=build-dev/pkg python bench/parallel_python.py --dim 2 --n 1000000 --phi 0.5 \\
        --collisions 2000000 --rounds 3 --json bench/results/lattice_parallel_python.json
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

from revcol.lattice import LatticeSimulation, LatticeSimulation3D

STATE = ("x", "v", "streams", "bits", "bits_size", "clock", "collisions", "particle_collisions", "log_particle",
         "log_count", "group_drawer", "group_counts")


def _same(a: dict, b: dict) -> bool:
    return all(np.array_equal(np.asarray(a[k]), np.asarray(b[k])) for k in STATE)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--dim", type=int, choices=(2, 3), default=2)
    p.add_argument("--n", type=int, default=1_000_000)
    p.add_argument("--phi", type=float, default=0.5)
    p.add_argument("--collisions", type=int, default=2_000_000)
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--workers", type=int, nargs="+", default=[1, 2], help="parallel variants (K = workers LPs)")
    p.add_argument("--json", required=True)
    a = p.parse_args(argv)
    cls = LatticeSimulation3D if a.dim == 3 else LatticeSimulation
    load0 = os.getloadavg()[0]
    sim = cls.random(a.n, phi=a.phi, seed=1)
    sim.run(collisions=a.n)  # warmed: the start's relaxation behind it
    s0 = sim.snapshot()
    names = ["seq"] + [f"K{w}_w{w}" for w in a.workers]
    rates: dict[str, list[float]] = {k: [] for k in names}
    same: dict[str, bool] = {k: True for k in names}
    report: dict[str, dict] = {}
    want = None
    for r in range(a.rounds):
        for name in names:
            s = cls.from_snapshot(s0)
            if name != "seq":
                w = int(name.split("_w")[1])
                s.set_parallel(w, lps=w)
            t0 = time.perf_counter()
            out = s.run(collisions=a.collisions)
            rates[name].append(a.collisions / (time.perf_counter() - t0))
            end = s.snapshot()
            if want is None:
                want = end
            same[name] = same[name] and _same(end, want)
            if "parallel" in out:
                report[name] = out["parallel"]
            print(f"round {r} {name}: {rates[name][-1]:,.0f} collisions/s, same {same[name]}", file=sys.stderr, flush=True)
    base = float(np.median(rates["seq"]))
    result = {
        "what": "LatticeSimulation.run(collisions=C) on the parallel engine against the sequential engine, end to end",
        "command": " ".join(["python", "bench/parallel_python.py", *(argv if argv is not None else sys.argv[1:])]),
        "commit": subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip(),
        "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), "load_before": load0, "load_after": os.getloadavg()[0],
        "cores": os.cpu_count(), "dim": a.dim, "n": a.n, "phi": a.phi, "collisions": a.collisions, "rounds": a.rounds,
        "variants": {k: {"per_s": float(np.median(v)), "per_s_min": float(min(v)), "per_s_max": float(max(v)),
                         "speedup": float(np.median(v)) / base, "speedup_min": float(min(v)) / base,
                         "speedup_max": float(max(v)) / base, "same_as_sequential": same[k],
                         "report": report.get(k)} for k, v in rates.items()},
    }
    d = os.path.dirname(os.path.abspath(a.json))
    with tempfile.NamedTemporaryFile("w", dir=d, delete=False, suffix=".tmp") as f:
        json.dump(result, f, indent=1)
    os.replace(f.name, a.json)
    for k, v in result["variants"].items():
        print(f"{k}: {v['per_s']:,.0f} collisions/s ({v['speedup']:.2f}x, {v['speedup_min']:.2f}-{v['speedup_max']:.2f}), "
              f"same {v['same_as_sequential']}")
    return 0 if all(same.values()) else 1


if __name__ == "__main__":
    sys.exit(main())
