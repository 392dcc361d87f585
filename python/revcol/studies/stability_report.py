"""The stability suite's report (``python -m revcol.studies.stability --markdown``): one markdown
table per class, each operator's worst round trip, law and failures, from the suite's results
(:func:`revcol.studies.stability.run`).
"""
from __future__ import annotations

import math

__all__ = ["markdown", "progress_line"]



def _fmt(x) -> str:
    return "-" if x is None else (f"{x:.2e}" if isinstance(x, float) else str(x))


def progress_line(r: dict) -> str:
    if not r.get("applies", True):
        return f"{r['operator']:28s} {r['class']:10s} n/a: {r['why']}"
    extra = (f"growth {_fmt(r.get('growth_exponent'))} bit_exact {r['bit_exact_all']}" if r["class"] == "chains"
             else f"law_D {_fmt(r.get('law_D'))} refused {r['refused']} nonfinite {r['nonfinite']} "
                  f"mismatch {r['mismatch']}")
    return (f"{r['operator']:28s} {r['class']:10s} roundtrip {_fmt(r['roundtrip'])} failures {r['failures']} "
            f"log {_fmt(r['log_rate'])} {extra} ({r['seconds']:.1f} s)")


def _span(values) -> str:
    v = [r["value"] for r in values]
    return f"{v[0]:.0e} .. {v[-1]:.0e}" if len(v) > 1 else f"{v[0]:g}"


def _failed_at(values) -> str:
    bad = [r for r in values if r["failures"]]
    if not bad:
        return ""
    kinds = sorted({k for r in bad for k in ("refused", "nonfinite", "mismatch") if r[k]})
    return f" at {_span(bad)} ({', '.join(kinds)})"


def _magnitude_row(r: dict, q, law: str) -> str:
    """Magnitudes: the scales handled, and those refused (below and above) with their message."""
    done = [v for v in r["values"] if v["refused"] < r["count"]]
    lo = min((v["value"] for v in done), default=math.inf)
    parts = []
    for side in ([v for v in r["values"] if v["value"] < lo], [v for v in r["values"] if v["value"] > lo and v not in done]):
        if side:
            msgs = sorted({v["first_refusal"].split(":")[0] for v in side})
            parts.append(f"refused {_span(side)} (" + "; ".join(f'"{m}"' for m in msgs) + ")")
    other = sum(v["nonfinite"] + v["mismatch"] + v["refused"] for v in done)
    said = ", ".join(parts) if parts else "none refused"
    return (f"| magnitude | handled {_span(done)}, {said} | {_fmt(r['roundtrip'])} | {_fmt(q)} "
            f"| {law} | {other} / {r['count'] * len(done)} handled{_failed_at(done)} | {_fmt(r['log_rate'])} |")


def markdown(res: dict) -> str:
    """One table per operator, a row per class, from a :func:`run` result."""
    out = []
    by: dict = {}
    for r in res["results"]:
        by.setdefault(r["operator"], []).append(r)
    for name, rows in by.items():
        out += [f"### {name}", "",
                "| class | values | worst round trip | quantization | law KS D (bound) | failures / round trips "
                "| rare log per collision |", "|---|---|---|---|---|---|---|"]
        for r in rows:
            if not r.get("applies", True):
                out.append(f"| {r['class']} | n/a: {r['why']} | | | | | |")
            elif r["class"] == "chains":
                last = r["values"][-1]
                drift = ("bit for bit at every length" if r["bit_exact_all"] else
                         f"growth exponent {_fmt(r['growth_exponent'])}")
                out.append(f"| chains | 1e2 .. {last['collisions']:.0e} collisions | {_fmt(r['roundtrip'])} "
                           f"({drift}) | | | {r['failures']} of {len(r['values'])} lengths fail verify "
                           f"| {_fmt(r['log_rate'])} |")
            else:
                q = max((v["quantization"] for v in r["values"] if v.get("quantization") is not None), default=None)
                law = "-" if r["law_D"] is None else f"{r['law_D']:.2g} ({r['law_D_bound']:.2g})"
                n = r["count"] * len(r["values"])
                extra = f"; {r['not_pre']} not pre states" if r.get("not_pre") else ""
                if r["class"] == "magnitude":
                    out.append(_magnitude_row(r, q, law))
                    continue
                out.append(f"| {r['class']} | {_span(r['values'])} | {_fmt(r['roundtrip'])} | {_fmt(q)} | {law} "
                           f"| {r['failures']} / {n}{_failed_at(r['values'])}{extra} | {_fmt(r['log_rate'])} |")
        out.append("")
    return "\n".join(out)
