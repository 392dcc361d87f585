"""Two builds side by side, interleaved (A B A B ...), for a change that must keep the engine's
figures: throughput of `revcol-bench --bench engine/<case>`, and the horizon and memory
studies of bench/engine_study.py run against each build's staged package.

    python3 bench/ab_compare.py throughput OLD_BUILD NEW_BUILD [--rounds 5] [--cpu 1]
        [--case engine/d3/n10000/phi0.45 ...] [--custom "d=3,n=10976,phi=0.45,warm=30" ...]
        [--json bench/results/ab_throughput.json]
    python3 bench/ab_compare.py studies    OLD_BUILD NEW_BUILD
    python3 bench/ab_compare.py callgrind  OLD_BUILD NEW_BUILD [--case engine/d2/n10000/phi0.5 ...]
        [--setting lattice/periodic/n10000/phi0.3:REVCOL_LATTICE=observe=1 ...] [--both CASE:VAR=VALUE ...]

A build directory is one made by scripts/dev_build.sh (it holds revcol-bench and pkg/).
Throughput: each round runs every case once per build, alternating which build goes first,
one process per run pinned to one core (`taskset -c CPU`), and records the load average
before each run; the report gives per build and case the median and the range over rounds,
new/old of the medians, and the paired ratios: new/old of the two runs of each round (taken
minutes apart at most, so a slow phase of a shared host hits both), their median and
quartiles, which resolve a few per cent where the medians of either build swing by 10%.
`--case` chooses named cases (default: all five below; `floor/pair2d` and `floor/pair3d`
report the operator's ns per collision and its ratio to the floor instead of throughput);
`--custom SPEC` adds an `engine/custom` case with REVCOL_ENGINE=SPEC (any number of each; in
callgrind too, run on both builds).
Callgrind: instructions per collision, which a loaded host does not change: for each case and
build, valgrind's Ir of the whole benchmark at two collision counts C1 < C2, and their
difference over C2 - C1 (forward and back, the start and setup cancelling); `--setting
CASE:VAR=VALUE` adds a case run with that environment on the new build (e.g. an observed
lattice run) against the plain case on the old build: the setting's cost; `--both CASE:VAR=VALUE`
runs it so on both builds (a change to what the setting runs). Default cases: the float engine 2D and 3D and the lattice engine 2D and 3D.
Studies: engine_study.py horizon and memory, once per build, with each build's package on
PYTHONPATH; their JSON goes to a temporary folder and the report keeps both. Writes
bench/results/ab_<what>.json (or --json).
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
RESULTS = os.path.join(HERE, "results")

CASES = ["engine/d3/n10000/phi0.3", "engine/d3/n10000/phi0.45", "engine/d3/n100000/phi0.3",
         "engine/d3/n100000/phi0.45", "engine/d2/n10000/phi0.5"]


def write_json(doc: dict, path: str) -> None:
    """doc as JSON at path, atomically (a temporary file renamed over it)."""
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(doc, f, indent=1)
    os.replace(tmp, path)


def _load() -> float:
    with open("/proc/loadavg") as f:
        return float(f.read().split()[0])


def _bench(build: str, case: str, collisions: int, cpu: int | None) -> dict:
    """One run; `case` is a named bench or "engine/custom:SPEC" (REVCOL_ENGINE=SPEC)."""
    name, _, spec = case.partition(":")
    env = dict(os.environ, REVCOL_ENGINE=spec) if spec else None
    with tempfile.TemporaryDirectory() as tmp:
        js = os.path.join(tmp, "b.json")
        cmd = [os.path.join(build, "revcol-bench"), "--bench", name, "--collisions", str(collisions),
               "--repeats", "1", "--json", js]
        if cpu is not None and shutil.which("taskset"):
            cmd = ["taskset", "-c", str(cpu)] + cmd
        subprocess.run(cmd, check=True, capture_output=True, env=env)
        with open(js) as f:
            data = json.load(f)
    return {r["metric"]: r["median"] for r in data["results"] if r["bench"] == name}


CALLGRIND_CASES = ["engine/d2/n10000/phi0.5", "engine/d3/n10000/phi0.3", "lattice/periodic/n10000/phi0.3",
                   "lattice3d/periodic/n10000/phi0.3"]


def _instructions(build: str, case: str, collisions: int) -> int:
    """valgrind --tool=callgrind's total Ir of one benchmark run; `case` is NAME or NAME:VAR=VALUE."""
    name, _, setting = case.partition(":")
    env = dict(os.environ)
    if setting:
        var, _, value = setting.partition("=")
        env[var] = value
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "cg.out")
        cmd = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", os.path.join(build, "revcol-bench"),
               "--bench", name, "--collisions", str(collisions), "--repeats", "1", "--json", os.path.join(tmp, "b.json")]
        subprocess.run(cmd, check=True, capture_output=True, env=env)
        with open(out) as f:
            for line in f:
                if line.startswith("summary:") or line.startswith("totals:"):
                    return int(line.split()[1])
    raise RuntimeError(f"no instruction total from callgrind for {case}")


def callgrind(args) -> dict:
    custom = [f"engine/custom:REVCOL_ENGINE={c}" for c in (args.custom or [])] + (args.both or [])
    cases = (args.case or ([] if custom else CALLGRIND_CASES)) + (args.setting or []) + custom
    c1, c2 = args.c1, args.c2
    rows = []
    for case in cases:
        row = {"case": case}
        for label, build in (("old", args.old), ("new", args.new)):
            # a setting runs on the new build only; the old one runs the case without it (a
            # --custom or --both case runs on both: the same gas)
            run = case if label == "new" or case in custom else case.partition(":")[0]
            a, b = _instructions(build, run, c1), _instructions(build, run, c2)
            row[label] = (b - a) / (c2 - c1)
        row["new_over_old"] = row["new"] / row["old"]
        rows.append(row)
        print(f"{case:60s} old {row['old']:9.1f}  new {row['new']:9.1f}  Ir per collision  new/old {row['new_over_old']:.4f}")
    return {"c1": c1, "c2": c2, "rows": rows}


def _metrics(case: str) -> tuple[str, ...]:
    """What a case reports: throughput for engine cases; the operator's time and its ratio to
    the bare floor for `floor/...` cases (lower is better there)."""
    if case.startswith("floor/"):
        return ("exact_forward_ns", "exact_reverse_ns", "ratio_forward", "ratio_reverse")
    return ("forward_per_s", "reverse_per_s")


def _paired(new: list[float], old: list[float]) -> dict:
    """new/old per round: median and quartiles (the middle half) of the ratios."""
    ratios = [a / b for a, b in zip(new, old)]
    q = statistics.quantiles(ratios, n=4, method="inclusive") if len(ratios) > 1 else [ratios[0]] * 3
    return dict(median=statistics.median(ratios), quartiles=[q[0], q[2]], ratios=ratios)


def _summary(values: list[float]) -> dict:
    return dict(median=statistics.median(values), min=min(values), max=max(values), runs=values)


def throughput(args) -> dict:
    builds = {"old": args.old, "new": args.new}
    cases = (args.case or ([] if args.custom else CASES)) + [f"engine/custom:{c}" for c in (args.custom or [])]
    raw = {b: {c: [] for c in cases} for b in builds}
    loads = []
    for k in range(args.rounds):
        order = ["old", "new"] if k % 2 == 0 else ["new", "old"]
        for case in cases:
            nc = 2 * args.collisions if "n100000" in case else args.collisions
            for b in order:
                loads.append(_load())
                r = _bench(builds[b], case, nc, args.cpu)
                raw[b][case].append(r)
                shown = " ".join(f"{m} {r[m]:.4g}" for m in _metrics(case))
                print(f"round {k} {b:3s} {case:28s} {shown} (load {loads[-1]:.2f})", flush=True)
    rows = []
    for case in cases:
        row = dict(case=case)
        for b in builds:
            for m in _metrics(case):
                row[f"{b}_{m}"] = _summary([r[m] for r in raw[b][case]])
        for m in _metrics(case):
            row[f"new_over_old_{m}"] = row[f"new_{m}"]["median"] / row[f"old_{m}"]["median"]
            row[f"paired_new_over_old_{m}"] = _paired([r[m] for r in raw["new"][case]],
                                                       [r[m] for r in raw["old"][case]])
        rows.append(row)
    for r in rows:
        if r["case"].startswith("floor/"):
            print(f"{r['case']:28s} " + " | ".join(
                f"{m} old {r[f'old_{m}']['median']:.4g} new {r[f'new_{m}']['median']:.4g} "
                f"(paired new/old {_fmt(r[f'paired_new_over_old_{m}'])})" for m in _metrics(r["case"])))
            continue
        print(f"{r['case']:28s} forward old {r['old_forward_per_s']['median']:.3g} "
              f"[{r['old_forward_per_s']['min']:.3g}, {r['old_forward_per_s']['max']:.3g}] "
              f"new {r['new_forward_per_s']['median']:.3g} "
              f"[{r['new_forward_per_s']['min']:.3g}, {r['new_forward_per_s']['max']:.3g}] "
              f"new/old {r['new_over_old_forward_per_s']:.3f} (paired {_fmt(r['paired_new_over_old_forward_per_s'])}) | "
              f"reverse new/old {r['new_over_old_reverse_per_s']:.3f} (paired {_fmt(r['paired_new_over_old_reverse_per_s'])})")
    return dict(rows=rows, load_avg=_summary(loads), rounds=args.rounds, cpu=args.cpu,
                collisions=args.collisions)


def _fmt(p: dict) -> str:
    return f"{p['median']:.3f} [{p['quartiles'][0]:.3f}, {p['quartiles'][1]:.3f}]"


def _study(build: str, study: str, extra: list[str]) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        # engine_study.py writes into bench/results next to itself: run a copy in tmp
        os.makedirs(os.path.join(tmp, "results"))
        shutil.copy(os.path.join(HERE, "engine_study.py"), tmp)
        env = dict(os.environ, PYTHONPATH=os.path.join(os.path.abspath(build), "pkg"), MPLBACKEND="Agg")
        t0 = time.perf_counter()
        subprocess.run([sys.executable, os.path.join(tmp, "engine_study.py"), study] + extra, check=True,
                       env=env, capture_output=True)
        with open(os.path.join(tmp, "results", f"engine_{study}.json")) as f:
            out = json.load(f)
        out["wall_s"] = time.perf_counter() - t0
        return out


def studies(args) -> dict:
    out = {}
    for study in ("horizon", "memory"):
        for b, build in (("old", args.old), ("new", args.new)):
            load = _load()
            r = _study(build, study, [])
            r["load_before"] = load
            out[f"{study}_{b}"] = r
            print(f"{study} {b}: done in {r['wall_s']:.0f} s (load {load:.2f})", flush=True)
    for key in ("horizon",):
        old, new = out[f"{key}_old"], out[f"{key}_new"]
        same = [(a["err_x"], a["err_v"]) == (b["err_x"], b["err_v"]) for a, b in zip(old["rows"], new["rows"])]
        out[f"{key}_rows_identical"] = all(same) and len(old["rows"]) == len(new["rows"])
        for s_old, s_new in zip(old["horizon"], new["horizon"]):
            print(f"horizon d={s_old['dim']} phi={s_old['phi']} {s_old['mode']}: old {s_old['horizon_collisions']} "
                  f"new {s_new['horizon_collisions']}")
        print(f"horizon rows bit-identical: {out[f'{key}_rows_identical']}")
    mo, mn = out["memory_old"], out["memory_new"]
    print(f"memory: peak RSS growth old {100 * mo['peak_rss_growth']:+.3f}% new {100 * mn['peak_rss_growth']:+.3f}%; "
          f"last row old {mo['rows'][-1]} new {mn['rows'][-1]}")
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("what", choices=["throughput", "studies", "callgrind"])
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--collisions", type=int, default=1_000_000, help="per run (twice that at N = 1e5)")
    ap.add_argument("--cpu", type=int, default=1, help="core to pin each run to (taskset); -1: no pinning")
    ap.add_argument("--case", action="append", help="a named engine bench, or floor/pair2d, floor/pair3d (repeatable; default: the five engine cases)")
    ap.add_argument("--custom", action="append", help="an engine/custom case: its REVCOL_ENGINE (repeatable)")
    ap.add_argument("--setting", action="append", help="callgrind: CASE:VAR=VALUE, a case run with that environment")
    ap.add_argument("--both", action="append",
                    help="callgrind: CASE:VAR=VALUE run with that environment on both builds (an observed run's cost)")
    ap.add_argument("--c1", type=int, default=2000, help="callgrind: the smaller collision count")
    ap.add_argument("--c2", type=int, default=22000, help="callgrind: the larger collision count")
    ap.add_argument("--json", help="where the report goes (default bench/results/ab_<what>.json)")
    args = ap.parse_args()
    if args.cpu is not None and args.cpu < 0:
        args.cpu = None
    report = {"throughput": throughput, "studies": studies, "callgrind": callgrind}[args.what](args)
    report.update(command=" ".join(sys.argv), date=time.strftime("%Y-%m-%d %H:%M:%S %Z"), machine=os.uname().nodename,
                  old=os.path.abspath(args.old), new=os.path.abspath(args.new))
    os.makedirs(RESULTS, exist_ok=True)
    path = args.json or os.path.join(RESULTS, f"ab_{args.what}.json")
    write_json(report, path)
    print(f"wrote {os.path.relpath(path)}")


if __name__ == "__main__":
    main()
