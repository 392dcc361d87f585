"""The lattice engine's neighbour search in a field: the cell grid against neighbour lists (the
shell 3D takes without a field; 0.3 in 2D) and the automatic search, on gases under gravity,
interleaved (cells, lists, auto; auto, lists, cells; ...), each run a fresh process pinned to one
core, the 1-minute load recorded before each. Every run goes C collisions forward and back, and must
end on the bits it started from; both searches must reach the same state forward (the same
collisions: the lists are only a faster way to find them).

    PYTHONPATH=build-dev/pkg python bench/lattice_field_search.py --rounds 3 --cpu 1 \\
        [--collisions 500000] [--json bench/results/lattice_field_search.json]

Writes the medians with their ranges and the ratios lists / cells and auto / cells of the medians per gas.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from ab_compare import write_json  # noqa: E402  (atomic JSON, the benches' one writer)

# (name, dim, n, packing fraction, g in kT / sigma along the last axis, walls on the others)
GASES = [
    ("3D N=10^4 phi=0.1 g=-1 slab", 3, 10_000, 0.1, -1.0, False),
    ("3D N=10^4 phi=0.2 g=-1 slab", 3, 10_000, 0.2, -1.0, False),
    ("3D N=10^4 phi=0.3 g=-1 slab", 3, 10_000, 0.3, -1.0, False),
    ("3D N=10^4 phi=0.3 g=-1 walls", 3, 10_000, 0.3, -1.0, True),
    ("3D N=10^5 phi=0.3 g=-1 slab", 3, 100_000, 0.3, -1.0, False),
    ("2D N=10^4 phi=0.5 g=-1 channel", 2, 10_000, 0.5, -1.0, False),
]

CHILD = r"""
import hashlib, json, sys, time
import numpy as np
from revcol.lattice import LatticeSimulation, LatticeSimulation3D
dim, n, phi, g, walls, search, c = json.loads(sys.argv[1])
cls = LatticeSimulation3D if dim == 3 else LatticeSimulation
bounds = ["wall" if walls else "periodic"] * (dim - 1) + ["wall"]
sim = cls.random(n, phi=phi, boundary=bounds, gravity=[0.0] * (dim - 1) + [g], seed=3)
sim.search = search
sim.run(collisions=max(n, 20000))  # settle a little (untimed)
def digest(s):
    h = hashlib.sha256()
    for k in ("x", "v", "streams", "particle_collisions", "bits", "bits_size", "clock", "collisions", "log_count"):
        h.update(np.ascontiguousarray(np.asarray(s[k])).tobytes())
    return h.hexdigest()[:16]
start = sim.snapshot()
t0 = time.process_time(); sim.run(collisions=c); fwd = time.process_time() - t0
end = digest(sim.snapshot())
t0 = time.process_time(); sim.run_back(collisions=c); back = time.process_time() - t0
print(json.dumps({"search": sim.search, "forward_per_s": c / fwd, "reverse_per_s": c / back, "end": end,
                  "back_to_start": digest(sim.snapshot()) == digest(start)}))
"""


def list_shell(dim: int, n: int, phi: float) -> float:
    """The lists' shell measured: the one 3D's automatic search takes for the same gas without a
    field (the engine's own choice, read from a gas built so), 0.3 in 2D."""
    if dim == 2:
        return 0.3
    from revcol.lattice import LatticeSimulation3D
    return float(LatticeSimulation3D.random(n, phi=phi, boundary=["periodic", "periodic", "wall"], seed=3).search)


def _load() -> float:
    with open("/proc/loadavg") as f:
        return float(f.read().split()[0])


def _run(gas, search: str | float, collisions: int, cpu: int) -> dict:
    _, dim, n, phi, g, walls = gas
    cmd = [sys.executable, "-c", CHILD, json.dumps([dim, n, phi, g, walls, search, collisions])]
    if cpu >= 0:
        cmd = ["taskset", "-c", str(cpu)] + cmd
    load = _load()
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    r = json.loads(out.strip().splitlines()[-1])
    r["load_before"] = load
    return r


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--collisions", type=int, default=500_000)
    ap.add_argument("--cpu", type=int, default=1, help="core to pin each run to (-1: none)")
    ap.add_argument("--json", default=os.path.join(HERE, "results", "lattice_field_search.json"))
    args = ap.parse_args()
    try:
        commit = subprocess.run(["git", "-C", HERE, "rev-parse", "HEAD"], capture_output=True, text=True).stdout.strip()
    except OSError:
        commit = "unknown"
    rows = []
    for gas in GASES:
        runs = {"cells": [], "lists": []}
        shell = list_shell(gas[1], gas[2], gas[3])
        for r in range(args.rounds):
            order = ["cells", "lists", "auto"] if r % 2 == 0 else ["auto", "lists", "cells"]
            for s in order:
                res = _run(gas, shell if s == "lists" else s, args.collisions, args.cpu)
                if not res["back_to_start"]:
                    raise SystemExit(f"{gas[0]}, {s}: the run back did not end on its starting bits")
                runs.setdefault(s, []).append(res)
        ends = {x["end"] for k in runs for x in runs[k]}
        if len(ends) != 1:
            raise SystemExit(f"{gas[0]}: the searches ended on different states: {ends}")
        row = {"gas": gas[0], "dim": gas[1], "n": gas[2], "phi": gas[3], "g": gas[4], "walls_all_round": gas[5],
               "shell": runs["lists"][0]["search"], "auto_search": runs["auto"][0]["search"],
               "same_state": True, "back_to_start": True}
        for k in ("cells", "lists", "auto"):
            for d in ("forward_per_s", "reverse_per_s"):
                v = [x[d] for x in runs[k]]
                row[f"{k}_{d}"] = {"median": statistics.median(v), "min": min(v), "max": max(v)}
            row[f"{k}_load_before"] = [x["load_before"] for x in runs[k]]
        for d in ("forward_per_s", "reverse_per_s"):
            row[f"ratio_{d}"] = row[f"lists_{d}"]["median"] / row[f"cells_{d}"]["median"]
            row[f"auto_ratio_{d}"] = row[f"auto_{d}"]["median"] / row[f"cells_{d}"]["median"]
        rows.append(row)
        print(f"{gas[0]}: lists/cells fwd {row['ratio_forward_per_s']:.2f} rev {row['ratio_reverse_per_s']:.2f} "
              f"(cells {row['cells_forward_per_s']['median']:.0f}/s, shell {row['shell']:.2f}); automatic "
              f"{row['auto_search']}: {row['auto_ratio_forward_per_s']:.2f} / {row['auto_ratio_reverse_per_s']:.2f}", flush=True)
    doc = {"command": "python bench/lattice_field_search.py " + " ".join(sys.argv[1:]), "commit": commit,
           "utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), "rounds": args.rounds,
           "collisions": args.collisions, "cpu": args.cpu, "rows": rows}
    write_json(doc, args.json)
    print("wrote", args.json)


if __name__ == "__main__":
    main()
