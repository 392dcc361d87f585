"""Transport in the specular hard-sphere gas: self-diffusion D and shear viscosity eta of the
lattice engine's specular mode against the float engine's specular mode, 3D, periodic, with
Enskog's values as the scale (docs/physics.md, "Transport in the specular gas").

    PYTHONPATH=build-dev/pkg python -m revcol.studies.transport_specular [--n 1000] \\
        [--phi 0.2 0.3 0.4 0.45] [--seeds 4] [--first-seed 1] [--time 5000] [--out transport_specular.json]

Each run (engine, packing fraction, seed): N spheres from the same random start (``random(...,
seed)``: the lattice quantizes the float engine's start once; the trajectories are independent
after a few collisions), kT = 1, zero momentum; ``--equilibrate`` collisions per particle; then
``--time`` time units (sigma sqrt(m / kT)) observed in windows of ``WINDOW_BLOCKS`` blocks of
``--block`` each, every window a fresh ``observe(block_time=...)`` (the observer merges blocks past
256, which would coarsen its record; a window keeps one spacing).

D: the slope / 6 of each window's MSD (one origin, the window's start, averaged over the N
particles) over its second half; the mean over all windows of all seeds. eta: Einstein-Helfand
(revcol.observe.helfand_viscosity): the mean-square increment of the Helfand moments I_xy,
I_xz, I_yz over every origin at a block end within a window, pooled over the windows and seeds,
a straight line through the lags in [--lag-min, --lag-max]; eta = slope / (2 V T). Errors:
the windows in 4 contiguous batches per seed, s / sqrt(batches) of the batch values (D and
eta alike); the seeds' own values are in the JSON as a check. Agreement: (lattice - float) /
sqrt(se_l^2 + se_f^2).

References (revcol.studies.literature): Enskog's D_E and eta_E (first Chapman-Enskog / Sonine
approximations) with the Carnahan-Starling contact value; the Yeh-Hummer correction
D_inf = D_N + 2.837297 kT / (6 pi eta L) with eta the engine's own measured value.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import time
from typing import Any, Callable

import numpy as np

from ..engine import Simulation
from ..lattice import LatticeSimulation3D
from ..observe import helfand_viscosity, self_diffusion
from .literature import contact_value, enskog_D, enskog_eta, yeh_hummer

WINDOW_BLOCKS = 250  # blocks per window (below the observer's 256: no merging)
BATCHES_PER_SEED = 4
ENGINES: dict[str, Callable[[int, float, int], Any]] = {
    "lattice": lambda n, phi, seed: LatticeSimulation3D.random(n, phi=phi, seed=seed, mode="specular"),
    "float": lambda n, phi, seed: Simulation.random(n, 3, phi, seed=seed, mode="specular"),
}


def run_one(engine: str, n: int, phi: float, seed: int, *, duration: float, block: float,
            equilibrate: float) -> tuple[list, dict]:
    """One run: its windows' observations and a few scalars (T, Z, collision rate, box side)."""
    sim = ENGINES[engine](n, phi, seed)
    sim.run(collisions=int(equilibrate * n))
    window = WINDOW_BLOCKS * block
    obs = []
    for _ in range(max(1, int(round(duration / window)))):
        sim.observe(block_time=block)
        sim.run(time=sim.time + window + 0.5 * block)  # ends between the 250th and a 251st block end
        obs.append(sim.observation())
    mean = lambda key: float(np.mean([getattr(o, key).value for o in obs]))  # noqa: E731
    return obs, {"temperature": mean("temperature"), "compressibility": mean("compressibility"),
                 "collision_rate": mean("collision_rate"), "box": float(sim.box[0]),
                 "volume": float(np.prod(sim.box))}


def measure(engine: str, n: int, phi: float, seeds: list[int], *, duration: float, block: float,
            equilibrate: float, lag_min: float, lag_max: float) -> dict:
    """D and eta of one (engine, phi) over its seeds, with their errors (module docstring)."""
    t0 = time.time()
    runs = [run_one(engine, n, phi, s, duration=duration, block=block, equilibrate=equilibrate) for s in seeds]
    windows = [o for obs, _ in runs for o in obs]
    info = runs[0][1]
    T = float(np.mean([r[1]["temperature"] for r in runs]))
    batches = BATCHES_PER_SEED * len(seeds)
    D = self_diffusion(windows, batches=batches)
    eta = helfand_viscosity(windows, info["volume"], lag_min, lag_max, temperature=T, batches=batches)
    seed_D = [self_diffusion(obs).value for obs, _ in runs]
    seed_eta = [helfand_viscosity(obs, info["volume"], lag_min, lag_max, batches=1).value for obs, _ in runs]
    d_e, eta_e = enskog_D(phi, 3, T), enskog_eta(phi, 3, T)
    d_yh = yeh_hummer(D.value, eta.value, info["box"], T)
    return {"engine": engine, "phi": phi, "n": n, "seeds": seeds, "windows": len(windows),
            "observed_time": float(sum(o.duration for o in windows)),
            "collisions": int(sum(o.pair_collisions + o.group_collisions for o in windows)),
            "temperature": T, "compressibility": float(np.mean([r[1]["compressibility"] for r in runs])),
            "collision_rate": float(np.mean([r[1]["collision_rate"] for r in runs])), "box": info["box"],
            "D": D.value, "D_error": D.error, "D_seeds": seed_D, "eta": eta.value, "eta_error": eta.error,
            "eta_seeds": seed_eta, "g_contact_cs": contact_value(phi, 3), "D_enskog": d_e, "eta_enskog": eta_e,
            "D_over_enskog": D.value / d_e, "eta_over_enskog": eta.value / eta_e,
            "D_yeh_hummer": d_yh, "D_yeh_hummer_over_enskog": d_yh / d_e, "wall_s": time.time() - t0}


def compare(rows: list[dict]) -> list[dict]:
    """Per packing fraction: lattice - float in units of the combined standard error."""
    out = []
    for phi in sorted({r["phi"] for r in rows}):
        pair = {r["engine"]: r for r in rows if r["phi"] == phi}
        if set(pair) != {"lattice", "float"}:
            continue
        a, b = pair["lattice"], pair["float"]
        entry: dict[str, Any] = {"phi": phi}
        for key in ("D", "eta"):
            se = math.hypot(a[f"{key}_error"], b[f"{key}_error"])
            entry[f"{key}_difference"] = a[key] - b[key]
            entry[f"{key}_sigmas"] = (a[key] - b[key]) / se if se > 0 else math.nan
        out.append(entry)
    return out


def study(n: int, phis: list[float], seeds: list[int], *, duration: float, block: float, equilibrate: float,
          lag_min: float, lag_max: float, engines=("lattice", "float"), progress=print,
          on_row: Callable[[list[dict]], None] | None = None) -> dict:
    """Every (phi, engine) point, then the comparison."""
    rows = []
    for phi in phis:
        for engine in engines:
            r = measure(engine, n, phi, seeds, duration=duration, block=block, equilibrate=equilibrate,
                        lag_min=lag_min, lag_max=lag_max)
            rows.append(r)
            progress(f"phi={phi} {engine:7s} D = {r['D']:.5f} +- {r['D_error']:.5f} (D/D_E {r['D_over_enskog']:.3f}) "
                     f"eta = {r['eta']:.4f} +- {r['eta_error']:.4f} (eta/eta_E {r['eta_over_enskog']:.3f}) "
                     f"{r['collisions']:.3g} collisions, {r['wall_s']:.0f} s")
            if on_row:
                on_row(rows)
    return {"n": n, "phis": phis, "seeds": seeds, "time_per_seed": duration, "block_time": block,
            "window_blocks": WINDOW_BLOCKS, "equilibrate_per_particle": equilibrate, "lag_min": lag_min,
            "lag_max": lag_max, "batches_per_seed": BATCHES_PER_SEED, "rows": rows, "comparison": compare(rows)}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1000)
    ap.add_argument("--phi", type=float, nargs="+", default=[0.2, 0.3, 0.4, 0.45])
    ap.add_argument("--seeds", type=int, default=4)
    ap.add_argument("--first-seed", type=int, default=1, help="seeds first-seed .. first-seed + seeds - 1")
    ap.add_argument("--time", type=float, default=5000.0, help="observed time per seed (time units)")
    ap.add_argument("--block", type=float, default=0.16, help="block time (time units)")
    ap.add_argument("--equilibrate", type=float, default=100.0, help="collisions per particle before observing")
    ap.add_argument("--lag-min", type=float, default=4.0)
    ap.add_argument("--lag-max", type=float, default=10.0)
    ap.add_argument("--out", default="transport_specular.json")
    a = ap.parse_args(argv)
    t0, load0 = time.time(), os.getloadavg()
    head = {"command": " ".join(["python", "-m", "revcol.studies.transport_specular"] + sys.argv[1:]),
            "commit": subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                                     text=True).stdout.strip(), "loadavg_start": load0}

    def write(res: dict) -> None:
        out = dict(head, loadavg_end=os.getloadavg(), wall_s=time.time() - t0, **res)
        tmp = a.out + ".tmp"
        with open(tmp, "w") as f:
            json.dump(out, f, indent=1)
        os.replace(tmp, a.out)

    kw = dict(duration=a.time, block=a.block, equilibrate=a.equilibrate, lag_min=a.lag_min, lag_max=a.lag_max)
    seeds = list(range(a.first_seed, a.first_seed + a.seeds))
    res = study(a.n, a.phi, seeds, progress=lambda s: print(s, flush=True),
                on_row=lambda rows: write({"rows": rows, "partial": True}), **kw)
    write(res)
    for c in res["comparison"]:
        print(f"phi={c['phi']}: lattice - float: D {c['D_sigmas']:+.2f} sd, eta {c['eta_sigmas']:+.2f} sd")
    print(f"{time.time() - t0:.0f} s -> {a.out}")


if __name__ == "__main__":
    main()
