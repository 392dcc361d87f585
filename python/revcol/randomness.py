"""The paper's randomness experiment (§5.2): post-collision chart coordinates as 32-bit words,
run through a Diehard-class battery (``dieharder``), with controls that must fail and pass.

A chain of collisions (the paper's Reversal Illustration run forward: invariants held, the
post velocities negated to make the next collision) maps each post state x to its chart
coordinates u = F(x) in [0,1)^(d_n), F the measure-preserving chart of the law (each
coordinate is the CDF value of one one-dimensional law), and writes floor(u 2^32) as raw
uint32 words, the format ``dieharder -g 201 -f FILE`` reads. Under the operator's law the
words are uniform; through the other law's CDF, or from a biased operator, they are not.
Paper mode is read through the exact uniform law's chart: the paper's stated law (uniform
on the permitted set, uniform in its angles on a round circle for pair2d and triple1d).
The cases gas2d and gas3d are the float engine's pair collisions in a periodic gas (exact
mode): the direction of each post relative velocity about its contact normal, read through
the law's CDF (revcol/randomness.hpp).

The battery runs the paper's tests by dieharder number (``PAPER_TESTS``), one process per
test and each from the start of the file, without dieharder's ``rate`` output field (its
timing run reads, and rewinds, the file before the test). On a short file (the paper's
3 x 10^6 words) psamples is lowered until the test does not rewind; on a long file
(>= 2.4 x 10^8 words) every test runs with dieharder's defaults without rewinding. A WEAK
result (p < 0.005 or p > 0.995) is rerun on a fresh file from another seed; dieharder
calls p < 1e-6 (or > 1 - 1e-6) FAILED. All p-values of a run then get one Kolmogorov-Smirnov
test against the uniform law.

Command line (``python -m revcol.randomness``, also ``revcol study randomness``)::

    python -m revcol.randomness battery --case pair2d --mode exact --law flux --rng philox --words 3000000
    python -m revcol.randomness battery --case gas2d --particles 1000 --fraction 0.2 --words 3000000
    python -m revcol.randomness controls --words 3000000
    python -m revcol.randomness matrix --words 3000000 --json bench/results/randomness_3e6.json
    python -m revcol.randomness coverage --out docs/figures/randomness
    python -m revcol.randomness table bench/results/randomness_paper_cases_3e6.json [--detail]

    >>> import revcol.randomness as R
    >>> w = R.stream("pair2d", mode="exact", law="flux", rng="philox").words(4)
    >>> w.dtype.name, len(w)
    ('uint32', 4)
"""
from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from typing import Any, Optional, Sequence

import numpy as np

from ._io import atomic_open
from . import _core

__all__ = ["PAPER_TESTS", "CI_TESTS", "stream", "stream_cases", "write_words", "has_dieharder",
           "run_test", "battery", "controls", "ks_uniform", "coverage", "table", "marginals", "main"]

#: the paper's Diehard tests as dieharder numbers: runs, craps, 3D spheres, minimum distance,
#: parking lot, squeeze, birthdays, and the 32x32 and 6x8 binary rank tests. (The paper's
#: SUMS test is dieharder -d 14, which dieharder marks "Do Not Use": a known bug.)
PAPER_TESTS = {15: "runs", 16: "craps", 12: "3d spheres", 11: "minimum distance (2d circle)",
               10: "parking lot", 13: "squeeze", 0: "birthdays", 2: "rank 32x32", 3: "rank 6x8"}
#: the reduced battery of the CI test
CI_TESTS = (15, 12, 10)
#: the gas streams' defaults: particles, packing fraction, warm-up collisions per particle
GAS_PARTICLES, GAS_FRACTION, GAS_WARMUP = 1000, 0.2, 5.0

_FIELDS = ["-D", "test_name", "-D", "ntuple", "-D", "tsamples", "-D", "psamples", "-D", "pvalues",
           "-D", "assessment"]


def stream_cases(mode: str = "exact") -> list[str]:
    """The cases a word stream knows for a mode ("raw", then "pair2d", then each named case
    with at least one draw, or the paper-mode cases)."""
    return list(_core.stream_cases(mode))


def stream(case: str, *, mode: str = "exact", law: str = "flux", rng: str = "philox", seed: int = 0,
           cdf_law: Optional[str] = None, bits: int = 40, particles: int = GAS_PARTICLES,
           fraction: float = GAS_FRACTION, warmup: float = GAS_WARMUP) -> Any:
    """A :class:`revcol._core.WordStream`: ``.words(n)`` (numpy uint32), ``.write(path, n)``.

    cdf_law: the law whose chart maps post states to words; default ``law`` in exact mode
    and ``"uniform"`` (the paper's stated law) in paper mode. rng: clcg4, philox, or the
    bad controls randu and philox-repeat100. case "raw": the generator's own draws.
    case "gas2d" / "gas3d": the float engine's pair collisions in a periodic gas of
    ``particles`` at packing fraction ``fraction``, after ``warmup`` collisions per particle
    (exact mode, philox or clcg4; group collisions give no word, ``.skipped`` counts them).
    """
    if cdf_law is None:
        cdf_law = law if mode == "exact" else "uniform"
    return _core.WordStream(case=case, mode=mode, law=law, cdf_law=cdf_law, rng=rng, seed=int(seed),
                            bits=int(bits), particles=int(particles), fraction=float(fraction),
                            warmup=float(warmup))


def write_words(path: str, n: int, **config: Any) -> dict:
    """Writes n words of ``stream(**config)`` to a new raw file, atomically: into
    ``path + ".part"``, renamed when complete, so that an error or Ctrl-C (KeyboardInterrupt,
    the stream polls every 2^16 words) leaves no file. Returns the stream's counts (gas:
    the group collisions skipped) and the wall time."""
    if os.path.exists(path):
        os.remove(path)
    part = path + ".part"
    s = stream(**config)
    t0 = time.perf_counter()
    try:
        if os.path.exists(part):
            os.remove(part)
        s.write(part, int(n))
        os.replace(part, path)
    finally:
        if os.path.exists(part):
            os.remove(part)
    return {"words": int(s.emitted), "collisions": int(s.collisions), "restarts": int(s.restarts),
            "skipped": int(s.skipped), "write_s": round(time.perf_counter() - t0, 3)}


def has_dieharder() -> bool:
    """Whether the dieharder binary is on PATH."""
    return shutil.which("dieharder") is not None


_LINE = re.compile(r"^\s*(\S+)\|\s*(\d+)\|\s*(\d+)\|\s*(\d+)\|\s*([0-9.eE+-]+)\|\s*(\w+)\s*$")
_REWOUND = re.compile(r"rewound (\d+) times")


def parse(output: str) -> dict:
    """dieharder's table (the fields of ``_FIELDS``) as a dict: rows of (name, ntuple,
    tsamples, psamples, p, assessment) and the number of times the file was rewound."""
    rows = []
    for line in output.splitlines():
        m = _LINE.match(line)
        if m:
            rows.append({"name": m.group(1), "ntuple": int(m.group(2)), "tsamples": int(m.group(3)),
                         "psamples": int(m.group(4)), "p": float(m.group(5)), "assessment": m.group(6)})
    m = _REWOUND.search(output)
    return {"rows": rows, "rewound": int(m.group(1)) if m else 0}


#: below this many psamples dieharder's final KS of the psample p-values is wrong (2 or 3
#: psamples of /dev/urandom give p = 1.00000000, FAILED): such a test runs instead once
#: (-p 1) on each of that many disjoint segments of the file, every p-value reported, as the
#: paper's Diehard ran its tests once or twice
MIN_PSAMPLES = 10


def _dieharder(path: str, test: int, psamples: Optional[int], nice: bool) -> tuple[dict, list[str]]:
    cmd = (["nice", "-n", "10"] if nice else []) + ["dieharder", "-g", "201", "-f", path, "-d", str(test)]
    cmd += _FIELDS + (["-p", str(psamples)] if psamples else [])
    done = subprocess.run(cmd, capture_output=True, text=True, check=True)
    out = done.stdout + done.stderr  # the rewind notice is on stderr
    r = parse(out)
    if not r["rows"]:
        raise RuntimeError(f"dieharder -d {test} printed no result:\n{out}")
    return r, cmd[3:] if nice else cmd


def run_test(path: str, test: int, *, psamples: Optional[int] = None, fit: bool = True,
             nice: bool = True) -> dict:
    """One dieharder test on a raw file. With ``fit``, a run that rewinds the file is redone
    with fewer psamples (scaled down by the rewinds, 10% margin) until it does not; when
    that leaves fewer than MIN_PSAMPLES, the test runs with -p 1 on that many segments."""
    while True:
        r, cmd = _dieharder(path, test, psamples, nice)
        used = r["rows"][0]["psamples"]
        if not fit or r["rewound"] == 0 or used == 1:
            break
        psamples = max(1, int(used * 0.9 / (r["rewound"] + 1)))
    if fit and 1 < used < MIN_PSAMPLES:
        words = np.memmap(path, dtype="<u4", mode="r")
        size = len(words) // used
        rows, rewound = [], 0
        for k in range(used):
            seg = f"{path}.seg{k}"
            np.asarray(words[k * size:(k + 1) * size]).tofile(seg)
            try:
                rk, cmd = _dieharder(seg, test, 1, nice)
            finally:
                os.remove(seg)
            rows += rk["rows"]
            rewound += rk["rewound"]
        del words
        r = {"rows": rows, "rewound": rewound, "segments": used}
        cmd[cmd.index(seg)] = f"SEGMENT_OF_{size}_WORDS"
        used = 1
    r.update(test=test, name=PAPER_TESTS.get(test, r["rows"][0]["name"]), psamples=used,
             command=" ".join(cmd))
    return r


def ks_uniform(p: Sequence[float]) -> float:
    """Kolmogorov-Smirnov p-value of a sample against the uniform law on [0, 1]."""
    from scipy import stats

    return float(stats.kstest(np.asarray(p, float), "uniform").pvalue) if len(p) else float("nan")


def _verdict(rows: Sequence[dict]) -> str:
    a = {r["assessment"] for r in rows}
    return "FAILED" if "FAILED" in a else "WEAK" if "WEAK" in a else "PASSED"


def battery(config: dict, words: int, tests: Sequence[int] = tuple(PAPER_TESTS), *,
            workdir: Optional[str] = None, rerun_seed: int = 1000, fit: bool = True,
            keep: bool = False) -> dict:
    """Writes ``words`` words of ``stream(**config)`` and runs each test; a WEAK test is rerun
    on a fresh file (seed + rerun_seed), and its final verdict is the rerun's. Returns the
    per-test results, the KS p-value of all first-run p-values and the overall verdict
    (FAILED if any test's final verdict is FAILED or WEAK)."""
    workdir = workdir or tempfile.gettempdir()
    tag = "-".join(str(config.get(k, "")) for k in ("case", "mode", "law", "rng", "seed"))
    path = os.path.join(workdir, f"revcol-words-{tag}-{os.getpid()}.bin")
    info = write_words(path, words, **config)
    t0 = time.perf_counter()
    results, rerun_path = [], None
    try:
        for t in tests:
            r = run_test(path, t, fit=fit)
            r["verdict"] = _verdict(r["rows"])
            if r["verdict"] == "WEAK":
                if rerun_path is None:
                    rerun_path = path + ".rerun"
                    cfg = dict(config, seed=int(config.get("seed", 0)) + rerun_seed)
                    info["rerun"] = write_words(rerun_path, words, **cfg)
                r2 = run_test(rerun_path, t, psamples=None if fit else r["psamples"], fit=fit)
                r["rerun"] = {"rows": r2["rows"], "rewound": r2["rewound"], "seed_offset": rerun_seed,
                              "command": r2["command"]}
                r["verdict"] = "WEAK then " + _verdict(r2["rows"])
            results.append(r)
    finally:
        for p in (path, rerun_path):
            if p and os.path.exists(p) and not keep:
                os.remove(p)
    pvals = [row["p"] for r in results for row in r["rows"]]
    final = [r["verdict"].split()[-1] for r in results]
    overall = "FAILED" if "FAILED" in final else "WEAK" if "WEAK" in final else "PASSED"
    return {"config": dict(config), "words": int(words), "stream": info, "tests": results,
            "pvalues": pvals, "ks_p": ks_uniform(pvals), "verdict": overall,
            "battery_s": round(time.perf_counter() - t0, 2)}


def controls(words: int, tests: Sequence[int] = tuple(PAPER_TESTS), **kw: Any) -> list[dict]:
    """The battery's controls: raw CLCG4 and Philox (must pass), raw RANDU and the exact pair2d
    chain driven by RANDU and by philox-repeat100 (the bad ones)."""
    out = []
    for case, rng in (("raw", "clcg4"), ("raw", "philox"), ("raw", "randu"), ("pair2d", "randu"),
                      ("raw", "philox-repeat100"), ("pair2d", "philox-repeat100")):
        out.append(battery({"case": case, "mode": "exact", "law": "flux", "rng": rng, "seed": 1}, words,
                           tests, **kw))
    return out


# --- coverage figures ---------------------------------------------------------------------

def _posts(case: str, mode: str, law: str, samples: int, seed: int = 7) -> tuple[np.ndarray, np.ndarray]:
    """``samples`` post states (samples, n, d) of one fixed pre state (the word stream's start)
    and that pre state: exact mode through revcol.Collision, paper mode through its operator."""
    from . import paper as P
    from .rng import Philox

    if case == "pair2d":
        v = np.array([[0.25, -0.5], [1.0, 0.75]])
    elif case in P.PAPER_CASES:
        v = P.paper_cases()[case]["velocities"]
    else:  # standard normal velocities, the first draw that approaches at every contact
        op = _core.Collision.named(case)
        rng = np.random.default_rng(seed)
        while True:
            v = rng.normal(size=(op.particles, op.dim))
            if max(op.normal_speeds(v)) < 0:
                break
    n, d = v.shape
    if mode == "exact":
        op = _core.Collision.named(case, law=law)
        post = op.forward(np.broadcast_to(v, (samples, n, d)).copy(), rng=Philox(key=(seed, 0)))
        return np.asarray(post).reshape(samples, n, d), v
    if case == "pair2d":
        post = _core.Pair2D(mode="paper").forward(np.broadcast_to(v, (samples, n, d)).copy(),
                                                  np.array([1.0, 1.0]), rng=Philox(key=(seed, 0)))
        return np.asarray(post).reshape(samples, n, d), v
    return P.paper_posts(case, v, samples, stream=seed), v


def _relative(case: str, post: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit relative velocities x / |x| in Helmert coordinates (samples, (n-1) d) and the
    constraint vectors a_k (m, (n-1) d) of the case's contacts."""
    from . import paper as P

    nc = {c["name"]: c for c in _core.named_cases()}[case]
    n, d = nc["n"], nc["d"]
    h = P._helmert(n)
    x = np.einsum("kp,spa->ska", h, post.reshape(-1, n, d)).reshape(len(post), -1)
    x /= np.linalg.norm(x, axis=1)[:, None]
    pos = np.asarray(nc["positions"], float).reshape(n, d)
    a = []
    for (i, j) in nc["contacts"]:
        r = pos[i] - pos[j]
        a.append(np.kron(h[:, i] - h[:, j], r / np.linalg.norm(r)) / np.sqrt(2.0))
    return x, np.array(a)


def _save(fig: Any, path: str, dpi: int) -> str:
    """Saves a figure as a 256-colour PNG (a third of the size of matplotlib's RGBA PNG)."""
    import io

    import matplotlib.pyplot as plt
    from PIL import Image

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    plt.close(fig)
    buf.seek(0)
    Image.open(buf).convert("RGB").quantize(256).save(path, optimize=True)
    return path


_MODES = (("exact", "flux"), ("exact", "uniform"), ("paper", "uniform"))


def _title(mode: str, law: str) -> str:
    return f"exact, {law} law" if mode == "exact" else "paper mode (target: uniform)"


def _figure_pair2d(out: str, samples: int) -> str:
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(2, 3, figsize=(10, 5.6), constrained_layout=True)
    a = np.array([1.0, 1.0]) / np.sqrt(2.0)
    t = np.array([-a[1], a[0]])
    eta_grid = np.linspace(-np.pi / 2, np.pi / 2, 400)
    for col, (mode, law) in enumerate(_MODES):
        post, _ = _posts("pair2d", mode, law, samples)
        w = post[:, 0] - post[:, 1]
        w /= np.linalg.norm(w, axis=1)[:, None]
        p, q = w @ a, w @ t
        eta = np.arctan2(q, p)
        s = ax[0, col]
        th = np.linspace(0, 2 * np.pi, 400)
        s.plot(np.cos(th), np.sin(th), color="0.8", lw=0.8)
        s.plot(np.cos(eta_grid), np.sin(eta_grid), color="tab:green", lw=3, label="permitted half circle")
        r = 1 + 0.03 * np.random.default_rng(0).standard_normal(min(2000, samples))
        s.scatter(r * p[:len(r)], r * q[:len(r)], s=1, color="tab:blue", alpha=0.4, zorder=3,
                  label="post (2000, jittered radially)")
        s.set_aspect("equal")
        s.set_xlabel("w.a / |w|  (a: contact normal)")
        s.set_ylabel("w.t / |w|")
        s.set_title(_title(mode, law), fontsize=10)
        if col == 0:
            s.legend(fontsize=7, loc="lower left")
        h = ax[1, col]
        h.hist(eta, bins=60, range=(-np.pi / 2, np.pi / 2), density=True, color="tab:blue", alpha=0.6,
               label=f"{samples} posts")
        dens = np.cos(eta_grid) / 2 if law == "flux" else np.full_like(eta_grid, 1 / np.pi)
        h.plot(eta_grid, dens, color="k", lw=1.5, label="cos(eta)/2" if law == "flux" else "1/pi")
        h.set_xlabel("post angle eta from the normal (rad)")
        h.set_ylabel("density")
        h.legend(fontsize=7)
    fig.suptitle("2 particles in 2D: post-collision directions from one pre state (normal (1,1))", fontsize=11)
    path = os.path.join(out, "coverage_pair2d.png")
    return _save(fig, path, 110)


def _figure_triple1d(out: str, samples: int) -> str:
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(2, 3, figsize=(10, 5.6), constrained_layout=True)
    lo, hi = 7 * np.pi / 6, 3 * np.pi / 2
    for col, (mode, law) in enumerate(_MODES):
        post, _ = _posts("triple1d", mode, law, samples)
        # the paper's angle: x = (lambda / sqrt2)(cos phi, sin phi) in Jacobi coordinates
        # ((a-b)/sqrt2, (a+b-2c)/sqrt6); Helmert's rows are these up to sign
        j1 = (post[:, 0, 0] - post[:, 1, 0]) / np.sqrt(2)
        j2 = (post[:, 0, 0] + post[:, 1, 0] - 2 * post[:, 2, 0]) / np.sqrt(6)
        phi = np.mod(np.arctan2(j2, j1), 2 * np.pi)
        s = ax[0, col]
        th = np.linspace(0, 2 * np.pi, 400)
        s.plot(np.cos(th), np.sin(th), color="0.8", lw=0.8)
        arc = np.linspace(lo, hi, 100)
        s.plot(np.cos(arc), np.sin(arc), color="tab:green", lw=3, label="permitted arc S1")
        r = 1 + 0.03 * np.random.default_rng(0).standard_normal(min(2000, samples))
        s.scatter(r * np.cos(phi[:len(r)]), r * np.sin(phi[:len(r)]), s=1, color="tab:blue", alpha=0.4,
                  zorder=3, label="post (2000, jittered radially)")
        s.set_aspect("equal")
        s.set_xlabel("(a - b)/sqrt2 (scaled)")
        s.set_ylabel("(a + b - 2c)/sqrt6 (scaled)")
        s.set_title(_title(mode, law) + (" (= uniform: f = 0)" if mode == "exact" and law == "flux" else ""),
                    fontsize=9)
        if col == 0:
            s.legend(fontsize=7, loc="upper right")
        h = ax[1, col]
        h.hist(phi, bins=60, range=(lo, hi), density=True, color="tab:blue", alpha=0.6, label=f"{samples} posts")
        h.axhline(3 / np.pi, color="k", lw=1.5, label="uniform on S1: 3/pi")
        h.set_xlabel("post angle phi (rad), S1 = (7pi/6, 3pi/2)")
        h.set_ylabel("density")
        h.legend(fontsize=7)
    fig.suptitle("3 particles in 1D: post-collision angle on the arc S1 from one pre state", fontsize=11)
    path = os.path.join(out, "coverage_triple1d.png")
    return _save(fig, path, 110)


def _figure_triple2d(out: str, case: str, samples: int) -> str:
    import matplotlib.pyplot as plt

    from . import paper as P

    fig, ax = plt.subplots(3, 3, figsize=(10, 9.2), constrained_layout=True)
    for col, (mode, law) in enumerate(_MODES):
        post, _ = _posts(case, mode, law, samples)
        keep = P._separates(case, post, P.paper_cases()[case]["geometry"])
        x, a = _relative(case, post)
        # projection 1: the plane of a_1, a_2 (their half planes are wedges there);
        # projection 2: its orthogonal complement (a_3's half plane, or no constraint)
        e, _ = np.linalg.qr(a[:2].T)
        e *= np.sign(np.sum(e * a[:2].T, axis=0))  # e1 along a1, e2 towards a2
        full = np.linalg.qr(np.hstack([e, np.eye(4)]))[0]
        comp = full[:, 2:4]
        for row, (basis, names) in enumerate(((e, ("e1", "e2")), (comp, ("e3", "e4")))):
            s = ax[row, col]
            pr = x @ basis
            th = np.linspace(0, 2 * np.pi, 400)
            s.plot(np.cos(th), np.sin(th), color="0.8", lw=0.8)
            for k in range(len(a)):
                nk = basis.T @ a[k]
                if np.linalg.norm(nk) < 1e-9:
                    continue
                nk = nk / np.linalg.norm(nk)
                tk = np.array([-nk[1], nk[0]])
                s.plot([-tk[0], tk[0]], [-tk[1], tk[1]], color="tab:red", lw=1)
                s.annotate(f"a{k + 1}.x > 0", xy=0.55 * nk, fontsize=7, color="tab:red", zorder=5,
                           bbox={"fc": "white", "ec": "none", "alpha": 0.7})
            s.scatter(pr[:1500, 0], pr[:1500, 1], s=1, color="tab:blue", alpha=0.5, zorder=3)
            s.set_aspect("equal")
            s.set_xlim(-1.05, 1.05)
            s.set_ylim(-1.05, 1.05)
            s.set_xlabel(f"x . {names[0]}")
            s.set_ylabel(f"x . {names[1]}")
            if row == 0:
                bad = f"\n{1 - keep.mean():.1%} of the posts do not separate" if not keep.all() else ""
                s.set_title(_title(mode, law) + bad, fontsize=9)
        # the chart coordinates of the study's mapping (the law's own; paper: uniform), flat
        # when the posts follow that law
        op = _core.Collision.named(case, law=law)
        keep = P._separates(case, post, P.paper_cases()[case]["geometry"])
        ch = np.asarray(op.chart(post[keep]))
        h = ax[2, col]
        for k in range(ch.shape[1]):
            h.hist(ch[:, k], bins=40, range=(0, 1), density=True, histtype="step", lw=1.2,
                   label=f"u{k + 1}")
        h.axhline(1.0, color="k", lw=1.5, label="the law: 1")
        h.set_xlabel(f"u: {law}-law chart of the separating posts")
        h.set_ylabel("density")
        h.set_ylim(0, 2.2)
        h.legend(fontsize=7, ncol=2)
    fig.suptitle(f"3 particles in 2D ({case}), one pre state: unit relative velocity x on S^3 in two "
                 "projections\n(e1 = a1, e2 = a2 orthogonalized, e3, e4 the rest; red: contact "
                 "planes a_k.x = 0), and its chart coordinates", fontsize=10)
    path = os.path.join(out, f"coverage_{case}.png")
    return _save(fig, path, 90)


def _figure_pair3d(out: str, samples: int) -> str:
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(2, 3, figsize=(10, 6.4), constrained_layout=True)
    a = np.ones(3) / np.sqrt(3.0)
    t1 = np.array([1.0, -1.0, 0.0]) / np.sqrt(2.0)
    t2 = np.cross(a, t1)
    c_grid = np.linspace(0, 1, 200)
    for col, (mode, law) in enumerate(_MODES):
        post, _ = _posts("pair3d", mode, law, samples)
        w = post[:, 0] - post[:, 1]
        w /= np.linalg.norm(w, axis=1)[:, None]
        c = w @ a
        s = ax[0, col]
        th = np.linspace(0, 2 * np.pi, 400)
        s.plot(np.cos(th), np.sin(th), color="tab:green", lw=2, label="rim of the permitted hemisphere")
        keep = c > 0
        s.scatter((w @ t1)[:2000], (w @ t2)[:2000], s=1, alpha=0.5, zorder=3,
                  c=np.where(keep[:2000], "tab:blue", "tab:red"))
        s.set_aspect("equal")
        s.set_xlabel("w.t1 / |w|")
        s.set_ylabel("w.t2 / |w|")
        bad = f"\n{1 - keep.mean():.1%} approach (red)" if not keep.all() else ""
        s.set_title(_title(mode, law) + bad, fontsize=9)
        if col == 0:
            s.legend(fontsize=7, loc="lower left")
        h = ax[1, col]
        h.hist(c, bins=50, range=(-1, 1) if not keep.all() else (0, 1), density=True, color="tab:blue",
               alpha=0.6, label=f"{samples} posts")
        dens = 2 * c_grid if law == "flux" else np.ones_like(c_grid)
        h.plot(c_grid, dens, color="k", lw=1.5, label="2 cos(theta)" if law == "flux" else "uniform: 1")
        h.set_xlabel("cos(theta) = w.a / |w| of the post state")
        h.set_ylabel("density")
        h.legend(fontsize=7)
    fig.suptitle("2 particles in 3D, normal (1,1,1): post directions seen from the normal, one pre state",
                 fontsize=11)
    return _save(fig, os.path.join(out, "coverage_pair3d.png"), 110)


def _figure_exact_cases(out: str, samples: int) -> str:
    import matplotlib.pyplot as plt

    cases = [c for c in stream_cases("exact") if c not in ("raw", "pair2d", "pair3d", "triple1d")
             and not c.startswith(("triple2d", "gas"))]
    fig, ax = plt.subplots(2, len(cases), figsize=(2.2 * len(cases), 4.4), constrained_layout=True)
    for col, case in enumerate(cases):
        for row, law in enumerate(("flux", "uniform")):
            post, _ = _posts(case, "exact", law, samples)
            op = _core.Collision.named(case, law=law)
            ch = np.asarray(op.chart(post))
            h = ax[row, col]
            for k in range(ch.shape[1]):
                h.hist(ch[:, k], bins=25, range=(0, 1), density=True, histtype="step", lw=1)
            h.axhline(1.0, color="k", lw=1)
            h.set_ylim(0, 1.6)
            h.set_title(f"{case}, {law}" + (f"\n{ch.shape[1]} coordinates" if row == 0 else ""), fontsize=8)
            h.tick_params(labelsize=7)
            if col == 0:
                h.set_ylabel("density", fontsize=8)
            if row == 1:
                h.set_xlabel("chart coordinate u", fontsize=8)
    fig.suptitle("The other exact cases: chart coordinates of 20000 post states of one pre state, "
                 "each law read by its own chart (flat = the law)", fontsize=10)
    return _save(fig, os.path.join(out, "coverage_exact_cases.png"), 100)


def coverage(out: str = "docs/figures/randomness", samples: int = 20000) -> list[str]:
    """The coverage figures (PNG): pair2d, triple1d, triple2d-c1..c4 and pair3d, exact flux
    and uniform beside paper mode, and the chart coordinates of every other exact case, from
    one fixed pre state each. Returns the paths."""
    import matplotlib

    matplotlib.use("Agg")
    os.makedirs(out, exist_ok=True)
    paths = [_figure_pair2d(out, samples), _figure_triple1d(out, samples)]
    for c in ("triple2d-c1", "triple2d-c2", "triple2d-c3", "triple2d-c4"):
        paths.append(_figure_triple2d(out, c, samples))
    paths += [_figure_pair3d(out, samples), _figure_exact_cases(out, samples)]
    return paths


def _run_info(argv: Sequence[str], t0: float) -> dict:
    def sh(cmd: list[str]) -> str:
        try:
            return subprocess.run(cmd, capture_output=True, text=True, check=True).stdout.strip()
        except (OSError, subprocess.CalledProcessError):
            return ""

    return {"command": "python -m revcol.randomness " + " ".join(argv),
            "commit": sh(["git", "rev-parse", "--short", "HEAD"]), "uptime": sh(["uptime"]),
            "wall_s": round(time.perf_counter() - t0, 1),
            "dieharder": " ".join(re.findall(r"dieharder version \S+", sh(["dieharder", "-l"]))[:1])}


def _summary(b: dict) -> str:
    c = b["config"]
    tests = " ".join(f"{r['test']}:{r['verdict']}" for r in b["tests"])
    return (f"{c['case']:12s} {c['mode']:5s} {c['law']:7s} {c['rng']:16s} {b['verdict']:6s} "
            f"KS p={b['ks_p']:.3f}  restarts={b['stream']['restarts']}  {tests}")


def table(runs: Sequence[dict], detail: bool = False) -> str:
    """Markdown: one row per battery (verdict, KS of its p-values, extremes, WEAK tests and
    their reruns); with ``detail``, one row per test and p-value column per battery."""
    if detail:
        head = ["test"] + [f"{r['config']['case']} {r['config']['mode']} {r['config']['law']} "
                           f"{r['config']['rng']}" for r in runs]
        lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        for i, t in enumerate(runs[0]["tests"]):
            cells = [f"{t['name']} (-d {t['test']})"]
            for r in runs:
                rt = r["tests"][i]
                ps = ", ".join(f"{row['p']:.4f}" for row in rt["rows"])
                if "rerun" in rt:
                    ps += " (WEAK; rerun: " + ", ".join(f"{row['p']:.4f}" for row in rt["rerun"]["rows"]) + ")"
                cells.append(ps)
            lines.append("| " + " | ".join(cells) + " |")
        return "\n".join(lines)
    lines = ["| case | mode | law | rng | words | restarts | n p | min p | max p | KS p | WEAK (rerun) | verdict |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in runs:
        c = r["config"]
        weak = "; ".join(f"-d {t['test']}: {t['verdict']}" for t in r["tests"] if "rerun" in t) or "-"
        p = r["pvalues"]
        lost = (f"{r['stream'].get('skipped', 0)} groups" if c["case"].startswith("gas")
                else r["stream"]["restarts"])
        lines.append(f"| {c['case']} | {c['mode']} | {c['law']} | {c['rng']} | {r['words']:.2g} | "
                     f"{lost} | {len(p)} | {min(p):.2g} | {max(p):.4f} | {r['ks_p']:.3f} | "
                     f"{weak} | **{r['verdict']}** |")
    return "\n".join(lines)


def marginals(config: dict, words: int = 3_000_000) -> dict:
    """One-sample KS of each chart coordinate of the first ``words`` words of a stream against
    the uniform law: D, sqrt(n) D and p per coordinate. A battery failure with a large D is
    the law's (the operator's or the chart's), not the generator's."""
    from scipy import stats

    s = stream(**config)
    w = s.words(int(words) - int(words) % s.width).reshape(-1, s.width)
    out = []
    for k in range(s.width):
        r = stats.kstest((w[:, k] + 0.5) / 2.0**32, "uniform")
        out.append({"D": float(r.statistic), "K": float(r.statistic * np.sqrt(len(w))), "p": float(r.pvalue)})
    return {"config": dict(config), "words": int(w.size), "restarts": int(s.restarts), "coordinates": out}


def _tests(spec: str) -> list[int]:
    return list(PAPER_TESTS) if spec == "paper" else [int(t) for t in spec.split(",")]


def _matrix_configs(cases: Sequence[str], modes: Sequence[str], laws: Sequence[str],
                    rngs: Sequence[str], gas: Optional[dict] = None) -> list[dict]:
    out = []
    for mode in modes:
        known = stream_cases(mode)
        for case in cases:
            if case not in known:
                continue
            for law in (laws if mode == "exact" else ["uniform"]):
                for rng in rngs:
                    out.append(_gas_options({"case": case, "mode": mode, "law": law, "rng": rng, "seed": 1}, gas))
    return out


def _gas_options(cfg: dict, gas: Optional[dict]) -> dict:
    """cfg with the gas options (particles, fraction, warmup) when its case is a gas."""
    if not cfg["case"].startswith("gas"):
        return cfg
    g = {"particles": GAS_PARTICLES, "fraction": GAS_FRACTION, "warmup": GAS_WARMUP}
    g.update({k: v for k, v in (gas or {}).items() if v is not None})
    return dict(cfg, particles=int(g["particles"]), fraction=float(g["fraction"]), warmup=float(g["warmup"]))


def main(argv: Optional[Sequence[str]] = None) -> int:
    """The command line (see the module docstring)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    ap = argparse.ArgumentParser(prog="python -m revcol.randomness", description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("--words", type=float, default=3e6)
    common.add_argument("--tests", default="paper", help="'paper' or dieharder numbers, e.g. 15,12")
    common.add_argument("--json", help="write the results here")
    common.add_argument("--workdir", help="where the word files go (default: the temp dir)")
    common.add_argument("--defaults", action="store_true",
                        help="dieharder's default psamples (a long file); otherwise fit them to the file")
    gas_args = argparse.ArgumentParser(add_help=False)
    gas_args.add_argument("--particles", type=int, help=f"gas cases: N (default {GAS_PARTICLES})")
    gas_args.add_argument("--fraction", type=float, help=f"gas cases: packing fraction (default {GAS_FRACTION})")
    gas_args.add_argument("--warmup", type=float,
                          help=f"gas cases: collisions per particle before the first word (default {GAS_WARMUP})")
    b = sub.add_parser("battery", parents=[common, gas_args], help="one case")
    b.add_argument("--case", default="pair2d")
    b.add_argument("--mode", default="exact")
    b.add_argument("--law", default="flux")
    b.add_argument("--rng", default="philox")
    b.add_argument("--seed", type=int, default=1)
    sub.add_parser("controls", parents=[common], help="the good and bad controls")
    m = sub.add_parser("matrix", parents=[common, gas_args], help="case x mode x law x rng")
    m.add_argument("--cases", default="pair2d,triple1d")
    m.add_argument("--modes", default="exact,paper")
    m.add_argument("--laws", default="flux,uniform")
    m.add_argument("--rngs", default="clcg4,philox")
    w = sub.add_parser("words", parents=[gas_args], help="write a raw word file (for dieharder by hand)")
    w.add_argument("path")
    w.add_argument("--words", type=float, default=3e6)
    for k, v in (("--case", "pair2d"), ("--mode", "exact"), ("--law", "flux"), ("--rng", "philox")):
        w.add_argument(k, default=v)
    w.add_argument("--seed", type=int, default=1)
    tb = sub.add_parser("table", help="markdown tables of result files")
    tb.add_argument("files", nargs="+")
    tb.add_argument("--detail", action="store_true", help="one row per test, p-values per battery")
    tb.add_argument("--only", help="batteries to show, e.g. pair2d:exact:flux:clcg4,triple1d:paper:uniform:clcg4")
    mg = sub.add_parser("marginals", help="per-coordinate KS of the words of each battery in result files")
    mg.add_argument("files", nargs="+")
    mg.add_argument("--words", type=float, default=3e6)
    mg.add_argument("--json", help="write the results here")
    c = sub.add_parser("coverage", help="the coverage figures")
    c.add_argument("--out", default="docs/figures/randomness")
    c.add_argument("--samples", type=int, default=20000)
    a = ap.parse_args(argv)
    t0 = time.perf_counter()
    if a.cmd == "coverage":
        for p in coverage(a.out, samples=a.samples):
            print(p)
        return 0
    if a.cmd == "table":
        runs = [r for f in a.files for r in json.load(open(f))["runs"]]
        if a.only:
            key = [tuple(k.split(":")) for k in a.only.split(",")]
            runs = [r for k in key for r in runs
                    if tuple(r["config"][x] for x in ("case", "mode", "law", "rng")) == k]
        print(table(runs, a.detail))
        return 0
    if a.cmd == "marginals":
        res = []
        for f in a.files:
            for r in json.load(open(f))["runs"]:
                keys = ("case", "mode", "law", "rng", "seed", "particles", "fraction", "warmup")
                res.append(marginals({k: r["config"][k] for k in keys if k in r["config"]}, int(a.words)))
                c = res[-1]["config"]
                ks = ", ".join(f"D={x['D']:.2g} p={x['p']:.2g}" for x in res[-1]["coordinates"])
                print(f"| {c['case']} | {c['mode']} | {c['law']} | {c['rng']} | {ks} |", flush=True)
        if a.json:
            with atomic_open(a.json) as f:
                json.dump(dict(_run_info(argv, t0), runs=res), f, indent=1)
                f.write("\n")
        return 0
    gas = {k: getattr(a, k, None) for k in ("particles", "fraction", "warmup")}
    if a.cmd == "words":
        cfg = _gas_options({"case": a.case, "mode": a.mode, "law": a.law, "rng": a.rng, "seed": a.seed}, gas)
        print(json.dumps(dict(write_words(a.path, int(a.words), **cfg), config=cfg)))
        return 0
    if not has_dieharder():
        print("dieharder is not installed (apt-get install dieharder; scripts/setup.sh does it)",
              file=sys.stderr)
        return 2
    kw = {"workdir": a.workdir, "fit": not a.defaults}
    tests = _tests(a.tests)
    commit = _run_info([], t0)["commit"]  # the code that runs (HEAD may move during a long run)

    def save(runs: list[dict], complete: bool) -> None:
        if a.json:  # after every battery of a matrix, so that a stopped run keeps what it did
            with atomic_open(a.json) as f:
                json.dump(dict(_run_info(argv, t0), commit=commit, complete=complete, runs=runs), f, indent=1)
                f.write("\n")

    if a.cmd == "battery":
        cfg = _gas_options({"case": a.case, "mode": a.mode, "law": a.law, "rng": a.rng, "seed": a.seed}, gas)
        runs = [battery(cfg, int(a.words), tests, **kw)]
    elif a.cmd == "controls":
        runs = controls(int(a.words), tests, **kw)
    else:
        runs = []
        for cfg in _matrix_configs(a.cases.split(","), a.modes.split(","), a.laws.split(","),
                                   a.rngs.split(","), gas):
            runs.append(battery(cfg, int(a.words), tests, **kw))
            print(_summary(runs[-1]), flush=True)
            save(runs, False)
    if a.cmd != "matrix":
        for r in runs:
            print(_summary(r))
    save(runs, True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
