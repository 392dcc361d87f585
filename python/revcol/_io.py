"""Atomic output: a file is written beside its target and moved into place, so a reader (or a
crash, or Ctrl-C) never sees half a checkpoint; and reports as JSON (numpy values and
non-finite floats become plain JSON)."""
from __future__ import annotations

import contextlib
import json
import math
import os
import tempfile
import warnings
import zipfile
from pathlib import Path
from typing import IO, Any, Iterator, Mapping, Union

import numpy as np

from . import _core
from ._version import __version__

__all__ = ["write_npz_atomic", "atomic_open", "save_figure", "read_checkpoint", "STAMP_KEYS", "jsonable",
           "write_json", "named_os_error"]

#: keys a checkpoint file carries besides the snapshot: what wrote it
STAMP_KEYS = ("revcol_version", "revcol_build", "revcol_engine")


def _fsync_folder(folder: str) -> None:
    """Makes a rename durable (POSIX: fsync the folder); a no-op where folders cannot be opened."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _open_permissions(path: str) -> None:
    """The mode open() would have given a new file (0666 less the umask)."""
    mask = os.umask(0)
    os.umask(mask)
    os.chmod(path, 0o666 & ~mask)


def named_os_error(e: OSError, path: Union[str, os.PathLike], doing: str = "") -> OSError:
    """``e`` as an OSError of its errno that names ``path`` (and what was being done): a write that
    fails on a full disk raises ``[Errno 28] No space left on device`` naming no file (issue 59)."""
    what = (e.strerror or str(e) or type(e).__name__) + (f" ({doing})" if doing else "")
    if e.errno is None:
        return OSError(f"{what}: {os.fspath(path)!r}")
    return OSError(e.errno, what, os.fspath(path))


@contextlib.contextmanager
def atomic_open(path: Union[str, os.PathLike], mode: str = "w", **kwargs) -> Iterator[IO]:
    """A file to write ``path`` through: a temporary file beside it, fsynced and renamed over
    ``path`` when the block ends without an exception; removed otherwise, leaving any previous
    file at ``path`` whole. Every output the CLI writes goes through here (issue 17). An OSError
    that names no file (a write or flush on a full disk) is raised again naming ``path`` (issue 59)."""
    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    suffix = os.path.splitext(path)[1]
    fd, tmp = tempfile.mkstemp(prefix=".revcol-", suffix=suffix + ".tmp", dir=folder)
    try:
        _open_permissions(tmp)  # mkstemp's 0600 would make every output private
        with os.fdopen(fd, mode, **kwargs) as f:
            yield f
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
        _fsync_folder(folder)
    except BaseException as e:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        if isinstance(e, OSError) and e.filename is None:
            raise named_os_error(e, path, "writing it; the partial file is removed") from e
        raise


def save_figure(fig, path: Union[str, os.PathLike], **kwargs) -> None:
    """``fig.savefig`` through :func:`atomic_open` (the format from the path's suffix)."""
    fmt = os.path.splitext(os.fspath(path))[1].lstrip(".") or "png"
    with atomic_open(path, "wb") as f:
        fig.savefig(f, format=fmt, **kwargs)


def write_npz_atomic(path: Union[str, os.PathLike], arrays: Mapping[str, np.ndarray]) -> None:
    """Writes ``arrays`` as an ``.npz`` to ``path`` atomically (:func:`atomic_open`): a failed
    save leaves any previous file at ``path`` whole."""
    with atomic_open(path, "wb") as f:
        np.savez(f, **arrays)


def stamped(arrays: Mapping[str, np.ndarray], engine: str) -> dict:
    """``arrays`` with the stamp of this revcol (version, build: compiler and flags) and ``engine``."""
    out = dict(arrays)
    out.update(revcol_version=np.asarray(__version__), revcol_build=np.asarray(_core.build),
               revcol_engine=np.asarray(engine))
    return out


def read_checkpoint(path: Union[str, os.PathLike], engine: str) -> dict:
    """The arrays of a checkpoint written by ``save`` (no pickles), its stamp checked: a file that is
    not an ``.npz``, or whose stamp names another engine, raises ValueError naming the problem; one
    written by another revcol version or build loads with a RuntimeWarning (it resumes, but bit-for-bit
    agreement with the other build's run is not promised). Files from before stamps load silently."""
    try:
        z = np.load(path, allow_pickle=False)
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as e:
        raise ValueError(f"{os.fspath(path)!r} is not a readable revcol checkpoint ({e})") from None
    if not isinstance(z, np.lib.npyio.NpzFile):
        raise ValueError(f"{os.fspath(path)!r} is not a revcol checkpoint (.npz), it holds one array")
    out = {}
    with z:
        try:
            for k in z.files:
                out[k] = z[k]
        except (OSError, ValueError, EOFError, zipfile.BadZipFile) as e:
            raise ValueError(f"{os.fspath(path)!r}: entry {k!r} is damaged ({e})") from None
    stamp = {k: out.pop(k) for k in STAMP_KEYS if k in out}
    if "revcol_engine" in stamp and str(stamp["revcol_engine"]) != engine:
        raise ValueError(f"{os.fspath(path)!r} is a {stamp['revcol_engine']} engine checkpoint, not {engine}")
    ver, build = str(stamp.get("revcol_version", __version__)), str(stamp.get("revcol_build", _core.build))
    if ver != __version__ or build != _core.build:
        warnings.warn(f"{os.fspath(path)!r} was written by revcol {ver} ({build}); this is {__version__} "
                      f"({_core.build}): the run resumes, but bit-for-bit agreement across builds is not promised",
                      RuntimeWarning, stacklevel=3)
    return out


def jsonable(o: Any) -> Any:
    """``o`` with numpy values as Python's, non-finite floats as strings ("inf", "nan") and paths
    as strings: what :func:`json.dumps` takes."""
    if isinstance(o, dict):
        return {str(k): jsonable(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [jsonable(v) for v in o]
    if isinstance(o, np.ndarray):
        return jsonable(o.tolist())
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, (np.floating, float)):
        return float(o) if math.isfinite(o) else str(o)
    if isinstance(o, Path):
        return str(o)
    return o


def write_json(report: dict, path: str | os.PathLike) -> str:
    """Writes the report as indented JSON (:func:`jsonable`; creating the directory, atomically);
    returns the path."""
    p = Path(path)
    with atomic_open(p) as f:
        f.write(json.dumps(jsonable(report), indent=1) + "\n")
    return str(p)
