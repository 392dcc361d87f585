"""Independent replicas of one equation-of-state point: are the block errors honest?

The dense study (`python -m revcol.studies.equilibrium dense`) quotes Z with a block-average error from one
long run. Slow modes that outlive the blocks make such an error too small. Here the same point
runs from `--seeds` independent starts (each its own random state and warm-up, as the study
makes them), and the spread of the runs' Z is set against the errors their blocks claimed:

    scatter ratio = sample sd of Z over the runs / rms of their block errors

(about 1 when the block errors are honest; its own uncertainty is about 1 / sqrt(2 (k - 1))
for k runs). The mean of the runs with the error from their spread, sd / sqrt(k), is an
estimate of Z that does not lean on the blocks, compared with Liu's equation of state (the
study's reference) and, for two laws, with each other.

    PYTHONPATH=<package> python -m revcol.studies.eos_replicas --dim 2 --phi 0.6 --n 4000 \
        --laws specular flux --per-particle 20000 --seeds 12 --first-seed 201 \
        --cores 0 1 --json bench/results/eos_replicas_2d_phi0.6_n4000.json

Each run is a child process (`revcol.studies.equilibrium dense`, pinned with taskset to one of `--cores`
when given; runs on different cores go side by side). The JSON is written atomically, and
rewritten after every run (a stopped study keeps what it finished).

    python -m revcol.studies.eos_replicas --fit STUDY_N1.json STUDY_N2.json ... --json FIT.json

fits Z(N) = Z(inf) + a / N through the studies' replica means (one point at several N), per law
and pooled, and sets Z(inf) against Liu's form in its own error.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from concurrent.futures import ThreadPoolExecutor

from .. import _core
from .._io import atomic_open


def _write_atomic(path: str, obj) -> None:
    with atomic_open(path) as f:
        json.dump(obj, f, indent=1)
        f.write("\n")


def _git_commit() -> str:
    """The commit of the checkout the study is run from (the current directory)."""
    try:
        head = subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True, text=True, check=True)
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, check=True)
        return head.stdout.strip() + ("-dirty" if dirty.stdout.strip() else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def _module_path() -> str:
    """The compiled module the runs import (the children inherit this environment)."""
    return _core.__file__


def _run(args, law: str, seed: int, core, workdir: str) -> dict:
    out = os.path.join(workdir, f"{law}_{seed}.json")
    cmd = [sys.executable, "-m", "revcol.studies.equilibrium", "dense", "--dim", str(args.dim), "--phi", str(args.phi),
           "--n", str(args.n), "--laws", law, "--per-particle", str(args.per_particle), "--seed", str(seed),
           "--json", out]
    if core is not None and shutil.which("taskset"):
        cmd = ["taskset", "-c", str(core)] + cmd
    t0 = time.time()
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"run {law} seed {seed} failed ({proc.returncode}): {proc.stderr[-2000:]}")
    with open(out) as f:
        row = json.load(f)["dense"][0]
    return {"law": law, "seed": seed, "z": row["z"][0], "z_block_error": row["z"][1], "blocks": row["blocks"],
            "z_ref": row["z_ref"], "collisions": row["collisions"], "cpu_s": row["cpu_s"],
            "wall_s": time.time() - t0, "core": core}


def summarize(runs: list[dict]) -> dict:
    """Per law: the runs' mean, its error from their spread, the scatter ratio; the difference of two laws."""
    out = {}
    for law in sorted({r["law"] for r in runs}):
        zs = [r["z"] for r in runs if r["law"] == law]
        es = [r["z_block_error"] for r in runs if r["law"] == law]
        k = len(zs)
        if k < 2:
            continue
        mean = sum(zs) / k
        sd = math.sqrt(sum((z - mean) ** 2 for z in zs) / (k - 1))
        rms_block = math.sqrt(sum(e * e for e in es) / k)
        ref = next(r["z_ref"] for r in runs if r["law"] == law)
        se = sd / math.sqrt(k)
        out[law] = {"runs": k, "mean": mean, "error_from_spread": se, "sd": sd, "rms_block_error": rms_block,
                    "scatter_ratio": sd / rms_block if rms_block > 0 else None,
                    "scatter_ratio_uncertainty": 1.0 / math.sqrt(2.0 * (k - 1)),
                    "z_ref_liu": ref, "sigmas_from_liu": (mean - ref) / se if se > 0 else None,
                    "relative_to_liu": mean / ref - 1.0}
    laws = list(out)
    if len(laws) == 2:
        a, b = out[laws[0]], out[laws[1]]
        se = math.hypot(a["error_from_spread"], b["error_from_spread"])
        out[f"{laws[1]} - {laws[0]}"] = {"difference": b["mean"] - a["mean"], "error": se,
                                         "sigmas": (b["mean"] - a["mean"]) / se if se > 0 else None}
    return out


def _line_fit(points: list[tuple[float, float, float]]) -> dict:
    """Weighted least squares of y = y_inf + a x over (x, y, error): y_inf, a, their errors, chi2 / dof."""
    w = [1.0 / (e * e) for _, _, e in points]
    sw = sum(w)
    sx = sum(wi * x for wi, (x, _, _) in zip(w, points))
    sy = sum(wi * y for wi, (_, y, _) in zip(w, points))
    sxx = sum(wi * x * x for wi, (x, _, _) in zip(w, points))
    sxy = sum(wi * x * y for wi, (x, y, _) in zip(w, points))
    det = sw * sxx - sx * sx
    y_inf = (sxx * sy - sx * sxy) / det
    a = (sw * sxy - sx * sy) / det
    chi2 = sum(wi * (y - y_inf - a * x) ** 2 for wi, (x, y, _) in zip(w, points))
    dof = len(points) - 2
    return {"z_inf": y_inf, "z_inf_error": math.sqrt(sxx / det), "a": a, "a_error": math.sqrt(sw / det),
            "chi2": chi2, "dof": dof}


def fit(paths: list[str]) -> dict:
    """Z(N) = Z(inf) + a / N through the replica means of several sizes (their errors from the
    spread), per law and for the laws pooled (one Z(inf) and one a for both: equilibrium says
    they share them); Z(inf) against Liu's form in its own errors."""
    studies = []
    for p in paths:
        with open(p) as f:
            studies.append(json.load(f))
    laws = sorted({law for s in studies for law in s["summary"] if " - " not in law})
    out = {"sizes": sorted(s["n"] for s in studies), "files": [os.path.basename(p) for p in paths], "fits": {}}
    pooled = []
    for law in laws:
        pts = [(1.0 / s["n"], s["summary"][law]["mean"], s["summary"][law]["error_from_spread"])
               for s in studies if law in s["summary"]]
        pooled += pts
        if len(pts) >= 2:
            out["fits"][law] = _line_fit(pts)
    if len(laws) > 1 and len(pooled) >= 3:
        out["fits"]["pooled"] = _line_fit(pooled)
    ref = studies[0]["summary"][laws[0]]["z_ref_liu"]
    for f in out["fits"].values():
        f["z_ref_liu"] = ref
        f["sigmas_from_liu"] = (f["z_inf"] - ref) / f["z_inf_error"]
        f["relative_to_liu"] = f["z_inf"] / ref - 1.0
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dim", type=int, choices=(2, 3))
    ap.add_argument("--phi", type=float)
    ap.add_argument("--n", type=int)
    ap.add_argument("--laws", nargs="+", default=["specular", "flux"], choices=["specular", "flux", "uniform", "paper"])
    ap.add_argument("--per-particle", type=int, default=20000, help="observed collisions per particle per run")
    ap.add_argument("--seeds", type=int, default=8, help="independent runs per law (>= 2)")
    ap.add_argument("--first-seed", type=int, default=1)
    ap.add_argument("--cores", type=int, nargs="*", default=None, help="pin runs to these cores, one run per core at a time")
    ap.add_argument("--json", required=True)
    ap.add_argument("--fit", nargs="+", metavar="STUDY_JSON",
                    help="no runs: fit Z(N) = Z(inf) + a / N through these studies' replica means (sizes of one point)")
    args = ap.parse_args(argv)
    if args.fit:
        res = fit(args.fit)
        res["command"] = " ".join([os.path.basename(sys.executable)] + sys.argv)
        _write_atomic(args.json, res)
        print(json.dumps(res["fits"], indent=1))
        return 0
    if args.dim is None or args.phi is None or args.n is None:
        ap.error("--dim, --phi and --n are needed to run a study (or --fit)")
    if args.seeds < 2:
        ap.error("--seeds must be >= 2 (the spread needs two runs)")
    if args.n < 2 or args.per_particle < 1 or not (0.0 < args.phi < 1.0):
        ap.error("--n >= 2, --per-particle >= 1 and 0 < --phi < 1")
    cores = args.cores or [None]
    res = {"what": "independent replicas of one equation-of-state point (python -m revcol.studies.eos_replicas)",
           "command": " ".join([os.path.basename(sys.executable)] + sys.argv),
           "commit": _git_commit(), "module": _module_path(),
           "dim": args.dim, "phi": args.phi, "n": args.n, "per_particle": args.per_particle,
           "started_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
           "uptime_start": subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip(),
           "runs": []}
    jobs = [(law, args.first_seed + s) for s in range(args.seeds) for law in args.laws]
    free = list(cores)
    lock = threading.Lock()

    def work(job):
        with lock:
            core = free.pop(0)
        try:
            return _run(args, job[0], job[1], core, workdir)
        finally:
            with lock:
                free.append(core)

    with tempfile.TemporaryDirectory() as workdir, ThreadPoolExecutor(max_workers=len(cores)) as pool:
        for r in pool.map(work, jobs):
            res["runs"].append(r)
            res["summary"] = summarize(res["runs"])
            print(f"{r['law']:9s} seed {r['seed']}: Z {r['z']:.5f} +- {r['z_block_error']:.5f} ({r['wall_s']:.0f} s)",
                  flush=True)
            _write_atomic(args.json, res)
    res["finished_utc"] = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
    res["uptime_end"] = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    _write_atomic(args.json, res)
    print(json.dumps(res["summary"], indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
