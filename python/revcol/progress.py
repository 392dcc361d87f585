"""What a long run does besides running: count Ctrl-C presses, draw a progress bar on a
terminal, and read the process's peak resident set.

Ctrl-C (SIGINT) inside :class:`Interrupt` is counted, not raised, and stops the engine's run
under way at its next poll, so a run can stop between events and still report; from the
second press on, the next one raises KeyboardInterrupt as Python's default handler does.
:class:`Bar` is a tqdm bar when tqdm is installed and the run asks for one, nothing otherwise.
"""
from __future__ import annotations

import signal
import sys
import threading

from . import _core

__all__ = ["Interrupt", "Bar", "peak_rss"]


def peak_rss() -> int | None:
    """Peak resident set of this process in bytes (VmHWM), or None where unknown."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        import resource  # Unix only

        r = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        return int(r) if sys.platform == "darwin" else int(r) * 1024
    except (ImportError, OSError):
        return None


class Interrupt:
    """SIGINT while a run is under way: counts the presses (the run loops read ``presses``) and
    stops the engine's run under way at its next poll (``_core.request_stop``; the engines poll
    every 16 384 events, collisions or not: a callback alone never runs in a gas without
    collisions); engine runs started after a press stop at their first poll, until :meth:`resume`. From the
    second press on, the next one raises KeyboardInterrupt as Python's default."""

    def __init__(self) -> None:
        self.presses = 0
        self._old = None
        self._stop_before = False

    def __enter__(self) -> "Interrupt":
        if threading.current_thread() is threading.main_thread():
            self._stop_before = _core.stop_requested()
            self._old = signal.signal(signal.SIGINT, self._handler)
        return self

    def __exit__(self, *exc) -> None:
        if self._old is not None:
            signal.signal(signal.SIGINT, self._old)
            _core.request_stop(self._stop_before)

    def resume(self) -> int:
        """The presses so far are handled (a round trip goes back from where Ctrl-C stopped it):
        engine runs go on until the next press. Returns the presses so far."""
        if self._old is not None:
            _core.request_stop(self._stop_before)
        return self.presses

    def _handler(self, signum, frame) -> None:
        self.presses += 1
        _core.request_stop(True)
        if self.presses >= 2:
            signal.signal(signal.SIGINT, signal.default_int_handler)


class Bar:
    """A tqdm progress bar on a terminal; nothing otherwise (or when tqdm is missing)."""

    def __init__(self, enabled: bool, total: float, desc: str, unit: str):
        self.bar, self.n = None, 0.0
        if enabled:
            try:
                from tqdm import tqdm  # only when a progress bar is drawn
            except ImportError:
                return
            self.bar = tqdm(total=total, desc=desc, unit=unit, leave=False, file=sys.stdout,
                            dynamic_ncols=True, unit_scale=True)

    def to(self, value: float) -> None:
        if self.bar is not None and value > self.n:
            self.bar.update(value - self.n)
            self.n = value

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
