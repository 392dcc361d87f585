"""What ``revcol sweep`` makes of its finished points: the table (CSV, and Parquet when pyarrow is
installed), the JSON summary, the horizon combined over seeds, and the figures.

The table is built from the point files of the sweep's own points, in the sweep's order, so it has
one row per finished point whatever ran when (a resumed sweep, a rerun task): never two.
Combining the horizon over seeds follows :func:`revcol.studies.horizon.horizon` exactly (per grid point
the worst error over the seeds, a seed that stopped counting as O(1); the median of the per-seed
worst; the horizon the largest N_c before the first grid point over the bar), so a sweep over
seeds 0 .. K-1 of one scene reports what ``revcol run --horizon --seeds K`` does.
"""
from __future__ import annotations

import csv
import datetime as dt
import io
import json
import os
from pathlib import Path

from .._io import atomic_open, save_figure
from .._version import __version__
from ..plots import _pyplot
from ..roundtrip import BAR, combine_seeds

__all__ = ["gather", "combine_horizon", "table_rows", "output_names"]

# report keys left out of the table: long text, or lists
_SKIP = {"summary", "written", "error_definitions"}


def _scalar(v) -> bool:
    return v is None or isinstance(v, (bool, int, float, str))


def table_rows(spec, points: list[dict]) -> list[dict]:
    """One row per finished point: index, hash, its parameters, the report's scalars and its run."""
    rows = []
    for d in points:
        row = {"index": d["index"], "hash": d["hash"]}
        row.update({k: (json.dumps(v) if not _scalar(v) else v) for k, v in d["point"].items()})
        row.update({k: v for k, v in d["report"].items() if k not in _SKIP and _scalar(v) and k not in row})
        row.update({"seconds": d["seconds"], "host": d["host"], "pid": d["pid"]})
        rows.append(row)
    return rows


def _write_table(path: Path, rows: list[dict]) -> list[str]:
    cols: list[str] = []
    for r in rows:
        cols += [k for k in r if k not in cols]
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=cols, lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    with atomic_open(path) as f:
        f.write(buf.getvalue())
    written = [str(path)]
    try:
        import pyarrow as pa  # optional: the parquet table only when pyarrow is installed
        import pyarrow.parquet as pq  # optional: the parquet table only when pyarrow is installed
    except ImportError:
        return written
    columns = {}
    for c in cols:  # one type a column: a column mixing text and numbers (e.g. "inf") is text
        values = [r.get(c) for r in rows]
        kinds = {type(v) for v in values if v is not None}
        mixed = str in kinds and len(kinds) > 1
        columns[c] = [str(v) if mixed and v is not None else v for v in values]
    try:
        table = pa.table(columns)
    except (pa.ArrowInvalid, pa.ArrowTypeError):  # the CSV has it all; Parquet is a convenience
        return written
    with atomic_open(path.with_suffix(".parquet"), "wb") as f:
        pq.write_table(table, f)
    return written + [str(path.with_suffix(".parquet"))]


def combine_horizon(reports: list[dict]) -> dict | None:
    """The horizon of several one-seed horizon reports of one scene (in seed order), as
    ``revcol run --horizon --seeds K`` reports it; None when they cannot be combined (a report of
    more than one seed, or different grids)."""
    if not reports or any(r.get("kind") != "horizon" or r.get("seeds") != 1 for r in reports):
        return None
    n = int(reports[0]["scene"]["particles"])
    if reports[0].get("engine") == "lattice":
        rows: dict[int, dict] = {}
        for r in reports:
            for row in r["rows"]:
                c = rows.setdefault(row["collisions"], {"collisions": row["collisions"], "per_particle":
                                                        row["per_particle"], "bit_for_bit": 0, "seeds": 0,
                                                        "errors": []})
                c["bit_for_bit"] += row["bit_for_bit"]
                c["seeds"] += row["seeds"]
                c["errors"] += row["errors"]
        table = [rows[k] for k in sorted(rows)]
        return {"engine": "lattice", "seeds": len(reports), "seed_first": reports[0]["seed_first"], "rows": table,
                "passed": all(r["bit_for_bit"] == r["seeds"] for r in table), "horizon_reached": False}
    grid = [row["collisions"] for row in max((r["rows"] for r in reports), key=len)]
    if any([row["collisions"] for row in r["rows"]] != grid[:len(r["rows"])] for r in reports):
        return None
    per_seed = [[(float(row["error_x"]), float(row["error_v"])) for row in r["rows"]] for r in reports]
    table, h = combine_seeds(grid, n, per_seed)
    return {"engine": "float", "seeds": len(reports), "seed_first": reports[0]["seed_first"], "rows": table,
            "horizon_collisions": h, "horizon_per_particle": 2.0 * h / n,
            "horizon_reached": any(max(r["error_x"], r["error_v"]) > BAR for r in table)}


def _groups(spec, points: list[dict]) -> list[dict]:
    """The horizon points grouped by every varied parameter but the seed, each group combined."""
    groups: dict[str, list[dict]] = {}
    for d in points:
        key = json.dumps({k: d["point"][k] for k in spec.varied if k != "seed"}, default=str)
        groups.setdefault(key, []).append(d)
    out = []
    for key, ds in groups.items():
        ds = sorted(ds, key=lambda d: d["report"]["seed_first"])
        c = combine_horizon([d["report"] for d in ds])
        if c is not None:
            out.append({"point": json.loads(key), **c})
    return out


def gather(spec, out: Path, state, *, reused: int, seconds: float, load, log, output_estimate: dict | None = None) -> dict:
    """Writes ``NAME.csv`` (+ ``.parquet``), the figures and ``NAME.json``; returns the summary
    (``output_estimate``: the bytes each output was estimated to take, checked before the start)."""
    points, missing = [], []
    for p in spec.points:
        d = read_point(out, p.hash)
        (points.append(d) if d is not None else missing.append({"index": p.index, "point": p.params}))
    written = _write_table(out / f"{spec.name}.csv", table_rows(spec, points)) if points else []
    combined = _groups(spec, points) if spec.study == "horizon" else []
    figures = _figures(spec, out, combined)
    summary = {
        "kind": "sweep", "name": spec.name, "description": spec.description, "study": spec.study,
        "scene": spec.scene_name, "source": spec.source, "out": str(out), "points": len(spec.points),
        "done": len(points), "missing": missing, "failed": state.failed, "ran": state.ran, "reused": reused,
        "interrupted": state.interrupted, "complete": not missing, "cluster": state.cluster,
        "seconds": seconds, "loadavg_start": list(load[0]), "loadavg_end": list(load[1]),
        "cpu_count": os.cpu_count(), "revcol": __version__, "combined": combined, "table": written,
        "figures": figures, "output_estimate": output_estimate or {},
        "date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
    }
    with atomic_open(out / f"{spec.name}.json") as f:
        json.dump(summary, f, indent=1, default=str)
    log(f"revcol sweep {spec.name}: {len(points)}/{len(spec.points)} points done ({state.ran} run now, {reused} "
        f"reused, {len(state.failed)} failed) in {seconds:.1f} s; table {written[0] if written else '(none)'}")
    return summary


def _figures(spec, out: Path, combined: list[dict]) -> list[str]:
    """Float-engine horizon only: horizon against the first varied parameter, and the worst error
    against collisions per particle, one line per group (matplotlib; none without it)."""
    groups = [g for g in combined if g["engine"] == "float"]
    if not groups:
        return []
    try:
        plt = _pyplot()
    except ImportError:  # no matplotlib: the table and the summary say it all
        return []
    written = []
    fig, ax = plt.subplots(figsize=(6, 4))
    for g in groups:
        x = [r["per_particle"] for r in g["rows"]]
        y = [max(r["error_x"], r["error_v"]) for r in g["rows"]]
        ax.loglog(x, y, marker="o", ms=3, label=", ".join(f"{k}={v}" for k, v in g["point"].items()) or spec.name)
    ax.axhline(BAR, color="k", lw=0.8, ls="--")
    ax.set(xlabel="collisions per particle (2 N_c / N)", ylabel=f"worst round-trip error over {groups[0]['seeds']} "
           "seeds", title=spec.name)
    if len(groups) <= 12:
        ax.legend(fontsize=7)
    path = out / f"{spec.name}-error.png"
    save_figure(fig, path, dpi=120, bbox_inches="tight")
    plt.close(fig)
    written.append(str(path))
    numeric = [k for k, v in groups[0]["point"].items() if isinstance(v, (int, float)) and not isinstance(v, bool)]
    if numeric and len(groups) > 1:
        xkey, lines = numeric[0], {}
        for g in groups:
            rest = ", ".join(f"{k}={v}" for k, v in g["point"].items() if k != xkey)
            lines.setdefault(rest, []).append((g["point"][xkey], g["horizon_per_particle"]))
        fig, ax = plt.subplots(figsize=(6, 4))
        for label, pts in lines.items():
            pts.sort()
            ax.plot([a for a, _ in pts], [b for _, b in pts], marker="o", label=label or None)
        ax.set(xlabel=xkey, ylabel="horizon (collisions per particle)", title=spec.name)
        if any(lines):
            ax.legend(fontsize=7)
        path = out / f"{spec.name}-horizon.png"
        save_figure(fig, path, dpi=120, bbox_inches="tight")
        plt.close(fig)
        written.append(str(path))
    return written



def output_names(spec) -> tuple[frozenset[str], frozenset[str]]:
    """The file names a sweep writes into its folder (table, summary, figures) and into its
    ``points`` folder (one per point): what revcol._outputs checks against the sweep's inputs."""
    top = frozenset(f"{spec.name}{end}" for end in (".csv", ".parquet", ".json", "-error.png", "-horizon.png"))
    return top, frozenset(point_path(Path("."), p.hash).name for p in spec.points)


def point_path(out: Path, h: str) -> Path:
    """Where the point with hash ``h`` is written."""
    return out / "points" / f"{h}.json"


def read_point(out: Path, h: str) -> dict | None:
    """The finished point with hash ``h``, or None (absent, or not a whole point file)."""
    try:
        d = json.loads(point_path(out, h).read_text())
    except (OSError, ValueError):
        return None
    return d if isinstance(d, dict) and d.get("hash") == h and isinstance(d.get("report"), dict) else None
