"""Studies of the 2D lattice engine (revcol/lattice/engine.hpp, LATTICE.md). Writes
bench/results/lattice_*.json.

    python3 bench/lattice_study.py throughput [--bin build-dev/revcol-bench] [--collisions 2e5]
    PYTHONPATH=build-dev/pkg python3 bench/lattice_study.py roundtrip [--n 1000] [--phi 0.3] [--max 1e6] [--law flux] [--boundary both]
    python3 bench/lattice_study.py all

throughput: one revcol-bench invocation running the lattice family (periodic N = 1e4 at area
fractions 0.3 and 0.5, walls at 0.3) and, timed the same way, the float engine on the same
periodic gases (lattice/float/...), so the two are measured side by side on the same (shared)
machine; collisions per second forward and reverse (wall clock and CPU time), bit-exactness of the
round trip, redraws and log entries per collision. Writes lattice_throughput.json and prints the
lattice / float ratios.

roundtrip: one gas (N, area fraction, periodic and walls) run forward in steps of 10x collisions up
to --max and back to the start after each step, from Python: bit-for-bit restoration of positions,
velocities, stream counters, X and clock; X's bit length, rare-log entries, redraws, multi-body and
wall-body ticks, energy drift (relative) and momentum drift (lattice units) after the forward run.
Under the uniform law X grows (the entropy the non-equilibrium law produces): its bit length after
each forward run is the measurement. Writes lattice_roundtrip_<law>_n<N>_phi<phi>.json.
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

HERE = os.path.dirname(os.path.abspath(__file__))
RESULTS = os.path.join(HERE, "results")


def throughput(args) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "b.json")
        cmd = [args.bin, "--bench", "lattice/",
               "--collisions", str(int(float(args.collisions))), "--repeats", str(args.repeats), "--json", out]
        t0 = time.time()
        subprocess.run(cmd, check=True)
        with open(out) as f:
            res = json.load(f)
    res = {"command": " ".join(cmd), "wall_seconds": time.time() - t0, "results": res}
    rates: dict = {}
    for row in res["results"]["results"]:  # revcol-bench rows: bench, metric, median, values
        rates.setdefault(row["bench"], {})[row["metric"]] = row["median"]
    ratios = {}
    for phi in ("0.3", "0.5"):
        lat, flo = rates.get(f"lattice/periodic/n10000/phi{phi}"), rates.get(f"lattice/float/n10000/phi{phi}")
        if lat and flo:
            ratios[phi] = {m: lat[m] / flo[m] for m in ("forward_per_s", "reverse_per_s",
                                                        "forward_cpu_per_s", "reverse_cpu_per_s")}
    res["lattice_over_float"] = ratios
    print(json.dumps(ratios, indent=1))
    path = os.path.join(RESULTS, "lattice_throughput.json")
    with open(path, "w") as f:
        json.dump(res, f, indent=1)
    print("wrote", path)
    return res


def _same(a: dict, b: dict) -> bool:
    keys = ["clock", "origin", "collisions", "x", "v", "streams", "bits", "log_index", "log_redraws",
            "group_index", "group_drawer", "group_size", "group_members"]
    return all(np.array_equal(np.asarray(a[k]), np.asarray(b[k])) for k in keys)


def roundtrip(args) -> dict:
    from revcol.lattice import LatticeSimulation
    rows = []
    for boundary in (("periodic", "wall") if args.boundary == "both" else (args.boundary,)):
        sim = LatticeSimulation.random(n=args.n, phi=args.phi, boundary=boundary, seed=args.seed,
                                       init="lattice" if args.phi > 0.35 else "auto", law=args.law)
        s0 = sim.state()
        nc = args.n * 10
        while nc <= float(args.max):
            t0 = time.perf_counter()
            sim.run(collisions=nc)
            t1 = time.perf_counter()
            d = sim.diagnostics()
            sim.run_back()
            t2 = time.perf_counter()
            ok = _same(sim.state(), s0)
            row = {"boundary": boundary, "law": args.law, "n": args.n, "phi": args.phi, "collisions": nc,
                   "per_particle": 2 * nc / args.n, "bit_for_bit": bool(ok),
                   "forward_s": t1 - t0, "reverse_s": t2 - t1,
                   "bits_length": d["bits_length"], "log_entries": d["log_entries"],
                   "log_entries_written": d["log_entries_written"],
                   "redraws": d["redraws"], "multi_body": d["multi_body"], "wall_body": d["wall_body"],
                   "group_bounces": d["group_bounces"],
                   "energy_drift": d["energy_drift"], "momentum_drift": list(d["momentum_drift"]),
                   "quantization": sim.quantization}
            print(json.dumps(row))
            rows.append(row)
            if not ok:
                break
            nc *= 10
    tag = "" if args.boundary == "both" else f"_{args.boundary}"
    path = os.path.join(RESULTS, f"lattice_roundtrip_{args.law}_n{args.n}_phi{args.phi}{tag}.json")
    with open(path, "w") as f:
        json.dump({"rows": rows}, f, indent=1)
    print("wrote", path)
    return {"rows": rows}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("what", choices=["throughput", "roundtrip", "all"])
    ap.add_argument("--bin", default=os.path.join(HERE, "..", "build-dev", "revcol-bench"))
    ap.add_argument("--collisions", default="2e5")
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--n", type=int, default=1000)
    ap.add_argument("--phi", type=float, default=0.3)
    ap.add_argument("--max", default="1e5")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--law", default="flux", choices=["flux", "uniform"])
    ap.add_argument("--boundary", default="both", choices=["both", "periodic", "wall"])
    a = ap.parse_args(argv)
    os.makedirs(RESULTS, exist_ok=True)
    if a.what in ("throughput", "all"):
        throughput(a)
    if a.what in ("roundtrip", "all"):
        roundtrip(a)
    return 0


if __name__ == "__main__":
    sys.exit(main())
