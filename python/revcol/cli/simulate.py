"""``revcol simulate``: a forward-only production run of a gas scene, of any length, with
trajectory frames, checkpoints and the scene's observables (``revcol run`` is the
forward-and-back job; this one never reverses, so its length has no round-off horizon).

The run goes ``collisions`` more collisions or ``time`` more units of time (else the scene's
``[run]`` collisions or time), on the scene's engine (float or lattice). It writes the outputs
its arguments ask for (a scene's ``[output]`` json, trajectory and checkpoints are ``revcol
run``'s: the report lists them as ``scene_outputs_not_written``), driven by triggers in *net
collisions* (the engine's count since the scene's start, so a resumed run keeps the numbering
of the run it resumes):

- ``trajectory`` (``.xyz`` or ``.gsd``, :mod:`revcol.trajectory`): a frame at the start, at
  every multiple of ``every`` collisions (or, with ``every_time`` T instead, at every multiple
  of T in time), and at the end. A frame on a collision trigger is taken at a collision: one
  pair sits exactly at contact in it. Structure (g(r) at contact) wants frames at times
  independent of the events: ``every_time`` (tests/long/production_check.py measures the bias);
- ``checkpoints`` (a folder): ``checkpoint-<net collisions>.npz`` at every multiple of
  ``checkpoint_every`` and at the end; ``resume`` continues from one bit for bit (the run that
  resumes from checkpoint k and goes on to n collisions ends in the state of one that never
  stopped), and writes none at k itself (a run that does no collision: k is the file it resumed
  from, never written over);
- a scene's ``[observe]`` table (either engine): the forward run is observed and its values go in
  the report (``report["observe"]``, :mod:`revcol.observe`).

Ctrl-C (SIGINT) stops the run between events (float engine) or between chunks of at most
10^4 collisions (lattice engine); the last frame and checkpoint are written, the trajectory
is closed, and the report says ``interrupted``. Every option is checked before anything runs;
a bad one raises :class:`revcol.scene.SceneError` naming it, and so does an output that names an
input (the scene, its initial state, the checkpoint resumed from) or another output
(:mod:`revcol._outputs`).

    >>> r = simulate("spheres-3d", collisions=2000, progress=False)
    >>> r["collisions"], r["net_collisions"], r["interrupted"]
    (2000, 2000, False)
"""
from __future__ import annotations

import dataclasses
import datetime as dt
import math
import os
import sys
import time as _time
from pathlib import Path
from typing import Any

import numpy as np

from .._args import integer
from .._io import write_json
from .._version import __version__
from ..engine import Simulation
from .._output_size import (checkpoints_size, production_checkpoints, production_frames, report_size,
                            trajectory_size)
from .._outputs import Output, check_outputs, checkpoint_names, estimates, output_limit, run_inputs
from ..gas import build_simulation, check_memory
from ..lattice import LatticeSimulation, add_reports
from ..lattice_gas import geometry as lattice_geometry
from .report import field_line, parallel_line
from ..observe import report_lines
from ..progress import Bar, Interrupt, peak_rss
from ..roundtrip import geometry
from ..scene import Scene, SceneError, load_scene, observes_frames, with_engine, with_lattice_options, with_mode
from ..scene_schema import field_text, shear_text
from ..trajectory import _species, check_format, open_trajectory, true_images  # revcol simulate writes frames

__all__ = ["simulate", "format_simulate"]

#: collisions per lattice engine call (how often Ctrl-C and the progress bar are looked at)
LATTICE_CHUNK = 10_000


def _net(sim) -> int:
    """The engine's net collision count (forward minus undone, since the scene's start)."""
    if hasattr(sim, "collisions"):
        return int(sim.collisions)
    return int(sim.diagnostics()["net_collisions"])


def _options(scene: Scene, collisions, time, trajectory, every, checkpoints, checkpoint_every, resume,
             every_time=None):
    """The run's length and outputs, checked (SceneError naming the option)."""
    src = scene.source
    if scene.kind != "gas":
        raise SceneError(f"{src}: revcol simulate runs 'gas' scenes, not {scene.kind!r} (use revcol run)")
    if collisions is not None and time is not None:
        raise SceneError(f"{src}: --collisions and --time: give one length, not both")
    if collisions is not None and (isinstance(collisions, bool) or int(collisions) != collisions or collisions < 1):
        raise SceneError(f"{src}: --collisions must be a positive integer, got {collisions!r}")
    if time is not None and not (isinstance(time, (int, float)) and math.isfinite(time) and time > 0):
        raise SceneError(f"{src}: --time must be a positive finite number, got {time!r}")
    if collisions is None and time is None:
        collisions, time = scene.collisions, scene.time
    if scene.particles == 1 and time is None:
        raise SceneError(f"{src}: --collisions: a single particle never collides (give --time)")
    for name, k in (("--every", every), ("--checkpoint-every", checkpoint_every)):
        try:
            if k is not None:
                integer(k, name, lo=1)
        except (TypeError, ValueError):
            raise SceneError(f"{src}: {name} must be a positive integer, got {k!r}") from None
    # the scene's [output] trajectory, checkpoints and json are revcol run's: simulate writes what
    # its options ask for (issue 58: a shipped scene's demo outputs filled ./out with a GB)
    if every is not None and trajectory is None:
        raise SceneError(f"{src}: --every needs --trajectory")
    if every_time is not None:
        if isinstance(every_time, bool) or not isinstance(every_time, (int, float)) or \
                not (math.isfinite(every_time) and every_time > 0):
            raise SceneError(f"{src}: --every-time must be a positive finite number, got {every_time!r}")
        if every is not None:
            raise SceneError(f"{src}: --every and --every-time: give one frame trigger, not both")
        if trajectory is None:
            raise SceneError(f"{src}: --every-time needs --trajectory")
        every = 0  # no collision trigger
    every = every if every is not None else scene.trajectory_every
    if checkpoint_every is not None and checkpoints is None:
        raise SceneError(f"{src}: --checkpoint-every needs --checkpoint DIR")
    if checkpoints is not None and not checkpoint_every:
        checkpoint_every = scene.checkpoint_interval  # a setting, not an output: the scene's default
    if checkpoints is not None and not checkpoint_every:
        raise SceneError(f"{src}: --checkpoint needs --checkpoint-every K (or the scene's [run] checkpoint_interval)")
    if trajectory is not None:
        try:
            check_format(trajectory)
        except ValueError as e:
            raise SceneError(f"{src}: {e}") from None
    if resume is not None and not Path(resume).is_file():
        raise SceneError(f"{src}: --resume: {os.fspath(resume)!r} is not a file")
    return collisions, time, trajectory, int(every or 0), checkpoints, int(checkpoint_every or 0)


def _build(scene: Scene, resume):
    """The engine: from a checkpoint (``resume``, the scene's engine) or from the scene."""
    if resume is None:
        return build_simulation(scene)
    cls = LatticeSimulation if scene.engine == "lattice" else Simulation
    try:
        sim = cls.load(resume)
    except (ValueError, KeyError, TypeError) as e:
        raise SceneError(f"{scene.source}: --resume {os.fspath(resume)!r}: {e}") from None
    mode = _mode(sim)
    if mode != scene.mode:  # the checkpoint's dynamics go on; a scene asking for others is a mistake
        raise SceneError(f"{scene.source}: --resume {os.fspath(resume)!r}: the checkpoint runs {mode} mode, the "
                         f"scene {scene.mode} mode (--mode {mode} resumes it)")
    rounding = sim.quantization.get("gravity_error", 0.0) if isinstance(sim, LatticeSimulation) else 0.0
    if _field_mismatch(sim.gravity, scene.gravity, rounding):  # nor another field
        raise SceneError(f"{scene.source}: --resume {os.fspath(resume)!r}: the checkpoint runs gravity "
                         f"{field_text(sim.gravity if sim.gravity.any() else None)}, the scene "
                         f"{field_text(scene.gravity)} ([system] gravity)")
    rate = float(getattr(sim, "shear_rate", 0.0))  # nor another shear (the float engine runs none)
    rounding = sim.quantization.get("shear_error", 0.0) if isinstance(sim, LatticeSimulation) else 0.0
    if _field_mismatch(np.array([rate]), (scene.shear_rate,) if scene.shear_rate else None, rounding):
        raise SceneError(f"{scene.source}: --resume {os.fspath(resume)!r}: the checkpoint runs shear rate "
                         f"{shear_text(rate)}, the scene {shear_text(scene.shear_rate)} ([system] shear_rate)")
    return sim


def _field_mismatch(run: np.ndarray, scene: tuple[float, ...] | None, rounding: float = 0.0) -> bool:
    """Whether the field an engine runs (``run``, its ``.gravity``; or its shear rate, one
    component) is not the scene's (None: none), beyond the relative ``rounding`` the lattice
    quantized it with (its ``quantization["gravity_error"]``, ``["shear_error"]``): a checkpoint
    resumed under another scene's field or shear."""
    want = np.zeros_like(run) if scene is None else np.asarray(scene, dtype=float)
    scale = float(np.abs(want).max(initial=0.0))
    return bool(np.abs(run - want).max(initial=0.0) > (rounding + 1e-12) * scale)


def _mode(sim) -> str:
    """The collision mode an engine runs (the float engine's from its snapshot)."""
    return sim.mode if isinstance(sim, LatticeSimulation) else str(sim.snapshot().get("mode", "exact"))


class _Production:
    """One forward run with its outputs; ``go`` runs it, ``report`` describes it."""

    def __init__(self, scene: Scene, sim, collisions, time, trajectory, every, checkpoints, checkpoint_every,
                 species: str, precise: bool, every_time: float | None = None, resumed: bool = False):
        self.scene, self.sim, self.resumed = scene, sim, resumed
        self.lattice = scene.engine == "lattice"
        self.parallel: dict | None = None  # the run's report on the parallel engine (lattice, workers > 1)
        self.start = self.done = _net(sim)
        self.target = None if collisions is None else self.start + int(collisions)
        self.t_start = sim.time
        # the clock's resolution: a lattice run to a time ends on the nearest tick
        self.t_eps = float(sim.units["tick"]) if self.lattice else 0.0
        self.t_end = None if time is None else self.t_start + float(time)
        self.every, self.ckpt_every = every, checkpoint_every
        # time trigger: frames at the multiples of every_time on the engine's clock
        self.every_time = float(every_time) if every_time else None
        self.next_t = None if self.every_time is None else (math.floor(sim.time / self.every_time) + 1) * self.every_time
        self.checkpoints = None if checkpoints is None else Path(checkpoints)
        self.written_ckpt: list[str] = []
        self.trajectory, self.writer, self.last_frame = trajectory, None, None
        if trajectory is not None:
            box, periodic = lattice_geometry(sim) if self.lattice else geometry(sim)
            self.writer = open_trajectory(trajectory, box, periodic, scene.diameter, species=species,
                                          precise=precise)
        if scene.observe is not None:
            sim.observe(**scene.observe)
        elif observes_frames(scene, trajectory):  # the frames' image flags: its crossings (not reported)
            sim.observe()
        self.interrupted, self.engine_error, self.stalled, self.wall_s = False, None, False, 0.0

    def advance_frame_time(self) -> None:
        """The next multiple of every_time after the clock (counted in whole periods, so that
        a product that rounds back onto the current time cannot stall the run)."""
        k = round(self.next_t / self.every_time)
        while True:
            k += 1
            self.next_t = k * self.every_time
            if self.next_t > self.sim.time + self.t_eps:
                return

    def finished(self) -> bool:
        return ((self.target is not None and self.done >= self.target)
                or (self.t_end is not None and self.sim.time >= self.t_end - self.t_eps))

    def next_stop(self) -> int | None:
        stops = [(self.done // k + 1) * k for k in (self.every if self.writer else 0, self.ckpt_every) if k]
        if self.target is not None:
            stops.append(self.target)
        return min(stops) if stops else None

    def frame(self) -> None:
        sim = self.sim
        if self.writer is not None and self.last_frame != (self.done, sim.time):
            x = sim.positions
            self.writer.write(x, sim.velocities, sim.time, self.done, "forward", image=true_images(sim, x))
            self.last_frame = (self.done, sim.time)

    def checkpoint(self) -> None:
        if self.resumed and self.done == self.start:
            # no collision since the resumed checkpoint: its count is that file's (never written over, issue 59)
            return
        if self.checkpoints is not None and (not self.written_ckpt or not self.written_ckpt[-1].endswith(
                f"-{self.done:012d}.npz")):
            path = self.checkpoints / f"checkpoint-{self.done:012d}.npz"
            path.parent.mkdir(parents=True, exist_ok=True)
            self.sim.save(path)
            self.written_ckpt.append(str(path))

    def stop_time(self) -> float | None:
        """The clock at which the next engine call ends: the end time or the next time frame."""
        ts = [t for t in (self.t_end, self.next_t if self.writer is not None else None) if t is not None]
        return min(ts) if ts else None

    def step(self, stop: Interrupt, bar: Bar, stop_c: int | None) -> int:
        """One engine call towards ``stop_c`` (or the end time, or the next time frame); the
        collisions it did."""
        sim, more = self.sim, None if stop_c is None else stop_c - self.done
        until = self.stop_time()
        if self.lattice:
            # (the parallel engine: calls long enough to pay for its K views; Ctrl-C is polled inside)
            chunk = LATTICE_CHUNK if sim.parallel["lps"] == 1 else max(5 * LATTICE_CHUNK, 2 * sim.n)
            more = chunk if more is None else min(more, chunk)
            try:
                r = sim.run(collisions=more, time=until)
                self.parallel = add_reports(self.parallel, r.get("parallel"))
                return int(r["collisions"])
            except RuntimeError as e:  # a collision the lattice engine cannot resolve: stop here
                self.engine_error = str(e)
                return _net(sim) - self.done
        base = self.done

        def callback(k: int) -> bool:
            bar.to(base + k - self.start if self.target is not None else sim.time - self.t_start)
            return stop.presses == 0
        chunk = max(1, min(10_000, sim.n))
        return int(sim.run(collisions=more, time=until, callback=callback, every=chunk)["collisions"])

    def go(self, progress: bool) -> None:
        total = float(self.target - self.start) if self.target is not None else float(self.t_end - self.t_start)
        bar = Bar(progress, total, "simulate", "coll" if self.target is not None else "t")
        tick = _time.perf_counter()
        failed = True  # an error (a full disk: ENOSPC) must not be masked by closing the trajectory
        try:
            with Interrupt() as stop:
                self.frame()
                while not self.finished():
                    did = self.step(stop, bar, self.next_stop())
                    self.done += did
                    bar.to(self.done - self.start if self.target is not None else self.sim.time - self.t_start)
                    if stop.presses:
                        self.interrupted = True
                    if self.interrupted or self.engine_error is not None:
                        break
                    at_frame_time = self.next_t is not None and self.sim.time >= self.next_t - self.t_eps
                    if did == 0 and not self.finished() and not at_frame_time:  # nothing left to happen
                        self.stalled = True
                        break
                    if self.every and self.done % self.every == 0:
                        self.frame()
                    if at_frame_time:
                        self.frame()
                        self.advance_frame_time()
                    if self.ckpt_every and self.done % self.ckpt_every == 0:
                        self.checkpoint()
                self.frame()
                self.checkpoint()
            failed = False
        finally:
            self.wall_s = _time.perf_counter() - tick
            bar.close()
            if self.writer is not None:
                if failed:
                    self.writer.close_quietly()
                else:
                    self.writer.close()

    def length(self) -> str:
        """This run's length as asked (the scene's own [run] length is not what simulate runs)."""
        if self.target is not None:
            return f"{self.target - self.start:,} collisions"
        return f"a time of {self.t_end - self.t_start:g}"

    def report(self, resume) -> dict[str, Any]:
        sim, scene = self.sim, self.scene
        d = sim.diagnostics()
        obs = sim.observation() if scene.observe is not None else None
        ran = self.done - self.start
        return {
            "kind": "simulate", "revcol_version": __version__, "scene": scene.to_dict(), "summary": scene.summary(self.length()),
            "engine": scene.engine, "mode": scene.mode, "particles": sim.n, "dimension": sim.dim,
            "lattice": {"tick_bits": sim.units["tick_bits"], "cell_bits": sim.units["cell_bits"],
                        "search": sim.search} if self.lattice else None,
            # the run on the parallel engine: its settings and report (None: sequential)
            "parallel": None if self.parallel is None else {**sim.parallel, **self.parallel},
            # the lattice's specular pairs turned back in place (specular.hpp); None on the float engine
            "backscatters": int(d["backscatters"]) if self.lattice else None,
            # the field run (None: none) and, on the lattice, its rounding (quantization's gravity_error)
            "gravity": sim.gravity.tolist() if sim.gravity.any() else None,
            # the shear run (None: none) and, on the lattice, its integer per tick (quantization's shear_error)
            "shear_rate": float(getattr(sim, "shear_rate", 0.0)) or None,
            "shear_per_tick": (int(sim.units.get("shear", 0)) or None) if self.lattice else None,
            "quantization": sim.quantization if self.lattice else None,
            "resumed_from": None if resume is None else os.fspath(resume),
            "collisions": ran, "net_collisions": self.done, "collisions_per_particle": 2.0 * ran / sim.n,
            "time_start": self.t_start, "time_end": sim.time,
            "wall_s": self.wall_s, "collisions_per_s": ran / self.wall_s if self.wall_s > 0 else None,
            "energy_drift": float(d["energy_drift"]),
            "energy_drift_definition": "(E - E0) / E0, E0 at the scene's start",
            "interrupted": self.interrupted, "engine_error": self.engine_error, "stalled": self.stalled,
            "trajectory": None if self.trajectory is None else os.fspath(self.trajectory),
            "trajectory_frames": self.writer.frames if self.writer is not None else 0,
            "checkpoints": self.written_ckpt,
            "observe": obs.to_dict() if obs is not None else None,
            "peak_rss_bytes": peak_rss(),
            "date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
            "written": ([os.fspath(self.trajectory)] if self.writer is not None else []) + list(self.written_ckpt),
        }


def simulate(scene: Scene | str | os.PathLike | None = None, *, collisions: int | None = None,
             time: float | None = None, trajectory: str | os.PathLike | None = None, every: int | None = None,
             checkpoints: str | os.PathLike | None = None, checkpoint_every: int | None = None,
             resume: str | os.PathLike | None = None, seed: int | None = None, engine: str | None = None,
             species: str = "Ar", precise: bool = False, json_path: str | os.PathLike | None = None,
             progress: bool | None = None, every_time: float | None = None, tick_bits: int | None = None,
             cell_bits: int | None = None, search: str | float | None = None, mode: str | None = None,
             max_output: int | str | None = None, workers: int | None = None) -> dict:
    """Runs a gas scene forward only (see the module's docstring) and returns the report; with
    ``json_path`` also writes it (atomically). ``species`` names the trajectory's element,
    ``precise`` adds float64 positions to a GSD trajectory; ``every_time`` writes frames at the
    multiples of that time instead of every ``every`` collisions. ``tick_bits``, ``cell_bits``,
    ``search``, ``workers``: the lattice engine's options instead of the scene's (a resumed run keeps its
    checkpoint's units, tick and cells, and takes a new search and workers). ``mode``: the collision mode
    instead of the scene's ``[collisions] mode`` (``"exact"``, ``"paper"``: float engine, 1D and
    2D, or ``"specular"``; a resumed run must be in its checkpoint's). ``max_output``: the outputs'
    limit in bytes (``"20G"``; 0 or ``"none"``: none) instead of the scene's ``[output] max_output``
    or 10 GiB; the outputs' estimated sizes (``report["output_estimate"]``) must fit it and the free
    space. A bad option raises SceneError before anything runs."""
    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    if mode is not None:
        scene = with_mode(scene, mode, engine)
    elif engine is not None:
        scene = with_engine(scene, engine)
    scene = with_lattice_options(scene, tick_bits=tick_bits, cell_bits=cell_bits, search=search, workers=workers)
    if resume is not None and (tick_bits, cell_bits) != (None, None):
        raise SceneError(f"{scene.source}: --tick-bits, --cell-bits: a resumed run keeps its checkpoint's units")
    if seed is not None:
        scene = dataclasses.replace(scene, seed=int(seed))
    not_written = [name for name, v in (("json", scene.json), ("trajectory", scene.trajectory),
                                        ("checkpoints", scene.checkpoints)) if v is not None]
    collisions, time, trajectory, every, checkpoints, checkpoint_every = _options(
        scene, collisions, time, trajectory, every, checkpoints, checkpoint_every, resume, every_time)
    try:
        _species(species)
    except ValueError as e:
        raise SceneError(f"{scene.source}: --species: {e}") from None
    limit = output_limit(scene.source, max_output, scene.max_output)
    check_memory(scene)
    # the checkpoint resumed from is read first: its count numbers the checkpoints the run may write
    sim = _build(scene, resume) if resume is not None else None
    start = 0 if sim is None else _net(sim)
    # no output may name an input or another output (issue 59), nor outgrow the limit or the free
    # space (issue 59); every one writable (issue 17)
    # a run that observes for its frames' image flags keeps the observer in its checkpoints too
    observed = dataclasses.replace(scene, observe={}) if observes_frames(scene, trajectory) else scene
    outputs = _outputs(observed, sim, start, collisions, time, json_path, trajectory, every, every_time, checkpoints,
                       checkpoint_every, species, precise)
    check_outputs(scene.source, outputs, run_inputs(scene, resume), max_output=limit)
    if sim is None:
        sim = _build(scene, None)
    if resume is not None and search is not None:  # the checkpoint holds its own; a new one is the same run
        sim.search = scene.search
    if scene.engine == "lattice":  # (a checkpoint holds no workers: a parallel run resumes on any)
        sim.set_parallel(scene.workers)
    run = _Production(scene, sim, collisions, time, trajectory, every, checkpoints, checkpoint_every,
                      species, precise, every_time, resumed=resume is not None)
    run.go(sys.stdout.isatty() if progress is None else progress)
    r = run.report(resume)
    r["output_estimate"] = estimates(outputs)
    r["scene_outputs_not_written"] = not_written
    if json_path is not None:
        r["written"].append(os.fspath(json_path))
        write_json(r, json_path)
    return r


def _outputs(scene: Scene, sim, start: int, collisions, time, json_path, trajectory, every: int, every_time,
             checkpoints, checkpoint_every: int, species: str, precise: bool) -> list[Output]:
    """The run's outputs, each with its estimated size (:mod:`revcol._output_size`): the report, the
    frames (the start, every ``every`` collisions or ``every_time``, the end) and the checkpoints
    (every ``checkpoint_every`` collisions after ``start`` and the end; a resumed run writes none at
    its start, :meth:`_Production.checkpoint`)."""
    first = 0 if sim is None else start + 1
    names = checkpoint_names(first, None if collisions is None else start + int(collisions))
    traj = ckpt = None
    if trajectory is not None:
        frames = production_frames(scene, start, collisions, time, every, every_time, sim)
        traj = trajectory_size(scene, trajectory, frames, sim=sim, species=species, precise=precise,
                               collisions=start + (collisions or 0))
    if checkpoints is not None:
        ckpt = checkpoints_size(scene, *production_checkpoints(scene, start, collisions, time, checkpoint_every, sim),
                                sim=sim)
    return [Output("[output] json / --json", json_path, size=report_size(scene) if json_path is not None else None),
            Output("[output] trajectory / --trajectory", trajectory, size=traj),
            Output("[output] checkpoints / --checkpoint", checkpoints, folder=True, match=names, size=ckpt)]


def format_simulate(r: dict) -> str:
    """The report as text."""
    s = r["scene"]
    rate = r["collisions_per_s"]
    lines = [f"revcol simulate {s['name']}  ({s['source']})", f"  scene            {r['summary']}",
             f"  engine           {r['engine']}, {r.get('mode', 'exact')} mode"
             + (f"  (resumed from {r['resumed_from']})" if r["resumed_from"] else "")
             + (f"  (tick_bits {r['lattice']['tick_bits']}, cell_bits {r['lattice']['cell_bits']}, search "
                f"{r['lattice']['search']})" if r.get("lattice") else ""),
             *field_line(r),
             *parallel_line(r.get("parallel")),
             f"  collisions       {r['collisions']:,} ({r['collisions_per_particle']:.3g} per particle; "
             f"net count now {r['net_collisions']:,})",
             f"  time             {r['time_start']:.6g} -> {r['time_end']:.6g}",
             f"  wall             {r['wall_s']:.3g} s" + (f"  ({rate:,.0f} collisions/s)" if rate else ""),
             f"  energy drift     {r['energy_drift']:.3g}  ((E - E0) / E0)"]
    if r.get("mode") == "specular" and r.get("backscatters") is not None:
        lines.append(f"  backscatters     {r['backscatters']:,} (specular pairs turned back in place)")
    if r["trajectory"]:
        lines.append(f"  trajectory       {r['trajectory']}  ({r['trajectory_frames']} frames)")
    if r["checkpoints"]:
        lines.append(f"  checkpoints      {len(r['checkpoints'])}, last {r['checkpoints'][-1]}")
    if r["interrupted"]:
        lines.append("  interrupted      (Ctrl-C): stopped between events; the last frame and checkpoint are written")
    if r["engine_error"]:
        lines.append(f"  engine error     {r['engine_error']} (stopped there)")
    if r["stalled"]:
        lines.append("  stalled          the engine had no more collisions to do before the end")
    if r["observe"]:
        lines += report_lines(r["observe"])
    if r["written"]:
        lines.append("  written          " + _written(r))
    if r.get("scene_outputs_not_written"):
        names = ", ".join(f"[output] {k}" for k in r["scene_outputs_not_written"])
        lines.append(f"  not written      the scene's {names} (revcol run's; simulate writes what --json, "
                     "--trajectory and --checkpoint ask for)")
    return "\n".join(lines)


def _written(r: dict) -> str:
    """The files written, the checkpoints as a count and a folder (a long run writes thousands)."""
    ckpts = set(r["checkpoints"])
    parts = [w for w in r["written"] if w not in ckpts]
    if ckpts:
        folder = os.path.dirname(r["checkpoints"][-1]) or "."
        parts.append(f"{len(ckpts)} checkpoint{'s' if len(ckpts) != 1 else ''} in {folder}{os.sep}")
    return ", ".join(parts)
