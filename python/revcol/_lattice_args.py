"""The lattice engine's keyword arguments checked and put as the binding takes them (a
ValueError naming each wrong one): boundaries, mode against law, tick_bits, the neighbour
search, a uniform field. :mod:`revcol.lattice` builds its simulations with them."""
from __future__ import annotations

from typing import Optional, Sequence, Union

import numpy as np

from ._args import integer, names, real, real_array

#: the lattice engine's modes: "exact" (the randomized pair operator, drawing its post direction
#: by ``law``) and "specular" (deterministic specular dynamics: no draws; docs/lattice.md)
MODES = ("exact", "specular")

_Boundary = Union[str, Sequence[str]]


def _boundary(boundary: _Boundary) -> list:
    """One boundary name or one per axis, as the binding takes them (the C++ parser,
    revcol/engine/boundary_kind.hpp, names a wrong one or a wrong count)."""
    return names(boundary, "boundary")


def _mode(mode, law) -> str:
    """``mode`` checked against ``law``: a ValueError naming ``mode`` unless it is one of
    :data:`MODES`, or naming ``law`` when specular mode is given a law other than the default
    (it draws no post direction, so no law applies)."""
    if not isinstance(mode, str) or mode not in MODES:
        raise ValueError(f"mode must be 'exact' or 'specular', got {mode!r}")
    if mode == "specular" and law != "flux":
        raise ValueError(f"law applies to mode='exact' only (specular mode draws nothing), got law={law!r}")
    return mode


def _tick(tick_bits: Optional[int]) -> int:
    """The binding's tick_bits: 0 asks for the automatic tick."""
    return 0 if tick_bits is None else integer(tick_bits, "tick_bits", 16, 26)


#: the neighbour searches by name, as the engine's list shell (BasicEngine::set_list_shell)
SEARCHES = {"auto": -1.0, "cells": 0.0}


def _shell(search: Union[str, float]) -> float:
    """The engine's list shell for ``search``: ``"auto"`` -1, ``"cells"`` 0, or a shell in
    diameters in [0.02, 2]; a ValueError naming ``search`` otherwise."""
    if isinstance(search, str):
        if search in SEARCHES:
            return SEARCHES[search]
        raise ValueError(f"search must be 'auto', 'cells' or a shell in diameters in [0.02, 2], got {search!r}")
    s = real(search, "search")
    if not 0.02 <= s <= 2.0:
        raise ValueError(f"search = {s!r} is outside [0.02, 2] (a shell in diameters; or 'auto', 'cells')")
    return s




def _gravity(gravity, dim: int, workers: int = 1) -> list:
    """A uniform field's components for the engine (empty: none). More than one worker cuts the box
    along axis 0 (set_parallel's default), which must then be another axis than the field's."""
    if gravity is None:
        return []
    g = np.atleast_1d(real_array(gravity, "gravity")).astype(float)
    if g.shape != (dim,):
        raise ValueError(f"gravity must have one component per axis ({dim}), got shape {g.shape}")
    if g[0] != 0.0 and integer(workers, "workers", 1) > 1:
        raise ValueError("gravity along axis 0 runs on one worker here: the parallel engine cuts the box across "
                         "the field, and its default slabs lie along axis 0 (set_parallel(axis=...) after building)")
    return g.tolist()


def _shear(shear_rate, workers: int = 1) -> float:
    """A Lees-Edwards shear rate for the engine (0: none); shear runs on one worker."""
    if shear_rate is None:
        return 0.0
    g = real(shear_rate, "shear_rate")
    if g != 0.0 and integer(workers, "workers", 1) > 1:
        raise ValueError("shear runs on one worker: the parallel lattice engine is not built for shear yet")
    return g
