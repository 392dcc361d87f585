"""``revcol run``: run a scene forward, back to its start, and report the round trip.

A *gas* scene (``revcol.scene``) builds N hard spheres, runs N_c collisions forward (or to an
end time), then ``run_back`` to the start time, and compares with the start:

- ``error_x`` = max over particles and axes of |x - x0| / L_axis (periodic images folded);
- ``error_v`` = max over particles of |v - v0| / max over particles of |v0| (Euclidean norms);
- ``passed`` when both are <= 1e-9 (the paper's bar).

The report also has forward and reverse collisions/s (engine calls only), energy drift
(E - E0) / E0 and momentum drift |P - P0| / sqrt(2 E0 N) along the periodic axes (walls
exchange momentum, so there is none to conserve along a walled axis), the rare-log bytes,
and the process's peak RSS. A real gas is chaotic: round-off grows by about an order of
magnitude per collision per particle, so a round trip passes only within a *horizon* of a
few collisions per particle; :func:`horizon` measures it (``revcol run --horizon``).

*Reversal* scenes run the paper's illustration (:func:`revcol.verify`; velocities only, no
positions are built), *statesave* scenes the paper's §6 study (:func:`revcol.statesave.study`).

Only what a run asks for is built or imported: matplotlib with ``plot`` only, the trajectory
writers with ``trajectory`` only, the intermediate round trips (state clones run back to the
start) and the energy series only for the plot, and a progress bar only on a terminal.
Ctrl-C (SIGINT) stops the forward run between events; the run then goes back from where it
stopped and writes everything asked for, marked interrupted. Ctrl-C during the reversal
stops it at the next chunk of collisions (the report then says the round trip is
incomplete); a third Ctrl-C ends the process.

    >>> from revcol.scene import load_scene
    >>> from revcol.run import run_gas
    >>> r = run_gas(load_scene(None), progress=False)   # the built-in default scene
    >>> r["passed"], r["collisions_forward"] == r["collisions_back"]
    (True, True)
"""
from __future__ import annotations

import dataclasses
import datetime as dt
import json
import math
import os
import signal
import sys
import textwrap
import threading
import time as _time
from pathlib import Path
from typing import Any, Callable

import numpy as np

from .engine import Simulation
from .scene import Scene, SceneError, engine_options, load_scene

__all__ = ["BAR", "build_simulation", "run_gas", "run_reversal", "run_statesave", "horizon", "run_scene",
           "format_report", "format_horizon", "write_json", "round_trip_errors"]

#: the round-trip bar (the paper's): both errors must be at most this
BAR = 1e-9

ERROR_DEFINITIONS = {
    "error_x": "max over particles and axes of |x - x0| / L_axis (periodic images folded)",
    "error_v": "max over particles of |v - v0| / max over particles of |v0| (Euclidean norms)",
}


# --- building --------------------------------------------------------------------------------

def build_simulation(scene: Scene, seed: int | None = None) -> Simulation:
    """The engine for a gas scene: from its initial state, from a random start at its packing
    fraction, or on a jittered lattice in its explicit box. ``seed`` overrides the scene's.
    A state the engine refuses raises :class:`SceneError` naming the field."""
    if scene.kind != "gas":
        raise SceneError(f"{scene.source}: [scene] kind: {scene.kind!r} scenes build no particles")
    opts = engine_options(scene)
    if seed is not None:
        opts["seed"] = int(seed)
    if scene.initial_state is not None:
        from .scene import _read_initial

        x, v = _read_initial(scene.source, scene.initial_state, scene.dimension)
        where = "[system] initial_state"
        return _engine(scene, where, lambda: Simulation(x, v, scene.box, **opts))
    if scene.packing_fraction is not None:
        init = {"auto": "auto", "random": "rsa", "lattice": "lattice"}[scene.start]
        return _engine(scene, "[system] packing_fraction", lambda: Simulation.random(
            scene.particles, scene.dimension, scene.packing_fraction, init=init,
            energy=scene.kinetic_energy, **opts))
    x, v = _lattice_start(scene, opts["seed"])
    return _engine(scene, "[system] box", lambda: Simulation(x, v, scene.box, **opts))


def _engine(scene: Scene, where: str, make: Callable[[], Simulation]) -> Simulation:
    try:
        return make()
    except ValueError as e:
        raise SceneError(f"{scene.source}: {where}: {e}") from None


def _lattice_start(scene: Scene, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """N particles on a jittered simple lattice in a (non-cubic) box, Gaussian velocities with
    zero momentum scaled to the kinetic energy (default N d / 2).

    Sites are spaced a_k >= D per axis; each particle moves by at most 0.45 (a_k - D) per
    axis, so any two stay at least D + 0.1 (a_k - D) apart along the axis their sites differ
    in. Walled axes keep centres 1e-6 D inside [D/2, L - D/2], like the engine's start."""
    n, d, sigma = scene.particles, scene.dimension, scene.diameter
    rng = np.random.default_rng([0x5CE1E, seed])
    lo, span, walls = [], [], []
    for L, b in zip(scene.box, scene.boundaries):
        wall = b == "walls"
        margin = 0.5 * sigma * (1 + 2e-6) if wall else 0.0
        lo.append(margin)
        span.append(L - 2 * margin)
        walls.append(wall)

    def spacing(k: int, m: int) -> float:  # walls: sites at both ends; periodic: m per period
        if walls[k]:
            return math.inf if m == 1 else span[k] / (m - 1)
        return span[k] / m

    m = [1] * d
    while math.prod(m) < n:  # refine the axis with the widest spacing
        k = max(range(d), key=lambda j: spacing(j, m[j]) if not math.isinf(spacing(j, m[j])) else 1e300)
        m[k] += 1
    a = [spacing(k, m[k]) for k in range(d)]
    if min(a) < sigma * (1 + 1e-9):
        raise SceneError(f"{scene.source}: [system] box: {n} particles of diameter {sigma:g} do not fit on a "
                         f"lattice in this box (spacing {min(a):.4g}); make the box larger")
    sites = rng.choice(math.prod(m), size=n, replace=False)
    x = np.empty((n, d))
    for k in range(d):
        idx = (sites // math.prod(m[k + 1:])) % m[k]
        if walls[k]:
            pos = lo[k] + (idx * a[k] if m[k] > 1 else 0.5 * span[k])
        else:
            pos = (idx + 0.5) * a[k]
        room = 0.45 * ((a[k] if not math.isinf(a[k]) else span[k]) - sigma)
        pos = pos + rng.uniform(-1.0, 1.0, n) * max(room, 0.0)
        if walls[k]:
            pos = np.clip(pos, lo[k], lo[k] + span[k])
        else:
            pos = np.mod(pos, scene.box[k])
        x[:, k] = pos
    v = rng.normal(size=(n, d))
    if n > 1:
        v -= v.mean(axis=0)
    e = 0.5 * float((v * v).sum())
    target = scene.kinetic_energy if scene.kinetic_energy is not None else 0.5 * n * d
    v *= math.sqrt(target / e) if e > 0 else 0.0
    return x, v


# --- measuring -------------------------------------------------------------------------------

def round_trip_errors(x, v, x0, v0, box, periodic) -> tuple[float, float]:
    """(error_x, error_v) as defined in :data:`ERROR_DEFINITIONS`."""
    box = np.asarray(box, dtype=float)
    per = np.asarray(periodic, dtype=bool)
    dx = np.abs(np.asarray(x) - x0)
    dx[:, per] = np.minimum(dx[:, per], box[per] - dx[:, per])
    err_x = float((dx / box).max())
    err_v = float(np.linalg.norm(np.asarray(v) - v0, axis=1).max() / np.linalg.norm(v0, axis=1).max())
    return err_x, err_v


def _version() -> str:
    from . import __version__

    return __version__


def _peak_rss() -> int | None:
    """Peak resident set of this process in bytes (VmHWM), or None where unknown."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        import resource

        r = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        return int(r) if sys.platform == "darwin" else int(r) * 1024
    except (ImportError, OSError):
        return None


class _Interrupt:
    """SIGINT while a run is under way: counts the presses (the run loops read ``presses``);
    from the second press on, the next one raises KeyboardInterrupt as Python's default."""

    def __init__(self) -> None:
        self.presses = 0
        self._old = None

    def __enter__(self) -> "_Interrupt":
        if threading.current_thread() is threading.main_thread():
            self._old = signal.signal(signal.SIGINT, self._handler)
        return self

    def __exit__(self, *exc) -> None:
        if self._old is not None:
            signal.signal(signal.SIGINT, self._old)

    def _handler(self, signum, frame) -> None:
        self.presses += 1
        if self.presses >= 2:
            signal.signal(signal.SIGINT, signal.default_int_handler)


class _Bar:
    """A tqdm progress bar on a terminal; nothing otherwise (or when tqdm is missing)."""

    def __init__(self, enabled: bool, total: float, desc: str, unit: str):
        self.bar, self.n = None, 0.0
        if enabled:
            try:
                from tqdm import tqdm
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


# --- a gas scene ---------------------------------------------------------------------------

def run_gas(scene: Scene, *, plot: str | os.PathLike | None = None,
            trajectory: str | os.PathLike | None = None, progress: bool | None = None,
            checkpoints: bool = True) -> dict:
    """Runs a gas scene forward and back; returns the report (a dict, see the module doc).

    ``plot``: a directory for the PNG figures (round-trip error and energy drift against
    collisions, snapshots at the start, the turn and the end); ``trajectory``: a ``.xyz`` or
    ``.gsd`` file of frames every ``scene.trajectory_every`` collisions, forward and through
    the reversal (at the same times); ``progress``: a bar (None: when stdout is a
    terminal); ``checkpoints``: write the scene's ``.npz`` checkpoints. Outputs are checked
    before anything runs."""
    if scene.kind != "gas":
        raise SceneError(f"{scene.source}: [scene] kind: run_gas needs a 'gas' scene, got {scene.kind!r}")
    if trajectory is not None:
        from .trajectory import check_format

        try:
            check_format(trajectory)
        except ValueError as e:
            raise SceneError(str(e)) from None
    if plot is not None:
        _require_matplotlib()
    if progress is None:
        progress = sys.stdout.isatty()

    sim = build_simulation(scene)
    n, d = sim.n, sim.dim
    st = sim.state()
    box = np.asarray(st["box"], dtype=float)[:d]
    periodic = np.asarray(st["periodic"], dtype=bool)[:d]
    del st
    x0, v0 = sim.positions, sim.velocities
    diag0 = sim.diagnostics()
    e0, p0 = diag0["energy"], np.asarray(diag0["momentum"], dtype=float)[:d]
    t0 = sim.time
    nc, t_end = scene.collisions, scene.time

    def momentum_drift(diag: dict) -> float | None:
        if not periodic.any():
            return None
        dp = (np.asarray(diag["momentum"], dtype=float)[:d] - p0)[periodic]
        return float(np.sqrt((dp * dp).sum()) / math.sqrt(2.0 * e0 * n))

    # where the forward run pauses: checkpoints and trajectory frames every so many
    # collisions; for the plot, 9 intermediate round trips (by collisions, or by time)
    ckpt_every = scene.checkpoint_interval if checkpoints else 0
    traj_every = scene.trajectory_every if trajectory is not None else 0
    plot_c: set[int] = set()
    plot_t: list[float] = []
    if plot is not None:
        if nc is not None:
            plot_c = {max(1, round(nc * k / 10)) for k in range(1, 10)} - {nc}
        else:
            plot_t = [t0 + (t_end - t0) * k / 10 for k in range(1, 10)]

    def next_stop(done: int) -> int | None:
        cands = [c for c in plot_c if c > done]
        for every in (ckpt_every, traj_every):
            if every:
                cands.append((done // every + 1) * every)
        if nc is not None:
            cands = [min(c, nc) for c in cands] + [nc]
        return min(cands) if cands else None

    writer = None
    frames_t: list[float] = []
    if trajectory is not None:
        from .trajectory import open_trajectory

        writer = open_trajectory(trajectory, box, periodic, scene.diameter)
        writer.write(x0, v0, t0, 0, "forward")
        frames_t.append(t0)

    curve: list[dict] = []
    energy_series: list[tuple[int, float]] = [(0, 0.0)] if plot is not None else []
    written_ckpt: list[str] = []
    every = max(1, min(10_000, (nc // 200) if nc is not None else max(1, n // 2)))
    series_every = max(every, (nc // 200) if nc is not None else every)
    total = float(nc) if nc is not None else float(t_end - t0)
    bar = _Bar(progress, total, "forward", "coll" if nc is not None else "t")
    done, forward_s, interrupted = 0, 0.0, None

    with _Interrupt() as stop:
        try:
            base = 0

            def callback(k: int) -> bool:
                c = base + k
                if plot is not None and c % series_every < every:
                    energy_series.append((c, float(sim.diagnostics()["energy_drift"])))
                bar.to(c if nc is not None else sim.time - t0)
                return stop.presses == 0

            while True:
                stop_c = next_stop(done)
                stop_t = min([t for t in plot_t if t > sim.time] + ([t_end] if t_end is not None else []),
                             default=None)
                base = done
                tick = _time.perf_counter()
                r = sim.run(collisions=None if stop_c is None else stop_c - done, time=stop_t,
                            callback=callback, every=every)
                forward_s += _time.perf_counter() - tick
                done += int(r["collisions"])
                if stop.presses:
                    interrupted = "forward"
                    break
                finished = (nc is not None and done >= nc) or (t_end is not None and sim.time >= t_end)
                if ckpt_every and done % ckpt_every == 0 and done > 0:
                    path = Path(scene.checkpoints) / f"checkpoint-{done:012d}.npz"
                    path.parent.mkdir(parents=True, exist_ok=True)
                    sim.save(path)
                    written_ckpt.append(str(path))
                if writer is not None and not finished and done % traj_every == 0 and done > 0:
                    writer.write(sim.positions, sim.velocities, sim.time, done, "forward")
                    frames_t.append(sim.time)
                if finished:
                    break
                if (done in plot_c) or (plot_t and sim.time in plot_t):
                    clone = Simulation.from_state(sim.state())
                    clone.run_back()
                    ex, ev = round_trip_errors(clone.positions, clone.velocities, x0, v0, box, periodic)
                    curve.append({"collisions": done, "time": sim.time, "error_x": ex, "error_v": ev})
                    del clone
        finally:
            bar.close()

        # the turn
        t_turn = sim.time
        diag_turn = sim.diagnostics()
        if plot is not None:
            energy_series.append((done, float(diag_turn["energy_drift"])))
            x_turn, v_turn = sim.positions, sim.velocities
        if writer is not None and (not frames_t or frames_t[-1] != t_turn):
            writer.write(sim.positions, sim.velocities, t_turn, done, "forward")
            frames_t.append(t_turn)
        presses_at_turn = stop.presses

        # back to the start: in chunks (each run_back re-predicts every event, about the
        # cost of 0.2 N collisions, so chunks are >= 20 N collisions) or, with a
        # trajectory, to each forward frame's time in turn
        back, reverse_s = 0, 0.0
        bar = _Bar(progress, float(done), "reverse", "coll")
        try:
            if writer is not None:
                targets = frames_t[-2::-1]
            else:
                chunk = max(20 * n, done // 100, 1)
                targets = [None] * max(0, math.ceil(done / chunk) - 1) + ["start"]
            for target in targets:
                if stop.presses > presses_at_turn:
                    interrupted = "reverse"
                    break
                tick = _time.perf_counter()
                if target is None:
                    r = sim.run_back(collisions=chunk)
                elif target == "start" or target == t0:
                    r = sim.run_back()
                else:
                    r = sim.run_back(time=target)
                reverse_s += _time.perf_counter() - tick
                back += int(r["collisions"])
                bar.to(back)
                if writer is not None:
                    writer.write(sim.positions, sim.velocities, sim.time, done - back, "reverse")
        finally:
            bar.close()
            if writer is not None:
                writer.close()

    diag_end = sim.diagnostics()
    complete = sim.time == t0 and interrupted != "reverse"
    ex, ev = round_trip_errors(sim.positions, sim.velocities, x0, v0, box, periodic)
    passed = bool(complete and ex <= BAR and ev <= BAR)
    if plot is not None and complete:
        curve.append({"collisions": done, "time": t_turn, "error_x": ex, "error_v": ev})

    report: dict[str, Any] = {
        "kind": "gas", "revcol_version": _version(), "scene": scene.to_dict(), "summary": scene.summary(),
        "particles": n, "dimension": d, "box": box.tolist(), "periodic": periodic.tolist(),
        "collisions_forward": done, "collisions_back": back, "per_particle": 2.0 * done / n,
        "time_start": t0, "time_turn": t_turn, "time_end": sim.time,
        "forward_s": forward_s, "reverse_s": reverse_s,
        "forward_per_s": done / forward_s if forward_s > 0 else None,
        "reverse_per_s": back / reverse_s if reverse_s > 0 else None,
        "segments_note": ("the runs paused for checkpoints, frames or the plot's round trips; the rates "
                          "count engine calls only" if (ckpt_every or traj_every or plot is not None) else ""),
        "error_x": ex, "error_v": ev, "error_definitions": ERROR_DEFINITIONS, "bar": BAR,
        "round_trip_complete": complete, "passed": passed, "interrupted": interrupted,
        "energy_drift_turn": float(diag_turn["energy_drift"]), "energy_drift_end": float(diag_end["energy_drift"]),
        "momentum_drift_turn": momentum_drift(diag_turn), "momentum_drift_end": momentum_drift(diag_end),
        "drift_definitions": {"energy": "(E - E0) / E0",
                              "momentum": "|P - P0| / sqrt(2 E0 N) over the periodic axes (None: walls only)"},
        "log_bytes_turn": int(diag_turn["log_bytes"]), "log_bytes_end": int(diag_end["log_bytes"]),
        "reverse_failures": int(diag_end["events"]["reverse_failures"]),
        "events_turn": diag_turn["events"],
        "peak_rss_bytes": _peak_rss(),
        "checkpoints": written_ckpt, "trajectory": str(trajectory) if trajectory is not None else None,
        "trajectory_frames": writer.frames if writer is not None else 0,
        "curve": curve, "energy_series": [list(p) for p in energy_series],
        "date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
        "written": [],
    }
    if plot is not None:
        report["written"] += _plot_gas(report, Path(plot), sim, x0, v0, x_turn, v_turn)
    return report


# --- the other kinds ---------------------------------------------------------------------------

def run_reversal(scene: Scene) -> dict:
    """The paper's reversal illustration for the scene's case (:func:`revcol.verify`)."""
    from .verify import verify

    # one C++ call (10^6 collisions both ways in about a second): a Ctrl-C waits for it to end,
    # and the report, marked interrupted, is still written
    with _Interrupt() as stop:
        r = dict(verify(scene.case, collisions=scene.collisions, mode=scene.mode, law=scene.law,
                        rng=scene.generator, seed=scene.seed, bits=scene.bits))
    r.update({"kind": "reversal", "scene": scene.to_dict(), "summary": scene.summary(),
              "peak_rss_bytes": _peak_rss(), "interrupted": "reversal" if stop.presses else None,
              "written": []})
    return r


def run_statesave(scene: Scene, plot: str | os.PathLike | None = None, progress: bool | None = None) -> dict:
    """The paper's state-saving study for the scene's settings (:func:`revcol.statesave.study`).
    ``runner = "auto"`` runs each point in a fresh ``revcol-bench`` process when one is
    found (so peak RSS is the run's own), in this process otherwise."""
    from . import statesave

    if plot is not None:
        _require_matplotlib()
    inline = scene.runner == "inline"
    if not inline:
        try:
            statesave._find_binary(None)
        except FileNotFoundError:
            if scene.runner == "process":
                raise SceneError(f"{scene.source}: [statesave] runner: 'process' needs the revcol-bench binary "
                                 "(installed next to python by pip install ., or set REVCOL_BENCH); "
                                 "or use runner = 'auto' or 'inline'") from None
            inline = True
    # Ctrl-C ends the study after the run under way (each run is one C++ call or process);
    # the runs done are reported and written
    try:
        with _Interrupt() as stop:
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
        out = Path(plot) / "statesave.png"
        out.parent.mkdir(parents=True, exist_ok=True)
        statesave.plot(r, out)
        r["written"].append(str(out))
    return r


# --- the horizon ---------------------------------------------------------------------------------

#: collisions per particle tried by :func:`horizon` (1, 1.5, 2, 3, 5, 7 per decade)
HORIZON_GRID = tuple(m * 10.0**e for e in range(-1, 5) for m in (1, 1.5, 2, 3, 5, 7))


def horizon(scene: Scene, *, seeds: int = 1, max_collisions: int = 1_000_000, o1: float = 0.1,
            progress: bool | None = None) -> dict:
    """Round-trip error against collisions per particle (2 N_c / N) for a gas scene.

    For each of ``seeds`` seeds (the scene's seed, then the next ones), one forward run
    stops at each grid point (:data:`HORIZON_GRID`, up to ``max_collisions``); a clone of the
    state (``state()`` / ``from_state``) runs back to the start and gives both errors. A seed
    stops once its error reaches ``o1`` (O(1): the reversed trajectory has left the forward
    one). Each grid point reports the worst error over the seeds (a seed that stopped counts
    as O(1)); the horizon is the largest N_c before the first grid point whose worst error
    exceeds 1e-9."""
    if scene.kind != "gas":
        raise SceneError(f"{scene.source}: [scene] kind: --horizon measures gas scenes, not {scene.kind!r}")
    if scene.seed + seeds > 2**32:
        raise SceneError(f"{scene.source}: [rng] seed: seeds {scene.seed} .. {scene.seed + seeds - 1} "
                         "pass 2^32 - 1")
    if progress is None:
        progress = sys.stdout.isatty()
    n = scene.particles
    grid = sorted({max(1, round(c * n / 2)) for c in HORIZON_GRID if c * n / 2 <= max_collisions})
    if not grid:
        grid = [max(1, int(max_collisions))]
    per_seed = []
    bar = _Bar(progress, float(seeds * len(grid)), "horizon", "pt")
    done_pts = 0
    try:
        with _Interrupt() as stop:
            for s in range(seeds):
                sim = build_simulation(scene, scene.seed + s)
                st = sim.state()
                box = np.asarray(st["box"], dtype=float)[: sim.dim]
                periodic = np.asarray(st["periodic"], dtype=bool)[: sim.dim]
                del st
                x0, v0 = sim.positions, sim.velocities
                errs, done = [], 0
                for nc in grid:
                    done += int(sim.run(collisions=nc - done)["collisions"])
                    clone = Simulation.from_state(sim.state())
                    clone.run_back()
                    ex, ev = round_trip_errors(clone.positions, clone.velocities, x0, v0, box, periodic)
                    errs.append((ex, ev))
                    done_pts += 1
                    bar.to(done_pts)
                    if max(ex, ev) >= o1 or stop.presses:
                        break
                per_seed.append(errs)
                if stop.presses:
                    break
            interrupted = stop.presses > 0
    finally:
        bar.close()
    rows = []
    for k, nc in enumerate(grid):
        ex = [e[k][0] if k < len(e) else math.inf for e in per_seed]
        ev = [e[k][1] if k < len(e) else math.inf for e in per_seed]
        if all(k >= len(e) for e in per_seed):
            break
        worst = [max(a, b) for a, b in zip(ex, ev)]
        rows.append({"collisions": nc, "per_particle": 2.0 * nc / n, "error_x": max(ex), "error_v": max(ev),
                     "median": float(np.median(worst)), "fails": int(sum(w > BAR for w in worst)),
                     "seeds": len(per_seed)})
    h = 0
    for r in rows:
        if max(r["error_x"], r["error_v"]) > BAR:
            break
        h = r["collisions"]
    reached = any(max(r["error_x"], r["error_v"]) > BAR for r in rows)
    return {"kind": "horizon", "scene": scene.to_dict(), "summary": scene.summary(), "seeds": len(per_seed),
            "seed_first": scene.seed, "max_collisions": int(max_collisions), "o1": o1, "bar": BAR,
            "rows": rows, "horizon_collisions": h, "horizon_per_particle": 2.0 * h / n,
            "horizon_reached": reached, "interrupted": "horizon" if interrupted else None,
            "error_definitions": ERROR_DEFINITIONS, "peak_rss_bytes": _peak_rss(),
            "date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"), "written": []}


# --- plots ---------------------------------------------------------------------------------------

def _require_matplotlib() -> None:
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        raise SceneError("--plot needs matplotlib (pip install matplotlib)") from None


def _pyplot():
    import matplotlib

    if "matplotlib.pyplot" not in sys.modules:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _plot_gas(r: dict, out: Path, sim: Simulation, x0, v0, x_turn, v_turn) -> list[str]:
    plt = _pyplot()
    out.mkdir(parents=True, exist_ok=True)
    written = []
    title = textwrap.fill(r["summary"], 110)

    fig, ax = plt.subplots(figsize=(7, 4.5))
    c = [p["collisions"] for p in r["curve"]]
    ax.semilogy(c, [max(p["error_x"], 1e-18) for p in r["curve"]], "o-", label="positions: max |x - x0| / L")
    ax.semilogy(c, [max(p["error_v"], 1e-18) for p in r["curve"]], "s-", label="velocities: max |v - v0| / max |v0|")
    ax.axhline(BAR, color="k", ls=":", lw=1, label="bar 1e-9")
    ax.set_xlabel("collisions forward (then back to the start)")
    ax.set_ylabel("round-trip error")
    ax.set_title(title, fontsize=7)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    written.append(_save(fig, out / "roundtrip_error.png", plt))

    fig, ax = plt.subplots(figsize=(7, 4.5))
    es = np.array(r["energy_series"], dtype=float).reshape(-1, 2)
    ax.plot(es[:, 0], es[:, 1], "-", lw=1)
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_xlabel("collisions forward")
    ax.set_ylabel("energy drift (E - E0) / E0")
    ax.set_title(title, fontsize=7)
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    written.append(_save(fig, out / "energy_drift.png", plt))

    fig, axes = plt.subplots(1, 3, figsize=(13, 4.6))
    shots = [("start", x0, v0), (f"after {r['collisions_forward']:,} collisions forward", x_turn, v_turn),
             ("after reversal", sim.positions, sim.velocities)]
    for ax, (label, x, v) in zip(axes, shots):
        _draw_particles(ax, x, v, r["box"], r["scene"]["diameter"])
        ax.set_title(label, fontsize=9)
    fig.suptitle(title + ("  (x-y projection, colour: speed)" if r["dimension"] == 3 else "  (colour: speed)"),
                 fontsize=7)
    fig.tight_layout()
    written.append(_save(fig, out / "snapshots.png", plt))
    return written


def _draw_particles(ax, x, v, box, sigma) -> None:
    from matplotlib.collections import EllipseCollection
    from matplotlib.patches import Rectangle

    x = np.asarray(x)
    xy = x[:, :2] if x.shape[1] >= 2 else np.column_stack([x[:, 0], np.zeros(len(x))])
    ly = box[1] if len(box) >= 2 else sigma
    ec = EllipseCollection(sigma, sigma, 0.0, units="xy", offsets=xy if len(box) >= 2 else xy + [0, 0.5 * ly],
                           offset_transform=ax.transData, cmap="viridis", linewidths=0)
    ec.set_array(np.linalg.norm(v, axis=1))
    ax.add_collection(ec)
    ax.add_patch(Rectangle((0, 0), box[0], ly, fill=False, lw=0.8))
    ax.set_xlim(-0.02 * box[0], 1.02 * box[0])
    ax.set_ylim(-0.02 * max(ly, box[0]) if len(box) >= 2 else -ly, 1.02 * ly if len(box) >= 2 else 2 * ly)
    ax.set_aspect("equal" if len(box) >= 2 else "auto")
    ax.set_xticks([])
    ax.set_yticks([])


def _plot_horizon(r: dict, out: Path) -> list[str]:
    plt = _pyplot()
    out.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    pp = [row["per_particle"] for row in r["rows"]]
    ax.loglog(pp, [max(row["error_x"], 1e-18) for row in r["rows"]], "o-", label="positions: max |x - x0| / L")
    ax.loglog(pp, [max(row["error_v"], 1e-18) for row in r["rows"]], "s-", label="velocities: max |v - v0| / max |v0|")
    if r["seeds"] > 1:
        ax.loglog(pp, [max(row["median"], 1e-18) for row in r["rows"]], ":", color="0.5",
                  label="median over seeds (the larger of the two errors)")
    ax.axhline(BAR, color="k", ls=":", lw=1, label="bar 1e-9")
    if r["horizon_collisions"]:
        ax.axvline(r["horizon_per_particle"], color="C2", ls="--", lw=1,
                   label=f"horizon: N_c = {r['horizon_collisions']:,}")
    ax.set_xlabel("collisions per particle (2 N_c / N), forward then back")
    ax.set_ylabel(f"round-trip error (worst of {r['seeds']} seed{'s' if r['seeds'] > 1 else ''})")
    ax.set_title(textwrap.fill(r["summary"], 110), fontsize=7)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return [_save(fig, out / "horizon.png", plt)]


def _save(fig, path: Path, plt) -> str:
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return str(path)


# --- reports -------------------------------------------------------------------------------------

def _si(x: float | None, unit: str = "") -> str:
    return "n/a" if x is None else f"{x:.3g}{unit}"


def _duration(s: float) -> str:
    return f"{s * 1e3:.3g} ms" if s < 1 else f"{s:.3g} s"


def _mib(b: int | None) -> str:
    return "n/a" if b is None else f"{b / 2**20:.1f} MiB (this process)"


def format_report(r: dict) -> str:
    """The report as text (any kind)."""
    scene = r["scene"]
    head = f"revcol run {scene['name']}  ({scene['source']})"
    if r["kind"] == "horizon":
        return format_horizon(r)
    if r["kind"] == "reversal":
        lines = [head, f"  scene               {r['summary']}"] + _verify_lines(r)
        if r["interrupted"]:
            lines.append("  interrupted         (Ctrl-C) after the reversal, which is one call: it ran to the end")
    elif r["kind"] == "statesave":
        from .statesave import format_table

        lines = [head, f"  scene   {r['summary']}", f"  runner  {r['runner']}: {r['rss_note']}", format_table(r)]
        if r["interrupted"]:
            lines.append(f"  interrupted (Ctrl-C): the table covers the runs done; {r.get('not_run', 0)} not run")
    else:
        drift_p = ("n/a (walls on every axis)" if r["momentum_drift_turn"] is None else
                   f"{r['momentum_drift_turn']:+.2g} at the turn, {_si(r['momentum_drift_end'])} after reversal "
                   "(periodic axes)")
        fwd_end = f"t = {r['time_turn']:.6g}"
        lines = [
            head,
            f"  scene            {r['summary']}",
            f"  forward          {r['collisions_forward']:,} collisions ({r['per_particle']:.3g} per particle) to "
            f"{fwd_end} in {_duration(r['forward_s'])}: {_si(r['forward_per_s'])} collisions/s",
            f"  reverse          {r['collisions_back']:,} collisions back to t = {r['time_end']:.6g} in "
            f"{_duration(r['reverse_s'])}: {_si(r['reverse_per_s'])} collisions/s",
            f"  positions error  {r['error_x']:.3g}   {ERROR_DEFINITIONS['error_x']}",
            f"  velocity error   {r['error_v']:.3g}   {ERROR_DEFINITIONS['error_v']}",
            f"  bar              {BAR:g} (both)",
            f"  energy drift     {r['energy_drift_turn']:+.2g} at the turn, {r['energy_drift_end']:+.2g} after "
            "reversal   ((E - E0) / E0)",
            f"  momentum drift   {drift_p}",
            f"  log bytes        {r['log_bytes_turn']} at the turn, {r['log_bytes_end']} after reversal",
            f"  peak RSS         {_mib(r['peak_rss_bytes'])}",
        ]
        if r["reverse_failures"]:
            lines.append(f"  reverse failures {r['reverse_failures']} (the reversed run left the forward one)")
        if r["checkpoints"]:
            lines.append(f"  checkpoints      {len(r['checkpoints'])} in {Path(r['checkpoints'][0]).parent}")
        if r["trajectory"]:
            lines.append(f"  trajectory       {r['trajectory_frames']} frames in {r['trajectory']}")
        if r["interrupted"]:
            lines.append(f"  interrupted      during the {r['interrupted']} run (Ctrl-C)"
                         + ("; the round trip is incomplete" if not r["round_trip_complete"] else
                            "; went back from where it stopped"))
        lines.append(f"  result           {'PASSED' if r['passed'] else 'FAILED'}")
    if r.get("written"):
        lines.append("  written          " + " ".join(r["written"]))
    return "\n".join(lines)


def _verify_lines(r: dict) -> list[str]:
    """``revcol verify``'s report lines (shared with the CLI's verify command)."""
    return [
        f"  collisions          {r['collisions']:,} forward, {r['collisions']:,} back",
        f"  forward             {r['forward_per_s']:.3g} collisions/s",
        f"  reverse             {r['reverse_per_s']:.3g} collisions/s",
        f"  max relative error  {r['max_rel_error']:.3g}  (bar: 1e-9)",
        f"  bit exact           {r['bit_exact']}",
        f"  rng restored        {r['rng_restored']}  ({r['random_numbers_drawn']:,} drawn)",
        f"  rare log            {r['log_bytes']} bytes at the turn",
        f"  result              {'PASSED' if r['passed'] else 'FAILED'}",
    ] + ([f"  stopped             {r['error']}"] if r.get("error") else [])


def format_horizon(r: dict) -> str:
    """The horizon table as text."""
    lines = [f"revcol run --horizon {r['scene']['name']}  ({r['scene']['source']})",
             f"  scene  {r['summary']}",
             f"  worst round-trip error over {r['seeds']} seed(s) from {r['seed_first']}; "
             f"bar {BAR:g}; stop at {r['o1']:g}",
             f"  {'N_c':>10}  {'per particle':>12}  {'error_x':>9}  {'error_v':>9}  {'median':>9}  fails"]
    def e(x: float) -> str:  # a seed that already reached O(1) counts as infinite
        return f"{x:>9.2e}" if math.isfinite(x) else f"{'O(1)':>9}"

    for row in r["rows"]:
        lines.append(f"  {row['collisions']:>10,}  {row['per_particle']:>12.3g}  {e(row['error_x'])}  "
                     f"{e(row['error_v'])}  {e(row['median'])}  {row['fails']}/{row['seeds']}")
    if r["horizon_reached"]:
        lines.append(f"  horizon: N_c = {r['horizon_collisions']:,} ({r['horizon_per_particle']:.3g} collisions "
                     f"per particle) is the largest grid point with every error <= {BAR:g}")
    else:
        lines.append(f"  horizon: not reached up to N_c = {r['rows'][-1]['collisions']:,} "
                     f"(--max-collisions {r['max_collisions']:,})")
    if r["interrupted"]:
        lines.append("  interrupted (Ctrl-C): the table covers what ran")
    if r.get("written"):
        lines.append("  written  " + " ".join(r["written"]))
    return "\n".join(lines)


def _jsonable(o: Any) -> Any:
    if isinstance(o, dict):
        return {str(k): _jsonable(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [_jsonable(v) for v in o]
    if isinstance(o, np.ndarray):
        return _jsonable(o.tolist())
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, (np.floating, float)):
        return float(o) if math.isfinite(o) else str(o)
    if isinstance(o, Path):
        return str(o)
    return o


def write_json(report: dict, path: str | os.PathLike) -> str:
    """Writes the report as indented JSON (creating the directory); returns the path."""
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_text(json.dumps(_jsonable(report), indent=1) + "\n")
    return str(p)


# --- one entry point -----------------------------------------------------------------------------

def run_scene(scene: Scene | str | os.PathLike | None = None, *, json_path: str | os.PathLike | None = None,
              plot: str | os.PathLike | None = None, trajectory: str | os.PathLike | None = None,
              horizon_seeds: int | None = None, max_collisions: int = 1_000_000,
              collisions: int | None = None, seed: int | None = None, progress: bool | None = None) -> dict:
    """Runs any scene (a :class:`Scene`, a path, or None for the built-in default) and writes
    the outputs asked for (arguments here, else the scene's ``[output]``). ``collisions``
    overrides N_c (a gas's end time included); ``horizon_seeds`` measures the horizon over
    that many seeds instead of one round trip. Returns the report; every output is checked
    before anything runs, and a bad one raises :class:`SceneError`."""
    if not isinstance(scene, Scene):
        scene = load_scene(scene)
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
    if plot is not None:
        _require_matplotlib()
    if horizon_seeds is not None:
        r = horizon(scene, seeds=horizon_seeds, max_collisions=max_collisions, progress=progress)
        if plot is not None:
            r["written"] += _plot_horizon(r, Path(plot))
    elif scene.kind == "reversal":
        r = run_reversal(scene)
    elif scene.kind == "statesave":
        r = run_statesave(scene, plot, progress)
    else:
        r = run_gas(scene, plot=plot, trajectory=trajectory, progress=progress)
    if json_path is not None:
        r["written"].append(str(json_path))
        write_json(r, json_path)
    return r
