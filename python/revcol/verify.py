"""The paper's reversal illustrations as a self-check.

``verify(case="pair2d", collisions=N, mode=..., law=..., rng=..., seed=...)`` runs N_c
collisions of one pair with momentum and energy computed once and held, negating the
velocities after each collision (the paper's Procedure "Reversal Illustration for
2-Particle Collisions in 2 Dimensions", contact geometry r21 = (1, 1)), then reverses all of
them with the generator stepping back, and compares with the start:

- ``max_rel_error`` = max |v_end - v_0| / max |v_0|; the paper's bar is 1e-9;
- ``bit_exact``: exact mode returns the *quantized* start (its chart cell decoded at the
  centre) bit for bit; paper mode is compared with the start itself;
- ``passed``: generator restored, log empty, error <= 1e-9, and bit_exact where promised.

Case "pair3d-fast" (exact mode) is the same illustration in 3D for the engine's closed-form
operator (Pair3DExact, normal (1, 1, 1), 2 draws per collision); exact mode's "pair3d" runs
the general operator on the same geometry.

    >>> import revcol
    >>> r = revcol.verify(case="pair2d", collisions=1000)
    >>> r["passed"], r["bit_exact"]
    (True, True)
"""
from __future__ import annotations

from typing import Sequence

from . import _core

__all__ = ["verify", "verify_cases", "VERIFY_CASES"]


def verify_cases(mode: str = "exact") -> tuple[str, ...]:
    """The case names :func:`verify` knows for a mode ("exact" or "paper")."""
    return tuple(_core.verify_cases(mode))


#: every case name, either mode
VERIFY_CASES = tuple(dict.fromkeys(verify_cases("exact") + verify_cases("paper")))


def verify(case: str = "pair2d", *, collisions: int = 1_000_000, mode: str = "exact",
           law: str = "flux", rng: str = "clcg4", seed: int = 0, bits: int = 40,
           printed_reverse: bool = False, velocities: Sequence[float] | None = None,
           normal: Sequence[float] | None = None) -> dict:
    """Run a reversal illustration and return its report (a dict; see the module doc)."""
    if mode not in ("exact", "paper"):
        raise ValueError(f"mode must be 'exact' or 'paper', got {mode!r}")
    if case not in verify_cases(mode):
        raise ValueError(f"unknown case {case!r} for mode {mode}; known: {', '.join(verify_cases(mode))}")
    if isinstance(collisions, bool) or int(collisions) != collisions or collisions < 1:
        raise ValueError(f"collisions must be a positive integer, got {collisions!r}")
    if isinstance(seed, bool) or int(seed) != seed or seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    return _core.verify(case=case, mode=mode, law=law, rng=rng, seed=int(seed),
                        collisions=int(collisions), bits=int(bits),
                        printed_reverse=bool(printed_reverse),
                        velocities=list(velocities or []), normal=list(normal or []))
