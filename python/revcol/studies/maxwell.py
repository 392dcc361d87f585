"""Relaxation to Maxwell-Boltzmann speeds (docs/engine.md): does a gas started with all speeds
equal reach the Maxwell-Boltzmann law under each collision law? Writes its JSON to --json
(default engine_maxwell.json).

    PYTHONPATH=build-dev/pkg python -m revcol.studies.maxwell [--n 1000] [--relax 40] [--gap 4] \\
        [--samples 25] [--json bench/results/engine_maxwell.json]

From all speeds equal (random directions), N particles (area or volume fraction 0.3, periodic
box) relax for `relax` collisions per particle; then `samples` snapshots, `gap` collisions per
particle apart, are pooled and the speeds compared with the Maxwell-Boltzmann law of the
measured kT by Kolmogorov-Smirnov: in d dimensions the speed s has
P(s' <= s) = P(d / 2, s^2 / (2 kT)) (the regularized lower incomplete gamma function), with
kT = <s^2> / d. p > 0.001 is the criterion; pooled snapshots are correlated, so p is
optimistic, and the last snapshot's p alone is reported beside it.
"""
from __future__ import annotations

import argparse
import json
import sys

import numpy as np
from scipy import special, stats

from .._io import atomic_open
from ..engine import Simulation

#: (dimension, mode, law) of each gas
CASES = [(2, "exact", "flux"), (3, "exact", "flux"), (2, "exact", "uniform"), (3, "exact", "uniform"),
         (2, "paper", "flux")]


def mb_cdf(s, dim: int, kT: float):
    """The Maxwell-Boltzmann distribution function of the speed in ``dim`` dimensions."""
    return special.gammainc(dim / 2.0, s * s / (2.0 * kT))


def relax(dim: int, mode: str, law: str, n: int = 1000, relax: float = 40.0, gap: float = 4.0,
          samples: int = 25, seed: int = 3) -> dict:
    """One gas from equal speeds: KS of its pooled speeds against Maxwell-Boltzmann."""
    sim = Simulation.random(n=n, dim=dim, phi=0.3, seed=seed, equal_speeds=True, mode=mode, law=law)
    sim.run(collisions=int(relax * n / 2))
    pooled = []
    for _ in range(samples):
        sim.run(collisions=int(gap * n / 2))
        pooled.append(np.linalg.norm(sim.velocities, axis=1))
    s = np.concatenate(pooled)
    kT = float((s ** 2).mean() / dim)
    ks = stats.kstest(s, lambda q: mb_cdf(q, dim, kT))
    one = stats.kstest(pooled[-1], lambda q: mb_cdf(q, dim, kT))
    return dict(dim=dim, mode=mode, law=law, n=n, samples=len(s), kT=kT, ks_stat=float(ks.statistic),
                p_value=float(ks.pvalue), p_value_last_snapshot=float(one.pvalue), passes=bool(ks.pvalue > 1e-3))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1000)
    ap.add_argument("--relax", type=float, default=40.0, help="collisions per particle to relax")
    ap.add_argument("--gap", type=float, default=4.0, help="collisions per particle between samples")
    ap.add_argument("--samples", type=int, default=25, help="snapshots pooled")
    ap.add_argument("--json", default="engine_maxwell.json")
    args = ap.parse_args(argv)
    rows = []
    for dim, mode, law in CASES:
        r = relax(dim, mode, law, n=args.n, relax=args.relax, gap=args.gap, samples=args.samples)
        rows.append(r)
        print(f"d={dim} {mode:5s} {law:7s}: KS D={r['ks_stat']:.4f} p={r['p_value']:.3g} "
              f"(last snapshot alone p={r['p_value_last_snapshot']:.3g}) {'PASS' if r['passes'] else 'FAIL'}",
              flush=True)
    command = " ".join(["python", "-m", "revcol.studies.maxwell"] + (sys.argv[1:] if argv is None else argv))
    with atomic_open(args.json) as f:
        json.dump(dict(command=command, relax_per_particle=args.relax, gap_per_particle=args.gap, rows=rows), f,
                  indent=1)
    print(f"wrote {args.json}")
    return 0 if all(r["passes"] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
