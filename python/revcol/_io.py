"""Atomic output: a file is written beside its target and moved into place, so a reader (or a
crash, or Ctrl-C) never sees half a checkpoint; checkpoints stamped and carrying a content
digest that ``load`` checks (:func:`content_digest`); and reports as JSON (numpy values and
non-finite floats become plain JSON)."""
from __future__ import annotations

import contextlib
import hashlib
import json
import math
import os
import re
import tempfile
import warnings
import zipfile
from pathlib import Path
from typing import IO, Any, Iterator, Mapping, Union

import numpy as np

from . import _core
from ._version import __version__

__all__ = ["write_npz_atomic", "atomic_open", "save_figure", "write_checkpoint", "read_checkpoint", "STAMP_KEYS",
           "DIGEST_KEY", "content_digest", "digested", "jsonable", "write_json", "named_os_error"]

#: keys a checkpoint file carries besides the snapshot: what wrote it
STAMP_KEYS = ("revcol_version", "revcol_build", "revcol_engine")

#: the checkpoint entry holding the SHA-256 of every other entry (:func:`content_digest`), as
#: 64 lowercase hex digits in a 0-d unicode array
DIGEST_KEY = "digest_sha256"

# the first bytes hashed: names the definition below, so that a change of it cannot be mistaken
# for a changed file of the old one
_DIGEST_DOMAIN = b"revcol checkpoint digest v1\n"
_HEX64 = re.compile(r"[0-9a-f]{64}")


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


def _u64(k: int) -> bytes:
    return int(k).to_bytes(8, "little")


def content_digest(arrays: Mapping[str, np.ndarray]) -> str:
    """The SHA-256 (64 hex digits) of the canonical bytes of every entry of ``arrays`` but
    :data:`DIGEST_KEY`: the bytes ``revcol checkpoint digest v1\\n``, then per entry in the order of
    the sorted keys (Python's ``sorted``: by code point), each field length-prefixed with its byte
    count as a little-endian uint64 --

        len(key) key (UTF-8) | len(dtype) dtype.str (ASCII, e.g. ``<f8``, ``<U7``, ``|b1``) |
        ndim, then each extent (uint64 each) | len(data) data (the raw bytes in C order)

    so that no two different sets of entries give the same byte string. It is what an ``.npz``
    holds (``np.load`` gives back the dtype, shape and bytes ``np.savez`` was given, whatever
    the memory order), so the digest of a file's arrays is the one ``save`` computed unless a
    byte of the file changed. An integrity check, not a signature: anyone can recompute it.
    Object arrays (pickles) have no canonical bytes: TypeError."""
    h = hashlib.sha256(_DIGEST_DOMAIN)
    for key in sorted(k for k in arrays if k != DIGEST_KEY):
        a = np.asarray(arrays[key])
        if a.dtype.hasobject:
            raise TypeError(f"checkpoint entry {key!r} holds Python objects, which have no canonical bytes")
        for field in (key.encode("utf-8"), a.dtype.str.encode("ascii")):
            h.update(_u64(len(field)) + field)
        h.update(_u64(a.ndim) + b"".join(_u64(e) for e in a.shape))
        c = np.ascontiguousarray(a).reshape(-1)
        try:
            data = c.view(np.uint8)  # no copy of a large array
        except (TypeError, ValueError):  # a dtype of no bytes ("V0", "S0")
            data = np.frombuffer(c.tobytes(), dtype=np.uint8)
        h.update(_u64(data.size))
        h.update(data.data)  # a memoryview of the bytes
    return h.hexdigest()


def digested(arrays: Mapping[str, np.ndarray]) -> dict:
    """``arrays`` with :data:`DIGEST_KEY` set to their :func:`content_digest` (any old one replaced)."""
    out = {k: v for k, v in arrays.items() if k != DIGEST_KEY}
    out[DIGEST_KEY] = np.asarray(content_digest(out))
    return out


def write_checkpoint(path: Union[str, os.PathLike], arrays: Mapping[str, np.ndarray], engine: str) -> None:
    """Writes a checkpoint of ``engine``: ``arrays`` (:func:`stamped`, then :func:`digested`) as an
    ``.npz`` at ``path``, atomically (:func:`write_npz_atomic`). Every ``save`` of both engines
    writes through here, and :func:`read_checkpoint` reads what it wrote."""
    write_npz_atomic(path, digested(stamped({k: np.asarray(v) for k, v in arrays.items()}, engine)))


def _check_digest(arrays: Mapping[str, np.ndarray], path: str) -> None:
    """Refuses (ValueError "checkpoint corrupted: ...") a file whose digest entry is malformed or
    is not the :func:`content_digest` of its other entries; a file without one (written before
    digests) passes unchecked."""
    if DIGEST_KEY not in arrays:
        return
    d = arrays[DIGEST_KEY]
    stored = str(d) if d.dtype.kind == "U" and d.ndim == 0 else None
    if stored is None or not _HEX64.fullmatch(stored):
        got = f"a {d.dtype.str} array of shape {d.shape}" if stored is None else repr(stored[:80])
        raise ValueError(f"checkpoint corrupted: malformed digest entry {DIGEST_KEY!r} in {path!r} "
                         f"(64 lowercase hex digits expected, got {got})")
    computed = content_digest(arrays)
    if computed != stored:
        raise ValueError(f"checkpoint corrupted: digest mismatch in {path!r}: the file holds SHA-256 "
                         f"{stored[:16]}..., its entries hash to {computed[:16]}... (a byte changed after "
                         "it was written)")


def read_checkpoint(path: Union[str, os.PathLike], engine: str) -> dict:
    """The arrays of a checkpoint written by ``save`` (no pickles), its digest and stamp checked: a
    file that is not an ``.npz``, whose digest is malformed or does not match its entries
    ("checkpoint corrupted: digest mismatch ..."), or whose stamp names another engine, raises
    ValueError naming the problem and the file; one written by another revcol version or build
    loads with a RuntimeWarning (it resumes, but bit-for-bit agreement with the other build's run
    is not promised). Files from before stamps load silently, and files from before digests
    load without an integrity check."""
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
    _check_digest(out, os.fspath(path))
    out.pop(DIGEST_KEY, None)
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
