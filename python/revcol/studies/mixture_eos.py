"""The equation of state of a hard-sphere (3D) or hard-disk (2D) mixture on the lattice engine,
against the mixture theories: Boublik-Mansoori-Carnahan-Starling-Leland (BMCSL) for spheres
and the Santos-Lopez de Haro-Yuste (SLHY) form for disks, both from the sizes' moments.

BMCSL (T. Boublik, J. Chem. Phys. 53, 471 (1970); G. A. Mansoori et al., J. Chem. Phys. 54,
1523 (1971)): with xi_k = (pi/6) rho <d^k>,
    beta P = (6/pi) [xi_0 / (1 - xi_3) + 3 xi_1 xi_2 / (1 - xi_3)^2 + (3 - xi_3) xi_2^3 / (1 - xi_3)^3],
which is Carnahan-Starling for one diameter. SLHY (A. Santos, M. Lopez de Haro, S. B. Yuste,
J. Chem. Phys. 103, 4622 (1995)) for disks at area fraction eta:
    Z = 1 / (1 - eta) + (<d>^2 / <d^2>) [Z_1(eta) - 1 / (1 - eta)],
with Z_1 a one-component equation of state: Liu's (:func:`revcol.studies.eos.liu_disks`, the
project's reference for the disk fluid); Henderson's, which the SLHY paper used and which is
about 1.6% high at area fraction 0.5, is reported beside it.

A run: ``measure(dim, n, phi, ratio, ...)`` starts a binary mixture (equal numbers, diameters 1
and 1/ratio) at packing fraction phi, runs it ``equilibrate`` collisions per particle, then
observes ``collisions`` per particle (the collision virial, Z = 1 + W / K2, with its block
error) and runs back to the start bit for bit. ``compare`` pairs it with the one-size gas at
the same N, phi and seed (ratio 1, the mixture code path with equal radii): BMCSL is built on
Carnahan-Starling, which is 0.2-0.3% low for the pure sphere fluid at 0.3-0.45 (docs/physics.md),
so beside Z against BMCSL it reports the pure gas against Liu's and CS's equations and the
ratio Z_mixture / Z_pure against BMCSL / CS (SLHY / Liu in 2D), which the pure fluid's
equation and the O(1/N) terms both cancel from. ``python -m revcol.studies.mixture_eos --json F``
writes the 2D (area fraction 0.5) and 3D (0.4) points beside the theories.

    >>> round(bmcsl_z(0.3, [1.0]), 6) == round((1 + 0.3 + 0.09 - 0.027) / 0.7**3, 6)
    True
    >>> round(slhy_z(0.5, [1.0], henderson), 6) == round((1 + 0.25 / 8) / 0.25, 6)
    True
"""
from __future__ import annotations

import argparse
import json
import math
import time
from typing import Sequence

import numpy as np

from .eos import carnahan_starling, henderson, liu_disks, liu_spheres

__all__ = ["bmcsl_z", "slhy_z", "binary_diameters", "measure", "compare", "main"]


def _moments(diameters: Sequence[float]) -> list:
    d = np.asarray(diameters, dtype=float)
    return [float(np.mean(d**k)) for k in range(4)]


def bmcsl_z(phi: float, diameters: Sequence[float]) -> float:
    """Z = beta P / rho of a sphere mixture at packing fraction phi = (pi/6) rho <d^3>, its
    sizes given as one diameter per particle (or per species, equally weighted), by BMCSL."""
    m = _moments(diameters)
    rho = phi / (math.pi / 6.0 * m[3])
    xi = [math.pi / 6.0 * rho * mk for mk in m]
    one = 1.0 - xi[3]
    bp = 6.0 / math.pi * (xi[0] / one + 3.0 * xi[1] * xi[2] / one**2 + (3.0 - xi[3]) * xi[2] ** 3 / one**3)
    return bp / rho


def slhy_z(eta: float, diameters: Sequence[float], pure=liu_disks) -> float:
    """Z of a disk mixture at area fraction eta by SLHY, from the pure fluid's Z `pure`
    (Liu's by default)."""
    m = _moments(diameters)
    return 1.0 / (1.0 - eta) + m[1] ** 2 / m[2] * (pure(eta) - 1.0 / (1.0 - eta))


def binary_diameters(n: int, ratio: float) -> np.ndarray:
    """n diameters, every other one 1 / ratio (equal numbers of the two species)."""
    d = np.ones(n)
    d[1::2] = 1.0 / ratio
    return d


def measure(dim: int, n: int, phi: float, ratio: float, *, equilibrate: float = 100.0, collisions: float = 400.0,
            seed: int = 1, blocks: int = 32) -> dict:
    """One run (see the module docstring): Z with its block error, the theory, and the checks."""
    from ..lattice import LatticeSimulation, LatticeSimulation3D
    cls = LatticeSimulation3D if dim == 3 else LatticeSimulation
    d = binary_diameters(n, ratio)
    sim = cls.random(n, phi=phi, diameters=d, seed=seed)
    x0 = sim.lattice_positions.copy()
    t0 = time.perf_counter()
    sim.run(collisions=int(equilibrate * n))
    # blocks of equal time: the rate from the equilibration
    rate = sim.collisions / max(sim.time, 1e-300)
    sim.observe(block_time=collisions * n / rate / blocks)
    sim.run(collisions=int(collisions * n))
    obs = sim.observation()
    sim.run_back()
    seconds = time.perf_counter() - t0
    z, ze = obs.compressibility.value, obs.compressibility.error
    theory = bmcsl_z(phi, sim.diameters) if dim == 3 else slhy_z(phi, sim.diameters)
    out = {"dim": dim, "n": n, "phi": phi, "ratio": ratio, "seed": seed, "equilibrate_per_particle": equilibrate,
           "collisions_per_particle": collisions, "z": z, "z_error": ze, "blocks": obs.blocks,
           "theory": "BMCSL" if dim == 3 else "SLHY (Liu)", "z_theory": theory,
           "deviation_sd": (z - theory) / ze if ze > 0 else float("inf"),
           "back_to_start": bool((sim.lattice_positions == x0).all()), "seconds": seconds}
    if dim == 2:
        out["z_slhy_henderson"] = slhy_z(phi, sim.diameters, henderson)
    return out


def compare(dim: int, n: int, phi: float, ratio: float, **kw) -> dict:
    """The mixture (``measure``) and the one-size gas at the same N, phi and seed, and the
    ratio of their Z against the theory's (module docstring)."""
    mix = measure(dim, n, phi, ratio, **kw)
    pure = measure(dim, n, phi, 1.0, **kw)
    pure_theory = liu_spheres(phi) if dim == 3 else liu_disks(phi)
    pure_base = carnahan_starling(phi) if dim == 3 else liu_disks(phi)  # what the mixture theory reduces to
    r = mix["z"] / pure["z"]
    re = r * math.hypot(mix["z_error"] / mix["z"], pure["z_error"] / pure["z"])
    r_theory = mix["z_theory"] / pure_base
    return {"mixture": mix, "pure": pure, "pure_theory": "Liu (spheres)" if dim == 3 else "Liu (disks)",
            "z_pure_theory": pure_theory, "pure_deviation_sd": (pure["z"] - pure_theory) / pure["z_error"],
            "z_pure_cs": carnahan_starling(phi) if dim == 3 else None,
            "ratio": r, "ratio_error": re, "ratio_theory": r_theory, "ratio_deviation_sd": (r - r_theory) / re}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--n", type=int, default=4000)
    p.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    p.add_argument("--collisions", type=float, default=400.0, help="observed collisions per particle")
    p.add_argument("--json", default=None)
    a = p.parse_args(argv)
    runs = []
    for seed in a.seeds:
        for dim, phi in ((2, 0.5), (3, 0.4)):
            c = compare(dim, a.n, phi, 1.4, collisions=a.collisions, seed=seed)
            r, q = c["mixture"], c["pure"]
            print(f"{dim}D phi {phi} seed {seed}: Z = {r['z']:.4f} +- {r['z_error']:.4f}, {r['theory']} "
                  f"{r['z_theory']:.4f} ({r['deviation_sd']:+.1f} sd); one size {q['z']:.4f} +- {q['z_error']:.4f}, "
                  f"{c['pure_theory']} {c['z_pure_theory']:.4f} ({c['pure_deviation_sd']:+.1f} sd); ratio "
                  f"{c['ratio']:.5f} +- {c['ratio_error']:.5f} against {c['ratio_theory']:.5f} "
                  f"({c['ratio_deviation_sd']:+.1f} sd); back to start {r['back_to_start'] and q['back_to_start']}",
                  flush=True)
            runs.append(c)
    if a.json:
        from .._io import atomic_open
        with atomic_open(a.json) as f:
            json.dump({"study": "mixture_eos", "command": "python -m revcol.studies.mixture_eos " + " ".join(argv or []),
                       "runs": runs}, f, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
