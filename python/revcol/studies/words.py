"""The randomness study's word streams: post-collision chart coordinates of an operator (or of a
gas on the float engine) as 32-bit words, which the dieharder battery
(:mod:`revcol.studies.randomness`) and the coverage figures (:mod:`revcol.studies.coverage`)
both read.

    >>> w = stream("pair2d", mode="exact", law="flux", rng="philox").words(4)
    >>> w.dtype.name, len(w)
    ('uint32', 4)
"""
from __future__ import annotations

import os
import time
from typing import Any, Optional

from .. import _core

__all__ = ["GAS_PARTICLES", "GAS_FRACTION", "GAS_WARMUP", "stream", "stream_cases", "write_words"]



#: the gas streams' defaults: particles, packing fraction, warm-up collisions per particle
GAS_PARTICLES, GAS_FRACTION, GAS_WARMUP = 1000, 0.2, 5.0


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
