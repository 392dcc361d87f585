"""The Loschmidt echo of the hard-sphere gas, and its largest Lyapunov exponent.

A gas runs forward for a time T, recording frames; at the turn one particle is moved by one
lattice unit (``--perturb position``: 2^-S diameters along x) or its velocity changed by one
lattice unit (``velocity``); the gas runs back and, at each frame time, its distance from the
forward frame at the same time is measured: the position distance dx = sqrt(sum |x_i - x_i'|^2)
in diameters (nearest image) and the velocity distance dv = sqrt(sum |v_i - v_i'|^2) in units of
sqrt(kT/m). Four echoes of one start:

* ``exact``: the lattice engine in specular mode run back unperturbed: every frame must come
  back bit for bit (``frames_not_exact`` = 0);
* ``lattice``: the same with the one-unit perturbation: the distance grows as exp(lambda t)
  from ~1e-16 until it saturates, and the slope of ln dx against the time run back is the
  largest Lyapunov exponent lambda (fitted where dx is between ``--fit-lo`` and ``--fit-hi``
  diameters, after a growth of 10^3 from the start: the perturbation first turns into the most
  unstable direction);
* ``float``: the float engine in specular mode (the same start, double precision) run back
  unperturbed: its round-off is the perturbation, and it does not come back;
* ``flux``: the lattice engine's randomized flux law with the same one-unit perturbation: the
  random numbers and the bits-back integer are driven by the trajectory, so what the
  perturbation does there is measured (the distance, or the engine's refusal and when).

The same exponent is also measured forward, from two trajectories of each engine one
perturbation apart (``forward``): a deterministic reversible dynamics has the same lambda both
ways, and the lattice's must equal the float engine's within the spread over seeds.

    python -m revcol.studies.echo --json bench/results/echo.json --plot docs/figures/physics/echo.png

runs 2D (area fraction 0.5) and 3D (volume fraction 0.3), N = 1000, 3 seeds. Times are in
sigma sqrt(m/kT); lambda is also given per mean free time (lambda / collision rate per particle).
"""
from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import time
import warnings
from typing import Optional, Sequence

import numpy as np

from .._io import atomic_open, save_figure
from ..engine import Simulation
from .lyapunov import Metric, lattice_gas, lyapunov_scan, scan_summary

__all__ = ["lattice_gas", "echo_case", "fit_rate", "Metric", "main"]


def _float_dist(xa, va, xb, vb, box, periodic) -> tuple:
    d = np.asarray(xa) - np.asarray(xb)
    d = np.where(periodic, d - np.round(d / box) * box, d)
    dv = np.asarray(va) - np.asarray(vb)
    return float(np.sqrt((d * d).sum())), float(np.sqrt((dv * dv).sum()))


def fit_rate(t: Sequence[float], dist: Sequence[float], lo: float, hi: float, grow: float = 1e3) -> Optional[dict]:
    """The slope of ln(dist) against t where lo <= dist <= hi, after dist has grown by ``grow``
    from its first positive value: {rate, error (the fit's standard error), points, t0, t1};
    None when fewer than 4 points qualify."""
    t, dist = np.asarray(t, dtype=float), np.asarray(dist, dtype=float)
    pos = dist > 0
    if not pos.any():
        return None
    d0 = dist[pos][0]
    start = np.argmax(dist >= grow * d0) if (dist >= grow * d0).any() else len(dist)
    sel = np.zeros(len(t), dtype=bool)
    sel[start:] = True
    sel &= (dist >= lo) & (dist <= hi)
    if sel.sum() < 4:
        return None
    x, y = t[sel], np.log(dist[sel])
    A = np.vstack([x, np.ones_like(x)]).T
    coef, res, *_ = np.linalg.lstsq(A, y, rcond=None)
    yhat = A @ coef
    s2 = float(((y - yhat) ** 2).sum()) / max(len(x) - 2, 1)
    err = math.sqrt(s2 / float(((x - x.mean()) ** 2).sum()))
    return {"rate": float(coef[0]), "error": err, "points": int(sel.sum()), "t0": float(x[0]), "t1": float(x[-1])}


def _forward_frames(sim, times) -> list:
    frames = []
    for t in times:
        sim.run(time=t)
        frames.append((sim.lattice_positions.copy(), sim.lattice_velocities.copy()))
    return frames


def _perturbed(sim, what: str):
    """The same state with one lattice unit added to particle 0's x position or x velocity."""
    snap = sim.snapshot()
    key = "x" if what == "position" else "v"
    arr = np.array(snap[key], dtype=np.int64)
    arr[0, 0] += 1
    snap[key] = arr
    return type(sim).from_snapshot(snap)


def _back(sim, times, frames, metric) -> dict:
    """Runs sim back through ``times`` (descending); distances to ``frames`` there. An engine
    refusal ends the echo: its message and time are kept."""
    dx, dv, exact, t_done, error = [], [], 0, [], None
    for t, (xf, vf) in zip(times, frames):
        try:
            sim.run_back(time=t)
        except (RuntimeError, ValueError) as e:  # the flux law's perturbed reverse may be refused
            error = {"message": str(e)[:300], "time": float(sim.time)}
            break
        a, b = metric.lattice(sim.lattice_positions, sim.lattice_velocities, xf, vf)
        exact += int(a == 0.0 and b == 0.0)
        dx.append(a)
        dv.append(b)
        t_done.append(t)
    return {"t": t_done, "dx": dx, "dv": dv, "frames_exact": exact, "error": error}


def _float_pair(sim0, times, delta: float) -> dict:
    """Two float specular trajectories from the lattice start, particle 0 moved by ``delta``
    (``times`` from the start: the float engine's clock starts at 0); and the float engine's own
    unperturbed echo."""
    x = np.asarray(sim0.positions, dtype=float)
    v = np.asarray(sim0.velocities, dtype=float)
    box = np.asarray(sim0.box, dtype=float)
    periodic = np.array([b == "periodic" for b in sim0.boundary])
    xp = x.copy()
    xp[0, 0] += delta
    kw = dict(boundary=list(sim0.boundary), mode="specular")
    a, b = Simulation(x, v, box, **kw), Simulation(xp, v, box, **kw)
    out = {"t": [], "dx": [], "dv": []}
    for t in times:
        a.run(time=t)
        b.run(time=t)
        d = _float_dist(a.positions, a.velocities, b.positions, b.velocities, box, periodic)
        out["t"].append(t)
        out["dx"].append(d[0])
        out["dv"].append(d[1])
    # the float engine's own echo: back from the end, unperturbed, against its forward frames
    xs = {}
    c = Simulation(x, v, box, **kw)
    for t in times:
        c.run(time=t)
        xs[t] = (np.asarray(c.positions).copy(), np.asarray(c.velocities).copy())
    back = {"t": [], "dx": [], "dv": [], "warning": None}
    for t in reversed(times):
        with warnings.catch_warnings(record=True) as caught:  # the engine says when it diverged
            warnings.simplefilter("always")
            c.run_back(time=t)
        if caught and back["warning"] is None:
            back["warning"] = str(caught[0].message)[:300]
        d = _float_dist(c.positions, c.velocities, xs[t][0], xs[t][1], box, periodic)
        back["t"].append(t)
        back["dx"].append(d[0])
        back["dv"].append(d[1])
    return {"forward": out, "echo": back}


def echo_case(dim: int, phi: float, n: int, seed: int, t_end: float, frames: int, perturb: str = "position",
              warm: float = 5.0, fit_lo: float = 1e-7, fit_hi: float = 1e-2, flux: bool = True,
              float_delta: float = 1e-10) -> dict:
    """One start: the four echoes and the forward pairs (module doc), with fitted rates."""
    base = lattice_gas(dim, n, phi, seed)
    base.run(time=warm)  # away from the random start
    start = base.snapshot()
    t_start = base.time
    times = [t_start + t_end * (k + 1) / frames for k in range(frames)]
    metric = Metric(base)
    w0 = time.perf_counter()
    fwd = _forward_frames(base, times)
    collisions = base.collisions - int(start["collisions"])
    rate = 2.0 * collisions / (n * t_end)  # collisions per particle per unit time
    diag = base.diagnostics()
    back_times = [t_start] + times[:-1]
    back_frames = [(np.asarray(start["x"]), np.asarray(start["v"]))] + fwd[:-1]
    rb, rf = list(reversed(back_times)), list(reversed(back_frames))
    turn = base.snapshot()
    exact = _back(type(base).from_snapshot(turn), rb, rf, metric)
    pert = _back(_perturbed(type(base).from_snapshot(turn), perturb), rb, rf, metric)
    run_back = [times[-1] - t for t in exact["t"]]
    res = {"dim": dim, "phi": phi, "n": n, "seed": seed, "perturb": perturb, "time": t_end, "frames": frames,
           "collisions": collisions, "collision_rate": rate, "rare_log": int(diag["log_entries"]),
           "backscatters": int(diag.get("backscatters", 0)), "sigma_units": float(start["units"]["sigma"]),
           "exact": {"frames_exact": exact["frames_exact"], "frames": len(exact["t"]),
                     "max_dx": max(exact["dx"]), "max_dv": max(exact["dv"])},
           "lattice": {"time_back": run_back, "dx": pert["dx"], "dv": pert["dv"], "error": pert["error"]}}
    res["lattice"]["fit"] = fit_rate(run_back[:len(pert["dx"])], pert["dx"], fit_lo, fit_hi)
    # forward: the lattice gas from the start, perturbed at the start, against the frames
    fp = _perturbed(type(base).from_snapshot(start), perturb)
    fdx, fdv = [], []
    for t, (xf, vf) in zip(times, fwd):
        fp.run(time=t)
        a, b = metric.lattice(fp.lattice_positions, fp.lattice_velocities, xf, vf)
        fdx.append(a)
        fdv.append(b)
    tf = [t - t_start for t in times]
    res["lattice_forward"] = {"time": tf, "dx": fdx, "dv": fdv, "fit": fit_rate(tf, fdx, fit_lo, fit_hi)}
    # the float engine from the same start (its positions as floats)
    fl = _float_pair(type(base).from_snapshot(start), [t - t_start for t in times], delta=float_delta)
    res["float_forward"] = {"time": tf, "dx": fl["forward"]["dx"], "dv": fl["forward"]["dv"],
                            "fit": fit_rate(tf, fl["forward"]["dx"], fit_lo, fit_hi)}
    res["float_echo"] = {"time_back": [tf[-1] - t for t in fl["echo"]["t"]], "dx": fl["echo"]["dx"],
                         "dv": fl["echo"]["dv"], "warning": fl["echo"]["warning"]}
    if flux:  # the randomized gas from the same start, perturbed at its own turn
        fx = type(base).from_snapshot({**start, "mode": "exact"})
        ffr = _forward_frames(fx, times)
        bf = [(np.asarray(start["x"]), np.asarray(start["v"]))] + ffr[:-1]
        fe = _back(_perturbed(fx, perturb), rb, list(reversed(bf)), metric)
        res["flux"] = {"time_back": [times[-1] - t for t in fe["t"]], "dx": fe["dx"], "dv": fe["dv"], "error": fe["error"]}
    res["seconds"] = time.perf_counter() - w0
    return res


def _summary(cases: list) -> dict:
    """lambda per (dim, phi): mean and standard error over seeds, per method; per mean free time."""
    out = {}
    for key in sorted({(c["dim"], c["phi"]) for c in cases}):
        group = [c for c in cases if (c["dim"], c["phi"]) == key]
        row = {"seeds": len(group), "collision_rate": float(np.mean([c["collision_rate"] for c in group]))}
        for m, path in (("echo", ("lattice", "fit")), ("lattice_forward", ("lattice_forward", "fit")),
                        ("float_forward", ("float_forward", "fit"))):
            vals = [c[path[0]][path[1]]["rate"] for c in group if c[path[0]][path[1]]]
            if vals:
                se = float(np.std(vals, ddof=1) / math.sqrt(len(vals))) if len(vals) > 1 else float("nan")
                row[m] = {"lambda": float(np.mean(vals)), "error": se, "n": len(vals),
                          "per_mean_free_time": float(np.mean(vals)) / row["collision_rate"]}
        e, f = row.get("echo"), row.get("float_forward")
        if e and f and e["n"] > 1 and f["n"] > 1:
            row["echo_vs_float_sd"] = abs(e["lambda"] - f["lambda"]) / math.hypot(e["error"], f["error"])
        row["all_exact"] = all(c["exact"]["frames_exact"] == c["exact"]["frames"] for c in group)
        out[f"{key[0]}D phi {key[1]}"] = row
    return out


def plot(cases: list, path: str, lyapunov: Optional[dict] = None, show=("2:0.5", "3:0.3")) -> None:
    """Top: distance from the forward run against the time run back (the first seed of each
    case in ``show``); bottom: Benettin's lambda against the perturbation size on both engines."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    picks = []
    for spec in show:
        dim, phi = int(spec.split(":")[0]), float(spec.split(":")[1])
        found = [c for c in cases if c["dim"] == dim and abs(c["phi"] - phi) < 1e-12]
        if found:
            picks.append(found[0])
    rows = 2 if lyapunov else 1
    fig, axes = plt.subplots(rows, max(len(picks), 1), figsize=(5.6 * max(len(picks), 1), 4.2 * rows), squeeze=False)
    floor = 1e-18
    for ax, c in zip(axes[0], picks):
        la = c["lattice"]
        ax.semilogy(la["time_back"][:len(la["dx"])], np.maximum(la["dx"], floor),
                    label="lattice specular, one unit of velocity changed at the turn")
        ax.semilogy(c["float_echo"]["time_back"], np.maximum(c["float_echo"]["dx"], floor),
                    label="float specular, unperturbed (its round-off)")
        if "flux" in c and c["flux"]["dx"]:
            ax.semilogy(c["flux"]["time_back"], np.maximum(c["flux"]["dx"], floor),
                        label="lattice flux law, one unit changed (until refused)")
        ax.semilogy(la["time_back"], [floor] * len(la["time_back"]), "k:",
                    label="lattice specular, unperturbed: 0, bit for bit")
        ax.set_title(f"{c['dim']}D, packing fraction {c['phi']}, N = {c['n']}", fontsize=9)
        ax.set_xlabel("time run back (sigma sqrt(m/kT))")
        ax.set_ylabel("distance from the forward run (diameters)")
        ax.legend(fontsize=6.5, loc="lower right")
    if lyapunov:
        for ax, dim in zip(axes[1], sorted({c["dim"] for c in picks})):
            for k, (key, row) in enumerate(sorted(lyapunov.items())):
                if not key.startswith(f"{dim}D"):
                    continue
                d0 = np.array([float(x) for x in row["by_d0"]])
                for eng, mk in (("lattice", "o-"), ("float", "s--")):
                    y = np.array([r[eng]["lambda_linear"] for r in row["by_d0"].values()])
                    e = np.array([r[eng]["error_linear"] for r in row["by_d0"].values()])
                    ax.errorbar(d0, y, yerr=e, fmt=mk, color=f"C{k}", ms=4, capsize=2,
                                label=f"{key.split(' ', 1)[1]}, {eng}")
            ax.set_xscale("log")
            ax.set_xlabel("perturbation size d0 (diameters)")
            ax.set_ylabel("lambda (Benettin, linear steps; (sigma sqrt(m/kT))^-1)")
            ax.set_title(f"{dim}D: largest Lyapunov exponent, lattice and float", fontsize=9)
            ax.legend(fontsize=6.5, ncol=2)
    fig.tight_layout()
    save_figure(fig, path)


def _compact(cases: list) -> list:
    """The cases as written to JSON: every seed's fits and checks, the curves of seed 1 only
    (the figure's), their values to 5 significant digits."""
    def rnd(x):
        if isinstance(x, float):
            return float(f"{x:.5g}")
        if isinstance(x, list):
            return [rnd(v) for v in x]
        if isinstance(x, dict):
            return {k: rnd(v) for k, v in x.items()}
        return x
    out = []
    for c in cases:
        c = dict(c)
        for key in ("lattice", "lattice_forward", "float_forward", "float_echo", "flux"):
            if key not in c:
                continue
            if c["seed"] != 1:
                c[key] = {k: v for k, v in c[key].items() if not isinstance(v, list)}
            else:  # at most about 200 points a curve
                c[key] = {k: (v[::max(1, len(v) // 200)] if isinstance(v, list) else v) for k, v in c[key].items()}
        out.append(rnd(c))
    return out


def _commit() -> str:
    try:
        here = os.path.dirname(os.path.abspath(__file__))
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=here, capture_output=True, text=True,
                              check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m revcol.studies.echo", description=__doc__.split("\n\n")[0])
    ap.add_argument("--cases", nargs="+", default=["2:0.5", "3:0.3"], help="dim:phi pairs")
    ap.add_argument("--n", type=int, default=1000)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--time", type=float, default=None, help="time forward (default: 40 mean free times, estimated)")
    ap.add_argument("--frames", type=int, default=200)
    ap.add_argument("--perturb", choices=("position", "velocity"), default="position")
    ap.add_argument("--fit-lo", type=float, default=1e-12)
    ap.add_argument("--fit-hi", type=float, default=1e-3)
    ap.add_argument("--no-flux", action="store_true", help="skip the flux-law echo")
    ap.add_argument("--d0", type=float, nargs="*", default=[1e-6, 1e-5, 3e-5, 1e-4],
                    help="Benettin perturbation sizes (diameters); none: skip the scan")
    ap.add_argument("--json", help="write the results here (atomically)")
    ap.add_argument("--plot", help="write the figure here")
    ap.add_argument("--replot", help="only draw --plot from this study's JSON")
    a = ap.parse_args(argv)
    if a.replot:
        saved = json.load(open(a.replot))
        plot(saved["cases"], a.plot, saved.get("lyapunov"))
        return 0
    cases, w0, load0 = [], time.perf_counter(), os.getloadavg()
    for spec in a.cases:
        dim, phi = int(spec.split(":")[0]), float(spec.split(":")[1])
        t_end = a.time
        if t_end is None:  # 40 mean free times from a short probe
            probe = lattice_gas(dim, a.n, phi, 1)
            probe.run(collisions=20 * a.n)
            t_end = 40.0 / (2.0 * probe.collisions / (a.n * probe.time))
        for seed in range(1, a.seeds + 1):
            c = echo_case(dim, phi, a.n, seed, t_end, a.frames, a.perturb, fit_lo=a.fit_lo, fit_hi=a.fit_hi,
                          flux=not a.no_flux)
            cases.append(c)
            fit = c["lattice"]["fit"]
            print(f"{dim}D phi {phi} seed {seed}: {c['collisions']} collisions, exact frames "
                  f"{c['exact']['frames_exact']}/{c['exact']['frames']}, echo lambda "
                  f"{fit['rate'] if fit else float('nan'):.3f}, float lambda "
                  f"{(c['float_forward']['fit'] or {}).get('rate', float('nan')):.3f}, {c['seconds']:.1f} s", flush=True)
    scans = []
    for spec in a.cases if a.d0 else []:
        dim, phi = int(spec.split(":")[0]), float(spec.split(":")[1])
        for seed in range(1, a.seeds + 1):
            sc = lyapunov_scan(dim, phi, a.n, seed, a.d0)
            scans.append(sc)
            print(f"{dim}D phi {phi} seed {seed} Benettin: " + "; ".join(
                f"d0 {r['d0']:.0e}: lattice {r['lattice']['lambda_linear']:.2f}+-{r['lattice']['error_linear']:.2f} "
                f"({r['lattice']['steps_left_out']} out) float {r['float']['lambda_linear']:.2f}"
                f"+-{r['float']['error_linear']:.2f} ({r['float']['steps_left_out']} out)" for r in sc["rows"]), flush=True)
    summary = _summary(cases)
    for k, row in summary.items():
        print(k, json.dumps({m: row[m] for m in row if m in ("echo", "float_forward", "echo_vs_float_sd", "all_exact")}))
    if a.json:
        out = {"command": "python -m revcol.studies.echo " + " ".join(sys.argv[1:] if argv is None else list(argv)),
               "commit": _commit(), "loadavg_start": list(load0), "loadavg_end": list(os.getloadavg()),
               "wall_s": time.perf_counter() - w0, "summary": summary, "lyapunov": scan_summary(scans),
               "scans": scans, "cases": _compact(cases)}
        with atomic_open(a.json) as f:
            f.write(json.dumps(out, indent=1) + "\n")
    if a.plot:
        plot(cases, a.plot, scan_summary(scans) if scans else None)
    return 0 if all(r["all_exact"] for r in summary.values()) else 1


if __name__ == "__main__":
    raise SystemExit(main())
