"""What a randomized collision law does to transport: self-diffusion of a hard-sphere gas under
the flux and uniform laws against the specular (textbook) gas and Enskog's value
(docs/physics.md, "Transport"). Writes its JSON to --out (default transport.json).

    PYTHONPATH=build-dev/pkg python -m revcol.studies.transport [--seeds 3] [--collisions 1e6] \
        [--out bench/results/transport.json]

Each run: N = 1000, periodic box, 100 collisions per particle to equilibrate, then observed
(revcol.Simulation.observe) for `collisions` collisions; D = slope / (2 d) of a least-squares
line through the unwrapped MSD at the block ends over the second half of the observation (the
ballistic start is long gone: the first half spans tens of mean free times). The error is the
standard error over seeds. Enskog's D (first Chapman-Enskog approximation, unit mass, kT = T):
  3D  D_E = 3 / (8 n sigma^2 g(sigma)) sqrt(T / pi),   g(sigma) = (1 - phi / 2) / (1 - phi)^3 (CS)
  2D  D_E = 1 / (2 n sigma g(sigma)) sqrt(T / pi),     g(sigma) = (1 - 7 phi / 16) / (1 - phi)^2 (Henderson)
The equilibrium claim (docs/physics.md) is that the flux law keeps every static property of the
specular gas; this measures what it does not keep: its dynamics.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import time

import numpy as np

from ..engine import Simulation

CASES = [(2, 0.3), (2, 0.5), (3, 0.1), (3, 0.3)]
LAWS = [("specular", {"mode": "specular"}), ("flux", {"law": "flux"}), ("uniform", {"law": "uniform"})]


def enskog(d: int, phi: float, temperature: float) -> float:
    if d == 3:
        n = 6.0 * phi / math.pi
        g = (1.0 - phi / 2.0) / (1.0 - phi) ** 3
        return 3.0 / (8.0 * n * g) * math.sqrt(temperature / math.pi)
    n = 4.0 * phi / math.pi
    g = (1.0 - 7.0 * phi / 16.0) / (1.0 - phi) ** 2
    return 1.0 / (2.0 * n * g) * math.sqrt(temperature / math.pi)


def diffusion(d: int, phi: float, seed: int, collisions: int, **kw) -> tuple[float, float, float]:
    """(D, T, mean free time) of one run."""
    n = 1000
    s = Simulation.random(n, d, phi, seed=seed, **kw)
    s.run(collisions=50 * n)
    s.observe()
    s.run(collisions=collisions)
    o = s.observation()
    t, msd = np.asarray(o.msd_time), np.asarray(o.msd)
    half = t >= 0.5 * t[-1]
    slope = np.polyfit(t[half], msd[half], 1)[0]
    return slope / (2 * d), float(o.temperature.value), float(o.mean_free_time.value)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--collisions", type=float, default=1e6)
    ap.add_argument("--out", default="transport.json")
    a = ap.parse_args()
    t0 = time.time()
    rows = []
    for d, phi in CASES:
        for law, kw in LAWS:
            runs = [diffusion(d, phi, 1 + s, int(a.collisions), **kw) for s in range(a.seeds)]
            D = np.array([r[0] for r in runs])
            T = float(np.mean([r[1] for r in runs]))
            de = enskog(d, phi, T)
            row = {"dim": d, "phi": phi, "law": law, "D": float(D.mean()),
                   "D_error": float(D.std(ddof=1) / math.sqrt(len(D))) if len(D) > 1 else None,
                   "D_seeds": D.tolist(), "temperature": T, "mean_free_time": float(np.mean([r[2] for r in runs])),
                   "D_enskog": de, "D_over_enskog": float(D.mean() / de)}
            rows.append(row)
            print(f"d={d} phi={phi} {law:8s} D = {row['D']:.4f} +- {row['D_error']:.4f}  D/D_E = {row['D_over_enskog']:.3f}",
                  flush=True)
    for r in rows:  # against the specular gas of the same (d, phi)
        ref = next(q for q in rows if q["dim"] == r["dim"] and q["phi"] == r["phi"] and q["law"] == "specular")
        r["D_over_specular"] = r["D"] / ref["D"]
    out = {"command": " ".join(["python", "-m", "revcol.studies.transport"] + sys.argv[1:]),
           "commit": subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                                    text=True).stdout.strip(),
           "loadavg": os.getloadavg(), "wall_s": time.time() - t0, "n": 1000, "rows": rows}
    tmp = a.out + ".tmp"
    with open(tmp, "w") as f:
        json.dump(out, f, indent=1)
    os.replace(tmp, a.out)
    print(f"{out['wall_s']:.0f} s -> {a.out}")


if __name__ == "__main__":
    main()
