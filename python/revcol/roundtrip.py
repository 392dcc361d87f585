"""The round-trip bar and errors: how far a run that went forward and back is from its start.

- ``error_x`` = max over particles and axes of |x - x0| / L_axis (periodic images folded);
- ``error_v`` = max over particles of |v - v0| / max over particles of |v0| (Euclidean norms);
- a round trip passes when both are <= :data:`BAR` = 1e-9 (the paper's bar).

    >>> round_trip_errors([[0.5]], [[1.0]], [[0.5]], [[1.0]], [2.0], [True])
    (0.0, 0.0)
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["BAR", "ERROR_DEFINITIONS", "round_trip_errors", "geometry", "divergence_text", "combine_seeds"]

#: the round-trip bar (the paper's): both errors must be at most this
BAR = 1e-9

ERROR_DEFINITIONS = {
    "error_x": "max over particles and axes of |x - x0| / L_axis (periodic images folded)",
    "error_v": "max over particles of |v - v0| / max over particles of |v0| (Euclidean norms)",
}


def round_trip_errors(x, v, x0, v0, box, periodic) -> tuple[float, float]:
    """(error_x, error_v) as defined in :data:`ERROR_DEFINITIONS`."""
    box = np.asarray(box, dtype=float)
    per = np.asarray(periodic, dtype=bool)
    dx = np.abs(np.asarray(x) - x0)
    dx[:, per] = np.minimum(dx[:, per], box[per] - dx[:, per])
    err_x = float((dx / box).max())
    err_v = float(np.linalg.norm(np.asarray(v) - v0, axis=1).max() / np.linalg.norm(v0, axis=1).max())
    return err_x, err_v


def geometry(sim) -> tuple[np.ndarray, np.ndarray]:
    """(box lengths, periodic flags) per axis of a :class:`revcol.Simulation`, the inputs of
    :func:`round_trip_errors`."""
    return np.asarray(sim.box, dtype=float)[: sim.dim], np.asarray(sim.periodic, dtype=bool)[: sim.dim]


def divergence_text(d: dict) -> str:
    """One line on what the collision trace found, from ``diagnostics()`` or a report's
    ``divergence`` / ``diverged_at`` / ``verified_at`` (docs/robustness.md).

    >>> divergence_text({"divergence": "collision sequence", "diverged_at": 4096, "verified_at": 8192})
    'at forward collision 4,096 (collision sequence; last verified at 8,192): the state run_back restores is not the forward run's'
    """
    where = f"at forward collision {d['diverged_at']:,} ({d['divergence']}"
    if d.get("verified_at") is not None:
        where += f"; last verified at {d['verified_at']:,}"
    return where + "): the state run_back restores is not the forward run's"



def combine_seeds(grid: list[int], n: int, per_seed: list[list[tuple[float, float]]]) -> tuple[list[dict], int]:
    """The horizon's table from each seed's (position, velocity) errors at the grid's N_c (a seed
    stops early once O(1)): per N_c the worst of the seeds (a stopped seed counts as infinite),
    the median of each seed's larger error and how many fail the bar; and the horizon, the
    largest N_c before the first that fails. ``revcol sweep`` combines its seeds with this too."""
    rows = []
    for k, nc in enumerate(grid):
        if all(k >= len(e) for e in per_seed):
            break
        ex = [e[k][0] if k < len(e) else math.inf for e in per_seed]
        ev = [e[k][1] if k < len(e) else math.inf for e in per_seed]
        worst = [max(a, b) for a, b in zip(ex, ev)]
        rows.append({"collisions": nc, "per_particle": 2.0 * nc / n, "error_x": max(ex), "error_v": max(ev),
                     "median": float(np.median(worst)), "fails": int(sum(w > BAR for w in worst)),
                     "seeds": len(per_seed)})
    h = 0
    for r in rows:
        if max(r["error_x"], r["error_v"]) > BAR:
            break
        h = r["collisions"]
    return rows, h
