"""Two builds of the parallel lattice engine side by side, interleaved: each round runs every
variant once per build (old, then new), each run a fresh `revcol-bench` process that measures
the sequential engine and the variant from the same warmed state, unpinned (two workers need
both cores). The load average is recorded before each run.

    python3 bench/parallel_ab.py OLD_BUILD NEW_BUILD --variant parallel/d3/n1000000/phi0.3:2:2 \\
        [--variant BENCH:K:W ...] [--rounds 3] [--collisions 1000000] --json OUT.json

A variant is BENCH:K:W (K logical processes on W worker threads). Each run's whole benchmark
JSON is kept under `runs`; `summary` has per variant and build the median and range over the
rounds of the speed-up over the sequential engine (of the same process), and the medians of
undone journal entries, rollbacks and events per collision. The builds' commits are read from
their source trees when they are git worktrees (else given with --old-commit / --new-commit).
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

from ab_compare import _load, write_json  # (bench/ is the script's directory)


def _run(build: str, bench: str, k: int, w: int, collisions: int) -> dict:
    env = dict(os.environ, REVCOL_PARALLEL=f"rounds=1,lps={k},workers={w}")
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "b.json")
        subprocess.run([os.path.join(build, "revcol-bench"), "--repeats", "1", "--bench", bench, "--collisions", str(collisions),
                        "--json", out], check=True, capture_output=True, env=env)
        with open(out) as f:
            return json.load(f)


def _row(run: dict, k: int, w: int) -> dict:
    m = {r["metric"]: r["median"] for r in run["results"]}
    t = f"K{k}_w{w}"
    return dict(speedup=m[f"speedup_{t}"], same=m[f"same_{t}"], undone=m[f"undone_per_collision_{t}"],
                rollbacks_per_1k=m[f"rollbacks_per_1k_{t}"], events=m[f"events_per_collision_{t}"],
                seq_per_s=m["seq_per_s"], parallel_per_s=m[f"{t}_per_s"])


def summarize(rows: list[dict], commits: dict) -> list[dict]:
    groups: dict = {}
    for r in rows:
        groups.setdefault((r["bench"], r["lps"], r["workers"], r["build"]), []).append(r)
    out = []
    for (bench, k, w, b), rs in sorted(groups.items()):
        sp = [r["speedup"] for r in rs]
        med = lambda key: statistics.median(r[key] for r in rs)  # noqa: E731
        out.append(dict(bench=bench, lps=k, workers=w, build=b, commit=commits.get(b), rounds=len(rs),
                        speedup_median=statistics.median(sp), speedup_min=min(sp), speedup_max=max(sp),
                        undone_per_collision_median=med("undone"), rollbacks_per_1k_median=med("rollbacks_per_1k"),
                        events_per_collision_median=med("events"), seq_per_s_median=med("seq_per_s"),
                        parallel_per_s_median=med("parallel_per_s"), all_bit_exact=all(r["same"] == 1 for r in rs),
                        loads_before=[r["load"] for r in rs], starts_utc=[r["start"] for r in rs]))
    return out


def _commit(build: str, given: str | None) -> str | None:
    if given:
        return given
    cache = os.path.join(build, "CMakeCache.txt")
    try:
        with open(cache) as f:
            src = next(line.split("=", 1)[1].strip() for line in f if line.startswith("CMAKE_HOME_DIRECTORY"))
        return subprocess.run(["git", "-C", src, "rev-parse", "--short", "HEAD"], check=True, capture_output=True, text=True).stdout.strip()
    except (OSError, StopIteration, subprocess.CalledProcessError):
        return None


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--variant", action="append", required=True, help="BENCH:K:W (repeatable)")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--collisions", type=int, default=1_000_000)
    ap.add_argument("--old-commit")
    ap.add_argument("--new-commit")
    ap.add_argument("--json", required=True)
    args = ap.parse_args()
    variants = []
    for v in args.variant:
        bench, k, w = v.rsplit(":", 2)
        variants.append((bench, int(k), int(w)))
    builds = {"old": args.old, "new": args.new}
    commits = {"old": _commit(args.old, args.old_commit), "new": _commit(args.new, args.new_commit)}
    rows, runs = [], {}
    for r in range(1, args.rounds + 1):
        for bench, k, w in variants:
            for b in ("old", "new"):
                load, start = _load(), time.strftime("%H:%M:%S", time.gmtime())
                run = _run(builds[b], bench, k, w, args.collisions)
                runs[f"{bench.replace('/', '_')}_{r}_{b}_K{k}_w{w}"] = run
                row = dict(bench=bench, round=r, build=b, lps=k, workers=w, load=load, start=start, **_row(run, k, w))
                rows.append(row)
                print(f"{bench} round {r} {b} K={k} w={w} load {load:.2f}: speed-up {row['speedup']:.3f}, undone "
                      f"{row['undone']:.3f}, events {row['events']:.3f}, same {row['same']}", flush=True)
    doc = dict(bundle="the parallel lattice engine, two builds interleaved (bench/parallel_ab.py)", commits=commits,
               command=" ".join(sys.argv), collisions=args.collisions, summary=summarize(rows, commits), rows=rows, runs=runs)
    write_json(doc, args.json)
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
