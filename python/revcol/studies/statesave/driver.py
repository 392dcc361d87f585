"""The state-saving study (:func:`study`): every (mode, N, variant), each repeat in a fresh
``revcol-bench`` process (so that its peak resident set is its own) or in this process,
with the repeat of median total time reported; runs over the budget are skipped with their
projection, and RC's ratios to each state-saving variant are computed.

The machines are shared, so the variants of one (mode, N) are *interleaved*: round r runs
every variant once (the order reversed on odd rounds: A B, B A, ...), so that a change in the
machine's load hits all of them alike. Each run records the 1-minute load average before it;
``cpu=K`` pins every run to core K (``taskset``). The ratios RC / SS are given for the medians
and, round by round, as the median and range of the paired ratios.
"""
from __future__ import annotations

import datetime as dt
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Callable, Iterable, Sequence

from ... import _core
from ...statesave import MODES, _LABEL, _MAX_PARTICLES, _gib, _int, _kwargs, _supported

__all__ = ["study", "find_binary"]


def find_binary(explicit: str | None) -> str:
    """The ``revcol-bench`` to run: ``explicit``, ``$REVCOL_BENCH``, next to this Python, or
    on PATH; FileNotFoundError (ValueError for a bad ``explicit``) when there is none."""
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



_find_binary = find_binary


def _skip_text(projected: int) -> str:
    return f"skipped: needs {_gib(projected)} ({projected / 1e9:.1f} GB)"


class _Progress:
    """tqdm when installed, else a one-line bar; silent unless stdout is a terminal."""

    def __init__(self, total: int, enabled: bool | None):
        self.enabled = sys.stdout.isatty() if enabled is None else enabled
        self.total, self.done, self.bar = total, 0, None
        if self.enabled:
            try:
                from tqdm import tqdm  # only when a progress bar is drawn
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


def _run_process(binary: str, kw: dict, repeats: int, cpu: int | None = None) -> list[dict]:
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
        if cpu is not None:
            cmd = ["taskset", "-c", str(cpu)] + cmd
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
        "total_ms_all": [1e3 * t for t in totals],
        "total_ms_min": 1e3 * min(totals), "total_ms_max": 1e3 * max(totals),
        "load_1m_all": [x.get("load_1m") for x in reps],
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
                "total_ms_all": [], "total_ms_min": None, "total_ms_max": None, "load_1m_all": [],
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
            # round by round: RC's k-th run against SS's k-th, run next to each other
            paired = sorted(a / b for a, b in zip(rc["total_ms_all"], s["total_ms_all"]) if b > 0) if ran else []
            out.append({
                "mode": mode, "particles": n, "vs": v2,
                "time": rc["total_ms"] / s["total_ms"] if ran and s["total_ms"] > 0 else None,
                "time_paired_median": paired[(len(paired) - 1) // 2] if paired else None,
                "time_paired_min": paired[0] if paired else None,
                "time_paired_max": paired[-1] if paired else None,
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


def _rows(runs: list[dict], vs: Sequence[str], kws: dict, projs: dict, reps: dict) -> None:
    """Appends the rows of one (mode, N): skipped over the budget, or its repeats' summary."""
    for v in vs:
        p = projs[v]
        if p["over_budget"]:
            runs.append(_skipped_row(kws[v], p["record_bytes"], p["projected_bytes"]))
        else:
            row = _row(kws[v], reps[v], p["record_bytes"], p["projected_bytes"])
            row["status"] = "ok" if row["restored"] else "FAILED"
            runs.append(row)


class _Stopped(Exception):
    """``stop()`` said to end the study."""


def study(n: Iterable[int] = (1000, 10000, 100000, 1000000), collisions: int = 1000, *,
          lazy: bool = False, modes: Sequence[str] = ("exact",), law: str = "flux",
          variants: Sequence[str] | None = None, repeats: int = 3, budget_gib: float = 8.0,
          seed: int = 0, rng: str = "clcg4", mean_dt: float = 1e-5, grazing_tol: float = 1e-11,
          prefault: bool = True, binary: str | None = None, inline: bool = False,
          progress: bool | None = None, command: str | None = None,
          stop: Callable[[], bool] | None = None, cpu: int | None = None) -> dict:
    """Runs every (mode, N, variant) and returns the report (see the module doc).

    Each repeat is a fresh ``revcol-bench`` process (``binary``: explicit, ``$REVCOL_BENCH``,
    next to this Python, or on PATH), the variants of one (mode, N) interleaved round by
    round; ``inline=True`` runs in this process instead (peak RSS is then this whole
    process's). ``cpu``: pin each process to that core (``taskset -c``). Runs whose saved
    state exceeds ``budget_gib`` are not attempted. ``progress``: None = when stdout is a
    terminal. ``stop``: asked before each run; when it returns True the study ends there
    (the report has the rows of the runs done, those of the (mode, N) under way with the
    repeats they got, ``interrupted`` True and ``not_run`` the (mode, N, variant) rows left
    out).
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
    if cpu is not None:
        cpu = _int(cpu, "cpu", 0, (os.cpu_count() or 1) - 1)
        if inline:
            raise ValueError("cpu pins the fresh processes: it needs inline=False")
        if shutil.which("taskset") is None:
            raise FileNotFoundError("cpu needs taskset (util-linux), which is not on PATH")

    groups = [(m, N) for m in modes for N in ns]
    bar = _Progress(len(groups) * len(vs) * repeats, progress)
    runs = []
    not_run = 0
    loads = [os.getloadavg()[0]]
    try:
        for g, (m, N) in enumerate(groups):
            kws = {v: dict(base, mode=m, particles=N, variant=v) for v in vs}
            projs = {v: _core.statesave_projected_bytes(**kws[v]) for v in vs}
            live = [v for v in vs if not projs[v]["over_budget"]]
            reps: dict[str, list[dict]] = {v: [] for v in live}
            for r in range(repeats):
                for v in (live if r % 2 == 0 else live[::-1]):
                    if stop is not None and stop():
                        raise _Stopped
                    load = os.getloadavg()[0]
                    one = _run_inline(kws[v], 1) if inline else _run_process(exe, kws[v], 1, cpu)
                    one[0]["load_1m"] = load
                    reps[v] += one
                    bar.update(f"{m} N={N:,} {_LABEL[v]} {r + 1}/{repeats}")
            _rows(runs, vs, kws, projs, reps)
    except _Stopped:  # the group under way keeps the variants that ran at least once
        _rows(runs, [v for v in vs if reps.get(v)], kws, projs, reps)
        not_run = len(groups) * len(vs) - len(runs)
    finally:
        bar.close()
    loads.append(os.getloadavg()[0])
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
        "time_note": (f"the repeat with the median total of {repeats}, the variants of each (mode, N) "
                      "interleaved round by round, each repeat a fresh process"),
        "cpu": cpu, "load_1m_start": loads[0], "load_1m_end": loads[-1],
        "binary": exe, "command": command, "machine": _machine(),
        "date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
        "runs": runs, "ratios": _ratios(runs), "passed": passed,
        "interrupted": not_run > 0, "not_run": not_run,
    }


