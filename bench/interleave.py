#!/usr/bin/env python3
"""Interleaved benchmark rounds: every selected revcol-bench benchmark once per round, in turn
(A B C A B C ...), each in its own process pinned to one core, the load average recorded beside
each run (and its peak RSS, by /usr/bin/time); then per benchmark the median of every metric with its range over the rounds, and the
ratios of the main rate between variants of one case. On a shared machine this is the fair way
to compare variants: a burst of load hits every variant of a round alike.

    python bench/interleave.py --binary build-dev/revcol-bench --bench specular/ --rounds 5 \\
        --collisions 1000000 --cpu 1 --json bench/results/lattice_specular_speed.json

Benchmark names are family/variant/case...; ``--ratio A:B`` (default lattice:float and
lattice:flux) divides variant A's median forward and reverse rates by B's for each case.

Two builds compared (a change against its parent): give ``--binary LABEL=PATH`` twice; every
benchmark runs under each build in turn, its runs are named ``LABEL|benchmark``, and the ratios
are of the first build's rates to the second's, per round:

    python bench/interleave.py --binary new=build-dev/revcol-bench --binary old=/tmp/old/build/revcol-bench \
        --bench lattice/periodic/n100000 --rounds 5 --cpu 1 --json bench/results/x.json
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def _names(binary: str, prefixes: list) -> list:
    out = subprocess.run([binary, "--list"], capture_output=True, text=True, check=True).stdout
    names = [line.split("\t")[0] for line in out.splitlines() if line.strip()]
    return [n for n in names if any(n.startswith(p) for p in prefixes)]


def _run_one(binary: str, name: str, collisions: int, cpu: int | None) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "b.json")
        rss = os.path.join(tmp, "rss")
        timer = ["/usr/bin/time", "-f", "%M", "-o", rss] if os.path.exists("/usr/bin/time") else []
        cmd = timer + ([] if cpu is None else ["taskset", "-c", str(cpu)]) + [
            binary, "--bench", name, "--repeats", "1", "--collisions", str(collisions), "--json", path]
        subprocess.run(cmd, capture_output=True, text=True, check=True)
        data = json.load(open(path))
        peak = float(open(rss).read().split()[-1]) * 1024 if timer else None
    out = {r["metric"]: r["values"][0] for r in data["results"] if r["bench"] == name}
    if not out:
        raise RuntimeError(f"{name}: not in revcol-bench's output")
    if peak is not None:
        out["peak_rss_bytes"] = peak  # the whole process: setup, run and the benchmark's own snapshots
    return out


def _split(name: str) -> tuple:
    family, variant, *case = name.split("/")
    return family, variant, "/".join(case)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--binary", action="append", required=True, help="PATH, or LABEL=PATH twice (two builds)")
    ap.add_argument("--bench", action="append", required=True, help="name prefix (repeatable)")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--collisions", type=float, default=1e6)
    ap.add_argument("--cpu", type=int, default=None, help="pin every run to this core (taskset)")
    ap.add_argument("--ratio", action="append", default=None, help="A:B variant pairs (default lattice:float, lattice:flux)")
    ap.add_argument("--json", required=True)
    a = ap.parse_args()
    builds = [b.split("=", 1) if "=" in b else ["", b] for b in a.binary]
    if len(builds) > 2 or (len(builds) == 2 and not all(lab for lab, _ in builds)):
        sys.exit("interleave: one --binary PATH, or two as LABEL=PATH")
    names = _names(builds[0][1], a.bench)
    if not names:
        sys.exit(f"interleave: no benchmark matches {a.bench}")
    jobs = [(f"{lab}|{n}" if lab else n, path, n) for n in names for lab, path in builds]
    runs = {key: [] for key, _, _ in jobs}
    loads = []
    t0 = time.time()
    for r in range(a.rounds):
        for key, path, n in jobs:
            n_label = key
            load = os.getloadavg()[0]
            m = _run_one(path, n, int(a.collisions), a.cpu)
            m["_load1"] = load
            runs[key].append(m)
            loads.append(load)
            print(f"round {r + 1}/{a.rounds} {n_label}: forward {m.get('forward_per_s', float('nan')):.4g}/s "
                  f"reverse {m.get('reverse_per_s', float('nan')):.4g}/s (load {load:.2f})", flush=True)
    summary = {}
    for n, reps in runs.items():
        summary[n] = {k: {"median": statistics.median(r[k] for r in reps), "min": min(r[k] for r in reps),
                          "max": max(r[k] for r in reps)} for k in reps[0] if not k.startswith("_")}
    ratios = {}
    if len(builds) == 2:  # the first build over the second, per benchmark and round
        (la, _), (lb, _) = builds
        for n in names:
            row = {}
            for k in runs[f"{la}|{n}"][0]:
                if k.startswith("_") or not isinstance(runs[f"{la}|{n}"][0][k], (int, float)):
                    continue
                ra = [x[k] / y[k] for x, y in zip(runs[f"{la}|{n}"], runs[f"{lb}|{n}"]) if y[k]]
                if ra:
                    row[k] = {"median": statistics.median(ra), "min": min(ra), "max": max(ra)}
            ratios[f"{la}/{lb} {n}"] = row
    for pair in ([] if len(builds) == 2 else a.ratio or ["lattice:float", "lattice:flux"]):
        va, vb = pair.split(":")
        for n in names:
            fam, var, case = _split(n)
            other = f"{fam}/{vb}/{case}"
            if var != va or other not in summary:
                continue
            row = {}
            for k in ("forward_per_s", "reverse_per_s"):
                ra = [x[k] / y[k] for x, y in zip(runs[n], runs[other])]  # per round: the same load
                row[k] = {"median": statistics.median(ra), "min": min(ra), "max": max(ra)}
            ratios[f"{va}/{vb} {case}"] = row
    out = {"command": "python bench/interleave.py " + " ".join(sys.argv[1:]), "rounds": a.rounds,
           "collisions": int(a.collisions), "cpu": a.cpu, "wall_s": time.time() - t0,
           "loadavg1": {"median": statistics.median(loads), "min": min(loads), "max": max(loads)},
           "commit": subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=HERE, capture_output=True,
                                    text=True).stdout.strip(),
           "summary": summary, "ratios": ratios, "runs": runs}
    folder = os.path.dirname(os.path.abspath(a.json))
    fd, tmp = tempfile.mkstemp(prefix=".interleave-", suffix=".json.tmp", dir=folder)
    with os.fdopen(fd, "w") as f:  # written beside, then renamed over: never half a file
        f.write(json.dumps(out, indent=1) + "\n")
    os.replace(tmp, a.json)
    for k, row in ratios.items():
        if "forward_per_s" not in row or "reverse_per_s" not in row:
            print(f"{k}: " + ", ".join(f"{m} {v['median']:.3f}" for m, v in row.items()))
            continue
        print(f"{k}: forward {row['forward_per_s']['median']:.3f} [{row['forward_per_s']['min']:.3f}, "
              f"{row['forward_per_s']['max']:.3f}]  reverse {row['reverse_per_s']['median']:.3f} "
              f"[{row['reverse_per_s']['min']:.3f}, {row['reverse_per_s']['max']:.3f}]")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
