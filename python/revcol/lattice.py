"""The 2D lattice engine: a randomized hard-disk gas reversed bit for bit, for any number of
collisions, with memory that does not grow with them (revcol/lattice/engine.hpp, LATTICE.md).

Positions and velocities are integers: sigma = 2^S lattice units per diameter D, a tick moves a
typical particle 2^-20 sigma. Free flight is exact; a pair collides on the transition into the
first tick at which its incoming lines overlap, through an exact integer bijection (the lattice
pair operator, with a bits-back integer X carrying the sub-tick phase and the torus shift
``u = u' + G``), drawing 48-bit numbers from per-particle Philox streams. ``run_back`` negates the
velocities, runs the same event search with the inverse operator and the streams stepping back, and
negates again: positions, velocities, streams, X and clock come back **bit for bit**, to the start
or to any earlier collision count or time.

A float start (``random`` or arrays) is quantized once; ``quantization`` reports the error. The
round trip is exact from the quantized state on. Times in floats are ``clock * tick``.

    >>> from revcol.lattice import LatticeSimulation
    >>> sim = LatticeSimulation.random(n=100, phi=0.3, seed=1)
    >>> x0, v0 = sim.lattice_positions, sim.lattice_velocities
    >>> _ = sim.run(collisions=2000)
    >>> _ = sim.run_back()                       # back to the start
    >>> bool((sim.lattice_positions == x0).all() and (sim.lattice_velocities == v0).all())
    True
"""
from __future__ import annotations

import os
import warnings
from typing import Optional, Sequence, Union

import numpy as np

from . import _core
from ._args import integer, name, names, real
from ._args import packing_fraction as _packing_fraction
from ._attach import Attachable
from ._io import read_checkpoint, stamped, write_npz_atomic
from .engine import _real_array

__all__ = ["LatticeSimulation"]

_Boundary = Union[str, Sequence[str]]


def _walls(boundary: _Boundary) -> list:
    given = names(boundary, "boundary")
    given = given * 2 if isinstance(boundary, str) else given
    if len(given) != 2:
        raise ValueError("the lattice engine is 2D: boundary must be one name or two")
    out = []
    for b in given:
        if b in ("wall", "walls"):
            out.append(True)
        elif b == "periodic":
            out.append(False)
        else:
            raise ValueError(f"boundary must be 'wall' or 'periodic', got {b!r}")
    return out


def _tick(tick_bits: Optional[int]) -> int:
    """The binding's tick_bits: 0 asks for the automatic tick."""
    return 0 if tick_bits is None else integer(tick_bits, "tick_bits", 16, 26)


class LatticeSimulation(Attachable):
    """N hard disks on the integer lattice, run forward and back bit for bit (2D only).

    Build from float arrays (``LatticeSimulation(positions, velocities, box)``, quantized once)
    or at random (``LatticeSimulation.random(n, phi=...)``, the float engine's initialiser then
    quantized). ``boundary``: ``"periodic"`` or ``"wall"`` (one or per axis). ``law``: ``"flux"``
    (default) or ``"uniform"``. ``seed`` keys the Philox streams ``{particle, seed}`` and X's
    first 256 bits. ``tick_bits`` T (16..26; default ``None``: automatic): a particle of rms speed
    moves 2^-T diameters per tick; a finer tick (larger T) makes redraws and group collisions (a
    third body within one tick) rarer at the cost of fewer bits of velocity resolution (2^(S-T)
    units for the rms speed, S set by the box). The automatic tick keeps 30 bits:
    T = clamp(S - 30, 16, 24) (docs/lattice.md). ``cell_bits`` (12..20, default 16): the pair operator
    cuts directions into 2^cell_bits equal-angle cells per turn; fewer cells make the lifting
    rotation's read-back redraws rarer (docs/lattice.md). Bad input raises ``ValueError`` naming
    the problem.
    """

    def __init__(self, positions, velocities, box, *, boundary: _Boundary = "periodic",
                 diameter: float = 1.0, law: str = "flux", seed: int = 1, tick_bits: Optional[int] = None,
                 cell_bits: int = 16, _engine=None,
                 _quantization: Optional[dict] = None):
        if _engine is not None:
            self._e = _engine
            self._q = dict(_quantization or {})
            return
        x = _real_array(positions, "positions")
        v = _real_array(velocities, "velocities")
        box = _real_array(box, "box")
        if box.ndim > 1 or box.size not in (1, 2):
            raise ValueError(f"box must be one length or two (2D), got shape {box.shape}")
        start = _core.lattice_quantize(x, v, [float(b) for b in np.broadcast_to(box, (2,))],
                                       _walls(boundary), diameter, _tick(tick_bits), cell_bits)
        self._init_from_start(start, law, seed)

    def _init_from_start(self, start: dict, law: str, seed: int) -> None:
        self._e = _core.LatticeEngine(start["units"], start["x"], start["v"], seed, name(law, "law"))
        self._q = {"max_position_error": start["max_position_error"],
                   "max_velocity_error": start["max_velocity_error"]}

    @classmethod
    def random(cls, n: int, dim: int = 2, phi: Optional[float] = None, *, boundary: _Boundary = "periodic",
               diameter: float = 1.0, seed: int = 1, init: str = "auto", law: str = "flux",
               tick_bits: Optional[int] = None, cell_bits: int = 16,
               packing_fraction: Optional[float] = None) -> "LatticeSimulation":
        """n disks at area fraction ``phi`` (or ``packing_fraction=``; default 0.3) in a square
        box (the float engine's ``random_state``:
        random sequential addition or a jittered lattice, Gaussian velocities with zero momentum,
        kT = 1), quantized once. The same ``seed`` keys the streams."""
        phi = _packing_fraction(phi, packing_fraction)
        if dim != 2:
            raise ValueError(f"the lattice engine is 2D, got dim={dim}")
        start = _core.lattice_random_start(n, phi, _walls(boundary), diameter, seed, name(init, "init"), _tick(tick_bits),
                                            cell_bits)
        sim = cls.__new__(cls)
        sim._init_from_start(start, law, seed)
        return sim

    # --- running ---------------------------------------------------------------------------

    def _tick(self, time: float) -> int:
        ticks = round(real(time, "time") / self._e.units["tick"])
        if not -2**62 <= ticks <= 2**62:
            raise ValueError(f"time = {time} is outside the lattice clock (|ticks| <= 2^62)")
        return int(ticks)

    def run(self, collisions: Optional[int] = None, time: Optional[float] = None) -> dict:
        """Forward until ``collisions`` more collisions (the clock then at the last one's tick)
        or the clock reaches ``time`` (rounded to a tick), whichever comes first; actions
        attached with :meth:`attach` run at their triggers. Returns collisions done, clock and
        time."""
        if collisions is None and time is None:
            raise ValueError("run needs collisions= or time=")
        until = None if time is None else self._tick(time)
        n = None if collisions is None else integer(collisions, "collisions", 0)
        attached = self._attachments()
        if not attached:
            done = int(self._e.run(n, until))
        else:  # in segments that end at the attached actions' triggers
            done, net = 0, int(self._e.collisions)
            while n is None or done < n:
                seg = self._to_next_trigger(attached, net)
                if n is not None:
                    seg = min(seg, n - done)
                did = int(self._e.run(seg, until))
                done, net = done + did, net + did
                if did:
                    self._fire(attached, net)
                if did < seg:  # the clock reached time
                    break
        return {"collisions": done, "clock": self.clock, "time": self.time}

    def run_back(self, collisions: Optional[int] = None, time: Optional[float] = None,
                 to_collision: Optional[int] = None) -> dict:
        """Backwards until ``collisions`` collisions are undone (or the count is back at
        ``to_collision``: the state the forward run had right after it, bit for bit), or the
        clock is back at ``time``, whichever comes first; with none of them, to the start."""
        target = None
        if collisions is not None:
            target = self._e.collisions - integer(collisions, "collisions", 0)
            if target < 0:
                raise ValueError(f"cannot undo {collisions} collisions: only {self._e.collisions} were run")
        if to_collision is not None:
            to_collision = integer(to_collision, "to_collision", 0)
            target = to_collision if target is None else max(target, to_collision)
        tick = None if time is None else self._tick(time)
        before = self._e.collisions
        self._e.run_back(target, tick)
        return {"collisions": int(before - self._e.collisions), "clock": self.clock, "time": self.time}

    # --- state -----------------------------------------------------------------------------

    @property
    def lattice_positions(self) -> np.ndarray:
        """Integer positions at the clock, shape (n, 2), lattice units (a copy)."""
        return self._e.positions

    @property
    def lattice_velocities(self) -> np.ndarray:
        """Integer velocities, shape (n, 2), lattice units per tick (a copy)."""
        return self._e.velocities

    @property
    def positions(self) -> np.ndarray:
        """Positions at the clock in float units, shape (n, 2)."""
        return self._e.positions.astype(float) * self._e.units["length_unit"]

    @property
    def velocities(self) -> np.ndarray:
        """Velocities in float units, shape (n, 2)."""
        u = self._e.units
        return self._e.velocities.astype(float) * (u["length_unit"] / u["tick"])

    @property
    def clock(self) -> int:
        """The integer tick."""
        return int(self._e.clock)

    @property
    def time(self) -> float:
        """The clock in float time units (clock * tick)."""
        return self._e.clock * self._e.units["tick"]

    @property
    def collisions(self) -> int:
        """Collisions since the start (forward minus undone)."""
        return int(self._e.collisions)

    @property
    def n(self) -> int:
        """Number of particles."""
        return int(self._e.n)

    @property
    def dim(self) -> int:
        """Dimension: 2."""
        return 2

    @property
    def units(self) -> dict:
        """S, sigma, L, wall, vmax, length_unit, tick."""
        return dict(self._e.units)

    @property
    def quantization(self) -> dict:
        """Max position error (in diameters) and velocity error (relative to the rms speed) of
        the one quantization of the float start."""
        return dict(self._q)

    def diagnostics(self) -> dict:
        """Energy drift (relative and in lattice units), momentum drift per axis (lattice
        units), X's bit length, rare-log entries (redraw counts, and group collisions: a third body
        within one tick; ``group_resolves``, ``group_bounces``, ``wall_groups``), redraws by reason,
        multi-body and wall-body ticks, events by type, memory, and the quantization errors."""
        d = dict(self._e.diagnostics())
        d.update(self._q)
        return d

    # --- checkpoints -----------------------------------------------------------------------

    def snapshot(self) -> dict:
        """The full state (units, positions at the clock, velocities, stream counters, X's
        words, rare log, clock, collision count) as numpy arrays and numbers."""
        s = dict(self._e.snapshot())
        s["quantization"] = dict(self._q)
        return s

    @classmethod
    def from_snapshot(cls, snapshot: dict) -> "LatticeSimulation":
        """Rebuilds from ``snapshot()``; the run resumes bit for bit."""
        st = dict(snapshot)
        q = st.pop("quantization", None)
        engine = st.get("engine", "lattice")
        if str(np.asarray(engine)) != "lattice":
            raise ValueError(f"snapshot: engine must be 'lattice', got {str(np.asarray(engine))[:40]!r}")
        if q is not None:  # the float start's quantization errors: reported, so checked
            if not isinstance(q, dict):
                raise ValueError("snapshot: quantization must be a dict of errors")
            clean = {}
            for k, val in q.items():
                try:
                    x = float(np.asarray(val))
                except (TypeError, ValueError):
                    raise ValueError(f"snapshot: quantization.{k} must be a number") from None
                if not (np.isfinite(x) and x >= 0.0):
                    raise ValueError(f"snapshot: quantization.{k} must be finite and >= 0, got {x!r}")
                clean[str(k)] = x
            q = clean
        return cls(None, None, None, _engine=_core.LatticeEngine.from_snapshot(st), _quantization=q)

    def state(self) -> dict:
        """Deprecated name of ``snapshot()``."""
        warnings.warn("LatticeSimulation.state() is now snapshot()", DeprecationWarning, stacklevel=2)
        return self.snapshot()

    @classmethod
    def from_state(cls, state: dict) -> "LatticeSimulation":
        """Deprecated name of ``from_snapshot()``."""
        warnings.warn("LatticeSimulation.from_state() is now from_snapshot()", DeprecationWarning, stacklevel=2)
        return cls.from_snapshot(state)

    def save(self, path: Union[str, os.PathLike]) -> None:
        """Writes the full state to ``path`` atomically (numpy ``.npz``; nested dicts as ``a.b`` keys)."""
        flat = {}
        for k, v in self.snapshot().items():
            if isinstance(v, dict):
                for k2, v2 in v.items():
                    flat[f"{k}.{k2}"] = np.asarray(v2)
            else:
                flat[k] = np.asarray(v)
        write_npz_atomic(path, stamped(flat, "lattice"))

    @classmethod
    def load(cls, path: Union[str, os.PathLike]) -> "LatticeSimulation":
        """Reads a state written by ``save``."""
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
        return cls.from_snapshot(st)

    def __reduce__(self):
        """Pickling (threads, process pools, ensembles): the state is ``snapshot()``, rebuilt by
        ``from_snapshot``, so an unpickled copy resumes bit for bit; ``copy.deepcopy`` too."""
        return (type(self).from_snapshot, (self.snapshot(),))

    def __repr__(self) -> str:
        return f"LatticeSimulation(n={self.n}, collisions={self.collisions}, clock={self.clock})"
