"""``revcol sweep``: many runs of one study, spread over Dask distributed, gathered in one table.

The sweep file and its points: :mod:`.spec` (the format is described there); the tasks and the
client that submits them: :mod:`.tasks`; the table, the summary and the figures:
:mod:`.output`; the studies a sweep runs without a scene: :mod:`.studies`. This module is the
entry point, :func:`sweep` (also ``revcol.sweep``).
"""
from __future__ import annotations

import os
from pathlib import Path

from .._output_size import sweep_files_size, sweep_points_size
from .._outputs import Input, Output, check_sizes, estimates, output_limit, refuse_collisions
from ..scene_schema import SceneError
from .output import output_names, read_point
from .spec import SCENE_PARAMS, STUDIES, Point, Sweep, SweepError, load_sweep, sweep_from_dict, sweep_names
from .tasks import execute

__all__ = ["SweepError", "Sweep", "Point", "load_sweep", "sweep_from_dict", "sweep_names", "sweep", "STUDIES",
           "SCENE_PARAMS"]


def sweep(spec: Sweep | str | os.PathLike, *, out: str | os.PathLike | None = None, workers: int | None = None,
          scheduler: str | None = None, scheduler_file: str | os.PathLike | None = None, client=None,
          progress: bool | None = None, stop_after: int | None = None, log=None, on_result=None,
          max_output: int | str | None = None) -> dict:
    """Runs a sweep (a :class:`Sweep` or a sweep file) and returns its summary (also written to
    ``out/NAME.json``, with the table ``out/NAME.csv``).

    ``workers``: the LocalCluster's worker processes (default: the machine's cores; 0: no Dask, the
    points run here one after another). ``scheduler`` / ``scheduler_file``: use that running Dask
    cluster instead; ``client``: an existing ``distributed.Client``. ``stop_after``: stop once that
    many points have finished in this call (the rest stay to do: run again to resume). ``log``: a
    callable taking a line of text (default: nothing printed); ``on_result``: called here with
    ``{"index", "hash", "point"}`` as each point's file is written. ``max_output``: the limit on the
    bytes the sweep is estimated to write (``"20G"``; 0 or ``"none"``: none; default 10 GiB, as for
    ``revcol run``); a sweep over it, or over the free space, is refused before any point runs, and
    the summary's ``output_estimate`` gives the estimates (:mod:`revcol._output_size`)."""
    if not isinstance(spec, Sweep):
        spec = load_sweep(spec)
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 0):
        raise SweepError(f"workers must be an integer >= 0, got {workers!r}")
    if stop_after is not None and (isinstance(stop_after, bool) or not isinstance(stop_after, int) or stop_after < 1):
        raise SweepError(f"stop_after must be a positive integer, got {stop_after!r}")
    if sum(x is not None for x in (scheduler, scheduler_file, client)) > 1:
        raise SweepError("give at most one of scheduler, scheduler_file and client")
    if workers is not None and (scheduler is not None or scheduler_file is not None or client is not None):
        raise SweepError("workers sets the size of a local cluster; an existing cluster has its own")
    out = Path(out) if out is not None else Path.cwd() / "out" / "sweeps" / spec.name
    if out.exists() and not out.is_dir():
        raise SweepError(f"{out}: exists and is not a folder")
    _refuse_overwriting_inputs(spec, out)
    try:
        limit = output_limit(spec.source, max_output, None)
    except SceneError as e:
        raise SweepError(str(e)) from None
    outputs = _outputs(spec, out)
    check_sizes(spec.source, outputs, limit, SweepError, flag="--max-output")
    return execute(spec, out, workers=workers, scheduler=scheduler,
                   scheduler_file=None if scheduler_file is None else str(scheduler_file), client=client,
                   progress=progress, stop_after=stop_after, log=log or (lambda line: None), on_result=on_result,
                   output_estimate=estimates(outputs))


def _outputs(spec: Sweep, out: Path) -> list[Output]:
    """What the sweep writes, each with its estimated bytes (issue 59; revcol._output_size): a
    report for each point not yet written (points/HASH.json: a point writes nothing else), and the
    table, the summary and, for the horizon study, its two figures."""
    todo = [p.scene for p in spec.points if read_point(out, p.hash) is None]
    return [Output("the output folder's points/", out / "points", folder=True, size=sweep_points_size(todo)),
            Output("the output folder (--out)", out, folder=True,
                   size=sweep_files_size(len(spec.points), 2 if spec.study == "horizon" else 0))]


def _refuse_overwriting_inputs(spec: Sweep, out: Path) -> None:
    """SweepError when the sweep would write over its sweep file, its scene or a point's initial
    state (issue 59; the points themselves write nothing, revcol.sweep.spec)."""
    inputs = [Input("the sweep file itself", spec.source)] if Path(spec.source).is_file() else []
    if spec.scene_name not in ("default", "-") and Path(spec.scene_name).is_file():  # not the built-in, not none
        inputs.append(Input("the sweep's scene file ([sweep] scene)", spec.scene_name))
    states = {os.fspath(p.scene.initial_state) for p in spec.points if p.scene is not None and p.scene.initial_state}
    inputs += [Input("a point's initial state file ([system] initial_state)", s) for s in sorted(states)]
    top, points = output_names(spec)
    refuse_collisions(spec.source, [Output("the output folder (--out)", out, folder=True, names=top),
                                    Output("the output folder's points/", out / "points", folder=True,
                                           names=points)],
                      inputs, SweepError)
