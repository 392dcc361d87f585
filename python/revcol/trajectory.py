"""Trajectory files that standard viewers open: extended XYZ (OVITO, ASE, VMD's plugin) and
GSD (HOOMD-blue's format, through the ``gsd`` package).

Frames are written as they come (nothing is buffered): ``open_trajectory(path, ...)`` picks
the format from the suffix and returns a writer with ``write(positions, velocities, time,
collisions, phase)`` and ``close()``. Positions of a 1D or 2D gas are padded to 3 components
with zeros.

Extended XYZ, one frame::

    3
    Lattice="10 0 0 0 10 0 0 0 1" Properties=species:S:1:pos:R:3:velo:R:3:radius:R:1 Time=0.5 Collisions=100 Phase="forward" pbc="F F F"
    A 1.5 2.5 0 0.1 -0.3 0 0.5
    ...

The cell spans [0, L_k] per axis (OVITO's default origin); a missing axis gets the length
of one diameter. GSD frames follow HOOMD's conventions instead: the box is centred on the
origin (positions shifted by -L/2), a 2D box has Lz = 0, ``configuration.step`` holds the
collision count and ``log/revcol/time`` the clock. A 1D gas is written as 2D (Ly = D).

    >>> import numpy as np, tempfile, os
    >>> path = os.path.join(tempfile.mkdtemp(), "t.xyz")
    >>> w = open_trajectory(path, box=[4.0, 4.0], periodic=[False, False], diameter=1.0)
    >>> w.write(np.array([[1.0, 1.0], [3.0, 3.0]]), np.zeros((2, 2)), time=0.0, collisions=0, phase="forward")
    >>> w.close()
    >>> open(path).readline().strip()
    '2'
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Sequence

import numpy as np

__all__ = ["open_trajectory", "check_format", "XYZWriter", "GSDWriter", "FORMATS"]

#: suffix -> what writes it
FORMATS = {".xyz": "extended XYZ (OVITO, ASE)", ".gsd": "GSD (HOOMD-blue; needs the gsd package)"}


def _pad3(a: np.ndarray) -> np.ndarray:
    a = np.asarray(a, dtype=float)
    out = np.zeros((a.shape[0], 3))
    out[:, : a.shape[1]] = a
    return out


class XYZWriter:
    """Extended XYZ frames, appended to one text file."""

    def __init__(self, path: str | os.PathLike, box: Sequence[float], periodic: Sequence[bool],
                 diameter: float):
        self.path = Path(path)
        self.dim = len(box)
        lengths = list(box) + [diameter] * (3 - len(box))
        pbc = [bool(p) for p in periodic] + [False] * (3 - len(box))
        lattice = " ".join(f"{lengths[i] if i == j else 0.0:.17g}" for i in range(3) for j in range(3))
        self._head = (f'Lattice="{lattice}" Properties=species:S:1:pos:R:3:velo:R:3:radius:R:1 '
                      f'pbc="{" ".join("T" if p else "F" for p in pbc)}"')
        self._radius = 0.5 * diameter
        self.frames = 0
        self._tmp = _part(self.path)
        self._f = open(self._tmp, "w")

    def write(self, positions, velocities, time: float, collisions: int, phase: str) -> None:
        x, v = _pad3(positions), _pad3(velocities)
        n = x.shape[0]
        rows = np.empty((n, 7))
        rows[:, :3], rows[:, 3:6], rows[:, 6] = x, v, self._radius
        self._f.write(f"{n}\n{self._head} Time={time:.17g} Collisions={int(collisions)} Phase=\"{phase}\"\n")
        np.savetxt(self._f, rows, fmt="A" + " %.12g" * 7)
        self.frames += 1

    def close(self) -> None:
        self._f.close()
        _publish(self._tmp, self.path)


class GSDWriter:
    """GSD frames through the ``gsd`` package (HOOMD-blue's schema)."""

    def __init__(self, path: str | os.PathLike, box: Sequence[float], periodic: Sequence[bool],
                 diameter: float):
        import gsd.hoomd  # checked by open_trajectory

        self._hoomd = gsd.hoomd
        self.path = Path(path)
        self.dim = len(box)
        # HOOMD boxes are 2D or 3D; a 1D gas is shown as 2D with one diameter of height
        self._lengths = np.array(list(box) + [diameter] * max(0, 2 - len(box)), dtype=float)
        self._dimensions = 3 if self.dim == 3 else 2
        self._diameter = float(diameter)
        self.frames = 0
        self._tmp = _part(self.path)
        try:
            self._f = gsd.hoomd.open(self._tmp, mode="w")
        except ValueError:  # gsd < 3 spells the modes "wb"
            self._f = gsd.hoomd.open(self._tmp, mode="wb")

    def write(self, positions, velocities, time: float, collisions: int, phase: str) -> None:
        frame_cls = getattr(self._hoomd, "Frame", None) or self._hoomd.Snapshot
        f = frame_cls()
        n = np.asarray(positions).shape[0]
        lx, ly = self._lengths[0], self._lengths[1]
        lz = self._lengths[2] if self._dimensions == 3 else 0.0
        f.configuration.box = [lx, ly, lz, 0.0, 0.0, 0.0]
        f.configuration.dimensions = self._dimensions
        f.configuration.step = int(collisions)
        x = _pad3(positions)
        x[:, 0] -= 0.5 * lx
        x[:, 1] -= 0.5 * ly
        if self._dimensions == 3:
            x[:, 2] -= 0.5 * lz
        f.particles.N = n
        f.particles.types = ["A"]
        f.particles.typeid = np.zeros(n, dtype=np.uint32)
        f.particles.position = x.astype(np.float32)
        f.particles.velocity = _pad3(velocities).astype(np.float32)
        f.particles.diameter = np.full(n, self._diameter, dtype=np.float32)
        f.log["revcol/time"] = np.array([time], dtype=np.float64)
        f.log["revcol/reverse"] = np.array([phase == "reverse"], dtype=np.uint8)
        self._f.append(f)
        self.frames += 1

    def close(self) -> None:
        self._f.close()
        _publish(self._tmp, self.path)


def _part(path: Path) -> str:
    """A temporary file beside ``path`` that the frames go to until close() (atomic output:
    a reader never sees a file at ``path`` that is still being written)."""
    import tempfile

    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=".revcol-", suffix=path.suffix + ".part", dir=path.parent)
    os.close(fd)
    return tmp


def _publish(tmp: str, path: Path) -> None:
    """Moves a closed trajectory into place (fsynced first), with the frames written so far."""
    with open(tmp, "rb+") as f:
        os.fsync(f.fileno())
    os.replace(tmp, path)


def open_trajectory(path: str | os.PathLike, box: Sequence[float], periodic: Sequence[bool],
                    diameter: float) -> XYZWriter | GSDWriter:
    """A writer for ``path``: ``.xyz`` (extended XYZ) or ``.gsd`` (needs ``gsd``). Raises
    ValueError for another suffix, or for ``.gsd`` when ``gsd`` is not installed."""
    suffix = Path(path).suffix.lower()
    if suffix == ".xyz":
        return XYZWriter(path, box, periodic, diameter)
    if suffix == ".gsd":
        check_format(path)
        return GSDWriter(path, box, periodic, diameter)
    raise ValueError(f"trajectory {str(path)!r}: the suffix must be .xyz (extended XYZ) or .gsd")


def check_format(path: str | os.PathLike) -> None:
    """Raises ValueError (one line) when ``path`` cannot be written: an unknown suffix, or
    ``.gsd`` without the ``gsd`` package. Call it before a run so that nothing is half-done."""
    suffix = Path(path).suffix.lower()
    if suffix not in FORMATS:
        raise ValueError(f"trajectory {str(path)!r}: the suffix must be .xyz (extended XYZ) or .gsd")
    if suffix == ".gsd":
        try:
            import gsd.hoomd  # noqa: F401
        except ImportError:
            raise ValueError(f"trajectory {str(path)!r}: writing .gsd needs the gsd package "
                             "(pip install gsd), or write extended XYZ (.xyz) instead") from None
