"""A performance model of the parallel lattice engine (docs/parallel.md, "A model for more
cores"), fitted and validated on what ``revcol-bench --bench parallel/...`` measured on this
machine, and its predictions for more cores and larger gases, labelled as predictions.

The model has two parts.

Cost. A run's seconds per collision are its work, ``c_e E + c_u U + c_m M`` (E the LPs' events
processed, re-executions and stale pops included, U the journal entries its rollbacks undid, M
the messages sent), of which the busiest of the P workers does the share ``b / P`` (b its
events over the mean), plus the GVT step, measured (``gvt_s``: worker 0 drains the inboxes,
computes GVT and commits every LP while the others wait at the barrier), plus ``c_b`` per GVT
on more than one worker (the barrier itself). The unit costs are fitted per case (dimension,
N) by non-negative least squares in relative error on all its runs (1 and 2 workers, K = 1 to
16), and each run is predicted again with itself left out.

Counts. Each LP processes every event of the particles in its band (its slab widened by W on
both sides), so the LPs process ``rho = 1 + 2 K W / L`` times the events of one engine (slabs;
blocks of side l: ``(1 + 2 W / l)^d``). Undone entries and messages per collision are
proportional to the redundant part, ``e1 (rho - 1)``, with factors measured at one LP per core
(K = 2 on 2 workers) and, as the pessimistic bound, the largest factor measured with more LPs
than cores. W is fixed in diameters, so W / L falls as N^(-1/d); undone entries per collision
at K = 2 fall more slowly (a power law N^alpha fitted per dimension through its sizes), so the
factor per redundant event grows as N^(alpha + 1/d).

    python bench/parallel_model.py --runs bench/results/lattice_parallel_scaling.json \\
        --json bench/results/lattice_parallel_model.json
"""
from __future__ import annotations

import argparse
import json
import math
import os
import re
import subprocess
import tempfile

import numpy as np
from scipy.optimize import nnls


def load(paths: list[str]) -> dict[str, dict[str, float]]:
    """Each bench case's metrics (medians) from revcol-bench JSON files, or bundles of them
    (bench/results/README.md)."""
    out: dict[str, dict[str, float]] = {}
    for p in paths:
        with open(p) as f:
            d = json.load(f)
        for run in d["runs"].values() if "bundle" in d else [d]:
            for r in run["results"]:
                out.setdefault(r["bench"], {})[r["metric"]] = r["median"]
    return out


def runs_of(m: dict[str, float]) -> list[dict]:
    """The reverse-computation runs of one case: K, workers and the counts per collision."""
    c = m["collisions"]
    out = []
    for key in m:
        g = re.fullmatch(r"seconds_K(\d+)_w(\d+)", key)
        if not g:
            continue
        v = f"K{g[1]}_w{g[2]}"
        out.append({"name": v, "K": int(g[1]), "w": int(g[2]), "T": m[key] / c,
                    "E": m[f"events_per_collision_{v}"], "U": m[f"undone_per_collision_{v}"],
                    "M": m[f"messages_per_collision_{v}"], "G": m[f"gvts_{v}"] / c,
                    "S": m[f"gvt_s_per_collision_{v}"],
                    "b": m[f"worker_imbalance_{v}"], "speedup": m[f"speedup_{v}"],
                    "speedup_min": m[f"speedup_{v}_min"], "speedup_max": m[f"speedup_{v}_max"]})
    return sorted(out, key=lambda r: (r["w"], r["K"]))


def features(r: dict) -> list[float]:
    """The run's counts per collision weighted as the model charges them: the busiest worker's
    share of the events, undone entries and messages, and (more than one worker) the GVTs."""
    share = r["b"] / r["w"]
    return [r["E"] * share, r["U"] * share, r["M"] * share, r["G"] if r["w"] > 1 else 0.0]


def fit_costs(runs: list[dict]) -> np.ndarray:
    """(c_e, c_u, c_m, c_b): seconds per event, undone entry and message (spread over the
    workers) and per GVT barrier on more than one worker, fitted to the run time less its
    measured GVT step."""
    A = np.array([features(r) for r in runs]) / np.array([[r["T"] - r["S"]] for r in runs])
    x, _ = nnls(A, np.ones(len(runs)))
    return x


def cost(c: np.ndarray, r: dict) -> float:
    """A run's seconds per collision: the fitted work and barriers, and the GVT step measured."""
    return float(np.dot(c, features(r))) + r["S"]


def case_model(name: str, m: dict[str, float]) -> dict:
    """Fit and validate one case (dimension, N)."""
    runs = runs_of(m)
    one = [r for r in runs if r["w"] == 1]
    c = fit_costs(runs)
    loo = []
    for i, r in enumerate(runs):
        ci = fit_costs(runs[:i] + runs[i + 1:])
        loo.append({"run": r["name"], "measured_s_per_collision": r["T"], "fitted": cost(c, r),
                    "predicted_left_out": cost(ci, r), "ratio_left_out": cost(ci, r) / r["T"]})
    base = next(r for r in runs if r["w"] == 2 and r["K"] == 2)
    k1 = next(r for r in one if r["K"] == 1)
    beta = m["band_over_L"]
    d = int(re.search(r"/d(\d)/", name)[1])
    counts = []
    for r in runs:
        rho = min(r["K"], 1 + 2 * r["K"] * beta)
        red = k1["E"] * (rho - 1)
        counts.append({"run": r["name"], "rho": rho, "events_measured": r["E"],
                       "events_geometry": k1["E"] * rho, "events_geometry_plus_undone": k1["E"] * rho + r["U"],
                       "undone_per_redundant": r["U"] / red if red > 0 else None,
                       "messages_per_redundant": r["M"] / red if red > 0 else None})
    per_core = next(x for x in counts if x["run"] == "K2_w2")
    over = [x for x in counts if x["run"].endswith("_w2") and x["run"] != "K2_w2" and x["undone_per_redundant"] is not None]
    return {"case": name, "d": d, "n": m["n"], "phi": m["phi"], "band_over_L": beta,
            "seq_s_per_collision": m["seconds_seq"] / m["collisions"],
            "c_event_s": c[0], "c_undone_s": c[1], "c_message_s": c[2], "c_gvt_barrier_s": c[3],
            "gvt_step_s_per_event": base["S"] / base["E"],
            "events_per_collision_K1": k1["E"],
            "undone_per_redundant": per_core["undone_per_redundant"],
            "messages_per_redundant": per_core["messages_per_redundant"],
            "undone_per_redundant_worst": max([per_core["undone_per_redundant"]] + [x["undone_per_redundant"] for x in over]),
            "messages_per_redundant_worst": max([per_core["messages_per_redundant"]] + [x["messages_per_redundant"] for x in over]),
            "gvts_per_busiest_event": base["G"] / (base["E"] * base["b"] / 2),
            "imbalance_K2": base["b"],
            "validation_leave_one_out": loo, "counts": counts,
            "measured_speedup": {r["name"]: [r["speedup"], r["speedup_min"], r["speedup_max"]] for r in runs}}


def undone_slope(models: list[dict], d: int) -> float:
    """How undone entries per collision at K = 2 on 2 workers fall with N: the exponent of a
    power law through the cases of dimension d (two sizes or more; else through the 2D cases;
    else the bands', -1/d)."""
    for dim in (d, 2):
        pts = [(math.log(cm["n"]), math.log(cm["undone_per_redundant"] * cm["events_per_collision_K1"] * 4 * cm["band_over_L"]))
               for cm in models if cm["d"] == dim and cm["undone_per_redundant"] > 0]
        if len({x for x, _ in pts}) >= 2:
            x, y = np.array(pts).T
            return float(np.polyfit(x, y, 1)[0])
    return -1.0 / d


def predict(cm: dict, n: float, p: int, blocks: bool, worst: bool, alpha: float = 0.0) -> dict:
    """Speed-up over the sequential engine on p cores, one LP per core, for N = n (the costs
    per event and per collision of the case: flat in N beyond it; undone entries per collision
    at K = 2 scaling as N^alpha, per redundant event in K)."""
    d = cm["d"]
    beta = cm["band_over_L"] * (cm["n"] / n) ** (1.0 / d)
    scale = (n / cm["n"]) ** (alpha + 1.0 / d)  # undone per redundant event at n over the case's
    if blocks:
        side = p ** (1.0 / d)
        rho = min(p, (1 + 2 * beta * side) ** d)
    else:
        rho = min(p, 1 + 2 * p * beta)
    e1 = cm["events_per_collision_K1"]
    red = e1 * (rho - 1)
    u = red * cm["undone_per_redundant_worst" if worst else "undone_per_redundant"] * scale
    msg = red * cm["messages_per_redundant_worst" if worst else "messages_per_redundant"]
    e = e1 * rho + u
    busiest = e * cm["imbalance_K2"] / p
    w = (cm["c_event_s"] * e + cm["c_undone_s"] * u + cm["c_message_s"] * msg) * cm["imbalance_K2"] / p
    barrier = cm["c_gvt_barrier_s"] * (p / 2) * cm["gvts_per_busiest_event"] * busiest
    t = w + barrier + cm["gvt_step_s_per_event"] * e  # (the GVT step: serial, as many events per GVT as P workers process)
    return {"rho": rho, "speedup": cm["seq_s_per_collision"] / t, "efficiency": cm["seq_s_per_collision"] / t / p,
            "slab_width_over_band": (1 / p) / beta if not blocks else (1 / p ** (1.0 / d)) / beta}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", nargs="+", required=True, help="revcol-bench JSON files of parallel/... cases")
    ap.add_argument("--cores", type=int, nargs="+", default=[2, 8, 16, 64, 256, 1024])
    ap.add_argument("--n", type=float, nargs="+", default=[1e6, 1e7, 1e8])
    ap.add_argument("--json", help="write the fit, its validation and the predictions here (atomically)")
    a = ap.parse_args(argv)
    cases = load(a.runs)
    models = [case_model(k, v) for k, v in sorted(cases.items())]
    for cm in models:
        print(f"\n{cm['case']}: W/L {cm['band_over_L']:.4g}; c_e {cm['c_event_s'] * 1e9:.0f} ns, c_u {cm['c_undone_s'] * 1e9:.0f} ns, "
              f"c_m {cm['c_message_s'] * 1e9:.0f} ns, c_b {cm['c_gvt_barrier_s'] * 1e6:.0f} us per GVT barrier, GVT step {cm['gvt_step_s_per_event'] * 1e9:.0f} ns per event (measured); sequential {cm['seq_s_per_collision'] * 1e9:.0f} ns/collision")
        for v in cm["validation_leave_one_out"]:
            print(f"  {v['run']:>8}: measured {v['measured_s_per_collision'] * 1e9:7.0f} ns/collision, fitted {v['fitted'] * 1e9:7.0f}, "
                  f"left out {v['predicted_left_out'] * 1e9:7.0f} ({v['ratio_left_out']:.2f})")
        for x in cm["counts"]:
            print(f"  {x['run']:>8}: rho {x['rho']:.3f} events {x['events_measured']:.3f} geometry {x['events_geometry']:.3f} (+undone {x['events_geometry_plus_undone']:.3f})"
                  f" undone/red {x['undone_per_redundant'] if x['undone_per_redundant'] is None else round(x['undone_per_redundant'], 3)}")
    # the model of a smaller gas predicting a larger one's two-worker run (what the predictions do)
    alpha = {d: undone_slope(models, d) for d in sorted({cm["d"] for cm in models})}
    for d, a_d in alpha.items():
        print(f"{d}D: undone entries per collision at K = 2 on 2 workers scale as N^{a_d:.2f}")
    cross = []
    for a_ in models:
        for b_ in models:
            if a_["d"] == b_["d"] and a_["n"] < b_["n"]:
                q = predict(a_, b_["n"], 2, False, False, alpha[a_["d"]])
                got = b_["measured_speedup"]["K2_w2"]
                cross.append({"from": a_["case"], "to": b_["case"], "predicted_K2_speedup": q["speedup"],
                              "measured": got[0], "measured_min": got[1], "measured_max": got[2]})
                print(f"{a_['case']} -> {b_['case']}: K = 2 on 2 workers predicted {q['speedup']:.2f}, measured {got[0]:.2f} ({got[1]:.2f}-{got[2]:.2f})")
    # predictions from the largest N measured in each dimension
    preds = []
    for d in sorted({cm["d"] for cm in models}):
        cm = max((x for x in models if x["d"] == d), key=lambda x: x["n"])
        for n in a.n:
            for blocks in (False, True):
                for p in a.cores:
                    lo = predict(cm, n, p, blocks, True, alpha[d])
                    hi = predict(cm, n, p, blocks, False, alpha[d])
                    preds.append({"d": d, "phi": cm["phi"], "from_case": cm["case"], "n": n, "cores": p,
                                  "decomposition": "blocks" if blocks else "slabs", "rho": hi["rho"],
                                  "speedup": hi["speedup"], "speedup_pessimistic": lo["speedup"],
                                  "slab_width_over_band": hi["slab_width_over_band"]})
    print("\npredicted speed-up (pessimistic), one LP per core:")
    for q in preds:
        print(f"  d{q['d']} N {q['n']:.0e} {q['decomposition']:>6} P {q['cores']:5d}: rho {q['rho']:7.3f} "
              f"speed-up {q['speedup']:7.1f} ({q['speedup_pessimistic']:.1f})  slab/band {q['slab_width_over_band']:.1f}")
    print("\n| d | N | cut | " + " | ".join(f"P = {p}" for p in a.cores) + " |")
    print("|---|---|---|" + "---|" * len(a.cores))
    for d in sorted({q["d"] for q in preds}):
        for n in a.n:
            for cut in ("slabs", "blocks"):
                row = [q for q in preds if q["d"] == d and q["n"] == n and q["decomposition"] == cut]
                print(f"| {d} | 10^{round(math.log10(n))} | {cut} | " + " | ".join(
                    f"{q['speedup']:.1f} ({q['speedup_pessimistic']:.1f})" for q in row) + " |")
    if a.json:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
        out = {"what": "performance model of the parallel lattice engine (bench/parallel_model.py)", "commit": commit,
               "runs": a.runs, "cases": models, "undone_exponent": {str(d): a_d for d, a_d in alpha.items()}, "cross_validation": cross, "predictions": preds}
        fd, tmp = tempfile.mkstemp(dir=os.path.dirname(os.path.abspath(a.json)) or ".", suffix=".tmp")
        with os.fdopen(fd, "w") as f:
            json.dump(out, f, indent=1)
        os.replace(tmp, a.json)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
