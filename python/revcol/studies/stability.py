"""The numerical stress suite (issue 18): every collision operator at the edges of its domain.

For each operator (pair1d, pair2d, every named exact case with the flux and the uniform law,
the paper-mode operators) and each named stress class, the suite builds pre-collision states,
runs forward and then reverse with the same draws, and reports

- ``roundtrip``: the worst max |v_back - v_pre| / max |v_pre| (the speed scale, DESIGN §6);
  ``roundtrip_rel``: the same for the relative velocities v_i - v_j against their largest;
- ``law_D``: the largest one-sample KS distance of a post chart coordinate from uniform, for
  the class's most extreme pre state. Exact mode's chart is measure preserving, so every
  coordinate of the post state is uniform on (0, 1) under the operator's own law whatever the
  pre state; the paper operators are measured with the chart of exact mode's ``uniform`` law
  (the law the paper intends), so their figure includes the bias docs/paper-findings.md
  reports; none is given for the paper's 2D triple (its post states need not separate);
- ``failures``: named errors (``refused``: revcol's InvalidArgument), non-finite outputs and
  reversal mismatches (round trip above :data:`MISMATCH`), over ``count`` round trips;
- ``log_rate``: rare-log pushes per forward collision.

The classes (docs/stability.md says what each one means for each operator):

1. ``grazing``: one contact's approach at angle alpha = 1e-1 .. 1e-15 from its tangent plane
   (sin alpha = normal speed / (|a_k| |x|) in the zero-momentum coordinates x);
2. ``head-on``: relative velocities exactly along the contact normals (the chart's eta = 0);
3. ``pole``: theta = 1e-1 .. 1e-15 away from head-on (the 3D pole; eta -> 0 in 2D), pre states
   (forward, then reverse) and post states (reverse, then forward);
4. ``edges``: every contact, or every contact but one, approaching at delta = 1e-16 .. 1e-6 of
   the speed scale (eta -> pi/2, the vertices of the spherical triangle, and for the 1D triple
   the paper's region edge b' - c' -> 0 near Newton's cradle);
5. ``cm-speed``: centre-of-mass speed / relative speed R = 1 .. 1e12;
6. ``magnitude``: all velocities scaled by 1e-150 .. 1e150 and subnormals: each scale either
   handled (round trip within tolerance) or refused with a named error;
7. ``chains``: the reversal illustrations of ``revcol.verify`` (momentum and energy held) at
   collisions 10^2 .. N on a log grid; the error's growth exponent against 1/2.

Command line::

    python -m revcol.studies.stability --json out.json            # the reduced run (the CI's counts)
    python -m revcol.studies.stability --full --json bench/results/stability.json
    revcol study stability --full --json bench/results/stability.json

    >>> from revcol.studies import stability
    >>> r = stability.stress("pair2d/exact/flux", "grazing", count=8, law_samples=500)
    >>> r["failures"], r["roundtrip"] < 1e-9
    (0, True)
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from typing import Callable, Optional, Sequence

import numpy as np

from .. import _core
from .._io import atomic_open
from ..paper import S1_START, Triple1DPaper, paper_cases
from .stability_operators import EXACT_CASES, OPERATORS, PAPER_CASES, Operator, operators  # noqa: F401 (__all__)
from .stability_report import markdown, progress_line

__all__ = ["OPERATORS", "CLASSES", "MISMATCH", "EXACT_CASES", "PAPER_CASES", "operators", "stress", "chains", "ripple",
           "run", "markdown", "main"]

#: a round trip above this (relative to the speed scale) is a reversal mismatch: the paper's bar
MISMATCH = 1e-9

CLASSES = ("grazing", "head-on", "pole", "edges", "cm-speed", "magnitude", "chains")

#: the class parameters (one row per value in the JSON)
ANGLES = tuple(10.0 ** -k for k in range(1, 16))
DELTAS = tuple(10.0 ** -k for k in range(6, 17))
RATIOS = tuple(10.0 ** k for k in range(0, 13))
SCALES = (5e-324, 1e-310, 2.2250738585072014e-308, 1e-300, 1e-200, 1e-150, 1e-140, 1e-100, 1e-50, 1.0,
          1e50, 1e100, 1e135, 1e136, 1e150, 1e200, 1e300)


# ---- the geometry of the pre states -----------------------------------------------------------

class _Geometry:
    """The linear algebra of an operator's contacts in velocity space (n d coordinates): the
    contact functionals A v (normal speeds, < 0 when approaching), the zero-momentum subspace,
    its part V spanned by the contacts and the free part W."""

    def __init__(self, op: Operator):
        n, d, m = op.n, op.d, len(op.contacts)
        a = np.zeros((m, n * d))
        for k, (i, j) in enumerate(op.contacts):
            a[k, i * d:(i + 1) * d] = op.normals[k]
            a[k, j * d:(j + 1) * d] = -op.normals[k]
        mom = np.zeros((d, n * d))
        for p in range(n):
            mom[:, p * d:(p + 1) * d] = np.eye(d)
        self.n, self.d, self.m, self.a = n, d, m, a
        self.pairs, self.rows = op.contacts, op.normals
        self.gram_inv = np.linalg.inv(a @ a.T)
        # an orthonormal basis of W: zero momentum, zero normal speeds
        _, s, vt = np.linalg.svd(np.vstack([a, mom]))
        rank = int((s > 1e-12).sum())
        self.free = vt[rank:]
        self.relative_dim = (n - 1) * d

    def head_on(self, speeds: np.ndarray) -> np.ndarray:
        """(B, n d): the least-norm states with normal speeds -speeds (all in V: head-on)."""
        return -(self.a.T @ (self.gram_inv @ speeds.T)).T

    def free_unit(self, rng: np.random.Generator, count: int) -> np.ndarray:
        z = rng.normal(size=(count, len(self.free))) @ self.free
        return z / np.linalg.norm(z, axis=1)[:, None]

    def interior(self, rng: np.random.Generator, count: int) -> np.ndarray:
        """(count, n d) zero-momentum states approaching at every contact, max |v| = 1."""
        out: list = []
        while len(out) < count:
            v = rng.normal(size=(4 * count, self.n * self.d)).reshape(-1, self.n, self.d)
            v = (v - v.mean(axis=1, keepdims=True)).reshape(-1, self.n * self.d)
            ok = (v @ self.a.T < -0.05 * np.linalg.norm(v, axis=1)[:, None]).all(axis=1)
            out.extend(v[ok])
        v = np.array(out[:count])
        return v / np.abs(v).max(axis=1)[:, None]

    def speeds(self, v: np.ndarray) -> np.ndarray:
        """Normal speeds of (B, n, d) states, computed as the operators do (differences)."""
        return np.stack([(v[:, i] - v[:, j]) @ r for (i, j), r in zip(self.pairs, self.rows)], axis=1)


def _states(op: Operator, geo: _Geometry, cls: str, value: float, rng: np.random.Generator,
            count: int) -> tuple[np.ndarray, str]:
    """(count, n, d) states of a class at one parameter value, and the direction to test:
    "pre" (forward, then reverse) or "post" (reverse, then forward)."""
    n, d, m = op.n, op.d, geo.m
    base = geo.interior(rng, count)
    direction = "pre"
    if cls == "grazing":
        k = np.arange(count) % m
        q = geo.a.T @ geo.gram_inv                       # column k: A q_k = e_k, zero momentum
        vb = base - (base @ geo.a.T)[np.arange(count), k][:, None] * q[:, k].T
        s = math.sin(value) * np.linalg.norm(geo.a[k], axis=1) * np.linalg.norm(vb, axis=1)
        v = vb - s[:, None] * q[:, k].T
    elif cls == "head-on":
        v = geo.head_on(rng.uniform(0.5, 1.0, size=(count, m)))
    elif cls == "pole":
        v = geo.head_on(rng.uniform(0.5, 1.0, size=(count, m)))
        v = v / np.linalg.norm(v, axis=1)[:, None]
        v = math.cos(value) * v + math.sin(value) * geo.free_unit(rng, count)
        if count > 1:   # every other state: a post state near the pole, reversed first
            direction = "both"
    elif cls == "edges":
        b = rng.uniform(0.5, 1.0, size=(count, m))
        every = len(geo.free) > 0
        for s in range(count):
            if every and (s % 2 == 0 or m == 1):
                b[s] = value
            else:
                b[s, np.arange(m) != s % m] = value
        v = geo.head_on(b)
        if every:
            v = v + geo.free_unit(rng, count)
    elif cls == "cm-speed":
        u = rng.normal(size=(count, d))
        u /= np.linalg.norm(u, axis=1)[:, None]
        v = (base.reshape(count, n, d) + value * u[:, None, :]).reshape(count, n * d)
    elif cls == "magnitude":
        v = base * value
    else:
        raise ValueError(f"unknown class {cls!r}")
    if cls not in ("magnitude", "cm-speed"):
        v = v / np.abs(v).max(axis=1)[:, None]
    return v.reshape(count, n, d), direction


def applies(op: Operator, cls: str) -> Optional[str]:
    """None when a class applies to an operator, else why not (said in the report)."""
    geo_free = op.n * op.d - op.d - len(op.contacts)
    relative = (op.n - 1) * op.d
    if cls == "grazing" and relative == 1:
        return "one relative coordinate: no tangent"
    if cls == "pole" and geo_free == 0:
        return "no free part (f = 0): every state is head-on"
    if cls == "edges" and relative == 1:
        return "one relative coordinate: no edge but zero speed (class magnitude)"
    return None


# ---- one class: round trips, law, failures, log ------------------------------------------------

def _round(op: Operator, v: np.ndarray, g: np.ndarray) -> dict:
    """Forward, then reverse with the same draws, of a batch (entry by entry when the batch is
    refused): ``back`` (NaN where a step was refused or the forward gave a non-finite state),
    the refusal messages, and which entries the forward left non-finite."""
    back = np.full_like(v, np.nan)
    msgs = [""] * len(v)
    bad = np.zeros(len(v), bool)

    def step(idx) -> None:
        mid = op.forward(v[idx], g[idx])
        fin = np.isfinite(mid).reshape(len(mid), -1).all(axis=1)
        bad[idx] = ~fin
        if fin.all():
            back[idx] = op.reverse(mid, g[idx])

    try:
        step(np.arange(len(v)))
    except _core.InvalidArgument:
        for s in range(len(v)):
            try:
                step(np.array([s]))
            except _core.InvalidArgument as e:
                msgs[s] = str(e).split(": ", 1)[-1] if str(e).startswith("entry") else str(e)
    if bad.any() and not bad.all():   # a batch with some non-finite states: the rest one by one
        for i in np.flatnonzero(~bad):
            try:
                back[i] = op.reverse(op.forward(v[i:i + 1], g[i:i + 1]), g[i:i + 1])[0]
            except _core.InvalidArgument as e:
                msgs[i] = str(e)
    return {"back": back, "msgs": msgs, "nonfinite_mid": bad}


def _errors(v: np.ndarray, back: np.ndarray, pairs) -> tuple[np.ndarray, np.ndarray]:
    with np.errstate(all="ignore"):
        scale = np.abs(v).reshape(len(v), -1).max(axis=1)
        err = np.abs(back - v).reshape(len(v), -1).max(axis=1) / scale
        rel = np.stack([v[:, i] - v[:, j] for (i, j) in pairs], axis=1)
        relb = np.stack([back[:, i] - back[:, j] for (i, j) in pairs], axis=1)
        rerr = (np.abs(relb - rel).reshape(len(v), -1).max(axis=1)
                / np.abs(rel).reshape(len(v), -1).max(axis=1))
    return err, rerr


def _law(op: Operator, v0: Optional[np.ndarray], samples: int, rng: np.random.Generator) -> Optional[float]:
    """Largest KS distance from uniform of the post chart coordinates from one pre state."""
    if op.chart is None or samples <= 0 or v0 is None:
        return None
    from scipy import stats  # optional (the test extra) and slow to import

    g = rng.random(size=(samples, max(op.draws, 1)))[:, :op.draws] if op.draws else np.zeros((samples, 0))
    g = np.clip(g, 2.0**-53, 1 - 2.0**-53)
    try:
        post = op.forward(np.broadcast_to(v0, (samples,) + v0.shape).copy(), g)
        u = op.chart(post)
    except _core.InvalidArgument:
        return float("nan")
    if u.shape[1] == 0:
        return None
    return float(max(stats.kstest(u[:, k], "uniform").statistic for k in range(u.shape[1])))


def _accepted(op: Operator, cand: np.ndarray) -> Optional[np.ndarray]:
    """The first candidate state the operator takes as a pre state (at delta = 1e-16 the sign
    of a normal speed is the operator's rounding), or None."""
    g = np.full((1, op.draws), 0.5)
    for c in cand:
        try:
            op.forward(c[None], g)
            op.clear()
            return c
        except _core.InvalidArgument:
            pass
    return None


def _values(cls: str) -> tuple:
    return {"grazing": ANGLES, "head-on": (0.0,), "pole": ANGLES, "edges": DELTAS,
            "cm-speed": RATIOS, "magnitude": SCALES}[cls]


def _reference(op: Operator, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """What a round trip must return: exact mode promises the pre state's chart cell decoded at
    its centre (``quantize``), the paper's operators the pre state itself. Also the
    quantization |reference - v| / scale."""
    if op.quantize is None:
        return v, np.zeros(len(v))
    ref = np.array(v)
    for s in range(len(v)):
        try:
            ref[s] = op.quantize(v[s:s + 1])[0]
        except _core.InvalidArgument:
            ref[s] = np.nan
    with np.errstate(all="ignore"):
        q = np.abs(ref - v).reshape(len(v), -1).max(axis=1) / np.abs(v).reshape(len(v), -1).max(axis=1)
    return ref, q


#: a refusal that says the constructed state is not a pre state at all (rounding put a
#: grazing contact on the wrong side): not an operator failure, counted apart
NOT_PRE = ("separates before", "not approaching", "no contact approaches")


def _aim_posts(op: Operator, geo: _Geometry, v: np.ndarray, g: np.ndarray, rng: np.random.Generator,
               post: np.ndarray) -> None:
    """Turn the entries ``post`` into forward collisions whose post state is -v (a separating
    state at the class's angle): fresh interior pre states, and draws G = chart(-v) - chart(-pre)
    (mod 1), which the exact operator's torus shift maps onto -v's chart cell (within a cell)."""
    k = int(post.sum())
    assert op.chart is not None   # exact mode: every exact operator has its chart
    pre = geo.interior(rng, k).reshape(k, op.n, op.d)
    target = -v[post]
    gg = np.mod(op.chart(target) - op.chart(-pre), 1.0).reshape(k, -1)
    v[post] = pre
    g[post] = np.clip(gg, 2.0**-53, 1 - 2.0**-53)


def _one_value(op: Operator, geo: _Geometry, cls: str, value: float, rng: np.random.Generator,
               count: int) -> dict:
    """``count`` round trips of one class at one parameter value."""
    v, direction = _states(op, geo, cls, value, rng, count)
    g = np.clip(rng.random(size=(count, max(op.draws, 1)))[:, :op.draws], 2.0**-53, 1 - 2.0**-53)
    post = (np.arange(count) % 2 == 1) if direction == "both" and op.quantize is not None else None
    if post is not None:
        _aim_posts(op, geo, v, g, rng, post)
    op.clear()
    pushed0 = op.pushed()
    r = _round(op, v, g)
    pushed = op.pushed() - pushed0
    back, msgs, mid_bad = r["back"], r["msgs"], r["nonfinite_mid"]
    ref, quant = _reference(op, v)
    err, rerr = _errors(ref, back, op.contacts)
    rounding = cls in ("grazing", "pole", "edges")
    not_pre = sum(1 for m in msgs if rounding and any(t in m for t in NOT_PRE))
    refused = [m for m in msgs if m and not (rounding and any(t in m for t in NOT_PRE))]
    ok = np.array([not m for m in msgs])
    finite = np.isfinite(back).reshape(count, -1).all(axis=1)
    nonfinite = int((ok & (mid_bad | ~finite)).sum())
    mismatch = int((ok & ~mid_bad & finite & ~(err <= MISMATCH)).sum())
    left = op.logged()
    with np.errstate(all="ignore"):
        sp = geo.speeds(v)
        x = (v - v.mean(axis=1, keepdims=True)).reshape(count, -1)
        ratio = -sp.max(axis=1) / (math.sqrt(2) * np.linalg.norm(x, axis=1))   # |a_k| = sqrt 2
    good = ok & ~mid_bad & finite
    return {
        "value": value, "direction": direction,
        "roundtrip": float(np.nanmax(err[good])) if good.any() else None,
        "roundtrip_rel": float(np.nanmax(rerr[good])) if good.any() else None,
        "quantization": float(np.nanmax(quant[good])) if good.any() and op.quantize else None,
        "refused": len(refused), "nonfinite": nonfinite, "mismatch": mismatch, "not_pre": not_pre,
        "failures": len(refused) + nonfinite + mismatch + (1 if left else 0),
        "first_refusal": refused[0] if refused else "",
        "log_rate": pushed / count, "left_in_log": left, "posts_aimed": int(post.sum()) if post is not None else 0,
        # entry s of grazing grazes contact s mod m; of edges, every contact but s mod m (f = 0)
        "mismatch_by_entry_mod_m": [int(((ok & ~mid_bad & finite & ~(err <= MISMATCH))
                                         & (np.arange(count) % geo.m == k)).sum()) for k in range(geo.m)],
        "min_speed_ratio": float(np.nanmin(ratio)) if cls in ("grazing", "edges") and np.isfinite(ratio).any() else None,
    }


def stress(name: str, cls: str, *, count: int = 64, law_samples: int = 4000, seed: int = 0,
           op: Optional[Operator] = None) -> dict:
    """One operator under one stress class (not "chains": see :func:`chains`): ``count``
    round trips at every value of the class parameter, the law at its most extreme value.
    Returns the worst figures and one row per value."""
    op = operators()[name]() if op is None else op
    why = applies(op, cls)
    out: dict = {"operator": op.name, "class": cls, "count": count, "law_samples": law_samples, "seed": seed}
    if why is not None:
        return {**out, "applies": False, "why": why}
    geo = _Geometry(op)
    rng = np.random.default_rng([seed, CLASSES.index(cls), sum(map(ord, op.name))])
    rows = [_one_value(op, geo, cls, value, rng, count) for value in _values(cls)]
    extreme = _values(cls)[-1] if cls != "magnitude" else 1.0
    law = _law(op, _accepted(op, _states(op, geo, cls, extreme, rng, 16)[0]), law_samples, rng)
    done = [r["roundtrip"] for r in rows if r["roundtrip"] is not None]
    fails = sum(r["failures"] for r in rows)
    total = count * len(rows)
    return {**out, "applies": True, "values": rows,
            "roundtrip": max(done) if done else None,
            "roundtrip_rel": max((r["roundtrip_rel"] for r in rows if r["roundtrip_rel"] is not None), default=None),
            "law_D": law, "law_value": extreme,
            "law_D_bound": _ks_bound(law_samples, max(op.draws, 1)),
            "failures": fails, "failure_rate": fails / total,
            "refused": sum(r["refused"] for r in rows), "nonfinite": sum(r["nonfinite"] for r in rows),
            "not_pre": sum(r["not_pre"] for r in rows),
            "mismatch": sum(r["mismatch"] for r in rows),
            "log_rate": sum(r["log_rate"] * count for r in rows) / total}


def _ks_bound(samples: int, coordinates: int = 1, alpha: float = 1e-3) -> float:
    """The largest of ``coordinates`` one-sample KS distances of a uniform law exceeds this
    with probability at most alpha (asymptotic Kolmogorov tail, Bonferroni over coordinates)."""
    a = alpha / max(coordinates, 1)
    return math.sqrt(-math.log(a / 2) / (2 * samples)) if samples > 0 else float("nan")


# ---- class 7: long chains ----------------------------------------------------------------------

def _verify_args(op: Operator) -> dict:
    if op.name == "pair1d":
        return {"case": "pair1d", "mode": "exact"}
    if op.mode == "exact":
        return {"case": op.case, "mode": "exact", "law": op.law}
    return {"case": op.case, "mode": "paper"}


def chains(name: str, *, longest: int = 1000, seed: int = 0) -> dict:
    """The reversal illustration (``revcol.verify``: momentum and energy held, post negated is
    the next pre) at 10^2, 10^3, ... up to ``longest`` collisions. Exact mode returns its
    quantized start bit for bit (``bit_exact``) at every length, so its error cannot drift; for
    the others the growth exponent of the error against n is fitted (1/2: a random walk)."""
    op = operators()[name]()
    args = _verify_args(op)
    if op.options.get("cos_tol", 1e-8) != 1e-8:
        return {"operator": name, "class": "chains", "applies": False,
                "why": "revcol.verify has no cos_tol; see triple1d/paper"}
    grid = sorted({int(10 ** k) for k in np.arange(2, math.log10(longest) + 1e-9, 1.0)} | {int(longest)})
    rows = []
    for n in grid:
        t = time.perf_counter()
        r = _core.verify(collisions=n, seed=seed, rng="clcg4", bits=40, printed_reverse=False,
                         velocities=[], normal=[], law=args.get("law", "flux"), case=args["case"], mode=args["mode"])
        rows.append({"collisions": n, "max_rel_error": r["max_rel_error"], "bit_exact": r["bit_exact"],
                     "passed": r["passed"], "rng_restored": r["rng_restored"], "log_entries": r["log_entries"],
                     "error": r["error"], "seconds": time.perf_counter() - t})
    errs = np.array([r["max_rel_error"] for r in rows])
    ns = np.array([r["collisions"] for r in rows], float)
    slope = None
    # a drift is fitted only where the chain ran to its end and came back near the start: a
    # chain of wrong states (the paper's 3D pair) or one stopped early has no drift to fit
    good = (np.isfinite(errs) & (errs > 0) & (errs < 1e-6)
            & np.array([not r["error"] and r["rng_restored"] for r in rows]))
    if good.sum() >= 3 and not all(r["bit_exact"] for r in rows):
        slope = float(np.polyfit(np.log10(ns[good]), np.log10(errs[good]), 1)[0])
    return {"operator": name, "class": "chains", "applies": True, "verify": args, "values": rows,
            "longest": int(longest), "bit_exact_all": all(r["bit_exact"] for r in rows),
            "passed_all": all(r["passed"] for r in rows), "growth_exponent": slope,
            "roundtrip": float(np.nanmax(errs)) if np.isfinite(errs).any() else None,
            "failures": sum(not r["passed"] for r in rows),
            "log_rate": max(r["log_entries"] / r["collisions"] for r in rows)}


# ---- the 1D triple's post density (docs/paper-findings.md, Finding 2.4) -------------------------

def _arc_density(angle: str, t: np.ndarray, aspect: float = 1 / math.sqrt(3)) -> np.ndarray:
    """ds/dt on the ellipse (cos, aspect sin): t its parameter, or its polar angle."""
    a, b = 1.0, aspect
    if angle == "parametric":
        return np.sqrt(a * a * np.sin(t) ** 2 + b * b * np.cos(t) ** 2)
    q = b * b * np.cos(t) ** 2 + a * a * np.sin(t) ** 2
    r = a * b / np.sqrt(q)
    dr = -a * b * 0.5 * (a * a - b * b) * np.sin(2 * t) / q ** 1.5
    return np.sqrt(r * r + dr * dr)


def ripple(angle: str = "parametric", *, samples: int = 100_000_000, bins: Sequence[int] = (600, 3000),
           chunk: int = 5_000_000) -> dict:
    """The ripple of the paper 1D triple's post density: u = (phi - 7pi/6) / (pi/3) of the
    forward step from the case's start at ``samples`` evenly spaced G ((k + 1/2) / samples:
    the operator's own law, no sampling noise), histogrammed into each of ``bins`` cells;
    returns max and min of density / mean - 1 per bin count (a cell's count is exact to +-1,
    so to +-bins/samples). ``closed_form``: the same from the arc-length density alone, summed
    over the six shifts of pi/3 (Finding 2.3: the forward step is a rotation mod pi/3), at
    600,000 points of one period."""
    c = paper_cases()["triple1d"]
    x, v = c["geometry"], c["velocities"][:, 0]
    op = Triple1DPaper(arc="table", angle=angle)
    counts = {b: np.zeros(b, np.int64) for b in bins}
    for s in range(0, samples, chunk):
        m = min(chunk, samples - s)
        g = (np.arange(s, s + m) + 0.5) / samples
        u = (Triple1DPaper.angle_of(op.forward(np.broadcast_to(v, (m, 3)), x, g=g), x) - S1_START) / (np.pi / 3)
        for b in bins:
            counts[b] += np.bincount(np.clip((u * b).astype(np.int64), 0, b - 1), minlength=b)
    hist = {}
    for b in bins:
        d = counts[b] / counts[b].mean()
        hist[str(b)] = {"max": float(d.max() - 1), "min": float(d.min() - 1), "resolution": b / samples}
    t = np.arange(600_000) * (np.pi / 3) / 600_000
    dens = np.sum([_arc_density(angle, t + k * np.pi / 3) for k in range(6)], axis=0)
    dens = dens / dens.mean()
    return {"angle": angle, "samples": samples, "arc": "table", "histogram": hist,
            "closed_form": {"max": float(dens.max() - 1), "min": float(dens.min() - 1)}}


# ---- the whole suite ----------------------------------------------------------------------------

REDUCED = {"count": 32, "law_samples": 4000, "chain": 1000}
FULL = {"count": 1024, "law_samples": 100_000, "chain": 1_000_000}
#: the longest chains of the full run (the rest: FULL["chain"]); each under ~3 minutes here
FULL_CHAINS = {"pair2d/exact/flux": 100_000_000, "pair2d/exact/uniform": 100_000_000,
               "pair2d/paper": 100_000_000, "pair3d/exact/flux": 10_000_000,
               "triple1d/exact/flux": 10_000_000, "triple1d/paper": 1_000_000}


def run(names: Sequence[str] = OPERATORS, classes: Sequence[str] = CLASSES, *, full: bool = False,
        seed: int = 0, count: Optional[int] = None, law_samples: Optional[int] = None,
        progress: Optional[Callable[[str], None]] = None) -> dict:
    """Every class for every operator; the reduced counts unless ``full`` (or given)."""
    cfg = dict(FULL if full else REDUCED)
    cfg["count"] = count or cfg["count"]
    cfg["law_samples"] = law_samples or cfg["law_samples"]
    out: dict = {"full": full, "counts": cfg, "mismatch": MISMATCH, "seed": seed,
                 "build": _core.build, "results": []}
    for name in names:
        for cls in classes:
            t = time.perf_counter()
            if cls == "chains":
                longest = FULL_CHAINS.get(name, cfg["chain"]) if full else cfg["chain"]
                r = chains(name, longest=longest, seed=seed)
            else:
                r = stress(name, cls, count=cfg["count"], law_samples=cfg["law_samples"], seed=seed)
            r["seconds"] = time.perf_counter() - t
            out["results"].append(r)
            if progress:
                progress(progress_line(r))
    return out


def main(argv: Optional[Sequence[str]] = None, prog: str = "python -m revcol.studies.stability") -> int:
    ap = argparse.ArgumentParser(prog=prog, description=__doc__.split("\n\n")[0])
    ap.add_argument("--full", action="store_true", help="the bench counts (else the CI's reduced counts)")
    ap.add_argument("--operators", nargs="*", default=list(OPERATORS), choices=OPERATORS, metavar="OP",
                    help="operators to run (default: all): " + ", ".join(OPERATORS))
    ap.add_argument("--classes", nargs="*", default=list(CLASSES), choices=CLASSES, help="classes to run")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--count", type=int, help="round trips per class value (overrides the run's count)")
    ap.add_argument("--law-samples", type=int, help="samples of the law test (overrides the run's)")
    ap.add_argument("--ripple", type=int, metavar="SAMPLES",
                    help="instead of the suite: the paper 1D triple's post density ripple, both readings")
    ap.add_argument("--json", metavar="FILE", help="write the results as JSON to FILE")
    ap.add_argument("--markdown", metavar="FILE", help="instead of a run: the tables of a saved JSON result")
    a = ap.parse_args(argv)
    if a.markdown:
        with open(a.markdown) as f:
            print(markdown(json.load(f)))
        return 0
    t = time.perf_counter()
    if a.ripple:
        res: dict = {"ripple": [ripple(angle, samples=a.ripple) for angle in ("parametric", "polar")]}
        for r in res["ripple"]:
            print(json.dumps(r))
    else:
        res = run(a.operators, a.classes, full=a.full, seed=a.seed, count=a.count, law_samples=a.law_samples,
                  progress=lambda s: print(s, flush=True))
    res["seconds"] = time.perf_counter() - t
    res["command"] = "python -m revcol.studies.stability " + " ".join(sys.argv[1:] if argv is None else argv)
    if a.json:
        with atomic_open(a.json, "w") as f:
            json.dump(res, f, indent=1, allow_nan=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
