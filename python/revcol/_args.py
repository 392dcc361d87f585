"""Argument checks of the Python wrappers, with messages that name the argument (issue 17).

The compiled module names its own scalar arguments (``cpp/bindings/args.hpp``); these are for
wrappers that compute with an argument before it reaches C++ (``collisions - done``,
``time / tick``). ``bool`` is refused as an integer: ``run(collisions=True)`` is a mistake.
"""
from __future__ import annotations

import math
import operator
import warnings
from typing import Optional

import numpy as np


def integer(x, name: str, lo: Optional[int] = None, hi: Optional[int] = None) -> int:
    """``x`` as an int (anything with ``__index__`` but bool); TypeError / ValueError naming ``name``."""
    if isinstance(x, bool):
        raise TypeError(f"{name} must be an integer, got bool")
    try:
        v = operator.index(x)
    except TypeError:
        hint = f" ({x!r}; write int(...) or 1_000_000)" if isinstance(x, float) else ""
        raise TypeError(f"{name} must be an integer, got {type(x).__name__}{hint}") from None
    if (lo is not None and v < lo) or (hi is not None and v > hi):
        raise ValueError(f"{name} = {v} is outside [{'-inf' if lo is None else lo}, {'inf' if hi is None else hi}]")
    return v


def real(x, name: str, *, finite: bool = True) -> float:
    """``x`` as a float (a real number, not a string or bool); TypeError / ValueError naming ``name``."""
    if isinstance(x, (bool, str, bytes)):
        raise TypeError(f"{name} must be a real number, got {type(x).__name__}")
    try:
        v = float(x)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be a real number, got {type(x).__name__}") from None
    if finite and not math.isfinite(v):
        raise ValueError(f"{name} must be finite, got {v}")
    return v


def name(x, what: str) -> str:
    """``x`` as a str; TypeError naming ``what`` otherwise."""
    if not isinstance(x, str):
        raise TypeError(f"{what} must be a string, got {type(x).__name__}")
    return x


def names(x, what: str) -> list:
    """One name or a list/tuple of names, as a list; TypeError naming ``what`` otherwise."""
    if isinstance(x, str):
        return [x]
    if isinstance(x, (list, tuple)) and all(isinstance(b, str) for b in x):
        return list(x)
    raise TypeError(f"{what} must be a name or a list of names (one per axis), got {x!r}")


def packing_fraction(phi, packing_fraction, default: float = 0.3):
    """The packing fraction given as ``phi`` or as ``packing_fraction`` (the scenes' name), not
    both; ``default`` when neither. The value itself is checked by the engine's limits."""
    if phi is not None and packing_fraction is not None:
        raise TypeError("give the packing fraction once: phi= or packing_fraction=, not both")
    v = phi if phi is not None else packing_fraction
    return default if v is None else v


def real_array(a, name: str) -> np.ndarray:
    """``a`` as a float64 array; a TypeError naming ``name`` when it is not one (complex numbers
    included: converting them would drop the imaginary part)."""
    if np.iscomplexobj(a):
        raise TypeError(f"{name} must be an array of real numbers, got complex values")
    try:
        return np.asarray(a, dtype=float)
    except (TypeError, ValueError) as e:
        raise TypeError(f"{name} must be an array of real numbers ({e})") from None


def placement(init, stacklevel: int = 3) -> str:
    """A random start's placement, ``init``: ``"auto"``, ``"rsa"`` (random sequential addition),
    ``"crystal"`` (a jittered crystal: square in 1D/2D, face-centred cubic in 3D) or ``"relax"``
    (uniform at random, the overlaps then relaxed away: dense amorphous starts). The old
    name ``"lattice"`` (the word names the integer engine now) gives ``"crystal"`` with a
    DeprecationWarning; any other name is passed on for the engine to refuse by name."""
    init = name(init, "init")
    if init == "lattice":
        warnings.warn("init='lattice' is deprecated, write init='crystal' (the jittered crystal start; "
                      "'lattice' names the integer engine)", DeprecationWarning, stacklevel=stacklevel)
        return "crystal"
    return init


#: a size's suffixes: powers of 1024, as coreutils reads ``20G`` (``KiB`` ... ``TiB`` the same)
SIZE_UNITS = {"": 1, "k": 1 << 10, "m": 1 << 20, "g": 1 << 30, "t": 1 << 40}


def size(x, what: str) -> int:
    """A size in bytes: an integer >= 0, or a string: a number with an optional suffix K, M, G or T
    (powers of 1024; ``KiB``, ``MiB``, ``GiB``, ``TiB`` the same; ``20G``, ``1.5T``), or ``"none"``.
    0 and ``"none"`` give 0, which callers read as "no limit". ValueError naming ``what`` otherwise."""
    if isinstance(x, bool) or not isinstance(x, (int, str)):
        raise ValueError(f"{what} must be a size in bytes (an integer, or a string such as '20G'), got {x!r}")
    if isinstance(x, int):
        if x < 0:
            raise ValueError(f"{what} must be a size >= 0 bytes (0: no limit), got {x}")
        return x
    text = x.strip().lower()
    if text == "none":
        return 0
    for unit in ("ib", "i"):  # KiB, Ki: the same as K
        if text.endswith(unit) and text[-len(unit) - 1:-len(unit)] in "kmgt" and len(text) > len(unit) + 1:
            text = text[:-len(unit)]
            break
    number, unit = (text[:-1], text[-1]) if text[-1:] in "kmgt" and text[-1:] else (text, "")
    try:
        v = float(number)
    except ValueError:
        v = math.nan
    if not (math.isfinite(v) and v >= 0) or "_" in number:
        raise ValueError(f"{what} must be a size: bytes, or a number with K, M, G or T (powers of 1024; e.g. "
                         f"'20G'), or 0 or 'none' for no limit; got {x!r}")
    return int(round(v * SIZE_UNITS[unit]))


def masses_arg(masses, n: int) -> list:
    """The per-particle masses as the binding takes them ([] for unit masses)."""
    if masses is None:
        return []
    m = real_array(masses, "masses")
    if m.ndim != 1 or m.size != n:
        raise ValueError(f"masses must have one entry per particle ({n}), got shape {m.shape}")
    if not (np.isfinite(m).all() and (m > 0).all()):
        raise ValueError("masses must be finite and > 0")
    return [float(a) for a in m]


def diameters_arg(diameters, n: int, diameter: float) -> list:
    """The per-particle diameters as the binding takes them ([] for one diameter)."""
    if diameters is None:
        return []
    if diameter != 1.0:
        raise ValueError("give diameter (one for all) or diameters (one per particle), not both")
    d = real_array(diameters, "diameters")
    if d.ndim != 1 or d.size != n:
        raise ValueError(f"diameters must have one entry per particle ({n}), got shape {d.shape}")
    if not (np.isfinite(d).all() and (d > 0).all()):
        raise ValueError("diameters must be finite and > 0")
    return [float(a) for a in d]
