"""Run any scene (``revcol run``, and each point of a ``revcol sweep``): forward, back to its
start, and the report of the round trip.

A *gas* scene (``revcol.scene``) builds N hard spheres, runs N_c collisions forward (or to an
end time), then ``run_back`` to the start time, and compares with the start. On the lattice
engine (``[collisions] engine = "lattice"``, the default scene's; :mod:`revcol.lattice_gas`)
every part of the integer state is compared exactly: positions, velocities, stream counters,
the bits-back integer, the rare log and the clock; the round trip passes when all come back
bit for bit, for any N_c. On the float engine:

- ``error_x`` = max over particles and axes of |x - x0| / L_axis (periodic images folded);
- ``error_v`` = max over particles of |v - v0| / max over particles of |v0| (Euclidean norms);
- ``passed`` when both are <= 1e-9 (the paper's bar).

The report also has forward and reverse collisions/s (engine calls only), energy drift
(E - E0) / E0 and momentum drift |P - P0| / sqrt(2 E0 N) along the periodic axes (walls
exchange momentum, so there is none to conserve along a walled axis), the rare-log bytes,
and the process's peak RSS. A real gas is chaotic: on the float engine round-off grows by
about an order of magnitude per collision per particle, so a round trip passes only within a
*horizon* of a few collisions per particle; :func:`revcol.studies.horizon.horizon` measures it
(``revcol run --horizon``; on a lattice scene it checks a few N_c bit for bit instead: there is
none).

A float-engine gas scene with an ``[observe]`` table also reports its forward run's
observables (``report["observe"]``: pressure, temperature, collision rate, ... with block
errors; :mod:`revcol.observe`), measured on its forward run itself.

*Reversal* scenes run the paper's illustration (:func:`revcol.verify`; velocities only, no
positions are built), *statesave* scenes the paper's §6 study
(:func:`revcol.studies.statesave.study`).

This module is the entry point, :func:`run_scene`; the parts: :mod:`revcol.gas` (the gas run),
:mod:`revcol.lattice_gas` (on the lattice engine), :mod:`revcol.studies.horizon`,
:mod:`revcol.studies.paper_scenes` (reversal and statesave scenes), :mod:`revcol.plots`,
:mod:`revcol.roundtrip` (the bar and the errors) and :mod:`revcol.progress` (Ctrl-C, progress
bar, peak RSS); the text report is the command line's (:mod:`revcol.cli.report`). It sits
with the studies because two scene kinds and the horizon are studies; the library's part is
the gas run.

Only what a run asks for is built or imported: matplotlib with ``plot`` only, the trajectory
writers with ``trajectory`` only, the intermediate round trips (state clones run back to the
start) and the energy series only for the plot, and a progress bar only on a terminal.
Ctrl-C (SIGINT) stops the forward run between events; the run then goes back from where it
stopped and writes everything asked for, marked interrupted. Ctrl-C during the reversal
stops it at the next chunk of collisions (the report then says the round trip is
incomplete); a third Ctrl-C ends the process.

    >>> r = run_scene(None, collisions=20_000, progress=False)   # the default scene, shorter
    >>> r["passed"], r["bit_for_bit"], r["collisions_forward"] == r["collisions_back"]
    (True, True, True)
"""
from __future__ import annotations

import dataclasses
import os
from pathlib import Path

from .._io import write_json
from .._output_size import (checkpoints_size, figures_size, report_size, round_trip_checkpoints, round_trip_frames,
                            trajectory_size)
from .._outputs import Output, check_outputs, checkpoint_names, estimates, output_limit, run_inputs
from ..gas import check_memory, run_gas
from ..plots import check_format, figure_names, plot_horizon, require_matplotlib
from ..scene import Scene, SceneError, load_scene, observes_frames, with_engine
from .horizon import horizon
from .paper_scenes import run_reversal, run_statesave

__all__ = ["run_scene"]


def run_scene(scene: Scene | str | os.PathLike | None = None, *, json_path: str | os.PathLike | None = None,
              plot: str | os.PathLike | None = None, trajectory: str | os.PathLike | None = None,
              horizon_seeds: int | None = None, max_collisions: int = 1_000_000,
              collisions: int | None = None, seed: int | None = None, engine: str | None = None,
              progress: bool | None = None, plot_format: str = "png", max_output: int | str | None = None) -> dict:
    """Runs any scene (a :class:`Scene`, a path, or None for the built-in default) and writes
    the outputs asked for (arguments here, else the scene's ``[output]``). ``collisions``
    overrides N_c (a gas's end time included); ``horizon_seeds`` measures the horizon over
    that many seeds instead of one round trip; ``plot_format``: the figures' file format
    (png, pdf or svg); ``engine`` (``"float"`` or ``"lattice"``) runs a
    gas scene on that engine instead of its own; ``max_output``: the outputs' limit in bytes
    (``"20G"``; 0 or ``"none"``: none) instead of the scene's ``[output] max_output`` or 10 GiB.
    Returns the report (``output_estimate``: the bytes each output was estimated to take); every
    output, its estimated size and the free space are checked before anything runs, and a bad one
    raises :class:`SceneError`."""
    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    if engine is not None:
        scene = with_engine(scene, engine)
    if collisions is not None:
        if scene.kind == "gas" and scene.particles == 1:
            raise SceneError(f"{scene.source}: [run] collisions: a single particle never collides")
        scene = dataclasses.replace(scene, collisions=int(collisions), time=None)
    if seed is not None:
        scene = dataclasses.replace(scene, seed=int(seed))
    if horizon_seeds is None:  # the scene's [output] describes its run, not a horizon study
        json_path = json_path if json_path is not None else scene.json
        plot = plot if plot is not None else scene.plot
        trajectory = trajectory if trajectory is not None else scene.trajectory
    if scene.kind != "gas":
        if trajectory is not None:
            raise SceneError(f"{scene.source}: --trajectory needs a 'gas' scene ({scene.kind!r} scenes have no positions)")
        if horizon_seeds is not None:
            raise SceneError(f"{scene.source}: --horizon measures 'gas' scenes, not {scene.kind!r}")
    if scene.kind == "reversal" and plot is not None:
        raise SceneError(f"{scene.source}: --plot has no figures for a 'reversal' scene (velocities only; "
                         "see revcol verify)")
    if horizon_seeds is not None and plot is not None and scene.engine == "lattice":
        raise SceneError(f"{scene.source}: --horizon --plot: a lattice scene has no horizon to plot "
                         "(every round trip is bit for bit); add --engine float for the float engine's")
    if plot is not None:
        require_matplotlib()
        check_format(plot_format)
    if trajectory is not None and scene.kind == "gas":  # its format before its size: a bad name fails
        from ..trajectory import check_format as check_frames  # the same on every machine, whatever is free
        try:
            check_frames(trajectory)
        except ValueError as e:
            raise SceneError(str(e)) from None
    # every output and the memory are checked before anything runs: a run must not be lost to
    # an unwritable report at its end (issue 17), nor overwrite its own inputs, nor fill the disk (issue 59)
    limit = output_limit(scene.source, max_output, scene.max_output)
    # a run that observes for its frames' image flags keeps the observer in its checkpoints too
    observed = dataclasses.replace(scene, observe={}) if observes_frames(scene, trajectory) else scene
    outputs = _outputs(observed, json_path, plot, trajectory, horizon_seeds is not None, plot_format)
    check_outputs(scene.source, outputs, run_inputs(scene), max_output=limit)
    if scene.kind == "gas":
        check_memory(scene)
    if horizon_seeds is not None:
        r = horizon(scene, seeds=horizon_seeds, max_collisions=max_collisions, progress=progress)
        if plot is not None:
            r["written"] += plot_horizon(r, Path(plot), fmt=plot_format)
    elif scene.kind == "reversal":
        r = run_reversal(scene)
    elif scene.kind == "statesave":
        r = run_statesave(scene, plot, progress, plot_format)
    else:
        r = run_gas(scene, plot=plot, trajectory=trajectory, progress=progress, plot_format=plot_format)
    r["output_estimate"] = estimates(outputs)
    if json_path is not None:
        r["written"].append(str(json_path))
        write_json(r, json_path)
    return r


def _outputs(scene: Scene, json_path, plot, trajectory, horizon: bool, plot_format: str) -> list[Output]:
    """What a run writes: its report, its trajectory, the figures its plot folder gets, and the
    checkpoints of a gas's forward run (``checkpoint-<n>.npz`` at every multiple n of the interval
    up to N_c; a horizon writes none)."""
    figures = "horizon" if horizon else ("lattice" if scene.engine == "lattice" else scene.kind)
    ckpt = scene.kind == "gas" and not horizon and scene.checkpoint_interval > 0
    names = figure_names(figures, plot_format) if figures != "reversal" else frozenset()
    return [Output("[output] json / --json", json_path, size=report_size(scene) if json_path is not None else None),
            Output("[output] plot / --plot", plot, folder=True, names=names,
                   size=figures_size(scene, len(names), plot_format) if plot is not None else None),
            Output("[output] trajectory / --trajectory", trajectory,
                   size=trajectory_size(scene, trajectory, round_trip_frames(scene), collisions=scene.collisions or 0)
                   if trajectory is not None and scene.kind == "gas" and not horizon else None),
            Output("[output] checkpoints", scene.checkpoints, folder=True, names=frozenset(),
                   match=checkpoint_names(1, scene.collisions, scene.checkpoint_interval) if ckpt else None,
                   size=checkpoints_size(scene, *round_trip_checkpoints(scene)) if ckpt else None)]
