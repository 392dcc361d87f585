"""The trade-off study's law check (:mod:`revcol.studies.tradeoff`): how far an operator's post
states are from its target law, by two-sample KS against rejection sampling of the law itself.
"""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from .. import _core
from .. import paper as _paper

__all__ = ["rejection_posts", "law_distance"]



def _generator(rng: str, seed: int):
    return _core.CLCG4(stream=500 + seed) if rng == "clcg4" else _core.Philox(key=(500 + seed, 7))


def _helmert(n: int) -> np.ndarray:
    """Orthonormal rows spanning the zero-sum vectors of R^n ((n-1) x n)."""
    h = np.zeros((n - 1, n))
    for k in range(1, n):
        h[k - 1, :k] = 1.0 / math.sqrt(k * (k + 1))
        h[k - 1, k] = -k / math.sqrt(k * (k + 1))
    return h


def rejection_posts(v: np.ndarray, contacts: Sequence[tuple[int, int, np.ndarray]], law: str, count: int,
                    rng: np.random.Generator) -> np.ndarray:
    """``count`` post states (count, n, d) of the pre state ``v`` (n, d) from the target law,
    by rejection and without any chart: the relative velocities x (orthonormal Helmert
    coordinates) uniform on their sphere, kept where every contact (i, j, unit r) separates,
    (v_i - v_j) . r > 0; for the flux law kept further with probability cos(eta) = |x_V| / |x|
    (x_V: x's part in the span of the contacts' constraint vectors)."""
    n, d = v.shape
    hd = np.kron(_helmert(n), np.eye(d))  # ((n-1) d) x (n d), orthonormal rows
    a = np.array([np.kron(_helmert(n)[:, i] - _helmert(n)[:, j], r) for (i, j, r) in contacts])
    q = np.linalg.qr(a.T)[0]
    rho = float(np.linalg.norm(hd @ v.ravel()))
    cm = v.mean(axis=0)
    out, have = [], 0
    while have < count:
        x = rng.normal(size=(200_000, hd.shape[0]))
        x /= np.linalg.norm(x, axis=1, keepdims=True)
        keep = np.all(x @ a.T > 0.0, axis=1)
        if law == "flux":
            keep &= rng.random(len(x)) < np.linalg.norm(x @ q, axis=1)
        out.append(x[keep])
        have += int(keep.sum())
    x = np.concatenate(out)[:count] * rho
    return cm[None, None, :] + (x @ hd).reshape(count, n, d)


def _ks2(a: np.ndarray, b: np.ndarray) -> float:
    """Two-sample KS distance of two 1-D samples."""
    a, b = np.sort(a), np.sort(b)
    z = np.concatenate([a, b])
    return float(np.abs(np.searchsorted(a, z, "right") / len(a) - np.searchsorted(b, z, "right") / len(b)).max())


def _unit(r) -> np.ndarray:
    r = np.asarray(r, float)
    return r / np.linalg.norm(r)


def law_distance(settings: dict, samples: int) -> dict:
    """Distance of the point's post law from its target law for one fixed pre state:
    ``samples`` post states against as many :func:`rejection_posts` (flux or uniform; paper
    mode's target is the uniform law), two-sample KS distance on three projections of the
    velocities (the first and last component, one random direction), the largest
    (``law_D``); ``law_D_noise`` = 1.54 sqrt(2 / samples), the 95% level of the largest of
    three independent distances when the laws are equal. None for the 1D pair (no draw). ``invalid_post``: the fraction of post states that
    do not separate (paper mode; they are compared as they are)."""
    case, mode = settings["case"], settings["mode"]
    law = "uniform" if mode == "paper" else settings["law"]  # the paper's stated target
    gen = _generator(settings["rng"], int(settings["seed"]))
    if case == "pair1d":
        return {"law_D": None, "law_D_noise": None, "invalid_post": 0.0}
    if case == "pair2d":  # verify's pair: normal (1, 1)
        v, x = np.array([[0.25, -0.5], [1.0, 0.75]]), np.array([1.0, 1.0])
        op = _core.Pair2D(mode=mode, law=law, bits=int(settings["bits"]))
        post = op.forward(np.broadcast_to(v, (samples, 2, 2)), x, rng=gen)
        contacts = [(0, 1, _unit(x))]
    elif mode == "exact":
        nc = next(c for c in _core.named_cases() if c["name"] == case)
        op = _core.Collision.named(case, law=law, bits=int(settings["bits"]))
        pre_rng = np.random.default_rng(12345)
        while True:
            v = pre_rng.normal(size=(op.particles, op.dim))
            if max(op.normal_speeds(v)) < 0:
                break
        post = op.forward(np.broadcast_to(v, (samples,) + v.shape), rng=gen)
        pos = np.asarray(nc["positions"], float)
        contacts = [(i, j, _unit(pos[i] - pos[j])) for (i, j) in nc["contacts"]]
    else:
        pc = _paper.paper_cases()[case]
        x, v = pc["geometry"], pc["velocities"]
        if case == "pair3d":
            op, w = _core.Pair3DPaper(), v
        elif case == "triple1d":
            op, w = _core.Triple1DPaper(arc=settings["arc"]), v[:, 0]
        else:
            op, w = _core.Triple2DPaper(), v
        post = op.forward(np.broadcast_to(w, (samples,) + w.shape), x, rng=gen)
        contacts = _paper._contacts(case, x)
    post = np.asarray(post).reshape(samples, *v.shape)
    ok = np.ones(samples, bool)
    for (i, j, r) in contacts:
        ok &= (post[:, i, :] - post[:, j, :]) @ r > 0.0
    ref = rejection_posts(v, contacts, law, samples, np.random.default_rng(777 + int(settings["seed"])))
    u = np.random.default_rng(3).normal(size=v.size)
    proj = [np.eye(v.size)[0], np.eye(v.size)[-1], u / np.linalg.norm(u)]
    flat, rflat = post.reshape(samples, -1), ref.reshape(samples, -1)
    return {"law_D": max(_ks2(flat @ p, rflat @ p) for p in proj), "law_D_noise": 1.54 * math.sqrt(2.0 / samples),
            "invalid_post": float(1.0 - ok.mean())}
