"""The paper's scene kinds, run from a scene: the reversal illustration (``kind =
"reversal"``, :func:`revcol.verify`; velocities only, no positions are built) and the
state-saving study (``kind = "statesave"``, :func:`revcol.studies.statesave.study`).

Each is one C++ call or one process per run, so Ctrl-C is counted and acted on between
calls: the report, marked interrupted, is still written.
"""
from __future__ import annotations

import os
from pathlib import Path

from ..plots import require_matplotlib
from ..progress import Interrupt, peak_rss
from ..scene import Scene, SceneError
from ..verify import verify
from . import statesave
from .statesave.driver import find_binary

__all__ = ["run_reversal", "run_statesave"]


def run_reversal(scene: Scene) -> dict:
    """The paper's reversal illustration for the scene's case (:func:`revcol.verify`)."""
    # one C++ call (10^6 collisions both ways in about a second): a Ctrl-C waits for it to end,
    # and the report, marked interrupted, is still written
    with Interrupt() as stop:
        r = dict(verify(scene.case, collisions=scene.collisions, mode=scene.mode, law=scene.law,
                        rng=scene.generator, seed=scene.seed, bits=scene.bits))
    r.update({"kind": "reversal", "scene": scene.to_dict(), "summary": scene.summary(),
              "peak_rss_bytes": peak_rss(), "interrupted": "reversal" if stop.presses else None,
              "written": []})
    return r


def run_statesave(scene: Scene, plot: str | os.PathLike | None = None, progress: bool | None = None,
                  plot_format: str = "png") -> dict:
    """The paper's state-saving study for the scene's settings (:func:`revcol.studies.statesave.study`).
    ``runner = "auto"`` runs each point in a fresh ``revcol-bench`` process when one is
    found (so peak RSS is the run's own), in this process otherwise."""
    if plot is not None:
        require_matplotlib()
    inline = scene.runner == "inline"
    if not inline:
        try:
            find_binary(None)
        except FileNotFoundError:
            if scene.runner == "process":
                raise SceneError(f"{scene.source}: [statesave] runner: 'process' needs the revcol-bench binary "
                                 "(installed next to python by pip install ., or set REVCOL_BENCH); "
                                 "or use runner = 'auto' or 'inline'") from None
            inline = True
    # Ctrl-C ends the study after the run under way (each run is one C++ call or process);
    # the runs done are reported and written
    try:
        with Interrupt() as stop:
            r = statesave.study(scene.statesave_particles, scene.collisions, lazy=scene.lazy,
                                modes=(scene.mode,), law=scene.law, variants=scene.variants,
                                repeats=scene.repeats, budget_gib=scene.budget_gib, seed=scene.seed,
                                rng=scene.generator, inline=inline, progress=progress,
                                command=f"revcol run {scene.source}", stop=lambda: stop.presses > 0)
    except (ValueError, FileNotFoundError) as e:
        raise SceneError(f"{scene.source}: {e}") from None
    r.update({"kind": "statesave", "scene": scene.to_dict(), "summary": scene.summary(),
              "interrupted": "statesave" if r["interrupted"] or stop.presses else None, "written": []})
    if plot is not None:
        out = Path(plot) / f"statesave.{plot_format}"
        out.parent.mkdir(parents=True, exist_ok=True)
        statesave.plot(r, out)
        r["written"].append(str(out))
    return r

