"""A gas scene on the lattice engine (``[collisions] engine = "lattice"``): forward N_c
collisions (or to an end time), back to the start, and a report of what came back **bit for
bit** (:class:`revcol.lattice.LatticeSimulation` for disks, :class:`LatticeSimulation3D` for
spheres; LATTICE.md, docs/lattice.md).

The lattice engine's state is integers: positions and velocities in lattice units, the
per-particle Philox stream counters, the bits-back integer X (which carries each collision's
sub-tick phase and realises the torus shift exactly), the rare log and the clock (a tick
count). Every collision is an exact integer bijection, so the reversal restores each of them
exactly, for any number of collisions; the float start is quantized once (its error is
reported) and the round trip is exact from the quantized state on. :func:`restored` compares
each part of the state exactly; the round trip passes when every part is equal. In specular
mode (``[collisions] mode = "specular"``) no number is drawn (but for the rare logged fallback)
and the report counts the backscatters (pairs the specular map turned back in place).

The run goes forward in chunks (about 200 of them, at most 10^4 collisions each; the lattice
engine's run is the same in chunks as in one call) so that Ctrl-C stops it between chunks and
X's size and the energy drift are sampled as it goes; then back in chunks. An engine error
(a collision the engine cannot resolve) ends the phase it happens in; the report names it and
fails.

:func:`lattice_horizon` is ``revcol run --horizon`` on a lattice scene: there is no horizon,
and it checks that claim bit for bit at a few N_c.
"""
from __future__ import annotations

import datetime as dt
import math
import sys
import time as _time
from pathlib import Path
from typing import Any, Callable

import numpy as np

from . import _core
from .lattice import LatticeSimulation, LatticeSimulation3D, add_reports
from .progress import Bar, Interrupt, peak_rss
from ._species import trajectory_kinds
from ._version import __version__
from .roundtrip import BAR, round_trip_errors
from .scene import Scene, SceneError, lattice_options, observes_frames, read_initial

__all__ = ["build_lattice", "lattice_horizon", "restored", "RESTORED_PARTS",
           "LATTICE_HORIZON_GRID"]

#: the parts of the state compared exactly after the round trip: report name -> snapshot() keys
RESTORED_PARTS: dict[str, tuple[str, ...]] = {
    "positions": ("x",),
    "velocities": ("v",),
    "rng_counters": ("streams",),
    "bits_back": ("bits", "bits_size"),
    "clock": ("clock", "origin"),
    "collision_count": ("collisions", "particle_collisions"),
    "rare_log": ("log_particle", "log_count", "log_redraws", "group_drawer", "group_draws", "group_size",
                 "group_members", "group_counts", "group_kind", "group_v"),
}

_LOG_KEYS = RESTORED_PARTS["rare_log"]

#: collisions per particle (2 N_c / N) at which :func:`lattice_horizon` checks the round trip
LATTICE_HORIZON_GRID = (1.0, 10.0, 100.0)


def build_lattice(scene: Scene, seed: int | None = None) -> LatticeSimulation:
    """The lattice engine for a gas scene: the float engine's random start quantized once
    (``[system] packing_fraction`` without ``kinetic_energy``: ``LatticeSimulation.random``),
    else the float start in the scene's box, or its initial-state file, quantized once. Under
    shear a random start gets the steady profile (as ``LatticeSimulation.random``'s), an
    initial state runs its velocities as given.
    ``seed`` overrides the scene's. A state the lattice refuses raises :class:`SceneError`."""
    if scene.kind != "gas" or scene.engine != "lattice":
        raise SceneError(f"{scene.source}: [collisions] engine: build_lattice needs a lattice gas scene")
    opts = lattice_options(scene)
    if seed is not None:
        opts["seed"] = int(seed)
    init = {"auto": "auto", "random": "rsa", "crystal": "crystal", "relax": "relax"}[scene.start]
    cls = LatticeSimulation3D if scene.dimension == 3 else LatticeSimulation
    if scene.initial_state is not None:
        x, v = read_initial(scene.source, scene.initial_state, scene.dimension)
        return _make(scene, "[system] initial_state", lambda: cls(x, v, scene.box, **opts))
    if scene.packing_fraction is not None and scene.kinetic_energy is None:
        return _make(scene, "[system] packing_fraction", lambda: cls.random(
            scene.particles, scene.dimension, scene.packing_fraction, init=init, **opts))

    def make() -> LatticeSimulation:  # the float engine's start in the scene's box, quantized
        x, v = _core.engine_random_start(scene.particles, list(scene.box), list(scene.boundaries), scene.diameter,
                                         opts["seed"], scene.kinetic_energy or 0.0, init, False,
                                         diameters=list(opts.get("diameters", [])))
        if scene.shear_rate:  # the steady profile, centred (no momentum added), as random()'s
            x, v = np.asarray(x, dtype=float), np.array(v, dtype=float)
            v[:, 0] += scene.shear_rate * (x[:, 1] - x[:, 1].mean())
        return cls(x, v, scene.box, **opts)
    return _make(scene, "[system] box" if scene.packing_fraction is None else "[system] kinetic_energy", make)


def _make(scene: Scene, where: str, make: Callable[[], LatticeSimulation]) -> LatticeSimulation:
    try:
        return make()
    except ValueError as e:
        raise SceneError(f"{scene.source}: {where}: {e}") from None


def restored(start: dict, end: dict) -> dict[str, bool]:
    """Each part of :data:`RESTORED_PARTS`: is it exactly (every integer, every word) the start's?"""
    return {name: all(np.array_equal(np.asarray(start[k]), np.asarray(end[k])) for k in keys)
            for name, keys in RESTORED_PARTS.items()}


def log_size(state: dict) -> tuple[int, int]:
    """(entries, bytes) of the rare log in a state: its collisions (one entry each: those that
    needed redraws, keyed in ``log_particle``/``log_count``, and the group collisions, in
    ``group_drawer``), as ``diagnostics()["log_entries"]``, and the bytes its arrays take in a
    checkpoint."""
    entries = len(state["log_particle"]) + len(state["group_drawer"])
    return entries, int(sum(np.asarray(state[k]).nbytes for k in _LOG_KEYS))


def geometry(sim: LatticeSimulation) -> tuple[np.ndarray, np.ndarray]:
    """(box lengths in float units, periodic flags) of a lattice simulation."""
    u = sim.units
    return np.asarray(u["L"], dtype=float) * u["length_unit"], ~np.asarray(u["wall"], dtype=bool)


class _LatticeRun:
    """One round trip of a lattice gas scene; the phases share the engine and what they measured."""

    def __init__(self, scene: Scene, plot, trajectory, progress: bool, checkpoints: bool):
        self.scene, self.plot, self.progress = scene, plot, progress
        self.sim = sim = build_lattice(scene)
        # [observe]: the forward run itself is observed (run_back ends the observation)
        self.observation = None
        if scene.observe is not None:
            sim.observe(**scene.observe)
        self.n = sim.n
        self.box, self.periodic = geometry(sim)
        self.s0 = sim.snapshot()
        self.x0, self.v0 = sim.positions, sim.velocities
        self.bits0 = self.bits_max = int(sim.diagnostics()["bits_length"])
        self.nc = scene.collisions
        self.tick_end = None if scene.time is None else int(round(scene.time / sim.units["tick"]))
        self.every = max(1, min(10_000, (self.nc // 200) if self.nc is not None else 10 * self.n))
        if sim.parallel["lps"] > 1:  # the parallel engine: calls long enough to pay for its K views
            self.every = max(self.every, 2 * self.n, (self.nc or 0) // 20, 16_384)
        self.parallel: dict | None = None  # the forward run's report on the parallel engine
        self.parallel_back: dict | None = None  # the run back's
        self.ckpt_every = scene.checkpoint_interval if checkpoints else 0
        self.traj_every = scene.trajectory_every if trajectory is not None else 0
        self.trajectory, self.writer = trajectory, None
        self.frames: list[int] = []
        self.images: dict = {}  # each forward frame's image flags by its count: its reverse twin's (the same state)
        if trajectory is not None:
            from .trajectory import open_trajectory  # the writers only when a run writes frames

            if observes_frames(scene, trajectory):
                sim.observe()  # the observer's unwrapped positions give the frames' image flags (not reported)
            kinds = trajectory_kinds(scene.species, sim.diameters if scene.species else None)
            self.writer = open_trajectory(trajectory, self.box, self.periodic, scene.diameter, **kinds)
            self.frame(0, "forward")
        self.energy_series: list[tuple[int, float]] = [(0, 0.0)]
        self.bits_series: list[tuple[int, int]] = [(0, self.bits0)]
        self.written_ckpt: list[str] = []
        self.done, self.back, self.forward_s, self.reverse_s = 0, 0, 0.0, 0.0
        self.cpu = {"forward": 0.0, "reverse": 0.0}  # process CPU seconds in the engine calls
        self.interrupted: str | None = None
        self.engine_error: str | None = None

    def frame(self, collisions: int, phase: str) -> None:
        from .trajectory import true_images

        sim, x = self.sim, self.sim.positions
        if phase == "forward":
            image = true_images(sim, x)
            self.frames.append(collisions)
            self.images[collisions] = image
        else:  # back at a forward frame's count, bit for bit: that frame's flags
            image = self.images.get(collisions)
        self.writer.write(x, sim.velocities, sim.time, collisions, phase, image=image)

    def sample(self, collisions: int) -> None:
        d = self.sim.diagnostics()
        self.bits_max = max(self.bits_max, int(d["bits_length"]))
        self.energy_series.append((collisions, float(d["energy_drift"])))
        self.bits_series.append((collisions, int(d["bits_length"])))

    def finished(self) -> bool:
        return ((self.nc is not None and self.done >= self.nc)
                or (self.tick_end is not None and self.sim.clock >= self.tick_end))

    def forward(self, stop: Interrupt) -> None:
        sim = self.sim
        bar = Bar(self.progress, float(self.nc if self.nc is not None else self.tick_end), "forward",
                  "coll" if self.nc is not None else "tick")
        try:
            while not self.finished():
                stops = [(self.done // self.every + 1) * self.every]
                stops += [(self.done // k + 1) * k for k in (self.ckpt_every, self.traj_every) if k]
                if self.nc is not None:
                    stops.append(self.nc)
                tick, cpu = _time.perf_counter(), _time.process_time()
                try:
                    r = sim.run(collisions=min(stops) - self.done,
                                time=None if self.tick_end is None else self.tick_end * sim.units["tick"])
                except RuntimeError as e:  # a collision the engine cannot resolve: stop here
                    self.engine_error = f"forward: {e}"
                    self.done = sim.collisions
                    break
                finally:
                    self.forward_s += _time.perf_counter() - tick
                    self.cpu["forward"] += _time.process_time() - cpu
                self.done += int(r["collisions"])
                self.parallel = add_reports(self.parallel, r.get("parallel"))
                self.sample(self.done)
                bar.to(self.done if self.nc is not None else sim.clock)
                if stop.presses:
                    self.interrupted = "forward"
                    break
                self.pause()
        finally:
            bar.close()

    def pause(self) -> None:
        """A checkpoint and a trajectory frame where the count has reached one."""
        sim, done = self.sim, self.done
        if self.ckpt_every and done % self.ckpt_every == 0 and done > 0:
            path = Path(self.scene.checkpoints) / f"checkpoint-{done:012d}.npz"
            path.parent.mkdir(parents=True, exist_ok=True)
            sim.save(path)
            self.written_ckpt.append(str(path))
        if self.writer is not None and done % self.traj_every == 0 and done > 0 and not self.finished():
            self.frame(done, "forward")

    def turn(self) -> None:
        sim = self.sim
        self.diag_turn = sim.diagnostics()
        if self.scene.observe is not None:
            self.observation = sim.observation()
        self.state_turn = sim.snapshot()
        self.t_turn, self.clock_turn = sim.time, sim.clock
        self.shot_turn = (sim.positions, sim.velocities)
        if self.writer is not None and self.frames[-1] != self.done:
            self.frame(self.done, "forward")

    def reverse(self, stop: Interrupt, presses_at_turn: int) -> None:
        """Back to the start: in chunks of about 2% of the run (at least 20 N collisions), or through each forward frame's
        collision count (``run_back(to_collision=k)``: the forward state at k, bit for bit)."""
        sim, done = self.sim, self.done
        bar = Bar(self.progress, float(done), "reverse", "coll")
        if self.writer is not None:
            targets = self.frames[-2::-1]
        else:
            chunk = max(self.every, 20 * self.n, done // 50, 1)  # a run_back call re-predicts every event
            targets = list(range(done - chunk, 0, -chunk)) + [0]
        try:
            for target in targets:
                if stop.presses > presses_at_turn:
                    self.interrupted = "reverse"
                    break
                tick, cpu = _time.perf_counter(), _time.process_time()
                try:
                    r = sim.run_back(to_collision=target) if target > 0 else sim.run_back()
                    self.parallel_back = add_reports(self.parallel_back, r.get("parallel"))
                except (RuntimeError, ValueError) as e:
                    self.engine_error = (self.engine_error + "; " if self.engine_error else "") + f"reverse: {e}"
                    break
                finally:
                    self.reverse_s += _time.perf_counter() - tick
                    self.cpu["reverse"] += _time.process_time() - cpu
                self.back = done - sim.collisions
                self.bits_max = max(self.bits_max, int(sim.diagnostics()["bits_length"]))
                bar.to(self.back)
                if self.writer is not None:
                    self.frame(sim.collisions, "reverse")
        finally:
            bar.close()
            if self.writer is not None:
                self.writer.close()

    def report(self) -> dict[str, Any]:
        return lattice_report(self)


def lattice_report(run: _LatticeRun) -> dict[str, Any]:
    """The report of a lattice round trip (see :mod:`revcol.cli.report` for its text)."""
    sim, scene, done, n = run.sim, run.scene, run.done, run.n
    end, d_turn, d_end = sim.snapshot(), run.diag_turn, sim.diagnostics()
    same = restored(run.s0, end)
    complete = sim.collisions == 0 and run.interrupted != "reverse" and run.engine_error is None
    ex, ev = round_trip_errors(sim.positions, sim.velocities, run.x0, run.v0, run.box, run.periodic)
    fs, rs = run.forward_s, run.reverse_s
    v0 = np.asarray(run.s0["v"], dtype=float)
    p_scale = math.sqrt(n * float((v0 * v0).sum()))  # sqrt(2 E0 N) in lattice units, as the float report

    def momentum(d: dict) -> dict | None:
        if not run.periodic.any():
            return None
        dp = np.asarray(d["momentum_drift"], dtype=float)[run.periodic]
        return {"lattice_units": dp.tolist(), "relative": float(np.sqrt((dp * dp).sum()) / p_scale)}
    entries_turn, bytes_turn = log_size(run.state_turn)
    entries_end, bytes_end = log_size(end)
    redraws = {k: int(c) for k, c in d_turn["redraws"].items()}
    per = (lambda c: c / done) if done else (lambda c: 0.0)
    units = sim.units
    return {
        "kind": "gas", "engine": "lattice", "revcol_version": __version__, "scene": scene.to_dict(),
        "summary": scene.summary(), "particles": n, "dimension": sim.dim, "box": run.box.tolist(),
        "periodic": run.periodic.tolist(),
        "units": {"S": units["S"], "sigma": units["sigma"], "tick": units["tick"],
                  "tick_bits": units["tick_bits"], "cell_bits": units["cell_bits"],
                  "length_unit": units["length_unit"], "L": list(units["L"])},
        "search": sim.search,  # the neighbour search in use: "cells" or the lists' shell in diameters
        # the forward run on the parallel engine: its settings and report (None: sequential)
        "parallel": None if run.parallel is None else {**sim.parallel, **run.parallel},
        "parallel_back": None if run.parallel_back is None else {**sim.parallel, **run.parallel_back},
        "mode": sim.mode,
        "quantization": sim.quantization,
        # the field run, quantized once (its relative rounding: quantization's gravity_error); None: none
        "gravity": sim.gravity.tolist() if sim.gravity.any() else None,
        # Lees-Edwards shear run (1 / time; None: none) and its integer, lattice units per tick (the
        # rounding: quantization's shear_error)
        "shear_rate": sim.shear_rate or None, "shear_per_tick": int(units.get("shear", 0)) or None,
        "collisions_forward": done, "collisions_back": run.back, "per_particle": 2.0 * done / n,
        "time_start": 0.0, "time_turn": run.t_turn, "time_end": sim.time, "clock_turn": run.clock_turn,
        "clock_end": sim.clock,
        "forward_s": fs, "reverse_s": rs,
        "forward_per_s": done / fs if fs > 0 else None, "reverse_per_s": run.back / rs if rs > 0 else None,
        "forward_cpu_s": run.cpu["forward"], "reverse_cpu_s": run.cpu["reverse"],
        "forward_per_cpu_s": done / run.cpu["forward"] if run.cpu["forward"] > 0 else None,
        "reverse_per_cpu_s": run.back / run.cpu["reverse"] if run.cpu["reverse"] > 0 else None,
        "restored": same, "bit_for_bit": bool(complete and all(same.values())),
        "error_x": ex, "error_v": ev, "bar": BAR,
        "round_trip_complete": complete, "passed": bool(complete and all(same.values())),
        "interrupted": run.interrupted, "engine_error": run.engine_error,
        "observe": run.observation.to_dict() if run.observation is not None else None,
        "bits_back": {"start": run.bits0, "turn": int(d_turn["bits_length"]), "end": int(d_end["bits_length"]),
                      "max": run.bits_max, "sampled_every": run.every, "particles": sim.n},
        "log_entries_turn": entries_turn, "log_bytes_turn": bytes_turn,
        "log_entries_end": entries_end, "log_bytes_end": bytes_end,
        "group_resolves": int(d_turn["group_resolves"]), "group_bounces": int(d_turn["group_bounces"]),
        "backscatters": int(d_turn["backscatters"]),  # specular mode: pairs turned back in place
        "log_entries_per_collision": per(entries_turn),
        "redraws": redraws, "redraws_total": sum(redraws.values()), "redraws_per_collision": per(sum(redraws.values())),
        "multi_body": int(d_turn["multi_body"]), "wall_body": int(d_turn["wall_body"]),
        "energy_drift_turn": float(d_turn["energy_drift"]), "energy_drift_end": float(d_end["energy_drift"]),
        "momentum_drift_turn": momentum(d_turn), "momentum_drift_end": momentum(d_end),
        "drift_definitions": {"energy": "(E - E0) / E0, E = sum |v|^2 on the integers (in a field plus the potential, "
                                        "2 |g| times each centre's height above the floor)",
                              "momentum": "P - P0 per periodic axis in lattice units (the operator moves it by "
                                          "at most one unit per collision), and |P - P0| / sqrt(2 E0 N)"},
        "events_turn": {k: int(d_turn[k]) for k in ("events", "walls", "crossings", "stale")},
        "engine_memory_bytes": int(d_turn["memory_bytes"]), "peak_rss_bytes": peak_rss(),
        "checkpoints": run.written_ckpt,
        "trajectory": str(run.trajectory) if run.trajectory is not None else None,
        "trajectory_frames": run.writer.frames if run.writer is not None else 0,
        "energy_series": [list(p) for p in run.energy_series], "bits_series": [list(p) for p in run.bits_series],
        "date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"), "written": [],
    }


def lattice_horizon(scene: Scene, *, seeds: int = 1, max_collisions: int = 1_000_000,
                    progress: bool | None = None) -> dict:
    """``--horizon`` on a lattice scene: there is none. For each seed, one forward run stops at
    each N_c of :data:`LATTICE_HORIZON_GRID` (up to ``max_collisions``); a copy of the state
    (``snapshot()`` / ``from_snapshot``) runs back to the start and is compared with it exactly.
    ``passed`` when every round trip is bit for bit."""
    if progress is None:
        progress = sys.stdout.isatty()
    n = scene.particles
    grid = sorted({max(1, round(c * n / 2)) for c in LATTICE_HORIZON_GRID if round(c * n / 2) <= max_collisions})
    grid = grid or [max(1, int(max_collisions))]
    rows = {nc: {"collisions": nc, "per_particle": 2.0 * nc / n, "bit_for_bit": 0, "seeds": 0, "errors": []}
            for nc in grid}
    bar = Bar(progress, float(seeds * len(grid)), "horizon", "pt")
    with Interrupt() as stop:
        try:
            _horizon_seeds(scene, seeds, grid, rows, bar, stop)
        finally:
            bar.close()
        interrupted = stop.presses > 0
    table = [r for r in rows.values() if r["seeds"]]
    length = f"round trips of up to {grid[-1]:,} collisions"  # not the scene's own [run] length
    return {"kind": "horizon", "engine": "lattice", "scene": scene.to_dict(), "summary": scene.summary(length),
            "seeds": seeds, "seed_first": scene.seed, "max_collisions": int(max_collisions), "rows": table,
            "passed": all(r["bit_for_bit"] == r["seeds"] for r in table),
            "horizon_reached": False, "interrupted": "horizon" if interrupted else None,
            "peak_rss_bytes": peak_rss(),
            "date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"), "written": []}


def _horizon_seeds(scene: Scene, seeds: int, grid: list[int], rows: dict, bar: Bar, stop: Interrupt) -> None:
    """The round trips of :func:`lattice_horizon`, counted into ``rows``."""
    for s in range(seeds):
        sim = build_lattice(scene, scene.seed + s)
        s0, done = sim.snapshot(), 0
        for nc in grid:
            try:
                done += int(sim.run(collisions=nc - done)["collisions"])
                clone = LatticeSimulation.from_snapshot(sim.snapshot())
                clone.run_back()
                if stop.presses:  # Ctrl-C stopped the run or its reversal short of N_c: not counted
                    return
                ok = all(restored(s0, clone.snapshot()).values())
            except RuntimeError as e:
                ok = False
                rows[nc]["errors"].append(f"seed {scene.seed + s}: {e}")
            rows[nc]["seeds"] += 1
            rows[nc]["bit_for_bit"] += int(ok)
            bar.to(s * len(grid) + grid.index(nc) + 1)
            if not ok or stop.presses:
                break
        if stop.presses:
            break
