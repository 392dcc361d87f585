"""The operators the stability suite stresses (:mod:`revcol.studies.stability`): every exact
case, the 2D pair (exact, both laws, and paper mode), the 1D pair and the paper's own
procedures, each wrapped as an :class:`Operator` with its forward, reverse, log and checks.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import partial
from typing import Any, Callable, Optional

import numpy as np

from ..collide import Collision, Pair1D, Pair2D, named_cases
from ..paper import Pair3DPaper, Triple1DPaper, Triple2DPaper, _contacts, paper_cases

__all__ = ["Operator", "operators", "OPERATORS", "EXACT_CASES", "PAPER_CASES"]



EXACT_CASES = ("pair3d", "triple1d", "triple2d-c1", "triple2d-c2", "triple2d-c3", "triple2d-c4",
               "chain4-1d", "chain4-2d", "chain4-3d", "triple3d-2", "triple3d-3", "cradle1d", "cradle2d")


PAPER_CASES = ("pair3d", "triple1d", "triple2d-c1", "triple2d-c2", "triple2d-c3", "triple2d-c4")


@dataclass
class Operator:
    """One operator under stress: its geometry, and forward / reverse / chart on (B, n, d)."""

    name: str
    case: str
    mode: str
    law: str
    n: int
    d: int
    contacts: list            # [(i, j)]; the normal of contact k points from j to i
    normals: np.ndarray       # (m, d)
    draws: int
    forward: Callable[[np.ndarray, np.ndarray], np.ndarray]
    reverse: Callable[[np.ndarray, np.ndarray], np.ndarray]
    chart: Optional[Callable[[np.ndarray], np.ndarray]]   # post -> coordinates uniform under the law
    pushed: Callable[[], int]
    logged: Callable[[], int]
    options: dict = field(default_factory=dict)
    quantize: Optional[Callable[[np.ndarray], np.ndarray]] = None   # exact mode: the pre state's cell centre
    clear: Callable[[], None] = lambda: None   # empty the rare log (between parameter values)


def _normals(positions: np.ndarray, contacts) -> np.ndarray:
    x = np.asarray(positions, float)
    x = x.reshape(len(x), -1)
    out = [(x[i] - x[j]) / np.linalg.norm(x[i] - x[j]) for (i, j) in contacts]
    return np.array(out)


def _named(case: str) -> dict:
    return next(c for c in named_cases() if c["name"] == case)


def _log(op) -> tuple[Callable[[], int], Callable[[], int]]:
    return (lambda: int(op.log_pushed)), (lambda: int(op.log_size))


def _with_clear(o: Operator, op) -> Operator:
    o.clear = op.clear_log
    return o


def _exact(case: str, law: str) -> Operator:
    c = _named(case)
    op = Collision.named(case, law=law)
    pushed, logged = _log(op)
    return _with_clear(Operator(f"{case}/exact/{law}", case, "exact", law, c["n"], c["d"], list(c["contacts"]),
                    _normals(c["positions"], c["contacts"]), op.draws,
                    lambda v, g: op.forward(v, g=g), lambda v, g: op.reverse(v, g=g), op.chart,
                    pushed, logged, quantize=op.quantize), op)


def _pair2d(mode: str, law: str) -> Operator:
    c = _named("pair2d")
    normal = _normals(c["positions"], c["contacts"])
    op = Pair2D(mode=mode, law=law)
    ref = op if mode == "exact" else Pair2D(law="uniform")
    pushed, logged = _log(op)
    name = f"pair2d/{mode}/{law}" if mode == "exact" else "pair2d/paper"
    return _with_clear(Operator(name, "pair2d", mode, law if mode == "exact" else "uniform", 2, 2, [(0, 1)], normal, 1,
                    lambda v, g: op.forward(v, normal[0], g=g[:, 0]),
                    lambda v, g: op.reverse(v, normal[0], g=g[:, 0]),
                    lambda v: ref.chart(v, normal[0]).reshape(len(v), -1), pushed, logged,
                    quantize=(lambda v: op.quantize(v, normal[0])) if mode == "exact" else None), op)


def _pair1d() -> Operator:
    c = _named("pair1d")
    normal = _normals(c["positions"], c["contacts"])
    op = Pair1D()
    return Operator("pair1d", "pair1d", "exact", "-", 2, 1, [(0, 1)], normal, 0,
                    lambda v, g: op.forward(v[:, :, 0], normal[0]).reshape(v.shape),
                    lambda v, g: op.reverse(v[:, :, 0], normal[0]).reshape(v.shape),
                    None, lambda: 0, lambda: 0)


def _paper(case: str, cos_tol: float = 1e-8) -> Operator:
    """The paper's operator of a case; the 1D triple with the table arc length (the forward
    and the reverse use the same psi, so the method changes no round trip; it is the fast one)."""
    c = paper_cases()[case]
    geo = c["geometry"]
    con = _contacts(case, geo)
    contacts = [(i, j) for (i, j, _) in con]
    normals = np.array([r for (_, _, r) in con])
    ref = Collision(c["n"], c["d"], contacts, normals=normals, law="uniform")
    opts: dict = {}
    op: Any
    if case == "pair3d":
        op = Pair3DPaper()
        fwd = lambda v, g: op.forward(v, geo, g=g)  # noqa: E731
        rev = lambda v, g: op.reverse(v, geo, g=g)  # noqa: E731
    elif case == "triple1d":
        op = Triple1DPaper(arc="table", cos_tol=cos_tol)
        opts = {"arc": "table", "cos_tol": cos_tol}
        fwd = lambda v, g: op.forward(v[:, :, 0], geo, g=g[:, 0])[:, :, None]  # noqa: E731
        rev = lambda v, g: op.reverse(v[:, :, 0], geo, g=g[:, 0])[:, :, None]  # noqa: E731
    else:
        op = Triple2DPaper()
        fwd = lambda v, g: op.forward(v, geo, g=g)  # noqa: E731
        rev = lambda v, g: op.reverse(v, geo, g=g)  # noqa: E731
    chart = None if case.startswith("triple2d") else ref.chart
    name = f"{case}/paper" + ("" if cos_tol == 1e-8 else f"/cos_tol={cos_tol:g}")
    pushed, logged = _log(op)
    return _with_clear(Operator(name, case, "paper", "uniform", c["n"], c["d"], contacts, normals,
                                type(op).draws, fwd, rev, chart, pushed, logged, opts), op)


def operators() -> dict[str, Callable[[], Operator]]:
    """Every operator of the suite by name, as a constructor."""
    out: dict[str, Callable[[], Operator]] = {"pair1d": _pair1d}
    for law in ("flux", "uniform"):
        out[f"pair2d/exact/{law}"] = partial(_pair2d, "exact", law)
    out["pair2d/paper"] = partial(_pair2d, "paper", "uniform")
    for case in EXACT_CASES:
        for law in ("flux", "uniform"):
            out[f"{case}/exact/{law}"] = partial(_exact, case, law)
    for case in PAPER_CASES:
        out[f"{case}/paper"] = partial(_paper, case)
    out["triple1d/paper/cos_tol=0"] = partial(_paper, "triple1d", 0.0)
    return out


#: the operator names, in report order
OPERATORS = tuple(operators())
