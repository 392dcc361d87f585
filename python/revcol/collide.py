"""Collision operators: forward and reverse side by side, numpy in and out.

- :class:`Pair2D`: two particles in 2D, exact mode (flux or uniform law) or paper mode.
- :class:`Pair1D`: two particles in 1D (velocity exchange, no random number).
- :class:`Wall`: reflection on the walls of a box.
"""
from ._core import Pair1D, Pair2D, Wall

__all__ = ["Pair1D", "Pair2D", "Wall"]
