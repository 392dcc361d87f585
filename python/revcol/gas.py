"""A gas scene's run: build the engine, go forward N_c collisions (or to an end time), back to
the start, and report the round trip (errors in :mod:`revcol.roundtrip`).

The start comes from the engine (C++ ``engine/init.hpp``: random sequential addition or a
jittered crystal, in the cube of the scene's packing fraction or in its explicit box) or
from the scene's initial-state file. Forward, the run pauses for checkpoints, trajectory frames and,
with a plot, 9 intermediate round trips (state clones run back to the start). Ctrl-C stops
the forward run between events; the run then goes back from where it stopped. Ctrl-C during
the reversal stops it at the next chunk (the round trip is then incomplete).

    >>> from revcol.scene import load_scene
    >>> r = run_gas(load_scene("scenes/paper-mode-2d.toml"), progress=False)
    >>> r["passed"], r["collisions_forward"] == r["collisions_back"]
    (True, True)
"""
from __future__ import annotations

import datetime as dt
import math
import os
import sys
import time as _time
from pathlib import Path
from typing import Any, Callable

import numpy as np

from . import _core, plots
from ._outputs import Input, Output, check_outputs
from ._species import trajectory_kinds
from .engine import Simulation
from .lattice_gas import _LatticeRun, build_lattice
from .progress import Bar, Interrupt, peak_rss
from ._version import __version__
from .roundtrip import BAR, ERROR_DEFINITIONS, geometry, round_trip_errors
from .scene import Scene, SceneError, engine_options, observes_frames, read_initial

__all__ = ["build_simulation", "run_gas", "round_trip", "list_renewals", "BYTES_PER_PARTICLE", "check_memory",
           "check_output"]


def build_simulation(scene: Scene, seed: int | None = None) -> Simulation:
    """The engine for a gas scene: from its initial state, or from the engine's random start
    in its box (``[system] start``: auto, random or crystal). ``seed`` overrides the
    scene's. A state the engine refuses raises :class:`SceneError` naming the field. A
    lattice scene gets a :class:`revcol.lattice.LatticeSimulation` (:mod:`revcol.lattice_gas`)."""
    if scene.kind != "gas":
        raise SceneError(f"{scene.source}: [scene] kind: {scene.kind!r} scenes build no particles")
    if scene.engine == "lattice":
        return build_lattice(scene, seed)
    opts = engine_options(scene)
    if seed is not None:
        opts["seed"] = int(seed)
    if scene.initial_state is not None:
        x, v = read_initial(scene.source, scene.initial_state, scene.dimension)
        return _engine(scene, "[system] initial_state", lambda: Simulation(x, v, scene.box, **opts))
    init = {"auto": "auto", "random": "rsa", "crystal": "crystal", "relax": "relax"}[scene.start]
    if scene.packing_fraction is not None:  # the engine's cube for that fraction (random_state)
        return _engine(scene, "[system] packing_fraction", lambda: Simulation.random(
            scene.particles, scene.dimension, scene.packing_fraction, init=init,
            energy=scene.kinetic_energy, **opts))

    def make() -> Simulation:  # the engine's start in the scene's box (random_start; a mixture's as its largest,
        # else relaxed at its own sizes)
        x, v = _core.engine_random_start(scene.particles, list(scene.box), opts["boundary"], scene.diameter,
                                         opts["seed"], scene.kinetic_energy or 0.0, init, False,
                                         list(opts.get("masses", [])), list(opts.get("diameters", [])))
        return Simulation(x, v, scene.box, **opts)
    return _engine(scene, "[system] box", make)


def _engine(scene: Scene, where: str, make: Callable[[], Simulation]) -> Simulation:
    try:
        return make()
    except ValueError as e:
        # speeds out of the engine's range come from the scene's kinetic energy when it gives one
        # (issue 59: kinetic_energy = 1e-320 was reported under packing_fraction)
        if scene.kinetic_energy is not None and ("velocity" in str(e) or "speed" in str(e)):
            where = "[system] kinetic_energy"
        raise SceneError(f"{scene.source}: {where}: {e}") from None


def list_renewals(events: dict) -> int:
    """The engine's neighbour-list renewals from diagnostics' ``events`` (``list_renewals``,
    or ``cell_crossings`` as engines before the rename call it)."""
    return int(events.get("list_renewals", events.get("cell_crossings", 0)))


class _GasRun:
    """One round trip of a gas scene; the phases share the engine and what they measured."""

    def __init__(self, scene: Scene, plot, trajectory, progress: bool, checkpoints: bool):
        self.scene, self.plot, self.progress = scene, plot, progress
        self.sim = sim = build_simulation(scene)
        # [observe]: the forward run itself is observed (run_back ends the observation)
        self.observation = None
        if scene.observe is not None:
            sim.observe(**scene.observe)
        self.n, self.d = sim.n, sim.dim
        self.box, self.periodic = geometry(sim)
        # momentum is conserved along periodic axes unless a bounce-back wall (v -> -v) takes it
        bounce = np.array([b == "bounce" for b in sim.boundary])
        self.conserved = self.periodic & ~bounce.any()
        self.x0, self.v0 = sim.positions, sim.velocities
        diag0 = sim.diagnostics()
        self.e0, self.p0 = diag0["energy"], np.asarray(diag0["momentum"], dtype=float)[: self.d]
        self.t0 = sim.time
        self.nc, self.t_end = scene.collisions, scene.time
        self.ckpt_every = scene.checkpoint_interval if checkpoints else 0
        self.traj_every = scene.trajectory_every if trajectory is not None else 0
        self.trajectory = trajectory
        # with a plot, 9 intermediate round trips (by collisions, or by time)
        self.plot_c: set[int] = set()
        self.plot_t: list[float] = []
        if plot is not None:
            if self.nc is not None:
                self.plot_c = {max(1, round(self.nc * k / 10)) for k in range(1, 10)} - {self.nc}
            else:
                self.plot_t = [self.t0 + (self.t_end - self.t0) * k / 10 for k in range(1, 10)]
        self.writer = None
        self.frames_t: list[float] = []
        # each forward frame's image flags and the quarter of the box each particle is in, by the
        # frame's time: its reverse twin's (reverse frames are taken at the forward frames' times)
        self.images: dict = {}
        self.quarters: dict = {}
        if trajectory is not None:
            from .trajectory import open_trajectory  # the writers only when a run writes frames

            if observes_frames(scene, trajectory):
                sim.observe()  # the observer's unwrapped positions give the frames' image flags (not reported)
            kinds = trajectory_kinds(scene.species, sim.diameters if scene.species else None)
            self.writer = open_trajectory(trajectory, self.box, self.periodic, scene.diameter, **kinds)
            self.forward_frame(0)
        self.curve: list[dict] = []
        self.energy_series: list[tuple[int, float]] = [(0, 0.0)] if plot is not None else []
        self.written_ckpt: list[str] = []
        self.done, self.back, self.forward_s, self.reverse_s = 0, 0, 0.0, 0.0
        self.interrupted: str | None = None

    def momentum_drift(self, diag: dict) -> float | None:
        if not self.conserved.any():
            return None
        dp = (np.asarray(diag["momentum"], dtype=float)[: self.d] - self.p0)[self.conserved]
        return float(np.sqrt((dp * dp).sum()) / math.sqrt(2.0 * self.e0 * self.n))

    def next_stop(self) -> int | None:
        """The collision count the forward run pauses at next (None: none before the end)."""
        cands = [c for c in self.plot_c if c > self.done]
        for every in (self.ckpt_every, self.traj_every):
            if every:
                cands.append((self.done // every + 1) * every)
        if self.nc is not None:
            cands = [min(c, self.nc) for c in cands] + [self.nc]
        return min(cands) if cands else None

    def forward(self, stop: Interrupt) -> None:
        sim, nc = self.sim, self.nc
        every = max(1, min(10_000, (nc // 200) if nc is not None else max(1, self.n // 2)))
        series_every = max(every, (nc // 200) if nc is not None else every)
        total = float(nc) if nc is not None else float(self.t_end - self.t0)
        bar = Bar(self.progress, total, "forward", "coll" if nc is not None else "t")
        base = 0

        def callback(k: int) -> bool:
            c = base + k
            if self.plot is not None and c % series_every < every:
                self.energy_series.append((c, float(sim.diagnostics()["energy_drift"])))
            bar.to(c if nc is not None else sim.time - self.t0)
            return stop.presses == 0
        try:
            while True:
                stop_c = self.next_stop()
                stop_t = min([t for t in self.plot_t if t > sim.time] + ([self.t_end] if self.t_end is not None else []),
                             default=None)
                base = self.done
                tick = _time.perf_counter()
                r = sim.run(collisions=None if stop_c is None else stop_c - self.done, time=stop_t,
                            callback=callback, every=every)
                self.forward_s += _time.perf_counter() - tick
                self.done += int(r["collisions"])
                if stop.presses:
                    self.interrupted = "forward"
                    break
                if self.pause():
                    break
        finally:
            bar.close()

    def pause(self) -> bool:
        """Checkpoint, frame and intermediate round trip at a stop; True when the run is done."""
        sim, done = self.sim, self.done
        finished = (self.nc is not None and done >= self.nc) or (self.t_end is not None and sim.time >= self.t_end)
        if self.ckpt_every and done % self.ckpt_every == 0 and done > 0:
            path = Path(self.scene.checkpoints) / f"checkpoint-{done:012d}.npz"
            path.parent.mkdir(parents=True, exist_ok=True)
            sim.save(path)
            self.written_ckpt.append(str(path))
        if self.writer is not None and not finished and done % self.traj_every == 0 and done > 0:
            self.forward_frame(done)
        if finished:
            return True
        if (done in self.plot_c) or (self.plot_t and sim.time in self.plot_t):
            clone = Simulation.from_snapshot(sim.snapshot())
            clone.run_back(on_divergence="ignore")
            ex, ev = round_trip_errors(clone.positions, clone.velocities, self.x0, self.v0, self.box, self.periodic)
            self.curve.append({"collisions": done, "time": sim.time, "error_x": ex, "error_v": ev})
        return False

    def turn(self) -> None:
        sim = self.sim
        self.t_turn = sim.time
        self.diag_turn = sim.diagnostics()
        if self.scene.observe is not None:
            self.observation = sim.observation()
        self.shot_turn = (sim.positions, sim.velocities)
        if self.plot is not None:
            self.energy_series.append((self.done, float(self.diag_turn["energy_drift"])))
        if self.writer is not None and (not self.frames_t or self.frames_t[-1] != self.t_turn):
            self.forward_frame(self.done)

    def forward_frame(self, done: int) -> None:
        from .trajectory import true_images

        sim = self.sim
        x = sim.positions
        self.images[sim.time] = true_images(sim, x)
        # which quarter of each periodic axis it is in: its reverse twin, back within the round-off
        # horizon, may sit just across a boundary from it (one image away)
        self.quarters[sim.time] = np.floor(4.0 * x / self.box).astype(np.int8)
        self.frames_t.append(sim.time)
        self.writer.write(x, sim.velocities, sim.time, done, "forward", image=self.images[sim.time])

    def reverse_image(self, x: np.ndarray, t: float):
        """The image flags of a reverse frame at a forward frame's time: that frame's, less one
        where a particle came back just across the lower boundary and plus one across the upper
        (a twin within a quarter box of it); None at any other time (the writer infers them)."""
        if self.images.get(t) is None:
            return None
        q, low, high = self.quarters[t], x < 0.25 * self.box, x >= 0.75 * self.box
        shift = np.where((q == 3) & low, 1, 0) - np.where((q == 0) & high, 1, 0)
        return self.images[t] + np.where(self.periodic, shift, 0)

    def reverse(self, stop: Interrupt, presses_at_turn: int) -> None:
        """Back to the start: in chunks (each run_back re-predicts every event, about the cost
        of 0.2 N collisions, so chunks are >= 20 N collisions) or, with a trajectory, to each
        forward frame's time in turn."""
        sim, done = self.sim, self.done
        bar = Bar(self.progress, float(done), "reverse", "coll")
        try:
            if self.writer is not None:
                targets = self.frames_t[-2::-1]
            else:
                chunk = max(20 * self.n, done // 100, 1)
                targets = [None] * max(0, math.ceil(done / chunk) - 1) + ["start"]
            for target in targets:
                if stop.presses > presses_at_turn:
                    self.interrupted = "reverse"
                    break
                tick = _time.perf_counter()
                if target is None:
                    r = sim.run_back(collisions=chunk, on_divergence="ignore")
                elif target == "start" or target == self.t0:
                    r = sim.run_back(on_divergence="ignore")
                else:
                    r = sim.run_back(time=target, on_divergence="ignore")
                self.reverse_s += _time.perf_counter() - tick
                self.back += int(r["collisions"])
                bar.to(self.back)
                if self.writer is not None:  # at a forward frame's time: that frame's flags
                    x = sim.positions
                    self.writer.write(x, sim.velocities, sim.time, done - self.back, "reverse",
                                      image=self.reverse_image(x, sim.time))
        finally:
            bar.close()
            if self.writer is not None:
                self.writer.close()

    def report(self) -> dict[str, Any]:
        sim, scene, done, n = self.sim, self.scene, self.done, self.n
        diag_end, diag_turn = sim.diagnostics(), self.diag_turn
        complete = sim.time == self.t0 and self.interrupted != "reverse"
        ex, ev = round_trip_errors(sim.positions, sim.velocities, self.x0, self.v0, self.box, self.periodic)
        if self.plot is not None and complete:
            self.curve.append({"collisions": done, "time": self.t_turn, "error_x": ex, "error_v": ev})
        fs, rs = self.forward_s, self.reverse_s
        paused = self.ckpt_every or self.traj_every or self.plot is not None
        return {
            "kind": "gas", "revcol_version": __version__, "scene": scene.to_dict(), "summary": scene.summary(),
            "particles": n, "dimension": self.d, "box": self.box.tolist(), "periodic": self.periodic.tolist(),
            "collisions_forward": done, "collisions_back": self.back, "per_particle": 2.0 * done / n,
            "time_start": self.t0, "time_turn": self.t_turn, "time_end": sim.time,
            "forward_s": fs, "reverse_s": rs,
            "forward_per_s": done / fs if fs > 0 else None, "reverse_per_s": self.back / rs if rs > 0 else None,
            "segments_note": ("the runs paused for checkpoints, frames or the plot's round trips; the rates "
                              "count engine calls only" if paused else ""),
            "error_x": ex, "error_v": ev, "error_definitions": ERROR_DEFINITIONS, "bar": BAR,
            "round_trip_complete": complete, "passed": bool(complete and ex <= BAR and ev <= BAR),
            "interrupted": self.interrupted,
            "energy_drift_turn": float(diag_turn["energy_drift"]), "energy_drift_end": float(diag_end["energy_drift"]),
            "momentum_drift_turn": self.momentum_drift(diag_turn), "momentum_drift_end": self.momentum_drift(diag_end),
            "drift_definitions": {"energy": "(E - E0) / E0, E kinetic (plus the potential in a field)",
                                  "momentum": "|P - P0| / sqrt(2 E0 N) over the periodic axes (None: walls only, or a bounce-back wall)"},
            "log_bytes_turn": int(diag_turn["log_bytes"]), "log_bytes_end": int(diag_end["log_bytes"]),
            "reverse_failures": int(diag_end["events"]["reverse_failures"]),
            "observe": self.observation.to_dict() if self.observation is not None else None,
            "gravity": sim.gravity.tolist() if sim.gravity.any() else None,  # the field run (None: none)
            # the collision trace (docs/robustness.md): where the reversal was found off the forward run
            "divergence": diag_end["divergence"], "diverged_at": diag_end["diverged_at"],
            "verified_at": diag_end["verified_at"],
            "list_renewals_turn": list_renewals(diag_turn["events"]),
            "events_turn": diag_turn["events"],
            "peak_rss_bytes": peak_rss(),
            "checkpoints": self.written_ckpt,
            "trajectory": str(self.trajectory) if self.trajectory is not None else None,
            "trajectory_frames": self.writer.frames if self.writer is not None else 0,
            "curve": self.curve, "energy_series": [list(p) for p in self.energy_series],
            "date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
            "written": [],
        }


def run_gas(scene: Scene, *, plot: str | os.PathLike | None = None,
            trajectory: str | os.PathLike | None = None, progress: bool | None = None,
            checkpoints: bool = True, plot_format: str = "png") -> dict:
    """Runs a gas scene forward and back; returns the report (a dict, see
    :mod:`revcol.studies.scenes`; a lattice scene's: :mod:`revcol.lattice_gas`).

    ``plot``: a directory for the PNG figures (round-trip error and energy drift against
    collisions, snapshots at the start, the turn and the end); ``trajectory``: a ``.xyz`` or
    ``.gsd`` file of frames every ``scene.trajectory_every`` collisions, forward and through
    the reversal (at the same times); ``progress``: a bar (None: when stdout is a
    terminal); ``checkpoints``: write the scene's ``.npz`` checkpoints. Outputs are checked
    before anything runs."""
    if scene.kind != "gas":
        raise SceneError(f"{scene.source}: [scene] kind: run_gas needs a 'gas' scene, got {scene.kind!r}")
    if trajectory is not None:
        from .trajectory import check_format  # the writers only when a run writes frames

        try:
            check_format(trajectory)
        except ValueError as e:
            raise SceneError(str(e)) from None
    if plot is not None:
        plots.require_matplotlib()
        plots.check_format(plot_format)
    if progress is None:
        progress = sys.stdout.isatty()
    if scene.engine == "lattice":  # the lattice engine's run (revcol.lattice_gas), its own figures
        return round_trip(_LatticeRun(scene, plot, trajectory, progress, checkpoints), plot, "plot_lattice_gas",
                          plot_format)
    return round_trip(_GasRun(scene, plot, trajectory, progress, checkpoints), plot, "plot_gas", plot_format)


def round_trip(run, plot, figures: str, plot_format: str = "png") -> dict:
    """Forward, turn, back (Ctrl-C counted throughout), the report, and with ``plot`` the
    figures drawn by ``revcol.plots.<figures>``. ``run`` is a gas run (this module's, or the
    lattice engine's in :mod:`revcol.lattice_gas`). An error that ends the run (an output that
    cannot be written: a full disk) closes the trajectory on its way out (:meth:`close_quietly`:
    its frames kept, or no partial file left)."""
    try:
        with Interrupt() as stop:
            run.forward(stop)
            run.turn()
            run.reverse(stop, stop.resume())  # back from where a Ctrl-C stopped the forward run
    except BaseException:
        if run.writer is not None:
            run.writer.close_quietly()
        raise
    report = run.report()
    if plot is not None:
        sim = run.sim
        report["written"] += getattr(plots, figures)(report, Path(plot), (run.x0, run.v0), run.shot_turn,
                                                     (sim.positions, sim.velocities), fmt=plot_format)
    return report



#: bytes a gas scene needs per particle, measured with margin: the float engine holds 254 (2D) to
#: 282 (3D) bytes per particle (N = 1e5, Simulation.diagnostics()["memory_bytes"]); the start
#: arrays, the report's copies and Python's arrays come on top
BYTES_PER_PARTICLE = 1024


def _available_bytes() -> int | None:
    """MemAvailable from /proc/meminfo (None where there is none)."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        return None
    return None


def check_memory(scene: Scene) -> None:
    need, have = scene.particles * BYTES_PER_PARTICLE, _available_bytes()
    if have is not None and need > have:
        raise SceneError(f"{scene.source}: [system] particles: {scene.particles} particles need about "
                         f"{need / 2**30:.1f} GiB ({BYTES_PER_PARTICLE} bytes each), this machine has "
                         f"{have / 2**30:.1f} GiB available")


def check_output(source: str, what: str, path, folder: bool) -> None:
    """Raises SceneError naming ``what`` unless ``path`` can be written: not the scene file, not a
    folder where a file goes (or the reverse), its folder creatable and writable (tried). One
    output alone; a run checks all of its outputs against all of its inputs at once
    (:func:`revcol._outputs.check_outputs`, which this calls)."""
    inputs = [Input("the scene file itself", source)] if source and Path(source).is_file() else []
    check_outputs(source, [Output(what, path, folder)], inputs)
