"""Reversible random number generators (re-exported from the compiled core).

- :class:`CLCG4`: L'Ecuyer & Andres (1997) combined LCG; ``prev()`` undoes ``next()`` exactly.
- :class:`Philox`: Random123 Philox4x32-10, counter-based; draw k is a pure function of (key, k).
- :func:`philox4x32`: the raw Philox4x32-10 block function.

Example::

    >>> import revcol
    >>> g = revcol.CLCG4(stream=1)
    >>> a = g.next_many(5)
    >>> b = g.prev_many(5)          # values in the order undone: b == a[::-1]
    >>> g.state == revcol.CLCG4(stream=1).state
    True
"""
from ._core import CLCG4, Philox, philox4x32

__all__ = ["CLCG4", "Philox", "philox4x32"]
