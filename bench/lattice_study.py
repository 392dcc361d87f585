"""Studies of the 2D lattice engine (revcol/lattice/engine.hpp, LATTICE.md). Writes
bench/results/lattice_*.json.

    python3 bench/lattice_study.py throughput [--bin build-dev/revcol-bench] [--collisions 2e5] [--rounds 5] [--cpu 1] [--dim 3]
    PYTHONPATH=build-dev/pkg python3 bench/lattice_study.py roundtrip [--n 1000] [--phi 0.3] [--max 1e6] [--law flux] [--boundary both]
    python3 bench/lattice_study.py all

throughput: the lattice engine and, timed the same way, the float engine on the same periodic
gases (N = 1e4 and 1e5, area fractions 0.3 and 0.5; revcol-bench lattice/periodic/... and
lattice/float/...), interleaved: every round runs each case once per engine, alternating which goes
first, one process per run pinned to one core, the load average recorded before each run.
Collisions per second forward and reverse (wall clock and CPU time), medians and ranges over
rounds, and the lattice / float ratios of the medians. Writes lattice_throughput.json. With --dim 3:
the 3D lattice engine and the float engine on the same sphere gases (N = 1e3 and 1e4, volume
fractions 0.3 and 0.45; revcol-bench lattice3d/periodic/... and lattice3d/float/...), written to
lattice_throughput3d.json.

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


#: the gases of the issue's table: (N, area fraction); periodic, lattice and float side by side
THROUGHPUT_CASES = [(10000, "0.3"), (10000, "0.5"), (100000, "0.3"), (100000, "0.5")]
#: the 3D gases (N, volume fraction) with both engines in revcol-bench (lattice3d/...)
THROUGHPUT_CASES_3D = [(1000, "0.3"), (10000, "0.1"), (10000, "0.3"), (10000, "0.45")]


def _case_names(dim: int, n: int, phi: str) -> tuple[str, str]:
    """revcol-bench names of (lattice, float) for a gas."""
    fam = "lattice3d" if dim == 3 else "lattice"
    return f"{fam}/periodic/n{n}/phi{phi}", f"{fam}/float/n{n}/phi{phi}"
METRICS = ("forward_per_s", "reverse_per_s", "forward_cpu_per_s", "reverse_cpu_per_s")


def _bench_once(args, name: str, collisions: int) -> dict:
    """One revcol-bench process for one case (pinned to --cpu unless -1): its metrics."""
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "b.json")
        cmd = [args.bin, "--bench", name, "--collisions", str(collisions), "--repeats", "1", "--json", out]
        if args.cpu >= 0:
            cmd = ["taskset", "-c", str(args.cpu)] + cmd
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        with open(out) as f:
            res = json.load(f)
    return {row["metric"]: row["median"] for row in res["results"] if row["bench"] == name}


def throughput(args) -> dict:
    """Lattice and float engines on the same periodic gases, interleaved: each round runs every
    case once per engine, alternating which engine goes first, one process per run pinned to one
    core, with the load average before each run; the medians and ranges over rounds and the
    lattice / float ratios of the medians."""
    base = int(float(args.collisions))
    raw: dict = {}
    loads = []
    t0 = time.time()
    cases = THROUGHPUT_CASES_3D if args.dim == 3 else THROUGHPUT_CASES
    for r in range(args.rounds):
        for n, phi in cases:
            names = _case_names(args.dim, n, phi)
            for name in (names if r % 2 == 0 else names[::-1]):
                loads.append(os.getloadavg()[0])
                m = _bench_once(args, name, base if n <= 10000 else 2 * base)
                raw.setdefault(name, []).append(m)
                print(f"round {r} {name:34s} forward {m['forward_per_s']:.3g}/s reverse {m['reverse_per_s']:.3g}/s "
                      f"(load {loads[-1]:.2f})", flush=True)
    summary, ratios = {}, {}
    for name, runs in raw.items():
        summary[name] = {m: {"median": float(np.median([x[m] for x in runs])), "min": min(x[m] for x in runs),
                             "max": max(x[m] for x in runs)} for m in METRICS}
        for m in ("bit_exact", "log_entries", "redraws_per_collision", "multi_body", "events_per_collision"):
            if m in runs[0]:
                summary[name][m] = [x[m] for x in runs]
    for n, phi in cases:
        lat, flo = (summary[name] for name in _case_names(args.dim, n, phi))
        ratios[f"n{n}/phi{phi}"] = {m: lat[m]["median"] / flo[m]["median"] for m in METRICS}
    res = {"command": " ".join(sys.argv), "dim": args.dim, "rounds": args.rounds, "collisions_per_run": base,
           "collisions_per_run_n100000": 2 * base, "cpu": args.cpu, "wall_seconds": time.time() - t0,
           "load_before_runs": {"min": min(loads), "median": float(np.median(loads)), "max": max(loads)},
           "summary": summary, "lattice_over_float": ratios, "raw": raw,
           "commit": subprocess.run(["git", "-C", HERE, "rev-parse", "HEAD"], capture_output=True,
                                    text=True).stdout.strip()}
    print(json.dumps(ratios, indent=1))
    path = os.path.join(RESULTS, "lattice_throughput3d.json" if args.dim == 3 else "lattice_throughput.json")
    with open(path + ".tmp", "w") as f:
        json.dump(res, f, indent=1)
    os.replace(path + ".tmp", path)
    print("wrote", path)
    return res


def _same(a: dict, b: dict) -> bool:
    keys = ["clock", "origin", "collisions", "x", "v", "streams", "bits", "log_index", "log_redraws",
            "group_index", "group_drawer", "group_size", "group_members", "group_kind", "group_v"]
    return all(np.array_equal(np.asarray(a[k]), np.asarray(b[k])) for k in keys)


def roundtrip(args) -> dict:
    from revcol.lattice import LatticeSimulation
    rows = []
    for boundary in (("periodic", "wall") if args.boundary == "both" else (args.boundary,)):
        sim = LatticeSimulation.random(n=args.n, phi=args.phi, boundary=boundary, seed=args.seed,
                                       init="crystal" if args.phi > 0.35 else "auto", law=args.law)
        s0 = sim.snapshot()
        nc = args.n * 10
        while nc <= float(args.max):
            t0 = time.perf_counter()
            sim.run(collisions=nc)
            t1 = time.perf_counter()
            d = sim.diagnostics()
            sim.run_back()
            t2 = time.perf_counter()
            ok = _same(sim.snapshot(), s0)
            row = {"boundary": boundary, "law": args.law, "n": args.n, "phi": args.phi, "collisions": nc,
                   "per_particle": 2 * nc / args.n, "bit_for_bit": bool(ok),
                   "forward_s": t1 - t0, "reverse_s": t2 - t1,
                   "bits_length": d["bits_length"], "log_entries": d["log_entries"],
                   "log_entries_written": d["log_entries_written"],
                   "redraws": d["redraws"], "multi_body": d["multi_body"], "wall_body": d["wall_body"],
                   "group_resolves": d["group_resolves"], "group_bounces": d["group_bounces"],
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
    ap.add_argument("--rounds", type=int, default=5, help="throughput: interleaved rounds")
    ap.add_argument("--cpu", type=int, default=1, help="throughput: core to pin each run to (-1: none)")
    ap.add_argument("--n", type=int, default=1000)
    ap.add_argument("--phi", type=float, default=0.3)
    ap.add_argument("--max", default="1e5")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--law", default="flux", choices=["flux", "uniform"])
    ap.add_argument("--dim", type=int, default=2, choices=[2, 3], help="throughput: 2D disks or 3D spheres")
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
