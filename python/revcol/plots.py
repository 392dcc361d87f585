"""The PNG figures of ``revcol run --plot``: a gas run's round-trip error, energy drift and
snapshots (start, turn, end), a lattice run's energy drift, bits-back size and snapshots, and
the horizon's error against collisions per particle.

matplotlib is imported only here and only when a figure is drawn (Agg backend unless pyplot
is already in use); :func:`require_matplotlib` checks for it before a run starts.
"""
from __future__ import annotations

import sys
import textwrap
from pathlib import Path

import numpy as np

from ._io import save_figure
from .roundtrip import BAR
from .scene import SceneError

__all__ = ["require_matplotlib", "plot_gas", "plot_lattice_gas", "plot_horizon"]


def require_matplotlib() -> None:
    """Raises SceneError when matplotlib is missing (checked before anything runs)."""
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        raise SceneError("--plot needs matplotlib (pip install matplotlib)") from None


def _pyplot():
    import matplotlib

    if "matplotlib.pyplot" not in sys.modules:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_gas(r: dict, out: Path, start, turn, end) -> list[str]:
    """A gas run's figures in ``out``: round-trip error and energy drift against collisions,
    and snapshots; ``start``, ``turn``, ``end`` are (positions, velocities). Returns the paths."""
    plt = _pyplot()
    out.mkdir(parents=True, exist_ok=True)
    written = []
    title = textwrap.fill(r["summary"], 110)

    fig, ax = plt.subplots(figsize=(7, 4.5))
    c = [p["collisions"] for p in r["curve"]]
    ax.semilogy(c, [max(p["error_x"], 1e-18) for p in r["curve"]], "o-", label="positions: max |x - x0| / L")
    ax.semilogy(c, [max(p["error_v"], 1e-18) for p in r["curve"]], "s-", label="velocities: max |v - v0| / max |v0|")
    ax.axhline(BAR, color="k", ls=":", lw=1, label="bar 1e-9")
    ax.set_xlabel("collisions forward (then back to the start)")
    ax.set_ylabel("round-trip error")
    ax.set_title(title, fontsize=7)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    written.append(_save(fig, out / "roundtrip_error.png", plt))

    written.append(_energy_figure(r, out, plt, title))
    written.append(_snapshots_figure(r, out, plt, title, start, turn, end))
    return written


def plot_lattice_gas(r: dict, out: Path, start, turn, end) -> list[str]:
    """A lattice run's figures in ``out``: energy drift and the bits-back integer's size against
    collisions (sampled after each chunk of the forward run), and snapshots; ``start``,
    ``turn``, ``end`` are (positions, velocities). There is no round-trip error curve: every
    round trip is bit for bit. Returns the paths."""
    plt = _pyplot()
    out.mkdir(parents=True, exist_ok=True)
    title = textwrap.fill(r["summary"], 110)
    written = [_energy_figure(r, out, plt, title)]

    fig, ax = plt.subplots(figsize=(7, 4.5))
    bs = np.array(r["bits_series"], dtype=float).reshape(-1, 2)
    ax.plot(bs[:, 0], bs[:, 1], "-", lw=1)
    ax.set_xlabel("collisions forward")
    ax.set_ylabel("bits-back integer X: bit length")
    ax.set_title(title, fontsize=7)
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    written.append(_save(fig, out / "bits_back.png", plt))
    written.append(_snapshots_figure(r, out, plt, title, start, turn, end))
    return written


def _energy_figure(r: dict, out: Path, plt, title: str) -> str:
    fig, ax = plt.subplots(figsize=(7, 4.5))
    es = np.array(r["energy_series"], dtype=float).reshape(-1, 2)
    ax.plot(es[:, 0], es[:, 1], "-", lw=1)
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_xlabel("collisions forward")
    ax.set_ylabel("energy drift (E - E0) / E0")
    ax.set_title(title, fontsize=7)
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    return _save(fig, out / "energy_drift.png", plt)


def _snapshots_figure(r: dict, out: Path, plt, title: str, start, turn, end) -> str:
    fig, axes = plt.subplots(1, 3, figsize=(13, 4.6))
    shots = [("start", *start), (f"after {r['collisions_forward']:,} collisions forward", *turn),
             ("after reversal", *end)]
    for ax, (label, x, v) in zip(axes, shots):
        _draw_particles(ax, x, v, r["box"], r["scene"]["diameter"])
        ax.set_title(label, fontsize=9)
    fig.suptitle(title + ("  (x-y projection, colour: speed)" if r["dimension"] == 3 else "  (colour: speed)"),
                 fontsize=7)
    fig.tight_layout()
    return _save(fig, out / "snapshots.png", plt)


def _draw_particles(ax, x, v, box, sigma) -> None:
    from matplotlib.collections import EllipseCollection
    from matplotlib.patches import Rectangle

    x = np.asarray(x)
    xy = x[:, :2] if x.shape[1] >= 2 else np.column_stack([x[:, 0], np.zeros(len(x))])
    ly = box[1] if len(box) >= 2 else sigma
    ec = EllipseCollection(sigma, sigma, 0.0, units="xy", offsets=xy if len(box) >= 2 else xy + [0, 0.5 * ly],
                           offset_transform=ax.transData, cmap="viridis", linewidths=0)
    ec.set_array(np.linalg.norm(v, axis=1))
    ax.add_collection(ec)
    ax.add_patch(Rectangle((0, 0), box[0], ly, fill=False, lw=0.8))
    ax.set_xlim(-0.02 * box[0], 1.02 * box[0])
    ax.set_ylim(-0.02 * max(ly, box[0]) if len(box) >= 2 else -ly, 1.02 * ly if len(box) >= 2 else 2 * ly)
    ax.set_aspect("equal" if len(box) >= 2 else "auto")
    ax.set_xticks([])
    ax.set_yticks([])


def plot_horizon(r: dict, out: Path) -> list[str]:
    """The horizon's figure (horizon.png in ``out``); returns its path."""
    plt = _pyplot()
    out.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    pp = [row["per_particle"] for row in r["rows"]]
    ax.loglog(pp, [max(row["error_x"], 1e-18) for row in r["rows"]], "o-", label="positions: max |x - x0| / L")
    ax.loglog(pp, [max(row["error_v"], 1e-18) for row in r["rows"]], "s-", label="velocities: max |v - v0| / max |v0|")
    if r["seeds"] > 1:
        ax.loglog(pp, [max(row["median"], 1e-18) for row in r["rows"]], ":", color="0.5",
                  label="median over seeds (the larger of the two errors)")
    ax.axhline(BAR, color="k", ls=":", lw=1, label="bar 1e-9")
    if r["horizon_collisions"]:
        ax.axvline(r["horizon_per_particle"], color="C2", ls="--", lw=1,
                   label=f"horizon: N_c = {r['horizon_collisions']:,}")
    ax.set_xlabel("collisions per particle (2 N_c / N), forward then back")
    ax.set_ylabel(f"round-trip error (worst of {r['seeds']} seed{'s' if r['seeds'] > 1 else ''})")
    ax.set_title(textwrap.fill(r["summary"], 110), fontsize=7)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return [_save(fig, out / "horizon.png", plt)]


def _save(fig, path: Path, plt) -> str:
    save_figure(fig, path, dpi=110)
    plt.close(fig)
    return str(path)

