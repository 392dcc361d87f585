"""The equilibrium study (issue 16): does a collision law keep a hard-sphere gas in equilibrium?

(a) Two particles (disks or spheres, diameter D = 1) in a small closed box with specular
walls, whose equilibrium is known exactly: configurations uniform over the non-overlapping
ones, velocities uniform on the energy shell. Measured (time-weighted, ``revcol.observe``)
against the exact values: the time fraction near contact (|r| < 1.01 D), the collision rate
(:func:`exact_pair`), the distance distribution and the one-particle density along x (both
against a Monte Carlo of uniform non-overlapping configurations, :func:`monte_carlo`).

(b) Dense gases (N >= 1000, periodic): the compressibility factor Z from the collision
virial against Liu's equations of state (2D, 3D; Henderson's and Carnahan-Starling's beside them), the contact
value g(sigma) = (Z - 1) / (2^(d-1) phi) it implies, the collision rate against Enskog's
with that g(sigma), the speeds against the Maxwell-Boltzmann law (chi^2 of the time-weighted
histogram), and the temperature across slabs.

(c) The same N without dynamics: event-chain Monte Carlo (:mod:`revcol.studies.ecmc`) samples the
equilibrium of the engine's own N and box and gives its pressure exactly at that N, so the
engine's Z is tested with no equation of state and no extrapolation (``mc``, ``mc-compare``).

Every law runs from the same start: ``flux`` (the default), ``specular`` (deterministic
reflection: the textbook hard-sphere gas), ``uniform`` and ``paper`` (2D). docs/physics.md has
the derivations, the tables and the figures.

    python -m revcol.studies.equilibrium small --collisions 4000000 --json bench/results/equilibrium_small.json
    python -m revcol.studies.equilibrium dense --dim 2 --phi 0.3 0.5 0.6 0.7 --json bench/results/equilibrium_dense2d.json
    python -m revcol.studies.equilibrium walls --dim 2 --phi 0.5 --json bench/results/equilibrium_walls2d.json
    python -m revcol.studies.equilibrium mc --dim 2 --phi 0.6 --n 1000 --seeds 8 --per-particle 20000 --json bench/results/ecmc_2d_phi0.6_n1000.json
    python -m revcol.studies.equilibrium mc-compare --mc bench/results/ecmc_[23]d_*.json --md bench/results/eos_replicas_2d_phi0.6_n1000.json
    python -m revcol.studies.equilibrium figures --out docs/figures/physics bench/results/equilibrium_*.json
    revcol study equilibrium ...   (the same)
"""
from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import time
from typing import Any, Optional, Sequence

import numpy as np

from .._io import atomic_open
from ..engine import Simulation
from ..observe import radial_distribution
from . import ecmc
from .eos import (carnahan_starling, classic_z, contact_value, enskog_rate, extrapolate, henderson,  # noqa: F401 (__all__)
                  liu_disks, liu_spheres, maxwell_speed_density, microcanonical_speed_density, reference_z)
from .equilibrium_figures import figures

__all__ = ["LAWS", "exact_pair", "monte_carlo", "two_body", "small_study", "henderson", "carnahan_starling",
           "liu_disks", "liu_spheres", "reference_z", "classic_z",
           "enskog_rate", "maxwell_speed_density", "microcanonical_speed_density", "speed_check", "dense", "walled",
           "main"]

#: the laws compared: name -> Simulation keywords
LAWS = {"flux": {"mode": "exact", "law": "flux"}, "specular": {"mode": "specular"},
        "uniform": {"mode": "exact", "law": "uniform"}, "paper": {"mode": "paper"}}
#: near contact: |r| < D (1 + NEAR)
NEAR = 0.01
#: pair-distance bins per diameter: one bin is [D, D (1 + NEAR)), so its block error is the
#: near-contact fraction's
BINS_PER_D = 100


# ---- (a) two particles in a closed box: the exact answers -------------------------------

def _excluded(d: int, ell: float, s: float) -> float:
    """The integral of prod_k (ell - |r_k|) over |r| < s (s <= ell): the weight of the pair
    separations r closer than s, x1 and x2 uniform in a cube of side ell (the centres' box)."""
    if d == 2:
        return math.pi * s**2 * ell**2 - 8.0 / 3.0 * ell * s**3 + s**4 / 2.0
    return (4.0 / 3.0 * math.pi * s**3 * ell**3 - 1.5 * math.pi * s**4 * ell**2 + 1.6 * s**5 * ell - s**6 / 6.0)


def _shell(d: int, ell: float, s: float) -> float:
    """d/ds of _excluded: the weight of the separations at distance s (s <= ell)."""
    if d == 2:
        return s * (2.0 * math.pi * ell**2 - 8.0 * ell * s + 2.0 * s**2)
    return 4.0 * math.pi * s**2 * ell**3 - 6.0 * math.pi * s**3 * ell**2 + 8.0 * s**4 * ell - s**5


def exact_pair(d: int, box: float, energy: float, diameter: float = 1.0) -> dict[str, float]:
    """The exact equilibrium of two particles in a closed cube of side ``box`` (specular walls):
    centres uniform in the cube of side ell = box - D, not overlapping; velocities uniform on
    the shell |v1|^2 + |v2|^2 = 2 ``energy`` (walls keep no momentum). Needs D + NEAR D <= ell.

    Returns the contact density p(D) of the distance |r|, the fraction of time with |r| <
    D (1 + NEAR), the mean inward normal speed E[(w.n)^-] at contact and the pair collision
    rate p(D) E[(w.n)^-] (docs/physics.md derives it)."""
    ell = box - diameter
    s1 = diameter * (1.0 + NEAR)
    if not s1 <= ell:
        raise ValueError(f"the exact formulas need D (1 + {NEAR}) <= box - D, got box {box}")
    z = ell ** (2 * d) - _excluded(d, ell, diameter)  # the configurations' volume
    p_contact = _shell(d, ell, diameter) / z
    near = (_excluded(d, ell, s1) - _excluded(d, ell, diameter)) / z
    m = 2 * d  # the velocity sphere's dimension; radius sqrt(2 E)
    mean_abs = math.exp(math.lgamma(m / 2) - math.lgamma((m + 1) / 2)) / math.sqrt(math.pi)  # E|u_1| on S^(m-1)
    inward = math.sqrt(2.0) * math.sqrt(2.0 * energy) * 0.5 * mean_abs
    return {"contact_density": p_contact, "near_contact": near, "inward_speed": inward,
            "collision_rate": p_contact * inward}


def monte_carlo(d: int, box: float, samples: int, seed: int = 1, diameter: float = 1.0,
                slabs: int = 25) -> dict[str, Any]:
    """Uniform non-overlapping configurations of two particles (centres in [D/2, box - D/2]^d):
    the fraction near contact, the distance histogram (BINS_PER_D bins per D over [0, box
    sqrt(d)]) and the one-particle density along x (``slabs`` over [0, box], as number
    density of both particles), each with its binomial standard error."""
    rng = np.random.default_rng(seed)
    r_max = box * math.sqrt(d)
    nb = int(round(r_max * BINS_PER_D / diameter))
    h = diameter / BINS_PER_D
    dist = np.zeros(nb)
    xs = np.zeros(slabs)
    kept = 0
    lo, hi = diameter / 2, box - diameter / 2
    for _ in range(0, samples, 1_000_000):
        a = rng.uniform(lo, hi, (1_000_000, d))
        b = rng.uniform(lo, hi, (1_000_000, d))
        r = np.sqrt(((a - b) ** 2).sum(1))
        ok = r >= diameter
        kept += int(ok.sum())
        dist += np.bincount(np.minimum((r[ok] / h).astype(int), nb - 1), minlength=nb)
        for c in (a[ok, 0], b[ok, 0]):
            xs += np.bincount(np.minimum((c / box * slabs).astype(int), slabs - 1), minlength=slabs)
    near = dist[BINS_PER_D] / kept
    vol = box**d / slabs
    return {"samples": kept, "near_contact": near, "near_contact_error": math.sqrt(near * (1 - near) / kept),
            "distance_edges": (np.arange(nb + 1) * h).tolist(),
            "distance": (dist / (kept * h)).tolist(), "distance_error": (np.sqrt(dist) / (kept * h)).tolist(),
            "slab_density": (xs / kept / vol).tolist(), "slab_density_error": (np.sqrt(xs) / kept / vol).tolist()}


def two_body(d: int, box: float, law: str, collisions: int, seed: int = 1, slabs: int = 25) -> dict[str, Any]:
    """Two particles (D = 1) in a closed cube of side ``box`` under ``law`` (a key of LAWS),
    ``collisions`` pair collisions after 1000 to forget the start, observed: near-contact time
    fraction, collision rate, distance histogram, slab density, each with block errors."""
    c = box / 2
    x = np.array([[c - 0.6] * d, [c + 0.6] * d]) + np.array([[0.0] * d, [0.05] + [0.0] * (d - 1)])
    v = np.random.default_rng(seed).normal(size=(2, d))
    sim = Simulation(x, v, [box] * d, boundary="wall", seed=seed, **LAWS[law])
    sim.run(collisions=1000)
    r_max = box * math.sqrt(d)
    nb = int(round(r_max * BINS_PER_D))
    sim.observe(pair_bins=nb, pair_rmax=nb / BINS_PER_D, slabs=slabs, min_blocks=32)
    tick = time.process_time()
    sim.run(collisions=collisions)
    cpu = time.process_time() - tick
    o = sim.observation()
    h = 1.0 / BINS_PER_D
    raw = o.pair_distance
    near = [float(raw.value[BINS_PER_D] * h), float(raw.error[BINS_PER_D] * h)]
    energy = float(sim.diagnostics()["energy"])
    return {"law": law, "dim": d, "box": box, "collisions": collisions, "seed": seed, "cpu_s": cpu,
            "energy": energy, "time": o.duration, "blocks": o.blocks,
            "collision_rate": [o.collision_rate.value, o.collision_rate.error],
            "near_contact": near,
            "distance": raw.value.tolist(), "distance_error": raw.error.tolist(),
            "slab_density": o.slab_density.value.tolist(), "slab_density_error": o.slab_density.error.tolist()}


def small_study(collisions: int = 4_000_000, box: float = 2.5, seed: int = 1, mc_samples: int = 20_000_000,
                dims: Sequence[int] = (2, 3), laws: Optional[Sequence[str]] = None) -> dict[str, Any]:
    """(a) for each dimension and law: the two-particle run against the exact values and the
    Monte Carlo; each statistic with its number of standard errors (``sigmas``) and its
    relative deviation. The distance distribution and the slab density are summarized by
    chi^2 per bin against the Monte Carlo (both errors) and the largest |z| of a bin."""
    out: dict[str, Any] = {"box": box, "collisions": collisions, "seed": seed, "near": NEAR, "runs": []}
    for d in dims:
        mc = monte_carlo(d, box, mc_samples, seed=seed)
        out[f"mc_{d}d"] = mc
        for law in laws or [k for k in LAWS if d == 2 or k != "paper"]:
            r = two_body(d, box, law, collisions, seed=seed)
            ex = exact_pair(d, box, r["energy"])
            r["exact"] = ex
            for key in ("collision_rate", "near_contact"):
                v, e = r[key]
                r[key + "_sigmas"] = (v - ex[key]) / e
                r[key + "_rel"] = v / ex[key] - 1.0
            for key in ("distance", "slab_density"):
                a, ea = np.asarray(r[key]), np.asarray(r[key + "_error"])
                b, eb = np.asarray(mc[key]), np.asarray(mc[key + "_error"])
                n = min(a.size, b.size)
                a, ea, b, eb = a[:n], ea[:n], b[:n], eb[:n]
                use = (ea > 0) & (eb > 0)
                z = (a[use] - b[use]) / np.sqrt(ea[use] ** 2 + eb[use] ** 2)
                r[key + "_chi2_per_bin"] = float((z * z).mean())
                r[key + "_max_z"] = float(np.abs(z).max())
                r[key + "_bins"] = int(use.sum())
            out["runs"].append(r)
            print(f"  {d}D {law:9s} rate {r['collision_rate_rel']:+.4f} ({r['collision_rate_sigmas']:+.1f} sd)  "
                  f"near {r['near_contact_rel']:+.4f} ({r['near_contact_sigmas']:+.1f} sd)  "
                  f"chi2/bin {r['distance_chi2_per_bin']:.2f} {r['slab_density_chi2_per_bin']:.2f}  "
                  f"{r['cpu_s']:.0f} s", file=sys.stderr)
    return out


# ---- (b) dense gases -------------------------------------------------------------------


#: a speed bin enters the resolved chi^2 when each block draws at least this many new speeds
#: in it (2 per collision, by the reference law): its block error is then an estimate, not
#: the noise of a few visits
RESOLVED_VISITS = 25.0


def speed_check(r: dict[str, Any]) -> dict[str, float]:
    """A dense run's time-weighted speed histogram against the bin averages of the exact
    finite-n law (microcanonical, momentum 0) and of Maxwell-Boltzmann: chi^2 per bin and the
    largest |z| of a bin (block errors)."""
    c = np.asarray(r["speed_centres"])
    h = c[1] - c[0]
    val, err = np.asarray(r["speed"]), np.asarray(r["speed_error"])
    T, d, n = r["temperature"][0], r["dim"], r["n"]
    u = np.linspace(-0.5, 0.5, 33)
    use = err > 0
    resolved = None  # the bins of the resolved chi^2, chosen once by the exact law
    out = {}
    for name, law in (("microcanonical", lambda x: microcanonical_speed_density(d, n, x, T)),
                      ("maxwell", lambda x: maxwell_speed_density(d, x, T))):
        ref = np.array([np.trapezoid(law(ci + h * u), u) for ci in c])  # bin averages
        z = (val[use] - ref[use]) / err[use]
        out[f"speed_chi2_{name}"] = float((z * z).mean())
        out[f"speed_max_z_{name}"] = float(np.abs(z).max())
        # the same over the bins that every block visits often: a bin the blocks reach a few
        # times at most (the far tail) has a block error that is itself noise, and its z can
        # reach 35 in a run whose tail is right on average (tests/python/test_physics.py)
        if resolved is None:
            visits = ref[use] * h * 2.0 * r["collisions"] / max(r["blocks"], 1)  # new speeds per block
            resolved = visits >= RESOLVED_VISITS
            out["speed_bins_resolved"] = int(resolved.sum())
        zr = z[resolved]
        out[f"speed_chi2_{name}_resolved"] = float((zr * zr).mean()) if zr.size else float("nan")
    return out


def dense(d: int, phi: float, law: str, n: int = 1000, per_particle: float = 2000.0, seed: int = 1,
          frames: int = 40, speed_bins: int = 40, slabs: int = 8) -> dict[str, Any]:
    """(b) one dense gas: N particles at packing fraction ``phi`` in a periodic box under
    ``law``, 200 collisions per particle to equilibrate, then ``per_particle`` observed; Z,
    collision rate, speeds and slab temperatures with block errors, g(r) from ``frames``
    frames (numpy or freud) and its contact value by a quadratic fit of the first bins."""
    sim = Simulation.random(n=n, dim=d, phi=phi, seed=seed, boundary="periodic", **LAWS[law])
    sim.run(collisions=int(100 * n))
    T = float(sim.diagnostics()["energy"]) * 2.0 / (d * n)
    sim.observe(speed_bins=speed_bins, speed_max=5.0 * math.sqrt(T), slabs=slabs)
    total = int(per_particle * n / 2)
    # frames at times independent of the events (a frame taken right after a collision has
    # one pair exactly at contact and biases g(sigma+) upward): the equilibration's collision
    # rate sets a time step of about total / frames collisions
    rate = float(sim.diagnostics()["net_collisions"]) / max(float(sim.time), 1e-300)
    dt = total / frames / rate
    tick = time.process_time()
    shots = []
    for k in range(frames):
        sim.run(time=sim.time + dt)
        shots.append(sim.positions)
    cpu = time.process_time() - tick
    o = sim.observation()
    r, g = radial_distribution(shots, sim.box, bins=150, r_max=min(3.0, 0.5 * float(sim.box.min())))
    z_ref = reference_z(d, phi)
    g_ref = contact_value(d, phi, z_ref)
    rate_ref = enskog_rate(d, phi, o.temperature.value, g_ref)
    # g(sigma+) from frames: a quadratic through the first bins above contact, at r = 1
    near = (r > 1.0) & (r < 1.15)
    g_frames = float(np.polyval(np.polyfit(r[near] - 1.0, g[near], 2), 0.0)) if near.sum() >= 3 else float("nan")
    sp = o.speed
    st = o.slab_temperature
    tz = (st.value - o.temperature.value) / st.error
    res = {"dim": d, "phi": phi, "law": law, "n": n, "seed": seed, "collisions": total, "cpu_s": cpu,
           "blocks": o.blocks, "temperature": [o.temperature.value, o.temperature.error],
           "z": [o.compressibility.value, o.compressibility.error], "z_ref": z_ref,
           "z_sigmas": (o.compressibility.value - z_ref) / o.compressibility.error,
           "g_contact": [contact_value(d, phi, o.compressibility.value),
                         o.compressibility.error / (2 ** (d - 1) * phi)],
           "g_contact_ref": g_ref, "g_contact_frames": g_frames,
           "collision_rate": [o.collision_rate.value, o.collision_rate.error], "collision_rate_ref": rate_ref,
           "collision_rate_sigmas": (o.collision_rate.value - rate_ref) / o.collision_rate.error,
           "speed_centres": sp.centres.tolist(), "speed": sp.value.tolist(), "speed_error": sp.error.tolist(),
           "slab_temperature": st.value.tolist(), "slab_temperature_error": st.error.tolist(),
           "slab_temperature_max_z": float(np.abs(tz).max()),
           "g_r": [r.tolist(), g.tolist()], "mean_free_path": [o.mean_free_path.value, o.mean_free_path.error]}
    res.update(speed_check(res))
    print(f"  {d}D phi {phi:.2f} {law:9s} Z {o.compressibility.value:.4f}+-{o.compressibility.error:.4f} "
          f"(ref {z_ref:.4f}, {res['z_sigmas']:+.1f} sd)  rate {res['collision_rate_sigmas']:+.1f} sd  "
          f"speeds chi2/bin {res['speed_chi2_microcanonical']:.2f}  slabs max|z| {res['slab_temperature_max_z']:.1f}  "
          f"{cpu:.0f} s", file=sys.stderr)
    return res


def walled(d: int, phi: float, law: str, n: int = 1000, per_particle: float = 2000.0, seed: int = 1,
           slabs: int = 10) -> dict[str, Any]:
    """(b) in a closed box (specular walls on every axis): the temperature and the density in
    ``slabs`` slabs along x, and the pressure on each pair of faces, with block errors."""
    sim = Simulation.random(n=n, dim=d, phi=phi, seed=seed, boundary="wall", **LAWS[law])
    sim.run(collisions=int(100 * n))
    sim.observe(slabs=slabs)
    tick = time.process_time()
    sim.run(collisions=int(per_particle * n / 2))
    cpu = time.process_time() - tick
    o = sim.observation()
    st, sd = o.slab_temperature, o.slab_density
    tz = (st.value - o.temperature.value) / st.error
    pw = [[e.value, e.error] for e in o.pressure_wall]
    res = {"dim": d, "phi": phi, "law": law, "n": n, "seed": seed, "cpu_s": cpu, "box": sim.box.tolist(),
           "blocks": o.blocks, "temperature": [o.temperature.value, o.temperature.error],
           "slab_edges": st.edges.tolist(), "slab_temperature": st.value.tolist(),
           "slab_temperature_error": st.error.tolist(), "slab_temperature_max_z": float(np.abs(tz).max()),
           "slab_temperature_chi2_per_slab": float((tz * tz).mean()),
           "slab_density": sd.value.tolist(), "slab_density_error": sd.error.tolist(), "pressure_wall": pw,
           "virial_balance": [o.virial_balance.value, o.virial_balance.error]}
    print(f"  walls {d}D phi {phi:.2f} {law:9s} slab T max|z| {res['slab_temperature_max_z']:.1f}  P_wall "
          + " ".join(_pm(*p) for p in pw) + f"  {cpu:.0f} s", file=sys.stderr)
    return res


def walls_table(runs: Sequence[dict]) -> str:
    """The closed boxes as a markdown table."""
    rows = ["| d | phi | law | T | slab T: chi2 per slab (max abs z) | slab T range (%) | P on x faces | "
            "P on y faces | (P_x - P_y) / error | P_x - P_x(specular) in sd |", "|---|---|---|---|---|---|---|---|---|---|"]
    spec = {(r["dim"], r["phi"]): r for r in runs if r["law"] == "specular"}
    for r in runs:
        (px, ex), (py, ey) = r["pressure_wall"][0], r["pressure_wall"][1]
        t = np.asarray(r["slab_temperature"]) / r["temperature"][0] - 1.0
        s = spec.get((r["dim"], r["phi"]))
        vs = "" if s is None or s is r else \
            f"{(px - s['pressure_wall'][0][0]) / math.hypot(ex, s['pressure_wall'][0][1]):+.1f}"
        rows.append(f"| {r['dim']} | {r['phi']:.2f} | {r['law']} | {_pm(*r['temperature'])} | "
                    f"{r['slab_temperature_chi2_per_slab']:.2f} ({r['slab_temperature_max_z']:.1f}) | "
                    f"{100 * t.min():+.2f} .. {100 * t.max():+.2f} | {_pm(px, ex)} | {_pm(py, ey)} | "
                    f"{(px - py) / math.hypot(ex, ey):+.1f} | {vs} |")
    return "\n".join(rows)


# ---- tables, figures, command line -------------------------------------------------------

def _pm(v: float, e: float) -> str:
    return f"{v:.5g} +- {e:.2g}"


def small_table(study: dict) -> str:
    """(a) as a markdown table: per dimension and law, value +- error, exact, sigmas, deviation."""
    rows = ["| system | law | collision rate | exact | sd | deviation | time near contact | exact | sd | deviation "
            "| distances chi2/bin (max abs z) | x density chi2/bin (max abs z) |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in study["runs"]:
        ex = r["exact"]
        name = "two disks" if r["dim"] == 2 else "two spheres"
        rows.append(f"| {name} | {r['law']} | {_pm(*r['collision_rate'])} | {ex['collision_rate']:.5g} | "
                    f"{r['collision_rate_sigmas']:+.1f} | {100 * r['collision_rate_rel']:+.2f}% | "
                    f"{_pm(*r['near_contact'])} | {ex['near_contact']:.5g} | {r['near_contact_sigmas']:+.1f} | "
                    f"{100 * r['near_contact_rel']:+.2f}% | {r['distance_chi2_per_bin']:.2f} "
                    f"({r['distance_max_z']:.1f}) | {r['slab_density_chi2_per_bin']:.2f} ({r['slab_density_max_z']:.1f}) |")
    return "\n".join(rows)


def dense_table(runs: Sequence[dict]) -> str:
    """(b) as a markdown table."""
    rows = ["| d | phi | law | Z | EOS (Liu) | sd (%) | Henderson / CS: sd | Z - Z(specular) in sd | g(sigma) "
            "| collision rate | Enskog (EOS) | sd "
            "| rate / Enskog (own Z): sd | speeds chi2/bin: exact finite N (Maxwell) | slab T max abs z |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    spec = {(r["dim"], r["phi"]): r for r in runs if r["law"] == "specular"}
    for r in runs:
        r = {**r, **speed_check(r)}
        s = spec.get((r["dim"], r["phi"]))
        vs = "" if s is None or s is r else f"{(r['z'][0] - s['z'][0]) / math.hypot(r['z'][1], s['z'][1]):+.1f}"
        own, own_err = self_consistency(r)
        # the references are evaluated here, so a table of an older JSON uses today's (Liu)
        zr, zc = reference_z(r["dim"], r["phi"]), classic_z(r["dim"], r["phi"])
        rows.append(f"| {r['dim']} | {r['phi']:.2f} | {r['law']} | {_pm(*r['z'])} | {zr:.5g} | "
                    f"{(r['z'][0] - zr) / r['z'][1]:+.1f} ({100 * (r['z'][0] / zr - 1):+.2f}%) | "
                    f"{(r['z'][0] - zc) / r['z'][1]:+.1f} | {vs} | {r['g_contact'][0]:.4g} (frames {r['g_contact_frames']:.3g}) | "
                    f"{_pm(*r['collision_rate'])} | {r['collision_rate_ref']:.5g} | {r['collision_rate_sigmas']:+.1f} | "
                    f"{r['collision_rate'][0] / own:.4f}: {(r['collision_rate'][0] - own) / own_err:+.1f} | "
                    f"{r['speed_chi2_microcanonical']:.2f} ({r['speed_chi2_maxwell']:.2f}) | "
                    f"{r['slab_temperature_max_z']:.1f} |")
    return "\n".join(rows)


def finite_size(runs: Sequence[dict]) -> list[dict[str, Any]]:
    """Z(N -> infinity) per (d, phi, law) from dense runs at several N (``extrapolate``),
    against Liu's equation of state: value, error, number of standard errors."""
    groups: dict[tuple, list[dict]] = {}
    for r in runs:
        groups.setdefault((r["dim"], r["phi"], r["law"]), []).append(r)
    out = []
    for (d, phi, law), rs in sorted(groups.items()):
        rs = sorted(rs, key=lambda r: r["n"])
        if len({r["n"] for r in rs}) < 2:
            continue
        zi, ei, slope = extrapolate([r["n"] for r in rs], [r["z"][0] for r in rs], [r["z"][1] for r in rs])
        ref = reference_z(d, phi)
        out.append({"dim": d, "phi": phi, "law": law, "n": [r["n"] for r in rs],
                    "collisions": [r["collisions"] for r in rs], "cpu_s": [r["cpu_s"] for r in rs],
                    "z": [r["z"] for r in rs], "z_sigmas": [(r["z"][0] - ref) / r["z"][1] for r in rs],
                    "z_inf": [zi, ei], "slope": slope, "z_ref": ref, "z_inf_sigmas": (zi - ref) / ei})
    return out


def finite_size_table(rows: Sequence[dict]) -> str:
    """``finite_size`` as a markdown table."""
    out = ["| d | phi | law | Z at each N (sd from Liu) | Z(inf) = Z(N) - a / N | Liu | sd | a |",
           "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        each = "; ".join(f"{n}: {_pm(*z)} ({s:+.1f})" for n, z, s in zip(r["n"], r["z"], r["z_sigmas"]))
        out.append(f"| {r['dim']} | {r['phi']:.2f} | {r['law']} | {each} | {_pm(*r['z_inf'])} | {r['z_ref']:.5g} | "
                   f"{r['z_inf_sigmas']:+.1f} | {r['slope']:+.3g} |")
    return "\n".join(out)


def self_consistency(r: dict) -> tuple[float, float]:
    """Enskog's collision rate with the contact value of the run's own Z, and its error (the
    rate's and Z's combined): in an equilibrium hard-sphere gas the collision rate and the
    virial both follow from g(sigma), so their ratio is 1 whatever the equation of state."""
    d, phi, T = r["dim"], r["phi"], r["temperature"][0]
    own = enskog_rate(d, phi, T, contact_value(d, phi, r["z"][0]))
    err = math.hypot(r["collision_rate"][1], own * r["z"][1] / (r["z"][0] - 1.0))
    return own, err


def _run_info(argv: Sequence[str], t0: float) -> dict[str, Any]:
    def sh(cmd: list[str]) -> str:
        try:
            return subprocess.run(cmd, capture_output=True, text=True, timeout=10).stdout.strip()
        except (OSError, subprocess.SubprocessError):
            return ""
    return {"command": "python -m revcol.studies.equilibrium " + " ".join(argv), "commit": sh(["git", "rev-parse", "--short", "HEAD"]),
            "uptime": sh(["uptime"]), "wall_s": time.time() - t0,
            "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())}


def main(argv: Optional[Sequence[str]] = None, prog: str = "python -m revcol.studies.equilibrium") -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    ap = argparse.ArgumentParser(prog=prog, description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="what", required=True)
    a = sub.add_parser("small", help="(a) two particles in a closed box against the exact equilibrium")
    a.add_argument("--collisions", type=int, default=4_000_000)
    a.add_argument("--mc-samples", type=int, default=20_000_000)
    a.add_argument("--dims", type=int, nargs="+", default=[2, 3], choices=(2, 3))
    a.add_argument("--laws", nargs="+", choices=tuple(LAWS))
    a.add_argument("--seed", type=int, default=1)
    a.add_argument("--json")
    for name, text in (("dense", "(b) dense gases against the equations of state and Enskog"),
                       ("walls", "(b) dense gases in a closed box: temperature and density by slab, wall pressure")):
        g = sub.add_parser(name, help=text)
        g.add_argument("--dim", type=int, choices=(2, 3), required=True)
        g.add_argument("--phi", type=float, nargs="+", required=True)
        g.add_argument("--n", type=int, default=1000)
        g.add_argument("--per-particle", type=float, default=20000.0, help="observed collisions per particle")
        g.add_argument("--laws", nargs="+", choices=tuple(LAWS))
        g.add_argument("--seed", type=int, default=1)
        g.add_argument("--json")
    f = sub.add_parser("figures", help="figures from the JSON files")
    f.add_argument("json", nargs="+")
    f.add_argument("--out", default="docs/figures/physics")
    t = sub.add_parser("table", help="the markdown tables of JSON files")
    t.add_argument("json", nargs="+")
    fs = sub.add_parser("finite-size", help="Z(N -> infinity) from dense runs at several N against Liu")
    fs.add_argument("runs", nargs="+", help="JSON files of `dense` runs (any sizes, laws, densities)")
    fs.add_argument("--json")
    mc = sub.add_parser("mc", help="the equilibrium Z at the engine's own N by event-chain Monte Carlo (revcol.studies.ecmc)")
    mc.add_argument("--dim", type=int, choices=(1, 2, 3), required=True)
    mc.add_argument("--phi", type=float, nargs="+", required=True)
    mc.add_argument("--n", type=int, nargs="+", default=[1000])
    mc.add_argument("--seeds", type=int, default=4, help="independent starts per point (each its own random state)")
    mc.add_argument("--first-seed", type=int, default=1)
    mc.add_argument("--per-particle", type=float, default=2000.0, help="observed chain displacement per sphere, in D")
    mc.add_argument("--warmup", type=float, default=200.0, help="chain displacement per sphere before observing, in D")
    mc.add_argument("--blocks", type=int, default=32)
    mc.add_argument("--chain-length", type=float, help="default: ecmc.default_chain_length (about 100 lifts)")
    mc.add_argument("--json")
    cmp_ = sub.add_parser("mc-compare", help="engine runs against event chains of the same N, and Z(inf) from the chains")
    cmp_.add_argument("--mc", nargs="+", required=True, help="JSON files of `mc` runs")
    cmp_.add_argument("--md", nargs="*", default=[], help="JSON files of `dense` runs or revcol.studies.eos_replicas studies")
    cmp_.add_argument("--json")
    args = ap.parse_args(argv)
    t0 = time.time()
    if args.what in ("mc", "mc-compare"):
        return _mc_main(args, argv, t0)
    if args.what == "figures":
        print("\n".join(figures(args.json, args.out)))
        return 0
    if args.what == "finite-size":
        rows = finite_size([r for p in args.runs for r in json.load(open(p))["dense"]])
        print(finite_size_table(rows))
        if args.json:
            with atomic_open(args.json) as fh:
                json.dump({"finite_size": rows, "inputs": args.runs, **_run_info(argv, t0)}, fh, indent=1)
        return 0
    if args.what == "table":
        for p in args.json:
            doc = json.load(open(p))
            print(small_table(doc["small"]) if "small" in doc else
                  walls_table(doc["walls"]) if "walls" in doc else dense_table(doc["dense"]))
        return 0
    if args.what == "small":
        st = small_study(args.collisions, seed=args.seed, mc_samples=args.mc_samples, dims=args.dims, laws=args.laws)
        doc: dict[str, Any] = {"small": st}
        print(small_table(st))
    else:
        laws = args.laws or [k for k in LAWS if args.dim == 2 or k != "paper"]
        run = dense if args.what == "dense" else walled
        runs = [run(args.dim, phi, law, n=args.n, per_particle=args.per_particle, seed=args.seed)
                for phi in args.phi for law in laws]
        doc = {args.what: runs}
        print(dense_table(runs) if args.what == "dense" else walls_table(runs))
    if args.json:
        doc.update(_run_info(argv, t0))
        with atomic_open(args.json) as fh:
            json.dump(doc, fh, indent=1)
    return 0


def _mc_main(args: argparse.Namespace, argv: Sequence[str], t0: float) -> int:
    """The `mc` and `mc-compare` subcommands (:mod:`revcol.studies.ecmc`)."""
    if args.what == "mc":
        if args.seeds < 1 or any(n < 2 for n in args.n):
            raise SystemExit("mc: --seeds must be >= 1 and every --n >= 2")
        runs = []
        for phi in args.phi:
            for n in args.n:
                for seed in range(args.first_seed, args.first_seed + args.seeds):
                    r = ecmc.sample(args.dim, phi, n=n, seed=seed, per_particle=args.per_particle,
                                    blocks=args.blocks, warmup=args.warmup, chain_length=args.chain_length)
                    runs.append(r)
                    print(f"  {args.dim}D phi {phi:.2f} N {n} seed {seed}: Z_mc {r['z_mc'][0]:.5f}+-{r['z_mc'][1]:.5f} "
                          f"({r['lifts']:.3g} lifts, {r['cpu_s']:.0f} s)", file=sys.stderr)
        rows = ecmc.summarize(runs)
        print(ecmc.summary_table(rows))
        doc: dict[str, Any] = {"mc": runs, "summary": rows}
    else:
        runs = []
        for p in args.mc:
            doc_mc = json.load(open(p))
            if "mc" not in doc_mc:
                raise SystemExit(f"mc-compare: {p} holds no `mc` runs (a JSON of `python -m revcol.studies.equilibrium mc` has an 'mc' list)")
            runs += doc_mc["mc"]
        rows = ecmc.summarize(runs)
        md = [e for p in args.md for e in ecmc.md_estimates(json.load(open(p)))]
        cmp_rows = ecmc.compare(rows, md)
        inf = ecmc.infinite_size(rows)
        print(ecmc.summary_table(rows))
        if cmp_rows:
            print()
            print(ecmc.compare_table(cmp_rows))
        for r in inf:
            print(f"\n{r['dim']}D phi {r['phi']:.2f}: Z(inf) from the chains at N = {r['n']}: "
                  f"{r['z_inf'][0]:.5f} +- {r['z_inf'][1]:.5f} (a = {r['slope']:+.3g}, chi2 {r['chi2']:.2f} / {r['dof']}); "
                  f"Liu {r['z_ref_liu']:.5f}: {100 * r['liu_relative']:+.3f}%, {r['liu_sigmas']:+.1f} sd")
        doc = {"summary": rows, "compare": cmp_rows, "infinite_size": inf, "inputs": {"mc": args.mc, "md": args.md}}
    if args.json:
        doc.update(_run_info(argv, t0))
        with atomic_open(args.json) as fh:
            json.dump(doc, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
