"""The event-driven engine: N hard spheres forward, and back to the start with no
per-collision memory.

Particles of one diameter D and unit mass move freely between elastic collisions in a box
[0, L_k] per axis (``boundary``, one name or one per axis: ``"periodic"``; ``"wall"``,
specular walls, v_n -> -v_n; or ``"bounce"``, bounce-back no-slip walls, v -> -v, which keep
the energy and reverse like ``"wall"`` but not the tangential momentum, e.g. a channel
``["periodic", "bounce"]``); each collision's outcome is drawn over all
permitted post-collision states by a reversible operator (exact mode, ``flux`` law by
default; ``uniform``; ``mode="paper"``, the paper's Procedures 1-2, in 2D; or
``mode="specular"``, the deterministic elastic reflection: no random number, a baseline for
benchmarks and physics checks; groups still go through the exact operator). ``run`` goes
forward; ``run_back`` negates every velocity, runs the same event search applying
``v -> -reverse(-v)`` with the generators stepping back, and negates again, so the state
returns to an earlier time without any stored history (the rare log aside, usually empty).

Random numbers: by default one Philox stream per particle, keyed ``{id, seed}``; a collision
draws from the stream of its smallest particle id (the paper's per-particle policy), so
collisions that share no particle commute. ``generator="clcg4"`` uses the paper's CLCG4
(stream ``seed * count + i``), and ``streams="single"`` one stream for the whole system
(disjoint collisions then do not commute, so round-off that swaps two of them in the
reversed run breaks the round trip: its horizon is at most per-particle's). Contacts closed within ``group_tol * D`` at one instant form one
multi-particle collision (``revcol.Collision``'s operator). Round-off grows chaotically, so
a round trip restores the start to 1e-9 only within a horizon of some collisions per
particle (docs/engine.md).

    >>> import revcol
    >>> sim = revcol.Simulation.random(n=200, dim=2, phi=0.3, seed=1)
    >>> x0, v0 = sim.positions, sim.velocities
    >>> _ = sim.run(collisions=100)
    >>> _ = sim.run_back()                  # back to the start time
    >>> bool(abs(sim.velocities - v0).max() < 1e-9)
    True
"""
from __future__ import annotations

import os
import warnings
from typing import Callable, Optional, Sequence, Union

import numpy as np

from . import _core
from ._args import diameters_arg, integer, masses_arg, names, placement, real, real_array
from ._args import packing_fraction as _packing_fraction
from ._io import read_checkpoint, write_checkpoint
from .roundtrip import divergence_text
from .simulation import SimulationBase, engine_class, register_engine

__all__ = ["Simulation"]

_Boundary = Union[str, Sequence[str]]


def _boundary_list(boundary: _Boundary) -> list:
    return names(boundary, "boundary")


class Simulation(SimulationBase):
    """N hard spheres in d = 1, 2, 3, run forward and backwards (revcol/engine/engine.hpp).

    Build from arrays (``Simulation(positions, velocities, box=...)``) or at random
    (``Simulation.random(n, dim, phi)``). Everything is validated first; a bad state raises
    ``ValueError`` naming the problem (overlap, outside the box, non-finite, zero kinetic
    energy, diameter too large, N = 0, a periodic axis under 3 diameters).

    ``generator``: ``"philox"`` (default) or ``"clcg4"``; ``streams``: ``"per-particle"``
    (default; the smallest id of a collision draws) or ``"single"``. ``diameters`` and
    ``masses`` (one per particle): a mixture; ``gravity`` (one component per axis, nonzero only
    on walled axes): a uniform field (docs/mixtures.md, docs/engine.md).

    ``engine="lattice"`` builds the lattice engine's simulation instead
    (:class:`revcol.lattice.LatticeSimulation`, or ``LatticeSimulation3D`` for (n, 3)
    positions): both are a :class:`revcol.SimulationBase`. Its ``mode`` is ``"exact"`` or
    ``"specular"`` (deterministic specular dynamics, reversed bit for bit with no draws).
    """

    engine = "float"

    def __new__(cls, *args, engine: str = "float", **kwargs):
        # engine="lattice" hands the whole call to the lattice engine (revcol.lattice: disks, or
        # spheres for (n, 3) positions), which takes the same positions, velocities, box,
        # boundary, diameter, mode (exact or specular), law and seed
        if engine != "float":
            x = np.asarray(args[0] if args else kwargs.get("positions", ()))
            return engine_class(engine, 3 if x.ndim == 2 and x.shape[1] == 3 else 2)(*args, **kwargs)
        return super().__new__(cls)

    def __init__(self, positions, velocities, box, *, engine: str = "float", boundary: _Boundary = "periodic",
                 diameter: float = 1.0, mode: str = "exact", law: str = "flux", seed: int = 1,
                 bits: int = 40, groups: bool = True, group_tol: float = 1e-9,
                 time: float = 0.0, generator: str = "philox", streams: str = "per-particle",
                 diameters=None, masses=None, gravity=None, shear_rate=None, _engine=None):
        if _engine is not None:
            self._e = _engine
            return
        if shear_rate is not None and real(shear_rate, "shear_rate") != 0.0:
            raise ValueError("shear_rate: Lees-Edwards shear runs on the lattice engine (engine='lattice'); "
                             "the float engine's is not built yet")
        x = real_array(positions, "positions")
        v = real_array(velocities, "velocities")
        if x.ndim == 1:
            x = x[:, None]
        if v.ndim == 1:
            v = v[:, None]
        sizes = diameters_arg(diameters, x.shape[0], diameter)
        if sizes:  # a mixture: the engine's diameter is the largest (its lists' and cells' size)
            diameter = max(sizes)
        weights = masses_arg(masses, x.shape[0])
        box = np.atleast_1d(real_array(box, "box")).tolist()
        # scalars go through as given: the engine names a wrong type or range (issue 17)
        self._e = _core.Engine(x, v, box, _boundary_list(boundary), diameter, mode, law,
                               seed, bits, bool(groups), group_tol, time,
                               generator, streams, sizes, weights,
                               [] if gravity is None else np.atleast_1d(real_array(gravity, "gravity")).tolist())

    @classmethod
    def random(cls, n: int, dim: int = 3, phi: Optional[float] = None, *, boundary: _Boundary = "periodic",
               diameter: float = 1.0, seed: int = 1, energy: Optional[float] = None,
               init: str = "auto", equal_speeds: bool = False, engine: str = "float",
               packing_fraction: Optional[float] = None, **kwargs) -> "Simulation":
        """n particles at packing fraction ``phi`` (or ``packing_fraction=``, the scenes' name;
        default 0.3) in a cubic box: ``init`` ``"rsa"``, random sequential addition, or
        ``"crystal"``, a jittered crystal (square in 1D/2D, face-centred cubic in 3D), or
        ``"relax"``, uniform at random with the overlaps then relaxed away (FIRE on a harmonic
        overlap energy; dense amorphous starts, mixtures up to near jamming); ``"auto"`` picks (a
        mixture: as spheres of its largest size when they fit, else relaxed; the old name
        ``"lattice"`` still works, with a DeprecationWarning); Gaussian
        velocities with zero momentum scaled to kinetic ``energy`` (default n d / 2, kT = 1), or
        all of one speed (``equal_speeds``). Other keywords go to the constructor (mode, law, ...);
        the same ``seed`` keys the collision streams. ``engine="lattice"``: the lattice engine's
        ``LatticeSimulation.random`` (dim 2) or ``LatticeSimulation3D.random`` (dim 3), reversed
        bit for bit (``mode``, ``"exact"`` or ``"specular"``, ``law`` and ``seed`` apply)."""
        phi = _packing_fraction(phi, packing_fraction)
        init = placement(init)
        n, dim = integer(n, "n", 1), integer(dim, "dim", 1, 3)  # not a bool, not 2.0 (a named error)
        if engine != "float":
            lat = engine_class(engine, dim)
            if energy is not None or equal_speeds:
                raise ValueError("engine='lattice' starts at kT = 1 with Gaussian velocities: energy and "
                                 "equal_speeds are not available")
            return lat.random(n, dim, phi, boundary=boundary, diameter=diameter, seed=seed, init=init, **kwargs)
        diameters, masses = kwargs.pop("diameters", None), kwargs.pop("masses", None)
        sizes, weights = diameters_arg(diameters, n, diameter), masses_arg(masses, n)
        if weights and equal_speeds:
            raise ValueError("equal_speeds and masses: give one (with masses the speeds follow equipartition)")
        x, v, box = _core.engine_random_state(dim, n, phi, _boundary_list(boundary), diameter, seed,
                                              energy if energy is not None else 0.0, init,
                                              bool(equal_speeds), sizes, weights)
        size = dict(diameters=sizes) if sizes else dict(diameter=diameter)
        return cls(x, v, box, boundary=boundary, seed=seed, masses=weights or None, **size, **kwargs)

    # --- running -------------------------------------------------------------------------

    def run(self, collisions: Optional[int] = None, time: Optional[float] = None,
            callback: Optional[Callable[[int], object]] = None, every: int = 10000) -> dict:
        """Forward until ``collisions`` more collisions or the clock reaches ``time``,
        whichever comes first, ending between events. ``callback(done)`` is called every
        ``every`` collisions; returning False stops the run. Actions attached with
        :meth:`attach` run at their triggers. Returns collisions, events, time, interrupted."""
        # checked before the first event: a bad argument must not leave collisions done (issue 17)
        if callback is not None and not callable(callback):
            raise TypeError(f"callback must be callable, got {type(callback).__name__}")
        cb = None
        if callback is not None:
            cb = lambda k: bool(callback(k) is not False)  # None means go on
        attached = self._attachments()
        if not attached or (collisions is None and time is None):
            return self._e.run(collisions, time, cb, every)
        return self._run_triggered(integer(collisions, "collisions", lo=0) if collisions is not None else None,
                                   time, cb, every, attached)

    def _run_triggered(self, collisions: Optional[int], time, cb, every, attached) -> dict:
        """``run`` in segments that end at the attached actions' triggers and, with a callback,
        at each multiple of ``every`` (so that the callback sees this call's count, as without
        attachments)."""
        every = integer(every, "every", lo=1)
        done, events, out = 0, 0, None
        net = int(self._e.diagnostics()["net_collisions"])
        while True:
            seg = self._to_next_trigger(attached, net)
            if cb is not None:
                seg = min(seg, (done // every + 1) * every - done)
            if collisions is not None:
                seg = min(seg, collisions - done)
            out = dict(self._e.run(seg, time, None, every))
            did = int(out["collisions"])
            done, events, net = done + did, events + int(out["events"]), net + did
            if did:
                self._fire(attached, net)
            if cb is not None and did and done % every == 0 and not cb(done):
                out["interrupted"] = True
            if out["interrupted"] or did < seg or (collisions is not None and done >= collisions):
                break
        out["collisions"], out["events"] = done, events
        return out

    def run_back(self, collisions: Optional[int] = None, time: Optional[float] = None,
                 on_divergence: str = "warn") -> dict:
        """Backwards: until ``collisions`` collisions are undone or the clock is back at
        ``time`` (finite; it may be before the start); without ``time``, never past the start
        time. Returns collisions, events, time, interrupted, diverged.

        A float run reverses only within its round-off horizon (docs/engine.md). The collision
        trace checks, without a log, that the collisions undone are the ones done and that
        energy and momentum keep their values (``diagnostics()["diverged_at"]``,
        docs/robustness.md). ``on_divergence``: ``"warn"`` (default) runs on to the target and
        warns (``RuntimeWarning``) when this call finds the reversal off the forward
        trajectory; ``"stop"`` stops there and warns; ``"ignore"`` runs on silently (the result's
        ``diverged`` still says so)."""
        if on_divergence not in ("warn", "stop", "ignore"):
            raise ValueError(f"on_divergence must be 'warn', 'stop' or 'ignore', got {on_divergence!r}")
        r = self._e.run_back(collisions, time, on_divergence == "stop")
        if r["diverged"] and on_divergence != "ignore":
            d = self._e.diagnostics()
            warnings.warn("run_back diverged " + divergence_text(d) + " (beyond the round-off horizon, "
                          "docs/engine.md)", RuntimeWarning, stacklevel=2)
        return r

    # --- state ---------------------------------------------------------------------------

    @property
    def positions(self) -> np.ndarray:
        """Positions at the current time, shape (n, dim) (a copy)."""
        return self._e.positions

    @property
    def velocities(self) -> np.ndarray:
        """Velocities, shape (n, dim) (a copy)."""
        return self._e.velocities

    @property
    def collision_counts(self) -> np.ndarray:
        """Collisions each particle took part in (both directions counted)."""
        return self._e.collision_counts

    @property
    def time(self) -> float:
        """The clock."""
        return self._e.time

    @property
    def start_time(self) -> float:
        """The time the simulation was built at."""
        return self._e.start_time

    @property
    def n(self) -> int:
        """Number of particles."""
        return self._e.n

    @property
    def dim(self) -> int:
        """Dimension d."""
        return self._e.dim

    @property
    def box(self) -> np.ndarray:
        """Box lengths L_k, shape (dim,): the box is [0, L_k] per axis."""
        return np.asarray(self._e.box, dtype=float)

    @property
    def periodic(self) -> tuple:
        """Per axis, whether it is periodic (else walls at 0 and L_k: ``"wall"`` or ``"bounce"``)."""
        return tuple(bool(p) for p in self._e.periodic)

    @property
    def boundary(self) -> tuple:
        """Per axis its kind: ``"periodic"``, ``"wall"`` or ``"bounce"``."""
        return tuple(self._e.boundary)

    @property
    def collisions(self) -> int:
        """Net collisions since the start (forward less undone)."""
        return int(self._e.diagnostics()["net_collisions"])

    @property
    def diameters(self) -> np.ndarray:
        """Each particle's diameter, shape (n,) (one size: all ``diameter``)."""
        d = np.asarray(self._e.diameters, dtype=float)
        return d if d.size else np.full(self.n, float(self._e.diameter))

    mixture = property(lambda self: bool(len(self._e.diameters)),
                       doc="True for a mixture (built with ``diameters``; sizes kept per particle).")

    @property
    def gravity(self) -> np.ndarray:
        """The uniform field (acceleration), shape (dim,): zero unless built with ``gravity``."""
        return np.asarray(self._e.gravity, dtype=float)

    @property
    def masses(self) -> np.ndarray:
        """Each particle's mass, shape (n,) (all 1 unless built with ``masses``)."""
        m = np.asarray(self._e.masses, dtype=float)
        return m if m.size else np.ones(self.n)

    def diagnostics(self) -> dict:
        """Energy and momentum (and their drift from the start), rare-log bytes, collisions
        per particle, events by type."""
        return self._e.diagnostics()

    # --- checkpoints ---------------------------------------------------------------------

    def snapshot(self) -> dict:
        """The full state (positions, velocities, local times, list centres, stamps,
        per-stream generator counters, scheduled events, keyed logs, counters) as numpy
        arrays and scalars: ``Simulation.from_snapshot`` resumes it bit for bit."""
        return self._e.snapshot()

    @classmethod
    def from_snapshot(cls, snapshot: dict) -> "Simulation":
        """Rebuilds from ``snapshot()``; the run resumes bit for bit."""
        return cls(None, None, None, _engine=_core.Engine.from_snapshot(dict(snapshot)))

    def save(self, path: Union[str, os.PathLike]) -> None:
        """Writes the full state to ``path`` atomically (numpy ``.npz``, stamped, with a SHA-256
        digest of its entries that ``load`` checks: :func:`revcol._io.write_checkpoint`). A state
        no run can continue (particles overlapping after a ``run_back`` that left the forward
        trajectory) raises ``ValueError`` and writes nothing: ``load`` would refuse it."""
        fault = self._e.fault()
        if fault:
            d = self._e.diagnostics()
            why = (f"; run_back diverged at forward collision {d['diverged_at']:,} ({d['divergence']})"
                   if d["divergence"] != "none" else "")
            raise ValueError(f"cannot save {os.fspath(path)!r}: {fault}{why}. No run continues from this state, so no "
                             "checkpoint of it is written: go back to an earlier checkpoint")
        write_checkpoint(path, self.snapshot(), "float")

    @classmethod
    def load(cls, path: Union[str, os.PathLike]) -> "Simulation":
        """Reads a state written by ``save``. A file whose digest does not match its entries raises
        ``ValueError("checkpoint corrupted: digest mismatch in '<path>' ...")``; one written before
        digests loads unchecked."""
        st = {k: (a.item() if a.ndim == 0 else a) for k, a in read_checkpoint(path, "float").items()}
        return cls.from_snapshot(st)

    def __repr__(self) -> str:
        return f"Simulation(n={self.n}, dim={self.dim}, time={self.time:.6g})"


register_engine("float", lambda dim: Simulation)
