"""How many bytes a run's outputs will write, estimated before it runs (issue 59: outputs that
never fill a disk). :func:`revcol._outputs.check_outputs` compares the estimates with the output
limit and with the free space of the file system they go to.

- **Trajectory**: frames x (the frame's header + N x bytes per particle). The frame count is the
  run's own: ``revcol run`` writes the start, every ``trajectory_every`` collisions, the turn,
  and each of these again through the reversal (:func:`round_trip_frames`); ``revcol simulate``
  the start, every ``every`` collisions (or every ``every_time`` in time) and the end
  (:func:`production_frames`). Bytes per particle: extended XYZ is measured on a sample frame
  (up to :data:`SAMPLE_ROWS` particles: the initial state's, a resumed run's, or positions
  uniform in the scene's box with Maxwell velocities at its temperature) formatted by the
  writer's own code (:func:`revcol.trajectory.frame_size`); GSD from its chunk sizes.
- **Checkpoints**: count x the state's bytes, a + b N, measured by saving the scene's engine (its
  dimension, boundaries, streams, mode and ``[observe]``) at :data:`SAMPLE_PARTICLES` particles
  (:func:`state_bytes`); measured once per configuration in a process.
- **JSON report** and **figures**: fixed allowances (:data:`REPORT_BYTES`, :data:`FIGURE_BYTES`),
  with a share per histogram bin and, for vector figures, per particle drawn.
- **A sweep** (``revcol sweep``): its points write no trajectory, checkpoint or figure of their
  own (revcol.sweep.spec strips them), only their reports, ``points/HASH.json``: one report
  allowance per point still to run (:func:`sweep_points_size`); and the sweep's table, summary and
  figures (:func:`sweep_files_size`: :data:`SWEEP_ROW_BYTES` a point for the table, a report
  allowance and :data:`SWEEP_SUMMARY_BYTES_PER_POINT` a point for the summary, a figure allowance
  for each of the horizon study's two figures).

A run stopped by time has no collision count to read: its collisions (or, for frames every
``every_time`` of a run of N collisions, its time) are the expected ones, from the Enskog
collision rate at the scene's density and temperature (:func:`collision_rate`: per particle
2 n sigma g sqrt(pi kT) in 2D, 4 n sigma^2 g sqrt(pi kT) in 3D, 2 n g sqrt(kT / pi) in 1D, with
g(sigma) of Carnahan-Starling, Henderson and Tonks), and the estimate says so ("about 4.3e+04
collisions expected in t = 3 at the Enskog collision rate"). It is an expectation, not a bound: a
start far from equilibrium collides at another rate (measured: 0.83-1.12 of the bytes written for
equilibrium starts of 200-4096 particles).
"""
from __future__ import annotations

import dataclasses
import math
import os
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from . import _core
from ._outputs import Size, human
from .gas import build_simulation
from .scene import Scene, read_initial

__all__ = ["collision_rate", "expected_collisions", "round_trip_frames", "round_trip_checkpoints",
           "production_frames", "production_checkpoints", "trajectory_size", "state_bytes", "checkpoints_size",
           "report_size", "figures_size", "sweep_points_size", "sweep_files_size", "REPORT_BYTES", "FIGURE_BYTES",
           "SWEEP_ROW_BYTES", "SWEEP_SUMMARY_BYTES_PER_POINT", "SAMPLE_PARTICLES", "SAMPLE_ROWS"]

#: the JSON report's allowance (measured: 3-19 KB for the example scenes), and per histogram bin
REPORT_BYTES = 256 << 10
REPORT_BYTES_PER_BIN = 256
#: a figure's allowance (measured: PNGs of 50-720 KB, the largest the snapshots of 1000 disks), and
#: per particle in a vector format, where the snapshots draw every particle three times (start, turn,
#: end; measured about 400 bytes a particle in SVG)
FIGURE_BYTES = 1 << 20
FIGURE_BYTES_PER_PARTICLE = 512
#: a sweep's table, per point: its CSV row and its Parquet row (measured: CSV rows of 300-800 bytes)
SWEEP_ROW_BYTES = 8 << 10
#: a sweep's summary, per point besides the report allowance: a missing, failed or combined entry
SWEEP_SUMMARY_BYTES_PER_POINT = 1 << 10
#: the particle counts whose saved states give a checkpoint's bytes as a + b N
SAMPLE_PARTICLES = (32, 64)
#: the particles of the sample frame whose extended XYZ lines are measured
SAMPLE_ROWS = 512
#: (a, b) of a checkpoint when its engine cannot be sampled (over every engine's measured 74-430 B)
FALLBACK_STATE = (float(64 << 10), 512.0)

_STATE_CACHE: dict[tuple, tuple[float, float]] = {}


def _state(scene: Scene, sim=None) -> tuple[int, np.ndarray | None]:
    """(N, velocities or None) of the run: a resumed engine's, the initial state's, or None."""
    if sim is not None:
        return int(sim.n), np.asarray(sim.velocities, dtype=float)
    if scene.initial_state is not None:
        return scene.particles, read_initial(scene.source, scene.initial_state, scene.dimension)[1]
    return scene.particles, None


def temperature(scene: Scene, sim=None) -> float:
    """kT (mass 1): of the velocities a run starts from, else from ``[system] kinetic_energy``
    (default N d / 2, kT = 1)."""
    n, v = _state(scene, sim)
    if v is not None:
        return float((v * v).sum()) / (n * scene.dimension)
    return 2.0 * (scene.kinetic_energy or 0.5 * n * scene.dimension) / (n * scene.dimension)


def collision_rate(scene: Scene, sim=None) -> float:
    """Collisions per unit time of the whole gas (each pair's counted once), Enskog's: N nu / 2,
    nu the rate per particle at the scene's number density, packing fraction and temperature."""
    n, d, sigma = (sim.n if sim is not None else scene.particles), scene.dimension, scene.diameter
    volume = float(np.prod(scene.box))
    eta = min(0.99, n * _core.engine_particle_volume(d, sigma) / volume)
    rho, kt = n / volume, temperature(scene, sim)
    if d == 1:
        nu = 2.0 * rho / (1.0 - eta) * math.sqrt(kt / math.pi)
    elif d == 2:
        nu = 2.0 * rho * sigma * (1.0 - 7.0 * eta / 16.0) / (1.0 - eta) ** 2 * math.sqrt(math.pi * kt)
    else:
        nu = 4.0 * rho * sigma ** 2 * (1.0 - eta / 2.0) / (1.0 - eta) ** 3 * math.sqrt(math.pi * kt)
    return 0.5 * (n if n > 1 else 0) * nu


def expected_collisions(scene: Scene, time: float, sim=None) -> float:
    """The collisions a gas is expected to have in ``time`` (:func:`collision_rate`)."""
    return collision_rate(scene, sim) * float(time)


def _collisions(k: int) -> str:
    return "collision" if k == 1 else f"{k:,} collisions"


def _count(k: float, word: str) -> str:
    return f"{k:,.0f} {word}" + ("" if k == 1 else "s")


def _expected(c: float, time: float) -> str:
    return f"; about {c:.3g} collisions expected in t = {time:g} at the Enskog collision rate"


def round_trip_frames(scene: Scene) -> tuple[float, str]:
    """(frames, how counted) of ``revcol run``'s trajectory: the start, every ``trajectory_every``
    collisions and the turn forward, then each of them but the turn again through the reversal."""
    every = scene.trajectory_every
    if scene.collisions is not None:
        c, how = float(scene.collisions), ""
    else:
        c = expected_collisions(scene, scene.time)
        how = _expected(c, scene.time)
    inner = max(0, math.ceil(c / every) - 1)  # frames strictly inside the forward run
    return 2.0 * inner + 3.0, f"forward and back, a frame every {_collisions(every)}{how}"


def round_trip_checkpoints(scene: Scene) -> tuple[float, str]:
    """(checkpoints, how counted) of ``revcol run``: one at every multiple of the interval up to N_c."""
    every = scene.checkpoint_interval
    if scene.collisions is not None:
        return float(scene.collisions // every), f"one every {_collisions(every)}"
    c = expected_collisions(scene, scene.time)
    return float(math.floor(c / every)), f"one every {_collisions(every)}{_expected(c, scene.time)}"


def production_frames(scene: Scene, start: int, collisions: int | None, time: float | None, every: int,
                      every_time: float | None, sim=None) -> tuple[float, str] | None:
    """(frames, how counted) of ``revcol simulate``'s trajectory (the start, every ``every``
    collisions after the net count ``start``, or every ``every_time`` in time, and the end), or
    None when they cannot be known (frames in time over a collision count in a gas that has no
    collision rate: not a run ``revcol simulate`` accepts)."""
    if every_time:
        if time is not None:
            t, how = float(time), ""
        else:
            rate = collision_rate(scene, sim)
            if rate <= 0:
                return None
            t = collisions / rate
            how = f"; t = {t:.3g} expected for {collisions:,} collisions at the Enskog collision rate"
        return math.floor(t / every_time) + 2.0, f"a frame every {every_time:g} in time{how}"
    if collisions is not None:
        c, how = float(collisions), ""
    else:
        c = expected_collisions(scene, time, sim)  # none for one particle: its start and end frames
        how = _expected(c, time)
    return 1.0 + _triggers(start, c, every, collisions is None), f"a frame every {_collisions(every)}{how}"


def _triggers(start: int, c: float, every: int, timed: bool) -> float:
    """Outputs at the multiples of ``every`` in (start, start + c] and at the end (which a run of
    ``c`` collisions ending on a multiple shares; a run to a time: counted apart)."""
    end = start + c
    return math.floor(end / every) - math.floor(start / every) + (1.0 if timed or end % every else 0.0)


def production_checkpoints(scene: Scene, start: int, collisions: int | None, time: float | None, every: int,
                           sim=None) -> tuple[float, str]:
    """(checkpoints, how counted) of ``revcol simulate``: every ``every`` collisions after the net
    count ``start`` and one at the end."""
    if collisions is not None:
        c, how = float(collisions), ""
    else:
        c = expected_collisions(scene, time, sim)
        how = _expected(c, time)
    return _triggers(start, c, every, collisions is None), f"one every {_collisions(every)} and one at the end{how}"


def _sample_frame(scene: Scene, sim=None) -> tuple[np.ndarray, np.ndarray]:
    """Positions and velocities of up to :data:`SAMPLE_ROWS` particles like the run's: a resumed
    engine's or the initial state's, else uniform in the box with Maxwell velocities at kT."""
    if sim is not None:
        return np.asarray(sim.positions)[:SAMPLE_ROWS], np.asarray(sim.velocities)[:SAMPLE_ROWS]
    if scene.initial_state is not None:
        x, v = read_initial(scene.source, scene.initial_state, scene.dimension)
        return x[:SAMPLE_ROWS], v[:SAMPLE_ROWS]
    rng = np.random.default_rng(0)
    k, d = min(SAMPLE_ROWS, scene.particles), scene.dimension
    x = rng.uniform(0.0, 1.0, (k, d)) * np.asarray(scene.box, dtype=float)
    return x, rng.normal(0.0, math.sqrt(temperature(scene)), (k, d))


def trajectory_size(scene: Scene, path: str | os.PathLike, frames: tuple[float, str] | None, *, sim=None,
                    species: str = "Ar", precise: bool = False, collisions: float = 0.0) -> Size | None:
    """The trajectory's bytes: ``frames`` (:func:`round_trip_frames` or :func:`production_frames`;
    None: unknown, so no estimate) of N particles, each frame as its writer writes it."""
    if frames is None:
        return None
    from .trajectory import frame_size  # the writers only when a run writes frames

    x, v = _sample_frame(scene, sim)
    periodic = [b == "periodic" for b in scene.boundaries]
    head, per = frame_size(path, scene.box, periodic, scene.diameter, x, v, species=species, precise=precise,
                           time=1.234567890123 * max(1.0, collisions), collisions=int(collisions))
    n = int(sim.n) if sim is not None else scene.particles
    count, how = frames
    fmt = Path(path).suffix.lstrip(".") or "xyz"
    return Size(count * (head + n * per),
                f"{_count(count, 'frame')} of {_count(n, 'particle')}, {per:.0f} bytes a particle ({fmt}), {how}")


def _state_key(scene: Scene) -> tuple:
    obs = tuple(sorted(scene.observe.items())) if scene.observe is not None else None
    return (scene.engine, scene.dimension, scene.boundaries, scene.diameter, scene.mode, scene.law, scene.bits,
            scene.generator, scene.streams, scene.tick_bits, scene.cell_bits, scene.search, obs)


def _sample_state(scene: Scene, n: int, folder: str) -> int:
    """The bytes of a checkpoint of the scene's engine with ``n`` particles (saved into ``folder``)."""
    side = (n * _core.engine_particle_volume(scene.dimension, scene.diameter) / 0.1) ** (1.0 / scene.dimension)
    small = dataclasses.replace(scene, particles=n, packing_fraction=0.1, box=(side,) * scene.dimension,
                                initial_state=None, kinetic_energy=None, start="random")
    sim = build_simulation(small)
    if scene.observe is not None:
        sim.observe(**scene.observe)
    path = os.path.join(folder, f"sample-{n}.npz")
    sim.save(path)
    return os.path.getsize(path)


def state_bytes(scene: Scene) -> tuple[float, float]:
    """(a, b): a checkpoint of the scene's engine takes a + b N bytes, measured by saving the
    engine at :data:`SAMPLE_PARTICLES` particles (:data:`FALLBACK_STATE` when it cannot be built)."""
    key = _state_key(scene)
    if key not in _STATE_CACHE:
        n1, n2 = SAMPLE_PARTICLES
        try:
            with tempfile.TemporaryDirectory(prefix="revcol-size-") as folder:
                s1, s2 = _sample_state(scene, n1, folder), _sample_state(scene, n2, folder)
            b = (s2 - s1) / (n2 - n1)
            _STATE_CACHE[key] = (s1 - b * n1, b)
        except (ValueError, RuntimeError, OSError):
            _STATE_CACHE[key] = FALLBACK_STATE
    return _STATE_CACHE[key]


def checkpoints_size(scene: Scene, count: float, how: str, sim=None) -> Size:
    """``count`` checkpoints of the run's state (:func:`state_bytes` at the run's N)."""
    a, b = state_bytes(scene)
    n = int(sim.n) if sim is not None else scene.particles
    each = a + b * n
    return Size(count * each, f"{_count(count, 'checkpoint')} of about {each:,.0f} bytes ({scene.engine} engine, "
                f"N = {n:,}), {how}")


def report_size(scene: Scene) -> Size:
    """The JSON report's allowance."""
    obs: dict[str, Any] = scene.observe or {}
    bins = sum(int(obs.get(k, 0)) for k in ("speed_bins", "slabs", "pair_bins"))
    return Size(REPORT_BYTES + REPORT_BYTES_PER_BIN * bins, "a fixed allowance for the report")


def figures_size(scene: Scene, count: int, fmt: str) -> Size:
    """The figures' allowance: ``count`` figures, and every particle drawn in a vector format."""
    vector = FIGURE_BYTES_PER_PARTICLE * scene.particles if fmt in ("svg", "pdf") else 0
    return Size(count * FIGURE_BYTES + vector, f"a fixed allowance for {count} {fmt} figures")


def sweep_points_size(scenes: list[Scene | None]) -> Size | None:
    """The reports of a sweep's points still to run (``points/HASH.json``), one per scene given
    (None: a study without a scene), each :func:`report_size`'s allowance; None when none is left."""
    if not scenes:
        return None
    each = [report_size(s).bytes if s is not None else float(REPORT_BYTES) for s in scenes]
    size = f"about {human(each[0])} each" if min(each) == max(each) else \
        f"{human(min(each))} to {human(max(each))} each"
    return Size(sum(each), f"{_count(len(each), 'point report')} still to run, {size} (a fixed allowance for a "
                "report, and a share per histogram bin)")


def sweep_files_size(points: int, figures: int) -> Size:
    """A sweep's table (CSV and Parquet), summary and ``figures`` figures, over ``points`` points."""
    table = SWEEP_ROW_BYTES * points
    summary = REPORT_BYTES + SWEEP_SUMMARY_BYTES_PER_POINT * points
    figs = f" and {figures} figures" if figures else ""
    return Size(table + summary + figures * FIGURE_BYTES,
                f"the table of {_count(points, 'point')}, the summary{figs}: fixed allowances")
