"""The paper's performance study (§6): state saving against reverse computation, and beyond.

N particles in 2D (positions uniform in the unit box, velocity components uniform in
[-1, 1)). Each step draws exactly 3 numbers from the reversible generator (pair, exponential
inter-collision time, the operator's G), moves every particle x += v dt, and collides the
pair with the normal +-(x_i - x_j) oriented so that it approaches. After N_c steps the run
rolls back to the start:

- ``ss1``: saves all positions and velocities before every step (32 N bytes); restores them;
- ``ss2``: saves all positions and the pair's indices and pre-collision velocities (16 N + 40);
- ``ssp`` (lazy only): the pair's indices, x0 and velocities (72 bytes: the best lazy state saving);
- ``rc``:  saves nothing; reverse operator, then reverse transport, the generator stepping back.

Every step's record also holds the clock and the generator state (24 bytes more). *Lazy
transport* stores x0 = x - v t per particle, so a step costs O(1): a collision at time t
updates x0 += (v_old - v_new) t, and reverse undoes it. The C++ header
``revcol/statesave.hpp`` has the maths (orientation, grazing rule, exact mode's pre log).

:func:`run` does one run in this process. :func:`study` runs a grid of (mode, N, variant),
each in a fresh ``revcol-bench`` process so that its peak resident set (VmHWM) is its own,
and reports times (the repeat with the median total), bytes saved (counted), peak RSS and
the round-trip error; runs whose saved state exceeds the budget are skipped with their
projection. :func:`write_json`, :func:`write_csv` and :func:`plot` write the results.

    >>> import revcol
    >>> r = revcol.statesave.run(1000, 200, variant="rc")
    >>> r["restored"], r["max_rel_error"] < 1e-9, r["draws"] == 3 * 200
    (True, True, True)
"""
from __future__ import annotations

import argparse
import csv
import datetime as dt
import json
import math
import os
import platform
import shlex
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any, Callable, Iterable, Sequence

from . import _core

__all__ = ["run", "projected_bytes", "variants", "study", "write_json", "write_csv", "plot",
           "format_table", "add_arguments", "cli_main", "MODES"]

#: operator modes of the study
MODES = ("exact", "paper")
_GIB = 1 << 30
_MAX_PARTICLES = 1 << 26
_MAX_COLLISIONS = 1 << 32
_LABEL = {"ss1": "SS1", "ss2": "SS2", "ssp": "SS-pair", "rc": "RC"}


# --- validation --------------------------------------------------------------------------

def _int(value: Any, name: str, lo: int, hi: int | None = None) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or value != int(value):
        raise ValueError(f"{name} must be an integer, got {value!r}")
    v = int(value)
    if v < lo or (hi is not None and v > hi):
        bound = f"[{lo}, {hi}]" if hi is not None else f">= {lo}"
        raise ValueError(f"{name} must be {bound}, got {v}")
    return v


def _budget_bytes(budget_gib: Any) -> int:
    if isinstance(budget_gib, bool) or not isinstance(budget_gib, (int, float)) \
            or not math.isfinite(budget_gib) or budget_gib <= 0:
        raise ValueError(f"budget_gib must be a positive number of GiB, got {budget_gib!r}")
    return int(budget_gib * _GIB)


def _supported(lazy: bool) -> tuple[str, ...]:
    return tuple(_core.statesave_variants("lazy" if lazy else "eager"))


def variants(lazy: bool = False) -> tuple[str, ...]:
    """The variants a transport supports, in report order (eager: ss1 ss2 rc; lazy adds ssp)."""
    return _supported(lazy)


def _kwargs(particles, collisions, variant, lazy, mode, law, rng, seed, mean_dt, grazing_tol,
            budget_gib, prefault, bits=40) -> dict:
    if mode not in MODES:
        raise ValueError(f"mode must be 'exact' or 'paper', got {mode!r}")
    if variant not in _supported(lazy):
        need = " (ssp needs lazy=True)" if variant == "ssp" else ""
        raise ValueError(f"variant must be one of {', '.join(_supported(lazy))}, got {variant!r}{need}")
    return dict(particles=_int(particles, "particles", 2, _MAX_PARTICLES),
                collisions=_int(collisions, "collisions", 1, _MAX_COLLISIONS), variant=variant,
                transport="lazy" if lazy else "eager", mode=mode, law=law, bits=_int(bits, "bits", 8, 52),
                rng=rng, seed=_int(seed, "seed", 0, 2**32 - 1), mean_dt=float(mean_dt),
                grazing_tol=float(grazing_tol), budget_bytes=_budget_bytes(budget_gib),
                prefault=bool(prefault))


# --- one run -------------------------------------------------------------------------------

def run(particles: int, collisions: int = 1000, *, variant: str = "rc", lazy: bool = False,
        mode: str = "exact", law: str = "flux", rng: str = "clcg4", seed: int = 0,
        mean_dt: float = 1e-5, grazing_tol: float = 1e-11, budget_gib: float = 8.0,
        prefault: bool = True, capture: bool = False) -> dict:
    """One run in this process: N_c steps forward, roll back, compare with the start.

    Returns a dict: ``forward_s``, ``rollback_s``, ``bytes_saved`` (counted: the records, or
    for ``rc`` its logs), ``projected_bytes``, ``peak_rss_bytes`` (this *process's* VmHWM),
    ``max_rel_error`` (max of |x - x_0| / box and |v - v_0| / max|v_0|), ``restored`` (state
    saving: bit for bit; rc: within 1e-9; both: generator and clock back, logs empty),
    ``draws`` / ``draws_undone`` (3 per step), ``skipped`` (over the budget: not run), and
    with ``capture`` the (N, 4) arrays ``start``, ``turn`` and ``end`` (x, y, vx, vy;
    positions at the snapshot's time). Bad arguments raise ValueError naming the problem.
    """
    kw = _kwargs(particles, collisions, variant, lazy, mode, law, rng, seed, mean_dt,
                 grazing_tol, budget_gib, prefault)
    return _core.statesave_run(capture=bool(capture), **kw)


def projected_bytes(particles: int, collisions: int = 1000, *, variant: str = "ss1",
                    lazy: bool = False, **kw: Any) -> int:
    """Bytes the variant saves over a run (rc: 0; its logs are counted when it runs)."""
    args = dict(mode="exact", law="flux", rng="clcg4", seed=0, mean_dt=1e-5, grazing_tol=1e-11,
                budget_gib=8.0, prefault=True)
    args.update(kw)
    return int(_core.statesave_projected_bytes(
        **_kwargs(particles, collisions, variant, lazy, **args))["projected_bytes"])


# --- the study -----------------------------------------------------------------------------

def _find_binary(explicit: str | None) -> str:
    if explicit:
        if Path(explicit).is_file() and os.access(explicit, os.X_OK):
            return str(explicit)
        raise ValueError(f"binary {explicit!r} is not an executable file")
    for c in (os.environ.get("REVCOL_BENCH"), str(Path(sys.executable).parent / "revcol-bench"),
              shutil.which("revcol-bench")):
        if c and Path(c).is_file() and os.access(c, os.X_OK):
            return str(c)
    raise FileNotFoundError("revcol-bench not found (pip install . puts it next to python; "
                            "or pass binary=..., set REVCOL_BENCH, or use inline=True)")


def _gib(b: float) -> str:
    return f"{b / _GIB:.1f} GiB"


def _skip_text(projected: int) -> str:
    return f"skipped: needs {_gib(projected)} ({projected / 1e9:.1f} GB)"


class _Progress:
    """tqdm when installed, else a one-line bar; silent unless stdout is a terminal."""

    def __init__(self, total: int, enabled: bool | None):
        self.enabled = sys.stdout.isatty() if enabled is None else enabled
        self.total, self.done, self.bar = total, 0, None
        if self.enabled:
            try:
                from tqdm import tqdm
                self.bar = tqdm(total=total, unit="run", leave=False, file=sys.stdout)
            except ImportError:
                self.bar = None

    def update(self, label: str) -> None:
        if not self.enabled:
            return
        self.done += 1
        if self.bar is not None:
            self.bar.set_postfix_str(label)
            self.bar.update(1)
            return
        width = 30
        fill = int(width * self.done / max(self.total, 1))
        sys.stdout.write(f"\r[{'#' * fill}{'.' * (width - fill)}] {self.done}/{self.total} {label:<40.40s}")
        sys.stdout.flush()

    def close(self) -> None:
        if not self.enabled:
            return
        if self.bar is not None:
            self.bar.close()
        else:
            sys.stdout.write("\r" + " " * 80 + "\r")
            sys.stdout.flush()


def _run_process(binary: str, kw: dict, repeats: int) -> list[dict]:
    env = dict(os.environ)
    env["REVCOL_STATESAVE"] = ",".join([
        f"n={kw['particles']}", f"seed={kw['seed']}", f"rng={kw['rng']}", f"law={kw['law']}",
        f"bits={kw['bits']}", f"budget={kw['budget_bytes']}", f"prefault={int(kw['prefault'])}",
        f"mean_dt={kw['mean_dt']!r}", f"grazing_tol={kw['grazing_tol']!r}"])
    name = f"statesave/{kw['mode']}/{kw['transport']}/{kw['variant']}"
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "run.json"
        cmd = [binary, "--bench", name, "--collisions", str(kw["collisions"]), "--repeats", str(repeats),
               "--json", str(out)]
        # its own session: a terminal's Ctrl-C reaches the study (which stops after this run)
        # and not the run (a KeyboardInterrupt here makes subprocess.run kill the run)
        p = subprocess.run(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                           start_new_session=True)
        if p.returncode != 0:
            raise RuntimeError(f"{' '.join(cmd)} failed ({p.returncode}): {p.stderr.strip()}")
        data = json.loads(out.read_text())
    values: dict[str, list[float]] = {r["metric"]: r["values"] for r in data["results"] if r["bench"] == name}
    reps = []
    for k in range(repeats):
        reps.append({m: v[k] for m, v in values.items()})
    for r in reps:
        r["forward_s"], r["rollback_s"] = r["forward_ms"] / 1e3, r["rollback_ms"] / 1e3
    return reps


def _run_inline(kw: dict, repeats: int) -> list[dict]:
    return [dict(_core.statesave_run(capture=False, **kw)) for _ in range(repeats)]


def _row(kw: dict, reps: list[dict], record_bytes: int, projected: int) -> dict:
    totals = [r["forward_s"] + r["rollback_s"] for r in reps]
    med = sorted(range(len(reps)), key=lambda k: totals[k])[(len(reps) - 1) // 2]
    r = reps[med]
    counted = float(r["bytes_saved"])
    if kw["variant"] != "rc":
        # the bench prints 9 significant digits; the count is exact in C++ and equals this
        if abs(counted - projected) > 1e-8 * max(projected, 1):
            raise RuntimeError(f"bytes saved {counted} differ from the projection {projected}")
        saved = projected
    else:
        saved = int(round(counted))
    return {
        "mode": kw["mode"], "transport": kw["transport"], "variant": kw["variant"],
        "particles": kw["particles"], "collisions": kw["collisions"], "skipped": False, "status": "",
        "forward_ms": 1e3 * r["forward_s"], "rollback_ms": 1e3 * r["rollback_s"],
        "total_ms": 1e3 * totals[med],
        "forward_ms_all": [1e3 * x["forward_s"] for x in reps],
        "rollback_ms_all": [1e3 * x["rollback_s"] for x in reps],
        "bytes_saved": saved, "projected_bytes": projected, "record_bytes": record_bytes,
        "state_bytes": 32 * kw["particles"],
        "peak_rss_bytes": int(max(float(x["peak_rss_bytes"]) for x in reps)),
        "rss_before_bytes": int(float(reps[0]["rss_before_bytes"])),
        "max_rel_error": max(float(x["max_rel_error"]) for x in reps),
        "max_rel_error_x": max(float(x["max_rel_error_x"]) for x in reps),
        "max_rel_error_v": max(float(x["max_rel_error_v"]) for x in reps),
        "restored": all(bool(x["restored"]) for x in reps),
        "bit_exact": all(bool(x["bit_exact"]) for x in reps),
        "rng_restored": all(bool(x["rng_restored"]) for x in reps),
        "log_bytes": int(float(r["log_bytes"])),
        "pre_log_entries": int(float(r["pre_log_entries"])),
        "decision_log_entries": int(float(r["decision_log_entries"])),
        "rare_log_entries": int(float(r["rare_log_entries"])),
        "grazes": int(float(r["grazes"])),
        "draws": int(float(r["draws"])), "draws_undone": int(float(r["draws_undone"])),
    }


def _skipped_row(kw: dict, record_bytes: int, projected: int) -> dict:
    row = {k: None for k in ("forward_ms", "rollback_ms", "total_ms", "bytes_saved", "peak_rss_bytes",
                             "rss_before_bytes", "max_rel_error", "max_rel_error_x", "max_rel_error_v",
                             "restored", "bit_exact", "rng_restored", "log_bytes", "pre_log_entries",
                             "decision_log_entries", "rare_log_entries", "grazes", "draws", "draws_undone")}
    row.update({"mode": kw["mode"], "transport": kw["transport"], "variant": kw["variant"],
                "particles": kw["particles"], "collisions": kw["collisions"], "skipped": True,
                "status": _skip_text(projected), "forward_ms_all": [], "rollback_ms_all": [],
                "projected_bytes": projected, "record_bytes": record_bytes,
                "state_bytes": 32 * kw["particles"]})
    return row


def _ratios(runs: list[dict]) -> list[dict]:
    out = []
    by_key = {(r["mode"], r["particles"], r["variant"]): r for r in runs}
    for (mode, n, variant), rc in by_key.items():
        if variant != "rc":
            continue
        for (m2, n2, v2), s in by_key.items():
            if (m2, n2) != (mode, n) or v2 == "rc":
                continue
            ran = not s["skipped"] and not rc["skipped"]
            ss_bytes = s["projected_bytes"] if s["skipped"] else s["bytes_saved"]
            out.append({
                "mode": mode, "particles": n, "vs": v2,
                "time": rc["total_ms"] / s["total_ms"] if ran and s["total_ms"] > 0 else None,
                "bytes_saved": rc["bytes_saved"] / ss_bytes if not rc["skipped"] and ss_bytes else None,
                "peak_rss": rc["peak_rss_bytes"] / s["peak_rss_bytes"] if ran and s["peak_rss_bytes"] else None,
                "note": "state saving skipped: bytes ratio against its projection" if s["skipped"] else "",
            })
    return out


def _machine() -> dict:
    info = {"platform": platform.platform(), "cpus": os.cpu_count(), "python": platform.python_version()}
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                info["processor"] = line.split(":", 1)[1].strip()
                break
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemTotal:"):
                info["memory_bytes"] = int(line.split()[1]) * 1024
                break
    except OSError:
        pass
    return info


def study(n: Iterable[int] = (1000, 10000, 100000, 1000000), collisions: int = 1000, *,
          lazy: bool = False, modes: Sequence[str] = ("exact",), law: str = "flux",
          variants: Sequence[str] | None = None, repeats: int = 3, budget_gib: float = 8.0,
          seed: int = 0, rng: str = "clcg4", mean_dt: float = 1e-5, grazing_tol: float = 1e-11,
          prefault: bool = True, binary: str | None = None, inline: bool = False,
          progress: bool | None = None, command: str | None = None,
          stop: Callable[[], bool] | None = None) -> dict:
    """Runs every (mode, N, variant) and returns the report (see the module doc).

    Each run is a fresh ``revcol-bench`` process (``binary``: explicit, ``$REVCOL_BENCH``,
    next to this Python, or on PATH), repeated ``repeats`` times in it; ``inline=True`` runs
    in this process instead (peak RSS is then this whole process's). Runs whose saved
    state exceeds ``budget_gib`` are not attempted. ``progress``: None = when stdout is a
    terminal. ``stop``: asked before each run; when it returns True the study ends there
    (the report has the runs done, ``interrupted`` True and ``not_run`` the rest).
    """
    ns = list(n) if not isinstance(n, (int, float)) else [n]
    if not ns:
        raise ValueError("n must list at least one particle count")
    ns = [_int(x, "n", 2, _MAX_PARTICLES) for x in ns]
    modes = list(modes) if not isinstance(modes, str) else [modes]
    if not modes or any(m not in MODES for m in modes):
        raise ValueError(f"modes must be a non-empty list of 'exact' / 'paper', got {modes!r}")
    vs = list(variants) if variants is not None else list(_supported(lazy))
    if not vs or any(v not in _supported(lazy) for v in vs):
        raise ValueError(f"variants must be among {', '.join(_supported(lazy))}, got {vs!r}")
    vs = [v for v in _supported(lazy) if v in vs]  # report order
    repeats = _int(repeats, "repeats", 1, 1000)
    # validates everything else once (ValueError naming the problem)
    base = _kwargs(ns[0], collisions, vs[0], lazy, modes[0], law, rng, seed, mean_dt, grazing_tol,
                   budget_gib, prefault)
    exe = None if inline else _find_binary(binary)

    plan = [(m, N, v) for m in modes for N in ns for v in vs]
    bar = _Progress(len(plan), progress)
    runs = []
    not_run = 0
    try:
        for k, (m, N, v) in enumerate(plan):
            if stop is not None and stop():
                not_run = len(plan) - k
                break
            kw = dict(base, mode=m, particles=N, variant=v)
            proj = _core.statesave_projected_bytes(**kw)
            label = f"{m} N={N:,} {_LABEL[v]}"
            if proj["over_budget"]:
                runs.append(_skipped_row(kw, proj["record_bytes"], proj["projected_bytes"]))
            else:
                reps = _run_inline(kw, repeats) if inline else _run_process(exe, kw, repeats)
                row = _row(kw, reps, proj["record_bytes"], proj["projected_bytes"])
                row["status"] = "ok" if row["restored"] else "FAILED"
                runs.append(row)
            bar.update(label)
    finally:
        bar.close()
    passed = all(r["skipped"] or r["restored"] for r in runs) and \
        all(not r["skipped"] for r in runs if r["variant"] == "rc")
    return {
        "study": "statesave", "transport": base["transport"], "collisions": base["collisions"],
        "particles": ns, "modes": modes, "variants": vs, "law": law, "rng": rng, "seed": base["seed"],
        "repeats": repeats, "budget_bytes": base["budget_bytes"], "prefault": base["prefault"],
        "mean_dt": base["mean_dt"], "grazing_tol": base["grazing_tol"],
        "runner": "inline" if inline else "process",
        "rss_note": ("peak RSS of this whole Python process (inline)" if inline else
                     "peak RSS (VmHWM) of a fresh revcol-bench process per (mode, N, variant)"),
        "time_note": f"the repeat with the median total of {repeats}",
        "binary": exe, "command": command, "machine": _machine(),
        "date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
        "runs": runs, "ratios": _ratios(runs), "passed": passed,
        "interrupted": not_run > 0, "not_run": not_run,
    }


# --- output --------------------------------------------------------------------------------

def write_json(report: dict, path: str | os.PathLike) -> None:
    """The report as indented JSON."""
    Path(path).write_text(json.dumps(report, indent=1) + "\n")


_CSV_FIELDS = ["mode", "transport", "variant", "particles", "collisions", "status", "forward_ms",
               "rollback_ms", "total_ms", "bytes_saved", "projected_bytes", "record_bytes",
               "peak_rss_bytes", "rss_before_bytes", "state_bytes", "max_rel_error", "max_rel_error_x",
               "max_rel_error_v", "restored", "bit_exact", "log_bytes", "pre_log_entries",
               "decision_log_entries", "rare_log_entries", "rc_over_this_time",
               "rc_over_this_bytes_saved", "rc_over_this_peak_rss"]


def write_csv(report: dict, path: str | os.PathLike) -> None:
    """One row per run; state-saving rows carry RC's ratios to them."""
    ratio = {(q["mode"], q["particles"], q["vs"]): q for q in report["ratios"]}
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=_CSV_FIELDS, extrasaction="ignore")
        w.writeheader()
        for r in report["runs"]:
            row = dict(r)
            q = ratio.get((r["mode"], r["particles"], r["variant"]))
            if q:
                row.update(rc_over_this_time=q["time"], rc_over_this_bytes_saved=q["bytes_saved"],
                           rc_over_this_peak_rss=q["peak_rss"])
            w.writerow({k: ("" if row.get(k) is None else row.get(k)) for k in _CSV_FIELDS})


def _fmt_bytes(b: float | None) -> str:
    if b is None:
        return "-"
    for unit, size in (("GiB", _GIB), ("MiB", 1 << 20), ("KiB", 1 << 10)):
        if b >= size:
            return f"{b / size:.1f} {unit}"
    return f"{int(b)} B"


def _fmt_ratio(x: float | None) -> str:
    if x is None:
        return "-"
    return "0" if x == 0 else (f"{x:.3f}" if x >= 0.01 else f"{x:.1e}")


def format_table(report: dict) -> str:
    """A plain-text table of the runs and RC's ratios."""
    lines = [f"revcol bench statesave: {report['transport']} transport, N_c = {report['collisions']:,}, "
             f"{report['repeats']} repeat(s), budget {_gib(report['budget_bytes'])}",
             f"{'mode':6s} {'N':>9s} {'variant':8s} {'forward ms':>11s} {'rollback ms':>12s} "
             f"{'saved':>10s} {'peak RSS':>10s} {'max rel err':>11s}  status"]
    for r in report["runs"]:
        if r["skipped"]:
            lines.append(f"{r['mode']:6s} {r['particles']:>9,} {_LABEL[r['variant']]:8s} {'-':>11s} {'-':>12s} "
                         f"{'-':>10s} {'-':>10s} {'-':>11s}  {r['status']}")
        else:
            lines.append(f"{r['mode']:6s} {r['particles']:>9,} {_LABEL[r['variant']]:8s} {r['forward_ms']:11.2f} "
                         f"{r['rollback_ms']:12.2f} {_fmt_bytes(r['bytes_saved']):>10s} "
                         f"{_fmt_bytes(r['peak_rss_bytes']):>10s} {r['max_rel_error']:11.2e}  {r['status']}")
    lines.append("RC / state saving (time: total; saved: bytes saved; RSS: peak resident set):")
    for q in report["ratios"]:
        lines.append(f"  {q['mode']:6s} N={q['particles']:>9,}  RC/{_LABEL[q['vs']]:7s} time {_fmt_ratio(q['time']):>7s}"
                     f"  saved {_fmt_ratio(q['bytes_saved']):>7s}  RSS {_fmt_ratio(q['peak_rss']):>7s}"
                     + (f"  ({q['note']})" if q["note"] else ""))
    lines.append("PASSED" if report["passed"] else "FAILED (a run did not restore its start, or RC was skipped)")
    return "\n".join(lines)


def plot(report: dict, path: str | os.PathLike) -> None:
    """Stacked forward/rollback bars per N (the paper's figure), memory bars below, ratios."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ns, modes, vs = report["particles"], report["modes"], report["variants"]
    runs = {(r["mode"], r["particles"], r["variant"]): r for r in report["runs"]}
    ncol = len(ns)
    nlines = len(modes) * (len(vs) - 1)
    fig, axes = plt.subplots(3, ncol, figsize=(3.6 * ncol + 0.8, 8.4 + 0.16 * nlines), squeeze=False,
                             gridspec_kw={"height_ratios": [3, 2, 0.35 + 0.16 * nlines]})
    xs, labels = [], []
    for a, m in enumerate(modes):
        for b, v in enumerate(vs):
            xs.append(a * (len(vs) + 0.6) + b)
            labels.append(_LABEL[v] + (f"\n{m}" if len(modes) > 1 else ""))
    for c, N in enumerate(ns):
        ax, mx, tx = axes[0][c], axes[1][c], axes[2][c]
        top = max([runs[(m, N, v)]["total_ms"] for m in modes for v in vs
                   if not runs[(m, N, v)]["skipped"]] + [1e-9])
        k = 0
        for m in modes:
            for v in vs:
                r, x = runs[(m, N, v)], xs[k]
                k += 1
                if r["skipped"]:
                    ax.bar(x, top * 0.25, 0.7, fill=False, hatch="//", edgecolor="0.6")
                    need = r["projected_bytes"] / _GIB
                    ax.text(x, top * 0.27, f"skip\nneeds\n{need:.0f} GiB" if need >= 100 else
                            f"skip\nneeds\n{need:.1f} GiB", ha="center", va="bottom", fontsize=6, color="0.3")
                    mx.bar(x - 0.18, r["projected_bytes"], 0.36, fill=False, hatch="//", edgecolor="C2")
                    continue
                ax.bar(x, r["forward_ms"], 0.7, color="C0", label="forward" if k == 1 else None)
                ax.bar(x, r["rollback_ms"], 0.7, bottom=r["forward_ms"], color="C1",
                       label="rollback" if k == 1 else None)
                if not r["restored"]:
                    ax.text(x, r["total_ms"], "FAILED", ha="center", va="bottom", color="red", fontsize=7)
                mx.bar(x - 0.18, max(r["bytes_saved"], 1), 0.36, color="C2")
                mx.bar(x + 0.18, r["peak_rss_bytes"], 0.36, color="C3")
                if r["variant"] == "rc":
                    mx.text(x - 0.18, max(r["bytes_saved"], 1) * 1.5, _fmt_bytes(r["bytes_saved"]),
                            ha="center", va="bottom", fontsize=6.5, rotation=90)
        ax.set_title(f"N = {N:,}", fontsize=10)
        ax.set_xticks(xs)
        ax.set_xticklabels(labels, fontsize=8)
        ax.set_ylim(0, top * 1.15)
        mx.set_yscale("log")
        mx.set_xticks(xs)
        mx.set_xticklabels(labels, fontsize=8)
        if c == 0:
            ax.set_ylabel("time (ms)")
            mx.set_ylabel("bytes")
        # RC's ratios under the column
        text = ["RC / state saving:  time  saved    RSS"]
        for q in report["ratios"]:
            if q["particles"] == N:
                pre = f"{q['mode']} " if len(modes) > 1 else ""
                text.append(f"{pre + 'RC/' + _LABEL[q['vs']]:<19s} {_fmt_ratio(q['time']):>5s} "
                            f"{_fmt_ratio(q['bytes_saved']):>7s} {_fmt_ratio(q['peak_rss']):>6s}")
        tx.axis("off")
        tx.text(0.0, 1.0, "\n".join(text), transform=tx.transAxes, va="top", fontsize=7, family="monospace")
    from matplotlib.patches import Patch
    handles = [Patch(color="C0", label="forward time"), Patch(color="C1", label="rollback time"),
               Patch(color="C2", label="bytes saved (hatched: projected, skipped)"),
               Patch(color="C3", label="peak RSS (fresh process)")]
    fig.legend(handles=handles, loc="lower center", ncol=4, fontsize=8, frameon=False)
    lazy = report["transport"] == "lazy"
    fig.suptitle(f"State saving vs reverse computation, {'lazy' if lazy else 'eager'} transport, "
                 f"N_c = {report['collisions']:,}, mode {'/'.join(report['modes'])}"
                 + (f" ({report['law']} law)" if "exact" in modes else ""), fontsize=11)
    fig.tight_layout(rect=(0, 0.04, 1, 0.96))
    fig.savefig(path, dpi=130)
    plt.close(fig)


# --- command line (revcol bench statesave) -------------------------------------------------

def _count(text: str) -> int:
    try:
        v = float(text) if any(ch in text.lower() for ch in "e.") else int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if v != int(v) or v < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return int(v)


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The options of ``revcol bench statesave``."""
    p.add_argument("--n", type=_count, nargs="+", default=[1000, 10000, 100000, 1000000],
                   help="particle counts N (default 1e3 1e4 1e5 1e6)")
    p.add_argument("--collisions", type=_count, default=1000, help="N_c (default 1000)")
    p.add_argument("--lazy", action="store_true", help="lazy transport (x0 = x - v t, O(1) per step)")
    p.add_argument("--mode", nargs="+", choices=MODES, default=["exact"], help="operator mode(s)")
    p.add_argument("--law", choices=("flux", "uniform"), default="flux", help="exact mode's law")
    p.add_argument("--variants", nargs="+", choices=("ss1", "ss2", "ssp", "rc"), default=None,
                   help="subset of variants (default: all the transport supports)")
    p.add_argument("--repeats", type=_count, default=3, help="runs per (mode, N, variant) (default 3)")
    p.add_argument("--budget-gib", type=float, default=8.0,
                   help="skip state saving that would save more (default 8 GiB)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--rng", choices=("clcg4", "philox"), default="clcg4")
    p.add_argument("--mean-dt", type=float, default=1e-5, help="mean inter-collision time")
    p.add_argument("--grazing-tol", type=float, default=1e-11, help="exact mode's pre log threshold")
    p.add_argument("--first-touch", action="store_true",
                   help="state saving faults its record pages in inside the forward time")
    p.add_argument("--binary", help="the revcol-bench to run (default: next to python, or on PATH)")
    p.add_argument("--inline", action="store_true", help="run in this process (peak RSS is then shared)")
    p.add_argument("--no-progress", action="store_true")
    p.add_argument("--json", metavar="FILE", help="write the report (and FILE's .csv next to it)")
    p.add_argument("--csv", metavar="FILE", help="write the runs as CSV (default: next to --json)")
    p.add_argument("--plot", metavar="FILE", help="write the stacked bar plot (PNG)")


def cli_main(args: argparse.Namespace, argv: Sequence[str] | None = None) -> int:
    """Runs ``revcol bench statesave`` from parsed arguments; exit code 0 when it passed."""
    command = "revcol " + " ".join(shlex.quote(a) for a in (sys.argv[1:] if argv is None else argv))
    try:
        report = study(args.n, args.collisions, lazy=args.lazy, modes=args.mode, law=args.law,
                       variants=args.variants, repeats=args.repeats, budget_gib=args.budget_gib,
                       seed=args.seed, rng=args.rng, mean_dt=args.mean_dt, grazing_tol=args.grazing_tol,
                       prefault=not args.first_touch, binary=args.binary, inline=args.inline,
                       progress=False if args.no_progress else None, command=command)
    except (ValueError, FileNotFoundError) as e:
        print(f"revcol bench statesave: error: {e}", file=sys.stderr)
        return 2
    print(format_table(report))
    written = []
    if args.json:
        write_json(report, args.json)
        written.append(args.json)
    csv_path = args.csv or (str(Path(args.json).with_suffix(".csv")) if args.json else None)
    if csv_path:
        write_csv(report, csv_path)
        written.append(csv_path)
    if args.plot:
        plot(report, args.plot)
        written.append(args.plot)
    if written:
        print("written: " + " ".join(written))
    return 0 if report["passed"] else 1
