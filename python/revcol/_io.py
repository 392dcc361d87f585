"""Atomic output: a file is written beside its target and moved into place, so a reader (or a
crash, or Ctrl-C) never sees half a checkpoint."""
from __future__ import annotations

import os
import tempfile
from typing import Mapping, Union

import numpy as np

__all__ = ["write_npz_atomic"]


def write_npz_atomic(path: Union[str, os.PathLike], arrays: Mapping[str, np.ndarray]) -> None:
    """Writes ``arrays`` as an ``.npz`` to ``path`` atomically (temporary file, then ``os.replace``)."""
    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(prefix=".revcol-", suffix=".npz.tmp", dir=folder)
    try:
        with os.fdopen(fd, "wb") as f:
            np.savez(f, **arrays)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise
