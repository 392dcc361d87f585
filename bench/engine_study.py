"""Benchmarks of the event-driven engine (docs/engine.md): the round-trip horizon (error against
run length), memory over long runs and throughput. Writes bench/results/engine_*. (Relaxation to
Maxwell-Boltzmann speeds is the study `python -m revcol.studies.maxwell`.)

    PYTHONPATH=build-dev/pkg python3 bench/engine_study.py horizon   [--n 1000] [--max 1e6]
    PYTHONPATH=build-dev/pkg python3 bench/engine_study.py memory    [--n 10000] [--max 1e7]
    PYTHONPATH=build-dev/pkg python3 bench/engine_study.py throughput [--bin build-dev/revcol-bench] [--rounds 5] [--cpu 1]
    PYTHONPATH=build-dev/pkg python3 bench/engine_study.py all

horizon: for each (d, phi) a fresh random gas (N particles, periodic box, exact mode, flux
law) runs N_c collisions forward and then back to its start time; the error is
max |x - x0| / L (periodic images folded) and max |v - v0| / max |v0|. The horizon is the
largest N_c on the grid with both below 1e-9, in collisions per particle (2 N_c / N).
A 1D gas is run to 1e6 collisions the same way.

throughput: revcol-bench --bench engine/<case> --collisions 1e6 (2e6 for N = 1e5), one fresh
process per run (peak RSS per case), every case once per round and the rounds interleaved
(--rounds, default 5; --cpu K pins to core K); medians and ranges with the load recorded per
run, merged into engine_throughput.json with the reference rates of the fastest public EDMD
code measured on this machine.

memory: one process per run (peak RSS is the process's VmHWM); the RSS after 1e5, 1e6 and
1e7 collisions at N = 1e4 spheres, and the engine's log bytes.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
RESULTS = os.path.join(HERE, "results")


def _revcol():
    import revcol
    return revcol


def roundtrip(dim, n, phi, nc, seed=1, mode="exact", law="flux", boundary="periodic"):
    revcol = _revcol()
    sim = revcol.Simulation.random(n=n, dim=dim, phi=phi, seed=seed, mode=mode, law=law, boundary=boundary)
    x0, v0 = sim.positions, sim.velocities
    st = sim.snapshot() if hasattr(sim, "snapshot") else sim.state()  # builds before the rename (bench/ab_compare.py)
    box, per = st["box"], st["periodic"].astype(bool)
    t0 = time.perf_counter()
    sim.run(collisions=nc)
    t1 = time.perf_counter()
    sim.run_back()
    t2 = time.perf_counter()
    dx = np.abs(sim.positions - x0)
    dx[:, per] = np.minimum(dx[:, per], np.abs(dx[:, per] - box[per]))
    d = sim.diagnostics()
    return dict(dim=dim, n=n, phi=phi, collisions=int(nc), mode=mode, law=law,
                per_particle=2.0 * nc / n,
                err_x=float((dx / box).max()),
                err_v=float(np.abs(sim.velocities - v0).max() / np.abs(v0).max()),
                net_collisions=int(d["net_collisions"]),
                reverse_failures=int(d["events"]["reverse_failures"]),
                log_bytes=int(d["log_bytes"]),
                forward_s=t1 - t0, back_s=t2 - t1)


def horizon(args):
    grid = [int(round(m * 10 ** e)) for e in range(2, 7) for m in (1, 2, 5)]
    grid = [g for g in grid if g <= args.max]
    rows = []
    curves = [(2, 0.3, "exact"), (2, 0.5, "exact"), (3, 0.3, "exact"), (3, 0.45, "exact"), (2, 0.3, "paper")]
    for dim, phi, mode in curves:
        for nc in grid:
            r = roundtrip(dim, args.n, phi, nc, mode=mode)
            rows.append(r)
            print(f"d={dim} phi={phi} {mode:5s} Nc={nc:>8d} ({r['per_particle']:8.1f}/particle) "
                  f"err_x={r['err_x']:.2e} err_v={r['err_v']:.2e}", flush=True)
    r1 = roundtrip(1, args.n, 0.3, int(args.max))
    rows.append(r1)
    print(f"d=1 phi=0.3 Nc={int(args.max)} err_x={r1['err_x']:.2e} err_v={r1['err_v']:.2e}")
    summary = []
    for dim, phi, mode in curves:
        sel = [r for r in rows if r["dim"] == dim and r["phi"] == phi and r["mode"] == mode]
        ok = [r for r in sel if r["err_x"] <= 1e-9 and r["err_v"] <= 1e-9]
        h = max((r["collisions"] for r in ok), default=0)
        summary.append(dict(dim=dim, phi=phi, mode=mode, horizon_collisions=h,
                            horizon_per_particle=2.0 * h / args.n))
    for s in summary:
        print(f"horizon d={s['dim']} phi={s['phi']} {s['mode']}: N_c = {s['horizon_collisions']} "
              f"({s['horizon_per_particle']:.1f} collisions per particle)")
    os.makedirs(RESULTS, exist_ok=True)
    out = dict(command=" ".join(sys.argv), n=args.n, rows=rows, horizon=summary,
               one_d=dict(collisions=r1["collisions"], err_x=r1["err_x"], err_v=r1["err_v"]))
    with open(os.path.join(RESULTS, "engine_horizon.json"), "w") as f:
        json.dump(out, f, indent=1)
    with open(os.path.join(RESULTS, "engine_horizon.csv"), "w") as f:
        keys = list(rows[0].keys())
        f.write(",".join(keys) + "\n")
        for r in rows:
            f.write(",".join(str(r[k]) for k in keys) + "\n")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    for dim, phi, mode in curves:
        sel = [r for r in rows if r["dim"] == dim and r["phi"] == phi and r["mode"] == mode]
        c = np.array([r["per_particle"] for r in sel])
        lab = f"d={dim}, phi={phi}" + (" (paper mode)" if mode == "paper" else "")
        ax[0].loglog(c, [max(r["err_v"], 1e-17) for r in sel], "o-", label=lab)
        ax[1].loglog(c, [max(r["err_x"], 1e-17) for r in sel], "o-", label=lab)
    for a, t in zip(ax, ["velocities: max |v - v0| / max |v0|", "positions: max |x - x0| / L"]):
        a.axhline(1e-9, color="k", ls=":", lw=1)
        a.set_xlabel("collisions per particle (2 N_c / N), forward then back")
        a.set_title(t)
        a.grid(True, which="both", alpha=0.3)
    ax[0].set_ylabel(f"round-trip error, N = {args.n}")
    ax[1].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(RESULTS, "engine_horizon.png"), dpi=120)
    print("wrote bench/results/engine_horizon.{json,csv,png}")


_MEMORY_CHILD = r"""
import resource, sys, json, revcol
n, top = int(sys.argv[1]), int(float(sys.argv[2]))
sim = revcol.Simulation.random(n=n, dim=3, phi=0.3, seed=1)
done, rows, mark = 0, [], 100000
while mark <= top:
    sim.run(collisions=mark - done); done = mark
    d = sim.diagnostics()
    with open('/proc/self/status') as f:
        rss = [int(l.split()[1]) * 1024 for l in f if l.startswith(('VmHWM', 'VmRSS'))]
    rows.append(dict(collisions=done, peak_rss_bytes=rss[0], rss_bytes=rss[1], log_bytes=d['log_bytes'],
                     engine_bytes=d['memory_bytes']))
    print(json.dumps(rows[-1]), flush=True)
    mark *= 10
"""


def memory(args):
    env = dict(os.environ)
    p = subprocess.run([sys.executable, "-c", _MEMORY_CHILD, str(args.n), str(args.max)], capture_output=True,
                       text=True, env=env, check=True)
    rows = [json.loads(l) for l in p.stdout.splitlines() if l.startswith("{")]
    for r in rows:
        print(r)
    first, last = rows[0], rows[-1]
    growth = (last["peak_rss_bytes"] - first["peak_rss_bytes"]) / first["peak_rss_bytes"]
    print(f"peak RSS {first['peak_rss_bytes']} -> {last['peak_rss_bytes']} bytes ({100 * growth:+.3f}%), "
          f"log {last['log_bytes']} bytes after {last['collisions']} collisions")
    os.makedirs(RESULTS, exist_ok=True)
    with open(os.path.join(RESULTS, "engine_memory.json"), "w") as f:
        json.dump(dict(command=" ".join(sys.argv), n=args.n, rows=rows, peak_rss_growth=growth,
                       flat_within_1_percent=bool(abs(growth) <= 0.01)), f, indent=1)
    print("wrote bench/results/engine_memory.json")


REFERENCE = {  # collisions/s of the fastest public EDMD code on this machine (the numbers)
    "engine/d3/n10000/phi0.3": 6.1e5, "engine/d3/n10000/phi0.45": 9.8e5,
    "engine/d3/n100000/phi0.3": 2.7e5, "engine/d3/n100000/phi0.45": 4.5e5,
}


THROUGHPUT_CASES = ["engine/d3/n10000/phi0.3", "engine/d3/n10000/phi0.45", "engine/d3/n100000/phi0.3",
                    "engine/d3/n100000/phi0.45", "engine/d2/n10000/phi0.5"]


def throughput(args):
    """Every case once per round, the rounds interleaved (case order reversed on odd rounds), one
    fresh process per run, pinned to core ``--cpu`` when given; the 1-minute load before each
    run is recorded. Medians and ranges over the rounds."""
    import tempfile
    rounds = args.rounds
    runs = {c: [] for c in THROUGHPUT_CASES}
    loads = []
    for r in range(rounds):
        order = THROUGHPUT_CASES if r % 2 == 0 else THROUGHPUT_CASES[::-1]
        for case in order:
            nc = 2000000 if "n100000" in case else 1000000
            with tempfile.TemporaryDirectory() as tmp:
                js = os.path.join(tmp, "b.json")
                cmd = [args.bin, "--bench", case, "--collisions", str(nc), "--repeats", "1", "--json", js]
                if args.cpu is not None:
                    cmd = ["taskset", "-c", str(args.cpu)] + cmd
                load = os.getloadavg()[0]
                subprocess.run(cmd, check=True, capture_output=True)
                with open(js) as f:
                    data = json.load(f)
            one = {res["metric"]: res["values"][0] for res in data["results"] if res["bench"] == case}
            one["load_1m"] = load
            loads.append(load)
            runs[case].append(one)
            print(f"round {r + 1}/{rounds} {case:28s} forward {one['forward_per_s']:.3g}/s "
                  f"reverse {one['reverse_per_s']:.3g}/s  load {load:.2f}", flush=True)
    rows = []
    for case in THROUGHPUT_CASES:
        reps = runs[case]
        nc = 2000000 if "n100000" in case else 1000000
        row = dict(case=case, collisions=nc, rounds=rounds)
        for k in reps[0]:
            if k == "load_1m":
                continue
            vals = [x[k] for x in reps]
            row[k] = float(np.median(vals))
            if k in ("forward_per_s", "reverse_per_s"):
                row[k + "_min"], row[k + "_max"], row[k + "_all"] = min(vals), max(vals), vals
        row["load_1m_all"] = [x["load_1m"] for x in reps]
        ref = REFERENCE.get(case)
        if ref:
            row["reference_per_s"] = ref
            row["target_per_s"] = ref / 2
            row["meets_target"] = bool(row["forward_per_s"] >= ref / 2 and row["reverse_per_s"] >= ref / 2)
        rows.append(row)
        print(f"{case:28s} forward {row['forward_per_s']:.3g}/s [{row['forward_per_s_min']:.3g}, "
              f"{row['forward_per_s_max']:.3g}] reverse {row['reverse_per_s']:.3g}/s "
              f"[{row['reverse_per_s_min']:.3g}, {row['reverse_per_s_max']:.3g}]"
              + (f"  target {ref / 2:.3g}: {'met' if row['meets_target'] else 'MISSED'}" if ref else ""))
    os.makedirs(RESULTS, exist_ok=True)
    from revcol._io import atomic_open  # the package under test (PYTHONPATH=build-dev/pkg)
    with atomic_open(os.path.join(RESULTS, "engine_throughput.json"), "w") as f:
        json.dump(dict(command=" ".join(sys.argv), rounds=rounds, cpu=args.cpu,
                       date=time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
                       load_1m_min=min(loads), load_1m_max=max(loads), rows=rows), f, indent=1)
    with atomic_open(os.path.join(RESULTS, "engine_throughput.csv"), "w") as f:
        keys = ["case", "collisions", "rounds", "forward_per_s", "forward_per_s_min", "forward_per_s_max",
                "reverse_per_s", "reverse_per_s_min", "reverse_per_s_max", "peak_rss_bytes", "events_per_collision",
                "invalid_per_collision", "log_bytes", "reference_per_s", "meets_target"]
        f.write(",".join(keys) + "\n")
        for r in rows:
            f.write(",".join(str(r.get(k, "")) for k in keys) + "\n")
    print("wrote bench/results/engine_throughput.{json,csv}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("study", choices=["horizon", "memory", "throughput", "all"])
    ap.add_argument("--bin", default=os.path.join(HERE, "..", "build-dev", "revcol-bench"))
    ap.add_argument("--rounds", type=int, default=5, help="throughput: interleaved rounds (every case once each)")
    ap.add_argument("--cpu", type=int, default=None, help="throughput: pin each run to this core (taskset)")
    ap.add_argument("--n", type=int, default=None)
    ap.add_argument("--max", type=float, default=None)
    args = ap.parse_args()
    todo = ["horizon", "memory", "throughput"] if args.study == "all" else [args.study]
    for s in todo:
        a = argparse.Namespace(**vars(args))
        if s == "horizon":
            a.n = a.n or 1000
            a.max = a.max or 1e6
            horizon(a)
        elif s == "throughput":
            throughput(a)
        else:
            a.n = a.n or 10000
            a.max = a.max or 1e7
            memory(a)


if __name__ == "__main__":
    main()
