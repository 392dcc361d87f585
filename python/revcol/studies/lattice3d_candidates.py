"""The cube-sphere candidate of issue 14's design study, measured geometrically.

The 3D lattice operator needs a direction chart whose cells a whole-cell move maps onto cells,
so that a direction keeps its offset in its cell and the reverse reads the same cell back
(docs/lattice.md "3D: the direction chart"). A cube-sphere chart cuts each cube face into N x N
cells of equal gnomonic angle, (alpha, beta) = (atan(x / z), atan(y / z)) on the +z face. A cell
is moved onto another by a rotation; the cells are not congruent, so part of a cell lands
outside the target cell, and every such draw is a forward refusal (a redraw and a rare-log
entry). This script measures that fraction, which no lattice resolution changes: it is
geometry. Two maps are tried for each (pre cell, post cell) pair, the pairs drawn as a gas
draws them (both cells from the flux law, density cos(theta) about the normal +z, restricted
to the top face):
  * "minimal": the rotation about centre(pre) x centre(post) taking one centre onto the other;
  * "axes": a rotation about y by the alpha difference, then about x by the beta difference
    (two plane rotations, each exact as a lifting on the lattice: the per-face lifting map).
Points are uniform on the sphere inside the pre cell; the result is the fraction mapped outside
the post cell (the redraw probability per draw), with its binomial standard error.

    python -m revcol.studies.lattice3d_candidates --json bench/results/lattice3d_candidates.json
"""
from __future__ import annotations

import argparse
import json
import math
import time

import numpy as np

from .._io import atomic_open


def cell_of(v: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Top-face cell indices (i, j) of unit vectors v (rows) and whether v is on the top face."""
    z = v[:, 2]
    on = (z > 0) & (np.abs(v[:, 0]) <= z) & (np.abs(v[:, 1]) <= z)
    a = np.arctan2(v[:, 0], z)
    b = np.arctan2(v[:, 1], z)
    i = np.floor((a + math.pi / 4) / (math.pi / 2) * n).astype(np.int64)
    j = np.floor((b + math.pi / 4) / (math.pi / 2) * n).astype(np.int64)
    return i, j, on


def centre(i: int, j: int, n: int) -> np.ndarray:
    a = -math.pi / 4 + (i + 0.5) * (math.pi / 2) / n
    b = -math.pi / 4 + (j + 0.5) * (math.pi / 2) / n
    v = np.array([math.tan(a), math.tan(b), 1.0])
    return v / np.linalg.norm(v)


def rot_axis(axis: np.ndarray, ang: float) -> np.ndarray:
    k = axis / np.linalg.norm(axis)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(ang) * kx + (1 - math.cos(ang)) * kx @ kx


def rot_y(t: float) -> np.ndarray:  # rotates (z, x): alpha = atan(x / z) grows by t on the y = 0 circle
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rot_x(t: float) -> np.ndarray:  # beta = atan(y / z) grows by t on the x = 0 circle
    c, s = math.cos(t), math.sin(t)
    return np.array([[1, 0, 0], [0, c, s], [0, -s, c]])


def flux_cell(rng: np.random.Generator, n: int) -> tuple[int, int]:
    """A top-face cell drawn from the flux law about +z (sin^2 theta uniform, phi uniform)."""
    while True:
        s2 = rng.random()
        st, ct = math.sqrt(s2), math.sqrt(1 - s2)
        ph = 2 * math.pi * rng.random()
        v = np.array([[st * math.cos(ph), st * math.sin(ph), ct]])
        i, j, on = cell_of(v, n)
        if on[0]:
            return int(i[0]), int(j[0])


def points_in(rng: np.random.Generator, i: int, j: int, n: int, k: int) -> np.ndarray:
    """k points uniform on the sphere inside top-face cell (i, j) (rejection from its bounding cap)."""
    c = centre(i, j, n)
    rad = 2.5 * (math.pi / 2) / n  # the cell lies within this angle of its centre
    out = []
    e1 = np.cross(c, [1.0, 0, 0]) if abs(c[0]) < 0.9 else np.cross(c, [0, 1.0, 0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(c, e1)
    while sum(len(o) for o in out) < k:
        m = 4 * k
        cz = 1 - rng.random(m) * (1 - math.cos(rad))  # uniform on the cap
        sz = np.sqrt(1 - cz * cz)
        ph = 2 * math.pi * rng.random(m)
        v = np.outer(cz, c) + np.outer(sz * np.cos(ph), e1) + np.outer(sz * np.sin(ph), e2)
        ii, jj, on = cell_of(v, n)
        out.append(v[on & (ii == i) & (jj == j)])
    return np.concatenate(out)[:k]


def measure(n: int, pairs: int, k: int, seed: int) -> dict:
    rng = np.random.default_rng(seed)
    miss = {"minimal": 0, "axes": 0}
    total = 0
    for _ in range(pairs):
        (i, j), (i2, j2) = flux_cell(rng, n), flux_cell(rng, n)
        pts = points_in(rng, i, j, n, k)
        c, c2 = centre(i, j, n), centre(i2, j2, n)
        ax = np.cross(c, c2)
        ang = math.asin(min(1.0, np.linalg.norm(ax)))
        r_min = rot_axis(ax, ang) if np.linalg.norm(ax) > 1e-15 else np.eye(3)
        da = (i2 - i) * (math.pi / 2) / n
        db = (j2 - j) * (math.pi / 2) / n
        r_axes = rot_x(db) @ rot_y(da)
        for name, r in (("minimal", r_min), ("axes", r_axes)):
            v = pts @ r.T
            ii, jj, on = cell_of(v, n)
            miss[name] += int(np.sum(~(on & (ii == i2) & (jj == j2))))
        total += len(pts)
    out = {"n_per_face_edge": n, "pairs": pairs, "points_per_pair": k}
    for name, m in miss.items():
        p = m / total
        out[f"{name}_redraw_fraction"] = p
        out[f"{name}_redraw_se"] = math.sqrt(p * (1 - p) / total)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, nargs="+", default=[16, 64, 256], help="cells per cube-face edge")
    ap.add_argument("--pairs", type=int, default=400, help="(pre, post) cell pairs per N")
    ap.add_argument("--points", type=int, default=500, help="points per pre cell")
    ap.add_argument("--seed", type=int, default=14)
    ap.add_argument("--json", help="write the results here (atomically)")
    a = ap.parse_args()
    t0 = time.time()
    rows = [measure(n, a.pairs, a.points, a.seed + n) for n in a.n]
    for r in rows:
        print(f"N = {r['n_per_face_edge']:4d}: redraw per draw, minimal rotation {r['minimal_redraw_fraction']:.4f} "
              f"+- {r['minimal_redraw_se']:.4f}; per-face axis rotations {r['axes_redraw_fraction']:.4f} +- {r['axes_redraw_se']:.4f}")
    doc = {"command": "python -m revcol.studies.lattice3d_candidates " + " ".join(
        ["--n"] + [str(n) for n in a.n] + ["--pairs", str(a.pairs), "--points", str(a.points), "--seed", str(a.seed)]),
        "seconds": time.time() - t0, "rows": rows}
    if a.json:
        with atomic_open(a.json) as f:
            json.dump(doc, f, indent=1)


if __name__ == "__main__":
    main()
