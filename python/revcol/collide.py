"""Collision operators: forward and reverse side by side, numpy in and out.

- :class:`Pair2D`: two particles in 2D, exact mode (flux or uniform law) or paper mode.
- :class:`Pair1D`: two particles in 1D (velocity exchange, no random number).
- :class:`Wall`: reflection on the walls of a box.
- :class:`Collision`: the exact operator for any n, d with at most 3 independent contacts;
  :func:`named_cases` lists the paper's configurations and those beyond it.
"""
from ._core import Collision, Pair1D, Pair2D, Wall, named_cases

__all__ = ["Collision", "Pair1D", "Pair2D", "Wall", "named_cases"]
