"""The lattice engine: a randomized hard-disk (2D, ``LatticeSimulation``) or hard-sphere (3D,
``LatticeSimulation3D``) gas reversed bit for bit, for any number of collisions, with memory that
does not grow with them (revcol/lattice/engine.hpp, LATTICE.md).

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

``mode="specular"`` runs deterministic specular hard-sphere dynamics instead: each pair
collision reflects the relative velocity about the contact normal with an exact integer
involution (the momentum exact, the energy to a few lattice units), carrying the sub-tick phase
across; no random number is drawn and X does not change, and the run is still reversed bit for
bit (docs/specular.md). The rare log holds the rare cases: group collisions (a third body within
one tick) and, rarer, a post centre beyond a wall within the tick, drawn by the randomized
operator (``diagnostics()["drawn_fallbacks"]``).

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
from typing import Optional, Union

import numpy as np

from . import _core
from ._args import diameters_arg, integer, name, placement, real, real_array
from ._args import packing_fraction as _packing_fraction
from ._io import write_checkpoint
from ._lattice_args import MODES, _Boundary, _boundary, _gravity, _mode, _shear, _shell, _tick
from ._lattice_state import (add_reports, legacy_snapshot as _legacy_snapshot, read_state as _read_state,
                             snapshot_shell as _snapshot_shell)
from .simulation import SimulationBase, register_engine

__all__ = ["LatticeSimulation", "LatticeSimulation3D", "MODES", "restart_from_legacy"]

# the binding's engine class and start functions per dimension
_ENGINE = {2: "LatticeEngine", 3: "LatticeEngine3D"}
_RANDOM_START = {2: "lattice_random_start", 3: "lattice3d_random_start"}
_QUANTIZE = {2: "lattice_quantize", 3: "lattice3d_quantize"}


class LatticeSimulation(SimulationBase):
    """N hard disks on the integer lattice, run forward and back bit for bit (2D; spheres in 3D:
    :class:`LatticeSimulation3D`, the same API).

    Build from float arrays (``LatticeSimulation(positions, velocities, box)``, quantized once)
    or at random (``LatticeSimulation.random(n, phi=...)``, the float engine's initialiser then
    quantized). ``boundary``: ``"periodic"``, ``"wall"`` (specular) or ``"bounce"`` (bounce-back, v -> -v,
    as the float engine's), one name or one per axis. ``mode``: ``"exact"`` (default: the
    randomized pair operator, reversed bit for bit through its draws and the bits-back integer)
    or ``"specular"`` (deterministic specular hard-sphere dynamics, bit-reversible with no random
    numbers: the relative velocity reflected about the contact normal by an exact integer
    involution; nothing drawn but the rare logged fallback; docs/specular.md). ``law`` (exact mode only):
    ``"flux"`` (default) or ``"uniform"``. ``seed`` keys the Philox streams ``{particle, seed}`` and each
    particle's bits-back integer X (its first 128 bits). ``tick_bits`` T (16..26; default ``None``: automatic): a particle of rms speed
    moves 2^-T diameters per tick; a finer tick (larger T) makes redraws and group collisions (a
    third body within one tick) rarer at the cost of fewer bits of velocity resolution (2^(S-T)
    units for the rms speed, S set by the box). The automatic tick keeps 30 bits:
    T = clamp(S - 30, 16, 24) (docs/lattice.md). ``cell_bits`` (12..20, default 16): the pair operator
    cuts directions into 2^cell_bits equal-angle cells per turn; fewer cells make the lifting
    rotation's read-back redraws rarer (docs/lattice.md). ``search``: the neighbour search,
    ``"auto"`` (default: neighbour lists in 3D, the cell grid in 2D), ``"cells"`` (the cell
    grid) or neighbour lists with a shell of that many diameters (a float in [0.02, 2]); it
    changes the speed only, never which collisions happen (the state is the same bit for bit),
    and it is kept in snapshots and checkpoints. ``workers`` (1..64) and ``lps``: run forward on
    the parallel engine, K threads and slabs, the same bits (:meth:`set_parallel`,
    docs/parallel.md). ``diameters`` (one per particle; instead of ``diameter``): a mixture of
    equal masses, binary, ternary or polydisperse (a pair meets at the sum of its radii; the
    largest diameter is the lattice's sigma and the others, within a ratio of 16, are quantized to
    even lattice lengths; docs/mixtures.md). ``gravity`` (one component per axis, nonzero on one
    walled axis): a uniform field, exact on the lattice (quantized once to an even number of lattice
    units per tick^2, :attr:`gravity` the value run and ``quantization()["gravity_error"]`` the
    rounding; the cell grid searches; no journal or parallel run yet; :meth:`observe` follows the
    parabolas between events: a column's density profile from its slabs; docs/engine.md).
    ``shear_rate``: Lees-Edwards shear, exact on the lattice: the flow along axis 0, the gradient
    along axis 1 (both periodic), the box above moving ``shear_rate * box[1]`` faster (quantized
    once to lattice units per tick, :attr:`shear_rate` the value run and
    ``quantization()["shear_error"]`` the rounding; the cell grid searches; no journal or parallel
    run yet; energy grows by viscous heating; :meth:`observe` gives the shear stress, the viscosity
    and, with slabs along axis 1, the velocity profile; docs/shear.md).
    Bad input raises ``ValueError`` naming the problem.
    """

    _DIM = 2  # LatticeSimulation3D: 3
    engine = "lattice"

    def __init__(self, positions, velocities, box, *, boundary: _Boundary = "periodic",
                 diameter: float = 1.0, mode: str = "exact", law: str = "flux", seed: int = 1,
                 tick_bits: Optional[int] = None, cell_bits: int = 16, search: Union[str, float] = "auto",
                 workers: int = 1, lps: Optional[int] = None, diameters=None, gravity=None, shear_rate=None,
                 _engine=None, _quantization: Optional[dict] = None):
        if _engine is not None:
            self._e = _engine
            self._q = dict(_quantization or {})
            self._search = -1.0
            self.set_parallel(workers, lps=lps)
            return
        self.set_parallel(workers, lps=lps)  # (checked before anything is built)
        mode = _mode(mode, law)
        shell = _shell(search)
        x = real_array(positions, "positions")
        v = real_array(velocities, "velocities")
        box = real_array(box, "box")
        dim = self._DIM
        if dim == 2 and (box.ndim > 1 or box.size not in (1, 2)):
            raise ValueError(f"box must be one length or two (2D), got shape {box.shape}")
        if dim == 3 and (box.ndim > 1 or box.size not in (1, 3)):
            raise ValueError(f"box must be one length or three (3D), got shape {box.shape}")
        sizes = diameters_arg(diameters, x.shape[0] if x.ndim == 2 else -1, diameter)
        start = getattr(_core, _QUANTIZE[dim])(x, v, [float(b) for b in np.broadcast_to(box, (dim,))],
                                               _boundary(boundary), diameter, _tick(tick_bits), cell_bits, sizes,
                                               _gravity(gravity, dim, workers), _shear(shear_rate, workers))
        self._init_from_start(start, law, seed, dim, shell, mode)

    def _init_from_start(self, start: dict, law: str, seed: int, dim: int = 2, shell: float = -1.0,
                         mode: str = "exact") -> None:
        engine = getattr(_core, _ENGINE[dim])
        self._e = engine(start["units"], start["x"], start["v"], seed, name(law, "law"), mode=mode,
                         radius=start["radius"])
        self._q = {"max_position_error": start["max_position_error"],
                   "max_velocity_error": start["max_velocity_error"]}
        if any(start["units"].get("gravity", ())):
            self._q["gravity_error"] = start["gravity_error"]
        if start["units"].get("shear", 0):
            self._q["shear_error"] = start["shear_error"]
        self._search = -1.0
        self._set_shell(shell)

    def _set_shell(self, shell: float) -> None:
        """The engine's neighbour search (its list shell; -1 automatic, the engine's default)."""
        if shell != self._search:
            self._e.set_search(shell)
        self._search = shell

    @classmethod
    def random(cls, n: int, dim: Optional[int] = None, phi: Optional[float] = None, *, boundary: _Boundary = "periodic",
               diameter: float = 1.0, seed: int = 1, init: str = "auto", mode: str = "exact", law: str = "flux",
               tick_bits: Optional[int] = None, cell_bits: int = 16, search: Union[str, float] = "auto",
               packing_fraction: Optional[float] = None, workers: int = 1, lps: Optional[int] = None,
               diameters=None, gravity=None, shear_rate=None) -> "LatticeSimulation":
        """n disks (spheres for LatticeSimulation3D) at area (volume) fraction ``phi`` (or
        ``packing_fraction=``; default 0.3) in a square (cubic) box (the float engine's
        ``random_state``: ``init`` ``"rsa"``, random sequential addition, ``"crystal"``, a
        jittered crystal, square in 2D and face-centred cubic in 3D, or ``"relax"``, uniform with
        the overlaps relaxed away; ``"auto"`` picks; the old
        name ``"lattice"`` still works, with a DeprecationWarning; Gaussian velocities with zero
        momentum, kT = 1), quantized once. The same ``seed`` keys the streams. ``dim`` (default:
        the class's, 2 or 3) must be the class's; the other keywords (``mode``, ``law``, ...) as
        the constructor's. ``diameters`` (one per particle): a mixture at packing fraction
        ``phi`` (the particles' own volumes), placed as spheres of the largest diameter when they
        fit so, else (``"auto"``, or ``"relax"`` always) at random at their own sizes with the
        overlaps relaxed away, up to near the mixture's jamming (a 1:1 mixture of size ratio 1.4:
        about 0.84 in 2D, 0.64 in 3D). ``gravity``: a uniform field, as the
        constructor's (the particles placed uniformly, then left to fall). ``shear_rate``:
        Lees-Edwards shear, as the constructor's, the velocities along axis 0 given the steady
        profile ``shear_rate * (y - mean(y))`` (no momentum added)."""
        n = integer(n, "n", 1)  # not a bool or a float (a named error)
        if dim is not None:
            dim = integer(dim, "dim", 1, 3)
        phi = _packing_fraction(phi, packing_fraction)
        mode = _mode(mode, law)
        init = placement(init)
        shell = _shell(search)
        dim = cls._DIM if dim is None else dim
        if dim != cls._DIM:
            if cls._DIM == 2:
                raise ValueError(f"LatticeSimulation is the 2D class, got dim={dim} (spheres: LatticeSimulation3D, or "
                                 "Simulation.random(dim=3, engine='lattice'))")
            raise ValueError(f"LatticeSimulation3D is 3D, got dim={dim}")
        sizes = diameters_arg(diameters, n, diameter)
        start = getattr(_core, _RANDOM_START[dim])(n, phi, _boundary(boundary), diameter, seed, init,
                                                   _tick(tick_bits), cell_bits, sizes, _gravity(gravity, dim, workers),
                                                   _shear(shear_rate, workers))
        sim = cls.__new__(cls)
        sim.set_parallel(workers, lps=lps)
        sim._init_from_start(start, law, seed, dim, shell, mode)
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
        self._report = None
        if not attached:
            done = self._advance(n, until)
        else:  # in segments that end at the attached actions' triggers
            done, net = 0, int(self._e.collisions)
            while n is None or done < n:
                seg = self._to_next_trigger(attached, net)
                if n is not None:
                    seg = min(seg, n - done)
                did = self._advance(seg, until)
                done, net = done + did, net + did
                if did:
                    self._fire(attached, net)
                if did < seg:  # the clock reached time
                    break
        out = {"collisions": done, "clock": self.clock, "time": self.time}
        if self._report is not None:
            out["parallel"] = dict(self._report)
        return out

    def _advance(self, n: Optional[int], until: Optional[int]) -> int:
        """One run of the engine: sequential, or (set_parallel) on the parallel engine, whose
        reports add up in ``self._report``."""
        if self._par["lps"] == 1:
            return int(self._e.run(n, until))
        r = dict(self._e.run_parallel(n, until, **self._par))
        self._report = add_reports(self._report, r)
        return int(r["collisions"])

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
        out: dict = {}
        if self._par["lps"] == 1:
            self._e.run_back(target, tick)
        else:  # the parallel engine, in run_back's reversed frame
            out["parallel"] = self._report = dict(self._e.run_back_parallel(target, tick, **self._par))
        return {"collisions": int(before - self._e.collisions), "clock": self.clock, "time": self.time, **out}

    # --- the parallel engine ------------------------------------------------------------------

    def set_parallel(self, workers: int = 1, *, lps: Optional[int] = None, axis: int = 0, rollback: str = "reverse",
                     lazy: bool = True, window: int = 0) -> None:
        """Runs forward on the parallel engine (docs/parallel.md): the box cut into ``lps``
        slabs along ``axis`` (default: one per worker), each a logical process of Time Warp,
        run by ``workers`` threads without the GIL; a straggler is rolled back by the engine's
        own reverse computation (``rollback="reverse"``) or, for the comparison, by state saving
        (``"save_all"``, SS1, or ``"save_changes"``, SS2). ``lazy``: lazy cancellation (else
        anti-messages at once); ``window``: no event more than that many ticks past GVT (0:
        none). ``run`` then reaches the state the sequential engine reaches, bit for bit, and
        returns the run's ``"parallel"`` report (also :attr:`parallel_report`): collisions
        committed by the parallel engine and by the sequential one (a stop at a collision count
        is reached by a short sequential probe and tail, and runs of at most max(8192, n/4)
        collisions stay sequential), events processed, rollbacks, undone events, messages,
        anti-messages, per-LP events. ``run_back`` runs on the parallel engine too, in the
        reversed frame (rolled back by reverse computation whatever ``rollback`` says: an undone
        back step is its forward collision computed again), and reaches the sequential
        ``run_back``'s state bit for bit; its report is the ``"parallel"`` entry of what it
        returns. Checkpoints and the rest are the sequential engine's (the state is its own).
        The settings are not part of the state: a snapshot,
        checkpoint or pickle holds none, and a simulation rebuilt from one runs on the
        sequential engine until ``set_parallel`` (any K: the bits are the same). ``workers=1``
        with ``lps`` None is the sequential engine. A running observation (:meth:`observe`)
        sees the committed events and is the sequential run's bit for bit."""
        workers = integer(workers, "workers", 1, 64)
        k = workers if lps is None else integer(lps, "lps", 1, 64)
        if workers > k:
            raise ValueError(f"workers must be at most lps (the logical processes), got workers={workers} > lps={k}")
        axis = integer(axis, "axis", 0, self._DIM - 1)
        if k > 1 and hasattr(self, "_e") and self.gravity[axis] != 0.0:
            raise ValueError(f"axis: a gas in a field is cut across the field, not along it (the field is along "
                             f"axis {axis}): choose another axis for the slabs")
        rollback = name(rollback, "rollback")
        if rollback not in ("reverse", "save_all", "save_changes"):
            raise ValueError(f"rollback must be 'reverse', 'save_all' (SS1) or 'save_changes' (SS2), not {rollback!r}")
        if not isinstance(lazy, (bool, np.bool_)):
            raise ValueError(f"lazy must be True or False, got {lazy!r}")
        window = integer(window, "window", 0)
        self._par = {"lps": k, "workers": workers, "axis": axis, "rollback": rollback, "lazy": bool(lazy), "window": window}
        self._report = None

    @property
    def parallel(self) -> dict:
        """The parallel engine's settings (:meth:`set_parallel`; ``lps`` 1: the sequential engine)."""
        return dict(self._par)

    @property
    def workers(self) -> int:
        """The worker threads of a run (1: the sequential engine, unless ``lps`` > 1)."""
        return int(self._par["workers"])

    @property
    def parallel_report(self) -> Optional[dict]:
        """The last run's (or run back's) report on the parallel engine (None after a sequential run)."""
        return None if self._report is None else dict(self._report)

    # --- rollback: the journal of processed events ------------------------------------------

    def keep_journal(self, on: bool = True, by: str = "reverse") -> None:
        """Keeps (or stops keeping) the journal of the events processed from the current
        state on, 24 bytes per event: :meth:`rollback` then undoes the latest events one by one,
        each by its own reverse computation (nothing of the state is saved), in time
        proportional to the events undone. The journal starts afresh at the state whenever the
        search is rebuilt (``load``, ``run_back``, setting ``search``). ``by``: ``"reverse"``
        (reverse computation), or state saving for the comparison: ``"save_all"`` (SS1, each
        touched particle's whole record before every event) or ``"save_changes"`` (SS2, only the
        lines and X an event changes)."""
        self._e.keep_journal(bool(on), name(by, "by"))

    @property
    def journal(self) -> dict:
        """The journal: ``on``, ``start`` (the collision count rollback reaches back to),
        ``start_clock``, ``size`` (events held) and ``bytes`` (its memory)."""
        e = self._e
        return {"on": bool(e.journaling), "start": int(e.journal_start), "start_clock": int(e.journal_start_tick),
                "size": int(e.journal_size), "bytes": int(e.journal_bytes)}

    def rollback(self, to_collision: Optional[int] = None, time: Optional[float] = None) -> dict:
        """Undoes the journal's latest events: back to the state right after collision
        ``to_collision``, or to ``time`` (rounded to a tick), bit for bit the state the forward
        run had there. Needs :meth:`keep_journal`; no further back than ``journal["start"]``."""
        if (to_collision is None) == (time is None):
            raise ValueError("rollback needs one of to_collision= and time=")
        before = self._e.collisions
        if to_collision is not None:
            self._e.rollback(integer(to_collision, "to_collision", 0), None)
        else:
            self._e.rollback(None, self._tick(time))
        return {"collisions": int(before - self._e.collisions), "clock": self.clock, "time": self.time}

    def commit(self, to_collision: int) -> None:
        """Forgets the journal up to collision ``to_collision``: rollback goes no further back,
        and the journal's memory is freed."""
        self._e.commit(integer(to_collision, "to_collision", 0))

    # --- state -----------------------------------------------------------------------------

    @property
    def lattice_positions(self) -> np.ndarray:
        """Integer positions at the clock, shape (n, dim), lattice units (a copy)."""
        return self._e.positions

    @property
    def lattice_velocities(self) -> np.ndarray:
        """Integer velocities, shape (n, dim), lattice units per tick (a copy)."""
        return self._e.velocities

    @property
    def positions(self) -> np.ndarray:
        """Positions at the clock in float units, shape (n, dim)."""
        return self._e.positions.astype(float) * self._e.units["length_unit"]

    @property
    def velocities(self) -> np.ndarray:
        """Velocities in float units, shape (n, dim)."""
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
        """Dimension: 2 (3 for LatticeSimulation3D)."""
        return self._DIM

    @property
    def box(self) -> np.ndarray:
        """Box lengths in float units, shape (dim,) (``Simulation.box``)."""
        u = self._e.units
        return np.asarray(u["L"], dtype=float) * float(u["length_unit"])

    @property
    def boundary(self) -> tuple:
        """Per axis its kind: ``"periodic"``, ``"wall"`` or ``"bounce"``."""
        return tuple(self._e.units["boundary"])

    @property
    def mode(self) -> str:
        """``"exact"`` (the randomized pair operator) or ``"specular"`` (deterministic specular
        dynamics, no draws); kept in snapshots and checkpoints."""
        return str(self._e.mode)

    @property
    def units(self) -> dict:
        """S, sigma, L, boundary (per axis its kind), wall (per axis: walls), vmax, length_unit, tick."""
        return dict(self._e.units)

    @property
    def radii(self) -> np.ndarray:
        """Each particle's radius in lattice units (int64, by id; a pair meets at the sum of two)."""
        r = np.asarray(self._e.radius, dtype=np.int64)
        return r if r.size else np.full(self.n, int(self._e.units["sigma"]) // 2, dtype=np.int64)

    @property
    def diameters(self) -> np.ndarray:
        """Each particle's diameter in float units (2 radii x length_unit), shape (n,)."""
        return 2.0 * self.radii.astype(float) * float(self._e.units["length_unit"])

    @property
    def gravity(self) -> np.ndarray:
        """The uniform field run (acceleration in float units), shape (dim,): the lattice's even
        integer per tick^2 times length_unit / tick^2; zero without a field."""
        u = self._e.units
        g = np.asarray(u.get("gravity", (0,) * self._DIM), dtype=float)
        return g * (float(u["length_unit"]) / float(u["tick"]) ** 2)

    @property
    def shear_rate(self) -> float:
        """The Lees-Edwards shear rate run (1 / time, float units): the lattice's integer shear
        (lattice units per tick) over the box's gradient length; 0 without shear."""
        u = self._e.units
        return float(u.get("shear", 0)) / (float(u["L"][1]) * float(u["tick"]))

    mixture = property(lambda self: bool(np.asarray(self._e.radius).size),
                       doc="True for a mixture (built with ``diameters``; sizes kept per particle).")

    @property
    def search(self) -> Union[str, float]:
        """The neighbour search in use: ``"cells"`` (the cell grid) or the neighbour lists' shell
        in diameters (a float, the asked one on the lattice's integer radius); ``"auto"`` has
        resolved to one of them (lists in 3D, cells in 2D). Setting it (``"auto"``, ``"cells"``
        or a shell in [0.02, 2]) changes the speed only: the run is the same bit for bit."""
        shell = float(self._e.list_shell)
        return "cells" if shell == 0.0 else shell

    @search.setter
    def search(self, search: Union[str, float]) -> None:
        self._set_shell(_shell(search))

    @property
    def quantization(self) -> dict:
        """Max position error (in diameters) and velocity error (relative to the rms speed) of
        the one quantization of the float start."""
        return dict(self._q)

    def diagnostics(self) -> dict:
        """Energy drift (relative and in lattice units), momentum drift per axis (lattice
        units), X's bit length, rare-log entries (redraw counts, and group collisions: a third body
        within one tick; ``group_resolves``, ``group_bounces``, ``wall_groups``), redraws by reason,
        ``backscatters`` (specular mode: pairs turned back in place, a rare case; 0 in exact
        mode), multi-body and wall-body ticks, events by type, memory, and the quantization
        errors."""
        d = dict(self._e.diagnostics())
        d.update(self._q)
        return d

    # --- checkpoints -----------------------------------------------------------------------

    def snapshot(self) -> dict:
        """The full state (units, mode, positions at the clock, velocities, stream counters, X's
        words, rare log, clock, collision count) as numpy arrays and numbers, and the neighbour
        search asked (``"search"``: the list shell in diameters, -1 automatic, 0 the cell grid)."""
        s = dict(self._e.snapshot())
        s["quantization"] = dict(self._q)
        s["search"] = self._search
        return s

    @classmethod
    def from_snapshot(cls, snapshot: dict) -> "LatticeSimulation":
        """Rebuilds from ``snapshot()``; the run resumes bit for bit, in the snapshot's mode (one
        written before specular mode existed has no ``mode`` and is exact). A 3D snapshot (``dim``
        3) gives a LatticeSimulation3D whichever class is asked."""
        st = dict(snapshot)
        q = st.pop("quantization", None)
        shell = _snapshot_shell(st.pop("search", -1.0))  # written before it existed: automatic
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
        dim = int(np.asarray(st.get("dim", 2)))
        if dim not in (2, 3):
            raise ValueError(f"snapshot: dim must be 2 or 3, got {dim}")
        engine_class = getattr(_core, _ENGINE[dim])
        out = LatticeSimulation3D if dim == 3 else LatticeSimulation
        sim = out(None, None, None, _engine=engine_class.from_snapshot(st), _quantization=q)
        sim._set_shell(shell)
        return sim

    def save(self, path: Union[str, os.PathLike]) -> None:
        """Writes the full state to ``path`` atomically (numpy ``.npz``; nested dicts as ``a.b`` keys;
        stamped, with a SHA-256 digest of its entries that ``load`` checks:
        :func:`revcol._io.write_checkpoint`)."""
        flat = {}
        for k, v in self.snapshot().items():
            if isinstance(v, dict):
                for k2, v2 in v.items():
                    flat[f"{k}.{k2}"] = np.asarray(v2)
            else:
                flat[k] = np.asarray(v)
        write_checkpoint(path, flat, "lattice")

    @classmethod
    def load(cls, path: Union[str, os.PathLike]) -> "LatticeSimulation":
        """Reads a state written by ``save``. A file whose digest does not match its entries raises
        ``ValueError("checkpoint corrupted: digest mismatch in '<path>' ...")`` (one written before
        digests loads unchecked). A checkpoint of an older revcol (one bits-back integer for the
        whole gas) is refused: :func:`restart_from_legacy` starts a new run from it."""
        return cls.from_snapshot(_read_state(path))

    def __repr__(self) -> str:
        return f"{type(self).__name__}(n={self.n}, collisions={self.collisions}, clock={self.clock})"


def restart_from_legacy(source: Union[str, os.PathLike, dict]) -> "LatticeSimulation":
    """A new run from a checkpoint (path or snapshot dict) of a revcol that kept one bits-back
    integer for the whole gas and keyed its rare log by the global collision index. Such a state
    cannot resume bit for bit here (its draws and its reverse's keys are the old layout's), so this
    keeps its physical state (positions, velocities, clock, stream counters, units, mode, seed)
    and starts afresh at its clock: origin = clock, no collisions, every X its initial bits
    (:func:`revcol._core.lattice_initial_bits`), an empty rare log; the run cannot go back before
    it. A checkpoint of this version raises ``ValueError`` (load it with ``load``)."""
    return LatticeSimulation.from_snapshot(_legacy_snapshot(source))


class LatticeSimulation3D(LatticeSimulation):
    """N hard spheres on the integer lattice, run forward and back bit for bit: the 3D lattice
    engine (``LatticeEngine3D``), with :class:`LatticeSimulation`'s API.

    Build from (n, 3) float arrays and one or three box lengths
    (``LatticeSimulation3D(positions, velocities, box)``) or at random
    (``LatticeSimulation3D.random(n, phi=...)``: the float engine's 3D ``random_state``, random
    sequential addition up to a volume fraction 0.2, else a jittered face-centred cubic
    crystal). ``boundary``:
    one name or three. The exact mode's pair operator is ``LatticePair3D`` (the polar angle by
    whole-cell lifting rotations, the azimuth by bits-back over the exact rows of its cell;
    docs/lattice.md); ``cell_bits`` sets its 2^cell_bits polar cells per turn. ``mode="specular"``
    runs deterministic specular sphere dynamics (no draws), reversed bit for bit as well. Snapshots carry
    ``dim`` = 3 and (n, 3) arrays.

        >>> from revcol.lattice import LatticeSimulation3D
        >>> sim = LatticeSimulation3D.random(n=100, phi=0.3, seed=1)
        >>> x0 = sim.lattice_positions
        >>> _ = sim.run(collisions=1000)
        >>> _ = sim.run_back()
        >>> bool((sim.lattice_positions == x0).all())
        True
    """

    _DIM = 3


register_engine("lattice", lambda dim: LatticeSimulation3D if dim == 3 else LatticeSimulation)
