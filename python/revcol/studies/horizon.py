"""The reversal horizon of a gas scene (``revcol run --horizon``): round-trip error against
collisions per particle, the worst over several seeds.

A real gas is chaotic: round-off grows by about an order of magnitude per collision per
particle, so a round trip passes the 1e-9 bar only within a *horizon* of some collisions per
particle; :func:`horizon` measures it.
"""
from __future__ import annotations

import datetime as dt
import sys

from ..engine import Simulation
from ..gas import build_simulation
from ..lattice_gas import lattice_horizon
from ..progress import Bar, Interrupt, peak_rss
from ..roundtrip import BAR, ERROR_DEFINITIONS, combine_seeds, geometry, round_trip_errors
from ..scene import Scene, SceneError

__all__ = ["HORIZON_GRID", "horizon"]

#: collisions per particle tried by :func:`horizon` (1, 1.5, 2, 3, 5, 7 per decade)
HORIZON_GRID = tuple(m * 10.0**e for e in range(-1, 5) for m in (1, 1.5, 2, 3, 5, 7))


def horizon(scene: Scene, *, seeds: int = 1, max_collisions: int = 1_000_000, o1: float = 0.1,
            progress: bool | None = None) -> dict:
    """Round-trip error against collisions per particle (2 N_c / N) for a gas scene.

    For each of ``seeds`` seeds (the scene's seed, then the next ones), one forward run
    stops at each grid point (:data:`HORIZON_GRID`, up to ``max_collisions``); a clone of the
    state (``snapshot()`` / ``from_snapshot``) runs back to the start and gives both errors. A seed
    stops once its error reaches ``o1`` (O(1): the reversed trajectory has left the forward
    one). Each grid point reports the worst error over the seeds (a seed that stopped counts
    as O(1)); the horizon is the largest N_c before the first grid point whose worst error
    exceeds 1e-9. A lattice scene has none: :func:`revcol.lattice_gas.lattice_horizon` checks
    its round trip bit for bit at a few N_c."""
    if scene.kind != "gas":
        raise SceneError(f"{scene.source}: [scene] kind: --horizon measures gas scenes, not {scene.kind!r}")
    if scene.seed + seeds > 2**32:
        raise SceneError(f"{scene.source}: [rng] seed: seeds {scene.seed} .. {scene.seed + seeds - 1} "
                         "pass 2^32 - 1")
    if scene.engine == "lattice":  # no horizon: checked bit for bit at a few N_c instead
        return lattice_horizon(scene, seeds=seeds, max_collisions=max_collisions, progress=progress)
    if progress is None:
        progress = sys.stdout.isatty()
    n = scene.particles
    grid = sorted({max(1, round(c * n / 2)) for c in HORIZON_GRID if c * n / 2 <= max_collisions})
    if not grid:
        grid = [max(1, int(max_collisions))]
    per_seed = []
    bar = Bar(progress, float(seeds * len(grid)), "horizon", "pt")
    done_pts = 0
    try:
        with Interrupt() as stop:
            for s in range(seeds):
                sim = build_simulation(scene, scene.seed + s)
                box, periodic = geometry(sim)
                x0, v0 = sim.positions, sim.velocities
                errs, done = [], 0
                for nc in grid:
                    done += int(sim.run(collisions=nc - done)["collisions"])
                    clone = Simulation.from_snapshot(sim.snapshot())
                    clone.run_back(on_divergence="ignore")
                    if stop.presses:  # Ctrl-C stopped the run or its reversal short of N_c: no point
                        break
                    ex, ev = round_trip_errors(clone.positions, clone.velocities, x0, v0, box, periodic)
                    errs.append((ex, ev))
                    done_pts += 1
                    bar.to(done_pts)
                    if max(ex, ev) >= o1 or stop.presses:
                        break
                if errs or not stop.presses:
                    per_seed.append(errs)
                if stop.presses:
                    break
            interrupted = stop.presses > 0
    finally:
        bar.close()
    rows, h = combine_seeds(grid, n, per_seed)
    reached = any(max(r["error_x"], r["error_v"]) > BAR for r in rows)
    length = f"round trips of up to {grid[-1]:,} collisions" if grid else None  # not the scene's [run] length
    return {"kind": "horizon", "scene": scene.to_dict(), "summary": scene.summary(length), "seeds": len(per_seed),
            "seed_first": scene.seed, "max_collisions": int(max_collisions), "o1": o1, "bar": BAR,
            "rows": rows, "horizon_collisions": h, "horizon_per_particle": 2.0 * h / n,
            "horizon_reached": reached, "interrupted": "horizon" if interrupted else None,
            "error_definitions": ERROR_DEFINITIONS, "peak_rss_bytes": peak_rss(),
            "date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"), "written": []}

