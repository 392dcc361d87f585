"""Run time against error for every operator and accuracy knob (issue 18):
``revcol bench tradeoff`` or ``python -m revcol.studies.tradeoff``.

Each *point* is one operator (or engine) with one setting of its knobs. The C++ benchmark
``revcol-bench --bench tradeoff/op`` (or ``tradeoff/engine``, ``lattice/...``) times it and
measures its chain errors in a fresh process; this module adds the law's distance from its
target and writes the table, the JSON/CSV and the Pareto plots.

Per point:

- ``forward_us``, ``reverse_us``: microseconds per collision of the reversal chain (the
  paper's illustration, :func:`revcol.verify`), median and range over ``repeats`` runs. The
  runs of all points go round robin (A B C .. A B C ..), so a change of machine load hits
  every point alike; each run is pinned to one core (``taskset -c 1``) when it can be.
- ``roundtrip_error``: max |v_end - v_0| / max |v_0| after the chain of ``collisions``
  forward and back (momentum and energy held), ``bit_exact`` when the end is the quantized
  start bit for bit; ``log_bytes_per_collision``: the rare log at the turn.
- ``law_D``: Kolmogorov-Smirnov distance of the post states of ``samples`` collisions of one
  fixed pre state from the target law (flux or uniform; paper mode's stated target is the
  uniform law), against as many samples of that law drawn by rejection without any chart
  (:func:`rejection_posts`), the largest over three projections of the velocities;
  ``law_D_noise`` = 1.54 sqrt(2 / samples) is its 95% level when the laws are equal (a D
  below it is no evidence of bias; the reference sample has a fixed seed, so one chance
  excess repeats across the points of a curve).
- ``energy_drift``, ``momentum_drift``: per collision, the same chain forward *without*
  held invariants (relative energy; momentum over sqrt(energy)).
- ``failure_rate``: paper mode, the fraction of single collisions that do not reverse
  (``paper::study``); exact mode, the fraction of the chain not carried out (0 unless it broke);
  the float engine, the fraction of its ``seeds`` gases whose round trip exceeds 1e-6 (its
  ``roundtrip_error`` is the worst of them).
- ``map_error`` (the paper triples' G-to-Psi maps, timed alone: ``tradeoff/arc``,
  ``tradeoff/calotte``; their time per collision is two evaluations, forward and reverse):
  the ellipse arc's largest angle error against a long double reference, the calotte
  tables' largest error of the sampled probability, |F(psi(G)) - G|.

    >>> from revcol import tradeoff
    >>> rep = tradeoff.run(tradeoff.reduced_points(), repeats=1, collisions=2000, samples=2000)  # doctest: +SKIP
"""
from __future__ import annotations

import argparse
import csv
import datetime as dt
import json
import os
import platform
import shlex
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from .. import _core
from .._io import atomic_open
from .law_distance import law_distance, rejection_posts
from .statesave.driver import find_binary

__all__ = ["all_points", "reduced_points", "run", "law_distance", "rejection_posts", "pareto_front", "format_table",
           "write_json", "write_csv", "plot", "main", "add_arguments", "cli_main", "ERRORS"]

#: K values of the chart-bits knob
BITS = (24, 28, 32, 36, 40, 44, 48, 52)
#: engine contact tolerances (relative to D)
GROUP_TOLS = (1e-12, 1e-9, 1e-8, 1e-7, 1e-6, 1e-5, 1e-4)
#: the paper-mode cases (pair2d: the paper's Procedures 1-2)
PAPER_CASES = ("pair2d", "pair3d", "triple1d", "triple2d-c1", "triple2d-c2", "triple2d-c3", "triple2d-c4")
#: the error metrics a Pareto plot is drawn for, with their axis labels
ERRORS = {"roundtrip_error": "round-trip error (max |v_end - v_0| / max |v_0|)",
          "law_D": "law error (KS D against rejection samples of the target law)",
          "energy_drift": "energy drift per collision (nothing held)",
          "momentum_drift": "momentum drift per collision (nothing held)",
          "log_bytes_per_collision": "rare log, bytes per collision",
          "failure_rate": "failure rate (collisions not reversed)",
          "map_error": "G-to-Psi map error (arc: angle; calotte: probability)"}
_OP_DEFAULTS = {"mode": "exact", "law": "flux", "rng": "clcg4", "bits": 40, "arc": "simpson", "seed": 0}
_ENGINE_DEFAULTS = {"dim": 2, "particles": 10000, "phi": 0.5, "group_tol": 1e-9, "bits": 40, "rng": "philox",
                    "law": "flux", "seed": 0, "seeds": 6, "warm": 5}
_LATTICE_BENCH = "lattice/periodic/n10000/phi0.3"


def _op(knob: str, curve: str, label: str, **settings) -> dict:
    s = {**_OP_DEFAULTS, **settings}
    default = all(s[k] == _OP_DEFAULTS[k] for k in ("law", "rng", "bits", "arc")) and s["mode"] == "exact"
    if knob == "arc":
        default = s["arc"] == "simpson"  # the paper's method is the paper mode's default
    return {"knob": knob, "curve": curve, "label": label, "kind": "op", "settings": s, "default": default}


def _engine(knob: str, curve: str, label: str, **settings) -> dict:
    s = {**_ENGINE_DEFAULTS, **settings}
    default = s["group_tol"] == _ENGINE_DEFAULTS["group_tol"] and s["rng"] == _ENGINE_DEFAULTS["rng"]
    return {"knob": knob, "curve": curve, "label": label, "kind": "engine", "settings": s, "default": default}


def _map(kind: str, curve: str, label: str, default: bool, **settings) -> dict:
    return {"knob": kind, "curve": curve, "label": label, "kind": kind, "settings": settings, "default": default}


def map_points() -> list[dict]:
    """The G-to-Psi maps' knobs: the Simpson tolerance, the arc table's and the calotte tables'
    cells, the calotte quadrature's nodes per cell (defaults 1e-9, 4096, 2048, 10)."""
    pts = [_map("arc", "arc map: simpson tolerance", f"tol={t:g}", t == 1e-9, arc="simpson", tol=t)
           for t in (1e-5, 1e-7, 1e-9, 1e-11)]
    pts.append(_map("arc", "arc map: elliptic", "elliptic", False, arc="elliptic"))
    pts += [_map("arc", "arc map: table cells", f"cells={c}", c == 4096, arc="table", cells=c)
            for c in (256, 1024, 4096, 16384)]
    pts += [_map("calotte", "calotte map: cells", f"cells={c}", c == 2048, cells=c) for c in (256, 512, 2048, 8192)]
    pts += [_map("calotte", "calotte map: nodes per cell", f"nodes={q}", q == 10, nodes=q) for q in (1, 2, 4, 10)]
    return pts


def all_points() -> list[dict]:
    """Every operator at its defaults, and every knob's variants (see the module doc)."""
    pts = []
    for c in _core.named_cases():
        for law in ("flux", "uniform"):
            if c["name"] == "pair1d" and law == "uniform":
                continue  # the exchange has no law
            pts.append(_op("operator", f"exact {law}", c["name"], case=c["name"], law=law))
    for case in PAPER_CASES:
        pts.append(_op("operator", "paper", case, case=case, mode="paper"))
    for case in ("pair2d", "pair3d", "triple2d-c1"):
        for k in BITS:
            pts.append(_op("bits", f"K: {case}", f"K={k}", case=case, bits=k))
    for arc in ("simpson", "elliptic", "table"):
        pts.append(_op("arc", "arc: paper triple1d", arc, case="triple1d", mode="paper", arc=arc))
    for case in ("pair2d", "triple2d-c1"):
        for rng in ("clcg4", "philox"):
            pts.append(_op("rng", f"rng: {case}", rng, case=case, rng=rng))
    for tol in GROUP_TOLS:
        pts.append(_engine("group_tol", "group_tol: float engine 2D", f"{tol:g}", group_tol=tol))
    for rng in ("philox", "clcg4"):
        pts.append(_engine("rng", "rng: float engine 2D", rng, rng=rng))
    pts.append({"knob": "engine", "curve": "lattice engine 2D", "label": "lattice", "kind": "lattice",
                "settings": {"bench": _LATTICE_BENCH}, "default": True})
    return pts + map_points()


def reduced_points() -> list[dict]:
    """The CI's subset: K at 24, 40, 52 on pair2d, both generators, one paper case, the engine,
    the arc and calotte tables at 256 cells and their defaults."""
    pts = [_op("bits", "K: pair2d", f"K={k}", case="pair2d", bits=k) for k in (24, 40, 52)]
    pts += [_op("rng", "rng: pair2d", r, case="pair2d", rng=r) for r in ("clcg4", "philox")]
    pts.append(_op("operator", "paper", "triple2d-c1", case="triple2d-c1", mode="paper"))
    pts.append(_engine("group_tol", "group_tol: float engine 2D", "1e-09", particles=200))
    pts += [_map("arc", "arc map: table cells", f"cells={c}", c == 4096, arc="table", cells=c) for c in (256, 4096)]
    pts += [_map("calotte", "calotte map: cells", f"cells={c}", c == 2048, cells=c) for c in (256, 2048)]
    return pts


# ---- running the benchmark ----------------------------------------------------------------------

def _pin() -> list[str]:
    """``taskset -c 1`` when taskset exists and core 1 is ours; else nothing."""
    try:
        ok = shutil.which("taskset") is not None and 1 in os.sched_getaffinity(0)
    except AttributeError:
        ok = False
    return ["taskset", "-c", "1"] if ok else []


def _bench(binary: str, point: dict, collisions: int, pin: list[str]) -> dict[str, float]:
    """One run of the point's benchmark in a fresh process: its metrics."""
    s = point["settings"]
    env = dict(os.environ)
    if point["kind"] == "lattice":
        name = s["bench"]
    else:
        name = "tradeoff/" + point["kind"]
        env["REVCOL_TRADEOFF"] = ",".join(f"{k}={v}" for k, v in s.items())
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "r.json"
        cmd = pin + [binary, "--bench", name, "--repeats", "1", "--collisions", str(collisions), "--json", str(out)]
        done = subprocess.run(cmd, env=env, capture_output=True, text=True)
        if done.returncode != 0 or not out.exists():
            raise RuntimeError(f"{' '.join(cmd)} failed ({done.returncode}): {done.stderr.strip()}")
        rows = json.loads(out.read_text())["results"]
    return {r["metric"]: float(r["median"]) for r in rows}


def _collisions(binary: str, point: dict, pin: list[str], collisions: int, budget_s: float, floor: int) -> int:
    """Chain length of a point: ``collisions`` at most, and what ``budget_s`` seconds per
    direction allow at the rate of a 2000-collision probe (at least ``floor``)."""
    if point["kind"] == "engine":
        return 2 * int(point["settings"]["particles"])  # ~4 collisions per particle: inside the horizon
    if point["kind"] == "lattice":
        return min(collisions, 20_000)
    if point["kind"] in ("arc", "calotte"):
        return min(collisions, 100_000)  # map evaluations (simpson: a twentieth of them)
    m = _bench(binary, point, min(2000, collisions), pin)
    rate = min(m["forward_per_s"], m["reverse_per_s"])
    return int(max(min(collisions, floor), min(collisions, budget_s * rate)))



# ---- the study ----------------------------------------------------------------------------------

def _stat(values: list[float]) -> dict:
    return {"median": float(np.median(values)), "min": float(min(values)), "max": float(max(values)),
            "values": [float(x) for x in values]}


_DETERMINISTIC = ("roundtrip_error", "bit_exact", "log_bytes_per_collision", "energy_drift", "momentum_drift",
                  "failure_rate", "single_error")


def _row(point: dict, runs: list[dict[str, float]], collisions: int, law: dict | None) -> dict:
    """The table row of a point from its runs."""
    first = runs[0]
    row = {k: point[k] for k in ("knob", "curve", "label", "kind", "default")}
    row["settings"] = point["settings"]
    row.update({k: None for k in ERRORS})
    if point["kind"] in ("arc", "calotte"):  # a map: forward and reverse evaluate it once each
        row["collisions"] = collisions
        row["forward_us"] = row["reverse_us"] = _stat([r["ns_per_sample"] / 1e3 for r in runs])
        row["time_us"] = 2 * row["forward_us"]["median"]
        row.update(map_error=first["map_error"], bit_exact=None, law_D_noise=None, invalid_post=None,
                   deterministic=all(r["map_error"] == first["map_error"] for r in runs))
        if "build_ms" in first:
            row["build_ms"] = _stat([r["build_ms"] for r in runs])
        return row
    row["collisions"] = int(first.get("collisions", collisions))
    row["forward_us"] = _stat([1e6 / r["forward_per_s"] for r in runs])
    row["reverse_us"] = _stat([1e6 / r["reverse_per_s"] for r in runs])
    row["time_us"] = row["forward_us"]["median"] + row["reverse_us"]["median"]
    if point["kind"] == "lattice":
        coll = float(collisions)
        row.update(bit_exact=bool(first["bit_exact"]), roundtrip_error=0.0 if first["bit_exact"] else None,
                   log_bytes_per_collision=None, log_entries_per_collision=first["log_entries"] / coll,
                   energy_drift=abs(first["energy_drift"]) / coll, momentum_drift=None, failure_rate=0.0)
    elif point["kind"] == "engine":
        coll = first["collisions"]
        row.update(bit_exact=first["roundtrip_error"] == 0.0, roundtrip_error=first["roundtrip_error"],
                   log_bytes_per_collision=first["log_bytes_per_collision"],
                   group_fraction=first["group_fraction"], energy_drift=first["energy_drift"] / coll,
                   momentum_drift=None, failure_rate=first["broken_fraction"])  # gases not restored to 1e-6
    else:
        dc = max(first["drift_collisions"], 1.0)
        row.update(bit_exact=bool(first["bit_exact"]), roundtrip_error=first["roundtrip_error"],
                   log_bytes_per_collision=first["log_bytes_per_collision"],
                   energy_drift=first["energy_drift"] / dc, momentum_drift=first["momentum_drift"] / dc,
                   drift_collisions=int(first["drift_collisions"]), chain_failed=bool(first["chain_failed"]),
                   failure_rate=first.get("failure_rate", 1.0 - first["collisions"] / collisions))
        if "single_error" in first:
            row["single_error"] = first["single_error"]
    row["law_D"] = law["law_D"] if law else None
    row["law_D_noise"] = law["law_D_noise"] if law else None
    row["invalid_post"] = law["invalid_post"] if law else None
    # the errors come from the same seed every run: they must agree bit for bit
    row["deterministic"] = all(all(r.get(k) == first.get(k) for k in _DETERMINISTIC) for r in runs)
    return row


def _git_commit() -> str | None:
    """The commit of the package's source tree, else of the current directory's (a staged or
    installed package lives outside the repository); None outside any."""
    for where in (Path(__file__).resolve().parent, Path.cwd()):
        try:
            out = subprocess.run(["git", "-C", str(where), "rev-parse", "HEAD"], capture_output=True, text=True)
            if out.returncode != 0:
                continue
            dirty = subprocess.run(["git", "-C", str(where), "status", "--porcelain", "--untracked-files=no"],
                                   capture_output=True, text=True).stdout.strip()
            return out.stdout.strip() + ("-dirty" if dirty else "")
        except OSError:
            return None
    return None


def run(points: Sequence[dict], *, repeats: int = 3, collisions: int = 1_000_000, budget_s: float = 0.25,
        min_collisions: int = 20_000, samples: int = 50_000, binary: str | None = None, pin: bool = True,
        command: str = "", progress: Callable[[str], None] | None = None) -> dict:
    """Measures every point (see the module doc): chain length per point from a probe and
    ``budget_s`` (at most ``collisions``, at least ``min_collisions``), ``repeats`` runs of
    every point round robin, then the law's distance with ``samples`` collisions."""
    if repeats < 1 or collisions < 1 or samples < 100:
        raise ValueError("repeats and collisions must be >= 1 and samples >= 100")
    exe = find_binary(binary)
    pinned = _pin() if pin else []
    say = progress or (lambda s: None)
    load_before = os.getloadavg()
    started = dt.datetime.now(dt.timezone.utc)
    counts = [_collisions(exe, p, pinned, collisions, budget_s, min_collisions) for p in points]
    runs: list[list[dict]] = [[] for _ in points]
    for r in range(repeats):  # round robin: A B C .. A B C ..
        for k, p in enumerate(points):
            say(f"repeat {r + 1}/{repeats}  {p['curve']}  {p['label']}  ({counts[k]} collisions)")
            runs[k].append(_bench(exe, p, counts[k], pinned))
    rows = []
    for k, p in enumerate(points):
        law = law_distance(p["settings"], samples) if p["kind"] == "op" else None
        rows.append(_row(p, runs[k], counts[k], law))
    return {"command": command, "git_commit": _git_commit(), "date": started.isoformat(timespec="seconds"),
            "loadavg_before": list(load_before), "loadavg_after": list(os.getloadavg()),
            "pinned": " ".join(pinned) or None, "cpus": os.cpu_count(), "machine": platform.platform(),
            "binary": exe, "repeats": repeats, "max_collisions": collisions, "budget_s": budget_s,
            "min_collisions": min_collisions, "samples": samples,
            "seconds": (dt.datetime.now(dt.timezone.utc) - started).total_seconds(), "points": rows}


# ---- Pareto fronts, table, files, plots -------------------------------------------------------

def pareto_front(rows: Sequence[dict], error: str) -> list[dict]:
    """The rows no other row beats on both time and ``error`` (None errors left out)."""
    pts = [r for r in rows if r.get(error) is not None]
    return [r for r in pts if not any(o["time_us"] <= r["time_us"] and o[error] <= r[error]
                                      and (o["time_us"] < r["time_us"] or o[error] < r[error]) for o in pts)]


def _fmt(x, spec: str = ".2g") -> str:
    if x is None:
        return "-"
    if isinstance(x, bool):
        return "yes" if x else "no"
    return "0" if x == 0 else format(x, spec)


def format_table(rep: dict) -> str:
    """The points as a Markdown table."""
    head = ("| knob | curve | setting | N | fwd us | rev us | round trip | bit exact | law D (noise) "
            "| E drift/coll | P drift/coll | log B/coll | failure | map error |")
    lines = [head, "|" + "---|" * 14]
    for r in rep["points"]:
        t = lambda s: f"{s['median']:.3g} [{s['min']:.3g}, {s['max']:.3g}]"  # noqa: E731
        law = "-" if r["law_D"] is None else f"{r['law_D']:.2g} ({r['law_D_noise']:.1g})"
        lines.append(f"| {r['knob']} | {r['curve']} | {r['label']}{' **(default)**' if r['default'] else ''} "
                     f"| {r['collisions']} | {t(r['forward_us'])} | {t(r['reverse_us'])} "
                     f"| {_fmt(r['roundtrip_error'])} | {_fmt(r['bit_exact'])} | {law} | {_fmt(r['energy_drift'])} "
                     f"| {_fmt(r['momentum_drift'])} | {_fmt(r['log_bytes_per_collision'])} | {_fmt(r['failure_rate'])} "
                     f"| {_fmt(r['map_error'])} |")
    return "\n".join(lines)


_CSV_COLUMNS = ("knob", "curve", "label", "default", "collisions", "time_us", "roundtrip_error", "bit_exact",
                "law_D", "law_D_noise", "invalid_post", "energy_drift", "momentum_drift",
                "log_bytes_per_collision", "failure_rate", "map_error", "deterministic")


def write_json(rep: dict, path: str | os.PathLike) -> None:
    """The report as JSON (atomically)."""
    with atomic_open(path) as f:
        json.dump(rep, f, indent=1)


def write_csv(rep: dict, path: str | os.PathLike) -> None:
    """One row per point: the columns of :data:`_CSV_COLUMNS`, the times' median and range."""
    with atomic_open(path) as f:
        w = csv.writer(f)
        w.writerow(list(_CSV_COLUMNS[:6]) + ["forward_us", "forward_us_min", "forward_us_max", "reverse_us",
                                             "reverse_us_min", "reverse_us_max"] + list(_CSV_COLUMNS[6:]) + ["settings"])
        for r in rep["points"]:
            times = [r[k][s] for k in ("forward_us", "reverse_us") for s in ("median", "min", "max")]
            w.writerow([r[c] for c in _CSV_COLUMNS[:6]] + times + [r.get(c) for c in _CSV_COLUMNS[6:]]
                       + [json.dumps(r["settings"], sort_keys=True)])


def plot(rep: dict, outdir: str | os.PathLike) -> list[Path]:
    """One Pareto plot per error (time per collision, forward + reverse, against the error; log
    scales; a curve per knob, operators as points; the default marked with a black ring; an
    exact zero drawn on a dashed floor that says so) and an overview of all six."""
    import matplotlib  # optional (the plot extra): imported only when a figure is drawn

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # optional (the plot extra): imported only when a figure is drawn

    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    rows = rep["points"]
    curves = list(dict.fromkeys(r["curve"] for r in rows))
    cmap = plt.get_cmap("tab20")
    files = []

    def panel(ax, error):
        vals = [r[error] for r in rows if r.get(error) is not None]
        pos = [v for v in vals if v > 0]
        floor = (min(pos) / 30 if pos else 1e-20)
        for ci, curve in enumerate(curves):
            pts = sorted((r for r in rows if r["curve"] == curve and r.get(error) is not None), key=lambda r: r["time_us"])
            if not pts:
                continue
            xs = [r["time_us"] for r in pts]
            ys = [r[error] if r[error] > 0 else floor for r in pts]
            style = "o" if pts[0]["knob"] == "operator" else "o-"
            ax.plot(xs, ys, style, color=cmap(ci % 20), ms=4, lw=1, label=curve)
            if pts[0]["knob"] != "operator":
                for r, x, y in zip(pts, xs, ys):
                    ax.annotate(r["label"], (x, y), fontsize=5, xytext=(2, 2), textcoords="offset points")
            d = [(x, y) for r, x, y in zip(pts, xs, ys) if r["default"]]
            if d:
                ax.plot(*zip(*d), "o", mfc="none", mec="k", ms=8, mew=1.2)
        if len(pos) < len(vals):
            ax.axhline(floor, color="0.5", ls="--", lw=0.8)
            ax.text(0.01, floor, "exact 0 (drawn at this floor)", transform=ax.get_yaxis_transform(),
                    fontsize=6, va="bottom", color="0.3")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("time per collision, forward + reverse (us)")
        ax.set_ylabel(ERRORS[error], fontsize=7)
        ax.grid(True, which="both", alpha=0.3)

    for error in ERRORS:
        fig, ax = plt.subplots(figsize=(7.5, 5))
        panel(ax, error)
        ax.legend(fontsize=5, ncol=2, loc="best")
        ax.set_title(f"run time vs {error} (black ring: default)", fontsize=9)
        f = outdir / f"tradeoff_{error}.png"
        with atomic_open(f, "wb") as fh:
            fig.savefig(fh, format="png", dpi=130, bbox_inches="tight")
        plt.close(fig)
        files.append(f)
    fig, axes = plt.subplots(2, 4, figsize=(22, 10))
    for ax, error in zip(axes.ravel(), ERRORS):
        panel(ax, error)
    handles = {}
    for ax in axes.ravel()[:len(ERRORS)]:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(lab, h)
    legend_ax = axes.ravel()[-1]
    legend_ax.axis("off")
    legend_ax.legend(list(handles.values()), list(handles), loc="center", fontsize=8, title="curves (one per knob)")
    fig.suptitle("revcol: run time against error for every operator and knob (black ring: the default)")
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    f = outdir / "tradeoff.png"
    with atomic_open(f, "wb") as fh:
        fig.savefig(fh, format="png", dpi=110)
    plt.close(fig)
    files.append(f)
    return files


# ---- command line -------------------------------------------------------------------------------

def add_arguments(p: argparse.ArgumentParser) -> None:
    """The options of ``revcol bench tradeoff``."""
    p.add_argument("--reduced", action="store_true", help="the CI's few points instead of all")
    p.add_argument("--repeats", type=int, default=3, help="runs per point, round robin (default 3)")
    p.add_argument("--collisions", type=float, default=1e6, help="longest chain (default 1e6)")
    p.add_argument("--min-collisions", type=float, default=2e4, help="shortest chain (default 2e4)")
    p.add_argument("--budget", type=float, default=0.25,
                   help="seconds per direction a chain may take, at the probe's rate (default 0.25)")
    p.add_argument("--samples", type=float, default=5e4, help="collisions of the law's KS test (default 5e4)")
    p.add_argument("--binary", help="the revcol-bench to run (default: $REVCOL_BENCH, next to python, or on PATH)")
    p.add_argument("--no-pin", action="store_true", help="do not pin the runs to core 1 with taskset")
    p.add_argument("--json", metavar="FILE", help="write the report (and FILE's .csv next to it); - for standard output")
    p.add_argument("--plot", metavar="DIR", help="write the Pareto plots (PNG) into DIR")
    p.add_argument("--no-progress", action="store_true")
    p.add_argument("--from-json", metavar="FILE", help="no run: read a report written by --json and redo the "
                   "table, the CSV and the plots from it")


def cli_main(args: argparse.Namespace, argv: Sequence[str] | None = None) -> int:
    """Runs ``revcol bench tradeoff`` from parsed arguments; 0 when every point ran."""
    words = sys.argv[1:] if argv is None else list(argv)
    command = "revcol " + " ".join(shlex.quote(a) for a in words)
    progress = None if args.no_progress or not sys.stderr.isatty() else (
        lambda s: print(f"\r{s[:100]:<100}", end="", file=sys.stderr, flush=True))
    try:
        if args.from_json:
            rep = json.loads(Path(args.from_json).read_text())
        else:
            rep = run(reduced_points() if args.reduced else all_points(), repeats=args.repeats,
                      collisions=int(args.collisions), budget_s=args.budget, min_collisions=int(args.min_collisions),
                      samples=int(args.samples), binary=args.binary, pin=not args.no_pin, command=command,
                      progress=progress)
    except (ValueError, OSError, RuntimeError) as e:
        print(f"revcol bench tradeoff: error: {e}", file=sys.stderr)
        return 2
    if progress:
        print(file=sys.stderr)
    text = sys.stderr if args.json == "-" else sys.stdout  # --json -: the JSON alone on stdout
    print(format_table(rep), file=text)
    print(f"\nload average before {rep['loadavg_before']}, after {rep['loadavg_after']}; "
          f"pinned: {rep['pinned']}; {rep['seconds']:.0f} s", file=text)
    if args.json == "-":
        print(json.dumps(rep))
    elif args.json:
        write_json(rep, args.json)
        write_csv(rep, Path(args.json).with_suffix(".csv"))
    if args.plot:
        plot(rep, args.plot)
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m revcol.studies.tradeoff [options]`` (the options of ``revcol bench tradeoff``)."""
    p = argparse.ArgumentParser(prog="python -m revcol.studies.tradeoff", description=__doc__.split("\n")[0])
    add_arguments(p)
    args = p.parse_args(argv)
    words = sys.argv[1:] if argv is None else list(argv)
    return cli_main(args, ["bench", "tradeoff"] + words)


if __name__ == "__main__":
    sys.exit(main())
