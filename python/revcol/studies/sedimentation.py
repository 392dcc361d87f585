"""Sedimentation: a hard-sphere gas under gravity (the uniform field of either engine) against
hydrostatic equilibrium with the equation of state in the local-density approximation, and
against the barometric law it reduces to at low density; on the lattice engine also the walls'
momentum against the column's weight, and the run taken back to its start bit for bit.

A gas of N disks (spheres) of unit diameter and mass, dropped from a uniform start in a box
periodic across and walled along the field (g < 0 along the last axis: the floor at 0); energy
is kept, so the fall heats it, and kT is measured from the frames' velocities. In equilibrium the centres'
number density n(z) obeys dP/dz = -m |g| n with P = n kT Z(phi), phi = n v (v a particle's
volume) and Z Henderson's (disks) or Carnahan-Starling's (spheres): `lda_profile` integrates it
upwards from the floor's contact plane z = 1/2 with the bottom density that holds all N. The
ideal gas gives the barometric law n ~ exp(-m |g| z / kT). The layering at the floor (a few
diameters) is beyond the LDA: the comparison uses the mean height of the centres above 2 D and
the profile there. The deviations are in the combined error of the mean height (8 blocks of
frames) and of the prediction through kT's (the same blocks).

``--engine lattice``: the same start quantized once onto the lattice engine, whose field is an
even integer per tick^2 (the g run, ``sim.gravity``, is what the predictions use; at the
automatic tick it is within 2^-8 of the one asked). Over the frames the momentum the floor gave
the gas less the ceiling's is compared with the column's weight N m |g| t (``weight_ratio``,
which momentum balance makes 1 up to the change of the gas's own momentum), and at the end the
whole run goes back to the start and is compared bit for bit (``back_bit_for_bit``).

    python -m revcol.studies.sedimentation --dim 2 --n 400 --width 200 --g 0.2 [--engine lattice] --json F
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time

import numpy as np

__all__ = ["lda_profile", "measure", "figure", "main"]


def _z_eos(dim: int, phi: np.ndarray) -> np.ndarray:
    if dim == 2:
        return (1.0 + phi * phi / 8.0) / (1.0 - phi) ** 2  # Henderson
    if dim == 3:
        return (1.0 + phi + phi * phi - phi ** 3) / (1.0 - phi) ** 3  # Carnahan-Starling
    return 1.0 / (1.0 - phi)  # Tonks


def lda_profile(dim: int, n: int, area: float, height: float, g: float, kt: float = 1.0,
                ideal: bool = False, points: int = 4000) -> tuple:
    """(z, n(z)): the centres' density from z = 1/2 to height - 1/2 holding n particles over
    ``area`` (the box's cross-section: its width in 2D), field |g|, unit mass and diameter;
    ``ideal``: the barometric law instead of the equation of state."""
    v = {1: 1.0, 2: math.pi / 4.0, 3: math.pi / 6.0}[dim]
    z = np.linspace(0.5, height - 0.5, points)
    dz = z[1] - z[0]

    def column(n0: float) -> np.ndarray:
        if ideal:
            return n0 * np.exp(-g * (z - z[0]) / kt)
        out = np.empty_like(z)
        q = n0
        for i in range(len(z)):  # dn/dz = -g n / (kT dP/dn), P = n Z(n v): explicit midpoint steps
            out[i] = q

            def slope(x: float) -> float:
                h = 1e-7 * max(x, 1e-12)
                p = lambda y: y * _z_eos(dim, np.asarray(y * v))  # noqa: E731
                return -g * x / (kt * float((p(x + h) - p(x - h)) / (2.0 * h)))
            mid = q + 0.5 * dz * slope(q)
            q = max(q + dz * slope(max(mid, 0.0)), 0.0)
        return out

    lo, hi = 0.0, 0.99 / v
    for _ in range(60):  # the bottom density that holds all n
        mid = 0.5 * (lo + hi)
        if np.trapezoid(column(mid), z) * area < n:
            lo = mid
        else:
            hi = mid
    return z, column(0.5 * (lo + hi))


def measure(dim: int = 2, n: int = 400, width: float = 200.0, height: float = 60.0, g: float = 0.2,
            seed: int = 1, settle: float = 200.0, frames: int = 400, every: float = 1.0, bins: int = 40,
            engine: str = "float") -> dict:
    """A gas dropped from a random start in the box (width^(d-1) x height), settled for
    ``settle`` time units, then ``frames`` frames ``every`` apart: the centres' density profile,
    their mean height above 2 D with its error from 8 blocks of frames, the LDA's and the
    barometric law's, and the energy drift."""
    from ..engine import Simulation
    box = [width] * (dim - 1) + [height]
    bnd = ["periodic"] * (dim - 1) + ["wall"]
    gravity = [0.0] * (dim - 1) + [-g]
    from .. import _core
    x, v = _core.engine_random_start(n, box, bnd, 1.0, seed)  # uniform in the box (kT = 1): then it falls
    sim = Simulation(x, v, box, boundary=bnd, gravity=gravity, seed=seed, engine=engine)
    g = -float(sim.gravity[-1])  # the field run (the lattice's, quantized)
    start = sim.snapshot() if engine == "lattice" else None
    t0 = time.perf_counter()
    sim.run(time=settle)
    wall0 = _walls(sim)
    zs, k2 = [], []
    for k in range(frames):
        sim.run(time=settle + (k + 1) * every)
        zs.append(sim.positions[:, -1].copy())
        k2.append(float((sim.velocities ** 2).sum()) / (dim * n))
    zs = np.asarray(zs)
    wall1 = _walls(sim)
    kt = float(np.mean(k2))  # the gas's own temperature: energy is kept, so the fall heats it
    kt_blocks = np.array([b.mean() for b in np.array_split(np.asarray(k2), 8)])
    kt_error = float(kt_blocks.std(ddof=1) / math.sqrt(len(kt_blocks)))
    area = width ** (dim - 1)
    edges = np.linspace(0.5, height - 0.5, bins + 1)
    hist = np.array([np.histogram(f, edges)[0] for f in zs]) / (area * np.diff(edges))
    above = lambda f: f[f >= 2.0].mean()  # noqa: E731
    blocks = np.array_split(np.array([above(f) for f in zs]), 8)
    means = np.array([b.mean() for b in blocks])
    zm, ze = float(means.mean()), float(means.std(ddof=1) / math.sqrt(len(means)))
    # the prediction scales about as kT: its error from kT's, beside the mean height's own
    ze_all = math.hypot(ze, zm * kt_error / kt)
    out = {"dim": dim, "n": n, "width": width, "height": height, "g": g, "seed": seed, "settle": settle,
           "frames": frames, "every": every, "kt": kt, "kt_error": kt_error, "mean_height": zm,
           "mean_height_error": ze, "combined_error": ze_all,
           "profile_z": ((edges[1:] + edges[:-1]) / 2).tolist(), "profile": hist.mean(0).tolist(),
           "profile_error": (hist.std(0, ddof=1) / math.sqrt(frames)).tolist(),
           "energy_drift": sim.diagnostics()["energy_drift"], "seconds": time.perf_counter() - t0,
           "engine": engine, "g_run": g}
    if wall0 is not None:  # the floor's momentum less the ceiling's over the frames, against N |g| t
        (f0, c0, t_0), (f1, c1, t_1) = wall0, wall1
        u = sim.units
        out["weight_ratio"] = ((f1 - f0) - (c1 - c0)) / (n * abs(int(u["gravity"][-1])) * (t_1 - t_0))
        out["collisions"] = int(sim.diagnostics()["collisions"])
        t_back = time.perf_counter()
        sim.run_back()
        out["back_seconds"] = time.perf_counter() - t_back
        end = sim.snapshot()
        out["back_bit_for_bit"] = all(np.array_equal(np.asarray(start[k]), np.asarray(end[k]))
                                      for k in ("x", "v", "streams", "bits", "clock", "collisions"))
    for name, ideal in (("lda", False), ("barometric", True)):
        z, nz = lda_profile(dim, n, area, height, g, kt=kt, ideal=ideal)
        sel = z >= 2.0
        out[f"{name}_mean_height"] = float(np.trapezoid(z[sel] * nz[sel], z[sel]) / np.trapezoid(nz[sel], z[sel]))
        out[f"{name}_deviation_sd"] = (zm - out[f"{name}_mean_height"]) / ze_all
        out[f"{name}_bottom_fraction"] = float(nz[0] * {1: 1.0, 2: math.pi / 4, 3: math.pi / 6}[dim])
    return out


def figure(runs: list, path: str) -> None:
    """Per dimension, the density profile of the first seed on each engine beside the LDA's and the
    barometric law's (with that run's kT and field)."""
    from .._io import save_figure
    from ..plots import _pyplot
    plt = _pyplot()
    dims = sorted({r["dim"] for r in runs})
    fig, axes = plt.subplots(1, len(dims), figsize=(6 * len(dims), 4.2), squeeze=False)
    for ax, dim in zip(axes[0], dims):
        seen, first = set(), None
        for r in runs:
            eng = r.get("engine", "float")
            if r["dim"] != dim or eng in seen:
                continue
            seen.add(eng)
            first = first or r
            z, prof, err = (np.asarray(r[k]) for k in ("profile_z", "profile", "profile_error"))
            ax.errorbar(z, prof, yerr=err, fmt="o" if eng == "float" else "s", ms=3, mfc="none", lw=0.8,
                        label=f"{eng} engine (seed {r['seed']}, kT {r['kt']:.2f})")
        area = first["width"] ** (dim - 1)
        g = first.get("g_run", first["g"])
        for ideal, style, name in ((False, "-", "LDA, " + ("Henderson" if dim == 2 else "Carnahan-Starling")),
                                   (True, "--", "barometric (ideal gas)")):
            zz, nz = lda_profile(dim, first["n"], area, first["height"], g, kt=first["kt"], ideal=ideal)
            ax.plot(zz, nz, style, color="0.3", lw=1, label=name)
        ax.set_xlabel("height of the centre (diameters)")
        ax.set_ylabel("number density (per diameter^%d)" % dim)
        ax.set_title(f"{dim}D sedimentation, N = {first['n']}, g = {first['g']:g}, box {first['width']:g}"
                     f"{'^2' if dim == 3 else ''} x {first['height']:g}, {first['frames']} frames", fontsize=9)
        ax.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)


def _walls(sim):
    """The lattice's field walls (floor, ceiling) momentum and the clock; None on the float engine."""
    if sim.engine != "lattice":
        return None
    d = sim.diagnostics()
    floor, ceiling = d["field_wall_impulse"]
    return floor, ceiling, int(d["clock"])


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--dim", type=int, default=2)
    p.add_argument("--n", type=int, default=400)
    p.add_argument("--width", type=float, default=200.0)
    p.add_argument("--height", type=float, default=60.0)
    p.add_argument("--g", type=float, default=0.2)
    p.add_argument("--seeds", type=int, nargs="+", default=[1])
    p.add_argument("--frames", type=int, default=400)
    p.add_argument("--json", default=None)
    p.add_argument("--engine", default="float", choices=["float", "lattice"])
    p.add_argument("--figure", default=None, help="the density profiles (PNG): the runs', or with --from the files'")
    p.add_argument("--from", dest="sources", nargs="+", default=None, help="JSON files of earlier runs: only the figure")
    a = p.parse_args(argv)
    if a.sources:
        runs = [r for f in a.sources for r in json.load(open(f))["runs"]]
        if a.figure:
            figure(runs, a.figure)
        return 0
    runs = []
    for seed in a.seeds:
        r = measure(a.dim, a.n, a.width, a.height, a.g, seed=seed, frames=a.frames, engine=a.engine)
        print(f"seed {seed}: mean height above 2 D {r['mean_height']:.4f} +- {r['mean_height_error']:.4f}; LDA "
              f"{r['lda_mean_height']:.4f} ({r['lda_deviation_sd']:+.1f} sd), barometric {r['barometric_mean_height']:.4f} "
              f"({r['barometric_deviation_sd']:+.1f} sd); bottom packing fraction (LDA) {r['lda_bottom_fraction']:.3f}; "
              f"energy drift {r['energy_drift']:.1e}; {r['seconds']:.1f} s"
              + (f"; walls / weight {r['weight_ratio']:.5f}, back bit for bit {r['back_bit_for_bit']}"
                 if "weight_ratio" in r else ""), flush=True)
        runs.append(r)
    if a.json:
        from .._io import atomic_open
        with atomic_open(a.json) as f:
            json.dump({"study": "sedimentation", "command": "python -m revcol.studies.sedimentation " + " ".join(argv),
                       "runs": runs}, f, indent=1)
    if a.figure:
        figure(runs, a.figure)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
