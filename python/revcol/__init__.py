"""revcol: reversible simulation of randomized elastic hard-sphere collisions.

Collisions whose outcome is randomized over all permitted phase space, run forward and
then backwards to any earlier point with essentially no memory: the collision operators
are invertible and driven by reversible random number generators (Perumalla &
Protopopescu, ACM TOMACS 2013, and beyond).

    >>> import numpy as np, revcol
    >>> g = revcol.CLCG4()
    >>> op = revcol.Pair2D()                 # exact mode, flux law
    >>> v = np.array([[1.0, 0.0], [-1.0, 0.0]])
    >>> post = op.forward(v, [-1.0, 0.0], rng=g)
    >>> np.allclose(op.reverse(post, [-1.0, 0.0], rng=g), v)
    True
"""
from ._version import __version__
from .collide import Collision, Pair1D, Pair2D, Wall, named_cases
from .rng import CLCG4, Philox, philox4x32
from .verify import VERIFY_CASES, verify, verify_cases
from .paper import Pair3DPaper, Triple1DPaper, Triple2DPaper
from . import paper
from . import statesave
from .simulation import SimulationBase
from .engine import Simulation
from . import lattice  # registers engine="lattice" (revcol.simulation)
from . import observe
from .sweep import sweep

__all__ = ["CLCG4", "Philox", "philox4x32", "Collision", "named_cases", "Pair1D", "Pair2D", "Wall", "verify", "verify_cases", "VERIFY_CASES", "statesave", "Pair3DPaper", "Triple1DPaper", "Triple2DPaper", "paper", "Simulation", "SimulationBase", "lattice", "observe", "sweep"]
