"""Relaxed random starts (init "relax", engine/init.hpp): what they cost and what they give.

``time``: the seconds a relaxed start takes (positions drawn, overlaps relaxed away, velocities)
against N for the dense gases that need it: a 1:1 binary mixture of size ratio 1.4 at area
fraction 0.80 (2D) and volume fraction 0.58 and 0.62 (3D), a 10% Gaussian polydisperse gas at
0.60 (3D), and one size at 0.55 (3D; its "auto" start is a crystal). Rounds interleave the cases
(A B C ... A B C ...), one core if ``--cpu`` pins it; medians with their range and the load.

``eos``: the binary mixture's equation of state at the dense points the crystal of the largest
cannot start (2D 0.75, 3D 0.55) on the lattice engine, from relaxed starts: Z against SLHY (2D)
and BMCSL (3D), and against the event-chain sampler of the same particles at the same N (no
theory), each run back to its start bit for bit (revcol.studies.mixture_eos.measure). A relaxed
start has many pairs 1e-3 of a diameter apart; it is equilibrated by time, so give it hundreds of
collisions per particle (20 left Z 17% high in 2D, 56% in 3D; 500 about 1-3%).

    python bench/dense_starts.py time --n 1000 10000 100000 --rounds 3 --cpu 1 --json bench/results/dense_starts.json
    python bench/dense_starts.py eos --n 1000 --seeds 1 2 3 4 --equilibrate 1000 --collisions 2000 --ecmc 1000 \
        --json bench/results/dense_starts.json

(each part writes its section of the file, keeping the other's).
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

import numpy as np

CASES = {  # name: (dim, phi, sizes)
    "2D binary 0.80": (2, 0.80, "binary"),
    "3D binary 0.58": (3, 0.58, "binary"),
    "3D binary 0.62": (3, 0.62, "binary"),
    "3D polydisperse 0.60": (3, 0.60, "gauss"),
    "3D one size 0.55": (3, 0.55, "one"),
}


def _start(dim: int, n: int, phi: float, sizes: str, seed: int) -> None:
    from revcol import _core
    from revcol.studies.mixture_eos import binary_diameters, gaussian_diameters
    d = {"binary": lambda: binary_diameters(n, 1.4), "gauss": lambda: gaussian_diameters(n, seed), "one": lambda: []}[sizes]()
    _core.engine_random_state(dim, n, phi, ["periodic"], 1.0, seed, 0.0, "relax", False, list(d))


def time_starts(ns: list[int], rounds: int) -> dict:
    rows = {}
    for n in ns:
        for name in CASES:
            rows[f"{name}, N = {n}"] = {"seconds": [], "load": []}
    for r in range(rounds):
        for n in ns:
            for name, (dim, phi, sizes) in CASES.items():
                t0 = time.perf_counter()
                _start(dim, n, phi, sizes, seed=1 + r)
                dt = time.perf_counter() - t0
                row = rows[f"{name}, N = {n}"]
                row["seconds"].append(dt)
                row["load"].append(os.getloadavg()[0])
                print(f"round {r}: {name}, N = {n}: {dt:.3f} s (load {row['load'][-1]:.2f})", flush=True)
    for row in rows.values():
        s = row["seconds"]
        row.update(median=statistics.median(s), min=min(s), max=max(s))
    return rows


def eos(n: int, seeds: list[int], equilibrate: float, collisions: float, ecmc: float) -> list:
    from revcol.studies.mixture_eos import measure
    runs = []
    for seed in seeds:
        for dim, phi in ((2, 0.75), (3, 0.55)):
            m = measure(dim, n, phi, 1.4, equilibrate=equilibrate, collisions=collisions, seed=seed, ecmc=ecmc)
            print(f"{dim}D {phi} seed {seed}: Z = {m['z']:.4f} +- {m['z_error']:.4f}, {m['theory']} {m['z_theory']:.4f} "
                  f"({m['deviation_sd']:+.1f} sd, {100 * (m['z'] / m['z_theory'] - 1):+.2f}%); back to start "
                  f"{m['back_to_start']}; {m['seconds']:.1f} s", flush=True)
            if "ecmc" in m:
                print(f"    event chains at the same N: Z = {m['ecmc']['z_md'][0]:.4f} +- {m['ecmc']['z_md'][1]:.4f}; "
                      f"lattice - chains {m['ecmc_deviation_sd']:+.1f} sd", flush=True)
            runs.append(m)
    return runs


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("what", choices=["time", "eos"])
    p.add_argument("--n", type=int, nargs="+", default=None, help="time: N per case (1000 10000); eos: one N (4000)")
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--cpu", type=int, default=None, help="pin this process to one core")
    p.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    p.add_argument("--equilibrate", type=float, default=200.0, help="eos: collisions per particle before observing")
    p.add_argument("--collisions", type=float, default=1000.0, help="eos: observed collisions per particle")
    p.add_argument("--ecmc", type=float, default=0.0, help="eos: event-chain displacement per sphere (largest "
                   "diameters) of the same mixture at the same N, from the same start (0: none)")
    p.add_argument("--json", default=None)
    a = p.parse_args(argv)
    if a.cpu is not None:
        os.sched_setaffinity(0, {a.cpu})
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    out = {}
    if a.json and os.path.exists(a.json):
        with open(a.json) as f:
            out = json.load(f)
    section = {"command": "python bench/dense_starts.py " + " ".join(argv if argv is not None else sys.argv[1:]),
               "commit": commit, "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
               "cpu": a.cpu, "cores": os.cpu_count()}
    if a.what == "time":
        section["cases"] = time_starts(a.n or [1000, 10000], a.rounds)
    else:
        runs = eos((a.n or [4000])[0], a.seeds, a.equilibrate, a.collisions, a.ecmc)
        section["runs"] = runs
        table = {}
        for dim, phi in ((2, 0.75), (3, 0.55)):
            rs = [r for r in runs if r["dim"] == dim]
            z = np.array([r["z"] for r in rs])
            se = float(np.std(z, ddof=1) / np.sqrt(len(z))) if len(z) > 1 else rs[0]["z_error"]
            th = rs[0]["z_theory"]
            zc = np.array([r["ecmc"]["z_md"][0] for r in rs if "ecmc" in r])
            chains = {"z_ecmc": float(zc.mean()), "z_ecmc_error_seeds": float(np.std(zc, ddof=1) / np.sqrt(len(zc)))
                      if len(zc) > 1 else None} if len(zc) else {}
            table[f"{dim}D {phi}"] = {**chains, "z": float(z.mean()), "z_error_seeds": se, "theory": rs[0]["theory"],
                                      "z_theory": th, "deviation_percent": 100 * (z.mean() / th - 1),
                                      "deviation_sd": (z.mean() - th) / se if se > 0 else None,
                                      "all_back_to_start": all(r["back_to_start"] for r in rs)}
            print(f"{dim}D {phi}: Z = {z.mean():.4f} +- {se:.4f} ({len(z)} seeds) against {rs[0]['theory']} {th:.4f}: "
                  f"{table[f'{dim}D {phi}']['deviation_percent']:+.2f}%", flush=True)
        section["table"] = table
    out[a.what] = section
    if a.json:
        from revcol._io import atomic_open
        with atomic_open(a.json) as f:
            json.dump(out, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
