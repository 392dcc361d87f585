"""Paper mode beyond the 2D pair: the paper's own procedures for 2 particles in 3D and
3 particles in 1D and 2D (Perumalla & Protopopescu, ACM TOMACS 2013, §4.3-4.5), and the
measurements that show where they are not invertible or not uniform.

- :class:`Pair3DPaper`: §4.3, two draws per collision (not invertible as printed).
- :class:`Triple1DPaper`: §4.4, Procedures 3 and 4, ellipse arc-length G-to-Psi (three methods).
- :class:`Triple2DPaper`: §4.5, canonical configurations C1-C4, Procedures 5, 6 and 7.
- :func:`failure_rate`: forward + reverse of 10^6 collisions; how many fail, and how.
- :func:`uniform_posts`: the reference law by rejection sampling (the definition of the
  uniform law: relative velocities uniform on the sphere |x| = rho of the zero-momentum
  subspace, restricted to the cone where every contact separates).
- :func:`bias`: two-sample Kolmogorov-Smirnov statistics of paper-mode post states against
  :func:`uniform_posts`, per velocity component and per paper angle, for fixed pre states.
- :func:`uniformity`: the 1D triple's post angle against its exact uniform law, on 10^8 samples.

Command line (``python -m revcol.studies.paper_study``; each finding in docs/paper-findings.md quotes one)::

    python -m revcol.studies.paper_study failure-rate triple2d-c1 --collisions 1000000 --pre uniform
    python -m revcol.studies.paper_study bias pair3d --samples 1000000
    python -m revcol.studies.paper_study uniformity --samples 100000000

    >>> import numpy as np, revcol
    >>> op, g = revcol.Triple1DPaper(arc="table"), revcol.CLCG4()
    >>> v, x = np.array([0.75, 0.25, -0.5]), np.array([0.0, 1.0, 2.0])
    >>> np.allclose(op.reverse(op.forward(v, x, rng=g), x, rng=g), v)
    True
"""
from __future__ import annotations


import numpy as np

from . import _core
from ._core import Collision, Pair3DPaper, Triple1DPaper, Triple2DPaper
from .rng import CLCG4

__all__ = ["Pair3DPaper", "Triple1DPaper", "Triple2DPaper", "PAPER_CASES", "paper_cases",
           "failure_rate", "uniform_posts", "exact_uniform_posts", "paper_posts", "bias", "uniformity"]


def paper_cases() -> dict[str, dict]:
    """The paper-mode cases by name: n, d, geometry (pair3d: the normal; triples: the
    positions), the default start ``velocities`` (n x d by id) and a description."""
    out = {}
    for c in _core.paper_cases():
        c = dict(c)
        n, d = c["n"], c["d"]
        c["velocities"] = np.array(c["velocities"]).reshape(n, d)
        c["geometry"] = np.array(c["geometry"]) if d != 2 else np.array(c["geometry"]).reshape(n, d)
        out[c["name"]] = c
    return out


#: the paper-mode case names: pair3d, triple1d, triple2d-c1 .. triple2d-c4
PAPER_CASES = tuple(c["name"] for c in _core.paper_cases())


def failure_rate(case: str, *, collisions: int = 1_000_000, seed: int = 0, pre: str = "chain",
                 printed_reverse: bool = False, cos_tol: float = 1e-8, arc: str = "simpson",
                 angle: str = "parametric") -> dict:
    """Forward one collision, reverse it with the same draws, compare with the pre state
    (1e-9 relative), ``collisions`` times.

    pre="chain": the verify chain (post negated is the next pre, invariants held), restarted
    from a fresh state after a post state that does not separate; pre="uniform": every pre
    state fresh (standard normal velocities conditioned on approaching). Returns counts of
    ``ok``, ``invalid_post`` (the forward post state does not separate), ``reverse_threw``,
    ``wrong`` (reverse returned another state), their ``failure_rate``, ``max_ok_error``
    and the ``first_failure`` in words.
    """
    if case not in PAPER_CASES:
        raise ValueError(f"unknown paper case {case!r}; known: {', '.join(PAPER_CASES)}")
    return _core.paper_study(case=case, collisions=int(collisions), seed=int(seed), pre=pre,
                             printed_reverse=bool(printed_reverse), cos_tol=float(cos_tol),
                             arc=arc, angle=angle)


def _helmert(n: int) -> np.ndarray:
    """(n-1) x n orthonormal rows orthogonal to (1, ..., 1)."""
    h = np.zeros((n - 1, n))
    for k in range(1, n):
        h[k - 1, :k] = 1.0
        h[k - 1, k] = -k
        h[k - 1] /= np.sqrt(k * (k + 1))
    return h


def _contacts(case: str, geometry: np.ndarray) -> list[tuple[int, int, np.ndarray]]:
    """(i, j, unit normal from j to i) of every contact of a case's geometry."""
    if case == "pair3d":
        n = np.asarray(geometry, float)
        return [(0, 1, n / np.linalg.norm(n))]
    x = np.asarray(geometry, float).reshape(3, -1)
    pairs = [(0, 1), (1, 2), (0, 2)]
    dist = {p: np.linalg.norm(x[p[0]] - x[p[1]]) for p in pairs}
    dmin = min(dist.values())
    out = []
    for (i, j) in pairs:
        if dist[(i, j)] <= dmin * (1 + 1e-9):
            r = x[i] - x[j]
            out.append((i, j, r / np.linalg.norm(r)))
    return out


def uniform_posts(case: str, velocities: np.ndarray, samples: int, *, seed: int = 0,
                  geometry: np.ndarray | None = None) -> np.ndarray:
    """``samples`` post-collision states (samples, n, d) from the uniform law by rejection:
    the relative velocities in orthonormal Helmert coordinates (dimension (n-1) d) uniform on
    the sphere of the pre state's radius, kept where every contact separates; the centre of
    mass is the pre state's."""
    cases = paper_cases()
    geometry = cases[case]["geometry"] if geometry is None else np.asarray(geometry, float)
    v = np.asarray(velocities, float)
    n = v.shape[0]
    d = v.shape[1] if v.ndim == 2 else 1
    v = v.reshape(n, d)
    h = _helmert(n)
    cm = v.mean(axis=0)
    rho = np.linalg.norm(h @ v)
    contacts = _contacts(case, geometry)
    rng = np.random.default_rng(seed)
    out = []
    have = 0
    while have < samples:
        m = max(1024, 2 * (samples - have))
        x = rng.normal(size=(m, n - 1, d))
        x *= rho / np.linalg.norm(x.reshape(m, -1), axis=1)[:, None, None]
        w = cm + np.einsum("rp,mrk->mpk", h, x)
        keep = np.ones(m, bool)
        for (i, j, r) in contacts:
            keep &= (w[:, i, :] - w[:, j, :]) @ r > 0.0
        out.append(w[keep])
        have += int(keep.sum())
    return np.concatenate(out)[:samples]


def exact_uniform_posts(case: str, velocities: np.ndarray, samples: int, *, seed: int = 0,
                        geometry: np.ndarray | None = None) -> np.ndarray:
    """As :func:`uniform_posts`, from exact mode's ``uniform`` law (``revcol.Collision``, the
    general exact operator) instead of rejection sampling: a cross-check of both."""
    c = paper_cases()[case]
    geometry = c["geometry"] if geometry is None else np.asarray(geometry, float)
    contacts = _contacts(case, geometry)
    op = Collision(c["n"], c["d"], [(i, j) for (i, j, _) in contacts],
                   normals=np.array([r for (_, _, r) in contacts]), law="uniform")
    v = np.asarray(velocities, float).reshape(c["n"], c["d"])
    return op.forward(np.broadcast_to(v, (samples, c["n"], c["d"])), rng=CLCG4(stream=1000 + seed))


def _operator(case: str, **opts):
    if case == "pair3d":
        return Pair3DPaper(printed_reverse=opts.get("printed_reverse", False))
    if case == "triple1d":
        return Triple1DPaper(arc=opts.get("arc", "simpson"), cos_tol=opts.get("cos_tol", 1e-8),
                             printed_reverse=opts.get("printed_reverse", False),
                             angle=opts.get("angle", "parametric"))
    return Triple2DPaper()


def paper_posts(case: str, velocities: np.ndarray, samples: int, *, stream: int = 0, **opts) -> np.ndarray:
    """``samples`` paper-mode post states (samples, n, d) from one pre state, CLCG4 draws."""
    c = paper_cases()[case]
    op = _operator(case, **opts)
    v = np.asarray(velocities, float).reshape(c["n"], c["d"])
    if case == "triple1d":
        v = v[:, 0]
    post = op.forward(np.broadcast_to(v, (samples,) + v.shape), c["geometry"], rng=CLCG4(stream=stream))
    return post.reshape(samples, c["n"], c["d"])


def _angles(case: str, posts: np.ndarray, geometry) -> dict[str, np.ndarray]:
    if case == "pair3d":
        a = Pair3DPaper.angles(posts)
        return {"phi1": a[:, 0], "phi2": a[:, 1]}
    if case == "triple1d":
        return {"phi": Triple1DPaper.angle_of(posts[:, :, 0], geometry)}
    a = Triple2DPaper.angles(posts, geometry)
    return {"phi1": a[:, 0], "phi2": a[:, 1], "phi3": a[:, 2]}


def _separates(case: str, posts: np.ndarray, geometry) -> np.ndarray:
    keep = np.ones(len(posts), bool)
    for (i, j, r) in _contacts(case, geometry):
        keep &= (posts[:, i, :] - posts[:, j, :]) @ r > 0.0
    return keep


def _pre_states(case: str, count: int, seed: int) -> list[np.ndarray]:
    """The case's default start, then count - 1 states with standard normal velocities
    conditioned on approaching at every contact."""
    c = paper_cases()[case]
    states = [c["velocities"]]
    rng = np.random.default_rng(seed + 7919)
    contacts = _contacts(case, c["geometry"])
    while len(states) < count:
        v = rng.normal(size=(c["n"], c["d"]))
        if all((v[i] - v[j]) @ r < 0 for (i, j, r) in contacts):
            states.append(v)
    return states


def bias(case: str, *, samples: int = 1_000_000, states: int = 3, seed: int = 0,
         reference: str = "rejection", **opts) -> list[dict]:
    """Distance of the paper-mode post law from the uniform law, for ``states`` fixed pre
    states (the case's start first): two-sample KS (scipy.stats.ks_2samp) of ``samples``
    paper-mode post states against as many :func:`uniform_posts`, on every velocity
    component (``v{particle}{axis}``) and on the paper's own angles of the post state.
    Also the fraction of paper-mode post states that do not separate. reference="exact" uses
    exact mode's uniform law (revcol.Collision) instead of rejection sampling;
    "exact-vs-rejection" compares those two references with each other (no paper mode)."""
    from scipy import stats  # optional (the test extra) and slow to import: only when used

    c = paper_cases()[case]
    geometry = c["geometry"]
    out = []
    for k, v in enumerate(_pre_states(case, states, seed)):
        paper = paper_posts(case, v, samples, stream=seed * 101 + k, **opts)
        if reference == "rejection":
            ref = uniform_posts(case, v, samples, seed=seed * 101 + k + 1)
        elif reference == "exact":
            ref = exact_uniform_posts(case, v, samples, seed=seed * 101 + k + 1)
        elif reference == "exact-vs-rejection":  # the two references against each other
            paper = exact_uniform_posts(case, v, samples, seed=seed * 101 + k)
            ref = uniform_posts(case, v, samples, seed=seed * 101 + k + 1)
        else:
            raise ValueError(f"reference must be 'rejection', 'exact' or 'exact-vs-rejection', got {reference!r}")
        proj: dict[str, dict] = {}
        axes = "xyz"
        for p in range(c["n"]):
            for a in range(c["d"]):
                r = stats.ks_2samp(paper[:, p, a], ref[:, p, a])
                proj[f"v{p}{axes[a]}"] = {"D": float(r.statistic), "p": float(r.pvalue)}
        pa = _angles(case, paper, geometry)
        ra = _angles(case, ref, geometry)
        for name in pa:
            r = stats.ks_2samp(pa[name], ra[name])
            proj[name] = {"D": float(r.statistic), "p": float(r.pvalue)}
        worst = max(proj, key=lambda name: proj[name]["D"])
        out.append({"case": case, "state": np.asarray(v).ravel().tolist(), "samples": samples,
                    "invalid_post": float(1.0 - _separates(case, paper, geometry).mean()),
                    "max_D": proj[worst]["D"], "min_p": min(x["p"] for x in proj.values()),
                    "worst": worst, "projections": proj, "reference": reference, "options": dict(opts)})
    return out


def uniformity(*, samples: int = 100_000_000, states: int = 3, seed: int = 0, arc: str = "table",
               angle: str = "parametric", bins: int = 1 << 16, chunk: int = 5_000_000) -> list[dict]:
    """The 1D triple's post angle phi is the uniform angle on the round circle of relative
    velocities, so under the uniform law u = (phi - 7pi/6) / (pi/3) is uniform on (0, 1).
    One-sample KS distance of u over ``samples`` paper-mode collisions from each of
    ``states`` fixed pre states (binned into ``bins`` cells, so D is exact to 1/bins; the
    p-value is the asymptotic Kolmogorov one), and ``law_D``: the distance of the operator's
    own law of u (from 10^7 evenly spaced G) from uniform. Large samples find deviations that
    the two-sample test of :func:`bias` at 10^6 cannot."""
    from scipy import stats  # optional (the test extra) and slow to import: only when used

    c = paper_cases()["triple1d"]
    x = c["geometry"]
    op = Triple1DPaper(arc=arc, angle=angle)
    out = []
    for k, v in enumerate(_pre_states("triple1d", states, seed)):
        gen = CLCG4(stream=seed * 101 + k)
        counts = np.zeros(bins, np.int64)
        done = 0
        while done < samples:
            m = min(chunk, samples - done)
            post = op.forward(np.broadcast_to(v[:, 0], (m, 3)), x, rng=gen)
            u = (Triple1DPaper.angle_of(post, x) - S1_START) / (np.pi / 3)
            counts += np.bincount(np.clip((u * bins).astype(np.int64), 0, bins - 1), minlength=bins)
            done += m
        cdf = np.cumsum(counts) / samples
        edges = np.arange(1, bins + 1) / bins
        d = float(max(np.abs(cdf - edges).max(), np.abs(np.concatenate([[0.0], cdf[:-1]]) - edges + 1 / bins).max()))
        # the operator's own law of u (a fine deterministic grid of G): its distance from uniform
        grid = 10_000_000
        phi0 = float(Triple1DPaper.angle_of(v[:, 0], x))
        uu = np.sort(np.mod(phi0 + op.psi((np.arange(grid) + 0.5) / grid) - S1_START, np.pi / 3) / (np.pi / 3))
        law_d = float(max(np.abs(uu - np.arange(grid) / grid).max(), np.abs(uu - np.arange(1, grid + 1) / grid).max()))
        out.append({"state": v.ravel().tolist(), "samples": samples, "D": d,
                    "sqrtN_D": float(np.sqrt(samples) * d),
                    "p": float(stats.kstwobign.sf(np.sqrt(samples) * d)), "law_D": law_d,
                    "arc": arc, "angle": angle})
    return out


#: start of the post arc S1 of the 1D triple
S1_START = 7 * np.pi / 6
