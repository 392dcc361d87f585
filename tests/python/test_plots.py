"""The figures of ``revcol run --plot`` (issue 19: figures worth putting in a paper): file
formats, the views of 1D and 3D gases, periodic edges drawn as such, and log axes that mark
exact zeros instead of inventing a value."""
from __future__ import annotations

import pytest

pytest.importorskip("matplotlib")
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from revcol import plots  # noqa: E402
from revcol.cli.main import main as cli_main  # noqa: E402
from revcol.gas import run_gas  # noqa: E402
from revcol.scene import SceneError, scene_from_dict  # noqa: E402

MAGIC = {"png": b"\x89PNG\r\n\x1a\n", "pdf": b"%PDF-", "svg": b"<?xml"}


def gas(d=2, boundary=None, particles=60, collisions=120):
    system = {"dimension": d, "particles": particles, "packing_fraction": 0.2 if d > 1 else 0.3}
    if boundary is not None:
        system["boundaries"] = boundary
    doc = {"system": system, "rng": {"generator": "philox", "seed": 3}, "run": {"collisions": collisions}}
    return scene_from_dict(doc, "small.toml", None)


@pytest.mark.parametrize("fmt", ["png", "pdf", "svg"])
def test_formats(tmp_path, fmt):
    r = run_gas(gas(), plot=tmp_path, progress=False, plot_format=fmt)
    names = {p.rsplit("/", 1)[-1] for p in r["written"]}
    assert names == {f"roundtrip_error.{fmt}", f"energy_drift.{fmt}", f"snapshots.{fmt}"}
    for n in names:
        assert (tmp_path / n).read_bytes()[: len(MAGIC[fmt])] == MAGIC[fmt]


def test_bad_format_is_named_before_the_run(tmp_path):
    with pytest.raises(SceneError, match="plot-format.*png, pdf, svg"):
        run_gas(gas(), plot=tmp_path, progress=False, plot_format="jpeg")
    assert not any(tmp_path.iterdir())
    with pytest.raises(SystemExit):
        cli_main(["run", "--plot", str(tmp_path), "--plot-format", "jpeg"])


def _snapshot_axes(monkeypatch):
    """Runs the scene with --plot and returns the snapshot figure's axes (kept open)."""
    kept = {}
    real = plots._save

    def keep(fig, path, plt_, r=None):
        if path.name.startswith("snapshots"):
            kept["fig"] = fig
            plots.save_figure(fig, path)
            return str(path)
        return real(fig, path, plt_, r)

    monkeypatch.setattr(plots, "_save", keep)
    return kept


def test_periodic_edges_dashed_walls_solid_and_a_colourbar(tmp_path, monkeypatch):
    kept = _snapshot_axes(monkeypatch)
    r = run_gas(gas(boundary=["periodic", "wall"]), plot=tmp_path, progress=False)
    assert r["periodic"] == [True, False]
    fig = kept["fig"]
    panels = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]
    assert len(panels) == 3 and len(fig.axes) == 4  # three snapshots and one colourbar
    assert fig.axes[-1].get_ylabel() == "speed |v| / sqrt(kT / m)"
    ax = panels[0]
    assert ax.get_xlabel().startswith("x (length units") and ax.get_ylabel().startswith("y (length units")
    styles = {}
    for line in ax.get_lines():
        xs, ys = line.get_xdata(), line.get_ydata()
        vertical = xs[0] == xs[1]
        styles.setdefault("x" if vertical else "y", set()).add(line.get_linestyle())
    assert styles["x"] == {"--"}  # periodic x: the left and right edges dashed
    assert styles["y"] == {"-"}   # walls in y: solid
    plt.close(fig)


def test_1d_phase_space_and_3d_slice(tmp_path, monkeypatch):
    kept = _snapshot_axes(monkeypatch)
    run_gas(gas(d=1, particles=40), plot=tmp_path / "a", progress=False)
    ax = kept["fig"].axes[0]
    assert ax.get_ylabel() == "velocity v_x"  # phase space, not a line of rods
    assert len(ax.collections[0].get_offsets()) == 40
    plt.close(kept["fig"])
    r = run_gas(gas(d=3, particles=200), plot=tmp_path / "b", progress=False)
    fig = kept["fig"]
    assert "slice |z - Lz/2| < D/2" in fig._suptitle.get_text()
    assert np.asarray(r["box"]).shape == (3,)
    # the spheres drawn are those cut by the middle plane (and their periodic images): fewer than all
    drawn = len(fig.axes[0].collections[0].get_offsets())
    assert 0 < drawn < 200
    plt.close(fig)


def test_log_axes_mark_exact_zeros(tmp_path, monkeypatch):
    kept = {}
    monkeypatch.setattr(plots, "_save", lambda fig, path, plt_, r=None: kept.setdefault("fig", fig) and str(path))
    r = {"summary": "synthetic", "seeds": 1, "horizon_collisions": None, "horizon_per_particle": None,
         "rows": [{"per_particle": 1.0, "error_x": 0.0, "error_v": 0.0},
                  {"per_particle": 2.0, "error_x": 3e-14, "error_v": 0.0},
                  {"per_particle": 4.0, "error_x": 5e-12, "error_v": 1e-15}]}
    plots.plot_horizon(r, tmp_path)
    ax = kept["fig"].axes[0]
    lines = {ln.get_label(): ln for ln in ax.get_lines()}
    zero = next(ln for lab, ln in lines.items() if lab.startswith("exactly 0"))
    # drawn a decade below the smallest positive value (1e-15), never at a made-up 1e-18
    assert np.allclose(zero.get_ydata(), 1e-16)
    assert lines["positions: max |x - x0| / L"].get_xdata().tolist() == [2.0, 4.0]
    on_floor = {float(x) for ln in ax.get_lines() if ln.get_marker() == "v" for x in ln.get_xdata()}
    assert on_floor == {1.0, 2.0}  # positions exactly 0 at 1; velocities at 1 and 2
    plt.close(kept["fig"])
