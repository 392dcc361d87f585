"""The paper's performance study (§6): state saving against reverse computation, and beyond.

N particles in 2D (positions uniform in the unit box, velocity components uniform in
[-1, 1)). Each step draws exactly 3 numbers from the reversible generator (pair, exponential
inter-collision time, the operator's G), moves every particle x += v dt, and collides the
pair with the normal +-(x_i - x_j) oriented so that it approaches. After N_c steps the run
rolls back to the start:

- ``ss1``: saves all positions and velocities before every step (32 N bytes); restores them;
- ``ss2``: saves all positions and the pair's indices and pre-collision velocities (16 N + 40);
- ``ssp`` (lazy only): the pair's indices, x0 and velocities (72 bytes: the best lazy state saving);
- ``rc``:  saves nothing; reverse operator, then reverse transport, the generator stepping back.

Every step's record also holds the clock and the generator state (24 bytes more). *Lazy
transport* stores x0 = x - v t per particle, so a step costs O(1): a collision at time t
updates x0 += (v_old - v_new) t, and reverse undoes it. The C++ header
``revcol/studies/statesave.hpp`` has the maths (orientation, grazing rule, exact mode's pre log).

:func:`run` does one run in this process. :func:`study` runs a grid of (mode, N, variant),
each in a fresh ``revcol-bench`` process so that its peak resident set (VmHWM) is its own,
and reports times (the repeat with the median total), bytes saved (counted), peak RSS and
the round-trip error; runs whose saved state exceeds the budget are skipped with their
projection. :func:`write_json`, :func:`write_csv` and :func:`plot` write the results.

    >>> from revcol.studies import statesave
    >>> r = statesave.run(1000, 200, variant="rc")
    >>> r["restored"], r["max_rel_error"] < 1e-9, r["draws"] == 3 * 200
    (True, True, True)

This package gathers the study's parts: :mod:`revcol.statesave` (one run in this process, the
checks: the library's side, re-exported here), :mod:`.driver` (the study driver, :func:`study`),
:mod:`.output` (JSON, CSV, table, figure) and :mod:`.cli` (``revcol bench statesave``).
"""
from __future__ import annotations

from .cli import add_arguments, cli_main
from .output import format_table, plot, write_csv, write_json
from ...statesave import MODES, projected_bytes, run, variants
from .driver import study

__all__ = ["run", "projected_bytes", "variants", "study", "write_json", "write_csv", "plot",
           "format_table", "add_arguments", "cli_main", "MODES"]
