"""The state-saving study's outputs: JSON, CSV (one row per run, with RC's ratios), a
plain-text table and the stacked-bar figure (the paper's, with memory bars and ratios).
"""
from __future__ import annotations

import csv
import json
import os
from pathlib import Path

from ..._io import atomic_open, save_figure
from ...statesave import _GIB, _LABEL, _gib

__all__ = ["write_json", "write_csv", "format_table", "plot"]


def write_json(report: dict, path: str | os.PathLike) -> None:
    """The report as indented JSON."""
    with atomic_open(path) as f:
        f.write(json.dumps(report, indent=1) + "\n")


_CSV_FIELDS = ["mode", "transport", "variant", "particles", "collisions", "status", "forward_ms",
               "rollback_ms", "total_ms", "total_ms_min", "total_ms_max", "bytes_saved", "projected_bytes", "record_bytes",
               "peak_rss_bytes", "rss_before_bytes", "state_bytes", "max_rel_error", "max_rel_error_x",
               "max_rel_error_v", "restored", "bit_exact", "log_bytes", "pre_log_entries",
               "decision_log_entries", "rare_log_entries", "rc_over_this_time",
               "rc_over_this_bytes_saved", "rc_over_this_peak_rss", "rc_over_this_time_paired_median",
               "rc_over_this_time_paired_min", "rc_over_this_time_paired_max"]


def write_csv(report: dict, path: str | os.PathLike) -> None:
    """One row per run; state-saving rows carry RC's ratios to them."""
    ratio = {(q["mode"], q["particles"], q["vs"]): q for q in report["ratios"]}
    with atomic_open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=_CSV_FIELDS, extrasaction="ignore")
        w.writeheader()
        for r in report["runs"]:
            row = dict(r)
            q = ratio.get((r["mode"], r["particles"], r["variant"]))
            if q:
                row.update(rc_over_this_time=q["time"], rc_over_this_bytes_saved=q["bytes_saved"],
                           rc_over_this_peak_rss=q["peak_rss"],
                           rc_over_this_time_paired_median=q.get("time_paired_median"),
                           rc_over_this_time_paired_min=q.get("time_paired_min"),
                           rc_over_this_time_paired_max=q.get("time_paired_max"))
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
             f"{report['repeats']} repeat(s) interleaved, budget {_gib(report['budget_bytes'])}"
             + (f", pinned to core {report['cpu']}" if report.get("cpu") is not None else "")
             + (f", load {report['load_1m_start']:.2f} -> {report['load_1m_end']:.2f}"
                if report.get("load_1m_start") is not None else ""),
             f"{'mode':6s} {'N':>9s} {'variant':8s} {'forward ms':>11s} {'rollback ms':>12s} "
             f"{'total ms [range]':>24s} {'saved':>10s} {'peak RSS':>10s} {'max rel err':>11s}  status"]
    for r in report["runs"]:
        if r["skipped"]:
            lines.append(f"{r['mode']:6s} {r['particles']:>9,} {_LABEL[r['variant']]:8s} {'-':>11s} {'-':>12s} "
                         f"{'-':>24s} {'-':>10s} {'-':>10s} {'-':>11s}  {r['status']}")
        else:
            span = f"{r['total_ms']:.2f} [{r['total_ms_min']:.2f}, {r['total_ms_max']:.2f}]" \
                if r.get("total_ms_min") is not None else f"{r['total_ms']:.2f}"
            lines.append(f"{r['mode']:6s} {r['particles']:>9,} {_LABEL[r['variant']]:8s} {r['forward_ms']:11.2f} "
                         f"{r['rollback_ms']:12.2f} {span:>24s} {_fmt_bytes(r['bytes_saved']):>10s} "
                         f"{_fmt_bytes(r['peak_rss_bytes']):>10s} {r['max_rel_error']:11.2e}  {r['status']}")
    lines.append("RC / state saving (time: total of the medians, and round by round: median [range] of the "
                 "paired ratios; saved: bytes saved; RSS: peak resident set):")
    for q in report["ratios"]:
        paired = (f" paired {_fmt_ratio(q['time_paired_median'])} [{_fmt_ratio(q['time_paired_min'])}, "
                  f"{_fmt_ratio(q['time_paired_max'])}]" if q.get("time_paired_median") is not None else "")
        lines.append(f"  {q['mode']:6s} N={q['particles']:>9,}  RC/{_LABEL[q['vs']]:7s} time {_fmt_ratio(q['time']):>7s}"
                     f"{paired}  saved {_fmt_ratio(q['bytes_saved']):>7s}  RSS {_fmt_ratio(q['peak_rss']):>7s}"
                     + (f"  ({q['note']})" if q["note"] else ""))
    lines.append("PASSED" if report["passed"] else "FAILED (a run did not restore its start, or RC was skipped)")
    return "\n".join(lines)


def _md_ratio(q: dict) -> str:
    if q.get("time_paired_median") is None:
        return "-"
    return (f"{_fmt_ratio(q['time_paired_median'])} [{_fmt_ratio(q['time_paired_min'])}, "
            f"{_fmt_ratio(q['time_paired_max'])}]")


def markdown(report: dict, name: str = "statesave.json") -> str:
    """The docs' tables of a report: one table of runs per mode (the median repeat's times,
    the range of the totals) and the ratios RC / state saving (the paired ratios' median and
    range over the interleaved rounds, bytes saved, peak RSS)."""
    out = []
    n_c = f"N_c = {report['collisions']:,}"
    for mode in report["modes"]:
        out += [f"**{name}, mode {mode}** ({n_c}; times: the repeat with the median total of {report['repeats']}, "
                "and the range of the totals)", "",
                "| N | variant | forward ms | rollback ms | total ms [range] | bytes saved | peak RSS | max rel error |",
                "|---:|---|---:|---:|---:|---:|---:|---:|"]
        for r in report["runs"]:
            if r["mode"] != mode:
                continue
            if r["skipped"]:
                out.append(f"| {r['particles']:,} | {_LABEL[r['variant']]} | – | – | – | {r['status']} | – | – |")
                continue
            span = f"{r['total_ms']:.2f} [{r['total_ms_min']:.2f}, {r['total_ms_max']:.2f}]"
            out.append(f"| {r['particles']:,} | {_LABEL[r['variant']]} | {r['forward_ms']:.2f} | {r['rollback_ms']:.2f} | "
                       f"{span} | {r['bytes_saved']:,} | {_fmt_bytes(r['peak_rss_bytes'])} | {r['max_rel_error']:.2e} |")
        out.append("")
    vs = [v for v in report["variants"] if v != "rc"]
    head = " | ".join(f"RC/{_LABEL[v]} time [range] | saved | RSS" for v in vs)
    out += [f"**{name}: RC / state saving** (time: the median and range of RC's total over the state "
            "saving's, round by round; saved: bytes saved, against the projection where state saving was "
            "skipped; RSS: peak resident set of each fresh process)", "",
            f"| mode | N | {head} |", "|---|---:|" + "---:|---:|---:|" * len(vs)]
    by = {(q["mode"], q["particles"], q["vs"]): q for q in report["ratios"]}
    for mode in report["modes"]:
        for n in report["particles"]:
            cells = []
            for v in vs:
                q = by.get((mode, n, v))
                cells.append("- | - | -" if q is None else
                             f"{_md_ratio(q)} | {_fmt_ratio(q['bytes_saved'])} | {_fmt_ratio(q['peak_rss'])}")
            out.append(f"| {mode} | {n:,} | " + " | ".join(cells) + " |")
    return "\n".join(out)


def plot(report: dict, path: str | os.PathLike) -> None:
    """Stacked forward/rollback bars per N (the paper's figure) with each total's range over
    the repeats, and the memory bars below (log scale; a variant that saved 0 bytes gets no
    bar and a "0 B" label, never a bar at 1 byte). The ratios are in the table, not here.
    The format follows the file's suffix (.png, .pdf, .svg)."""
    import matplotlib  # optional (the plot extra): imported only when a figure is drawn
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # optional (the plot extra): imported only when a figure is drawn

    ns, modes, vs = report["particles"], report["modes"], report["variants"]
    runs = {(r["mode"], r["particles"], r["variant"]): r for r in report["runs"]}
    ncol = len(ns)
    fig, axes = plt.subplots(2, ncol, figsize=(3.6 * ncol + 0.8, 7.2), squeeze=False,
                             gridspec_kw={"height_ratios": [3, 2]})
    xs, labels = [], []
    for a, m in enumerate(modes):
        for b, v in enumerate(vs):
            xs.append(a * (len(vs) + 0.6) + b)
            labels.append(_LABEL[v] + (f"\n{m}" if len(modes) > 1 else ""))
    for c, N in enumerate(ns):
        ax, mx = axes[0][c], axes[1][c]
        done = [runs[(m, N, v)] for m in modes for v in vs if not runs[(m, N, v)]["skipped"]]
        top = max([r.get("total_ms_max") or r["total_ms"] for r in done] + [1e-9])
        mem = [b for r in done for b in (r["bytes_saved"], r["peak_rss_bytes"]) if b] + \
              [r["projected_bytes"] for m in modes for v in vs for r in [runs[(m, N, v)]] if r["skipped"]]
        floor = min(mem + [1 << 20]) / 8
        k = 0
        for m in modes:
            for v in vs:
                r, x = runs[(m, N, v)], xs[k]
                k += 1
                if r["skipped"]:
                    ax.bar(x, top * 0.25, 0.7, fill=False, hatch="//", edgecolor="0.6")
                    need = r["projected_bytes"] / _GIB
                    ax.text(x, top * 0.27, f"skipped\nneeds\n{need:.0f} GiB" if need >= 100 else
                            f"skipped\nneeds\n{need:.1f} GiB", ha="center", va="bottom", fontsize=6, color="0.3")
                    mx.bar(x - 0.18, r["projected_bytes"], 0.36, fill=False, hatch="//", edgecolor="C2")
                    continue
                ax.bar(x, r["forward_ms"], 0.7, color="C0")
                ax.bar(x, r["rollback_ms"], 0.7, bottom=r["forward_ms"], color="C1")
                if r.get("total_ms_min") is not None and len(r["total_ms_all"]) > 1:
                    ax.errorbar(x, r["total_ms"], yerr=[[r["total_ms"] - r["total_ms_min"]],
                                                        [r["total_ms_max"] - r["total_ms"]]],
                                fmt="none", ecolor="k", elinewidth=0.8, capsize=2)
                if not r["restored"]:
                    ax.text(x, r["total_ms"], "FAILED", ha="center", va="bottom", color="red", fontsize=7)
                if r["bytes_saved"] > 0:
                    mx.bar(x - 0.18, r["bytes_saved"], 0.36, color="C2")
                else:
                    mx.text(x - 0.18, floor * 1.3, "0 B", ha="center", va="bottom", fontsize=6.5, rotation=90)
                mx.bar(x + 0.18, r["peak_rss_bytes"], 0.36, color="C3")
                if r["variant"] == "rc" and r["bytes_saved"] > 0:
                    mx.text(x - 0.18, r["bytes_saved"] * 1.5, _fmt_bytes(r["bytes_saved"]),
                            ha="center", va="bottom", fontsize=6.5, rotation=90)
        ax.set_title(f"N = {N:,}", fontsize=10)
        ax.set_xticks(xs)
        ax.set_xticklabels(labels, fontsize=8)
        ax.set_ylim(0, top * 1.15)
        mx.set_yscale("log")
        mx.set_ylim(bottom=floor)
        mx.set_xticks(xs)
        mx.set_xticklabels(labels, fontsize=8)
        if c == 0:
            ax.set_ylabel("time per run (ms)")
            mx.set_ylabel("bytes")
    from matplotlib.patches import Patch  # optional (the plot extra): imported only when a figure is drawn
    from matplotlib.lines import Line2D  # optional (the plot extra): imported only when a figure is drawn
    handles = [Patch(color="C0", label="forward time"), Patch(color="C1", label="rollback time"),
               Line2D([], [], color="k", lw=0.8, label=f"range of {report['repeats']} interleaved repeats"),
               Patch(color="C2", label="bytes saved (hatched: projected, skipped)"),
               Patch(color="C3", label="peak RSS (fresh process)")]
    # at most 3 entries a row: five in one row were wider than a figure of two columns (issue 58:
    # "ard time" at the left edge)
    fig.legend(handles=handles, loc="lower center", ncol=min(3, max(2, ncol + 1)), fontsize=8, frameon=False)
    lazy = report["transport"] == "lazy"
    fig.suptitle(f"State saving vs reverse computation, {'lazy' if lazy else 'eager'} transport, "
                 f"N_c = {report['collisions']:,}, mode {'/'.join(report['modes'])}"
                 + (f" ({report['law']} law)" if "exact" in modes else ""), fontsize=11)
    fig.tight_layout(rect=(0, 0.09, 1, 0.96))
    save_figure(fig, path, dpi=130)
    plt.close(fig)
