"""The round-trip bar and errors: how far a run that went forward and back is from its start.

- ``error_x`` = max over particles and axes of |x - x0| / L_axis (periodic images folded);
- ``error_v`` = max over particles of |v - v0| / max over particles of |v0| (Euclidean norms);
- a round trip passes when both are <= :data:`BAR` = 1e-9 (the paper's bar).

    >>> round_trip_errors([[0.5]], [[1.0]], [[0.5]], [[1.0]], [2.0], [True])
    (0.0, 0.0)
"""
from __future__ import annotations

import numpy as np

__all__ = ["BAR", "ERROR_DEFINITIONS", "round_trip_errors", "geometry", "divergence_text"]

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
