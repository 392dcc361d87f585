"""Event-chain Monte Carlo: the equilibrium pressure of hard spheres at the engine's own N.

The engine's collision laws are tested against equilibrium. Equations of state (Liu's fits,
Henderson, Carnahan-Starling) describe the infinite fluid and are good to about 0.05-0.1%;
a run of 10^8 collisions measures Z to 0.005%. This module measures the reference itself:
``EventChain`` (C++, revcol/studies/ecmc.hpp) samples the uniform measure over non-overlapping
configurations of N spheres in the periodic box of the engine's random start, which is the
configurational equilibrium of hard spheres, by event-chain Monte Carlo (Bernard, Krauth and
Wilson 2009), a different algorithm from the event-driven engine. Its pressure estimator

    beta P V / N = 1 + < sum of the lifts' projections dx > / chain length

is exact at finite N (Michel, Kapfer and Krauth 2014); the C++ tests check it against Tonks'
gas and two spheres in a box, whose finite-N pressures are known in closed form.

The engine's observer reports Z_md = 1 + W / (sum m v^2), with the kinetic temperature over
d N degrees of freedom; at zero total momentum the contacts that give Z_mc - 1 give

    Z_md - 1 = (Z_mc - 1) N / (N - 1)                     (md_equivalent)

exactly, so an engine run and a chain run of the same N and box can be compared with no
extrapolation and no equation of state. Example::

    >>> from revcol.studies.ecmc import sample
    >>> r = sample(2, 0.3, n=100, seed=1, per_particle=50, blocks=8)   # doctest: +SKIP
    >>> r["z_md"]                                                       # [value, error]
"""
from __future__ import annotations

import math
import time
from typing import Any, Optional

import numpy as np

from .. import _core
from .._core import EventChain
from .eos import extrapolate, reference_z

__all__ = ["EventChain", "md_equivalent", "mc_equivalent", "start", "default_chain_length", "sample"]


def md_equivalent(z_mc: float, n: int) -> float:
    """The engine's Z (temperature over d N degrees of freedom, zero momentum) that a chain
    run's Z_mc = beta P V / N of the same N predicts: 1 + (Z_mc - 1) N / (N - 1)."""
    if n < 2:
        raise ValueError(f"md_equivalent needs n >= 2, got {n}")
    return 1.0 + (z_mc - 1.0) * n / (n - 1.0)


def mc_equivalent(z_md: float, n: int) -> float:
    """The inverse of md_equivalent: 1 + (Z_md - 1) (N - 1) / N."""
    if n < 2:
        raise ValueError(f"mc_equivalent needs n >= 2, got {n}")
    return 1.0 + (z_md - 1.0) * (n - 1.0) / n


def start(dim: int, phi: float, n: int, seed: int, diameter: float = 1.0) -> EventChain:
    """A sampler from the engine's random start (``Simulation.random(n, dim, phi, seed=seed,
    boundary="periodic")``'s positions and cubic box), chains keyed by the same seed."""
    x, _v, box = _core.engine_random_state(dim, n, phi, ["periodic"], diameter, seed, 0.0, "auto", False)
    return EventChain(list(np.asarray(box, dtype=float)), x, diameter=diameter, seed=seed)


def default_chain_length(dim: int, phi: float, diameter: float = 1.0) -> float:
    """A chain length that gives about 100 lifts per chain: 100 times the mean free
    displacement of an active sphere, 1 / lift rate, with the lift rate from Liu's Z. Any length
    samples the same equilibrium; this one was the cheapest per unit error in 2D at 0.6."""
    z = reference_z(dim, phi)
    # Z - 1 = lift rate x <dx>; <dx> ~ D pi/4 (2D), 2D/3 (3D), D (1D)
    mean_dx = {1: 1.0, 2: math.pi / 4, 3: 2.0 / 3.0}[dim] * diameter
    rate = max(z - 1.0, 1e-3) / mean_dx
    return 100.0 / rate


def sample(dim: int, phi: float, n: int = 1000, seed: int = 1, per_particle: float = 2000.0, blocks: int = 32,
           warmup: float = 200.0, chain_length: Optional[float] = None, sampler: Optional[EventChain] = None
           ) -> dict[str, Any]:
    """Z of N hard spheres at packing fraction ``phi`` in the engine's periodic cube, by event
    chains from the engine's random start at ``seed``: ``warmup`` diameters of chain
    displacement per sphere, then ``per_particle`` observed in ``blocks`` blocks. Returns Z_mc
    (beta P V / N) and Z_md (md_equivalent) as [value, block error], the lifts, the CPU
    seconds and the minimum pair distance at the end (>= 1 - 1e-9: no overlap)."""
    if blocks < 2:
        raise ValueError(f"blocks must be at least 2, got {blocks}")
    if not (per_particle > 0 and warmup >= 0):
        raise ValueError(f"per_particle must be positive and warmup non-negative, got {per_particle}, {warmup}")
    s = sampler if sampler is not None else start(dim, phi, n, seed)
    ell = chain_length if chain_length is not None else default_chain_length(dim, phi)
    tick = time.process_time()
    if warmup > 0:
        s.run(max(1, round(warmup * n / ell)), ell)
    per_block = max(1, round(per_particle * n / ell / blocks))
    zs, lifts = [], 0
    for _ in range(blocks):
        r = s.run(per_block, ell)
        zs.append(r["z"])
        lifts += r["lifts"]
    cpu = time.process_time() - tick
    z = np.asarray(zs)
    err = float(z.std(ddof=1) / math.sqrt(len(z)))
    zm = float(z.mean())
    return {"dim": dim, "phi": phi, "n": n, "seed": seed, "chain_length": ell, "chains_per_block": per_block,
            "blocks": blocks, "per_particle": per_particle, "warmup": warmup, "lifts": lifts, "cpu_s": cpu,
            "z_mc": [zm, err], "z_md": [md_equivalent(zm, n), err * n / (n - 1.0)],
            "block_z": z.tolist(), "min_distance": s.min_distance()}


# ---- the study: chain runs at the engine's N, and the comparison with engine runs ----------

def summarize(runs: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per (dim, phi, n): the mean Z_mc of the seeds with the larger of two errors, the one
    from their spread (k >= 3 runs) and the one their blocks claim (so neither a spread that
    happens to be small nor blocks that slow modes outlive make it too small), the scatter
    ratio (spread over rms block error, about 1 when the blocks are honest), Z_md
    (md_equivalent) and Liu's Z for the infinite fluid."""
    groups: dict[tuple, list[dict]] = {}
    for r in runs:
        groups.setdefault((r["dim"], r["phi"], r["n"]), []).append(r)
    out = []
    for (d, phi, n), rs in sorted(groups.items()):
        z = np.array([r["z_mc"][0] for r in rs])
        be = np.array([r["z_mc"][1] for r in rs])
        k = len(rs)
        block_err = float(math.sqrt((be ** 2).sum()) / k)
        sd = float(z.std(ddof=1)) if k >= 2 else float("nan")
        spread_err = sd / math.sqrt(k) if k >= 2 else float("nan")
        err = max(spread_err, block_err) if k >= 3 else block_err
        zm = float(z.mean())
        out.append({"dim": d, "phi": phi, "n": n, "runs": k, "z_mc": [zm, err], "z_mc_block_error": block_err,
                    "z_mc_spread_error": spread_err,
                    "scatter_ratio": sd / float(np.sqrt((be ** 2).mean())) if k >= 2 else float("nan"),
                    "z_md": [md_equivalent(zm, n), err * n / (n - 1.0)], "z_ref_liu": reference_z(d, phi),
                    "lifts": int(sum(r["lifts"] for r in rs)), "cpu_s": float(sum(r["cpu_s"] for r in rs)),
                    "min_distance": float(min(r["min_distance"] for r in rs))})
    return out


def summary_table(rows: list[dict[str, Any]]) -> str:
    """``summarize`` as a markdown table."""
    out = ["| d | phi | N | runs | Z_mc = beta P V / N | scatter ratio | Z_md equivalent | Liu (N = inf) | lifts | CPU s |",
           "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        out.append(f"| {r['dim']} | {r['phi']:.2f} | {r['n']} | {r['runs']} | {r['z_mc'][0]:.5f} +- {r['z_mc'][1]:.5f} | "
                   f"{r['scatter_ratio']:.2f} | {r['z_md'][0]:.5f} +- {r['z_md'][1]:.5f} | {r['z_ref_liu']:.5f} | "
                   f"{r['lifts']:.3g} | {r['cpu_s']:.0f} |")
    return "\n".join(out)


def md_estimates(doc: dict[str, Any]) -> list[dict[str, Any]]:
    """The engine's Z per (dim, phi, n, law) from a JSON file of ``python -m revcol.studies.equilibrium
    dense`` (one run each, block error) or of ``python -m revcol.studies.eos_replicas`` (the mean of the
    replicas with the error from their spread)."""
    out = []
    if "dense" in doc:
        for r in doc["dense"]:
            out.append({"dim": r["dim"], "phi": r["phi"], "n": r["n"], "law": r["law"], "z": list(r["z"]),
                        "source": "dense (1 run, block error)"})
    elif "summary" in doc and "runs" in doc:
        for law, s in doc["summary"].items():
            if " - " in law:
                continue
            out.append({"dim": doc["dim"], "phi": doc["phi"], "n": doc["n"], "law": law,
                        "z": [s["mean"], s["error_from_spread"]], "source": f"replicas ({s['runs']} runs, spread)"})
    else:
        raise ValueError("not a dense study or replicas JSON: it has neither 'dense' nor 'summary' and 'runs'")
    return out


def compare(mc_rows: list[dict[str, Any]], md_rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Each engine estimate against the chain runs of the same (dim, phi, n): Z_md - Z_md
    equivalent of the chains, in combined standard errors (no equation of state, no
    extrapolation)."""
    by_key = {(r["dim"], round(r["phi"], 9), r["n"]): r for r in mc_rows}
    out = []
    for m in md_rows:
        c = by_key.get((m["dim"], round(m["phi"], 9), m["n"]))
        if c is None:
            continue
        diff = m["z"][0] - c["z_md"][0]
        err = math.hypot(m["z"][1], c["z_md"][1])
        out.append({**m, "z_md_from_mc": c["z_md"], "difference": diff, "error": err, "sigmas": diff / err,
                    "relative": diff / c["z_md"][0]})
    return out


def compare_table(rows: list[dict[str, Any]]) -> str:
    """``compare`` as a markdown table."""
    out = ["| d | phi | N | law | engine Z_md | event chains: Z_md equivalent | difference | sd | source |",
           "|---|---|---|---|---|---|---|---|---|"]
    for r in sorted(rows, key=lambda r: (r["dim"], r["phi"], r["n"], r["law"])):
        out.append(f"| {r['dim']} | {r['phi']:.2f} | {r['n']} | {r['law']} | {r['z'][0]:.5f} +- {r['z'][1]:.5f} | "
                   f"{r['z_md_from_mc'][0]:.5f} +- {r['z_md_from_mc'][1]:.5f} | {100 * r['relative']:+.3f}% | "
                   f"{r['sigmas']:+.1f} | {r['source']} |")
    return "\n".join(out)


def infinite_size(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Z_mc(N) = Z(inf) + a / N through the chain summaries at two or more sizes per (dim,
    phi), against Liu's form: the equation of state of the infinite fluid from the chains."""
    groups: dict[tuple, list[dict]] = {}
    for r in rows:
        groups.setdefault((r["dim"], r["phi"]), []).append(r)
    out = []
    for (d, phi), rs in sorted(groups.items()):
        if len({r["n"] for r in rs}) < 2:
            continue
        rs = sorted(rs, key=lambda r: r["n"])
        zi, ei, a = extrapolate([r["n"] for r in rs], [r["z_mc"][0] for r in rs], [r["z_mc"][1] for r in rs])
        x = 1.0 / np.array([r["n"] for r in rs], dtype=float)
        resid = (np.array([r["z_mc"][0] for r in rs]) - (zi + a * x)) / np.array([r["z_mc"][1] for r in rs])
        ref = reference_z(d, phi)
        out.append({"dim": d, "phi": phi, "n": [r["n"] for r in rs], "z_inf": [zi, ei], "slope": a,
                    "chi2": float((resid ** 2).sum()), "dof": len(rs) - 2, "z_ref_liu": ref,
                    "liu_sigmas": (ref - zi) / ei, "liu_relative": (ref - zi) / zi})
    return out
