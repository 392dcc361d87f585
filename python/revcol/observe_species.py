"""Observables of a mixture per species, from frames (positions and velocities taken at chosen
times, e.g. ``sim.positions`` after ``sim.run(time=...)``): the partial radial distributions
g_ab(r) and their contact values, and each species' kinetic temperature (equal masses: the
equipartition check T_a = T_b); and from the collisions themselves (the lattice engine's
trace), the contact values through the collision rates, an exact identity at equilibrium that
needs no extrapolation of g to contact. A periodic box; docs/mixtures.md.

    >>> import numpy as np
    >>> rng = np.random.default_rng(1)
    >>> frames = rng.uniform(0, 10.0, size=(20, 400, 2))        # an ideal gas: g_ab = 1
    >>> r, g = partial_radial_distribution(frames, [10.0, 10.0], np.arange(400) % 2, bins=10, r_max=4.0)
    >>> g.shape, bool(np.all(np.abs(g[:, :, 3:] - 1) < 0.15))
    ((2, 2, 10), True)
"""
from __future__ import annotations

import math
from typing import Optional, Sequence

import numpy as np

__all__ = ["partial_radial_distribution", "species_temperatures", "species_labels", "pair_collision_counts",
           "contact_from_rates"]


def species_labels(diameters: Sequence[float]) -> tuple:
    """(labels, sizes): each particle's species index by its diameter (equal diameters, one
    species; ascending), and the species' diameters."""
    sizes, labels = np.unique(np.asarray(diameters, dtype=float), return_inverse=True)
    return labels, sizes


def partial_radial_distribution(frames, box: Sequence[float], labels: Sequence[int], bins: int = 100,
                                r_max: Optional[float] = None, chunk: int = 512) -> tuple:
    """g_ab(r) of a periodic box averaged over frames ((F, n, d) or one (n, d)), species by
    ``labels`` (n integers 0..S-1): the ordered pairs (i in a, j in b, i != j) at distance r
    (minimum image) over F N_a (N_b - [a = b]) / V times the shell's volume, so an ideal mixture
    has g_ab = 1 (the finite-size normalization of :func:`revcol.observe.radial_distribution`,
    which g of a one-species gas equals). ``r_max`` at most L/2 (default). Returns (r centres,
    g of shape (S, S, bins))."""
    x = np.asarray(frames, dtype=float)
    x = x[None] if x.ndim == 2 else x
    if x.ndim != 3 or x.shape[2] not in (2, 3):
        raise ValueError(f"frames must have shape (F, n, d) with d = 2 or 3, got {x.shape}")
    f, n, d = x.shape
    L = np.asarray(box, dtype=float)
    if L.shape != (d,) or not np.all(L > 0):
        raise ValueError(f"box needs {d} positive lengths, got {list(np.ravel(L))}")
    lab = np.asarray(labels)
    if lab.shape != (n,) or not np.issubdtype(lab.dtype, np.integer) or (n and lab.min() < 0):
        raise ValueError(f"labels must be {n} integers >= 0 (one species index per particle)")
    if isinstance(bins, bool) or not isinstance(bins, int) or bins < 1:
        raise TypeError(f"bins must be a positive integer, got {bins!r}")
    limit = 0.5 * float(L.min())
    r_max = limit if r_max is None else float(r_max)
    if not 0 < r_max <= limit + 1e-12:
        raise ValueError(f"r_max must be in (0, L/2 = {limit:g}], got {r_max}")
    s = int(lab.max()) + 1
    counts = np.zeros(s * s * bins, dtype=np.int64)
    dr = r_max / bins
    for frame in x:
        for a in range(0, n, chunk):
            diff = frame[a:a + chunk, None, :] - frame[None, :, :]
            diff -= L * np.round(diff / L)
            r = np.sqrt(np.einsum("ijk,ijk->ij", diff, diff))
            i = np.arange(a, min(a + chunk, n))
            r[i - a, i] = np.inf  # not with itself
            ii, jj = np.nonzero(r < r_max)
            k = np.minimum((r[ii, jj] / dr).astype(np.int64), bins - 1)
            counts += np.bincount((lab[ii + a] * s + lab[jj]) * bins + k, minlength=s * s * bins)
    edges = np.linspace(0.0, r_max, bins + 1)
    shell = (math.pi * np.diff(edges**2)) if d == 2 else (4.0 * math.pi / 3.0 * np.diff(edges**3))
    na = np.bincount(lab, minlength=s).astype(float)
    pairs = na[:, None] * (na[None, :] - np.eye(s))
    with np.errstate(divide="ignore", invalid="ignore"):
        g = counts.reshape(s, s, bins) / (f * pairs[:, :, None] / float(np.prod(L)) * shell[None, None, :])
    return 0.5 * (edges[1:] + edges[:-1]), np.nan_to_num(g)


def species_temperatures(velocities, labels: Sequence[int], masses: Optional[Sequence[float]] = None) -> np.ndarray:
    """Each species' kinetic temperature m <|v|^2> / d over the frames' velocities ((F, n, d) or
    (n, d)); ``masses`` per species (default 1)."""
    v = np.asarray(velocities, dtype=float)
    v = v[None] if v.ndim == 2 else v
    lab = np.asarray(labels)
    s = int(lab.max()) + 1
    m = np.ones(s) if masses is None else np.asarray(masses, dtype=float)
    v2 = np.einsum("fnk,fnk->n", v, v) / v.shape[0]
    return m * np.bincount(lab, weights=v2, minlength=s) / (np.bincount(lab, minlength=s) * v.shape[2])


def pair_collision_counts(trace, labels: Sequence[int]) -> np.ndarray:
    """Collisions per species pair (S x S, symmetric; a pair of one species on the diagonal)
    from a trace of (tick, i, j) rows (``LatticeEngine.take_trace``)."""
    t = np.asarray(trace, dtype=np.int64).reshape(-1, 3)
    lab = np.asarray(labels)
    s = int(lab.max()) + 1
    a, b = lab[t[:, 1]], lab[t[:, 2]]
    c = np.bincount(np.minimum(a, b) * s + np.maximum(a, b), minlength=s * s).reshape(s, s)
    return c + c.T - np.diag(np.diag(c))


def contact_from_rates(counts, labels: Sequence[int], sizes: Sequence[float], volume: float, duration: float,
                       temperature: float, dim: int) -> np.ndarray:
    """g_ab(sigma_ab+) from the collision counts of an equilibrium run of ``duration`` (equal unit
    masses, kT = ``temperature``): the rate of a-b collisions per volume is n_a n_b (1/2 if a = b)
    g_ab K sigma_ab^(d-1) sqrt(pi kT), K = 2 (disks), 4 (spheres) (Enskog's collision rate with
    the pair's own contact value; exact at equilibrium for any collision rule that keeps it)."""
    lab = np.asarray(labels)
    n = np.bincount(lab).astype(float) / volume
    sz = np.asarray(sizes, dtype=float)
    sab = 0.5 * (sz[:, None] + sz[None, :])
    k = {2: 2.0, 3: 4.0}[dim]
    per = np.outer(n, n) * np.where(np.eye(len(sz), dtype=bool), 0.5, 1.0) * k * sab ** (dim - 1) * math.sqrt(math.pi * temperature)
    return np.asarray(counts, dtype=float) / (volume * duration) / per

