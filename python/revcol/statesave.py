"""One run of the paper's state-saving study in this process (:func:`run`), the bytes a
variant would save (:func:`projected_bytes`), and the argument checks every run shares.

The model, the variants and the maths are in the study, :mod:`revcol.studies.statesave`, and
the C++ header ``revcol/studies/statesave.hpp``; the study (many runs, each in a fresh process, the
table and the figure) builds on this module, which the library (scene checks) uses too.

    >>> r = run(1000, 200, variant="rc")
    >>> r["restored"], r["max_rel_error"] < 1e-9, r["draws"] == 3 * 200
    (True, True, True)
"""
from __future__ import annotations

import math
from typing import Any

from . import _core

__all__ = ["run", "projected_bytes", "variants", "MODES"]

#: operator modes of the study
MODES = ("exact", "paper")
_GIB = 1 << 30
_MAX_PARTICLES = 1 << 26
_MAX_COLLISIONS = 1 << 32
_LABEL = {"ss1": "SS1", "ss2": "SS2", "ssp": "SS-pair", "rc": "RC"}


def _gib(b: float) -> str:
    return f"{b / _GIB:.1f} GiB"


# --- validation --------------------------------------------------------------------------

def _int(value: Any, name: str, lo: int, hi: int | None = None) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or value != int(value):
        raise ValueError(f"{name} must be an integer, got {value!r}")
    v = int(value)
    if v < lo or (hi is not None and v > hi):
        bound = f"[{lo}, {hi}]" if hi is not None else f">= {lo}"
        raise ValueError(f"{name} must be {bound}, got {v}")
    return v


def _budget_bytes(budget_gib: Any) -> int:
    if isinstance(budget_gib, bool) or not isinstance(budget_gib, (int, float)) \
            or not math.isfinite(budget_gib) or budget_gib <= 0:
        raise ValueError(f"budget_gib must be a positive number of GiB, got {budget_gib!r}")
    return int(budget_gib * _GIB)


def _supported(lazy: bool) -> tuple[str, ...]:
    return tuple(_core.statesave_variants("lazy" if lazy else "eager"))


def variants(lazy: bool = False) -> tuple[str, ...]:
    """The variants a transport supports, in report order (eager: ss1 ss2 rc; lazy adds ssp)."""
    return _supported(lazy)


def _kwargs(particles, collisions, variant, lazy, mode, law, rng, seed, mean_dt, grazing_tol,
            budget_gib, prefault, bits=40) -> dict:
    if mode not in MODES:
        raise ValueError(f"mode must be 'exact' or 'paper', got {mode!r}")
    if variant not in _supported(lazy):
        need = " (ssp needs lazy=True)" if variant == "ssp" else ""
        raise ValueError(f"variant must be one of {', '.join(_supported(lazy))}, got {variant!r}{need}")
    return dict(particles=_int(particles, "particles", 2, _MAX_PARTICLES),
                collisions=_int(collisions, "collisions", 1, _MAX_COLLISIONS), variant=variant,
                transport="lazy" if lazy else "eager", mode=mode, law=law, bits=_int(bits, "bits", 8, 52),
                rng=rng, seed=_int(seed, "seed", 0, 2**32 - 1), mean_dt=float(mean_dt),
                grazing_tol=float(grazing_tol), budget_bytes=_budget_bytes(budget_gib),
                prefault=bool(prefault))


# --- one run -------------------------------------------------------------------------------

def run(particles: int, collisions: int = 1000, *, variant: str = "rc", lazy: bool = False,
        mode: str = "exact", law: str = "flux", rng: str = "clcg4", seed: int = 0,
        mean_dt: float = 1e-5, grazing_tol: float = 1e-11, budget_gib: float = 8.0,
        prefault: bool = True, capture: bool = False) -> dict:
    """One run in this process: N_c steps forward, roll back, compare with the start.

    Returns a dict: ``forward_s``, ``rollback_s``, ``bytes_saved`` (counted: the records, or
    for ``rc`` its logs), ``projected_bytes``, ``peak_rss_bytes`` (this *process's* VmHWM),
    ``max_rel_error`` (max of |x - x_0| / box and |v - v_0| / max|v_0|), ``restored`` (state
    saving: bit for bit; rc: within 1e-9; both: generator and clock back, logs empty),
    ``draws`` / ``draws_undone`` (3 per step), ``skipped`` (over the budget: not run), and
    with ``capture`` the (N, 4) arrays ``start``, ``turn`` and ``end`` (x, y, vx, vy;
    positions at the snapshot's time). Bad arguments raise ValueError naming the problem.
    """
    kw = _kwargs(particles, collisions, variant, lazy, mode, law, rng, seed, mean_dt,
                 grazing_tol, budget_gib, prefault)
    return _core.statesave_run(capture=bool(capture), **kw)


def projected_bytes(particles: int, collisions: int = 1000, *, variant: str = "ss1",
                    lazy: bool = False, **kw: Any) -> int:
    """Bytes the variant saves over a run (rc: 0; its logs are counted when it runs)."""
    args = dict(mode="exact", law="flux", rng="clcg4", seed=0, mean_dt=1e-5, grazing_tol=1e-11,
                budget_gib=8.0, prefault=True)
    args.update(kw)
    return int(_core.statesave_projected_bytes(
        **_kwargs(particles, collisions, variant, lazy, **args))["projected_bytes"])
