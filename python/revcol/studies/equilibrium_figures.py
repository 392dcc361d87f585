"""The equilibrium study's figures (``python -m revcol.studies.equilibrium figures``): Z against phi
with the equations of state and event-chain Monte Carlo, g(r), speed histograms with the
Maxwellian, and the two-disk distance distribution, drawn from the study's JSON files.
matplotlib is imported when a figure is drawn, not with this module.
"""
from __future__ import annotations

import json
import math
import os
from typing import Sequence

import numpy as np

from .._io import save_figure
from .ecmc import summarize
from .eos import classic_z, microcanonical_speed_density, reference_z

__all__ = ["figures"]



def figures(paths: Sequence[str], out: str) -> list[str]:
    """Z against phi with the equation of state, g(r), speed histograms with the Maxwellian,
    and the two-disk distance distribution, from the study's JSON files; PNGs into ``out``."""
    import matplotlib  # optional and slow to import: only when figures are drawn

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # optional (the plot extra): imported only when a figure is drawn

    docs = [json.load(open(p)) for p in paths]
    dense_runs = [r for d in docs for r in d.get("dense", [])]
    small = [d["small"] for d in docs if "small" in d]
    mc_rows = summarize([r for d in docs for r in d.get("mc", [])])
    os.makedirs(out, exist_ok=True)
    written = []
    colours = {"flux": "C0", "specular": "k", "uniform": "C3", "paper": "C1"}
    if dense_runs:
        fig, axes = plt.subplots(2, 2, figsize=(9, 6), sharex="col")
        for col, d in enumerate((2, 3)):
            rs = [r for r in dense_runs if r["dim"] == d]
            if not rs:
                continue
            ax, dev = axes[0][col], axes[1][col]
            ph = np.linspace(0.0, max(r["phi"] for r in rs) + 0.02, 100)
            eos = "Liu"
            classic = "Henderson" if d == 2 else "Carnahan-Starling"
            ax.plot(ph, [reference_z(d, p) for p in ph], "-", color="0.6", label=f"{eos} (EOS)")
            ax.plot(ph, [classic_z(d, p) for p in ph], ":", color="0.6", label=classic)
            dev.plot(ph, [100 * (classic_z(d, p) / reference_z(d, p) - 1) for p in ph], ":", color="0.6",
                     label=f"{classic} / {eos} - 1")
            dev.axhline(0.0, color="0.6")
            for k, law in enumerate(colours):  # the laws, in the study's order
                sel = [r for r in rs if r["law"] == law]
                if not sel:
                    continue
                x = [r["phi"] + 0.004 * (k - 1.5) for r in sel]
                ax.errorbar(x, [r["z"][0] for r in sel], yerr=[r["z"][1] for r in sel], fmt="o", ms=3,
                            color=colours[law], label=law)
                zr = [reference_z(d, r["phi"]) for r in sel]
                dev.errorbar(x, [100 * (r["z"][0] / z - 1) for r, z in zip(sel, zr)],
                             yerr=[100 * r["z"][1] / z for r, z in zip(sel, zr)], fmt="o", ms=3, color=colours[law])
            same_n = [m for m in mc_rows if m["dim"] == d and m["n"] == rs[0]["n"]]
            if same_n:  # the equilibrium of the same N and box (event chains), in the engine's convention
                x = [m["phi"] + 0.008 for m in same_n]
                ax.errorbar(x, [m["z_md"][0] for m in same_n], yerr=[m["z_md"][1] for m in same_n], fmt="s", ms=4,
                            mfc="none", color="C2", label="event chains, same N")
                dev.errorbar(x, [100 * (m["z_md"][0] / reference_z(d, m["phi"]) - 1) for m in same_n],
                             yerr=[100 * m["z_md"][1] / reference_z(d, m["phi"]) for m in same_n], fmt="s", ms=4,
                             mfc="none", color="C2", label="event chains, same N")
            ax.set_ylabel("Z = PV / NkT"), ax.set_title(f"{d}D, N = {rs[0]['n']}, periodic")
            dev.set_xlabel("packing fraction"), dev.set_ylabel(f"Z / {eos} - 1 (%)")
            ax.legend(fontsize=7)
            dev.legend(fontsize=7)
        fig.tight_layout()
        written.append(_save(fig, out, "z_vs_phi.png"))
        def g_panel(ax, d, phi, rs):
            for r in rs:
                ax.plot(r["g_r"][0], r["g_r"][1], color=colours[r["law"]], lw=1, label=r["law"])
            ax.set_xlabel("r / sigma"), ax.set_ylabel("g(r) (40 frames)"), ax.set_title(f"{d}D, phi = {phi}")

        written.append(_per_dim(plt, dense_runs, {2: 0.5, 3: 0.45}, g_panel, out, "g_of_r.png"))

        def speed_panel(ax, d, phi, rs):
            for r in rs:
                c = np.asarray(r["speed_centres"])
                ref = microcanonical_speed_density(d, r["n"], c, r["temperature"][0])
                ax.errorbar(c, np.asarray(r["speed"]) / ref - 1.0, yerr=np.asarray(r["speed_error"]) / ref, fmt=".-",
                            lw=0.6, ms=3, color=colours[r["law"]], label=r["law"])
            ax.axhline(0.0, color="0.6")
            ax.set_ylim(-0.05, 0.05), ax.set_xlim(0, 3.5 * math.sqrt(rs[0]["temperature"][0]))
            ax.set_xlabel("speed"), ax.set_title(f"{d}D, phi = {phi}")
            ax.set_ylabel("time-weighted density / exact - 1")

        written.append(_per_dim(plt, dense_runs, {2: 0.3, 3: 0.1}, speed_panel, out, "speeds.png"))
    walls = [r for d in docs for r in d.get("walls", [])]
    if walls:
        dims = sorted({r["dim"] for r in walls})
        fig, axes = plt.subplots(len(dims), 2, figsize=(9, 3.2 * len(dims)), squeeze=False)
        for row, d in zip(axes, dims):
            rs = [r for r in walls if r["dim"] == d]
            for r in rs:
                e = np.asarray(r["slab_edges"])
                c = 0.5 * (e[1:] + e[:-1]) / e[-1]
                T = r["temperature"][0]
                row[0].errorbar(c, 100 * (np.asarray(r["slab_temperature"]) / T - 1),
                                yerr=100 * np.asarray(r["slab_temperature_error"]) / T, fmt="o-", ms=3, lw=0.7,
                                color=colours[r["law"]], label=r["law"])
                row[1].plot(c, r["slab_density"], "o-", ms=3, lw=0.7, color=colours[r["law"]], label=r["law"])
            row[0].axhline(0.0, color="0.6")
            row[0].set_ylabel("slab temperature / T - 1 (%)"), row[1].set_ylabel("number density")
            for ax in row:
                ax.set_xlabel("x / L"), ax.legend(fontsize=7)
                ax.set_title(f"{d}D, phi = {rs[0]['phi']}, walls, N = {rs[0]['n']}")
        fig.tight_layout()
        written.append(_save(fig, out, "walls_slabs.png"))
    for st in small:
        fig, axes = plt.subplots(1, 2, figsize=(9, 3.4))
        for ax, d in zip(axes, (2, 3)):
            mc = st.get(f"mc_{d}d")
            if mc is None:
                continue
            e = np.asarray(mc["distance_edges"])
            c = 0.5 * (e[1:] + e[:-1])
            ax.plot(c, mc["distance"], "-", color="0.6", lw=2, label="Monte Carlo (exact)")
            for r in st["runs"]:
                if r["dim"] == d:
                    n = min(len(c), len(r["distance"]))
                    ax.plot(c[:n], r["distance"][:n], "-", lw=0.8, color=colours[r["law"]], label=r["law"])
            ax.set_xlim(0.95, 1.6)
            ax.set_xlabel("|r| / sigma"), ax.set_ylabel("density of the distance")
            ax.set_title("two disks, box 2.5" if d == 2 else "two spheres, box 2.5")
            ax.legend(fontsize=7)
        fig.tight_layout()
        written.append(_save(fig, out, "two_body_distance.png"))
    return written


def _per_dim(plt, runs: Sequence[dict], phis: dict[int, float], panel, out: str, name: str) -> str:
    """One panel per dimension, of the runs at phis[d] (or the densest), saved as out/name."""
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.4))
    for ax, d in zip(axes, (2, 3)):
        rs = [r for r in runs if r["dim"] == d]
        if not rs:
            continue
        have = {r["phi"] for r in rs}
        phi = phis[d] if phis[d] in have else max(have)
        panel(ax, d, phi, [r for r in rs if r["phi"] == phi])
        ax.legend(fontsize=7)
    fig.tight_layout()
    return _save(fig, out, name)


def _save(fig, out: str, name: str) -> str:
    import matplotlib.pyplot as plt  # optional: only when figures are drawn

    path = os.path.join(out, name)
    save_figure(fig, path, dpi=90)
    plt.close(fig)
    return path
