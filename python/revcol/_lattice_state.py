"""The lattice simulation's state outside the class (revcol.lattice re-exports the public
names): parallel runs' reports added up, checkpoints read back as snapshots, and a snapshot's
neighbour search checked."""
from __future__ import annotations

import os
from typing import Optional, Union

import numpy as np

from . import _core
from ._io import read_checkpoint

__all__ = ["add_reports", "read_state", "snapshot_shell", "legacy_snapshot"]


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


#: what a checkpoint of an older revcol kept whole: its physical state and settings
_LEGACY_KEPT = ("engine", "dim", "units", "law", "mode", "seed", "clock", "x", "v", "streams", "energy0", "momentum0",
                "quantization", "search")


def legacy_snapshot(source: Union[str, os.PathLike, dict]) -> dict:
    """The snapshot revcol.lattice.restart_from_legacy starts from (see there)."""
    st = dict(source) if isinstance(source, dict) else read_state(source)
    if "log_index" not in st:
        raise ValueError("restart_from_legacy: this checkpoint is of the current layout: load it with LatticeSimulation.load")
    missing = [k for k in ("units", "x", "v", "clock", "seed", "streams", "energy0", "momentum0") if k not in st]
    if missing:
        raise ValueError(f"restart_from_legacy: the checkpoint lacks {', '.join(missing)}")
    new = {k: st[k] for k in _LEGACY_KEPT if k in st}
    n, dim = len(np.asarray(st["x"])), int(np.asarray(st.get("dim", 2)))
    new.update(_core.lattice_initial_bits(n, int(np.asarray(st["seed"]))))
    new["origin"], new["collisions"] = new["clock"], 0
    new["particle_collisions"] = np.zeros(n, dtype=np.uint64)
    empty_u, empty_i = np.zeros(0, dtype=np.uint64), np.zeros(0, dtype=np.int64)
    new.update(log_particle=empty_u, log_count=empty_u, log_redraws=empty_u, group_drawer=empty_i, group_draws=empty_u,
               group_size=empty_i, group_members=empty_i, group_counts=empty_u, group_kind=empty_i,
               group_v=np.zeros((0, dim), dtype=np.int64))
    return new
