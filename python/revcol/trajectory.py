"""Trajectory files that standard viewers open: extended XYZ (OVITO, ASE, VMD's plugin) and
GSD (HOOMD-blue's format, through the ``gsd`` package; OVITO and freud read it).

Frames are written as they come (nothing is buffered): ``open_trajectory(path, ...)`` picks
the format from the suffix and returns a writer with ``write(positions, velocities, time,
collisions, phase)`` and ``close()``; ``collisions`` is the net count (forward minus undone),
``phase`` ``"forward"`` or ``"reverse"``. Positions of a 1D or 2D gas are padded to 3
components with zeros. The file appears at ``path`` on ``close()`` only.

Extended XYZ, one frame (species: a chemical element symbol, ``"Ar"`` unless told, since ASE
maps the species column to elements and fails on another name)::

    3
    Lattice="10 0 0 0 10 0 0 0 0" Properties=species:S:1:pos:R:3:velo:R:3:radius:R:1:image:I:3 Time=0.5 Collisions=100 Phase="forward" pbc="T T F"
    Ar 1.5 2.5 0 0.1 -0.3 0 0.5 1 0 0
    ...

The last three columns (``image``, a periodic box only) are the particle's crossings of each
axis, as GSD's ``particles.image`` below: ``pos + image * L`` is its unwrapped position.

The cell spans [0, L_k] per axis (OVITO's default origin). A 2D gas has a third cell vector
of zero length and ``pbc`` F on z (what ASE writes for a 2D cell; OVITO detects the
dimensionality on import and ignores z in 2D mode, docs/run.md); a 1D gas is written the
same way with a y vector of one diameter (not periodic).

GSD frames follow HOOMD's conventions: the box is centred on the origin (positions shifted by
-L/2), a 2D box has Lz = 0 (a 1D gas is written as 2D with Ly = D), and

- ``configuration.step`` counts the collisions done in both directions since the first frame
  (plus the first frame's net count), so it never decreases over a run that goes forward and
  back (frames with no collision between them share a step);
- ``log/revcol/net_collisions`` (int64) is the net count, ``log/revcol/direction`` (int8) +1
  forward and -1 in the reversal, ``log/revcol/time`` (float64) the clock, and
  ``log/revcol/walls`` (uint8, 3 values, x y z) 1 where an axis is closed by walls (or is a
  padding axis) and 0 where it is periodic: HOOMD boxes are always periodic, so a reader must
  take the walls from here (docs/run.md);
- ``particles.image`` counts each particle's crossings of each periodic axis, so
  x + image * L is its unwrapped position (MSD across periodic boundaries). When the frame
  comes with them (``write(..., image=)``; a writer called on an observing simulation, and
  ``revcol run`` / ``revcol simulate``, which observe while they write frames: :func:`true_images`)
  they are the engine's own, exact at any frame spacing. Otherwise the writer sees only frames:
  it takes each particle's jump between consecutive frames as the minimum image, which is
  exact while no particle moves more than L/2 along an axis between two frames, and warns
  (RuntimeWarning, once) when some particle's minimum-image jump exceeds L/4 along a periodic
  axis: frames that sparse may hide a crossing (write frames more often, or observe);
- ``particles.diameter`` the diameter, ``particles.types`` the species;
- with ``precise=True``, ``log/particles/revcol/position`` holds the float64 positions (same
  centred frame) that ``particles.position`` (float32 in HOOMD's schema) rounds.

    >>> import numpy as np, tempfile, os
    >>> path = os.path.join(tempfile.mkdtemp(), "t.xyz")
    >>> w = open_trajectory(path, box=[4.0, 4.0], periodic=[False, False], diameter=1.0)
    >>> w.write(np.array([[1.0, 1.0], [3.0, 3.0]]), np.zeros((2, 2)), time=0.0, collisions=0, phase="forward")
    >>> w.close()
    >>> open(path).readlines()[2].split()[0]
    'Ar'
"""
from __future__ import annotations

import io
import os
import tempfile
import warnings
from pathlib import Path
from typing import Sequence

import numpy as np

from ._extras import install_hint
from ._io import named_os_error

__all__ = ["open_trajectory", "check_format", "XYZWriter", "GSDWriter", "FORMATS", "ELEMENTS", "net_collisions",
           "read_gsd", "frame_size", "true_images"]

#: suffix -> what writes it
FORMATS = {".xyz": "extended XYZ (OVITO, ASE)", ".gsd": "GSD (HOOMD-blue; needs the gsd package)"}

#: the chemical element symbols, the species names that ASE reads
ELEMENTS = frozenset((
    "H He Li Be B C N O F Ne Na Mg Al Si P S Cl Ar K Ca Sc Ti V Cr Mn Fe Co Ni Cu Zn Ga Ge As Se Br Kr "
    "Rb Sr Y Zr Nb Mo Tc Ru Rh Pd Ag Cd In Sn Sb Te I Xe Cs Ba La Ce Pr Nd Pm Sm Eu Gd Tb Dy Ho Er Tm Yb "
    "Lu Hf Ta W Re Os Ir Pt Au Hg Tl Pb Bi Po At Rn Fr Ra Ac Th Pa U Np Pu Am Cm Bk Cf Es Fm Md No Lr Rf "
    "Db Sg Bh Hs Mt Ds Rg Cn Nh Fl Mc Lv Ts Og").split())


def _species(species: str) -> str:
    if not isinstance(species, str) or species not in ELEMENTS:
        raise ValueError(f"species must be a chemical element symbol (e.g. 'Ar'; ASE reads no other "
                         f"name), got {species!r}")
    return species


def _pad3(a: np.ndarray) -> np.ndarray:
    a = np.asarray(a, dtype=float)
    out = np.zeros((a.shape[0], 3))
    out[:, : a.shape[1]] = a
    return out


def net_collisions(sim) -> int:
    """The net collision count of a :class:`revcol.Simulation` or a lattice simulation."""
    if hasattr(sim, "collisions"):
        return int(sim.collisions)
    return int(sim.diagnostics()["net_collisions"])


class _Writer:
    """What both writers share: a frame of a simulation by calling the writer (so that a writer
    can be attached to one: ``sim.attach(writer, every=1000)``), ``close``, and what a failed
    write does (issue 59): an ``OSError`` while writing or closing (a full disk: ENOSPC) removes
    the partial file and is raised again naming the trajectory's path, so that neither a
    ``.revcol-*.part`` file nor a file with half a frame is left behind."""

    path: Path
    _tmp: str
    frames: int
    closed: bool = False
    _image: np.ndarray | None = None

    def write(self, positions, velocities, time: float, collisions: int, phase: str, image=None) -> None:
        """Appends a frame (``collisions``: the net count; ``phase``: ``"forward"`` or ``"reverse"``;
        ``image``: the particles' periodic crossings (n x d integers, :func:`true_images`), else
        the writer infers them from consecutive frames; a walled box's XYZ has no image column)."""
        if self.closed:
            raise ValueError(f"trajectory {str(self.path)!r} is closed")
        self._image = None if image is None else np.asarray(image, dtype=np.int64)
        try:
            self._write(positions, velocities, time, collisions, phase)
        except OSError as e:
            raise self._failed(e, f"writing frame {self.frames + 1} of the trajectory") from e
        self.frames += 1

    def _write(self, positions, velocities, time: float, collisions: int, phase: str) -> None:
        raise NotImplementedError

    def __call__(self, sim, phase: str = "forward") -> None:
        """Writes the current state of ``sim`` as a frame (its clock and net collision count)."""
        if self.closed:
            raise ValueError(f"trajectory {str(self.path)!r} is closed (detach it from the simulation)")
        x = sim.positions
        self.write(x, sim.velocities, sim.time, net_collisions(sim), phase, image=true_images(sim, x))

    def _close_file(self) -> None:
        raise NotImplementedError

    def close(self) -> None:
        """Closes the file and moves it into place; frames written so far are kept. Does nothing
        when the writer is closed already (a failed write closed it and removed its file)."""
        if self.closed:
            return
        try:
            self._close_file()
            self.closed = True
            _publish(self._tmp, self.path)
        except OSError as e:
            raise self._failed(e, f"closing the trajectory after {self.frames} frames") from e

    def close_quietly(self) -> None:
        """:meth:`close` after another error ended the run: the frames so far are kept when the
        file can be closed; when it cannot, the partial file is removed and this second error is
        dropped (the first one is the one to report)."""
        try:
            self.close()
        except OSError:
            pass

    def _failed(self, e: OSError, doing: str) -> OSError:
        """After ``e``: the file closed and removed, and the error naming the trajectory's path."""
        self.closed = True
        try:
            self._close_file()
        except Exception:  # noqa: BLE001 - the file is being thrown away; the first error is reported
            pass
        try:
            os.unlink(self._tmp)
        except OSError:
            pass
        return named_os_error(e, self.path, f"{doing}; the partial file is removed")


class XYZWriter(_Writer):
    """Extended XYZ frames, appended to one text file."""

    def __init__(self, path: str | os.PathLike, box: Sequence[float], periodic: Sequence[bool],
                 diameter: float, *, species: str = "Ar", diameters=None):
        self.path = Path(path)
        self.dim = len(box)
        self.species = _species(species)
        self._head = _xyz_head(box, periodic, diameter)
        self._radius = 0.5 * (diameter if diameters is None else np.asarray(diameters, dtype=float))  # a mixture: per particle
        per = np.zeros(3, dtype=bool)
        per[: self.dim] = [bool(p) for p in periodic]
        lengths3 = np.ones(3)
        lengths3[: self.dim] = np.asarray(box, dtype=float)
        # a periodic box's frames carry their image flags (the last column), as GSD's
        self._unwrap = _Unwrap(lengths3, per) if per.any() else None
        self.frames = 0
        self._tmp = _part(self.path)
        self._f = _opened(self._tmp, self.path, lambda: open(self._tmp, "w"))

    def _write(self, positions, velocities, time: float, collisions: int, phase: str) -> None:
        image = None
        if self._unwrap is not None:
            raw = _pad3(positions)
            image = self._unwrap.update(raw) if self._image is None else self._unwrap.given(raw, self._image)
        _xyz_frame(self._f, self._head, self.species, self._radius, positions, velocities, time, collisions, phase,
                   image)

    def _close_file(self) -> None:
        self._f.close()


def _xyz_head(box: Sequence[float], periodic: Sequence[bool], diameter: float) -> str:
    """The extended XYZ header's cell and columns. 2D (and 1D, shown as 2D): a zero third vector and
    pbc F on z, as ASE writes a 2D cell."""
    lengths = list(box) + [diameter] * max(0, 2 - len(box)) + [0.0] * (3 - max(2, len(box)))
    pbc = [bool(p) for p in periodic] + [False] * (3 - len(box))
    lattice = " ".join(f"{lengths[i] if i == j else 0.0:.17g}" for i in range(3) for j in range(3))
    image = ":image:I:3" if any(pbc) else ""  # periodic crossings per axis (a periodic box only)
    return (f'Lattice="{lattice}" Properties=species:S:1:pos:R:3:velo:R:3:radius:R:1{image} '
            f'pbc="{" ".join("T" if p else "F" for p in pbc)}"')


def _xyz_frame(f, head: str, species: str, radius: float, positions, velocities, time: float, collisions: int,
               phase: str, image=None) -> None:
    """One extended XYZ frame written to ``f`` (the writer's format, and :func:`frame_size`'s sample);
    ``image`` (n x 3 integers) when the header has the image column."""
    x, v = _pad3(positions), _pad3(velocities)
    n = x.shape[0]
    rows = np.empty((n, 7 if image is None else 10))
    rows[:, :3], rows[:, 3:6], rows[:, 6] = x, v, radius
    if image is not None:
        rows[:, 7:] = image
    f.write(f"{n}\n{head} Time={time:.17g} Collisions={int(collisions)} Phase=\"{phase}\"\n")
    np.savetxt(f, rows, fmt=species + " %.12g" * 7 + ("" if image is None else " %d %d %d"))


#: GSD bytes per particle of a frame after the first (gsd writes a chunk only where it differs
#: from the first frame's): float32 positions and velocities, 3 x 4 bytes each; int32 image flags,
#: 3 x 4, once a particle has crossed a periodic axis; float64 positions, 3 x 8, when ``precise``
GSD_PARTICLE_BYTES = {"position": 12, "velocity": 12, "image": 12, "precise": 24}
#: GSD bytes of a frame besides its particles: the box, step and logs, and one index entry per
#: chunk (measured: 390 bytes with gsd 5; taken as 512)
GSD_FRAME_BYTES = 512


def frame_size(path: str | os.PathLike, box: Sequence[float], periodic: Sequence[bool], diameter: float,
               positions, velocities, *, species: str = "Ar", precise: bool = False, time: float = 0.0,
               collisions: int = 0) -> tuple[float, float]:
    """(bytes of a frame besides its particles, bytes per particle) of a frame in the format of
    ``path``, as its writer writes it. Extended XYZ: measured on a sample frame of these
    ``positions`` and ``velocities`` (any number of rows) formatted by the writer's own code, so
    the line length is that of the numbers a run prints (%.12g of each coordinate); ``time`` and
    ``collisions`` as in the header of the frames to come. GSD: :data:`GSD_PARTICLE_BYTES` (image
    flags counted when an axis is periodic) and :data:`GSD_FRAME_BYTES`."""
    if Path(path).suffix.lower() == ".gsd":
        per = GSD_PARTICLE_BYTES
        b = per["position"] + per["velocity"] + (per["image"] if any(periodic) else 0)
        return float(GSD_FRAME_BYTES), float(b + (per["precise"] if precise else 0))
    f = io.StringIO()
    sample = np.full((np.asarray(positions).shape[0], 3), -99) if any(periodic) else None  # 3 characters a flag
    _xyz_frame(f, _xyz_head(box, periodic, diameter), _species(species), 0.5 * diameter, positions, velocities,
               time, collisions, "forward", sample)
    text = f.getvalue().encode()
    n = max(1, np.asarray(positions).shape[0])
    header = text.index(b"\n", text.index(b"\n") + 1) + 1
    return float(header), (len(text) - header) / n


def true_images(sim, positions=None) -> np.ndarray | None:
    """The particles' periodic crossings since the observation began (n x d integers), from the
    observer, which never wraps its positions: (unwrapped - wrapped) / L on periodic axes, 0 on
    walled ones; None when ``sim`` is not observing. Exact at any frame spacing (the inferred
    flags assume less than L/2 between frames). None too for a sheared gas: the observer's
    unwrapped flow coordinate there includes the moving images' offset, not whole box lengths."""
    if getattr(sim, "shear_rate", None):
        return None
    e = getattr(sim, "_e", None)
    u = e.observed_positions() if e is not None and hasattr(e, "observed_positions") else None
    if u is None:
        return None
    x = np.asarray(sim.positions if positions is None else positions, dtype=float)
    box = np.asarray(sim.box, dtype=float)
    per = np.asarray(sim.periodic, dtype=bool)
    return np.where(per, np.rint((u - x) / box), 0.0).astype(np.int64)


class _Unwrap:
    """Image flags from consecutive wrapped frames: each jump taken as the minimum image; or
    given (:func:`true_images`), offset so that they go on from the frames before."""

    def __init__(self, box: np.ndarray, periodic: np.ndarray):
        self.box, self.periodic = box, periodic
        self.prev: np.ndarray | None = None
        self.image: np.ndarray | None = None
        self.offset: np.ndarray | None = None  # the given flags' offset from this writer's
        self.warned = False

    def given(self, x: np.ndarray, image: np.ndarray) -> np.ndarray:
        """The image flags (n, 3) of frame ``x`` from the given crossings (n x d)."""
        img = _pad3(image).astype(np.int64)
        if self.offset is None or self.offset.shape != img.shape:  # go on from the inferred frames before, if any
            self.offset = self.update(x) - img if self.prev is not None else np.zeros_like(img)
        self.image = img + self.offset
        self.prev = x.copy()
        return self.image

    def update(self, x: np.ndarray) -> np.ndarray:
        """The image flags (n, 3) after frame ``x`` (engine coordinates, padded to 3)."""
        if self.prev is None or self.prev.shape != x.shape:
            self.image = np.zeros(x.shape, dtype=np.int64)
        else:
            ax = np.flatnonzero(self.periodic)
            jump = x[:, ax] - self.prev[:, ax]
            wraps = np.rint(jump / self.box[ax]).astype(np.int64)
            self.image[:, ax] -= wraps
            rest = np.abs(jump - wraps * self.box[ax])
            if not self.warned and rest.size and (rest > 0.25 * self.box[ax]).any():
                self.warned = True
                warnings.warn("trajectory: a particle moved more than L/4 along a periodic axis between two "
                              "frames; image flags assume less than L/2, so frames this sparse may miss a "
                              "crossing (write frames more often)", RuntimeWarning, stacklevel=3)
        self.prev = x.copy()
        return self.image


class GSDWriter(_Writer):
    """GSD frames through the ``gsd`` package (HOOMD-blue's schema)."""

    def __init__(self, path: str | os.PathLike, box: Sequence[float], periodic: Sequence[bool],
                 diameter: float, *, species: str = "Ar", precise: bool = False, diameters=None, types=None,
                 typeid=None):
        import gsd.hoomd  # checked by open_trajectory

        # a mixture: per particle its diameter and its species (types[typeid]); else one of each
        self._diameters = None if diameters is None else np.asarray(diameters, dtype=np.float32)
        self._types = None if types is None else [str(t) for t in types]
        self._typeid = None if typeid is None else np.asarray(typeid, dtype=np.uint32)

        self._hoomd = gsd.hoomd
        self.path = Path(path)
        self.dim = len(box)
        self.species = _species(species)
        self.precise = bool(precise)
        # HOOMD boxes are 2D or 3D; a 1D gas is shown as 2D with one diameter of height
        self._lengths = np.array(list(box) + [diameter] * max(0, 2 - len(box)), dtype=float)
        self._dimensions = 3 if self.dim == 3 else 2
        self._diameter = float(diameter)
        per = np.zeros(3, dtype=bool)
        per[: self.dim] = [bool(p) for p in periodic]
        self._walls = (~per).astype(np.uint8)
        lengths3 = np.ones(3)
        lengths3[: len(self._lengths)] = self._lengths
        self._unwrap = _Unwrap(lengths3, per)
        self._step: int | None = None
        self._net: int | None = None
        self.frames = 0
        self._tmp = _part(self.path)

        def make():
            try:
                return gsd.hoomd.open(self._tmp, mode="w")
            except ValueError:  # gsd < 3 spells the modes "wb"
                return gsd.hoomd.open(self._tmp, mode="wb")
        self._f = _opened(self._tmp, self.path, make)

    def _next_step(self, collisions: int) -> int:
        """Collisions done in both directions: the step never decreases through a reversal."""
        if self._step is None:
            self._step = max(0, collisions)
        else:
            self._step += abs(collisions - self._net)
        self._net = collisions
        return self._step

    def _write(self, positions, velocities, time: float, collisions: int, phase: str) -> None:
        frame_cls = getattr(self._hoomd, "Frame", None) or self._hoomd.Snapshot
        f = frame_cls()
        collisions = int(collisions)
        n = np.asarray(positions).shape[0]
        lx, ly = self._lengths[0], self._lengths[1]
        lz = self._lengths[2] if self._dimensions == 3 else 0.0
        f.configuration.box = [lx, ly, lz, 0.0, 0.0, 0.0]
        f.configuration.dimensions = self._dimensions
        f.configuration.step = self._next_step(collisions)
        raw = _pad3(positions)
        image = self._unwrap.update(raw) if self._image is None else self._unwrap.given(raw, self._image)
        x = raw.copy()
        x[:, 0] -= 0.5 * lx
        x[:, 1] -= 0.5 * ly
        if self._dimensions == 3:
            x[:, 2] -= 0.5 * lz
        f.particles.N = n
        f.particles.types = [self.species] if self._types is None else self._types
        f.particles.typeid = np.zeros(n, dtype=np.uint32) if self._typeid is None else self._typeid
        f.particles.position = x.astype(np.float32)
        f.particles.image = image.astype(np.int32)
        f.particles.velocity = _pad3(velocities).astype(np.float32)
        f.particles.diameter = np.full(n, self._diameter, dtype=np.float32) if self._diameters is None else self._diameters
        if self.precise:
            f.log["particles/revcol/position"] = x
        f.log["revcol/time"] = np.array([time], dtype=np.float64)
        f.log["revcol/net_collisions"] = np.array([collisions], dtype=np.int64)
        f.log["revcol/direction"] = np.array([-1 if phase == "reverse" else 1], dtype=np.int8)
        f.log["revcol/reverse"] = np.array([phase == "reverse"], dtype=np.uint8)
        f.log["revcol/walls"] = self._walls.copy()
        f.log["revcol/box"] = self._lengths.astype(np.float64)  # configuration.box is float32
        self._f.append(f)

    def _close_file(self) -> None:
        self._f.close()


def read_gsd(path: str | os.PathLike) -> dict:
    """A GSD trajectory written by :class:`GSDWriter`, read back as arrays in the engine's
    coordinates ([0, L) per axis): ``time`` and ``net_collisions`` (F,), ``positions`` (F, n,
    d: the float64 positions when the file was written ``precise``, else float32's),
    ``image`` (F, n, d), ``unwrapped`` = positions + image L on periodic axes (what an MSD
    across periodic boundaries uses), ``box`` (d,), ``periodic`` (d,). Needs ``gsd``."""
    import gsd.hoomd  # optional (the gsd extra): only for a .gsd trajectory

    with gsd.hoomd.open(os.fspath(path), mode="r") as f:
        frames = list(f)
    if not frames:
        raise ValueError(f"{path}: no frames")
    first = frames[0]
    walls = np.asarray(first.log["revcol/walls"], dtype=bool) if "revcol/walls" in first.log else None
    d = 3 if first.configuration.dimensions == 3 else 2
    # the float64 lengths where the writer logged them (configuration.box is float32: an unwrapped
    # position 7 box lengths out was 1.3e-6 off, and a precise position re-centred 2e-7 off)
    box = np.asarray(first.log["revcol/box"] if "revcol/box" in first.log else first.configuration.box,
                     dtype=float)[:d]
    precise = "particles/revcol/position" in first.log
    pos = np.array([np.asarray(fr.log["particles/revcol/position"] if precise else fr.particles.position,
                               dtype=float)[:, :d] for fr in frames])
    pos += 0.5 * box
    image = np.array([np.asarray(fr.particles.image)[:, :d] for fr in frames], dtype=np.int64)
    periodic = ~walls[:d] if walls is not None else np.ones(d, dtype=bool)
    unwrapped = pos + image * (box * periodic)
    return {"time": np.array([float(fr.log["revcol/time"][0]) for fr in frames]),
            "net_collisions": np.array([int(fr.log["revcol/net_collisions"][0]) for fr in frames]),
            "positions": pos, "image": image, "unwrapped": unwrapped, "box": box, "periodic": periodic,
            "precise": precise}


def _part(path: Path) -> str:
    """A temporary file beside ``path`` that the frames go to until close() (atomic output:
    a reader never sees a file at ``path`` that is still being written)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=".revcol-", suffix=path.suffix + ".part", dir=path.parent)
    os.close(fd)
    return tmp


def _opened(tmp: str, path: Path, make):
    """``make()``, the writer's file on ``tmp``; when it cannot be opened, ``tmp`` is removed and the
    error names ``path``."""
    try:
        return make()
    except OSError as e:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise named_os_error(e, path, "opening the trajectory") from e


def _publish(tmp: str, path: Path) -> None:
    """Moves a closed trajectory into place (fsynced first), with the frames written so far, and
    with the permissions a plain ``open`` would give it (mkstemp makes it private, 0600)."""
    mask = os.umask(0)
    os.umask(mask)
    os.chmod(tmp, 0o666 & ~mask)
    with open(tmp, "rb+") as f:
        os.fsync(f.fileno())
    os.replace(tmp, path)


def open_trajectory(path: str | os.PathLike, box: Sequence[float], periodic: Sequence[bool],
                    diameter: float, *, species: str = "Ar", precise: bool = False, diameters=None, types=None,
                    typeid=None) -> XYZWriter | GSDWriter:
    """A writer for ``path``: ``.xyz`` (extended XYZ) or ``.gsd`` (needs ``gsd``; ``precise``
    adds the float64 positions). A mixture: ``diameters`` per particle (XYZ's radius column,
    GSD's particles.diameter) and, GSD, the species' names ``types`` with each particle's
    ``typeid``. Raises ValueError for another suffix, for ``.gsd`` when ``gsd`` is not
    installed, or for a ``species`` that is not an element symbol."""
    suffix = Path(path).suffix.lower()
    _species(species)
    if suffix == ".xyz":
        return XYZWriter(path, box, periodic, diameter, species=species, diameters=diameters)
    if suffix == ".gsd":
        check_format(path)
        return GSDWriter(path, box, periodic, diameter, species=species, precise=precise, diameters=diameters,
                         types=types, typeid=typeid)
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
                             f"({install_hint('gsd')}), or write extended XYZ (.xyz) instead") from None
