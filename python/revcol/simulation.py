"""The one simulation API of both engines.

``revcol.Simulation`` (the float engine) and ``revcol.lattice.LatticeSimulation`` /
``LatticeSimulation3D`` (the lattice engine, reversed bit for bit) are both a
:class:`SimulationBase`: the same constructor arguments for the state (positions,
velocities, box, ``boundary``, ``diameter``, ``law``, ``seed``), the same ``random``, ``run``,
``run_back``, state properties, observation (``observe``, :mod:`revcol.observe`), attached
actions (``attach``), checkpoints (``snapshot``, ``save``, ``load``) and pickling. Each engine
adds its own options (the float engine's ``groups``, ``generator``; the lattice's
``tick_bits``, ``cell_bits``, ``search``) and readings (the lattice's integer state). Both take
``mode``: the float engine ``"exact"``, ``"paper"`` or ``"specular"``, the lattice ``"exact"``
or ``"specular"`` (deterministic specular dynamics, reversed bit for bit with no draws).

``Simulation(..., engine="lattice")`` and ``Simulation.random(..., engine="lattice")`` build
the lattice engine's class through the registry below, which each engine's module fills in
when ``revcol`` is imported: neither engine's module imports the other.

    >>> import revcol
    >>> sims = [revcol.Simulation.random(n=100, dim=2, phi=0.3, seed=1, engine=e) for e in ("float", "lattice")]
    >>> all(isinstance(s, revcol.SimulationBase) for s in sims)
    True
    >>> [s.run(collisions=500)["collisions"] for s in sims]
    [500, 500]
"""
from __future__ import annotations

import abc
import os
from typing import Callable, Dict, Union

import numpy as np

from ._attach import Attachable
from .observe import Observing

__all__ = ["SimulationBase", "ENGINES", "register_engine", "engine_class"]

#: the engines a simulation can run on: "float" (any d; exact, paper and specular modes;
#: reverses within a round-off horizon) and "lattice" (d = 2, 3; exact and specular modes;
#: integer state; reverses bit for bit at any length)
ENGINES = ("float", "lattice")

# engine name -> a function of the dimension giving its class (filled in by engine.py, lattice.py)
_REGISTRY: Dict[str, Callable[[int], type]] = {}


def register_engine(engine: str, class_for_dim: Callable[[int], type]) -> None:
    """Registers an engine's simulation class (a function of the dimension)."""
    if engine not in ENGINES:
        raise ValueError(f"engine must be one of {ENGINES}, got {engine!r}")
    _REGISTRY[engine] = class_for_dim


def engine_class(engine: str, dim: int) -> type:
    """The simulation class of ``engine`` in ``dim`` dimensions (ValueError naming a bad engine)."""
    if engine not in ENGINES:
        raise ValueError(f"engine must be 'float' or 'lattice', got {engine!r}")
    return _REGISTRY[engine](dim)


class SimulationBase(Observing, Attachable, abc.ABC):
    """What a simulation does on either engine (see the module's docstring). Positions,
    velocities and times are in float units on both engines (the lattice converts its exact
    integers once per reading)."""

    #: the engine's name ("float" or "lattice")
    engine: str = ""

    # --- running ---------------------------------------------------------------------------

    @abc.abstractmethod
    def run(self, collisions=None, time=None) -> dict:
        """Forward until ``collisions`` more collisions or the clock reaches ``time``,
        whichever comes first. Returns at least ``collisions`` (done) and ``time``."""

    @abc.abstractmethod
    def run_back(self, collisions=None, time=None) -> dict:
        """Backwards until ``collisions`` collisions are undone or the clock is back at
        ``time``; with neither, to the start. Returns at least ``collisions`` and ``time``."""

    # --- the state -------------------------------------------------------------------------

    @property
    @abc.abstractmethod
    def positions(self) -> np.ndarray:
        """Positions at the clock, shape (n, dim) (a copy)."""

    @property
    @abc.abstractmethod
    def velocities(self) -> np.ndarray:
        """Velocities, shape (n, dim) (a copy)."""

    @property
    @abc.abstractmethod
    def time(self) -> float:
        """The clock."""

    @property
    @abc.abstractmethod
    def collisions(self) -> int:
        """Net collisions since the start (forward less undone)."""

    @property
    @abc.abstractmethod
    def n(self) -> int:
        """Number of particles."""

    @property
    @abc.abstractmethod
    def dim(self) -> int:
        """Dimension."""

    @property
    @abc.abstractmethod
    def box(self) -> np.ndarray:
        """Box lengths, shape (dim,)."""

    @property
    @abc.abstractmethod
    def boundary(self) -> tuple:
        """Per axis its kind: ``"periodic"``, ``"wall"`` (specular) or ``"bounce"`` (v -> -v)."""

    @property
    def periodic(self) -> tuple:
        """Per axis: periodic (True) or walls."""
        return tuple(b == "periodic" for b in self.boundary)

    @abc.abstractmethod
    def diagnostics(self) -> dict:
        """The engine's counts and checks (energy drift, events by type, rare log, memory)."""

    # --- checkpoints -----------------------------------------------------------------------

    @abc.abstractmethod
    def snapshot(self) -> dict:
        """The full state; ``from_snapshot`` resumes it."""

    @classmethod
    @abc.abstractmethod
    def from_snapshot(cls, snapshot: dict) -> "SimulationBase":
        """Rebuilds a simulation from ``snapshot()``."""

    @abc.abstractmethod
    def save(self, path: Union[str, os.PathLike]) -> None:
        """Writes the full state to ``path`` atomically (.npz)."""

    @classmethod
    @abc.abstractmethod
    def load(cls, path: Union[str, os.PathLike]) -> "SimulationBase":
        """Reads a state written by ``save``."""

    def __reduce__(self):
        """Pickling: the state is ``snapshot()``, rebuilt by ``from_snapshot`` (resumes bit for
        bit); ``copy.deepcopy`` too."""
        return (type(self).from_snapshot, (self.snapshot(),))
