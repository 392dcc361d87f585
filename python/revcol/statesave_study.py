"""The state-saving study (:func:`study`): every (mode, N, variant), each in a fresh
``revcol-bench`` process (so that its peak resident set is its own) or in this process,
repeated, with the repeat of median total time reported; runs over the budget are skipped
with their projection, and RC's ratios to each state-saving variant are computed.
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

from . import _core
from .statesave_run import MODES, _LABEL, _MAX_PARTICLES, _gib, _int, _kwargs, _supported

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


