"""The studies a sweep runs without a scene: the randomness battery (one point: one stream
configuration through dieharder, :func:`revcol.studies.randomness.battery`) and the equilibrium study's
dense gas (one point: one dimension x packing fraction x law x N, :func:`revcol.studies.equilibrium.dense`).

Each parameter has a default and a check; a point's parameters are checked before anything runs
(ValueError naming the parameter and what is allowed), and the point's report is the study
function's dict with ``kind`` added. The study modules are imported where a check or a point
needs them, not with this module: ``import revcol`` imports ``revcol.sweep``, and the studies
load only when a sweep names them.
"""
from __future__ import annotations

import math
from typing import Any, Callable

from ..scene import LIMITS

__all__ = ["SCENELESS", "defaults", "check", "run", "memory"]


def _int(lo: int, hi: int | None = None) -> Callable[[Any], str | None]:
    def ok(v: Any) -> str | None:
        if isinstance(v, bool) or not isinstance(v, int) or v < lo or (hi is not None and v > hi):
            return f"an integer {lo}..{hi if hi is not None else 'inf'}"
        return None
    return ok


def _real(lo: float, hi: float) -> Callable[[Any], str | None]:
    def ok(v: Any) -> str | None:
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or not lo < v < hi:
            return f"a number in ({lo:g}, {hi:g})"
        return None
    return ok


def _one_of(*names: str) -> Callable[[Any], str | None]:
    return lambda v: None if v in names else "one of " + ", ".join(map(repr, names))


def _tests(v: Any) -> str | None:
    from ..studies.randomness import PAPER_TESTS

    if not isinstance(v, list) or not v or any(isinstance(t, bool) or t not in PAPER_TESTS for t in v):
        return f"a non-empty list of dieharder test numbers among {sorted(PAPER_TESTS)}"
    return None


def _case(v: Any) -> str | None:
    from ..studies.words import stream_cases

    cases = sorted(set(stream_cases("exact")) | set(stream_cases("paper")))
    return None if v in cases else "a word-stream case: " + ", ".join(cases)


#: study -> parameter -> (default, check); a check returns None or what is allowed
SCENELESS: dict[str, dict[str, tuple[Any, Callable[[Any], str | None]]]] = {
    "randomness": {"case": ("pair2d", _case), "mode": ("exact", _one_of("exact", "paper")),
                   "law": ("flux", _one_of("flux", "uniform")),
                   "rng": ("philox", _one_of("clcg4", "philox", "randu", "philox-repeat100")),
                   "seed": (0, _int(0, 2**32 - 1)), "words": (3_000_000, _int(1000, 2**31)),
                   "tests": ([15, 12, 10], _tests)},
    "equilibrium": {"dimension": (2, _int(2, 3)), "packing_fraction": (0.3, _real(0.0, 0.75)),
                    "law": ("flux", _one_of("flux", "uniform", "specular", "paper")),
                    "particles": (1000, _int(16, 10**6)), "per_particle": (2000.0, _real(0.0, 1e7)),
                    "seed": (1, _int(0, 2**32 - 1))},
}


def defaults(study: str) -> dict[str, Any]:
    """The study's parameters at their defaults."""
    return {k: v[0] for k, v in SCENELESS[study].items()}


def check(study: str, params: dict[str, Any]) -> None:
    """ValueError naming the first parameter that is unknown or out of range."""
    spec = SCENELESS[study]
    for k, v in params.items():
        if k not in spec:
            raise ValueError(f"parameter {k!r}: unknown for study {study!r}; allowed: {', '.join(spec)}")
        bad = spec[k][1](v)
        if bad is not None:
            raise ValueError(f"parameter {k!r}: must be {bad}, got {v!r}")
    if study == "equilibrium":
        d, phi = params.get("dimension", 2), params.get("packing_fraction", 0.3)
        if phi > LIMITS["max_fraction"][d]:
            raise ValueError(f"parameter 'packing_fraction': at most {LIMITS['max_fraction'][d]} in {d}D "
                             f"(the engine's limit), got {phi!r}")


def memory(study: str, params: dict[str, Any]) -> int:
    """Bytes a point needs besides the interpreter: the dense gas's engine (1 KiB a particle);
    the battery streams its words to a file, not memory."""
    return 1024 * int(params["particles"]) if study == "equilibrium" else 0


def run(study: str, params: dict[str, Any]) -> dict:
    """Runs one point; its report (the study function's dict, ``kind`` added)."""
    if study == "randomness":
        from ..studies.randomness import battery, has_dieharder

        if not has_dieharder():
            raise RuntimeError("the randomness battery needs the dieharder program on every worker "
                               "(apt-get install dieharder)")
        config = {k: params[k] for k in ("case", "mode", "law", "rng", "seed")}
        r = battery(config, params["words"], tuple(params["tests"]))
        return {"kind": "randomness", **r}
    from ..studies.equilibrium import dense

    r = dense(params["dimension"], float(params["packing_fraction"]), params["law"], n=params["particles"],
              per_particle=float(params["per_particle"]), seed=params["seed"])
    return {"kind": "equilibrium", **r}
