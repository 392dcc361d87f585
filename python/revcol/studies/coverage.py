"""The randomness study's coverage figures (``python -m revcol.studies.randomness coverage``): where
one fixed pre state's post states land, for pair2d, triple1d, triple2d-c1..c4 and pair3d (exact flux
and uniform beside paper mode), and the chart coordinates of every other exact case.
matplotlib and PIL are imported when a figure is drawn, not with this module.
"""
from __future__ import annotations

import io
import os
from typing import Any

import numpy as np

from .. import _core
from .. import paper as P
from ..rng import Philox
from .words import stream_cases

__all__ = ["coverage"]


def _posts(case: str, mode: str, law: str, samples: int, seed: int = 7) -> tuple[np.ndarray, np.ndarray]:
    """``samples`` post states (samples, n, d) of one fixed pre state (the word stream's start)
    and that pre state: exact mode through revcol.Collision, paper mode through its operator."""
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
    import matplotlib.pyplot as plt  # optional: only when a figure is drawn
    from PIL import Image  # comes with matplotlib: only when a figure is drawn

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
    import matplotlib.pyplot as plt  # optional: only when a figure is drawn

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
    import matplotlib.pyplot as plt  # optional: only when a figure is drawn

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
    import matplotlib.pyplot as plt  # optional: only when a figure is drawn

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
    import matplotlib.pyplot as plt  # optional: only when a figure is drawn

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
    import matplotlib.pyplot as plt  # optional: only when a figure is drawn

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
    import matplotlib  # optional: only when figures are drawn

    matplotlib.use("Agg")
    os.makedirs(out, exist_ok=True)
    paths = [_figure_pair2d(out, samples), _figure_triple1d(out, samples)]
    for c in ("triple2d-c1", "triple2d-c2", "triple2d-c3", "triple2d-c4"):
        paths.append(_figure_triple2d(out, c, samples))
    paths += [_figure_pair3d(out, samples), _figure_exact_cases(out, samples)]
    return paths
