"""Relaxed random starts (init "relax"; engine/init.hpp): mixtures denser than the crystal of
their largest size (which bounds a 1:1 mixture of size ratio 1.4 near 0.5 in 3D and 0.62 in 2D),
placed at random at their own sizes with the overlaps relaxed away; on both engines, from Python
and from scenes, run forward and (lattice) back bit for bit; refused by name at jamming; Ctrl-C
stops a long relaxation."""
import numpy as np
import pytest

import revcol
from revcol import Simulation
from revcol._core import engine_limits
from revcol.lattice import LatticeSimulation, LatticeSimulation3D
from revcol.scene import SceneError, scene_from_dict
from revcol.studies.mixture_eos import binary_diameters

from conftest import interrupt_child


def _min_gap(x, d, box, periodic):
    """The smallest pair distance over its contact distance (nearest images on periodic axes)."""
    dx = x[:, None, :] - x[None, :, :]
    for k, p in enumerate(periodic):
        if p:
            dx[..., k] -= box[k] * np.round(dx[..., k] / box[k])
    r = np.sqrt((dx**2).sum(-1)) / (0.5 * (d[:, None] + d[None, :]))
    np.fill_diagonal(r, np.inf)
    return r.min()


@pytest.mark.parametrize("cls,phi", [(LatticeSimulation, 0.80), (LatticeSimulation3D, 0.58)])
def test_a_dense_mixture_starts_relaxed_and_runs_back_bit_for_bit(cls, phi):
    d = binary_diameters(300, 1.4)
    sim = cls.random(300, phi=phi, diameters=d, seed=4)  # "auto": past the largest's crystal, relaxed
    dim = 3 if cls is LatticeSimulation3D else 2
    own = np.sum((np.pi / 6 * sim.diameters**3) if dim == 3 else (np.pi / 4 * sim.diameters**2))
    assert own == pytest.approx(phi * np.prod(sim.box), rel=1e-9)
    assert _min_gap(sim.positions, sim.diameters, sim.box, [True] * dim) > 1.0009  # 1 + 1e-3, less the rounding
    x0, v0 = sim.lattice_positions.copy(), sim.lattice_velocities.copy()
    sim.run(collisions=3000)
    sim.run_back()
    assert np.array_equal(sim.lattice_positions, x0) and np.array_equal(sim.lattice_velocities, v0)
    relaxed = cls.random(300, phi=phi, diameters=d, seed=4, init="relax")
    assert np.array_equal(relaxed.lattice_positions, x0)  # "auto" went the relaxed way


def test_the_float_engine_and_one_size_relax_too():
    d = binary_diameters(400, 1.4)
    s = Simulation.random(400, 2, 0.80, diameters=d, seed=2, boundary=["periodic", "wall"])
    y = s.positions[:, 1]
    assert (y >= 0.5 * s.diameters).all() and (y <= s.box[1] - 0.5 * s.diameters).all()
    assert _min_gap(s.positions, s.diameters, s.box, [True, False]) >= 1.001 * (1 - 1e-12)
    s.run(collisions=5000)
    assert abs(s.diagnostics()["energy_drift"]) < 1e-12
    one = Simulation.random(400, 3, 0.55, init="relax", seed=3)  # amorphous, not the crystal
    assert _min_gap(one.positions, np.ones(400), one.box, [True] * 3) >= 1.001 * (1 - 1e-12)
    assert not np.array_equal(one.positions, Simulation.random(400, 3, 0.55, init="crystal", seed=3).positions)
    assert engine_limits()["max_relax_fraction"] == {1: 0.95, 2: 0.88, 3: 0.68}
    # one size in a cube: a relaxed start has the relaxed bound, as in a given box (the crystal's is 0.75 in 2D)
    disks = Simulation.random(300, 2, 0.8, init="relax", seed=4)
    assert _min_gap(disks.positions, np.ones(300), disks.box, [True, True]) >= 1.001 * (1 - 1e-12)
    with pytest.raises(ValueError, match=r"above what the initialiser reaches \(0\.75 in 2D\)"):
        Simulation.random(300, 2, 0.8, init="crystal", seed=4)


def test_scenes_take_a_relaxed_start_and_dense_species():
    from revcol.gas import build_simulation
    from revcol.lattice_gas import build_lattice
    import tomllib
    species = ("[[species]]\nname = \"big\"\ndiameter = 1.0\nfraction = 0.5\n"
               "[[species]]\nname = \"small\"\ndiameter = 0.714285714\nfraction = 0.5\n")
    dense = tomllib.loads("[system]\ndimension = 2\nparticles = 300\npacking_fraction = 0.8\nboundaries = \"periodic\"\n"
                          "[collisions]\nengine = \"lattice\"\n[run]\ncollisions = 1000\n" + species)
    lat = build_lattice(scene_from_dict(dense, "glass.toml"))
    assert lat.mixture and _min_gap(lat.positions, lat.diameters, lat.box, [True, True]) > 1.0009
    # a given box: the species' own diameters reach the start (0.77 of the box at their sizes)
    boxed = tomllib.loads("[system]\ndimension = 2\nparticles = 400\nbox = [20.0, 20.0]\n"
                          "boundaries = \"periodic\"\n[run]\ncollisions = 1000\n" + species.replace("0.714285714", "0.72"))
    flt = build_simulation(scene_from_dict(boxed, "boxed.toml"))
    assert _min_gap(flt.positions, flt.diameters, flt.box, [True, True]) >= 1.001 * (1 - 1e-12)
    one = tomllib.loads("[system]\ndimension = 3\nparticles = 300\npacking_fraction = 0.55\nboundaries = \"periodic\"\n"
                        "start = \"relax\"\n[run]\ncollisions = 1000\n")
    s = build_simulation(scene_from_dict(one, "one.toml"))
    assert _min_gap(s.positions, np.ones(300), s.box, [True] * 3) >= 1.001 * (1 - 1e-12)
    dense["system"]["packing_fraction"] = 0.9
    with pytest.raises(SceneError, match=r"packing_fraction: must be at most 0\.88 in 2D for a relaxed start"):
        scene_from_dict(dense, "too-dense.toml")


def test_jamming_and_bad_names_are_refused_by_name():
    d = binary_diameters(200, 1.4)
    with pytest.raises(ValueError, match="did not relax away .* jamming"):
        LatticeSimulation3D.random(200, phi=0.67, diameters=d, seed=1)
    with pytest.raises(ValueError, match="above what a relaxed random start reaches"):
        Simulation.random(200, 3, 0.7, diameters=d, seed=1)
    with pytest.raises(ValueError, match="init must be 'auto', 'rsa', 'crystal' or 'relax'"):
        Simulation.random(200, 3, 0.4, init="relaxed", seed=1)


RELAX_CHILD = r"""
import revcol
from revcol.studies.mixture_eos import binary_diameters
print("ready", flush=True)
try:  # past jamming: thousands of steps over 20 000 spheres before it gives up
    revcol.Simulation.random(20000, 3, 0.67, diameters=binary_diameters(20000, 1.4), seed=1)
    print("finished", flush=True)
except KeyboardInterrupt:
    print("interrupted", flush=True)
"""


def test_ctrl_c_stops_a_relaxation(tmp_path):
    rc, text = interrupt_child(tmp_path, RELAX_CHILD, [], after_s=1.0, wait_s=30)
    assert rc == 0 and "interrupted" in text and "finished" not in text, text


@pytest.mark.parametrize("engine", ["lattice", "float"])
def test_the_glass_scene_runs_and_draws_its_species(tmp_path, capsys, engine):
    # the shipped scene, reduced: its relaxed start, the run and back, and the figures, whose
    # snapshot draws each particle at its species' size (a species' mass broke that drawing)
    import tomllib
    from conftest import run_cli
    from revcol.scene import find_scene
    doc = tomllib.loads(find_scene("lattice-glass-2d").read_text())
    assert doc["system"]["start"] == "relax" and doc["system"]["packing_fraction"] == 0.80
    text = find_scene("lattice-glass-2d").read_text().replace("count = 1000", "count = 150")
    # (the float engine returns within its horizon, a few collisions per particle: 2 here)
    runs = "3000" if engine == "lattice" else "300"
    text = text.replace("collisions = 2000000", f"collisions = {runs}").replace('engine = "lattice"', f'engine = "{engine}"')
    (tmp_path / "glass.toml").write_text(text)
    rc, err = run_cli(tmp_path, ["run", "glass.toml"], capsys)
    assert rc == 0, err
    figures = tmp_path / "out" / "lattice-glass-2d" / "figures"
    assert any(p.name.startswith("snapshot") for p in figures.iterdir()), sorted(p.name for p in figures.iterdir())
