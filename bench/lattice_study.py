"""Throughput of the lattice engine against the float engine (docs/lattice.md), both timed by
revcol-bench. Writes bench/results/lattice_throughput.json (2D) or lattice_throughput3d.json (3D).

    python3 bench/lattice_study.py throughput [--bin build-dev/revcol-bench] [--collisions 2e5] [--rounds 5] [--cpu 1] [--dim 3]

throughput: the lattice engine and, timed the same way, the float engine on the same periodic
gases (N = 1e4 and 1e5, area fractions 0.3, 0.5 and 0.7; revcol-bench lattice/periodic/... and
lattice/float/...), interleaved: every round runs each case once per engine, alternating which goes
first, one process per run pinned to one core, the load average recorded before each run.
Collisions per second forward and reverse (wall clock and CPU time), medians and ranges over
rounds, and the lattice / float ratios of the medians. Writes lattice_throughput.json. With --dim 3:
the 3D lattice engine and the float engine on the same sphere gases (N = 1e3 and 1e4, volume
fractions 0.3 and 0.45; revcol-bench lattice3d/periodic/... and lattice3d/float/...), written to
lattice_throughput3d.json.

order: what the storage order costs (issue 57): one gas (default lattice3d/periodic/n100000/phi0.3)
under REVCOL_LATTICE settings, interleaved: the start's space order with no re-sort, a random order
(shuffle=1) with none, and a random order re-sorted after one neutral event per particle
(shuffle=1,resort=1: the re-sorts' cost counted in); every run back bit exact. Writes
lattice_storage_order.json.

    python3 bench/lattice_study.py order [--case lattice3d/periodic/n100000/phi0.3] [--collisions 1e6] [--rounds 5]

The lattice engine's bit-for-bit round trips at scale are tests/long/lattice_validation.py.
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
THROUGHPUT_CASES = [(10000, "0.3"), (10000, "0.5"), (10000, "0.7"), (100000, "0.3"), (100000, "0.5"), (100000, "0.7")]
#: the 3D gases (N, volume fraction) with both engines in revcol-bench (lattice3d/...)
THROUGHPUT_CASES_3D = [(1000, "0.3"), (10000, "0.1"), (10000, "0.3"), (10000, "0.45")]


def _case_names(dim: int, n: int, phi: str) -> tuple[str, str]:
    """revcol-bench names of (lattice, float) for a gas."""
    fam = "lattice3d" if dim == 3 else "lattice"
    return f"{fam}/periodic/n{n}/phi{phi}", f"{fam}/float/n{n}/phi{phi}"
METRICS = ("forward_per_s", "reverse_per_s", "forward_cpu_per_s", "reverse_cpu_per_s")


def _bench_once(args, name: str, collisions: int, setting: str = "") -> dict:
    """One revcol-bench process for one case (pinned to --cpu unless -1), with REVCOL_LATTICE =
    ``setting`` when given: its metrics."""
    env = dict(os.environ, REVCOL_LATTICE=setting) if setting else None
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "b.json")
        cmd = [args.bin, "--bench", name, "--collisions", str(collisions), "--repeats", "1", "--json", out]
        if args.cpu >= 0:
            cmd = ["taskset", "-c", str(args.cpu)] + cmd
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, env=env)
        with open(out) as f:
            res = json.load(f)
    return {row["metric"]: row["median"] for row in res["results"] if row["bench"] == name}


def _medians(runs: list, metrics) -> dict:
    """Per metric, the median and range over runs (each a dict of metrics)."""
    return {m: {"median": float(np.median([x[m] for x in runs])), "min": min(x[m] for x in runs),
                "max": max(x[m] for x in runs)} for m in metrics}


def _range(xs) -> dict:
    return {"min": min(xs), "median": float(np.median(xs)), "max": max(xs)}


def _commit() -> str:
    return subprocess.run(["git", "-C", HERE, "rev-parse", "HEAD"], capture_output=True, text=True).stdout.strip()


def _save(res: dict, name: str) -> None:
    """Writes bench/results/<name> atomically (a temporary file, then a rename)."""
    path = os.path.join(RESULTS, name)
    with open(path + ".tmp", "w") as f:
        json.dump(res, f, indent=1)
    os.replace(path + ".tmp", path)
    print("wrote", path)


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
        summary[name] = _medians(runs, METRICS)
        for m in ("bit_exact", "log_entries", "redraws_per_collision", "multi_body", "events_per_collision"):
            if m in runs[0]:
                summary[name][m] = [x[m] for x in runs]
    for n, phi in cases:
        lat, flo = (summary[name] for name in _case_names(args.dim, n, phi))
        ratios[f"n{n}/phi{phi}"] = {m: lat[m]["median"] / flo[m]["median"] for m in METRICS}
    res = {"command": " ".join(sys.argv), "dim": args.dim, "rounds": args.rounds, "collisions_per_run": base,
           "collisions_per_run_n100000": 2 * base, "cpu": args.cpu, "wall_seconds": time.time() - t0,
           "load_before_runs": _range(loads), "summary": summary, "lattice_over_float": ratios, "raw": raw,
           "commit": _commit()}
    print(json.dumps(ratios, indent=1))
    _save(res, "lattice_throughput3d.json" if args.dim == 3 else "lattice_throughput.json")
    return res


#: the storage orders compared by `order`: REVCOL_LATTICE settings of revcol-bench
ORDER_SETTINGS = {"space": "shuffle=0,resort=0", "random": "shuffle=1,resort=0", "random, re-sorted": "shuffle=1,resort=1"}


def storage_order(args) -> dict:
    """The case under each ORDER_SETTINGS, interleaved (the order reversed every other round),
    one process per run pinned to --cpu; medians, ranges and the ratios to space order."""
    n = int(float(args.collisions))
    raw: dict = {k: [] for k in ORDER_SETTINGS}
    loads = []
    names = list(ORDER_SETTINGS)
    for r in range(args.rounds):
        for k in (names if r % 2 == 0 else names[::-1]):
            loads.append(os.getloadavg()[0])
            m = _bench_once(args, args.case, n, ORDER_SETTINGS[k])
            if m.get("bit_exact") != 1.0:
                raise RuntimeError(f"{args.case} ({k}): the run back did not end on its starting bits")
            raw[k].append(m)
            print(f"round {r} {k:18s} forward {m['forward_per_s']:.4g}/s reverse {m['reverse_per_s']:.4g}/s "
                  f"re-sorts {m.get('resorts', 0):.0f} (load {loads[-1]:.2f})", flush=True)
    summary = {k: _medians(runs, ("forward_per_s", "reverse_per_s")) for k, runs in raw.items()}
    for k in summary:
        summary[k]["resorts"] = [x.get("resorts", 0) for x in raw[k]]
        summary[k]["over_space"] = {m: summary[k][m]["median"] / summary["space"][m]["median"]
                                    for m in ("forward_per_s", "reverse_per_s")}
    res = {"command": " ".join(sys.argv), "case": args.case, "collisions_per_run": n, "rounds": args.rounds,
           "cpu": args.cpu, "settings": ORDER_SETTINGS,
           "load_before_runs": _range(loads), "summary": summary, "raw": raw, "commit": _commit()}
    print(json.dumps({k: v["over_space"] for k, v in summary.items()}, indent=1))
    _save(res, "lattice_storage_order.json")
    return res


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("what", choices=["throughput", "order"])
    ap.add_argument("--case", default="lattice3d/periodic/n100000/phi0.3", help="order: the revcol-bench case")
    ap.add_argument("--bin", default=os.path.join(HERE, "..", "build-dev", "revcol-bench"))
    ap.add_argument("--collisions", default=None, help="per run (default 2e5; order: 1e6)")
    ap.add_argument("--rounds", type=int, default=5, help="throughput: interleaved rounds")
    ap.add_argument("--cpu", type=int, default=1, help="throughput: core to pin each run to (-1: none)")
    ap.add_argument("--dim", type=int, default=2, choices=[2, 3], help="throughput: 2D disks or 3D spheres")
    a = ap.parse_args(argv)
    os.makedirs(RESULTS, exist_ok=True)
    a.collisions = a.collisions or ("1e6" if a.what == "order" else "2e5")
    if a.what == "order":
        storage_order(a)
    else:
        throughput(a)
    return 0


if __name__ == "__main__":
    sys.exit(main())
