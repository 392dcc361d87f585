"""The parallel lattice engine end to end from Python: ``LatticeSimulation.run(collisions=C)``
with ``set_parallel(workers)`` against the sequential engine, then ``run_back(collisions=C)``
(the parallel engine in run_back's reversed frame, or the sequential run_back), interleaved
(seq, K2, seq, K2, ...), from one warmed state; each run's end state compared with the
sequential one bit for bit, and each run back's with the warmed state it started from. What it
measures beyond ``revcol-bench --bench parallel/...`` (the engine alone): the probe and the tail
a stop at a collision count costs, building the K views (a run back: flipped), and restoring the
committed state into the simulation; the sequential run_back's two rebuilds of its search (its
frame flipped and back).

    PYTHONPATH=build-dev/pkg python bench/parallel_python.py --dim 2 --n 1000000 --phi 0.5 \\
        --collisions 2000000 10000000 --rounds 3 --json bench/results/lattice_parallel_python.json

With ``--memory``, each variant runs alone in a fresh process instead (a random start, one
collision per particle of warm-up, then one run(collisions=C)), and the file gives each
process's peak resident set (ru_maxrss) against the sequential one's, per C: the memory a
parallel run costs.
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


def measure(cls, s0: dict, collisions: int, rounds: int, workers: list[int]) -> dict:
    """One call of run(collisions) per variant and round, interleaved, from the state s0."""
    names = ["seq"] + [f"K{w}_w{w}" for w in workers]
    rates: dict[str, list[float]] = {k: [] for k in names}
    back: dict[str, list[float]] = {k: [] for k in names}
    same: dict[str, bool] = {k: True for k in names}
    report: dict[str, dict] = {}
    back_report: dict[str, dict] = {}
    want = None
    for r in range(rounds):
        for name in names:
            s = cls.from_snapshot(s0)
            if name != "seq":
                w = int(name.split("_w")[1])
                s.set_parallel(w, lps=w)
            t0 = time.perf_counter()
            out = s.run(collisions=collisions)
            rates[name].append(collisions / (time.perf_counter() - t0))
            end = s.snapshot()
            if want is None:
                want = end
            same[name] = same[name] and _same(end, want)
            if "parallel" in out:
                report[name] = out["parallel"]
            t0 = time.perf_counter()
            out = s.run_back(collisions=collisions)  # back to the warmed state, exactly
            back[name].append(collisions / (time.perf_counter() - t0))
            same[name] = same[name] and _same(s.snapshot(), s0)
            if "parallel" in out:
                back_report[name] = out["parallel"]
            print(f"{collisions} round {r} {name}: {rates[name][-1]:,.0f} collisions/s, back {back[name][-1]:,.0f}, "
                  f"same {same[name]}", file=sys.stderr, flush=True)
    base, base_back = float(np.median(rates["seq"])), float(np.median(back["seq"]))

    def stats(v: list[float], b: float) -> dict:
        return {"per_s": float(np.median(v)), "per_s_min": float(min(v)), "per_s_max": float(max(v)),
                "speedup": float(np.median(v)) / b, "speedup_min": float(min(v)) / b, "speedup_max": float(max(v)) / b}
    return {k: {**stats(v, base), "back": {**stats(back[k], base_back), "report": back_report.get(k)},
                "same_as_sequential": same[k], "report": report.get(k)}
            for k, v in rates.items()}


def _child(a) -> None:
    """One variant alone: prints the process's peak resident set (KiB) after its run."""
    import resource
    cls = LatticeSimulation3D if a.dim == 3 else LatticeSimulation
    sim = cls.random(a.n, phi=a.phi, seed=1)
    sim.run(collisions=a.n)
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    if a.child > 1:
        sim.set_parallel(a.child, lps=a.child)
    sim.run(collisions=a.collisions[0])
    print(json.dumps({"rss_before_kib": before, "rss_peak_kib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss}))


def memory(a, argv) -> dict:
    """Peak RSS per variant and collision count, each in a fresh process (sequential, then K = 2, 4, ... per count)."""
    out: dict[str, dict] = {}
    for c in a.collisions:
        for w in [1] + a.workers:
            cmd = [sys.executable, os.path.abspath(__file__), "--dim", str(a.dim), "--n", str(a.n), "--phi", str(a.phi),
                   "--collisions", str(c), "--child", str(w), "--json", "-"]
            r = json.loads(subprocess.run(cmd, capture_output=True, text=True, check=True).stdout.strip().splitlines()[-1])
            out.setdefault(str(c), {})["seq" if w == 1 else f"K{w}_w{w}"] = r
            print(f"{c} collisions, workers {w}: peak {r['rss_peak_kib'] / 1024:.0f} MiB (before the run {r['rss_before_kib'] / 1024:.0f})",
                  file=sys.stderr, flush=True)
        seq = out[str(c)]["seq"]["rss_peak_kib"]
        for v in out[str(c)].values():
            v["over_sequential"] = v["rss_peak_kib"] / seq
    return out


def _write(result: dict, path: str) -> None:
    d = os.path.dirname(os.path.abspath(path))
    with tempfile.NamedTemporaryFile("w", dir=d, delete=False, suffix=".tmp") as f:
        json.dump(result, f, indent=1)
    os.replace(f.name, path)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--dim", type=int, choices=(2, 3), default=2)
    p.add_argument("--n", type=int, default=1_000_000)
    p.add_argument("--phi", type=float, default=0.5)
    p.add_argument("--collisions", type=int, nargs="+", default=[2_000_000], help="collisions per run() call")
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--workers", type=int, nargs="+", default=[2], help="parallel variants, 2 or more (K = workers LPs)")
    p.add_argument("--memory", action="store_true", help="peak RSS per variant, each in a fresh process")
    p.add_argument("--child", type=int, default=0, help=argparse.SUPPRESS)
    p.add_argument("--gravity", type=float, default=0.0,
                   help="a field along the last axis (walled; the others periodic), kT / sigma: the slabs cut across it")
    p.add_argument("--json", required=True)
    a = p.parse_args(argv)
    if a.child:
        _child(a)
        return 0
    cls = LatticeSimulation3D if a.dim == 3 else LatticeSimulation
    load0 = os.getloadavg()[0]
    if a.memory:
        result = {"what": "peak RSS of LatticeSimulation.run(collisions=C), sequential and parallel, each variant in a fresh process",
                  "command": " ".join(["python", "bench/parallel_python.py", *(argv if argv is not None else sys.argv[1:])]),
                  "commit": subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip(),
                  "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), "load_before": load0,
                  "dim": a.dim, "n": a.n, "phi": a.phi, "runs": memory(a, argv)}  # (no field: --gravity is for the timing)
        result["load_after"] = os.getloadavg()[0]
        _write(result, a.json)
        return 0
    field = {} if a.gravity == 0.0 else {"boundary": ["periodic"] * (a.dim - 1) + ["wall"],
                                         "gravity": [0.0] * (a.dim - 1) + [a.gravity]}
    sim = cls.random(a.n, phi=a.phi, seed=1, **field)
    sim.run(collisions=a.n)  # warmed: the start's relaxation behind it
    s0 = sim.snapshot()
    runs = {c: measure(cls, s0, c, a.rounds, a.workers) for c in a.collisions}
    result = {
        "what": "LatticeSimulation.run(collisions=C), then run_back(collisions=C), on the parallel engine against the "
                "sequential engine, end to end",
        "command": " ".join(["python", "bench/parallel_python.py", *(argv if argv is not None else sys.argv[1:])]),
        "commit": subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip(),
        "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), "load_before": load0, "load_after": os.getloadavg()[0],
        "cores": os.cpu_count(), "dim": a.dim, "n": a.n, "phi": a.phi, "gravity": a.gravity, "rounds": a.rounds,
        "runs": {str(c): v for c, v in runs.items()},
    }
    _write(result, a.json)
    for c, variants in runs.items():
        for k, v in variants.items():
            b = v["back"]
            print(f"{c} collisions per call, {k}: {v['per_s']:,.0f} collisions/s ({v['speedup']:.2f}x, "
                  f"{v['speedup_min']:.2f}-{v['speedup_max']:.2f}), back {b['per_s']:,.0f} ({b['speedup']:.2f}x, "
                  f"{b['speedup_min']:.2f}-{b['speedup_max']:.2f}), same {v['same_as_sequential']}")
    return 0 if all(v["same_as_sequential"] for r in runs.values() for v in r.values()) else 1


if __name__ == "__main__":
    sys.exit(main())
