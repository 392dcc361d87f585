"""The lattice engine against the float engine: the same flux-law gas observed on both.

The lattice engine runs an exact integer dynamics (collisions on tick transitions, an integer
pair operator); the float engine the continuous one. Both sample the flux law, so their
equilibrium statics must agree: the compressibility factor Z (collision virial), the
collision rate per particle and the contact value g(D+) of the radial distribution (from
frames, a quadratic fit of the bins in (D, D + 0.2]). Each is compared in standard errors:
Z and the rate from the observers' block errors, g(D+) from the spread of its value over
blocks of frames. Both start from the same random state (the lattice quantizes it once) and
are independent trajectories after.

    python -m revcol.studies.engine_agreement --json bench/results/engine_agreement.json

runs the issue's cases (N = 1000; 2D area fraction 0.5, 3D volume fraction 0.3); ``--collisions``
and ``--n`` make it shorter (the CI test runs a reduced form of ``compare``). ``--mode specular``
compares the two engines' specular dynamics instead (the lattice's deterministic map against the
float engine's reflection: bench/results/engine_agreement_specular.json), ``--cases`` and
``--seeds`` choose the gases.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from typing import Optional, Sequence

import numpy as np

from .._io import atomic_open
from ..engine import Simulation
from ..observe import contact_value, radial_distribution

__all__ = ["compare", "main"]


def _run(engine: str, dim: int, phi: float, n: int, collisions: int, warm: int, frames: int, groups: int,
         seed: int, bins: int, mode: str = "exact") -> dict:
    sim = Simulation.random(n=n, dim=dim, phi=phi, seed=seed, engine=engine, mode=mode)
    sim.run(collisions=warm)
    sim.observe()
    per = max(1, collisions // frames)
    xs = []
    t0 = time.perf_counter()
    for _ in range(frames):
        sim.run(collisions=per)
        xs.append(np.asarray(sim.positions))
    seconds = time.perf_counter() - t0
    o = sim.observation()
    box = np.asarray(sim.box, dtype=float)
    r_max = min(2.0, 0.5 * float(box.min()))
    gs = []
    for part in np.array_split(np.asarray(xs), groups):
        r, g = radial_distribution(part, box, bins=bins, r_max=r_max, use_freud=False)
        gs.append(contact_value(r, g))
    gs = np.asarray(gs)
    return {
        "engine": engine,
        "collisions": per * frames,
        "seconds": seconds,
        "z": [o.compressibility.value, o.compressibility.error],
        "collision_rate": [o.collision_rate.value, o.collision_rate.error],
        "g_contact": [float(gs.mean()), float(gs.std(ddof=1) / math.sqrt(len(gs)))],
        "temperature": o.temperature.value,
        "blocks": o.blocks,
    }


def compare(dim: int, phi: float, n: int = 1000, collisions: int = 2_000_000, warm: Optional[int] = None,
            frames: int = 100, groups: int = 10, seed: int = 1, bins: int = 100, mode: str = "exact") -> dict:
    """Both engines on one gas (periodic; ``mode`` "exact", the flux law, or "specular" on both):
    Z, collision rate and g(D+) with their errors, and their differences in combined standard
    errors (``sigmas``: |a - b| / sqrt(e_a^2 + e_b^2))."""
    warm = 20 * n if warm is None else warm
    runs = {e: _run(e, dim, phi, n, collisions, warm, frames, groups, seed, bins, mode) for e in ("float", "lattice")}
    sig = {}
    for q in ("z", "collision_rate", "g_contact"):
        (a, ea), (b, eb) = runs["float"][q], runs["lattice"][q]
        sig[q] = abs(a - b) / math.hypot(ea, eb) if ea > 0 or eb > 0 else float("inf")
    return {"dim": dim, "phi": phi, "n": n, "seed": seed, "mode": mode, "float": runs["float"], "lattice": runs["lattice"],
            "sigmas": sig}


def _lines(res: dict) -> list:
    out = []
    for q, name in (("z", "Z"), ("collision_rate", "collision rate"), ("g_contact", "g(D+)")):
        f, la = res["float"][q], res["lattice"][q]
        out.append(f"  {name:15s} float {f[0]:.5f} +- {f[1]:.5f}   lattice {la[0]:.5f} +- {la[1]:.5f}   "
                   f"{res['sigmas'][q]:.2f} sd")
    return out


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m revcol.studies.engine_agreement", description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=1000)
    ap.add_argument("--collisions", type=int, default=2_000_000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--seeds", type=int, default=1, help="independent gases per case (seed, seed + 1, ...)")
    ap.add_argument("--mode", choices=("exact", "specular"), default="exact",
                    help="exact: the flux law on both engines; specular: specular dynamics on both")
    ap.add_argument("--cases", nargs="+", default=["2:0.5", "3:0.3"], help="dim:phi pairs")
    ap.add_argument("--json", help="write the results here (atomically)")
    a = ap.parse_args(argv)
    results = []
    for spec in a.cases:
        dim, phi = int(spec.split(":")[0]), float(spec.split(":")[1])
        for seed in range(a.seed, a.seed + a.seeds):
            res = compare(dim, phi, n=a.n, collisions=a.collisions, seed=seed, mode=a.mode)
            results.append(res)
            print(f"{dim}D phi {phi}, N = {a.n}, seed {seed}, {a.mode}: {res['float']['collisions']} collisions each",
                  flush=True)
            for line in _lines(res):
                print(line)
    worst = max(max(r["sigmas"].values()) for r in results)
    print(f"largest difference: {worst:.2f} standard errors ({'within' if worst < 3 else 'BEYOND'} 3)")
    if a.json:
        with atomic_open(a.json) as f:
            cmd = "python -m revcol.studies.engine_agreement " + " ".join(sys.argv[1:])
            f.write(json.dumps({"command": cmd, "results": results}, indent=1) + "\n")
    return 0 if worst < 3 else 1


if __name__ == "__main__":
    raise SystemExit(main())
