"""Actions attached to a simulation on a periodic trigger in net collisions (HOOMD's writers
on a periodic trigger): the one implementation of ``attach`` / ``detach`` that both engines'
wrappers (:class:`revcol.Simulation`, :class:`revcol.lattice.LatticeSimulation`) inherit.
"""
from __future__ import annotations

from typing import Callable

from ._args import integer

__all__ = ["Attachable"]


class Attachable:
    """``attach(action, every)`` / ``detach(action)``; the engine's ``run`` pauses at each
    trigger (between events: the trajectory is the one without the pauses, bit for bit) and
    calls the actions whose period divides the net collision count."""

    def attach(self, action: Callable[..., object], every: int) -> None:
        """Runs ``action(sim)`` during ``run`` whenever the net collision count (forward minus
        undone) reaches a multiple of ``every``, as HOOMD's writers on a periodic trigger. A
        trajectory writer is such an action (``sim.attach(open_trajectory("t.gsd", sim.box,
        sim.periodic, 1.0), every=1000)`` writes a frame every 1000 collisions; close it after
        the runs). Attached actions are not part of ``snapshot()``, ``save`` or a pickle."""
        if not callable(action):
            raise TypeError(f"action must be callable (e.g. a trajectory writer), got {type(action).__name__}")
        k = integer(every, "every", lo=1)
        self.__dict__.setdefault("_attached", []).append((action, k))

    def detach(self, action: Callable[..., object]) -> None:
        """Removes every attachment of ``action`` (ValueError if there is none)."""
        kept = [(a, k) for a, k in self.__dict__.get("_attached", []) if not (a is action or a == action)]
        if len(kept) == len(self.__dict__.get("_attached", [])):
            raise ValueError("detach: this action is not attached")
        self.__dict__["_attached"] = kept

    def _attachments(self) -> list:
        return list(self.__dict__.get("_attached", []))

    @staticmethod
    def _to_next_trigger(attached: list, net: int) -> int:
        """Collisions from ``net`` to the next multiple of any attached period."""
        return min((net // k + 1) * k for _, k in attached) - net

    def _fire(self, attached: list, net: int) -> None:
        for action, k in attached:
            if net % k == 0:
                action(self)
