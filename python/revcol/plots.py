"""The figures of ``revcol run --plot``: a gas run's round-trip error, energy drift and
snapshots (start, turn, end), a lattice run's energy drift, bits-back size and snapshots, and
the horizon's error against collisions per particle.

Every figure is written as PNG (150 dpi), PDF or SVG (``fmt``). What they promise a reader:
axes with their quantities and units (lengths in the scene's units, the particle diameter
drawn to scale), a colourbar wherever colour carries a value, periodic axes drawn dashed and
walls solid, log axes that never invent a value (an exact zero is drawn as an open marker on
the axis floor, and the legend says so), legends inside the axes, no tables inside figures.
Titles are short (:func:`short_title`: scene, N, dimension, packing fraction, engine, mode); the
scene's whole summary goes into the file's metadata (PNG and SVG ``Description``, PDF ``Subject``).

1D gases are drawn in phase space (position against velocity): a line of rods shows nothing.
3D gases are drawn as a slice through the middle of the box (the spheres' cross sections in
|z - Lz/2| < D/2, to scale), not as a projection in which thousands of spheres overlap.

matplotlib is imported only here and only when a figure is drawn (Agg backend unless pyplot
is already in use); :func:`require_matplotlib` checks for it before a run starts.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from ._extras import install_hint
from ._io import save_figure
from .roundtrip import BAR
from .scene import SceneError

__all__ = ["FORMATS", "FIGURES", "figure_names", "require_matplotlib", "check_format", "plot_gas",
           "plot_lattice_gas", "plot_horizon"]

#: the file formats of the figures (``--plot-format``)
FORMATS = ("png", "pdf", "svg")
_EPS = float(np.finfo(float).eps)

#: the figures each run writes into its plot folder, by name (the format is the suffix): the float
#: engine's gas (plot_gas), the lattice's (plot_lattice_gas), the horizon (plot_horizon) and a
#: statesave scene's (revcol.studies.paper_scenes); what a run's outputs are checked against its
#: inputs with (revcol._outputs; tests/python/test_output_guard.py holds them to what is written)
FIGURES = {"gas": ("roundtrip_error", "energy_drift", "snapshots"),
           "lattice": ("energy_drift", "bits_back", "snapshots"),
           "horizon": ("horizon",), "statesave": ("statesave",)}


def figure_names(run: str, fmt: str = "png") -> frozenset[str]:
    """The file names a run (a key of :data:`FIGURES`) writes into its plot folder."""
    return frozenset(f"{stem}.{fmt}" for stem in FIGURES[run])


def require_matplotlib() -> None:
    """Raises SceneError when matplotlib is missing (checked before anything runs)."""
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        raise SceneError(f"--plot needs matplotlib, which is not installed: {install_hint('matplotlib')}") from None


def check_format(fmt: str) -> str:
    """``fmt`` if it is one of :data:`FORMATS`, else SceneError naming the choices."""
    if fmt not in FORMATS:
        raise SceneError(f"--plot-format: {fmt!r} is not one of {', '.join(FORMATS)}")
    return fmt


def _pyplot():
    import matplotlib  # optional (the plot extra): imported only when a figure is drawn

    if "matplotlib.pyplot" not in sys.modules:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # optional (the plot extra): imported only when a figure is drawn

    return plt


def _log_series(ax, x, y, marker: str, label: str, color: str, plot="semilogy") -> list[float]:
    """Draws the positive values of y on a log axis; returns the x of the exact zeros (drawn
    by :func:`_mark_zeros` once the floor is known)."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    pos = y > 0
    getattr(ax, plot)(x[pos], y[pos], marker + "-", label=label, color=color, ms=4)
    return list(x[~pos])


def _mark_zeros(ax, zeros: list[tuple[list[float], str]], ymin_pos: float) -> None:
    """Exact zeros as open markers on the log axis' floor, a decade below the smallest value."""
    if not any(z for z, _ in zeros):
        return
    floor = ymin_pos / 10.0
    lo, hi = ax.get_ylim()
    ax.set_ylim(floor / 3.0, max(hi, ymin_pos * 10))
    first = True
    for xs, color in zeros:
        if xs:
            ax.plot(xs, [floor] * len(xs), "v", mfc="none", color=color, ms=6,
                    label=f"exactly 0 (drawn at {floor:.0e})" if first else None)
            first = False
    ax.axhline(floor, color="0.7", lw=0.5, ls="-")


def _finish(ax, legend: bool = True) -> None:
    ax.grid(True, which="both", alpha=0.3)
    if legend:
        ax.legend(fontsize=8, loc="best", framealpha=0.85)


def plot_gas(r: dict, out: Path, start, turn, end, fmt: str = "png") -> list[str]:
    """A gas run's figures in ``out``: round-trip error and energy drift against collisions,
    and snapshots; ``start``, ``turn``, ``end`` are (positions, velocities). Returns the paths."""
    plt = _pyplot()
    out.mkdir(parents=True, exist_ok=True)
    written = []
    title = short_title(r)

    fig, ax = plt.subplots(figsize=(7, 4.5))
    c = [p["collisions"] for p in r["curve"]]
    ex, ev = [p["error_x"] for p in r["curve"]], [p["error_v"] for p in r["curve"]]
    zeros = [(_log_series(ax, c, ex, "o", "positions: max |x - x0| / L", "C0"), "C0"),
             (_log_series(ax, c, ev, "s", "velocities: max |v - v0| / max |v0|", "C1"), "C1")]
    ax.axhline(BAR, color="k", ls=":", lw=1, label="bar 1e-9")
    _mark_zeros(ax, zeros, min([y for y in ex + ev if y > 0] + [BAR]))
    ax.set_xlabel("collisions forward (each point: forward to here, then back to the start)")
    ax.set_ylabel("round-trip error (relative)")
    ax.set_title(title, fontsize=9)
    _finish(ax)
    fig.tight_layout()
    written.append(_save(fig, out / f"roundtrip_error.{fmt}", plt, r))

    written.append(_energy_figure(r, out, plt, title, fmt, exact=False))
    written.append(_snapshots_figure(r, out, plt, title, start, turn, end, fmt))
    return written


def plot_lattice_gas(r: dict, out: Path, start, turn, end, fmt: str = "png") -> list[str]:
    """A lattice run's figures in ``out``: energy drift and the bits-back integers' excursion
    against collisions (the particles' X, bit lengths summed, less their start: sampled after each
    chunk of the forward run; the start itself, 128 bits a particle, is flat and says nothing),
    and snapshots; ``start``,
    ``turn``, ``end`` are (positions, velocities). There is no round-trip error curve: every
    round trip is bit for bit. Returns the paths."""
    plt = _pyplot()
    out.mkdir(parents=True, exist_ok=True)
    title = short_title(r)
    written = [_energy_figure(r, out, plt, title, fmt, exact=True)]

    fig, ax = plt.subplots(figsize=(7, 4.5))
    bs = np.array(r["bits_series"], dtype=float).reshape(-1, 2)
    x0, n = bs[0, 1], r.get("bits_back", {}).get("particles")
    at0 = f"{x0:,.0f} bits at the start" + (f", {x0 / n:.4g} per particle" if n else "")
    ax.axhline(0.0, color="0.6", lw=0.8)
    ax.plot(bs[:, 0], bs[:, 1] - x0, "o-" if len(bs) < 30 else "-", lw=1, ms=3,
            label=f"sum of the particles' X bit lengths, less its start ({at0})")
    ax.set_xlabel("collisions forward")
    ax.set_ylabel("bits-back integers: bits gained since the start")
    ax.set_title(title, fontsize=9)
    _finish(ax)
    fig.tight_layout()
    written.append(_save(fig, out / f"bits_back.{fmt}", plt, r))
    written.append(_snapshots_figure(r, out, plt, title, start, turn, end, fmt))
    return written


def _energy_figure(r: dict, out: Path, plt, title: str, fmt: str, exact: bool) -> str:
    """The energy's relative drift in units of the double's epsilon (float engine: round-off is
    all there is to see, and this is the scale on which it is visible), or the lattice
    engine's: an exact integer map of each pair that keeps its energy to the velocity lattice's
    resolution, a random walk of about 2^-30 of a pair's energy per collision (docs/lattice.md;
    a drift that is 0 at every sample is said so in words)."""
    fig, ax = plt.subplots(figsize=(7, 4.5))
    es = np.array(r["energy_series"], dtype=float).reshape(-1, 2)
    style = "o-" if len(es) < 30 else "-"
    if exact:
        ax.plot(es[:, 0], es[:, 1], style, lw=1, ms=3,
                label="(E - E0) / E0 (a walk at the velocity lattice's resolution; reversed exactly)")
        ax.set_ylabel("energy drift (E - E0) / E0")
        if not np.any(es[:, 1]):
            ax.text(0.5, 0.6, f"exactly 0 at all {len(es)} samples\n(integer energy)", transform=ax.transAxes,
                    ha="center", fontsize=9)
    else:
        ax.plot(es[:, 0], es[:, 1] / _EPS, style, lw=1, ms=3, label="(E - E0) / E0 in units of eps")
        ax.set_ylabel(f"energy drift (E - E0) / E0  [eps = {_EPS:.2e}]")
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_xlabel(f"collisions forward ({len(es)} samples)")
    ax.set_title(title, fontsize=9)
    _finish(ax)
    fig.tight_layout()
    return _save(fig, out / f"energy_drift.{fmt}", plt, r)


def _snapshots_figure(r: dict, out: Path, plt, title: str, start, turn, end, fmt: str) -> str:
    d, box = r["dimension"], np.asarray(r["box"], float)
    periodic = list(r.get("periodic", [False] * d))
    species = r["scene"].get("species") or []  # a mixture: (name, diameter, count, mass), ids in blocks
    sigma = np.concatenate([np.full(int(sp[2]), float(sp[1])) for sp in species]) if species else r["scene"]["diameter"]
    shots = [("start", *start), (f"after {r['collisions_forward']:,} collisions forward", *turn),
             ("after reversal", *end)]
    vmax = max(float(np.max(np.linalg.norm(np.asarray(v, float).reshape(len(v), -1), axis=1), initial=0.0))
               for _, _, v in shots) or 1.0
    wide = d >= 2 and box[0] >= 1.6 * box[1]
    fig, axes = plt.subplots(3 if wide else 1, 1 if wide else 3, figsize=(8, 9) if wide else (13, 4.6),
                             squeeze=False, constrained_layout=True)
    mappable = None
    for ax, (label, x, v) in zip(axes.ravel(), shots):
        x, v = np.asarray(x, float).reshape(len(x), -1), np.asarray(v, float).reshape(len(v), -1)
        if d == 1:
            mappable = _phase_space(ax, x, v, box, periodic, vmax)
        else:
            mappable = _disks(ax, x, v, box, periodic, sigma, vmax, d)
        ax.set_title(label, fontsize=9)
    if d == 1:
        view = "phase space: position against velocity"
    elif d == 3:
        view = f"slice |z - Lz/2| < D/2 through the middle (cross sections to scale, {_slice_count(start[0], box, sigma)} " \
               "spheres at the start)"
    else:
        view = "disks to scale"
    bounds = ", ".join(f"{'xyz'[k]}: {'periodic (dashed)' if periodic[k] else 'walls (solid)'}"
                       for k in range(min(d, 2)))
    if d == 3:  # the slice's own axis: not drawn, but named
        bounds += f", z: {'periodic' if periodic[2] else 'walls'}"
    fig.suptitle(f"{title}\n{view}; {bounds}", fontsize=9)
    if mappable is not None:
        fig.colorbar(mappable, ax=axes.ravel().tolist(), shrink=0.85, label="speed |v| / sqrt(kT / m)")
    return _save(fig, out / f"snapshots.{fmt}", plt, r)


def _slice_count(x, box, sigma) -> int:
    z = np.asarray(x, float)[:, 2]
    return int(np.count_nonzero(np.abs(z - 0.5 * box[2]) < 0.5 * np.asarray(sigma, float)))


def _edges(ax, box, periodic) -> None:
    """The box: walls as solid lines, periodic edges dashed."""
    lx, ly = box[0], box[1]
    for k, segs in ((0, [((0, 0), (0, ly)), ((lx, lx), (0, ly))]), (1, [((0, lx), (0, 0)), ((0, lx), (ly, ly))])):
        for xs, ys in segs:
            if periodic[k]:
                ax.plot(xs, ys, ls=(0, (4, 3)), color="0.45", lw=0.9)
            else:
                ax.plot(xs, ys, ls="-", color="k", lw=1.6)


def _disks(ax, x, v, box, periodic, sigma, vmax, d):
    from matplotlib.collections import EllipseCollection  # optional (the plot extra)

    speed = np.linalg.norm(v, axis=1)
    diam = np.broadcast_to(np.asarray(sigma, float), (len(x),)).copy()  # one per particle (a mixture)
    sigma = float(np.max(diam, initial=0.0))
    if d == 3:
        dz = x[:, 2] - 0.5 * box[2]
        keep = np.abs(dz) < 0.5 * diam
        x, speed = x[keep], speed[keep]
        diam = 2.0 * np.sqrt(np.maximum(0.25 * diam[keep] ** 2 - dz[keep] ** 2, 0.0))
    xy = x[:, :2]
    # periodic images of particles that cross a periodic edge, so the picture wraps as the box does
    imgs, cols, ds = [xy], [speed], [diam]
    for k in range(2):
        if periodic[k]:
            for sgn in (-1.0, 1.0):
                shift = np.zeros(2)
                shift[k] = sgn * box[k]
                near = (xy[:, k] < 0.5 * sigma) if sgn > 0 else (xy[:, k] > box[k] - 0.5 * sigma)
                imgs.append(xy[near] + shift)
                cols.append(speed[near])
                ds.append(diam[near])
    xy, speed, diam = np.concatenate(imgs), np.concatenate(cols), np.concatenate(ds)
    ec = EllipseCollection(diam, diam, 0.0, units="xy", offsets=xy, offset_transform=ax.transData,
                           cmap="viridis", linewidths=0, clim=(0.0, vmax))
    ec.set_array(speed)
    ax.add_collection(ec)
    _edges(ax, box, periodic)
    pad = 0.03 * max(box[0], box[1])
    ax.set_xlim(-pad, box[0] + pad)
    ax.set_ylim(-pad, box[1] + pad)
    ax.set_aspect("equal")
    ax.set_xlabel(f"x (length units; D = {sigma:g})")
    ax.set_ylabel(f"y (length units; D = {sigma:g})")
    return ec


def _phase_space(ax, x, v, box, periodic, vmax):
    speed = np.abs(v[:, 0])
    sc = ax.scatter(x[:, 0], v[:, 0], c=speed, s=6 if len(x) > 2000 else 14, cmap="viridis", vmin=0.0, vmax=vmax,
                    linewidths=0)
    for edge in (0.0, box[0]):
        if periodic[0]:
            ax.axvline(edge, ls=(0, (4, 3)), color="0.45", lw=0.9)
        else:
            ax.axvline(edge, ls="-", color="k", lw=1.6)
    ax.axhline(0.0, color="0.6", lw=0.5)
    ax.set_xlim(-0.03 * box[0], 1.03 * box[0])
    ax.set_ylim(-1.08 * vmax, 1.08 * vmax)
    ax.set_xlabel("x (length units)")
    ax.set_ylabel("velocity v_x")
    return sc


def plot_horizon(r: dict, out: Path, fmt: str = "png") -> list[str]:
    """The horizon's figure (horizon.<fmt> in ``out``); returns its path."""
    plt = _pyplot()
    out.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    pp = [row["per_particle"] for row in r["rows"]]
    ex, ev = [row["error_x"] for row in r["rows"]], [row["error_v"] for row in r["rows"]]
    zeros = [(_log_series(ax, pp, ex, "o", "positions: max |x - x0| / L", "C0", "loglog"), "C0"),
             (_log_series(ax, pp, ev, "s", "velocities: max |v - v0| / max |v0|", "C1", "loglog"), "C1")]
    values = ex + ev
    if r["seeds"] > 1:
        med = [row["median"] for row in r["rows"]]
        zeros.append((_log_series(ax, pp, med, "", "median over seeds (the larger of the two errors)", "0.5",
                                  "loglog"), "0.5"))
        values += med
    ax.axhline(BAR, color="k", ls=":", lw=1, label="bar 1e-9")
    if r["horizon_collisions"]:
        ax.axvline(r["horizon_per_particle"], color="C2", ls="--", lw=1,
                   label=f"horizon: {r['horizon_per_particle']:.3g} collisions per particle "
                         f"(N_c = {r['horizon_collisions']:,})")
    _mark_zeros(ax, zeros, min([y for y in values if y > 0] + [BAR]))
    ax.set_xlabel("collisions per particle (2 N_c / N), forward then back")
    ax.set_ylabel(f"round-trip error, relative (worst of {r['seeds']} seed{'s' if r['seeds'] > 1 else ''})")
    ax.set_title(short_title(r), fontsize=9)
    _finish(ax)
    fig.tight_layout()
    return [_save(fig, out / f"horizon.{fmt}", plt, r)]


def short_title(r: dict) -> str:
    """A figure's title: the scene's name and the few facts that tell its figures apart; the whole
    summary goes into the file's metadata (:func:`_save`)."""
    sc = r.get("scene", {})
    d, n = sc.get("dimension"), sc.get("particles")
    body = {1: "rods", 2: "disks", 3: "spheres"}.get(d, "particles")
    phi = f", phi = {sc['packing_fraction']:.3g}" if sc.get("packing_fraction") else ""
    engine = "lattice" if sc.get("engine") == "lattice" else "float"
    law = f"/{sc['law']}" if sc.get("mode") == "exact" and sc.get("law") else ""
    return f"{sc.get('name', 'scene')}: {n:,} {body} in {d}D{phi}, {engine} engine, {sc.get('mode', 'exact')}{law}" \
        if n and d else str(sc.get("name", "scene"))


def _save(fig, path: Path, plt, r: dict | None = None) -> str:
    meta = None
    if r is not None and r.get("summary"):  # the whole scene summary: out of the picture, in the file
        meta = {"Title": short_title(r),
                ("Subject" if path.suffix.lower() == ".pdf" else "Description"): r["summary"]}
    save_figure(fig, path, dpi=150, metadata=meta)
    plt.close(fig)
    return str(path)
