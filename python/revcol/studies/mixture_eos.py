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
and 1/ratio; or, ``sizes="gauss"``, a polydisperse gas of diameters 1 + 0.1 z, z a standard
normal truncated at +-2) at packing fraction phi, runs it ``equilibrate`` collisions per particle, then
observes ``collisions`` per particle (the collision virial, Z = 1 + W / K2, with its block
error), with ``frames`` the partial contact values g_ab(sigma_ab+) against Boublik-Grundke-
Henderson-Lee-Levesque (spheres; the contact values behind BMCSL) or SLHY's (disks) and each
species' temperature, and runs back to the start bit for bit. ``compare`` pairs it with the one-size gas at
the same N, phi and seed (ratio 1, the mixture code path with equal radii): BMCSL is built on
Carnahan-Starling, which is 0.2-0.3% low for the pure sphere fluid at 0.3-0.45 (docs/physics.md),
so beside Z against BMCSL it reports the pure gas against Liu's and CS's equations and the
ratio Z_mixture / Z_pure against BMCSL / CS (SLHY / Liu in 2D), which the pure fluid's
equation and the O(1/N) terms both cancel from; and each beside the project's event-chain Monte
Carlo of the same mixture at the same N (``ecmc``), which needs no theory at all. ``python -m revcol.studies.mixture_eos --json F``
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
import sys
import time
from typing import Sequence

import numpy as np

from .eos import carnahan_starling, henderson, liu_disks, liu_spheres

__all__ = ["bmcsl_z", "slhy_z", "bghll_contact", "slhy_contact", "binary_diameters", "measure", "compare", "table",
           "figure", "main"]


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


def bghll_contact(phi: float, diameters: Sequence[float], a: float, b: float) -> float:
    """g_ab at contact (sigma_ab = (a + b) / 2) in a sphere mixture by Boublik-Grundke-Henderson-
    Lee-Levesque: 1 / (1 - xi_3) + 3 xi_2 / (1 - xi_3)^2 z + 2 xi_2^2 / (1 - xi_3)^3 z^2,
    z = a b / (a + b); the contact values the virial route turns into BMCSL's Z."""
    m = _moments(diameters)
    rho = phi / (math.pi / 6.0 * m[3])
    x2, x3 = math.pi / 6.0 * rho * m[2], phi
    z = a * b / (a + b)
    return 1.0 / (1.0 - x3) + 3.0 * x2 / (1.0 - x3) ** 2 * z + 2.0 * x2**2 / (1.0 - x3) ** 3 * z * z


def slhy_contact(eta: float, diameters: Sequence[float], a: float, b: float, pure=liu_disks) -> float:
    """g_ab at contact in a disk mixture by SLHY: 1 / (1 - eta) + [g_1 - 1 / (1 - eta)] z,
    z = (a b / sigma_ab) <d> / <d^2>, g_1 = (Z_1 - 1) / (2 eta) the pure fluid's; the contact
    values the virial route turns into SLHY's Z."""
    m = _moments(diameters)
    g1 = (pure(eta) - 1.0) / (2.0 * eta)
    return 1.0 / (1.0 - eta) + (g1 - 1.0 / (1.0 - eta)) * a * b / (0.5 * (a + b)) * m[1] / m[2]


def binary_diameters(n: int, ratio: float) -> np.ndarray:
    """n diameters, every other one 1 / ratio (equal numbers of the two species)."""
    d = np.ones(n)
    d[1::2] = 1.0 / ratio
    return d


def gaussian_diameters(n: int, seed: int, width: float = 0.1) -> np.ndarray:
    """n diameters 1 + width z, z standard normal truncated at +-2 (numpy's generator keyed by
    ``seed``; tests/long/lattice_validation.py's ``gauss`` sizes): a polydisperse sample."""
    z = np.random.default_rng(seed).standard_normal(4 * n)
    return 1.0 + width * z[np.abs(z) <= 2.0][:n]


def measure(dim: int, n: int, phi: float, ratio: float, *, equilibrate: float = 100.0, collisions: float = 400.0,
            seed: int = 1, blocks: int = 32, frames: int = 0, ecmc: float = 0.0, sizes: str = "binary",
            float_md: bool = False) -> dict:
    """One run (see the module docstring): Z with its block error, the theory, and the checks;
    ``frames`` > 0: that many frames at evenly spaced times (not at collisions) give the partial
    contact values g_ab(sigma_ab+) against the theory's and each species' temperature; ``ecmc``
    > 0: the event-chain sampler (:mod:`revcol.studies.ecmc`, a different algorithm sharing no
    code with the engine) from the same start, box and quantized diameters, that many largest
    diameters of chain displacement per sphere, its Z as the engine's (md_equivalent) beside;
    ``float_md``: the float engine's run of the same particles from the same start (its own
    dynamics, the same equilibration and observed collisions per particle)."""
    from ..lattice import LatticeSimulation, LatticeSimulation3D
    cls = LatticeSimulation3D if dim == 3 else LatticeSimulation
    if sizes not in ("binary", "gauss"):
        raise ValueError(f"sizes must be 'binary' or 'gauss', got {sizes!r}")
    if sizes == "gauss" and frames:
        raise ValueError("a polydisperse gas has no species for the partial contact values: frames=0")
    d = binary_diameters(n, ratio) if sizes == "binary" else gaussian_diameters(n, seed)
    sim = cls.random(n, phi=phi, diameters=d, seed=seed)
    x0 = sim.lattice_positions.copy()
    chains = _ecmc(dim, phi, sim, seed, ecmc) if ecmc > 0 else None
    flt = _float_md(sim, seed, equilibrate, collisions, blocks) if float_md else None
    t0 = time.perf_counter()
    sim.run(collisions=int(equilibrate * n))
    # blocks of equal time: the rate from the equilibration
    rate = sim.collisions / max(sim.time, 1e-300)
    t_obs = collisions * n / rate
    sim.observe(block_time=t_obs / blocks)
    if frames:
        t0_obs, xs, vs = sim.time, [], []
        sim._e.set_trace(True)  # the collisions by pair: the contact values through the rates
        for k in range(frames):
            sim.run(time=t0_obs + (k + 1) * t_obs / frames)
            xs.append(sim.positions)
            vs.append(sim.velocities)
        trace, t_obs = sim._e.take_trace(), sim.time - t0_obs
        sim._e.set_trace(False)
    else:
        sim.run(collisions=int(collisions * n))
    obs = sim.observation()
    sim.run_back()
    seconds = time.perf_counter() - t0
    z, ze = obs.compressibility.value, obs.compressibility.error
    theory = bmcsl_z(phi, sim.diameters) if dim == 3 else slhy_z(phi, sim.diameters)
    out = {"dim": dim, "n": n, "phi": phi, "sizes": sizes, "ratio": ratio if sizes == "binary" else None,
           "seed": seed, "equilibrate_per_particle": equilibrate,
           "collisions_per_particle": collisions, "z": z, "z_error": ze, "blocks": obs.blocks,
           "theory": "BMCSL" if dim == 3 else "SLHY (Liu)", "z_theory": theory,
           "deviation_sd": (z - theory) / ze if ze > 0 else float("inf"),
           "back_to_start": bool((sim.lattice_positions == x0).all()), "seconds": seconds}
    if dim == 2:
        out["z_slhy_henderson"] = slhy_z(phi, sim.diameters, henderson)
    # the observer's species (ascending diameter): temperatures and partial pressures, exact time averages
    out["species_temperature"] = [[e.value, e.error] for e in obs.species_temperature]
    out["species_pressure"] = [[e.value, e.error] for e in obs.species_pressure]
    if chains is not None:
        (zc, zce) = chains["z_md"]
        out["ecmc"] = chains
        out["ecmc_deviation_sd"] = (z - zc) / math.hypot(ze, zce)
    if flt is not None:
        out["float"] = flt
        out["float_deviation_sd"] = (flt["z"] - z) / math.hypot(ze, flt["z_error"])
    if frames:
        out.update(_structure(dim, phi, sim, np.asarray(xs), np.asarray(vs), trace, t_obs,
                              obs.temperature.value))
    return out


def _ecmc(dim: int, phi: float, sim, seed: int, per_particle: float) -> dict:
    """The event-chain run of ``measure``: chains from the lattice gas's start (its float
    positions, box and diameters), 200 diameters per sphere of warm-up, 32 blocks."""
    from .ecmc import EventChain, sample
    chain = EventChain(list(sim.box), sim.positions, diameters=sim.diameters, seed=seed)
    r = sample(dim, phi, n=sim.n, seed=seed, per_particle=per_particle, sampler=chain)
    return {k: r[k] for k in ("z_mc", "z_md", "per_particle", "warmup", "chain_length", "lifts", "cpu_s",
                              "min_distance")}


def _float_md(sim, seed: int, equilibrate: float, collisions: float, blocks: int) -> dict:
    """The float engine's run of ``measure``: the lattice gas's start (float positions,
    velocities, box and diameters), blocks of equal time from its own collision rate."""
    from ..engine import Simulation
    f = Simulation(sim.positions, sim.velocities, sim.box, diameters=sim.diameters, seed=seed)
    t0 = time.perf_counter()
    f.run(collisions=int(equilibrate * f.n))
    rate = f.collisions / max(f.time - f.start_time, 1e-300)
    f.observe(block_time=collisions * f.n / rate / blocks)
    f.run(collisions=int(collisions * f.n))
    obs = f.observation()
    return {"z": obs.compressibility.value, "z_error": obs.compressibility.error, "blocks": obs.blocks,
            "species_temperature": [[e.value, e.error] for e in obs.species_temperature],
            "energy_drift": f.diagnostics()["energy_drift"], "seconds": time.perf_counter() - t0}


def _structure(dim: int, phi: float, sim, xs: np.ndarray, vs: np.ndarray, trace, duration: float, kt: float) -> dict:
    """Partial contact values against the theory: from the collision rates (exact at
    equilibrium; the error: the counts' Poisson error) and from the frames' g_ab(r) (a quadratic
    fit over 0.25 diameters past contact; the error: the standard error of the fits of 5 blocks
    of frames; such fits read about 2% low at phi = 0.4 in 3D, the one-size gas's rate against
    its Z shows); and the species' temperatures."""
    from ..observe import contact_value
    from ..observe_species import (contact_from_rates, pair_collision_counts, partial_radial_distribution,
                                   species_labels, species_temperatures)
    labels, sizes = species_labels(sim.diameters)
    counts = pair_collision_counts(trace, labels)
    g_rate = contact_from_rates(counts, labels, sizes, float(np.prod(sim.box)), duration, kt, dim)
    f = len(xs)
    out = {"frames": f, "species_diameters": sizes.tolist(),
           "temperatures": species_temperatures(vs, labels).tolist(), "contact": []}
    blocks = [partial_radial_distribution(h, sim.box, labels, bins=250, r_max=2.5)[1]
              for h in np.array_split(xs, min(5, f))]
    r, g = partial_radial_distribution(xs, sim.box, labels, bins=250, r_max=2.5)
    out["g_r"] = {"r": np.round(r, 6).tolist(), "pairs": [[float(sizes[a]), float(sizes[b]), np.round(g[a, b], 5).tolist()]
                                                           for a in range(len(sizes)) for b in range(a, len(sizes))]}
    dr = r[1] - r[0]
    for a in range(len(sizes)):
        for b in range(a, len(sizes)):
            s_ab = 0.5 * (sizes[a] + sizes[b])
            past = r - 0.5 * dr >= s_ab  # whole bins past contact (one straddling it reads low)

            def fit(gg):
                return contact_value(r[past], gg[a, b][past], s_ab, width=0.25)
            val = fit(g)
            each = [fit(gb) for gb in blocks]  # the error: the block fits' standard error
            spread = float(np.std(each, ddof=1) / math.sqrt(len(each))) if len(each) > 1 else float("inf")
            th = (bghll_contact(phi, sim.diameters, sizes[a], sizes[b]) if dim == 3 else
                  slhy_contact(phi, sim.diameters, sizes[a], sizes[b]))
            gr, gr_err = float(g_rate[a, b]), float(g_rate[a, b] / math.sqrt(max(counts[a, b], 1)))
            out["contact"].append({"a": float(sizes[a]), "b": float(sizes[b]), "collisions": int(counts[a, b]),
                                   "g_rate": gr, "g_rate_error": gr_err, "theory": th,
                                   "deviation_sd": (gr - th) / gr_err, "g_frames": val, "g_frames_error": spread})
    # the virial route from the rates' contact values: Z = 1 + 2^(d-1) (v_1 rho) sum x_a x_b sigma_ab^d g_ab,
    # v_1 rho = phi / <d^d> (v_1 the unit sphere's volume over 2^d), beside the collisions' Z
    x = np.bincount(labels) / len(labels)
    idx = {float(v): k for k, v in enumerate(sizes)}
    sd = sum(x[idx[c["a"]]] * x[idx[c["b"]]] * (1 if c["a"] == c["b"] else 2) * (0.5 * (c["a"] + c["b"])) ** dim * c["g_rate"]
             for c in out["contact"])
    out["z_from_contact"] = 1.0 + 2 ** (dim - 1) * phi / float(np.mean(np.asarray(sim.diameters) ** dim)) * sd
    return out


def compare(dim: int, n: int, phi: float, ratio: float, pure: dict | None = None, **kw) -> dict:
    """The mixture (``measure``) and the one-size gas at the same N, phi and seed (``pure``: one
    measured already), and the ratio of their Z against the theory's (module docstring)."""
    mix = measure(dim, n, phi, ratio, **kw)
    if pure is None:
        pure = measure(dim, n, phi, 1.0, **{k: v for k, v in kw.items() if k != "sizes"})
    pure_theory = liu_spheres(phi) if dim == 3 else liu_disks(phi)
    pure_base = carnahan_starling(phi) if dim == 3 else liu_disks(phi)  # what the mixture theory reduces to
    r = mix["z"] / pure["z"]
    re = r * math.hypot(mix["z_error"] / mix["z"], pure["z_error"] / pure["z"])
    r_theory = mix["z_theory"] / pure_base
    return {"mixture": mix, "pure": pure, "pure_theory": "Liu (spheres)" if dim == 3 else "Liu (disks)",
            "z_pure_theory": pure_theory, "pure_deviation_sd": (pure["z"] - pure_theory) / pure["z_error"],
            "z_pure_cs": carnahan_starling(phi) if dim == 3 else None,
            "ratio": r, "ratio_error": re, "ratio_theory": r_theory, "ratio_deviation_sd": (r - r_theory) / re}


def figure(runs: list, path: str) -> None:
    """The partial g_ab(r) of the first run in each dimension, the theory's contact values marked."""
    from .._io import save_figure
    from ..plots import _pyplot
    plt = _pyplot()
    firsts = {}
    for c in runs:
        if "g_r" in c["mixture"]:  # the binary runs with frames
            firsts.setdefault(c["mixture"]["dim"], c["mixture"])
    fig, axes = plt.subplots(1, len(firsts), figsize=(6 * len(firsts), 4.2), squeeze=False)
    for ax, (dim, m) in zip(axes[0], sorted(firsts.items())):
        r = np.asarray(m["g_r"]["r"])
        for k, ((a, b, g), ct) in enumerate(zip(m["g_r"]["pairs"], m["contact"])):
            g = np.asarray(g)
            s_ab = 0.5 * (a + b)
            keep = r >= s_ab - 0.05
            ax.plot(r[keep], g[keep], lw=1, color=f"C{k}", label=f"g({a:.3g}, {b:.3g})")
            ax.plot([s_ab], [ct["theory"]], "o", mfc="none", color=f"C{k}")
        ax.axhline(1.0, color="0.6", lw=0.7)
        ax.set_xlabel("r (diameters of the larger species)")
        ax.set_ylabel("partial g_ab(r)")
        ax.set_title(f"{dim}D binary mixture, size ratio {m['ratio']:g}, phi = {m['phi']:g}, N = {m['n']}, "
                     f"{m['frames']} frames\n(circles: {'BGHLL' if dim == 3 else 'SLHY (Liu)'} at contact)", fontsize=9)
        ax.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)


def table(runs: list) -> str:
    """The runs pooled over seeds, as a markdown table: per dimension, the mean of each figure
    over the seeds and its standard error from their spread (the runs' own block and Poisson
    errors understate it for the contact values: collision counts are correlated in time)."""
    def pooled(vals):
        v = np.asarray(vals, dtype=float)
        return float(v.mean()), float(v.std(ddof=1) / math.sqrt(len(v))) if len(v) > 1 else float("nan")
    rows = ["| d | phi | quantity | measured (mean +- s.e., seeds) | theory | deviation (s.e.) |",
            "|---|---|---|---|---|---|"]
    for kind, dim in sorted({(c["mixture"].get("sizes", "binary"), c["mixture"]["dim"]) for c in runs}):
        cs = [c for c in runs if c["mixture"]["dim"] == dim and c["mixture"].get("sizes", "binary") == kind]
        m0, k = cs[0]["mixture"], len(cs)
        if kind == "gauss":
            rows.append(f"| {dim} | {m0['phi']:g} | (polydisperse: 10% Gaussian) | | | |")
        items = [("Z, mixture", [c["mixture"]["z"] for c in cs], m0["z_theory"], m0["theory"]),
                 ("Z, one size", [c["pure"]["z"] for c in cs], cs[0]["z_pure_theory"], cs[0]["pure_theory"]),
                 ("Z mixture / Z one size", [c["ratio"] for c in cs], cs[0]["ratio_theory"],
                  "BMCSL / CS" if dim == 3 else "SLHY / Liu")]
        if "ecmc" in m0:
            items.append(("Z, mixture: lattice - ECMC (same N)", [c["mixture"]["z"] - c["mixture"]["ecmc"]["z_md"][0]
                                                              for c in cs], 0.0, "0"))
            items.append(("Z, mixture, ECMC (same N)", [c["mixture"]["ecmc"]["z_md"][0] for c in cs], m0["z_theory"],
                          m0["theory"]))
            if "ecmc" in cs[0]["pure"]:
                items.append(("Z, one size: lattice - ECMC (same N)", [c["pure"]["z"] - c["pure"]["ecmc"]["z_md"][0]
                                                                    for c in cs], 0.0, "0"))
        if "float" in m0:
            items.append(("Z, mixture: float - lattice (same start)", [c["mixture"]["float"]["z"] - c["mixture"]["z"]
                                                                      for c in cs], 0.0, "0"))
            items.append(("Z, mixture, float engine", [c["mixture"]["float"]["z"] for c in cs], m0["z_theory"],
                          m0["theory"]))
            if "float" in cs[0]["pure"]:
                items.append(("Z, one size: float - lattice (same start)", [c["pure"]["float"]["z"] - c["pure"]["z"]
                                                                           for c in cs], 0.0, "0"))
        if "z_from_contact" in m0:
            items.append(("Z from the contact values (rates)", [c["mixture"]["z_from_contact"] for c in cs],
                          float(np.mean([c["mixture"]["z"] for c in cs])), "Z (collision virial)"))
            for j, ct in enumerate(m0["contact"]):
                th = "BGHLL" if dim == 3 else "SLHY (Liu)"
                items.append((f"g({ct['a']:.3g}, {ct['b']:.3g}) at contact, rates", [c["mixture"]["contact"][j]["g_rate"] for c in cs],
                              ct["theory"], th))
                items.append((f"g({ct['a']:.3g}, {ct['b']:.3g}) at contact, frames", [c["mixture"]["contact"][j]["g_frames"] for c in cs],
                              ct["theory"], th))
            t = np.asarray([c["mixture"]["temperatures"] for c in cs])
            items.append(("T small / T large (frames)", list(t[:, 0] / t[:, 1]), 1.0, "equipartition"))
        if m0.get("species_temperature"):
            t = np.asarray([[e[0] for e in c["mixture"]["species_temperature"]] for c in cs])
            items.append(("T small / T large (observer)", list(t[:, 0] / t[:, 1]), 1.0, "equipartition"))
        for name, vals, th, thname in items:
            mean, se = pooled(vals)
            pct = f" ({100 * (mean / th - 1):+.2f}%)" if th else ""
            rows.append(f"| {dim} | {m0['phi']:g} | {name} | {mean:.5g} +- {se:.2g} ({k}) | {th:.5g} ({thname}) | "
                        f"{(mean - th) / se if se > 0 else float('nan'):+.1f}{pct} |")
    return "\n".join(rows)


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--n", type=int, default=4000)
    p.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    p.add_argument("--collisions", type=float, default=400.0, help="observed collisions per particle")
    p.add_argument("--frames", type=int, default=100, help="frames for the partial contact values (0: none)")
    p.add_argument("--sizes", nargs="+", default=["binary"], choices=["binary", "gauss"],
                   help="the mixtures: 1:1 binary of ratio 1.4 (with partial contact values), 10%% Gaussian")
    p.add_argument("--ecmc", type=float, default=2000.0, help="event-chain displacement per sphere, in largest "
                   "diameters, for the cross-check at the same N (0: none)")
    p.add_argument("--float", dest="float_md", action="store_true", help="the float engine's run of the same "
                   "particles from the same start beside each")
    p.add_argument("--json", default=None)
    p.add_argument("--figure", default=None, help="the partial g_ab(r) of the first seed's runs (PNG); with --from, "
                   "from that JSON alone")
    p.add_argument("--from", dest="source", default=None, help="an earlier --json: its table (pooled over "
                   "seeds) and, with --figure, its figure; nothing is run")
    a = p.parse_args(argv)
    if a.source:
        with open(a.source) as f:
            runs = json.load(f)["runs"]
        if a.figure:
            figure(runs, a.figure)
        print(table(runs))
        return 0
    runs = []
    for seed in a.seeds:
        for dim, phi in ((2, 0.5), (3, 0.4)):
            pure = None
            for kind in a.sizes:
                c = compare(dim, a.n, phi, 1.4, pure=pure, collisions=a.collisions, seed=seed, ecmc=a.ecmc, sizes=kind,
                            frames=a.frames if kind == "binary" else 0, float_md=a.float_md)
                r, q = c["mixture"], c["pure"]
                pure = q
                print(f"{kind} {dim}D phi {phi} seed {seed}: Z = {r['z']:.4f} +- {r['z_error']:.4f}, {r['theory']} "
                      f"{r['z_theory']:.4f} ({r['deviation_sd']:+.1f} sd); one size {q['z']:.4f} +- {q['z_error']:.4f}, "
                      f"{c['pure_theory']} {c['z_pure_theory']:.4f} ({c['pure_deviation_sd']:+.1f} sd); ratio "
                      f"{c['ratio']:.5f} +- {c['ratio_error']:.5f} against {c['ratio_theory']:.5f} "
                      f"({c['ratio_deviation_sd']:+.1f} sd); back to start {r['back_to_start'] and q['back_to_start']}",
                      flush=True)
                for name, run in (("mixture", r), ("one size", q)):
                    if "ecmc" in run:
                        e = run["ecmc"]["z_md"]
                        print(f"    {name}: ECMC at the same N {e[0]:.4f} +- {e[1]:.4f}, lattice - ECMC "
                              f"{run['z'] - e[0]:+.4f} ({run['ecmc_deviation_sd']:+.1f} sd)", flush=True)
                for name, run in (("mixture", r), ("one size", q)):
                    if "float" in run:
                        f = run["float"]
                        print(f"    {name}: float engine {f['z']:.4f} +- {f['z_error']:.4f}, float - lattice "
                              f"{f['z'] - run['z']:+.4f} ({run['float_deviation_sd']:+.1f} sd)", flush=True)
                if "z_from_contact" in r:
                    print(f"    Z from the rates' contact values (virial route) {r['z_from_contact']:.4f}; temperatures "
                          + ", ".join(f"{t:.4f}" for t in r["temperatures"]) + " (frames), "
                          + ", ".join(f"{t:.4f} +- {e:.4f}" for t, e in r["species_temperature"]) + " (observer)", flush=True)
                for g in r.get("contact", []):
                    print(f"    g({g['a']:.3f}, {g['b']:.3f}) at contact: rates {g['g_rate']:.4f} +- {g['g_rate_error']:.4f}, "
                          f"theory {g['theory']:.4f} ({g['deviation_sd']:+.1f} sd); frames {g['g_frames']:.3f} +- "
                          f"{g['g_frames_error']:.3f}", flush=True)
                runs.append(c)
    if a.figure:
        figure(runs, a.figure)
    if a.json:
        from .._io import atomic_open
        with atomic_open(a.json) as f:
            json.dump({"study": "mixture_eos", "command": "python -m revcol.studies.mixture_eos " + " ".join(argv or []),
                       "runs": runs}, f, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
