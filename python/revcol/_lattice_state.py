"""The lattice simulation's state outside the class (revcol.lattice re-exports the public
names): parallel runs' reports added up, checkpoints read back as snapshots, and a snapshot's
neighbour search checked."""
from __future__ import annotations

import os
from typing import Optional, Union

import numpy as np

from ._io import read_checkpoint

__all__ = ["add_reports", "read_state", "snapshot_shell"]


def add_reports(a: Optional[dict], b: Optional[dict]) -> Optional[dict]:
    """Two parallel runs' reports (``run()["parallel"]``) as one: the counts summed, per LP
    too (runs on other K: the later's per-LP counts), ``stopped`` the later's."""
    if a is None or b is None:
        return dict(b if a is None else a) if (a, b) != (None, None) else None
    out = dict(a)
    for k, val in b.items():
        if k == "lp_events":
            mine, theirs = list(a[k]), list(val)
            out[k] = [x + y for x, y in zip(mine, theirs)] if len(mine) == len(theirs) else (theirs or mine)
        elif k == "stopped":
            out[k] = val
        else:
            out[k] = a[k] + val
    return out


def read_state(path: Union[str, os.PathLike]) -> dict:
    """A checkpoint written by ``save`` as a snapshot dict (nested ``a.b`` keys rebuilt)."""
    st: dict = {}
    for k, a in read_checkpoint(path, "lattice").items():
        val = a.item() if a.ndim == 0 else a
        if "." in k:
            outer, inner = k.split(".", 1)
            if isinstance(val, np.ndarray) and outer == "units":
                val = tuple(val.tolist())
            st.setdefault(outer, {})[inner] = val
        else:
            st[k] = val
    return st


def snapshot_shell(value) -> float:
    """A snapshot's ``search`` entry, checked: -1 (automatic; any negative), 0 (the cell grid)
    or a shell in [0.02, 2] diameters."""
    try:
        shell = float(np.asarray(value))
    except (TypeError, ValueError):
        raise ValueError(f"snapshot: search must be a number (the list shell), got {value!r:.40}") from None
    if shell < 0.0:
        return -1.0
    if not (shell == 0.0 or 0.02 <= shell <= 2.0):
        raise ValueError(f"snapshot: search = {shell!r} must be -1 (automatic), 0 (cells) or in [0.02, 2]")
    return shell
