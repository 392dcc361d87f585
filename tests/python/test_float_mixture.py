"""The float engine's mixtures (``Simulation(..., diameters=...)``): the same API as the lattice
engine's (``diameters``, ``mixture``), forward and back within the round-off horizon in 1D, 2D
and 3D, checkpoints and pickles that resume bit for bit, the observer's species, scenes with
``[[species]]`` on either engine, and bad sizes refused by name with nothing built. The
equation of state against the lattice engine and the theory is in test_lattice_mixture.py
(test_equation_of_state_reduced, ``float_md``)."""
import pickle

import numpy as np
import pytest

from revcol import Simulation
from revcol.studies.mixture_eos import binary_diameters


@pytest.mark.parametrize("dim,phi,boundary", [(1, 0.5, "periodic"), (1, 0.5, "wall"), (2, 0.5, "periodic"),
                                              (2, 0.45, "bounce"), (3, 0.4, "periodic"), (3, 0.3, "wall")])
def test_round_trip_within_the_horizon(dim, phi, boundary):
    d = binary_diameters(400, 1.4)
    sim = Simulation.random(400, dim, phi, diameters=d, seed=4, boundary=boundary)
    assert sim.mixture and np.array_equal(sim.diameters, d)
    x0, v0 = sim.positions.copy(), sim.velocities.copy()
    sim.run(collisions=400)  # one per particle: inside the round-off horizon
    assert sim._e.fault() == ""
    sim.run_back(time=0.0)
    assert sim.collisions == 0
    assert np.abs(sim.positions - x0).max() < 1e-9 * sim.box.max()
    assert np.abs(sim.velocities - v0).max() < 1e-9
    sim.run(collisions=8000)  # 20 per particle: conserved, no pair inside its contact distance
    assert sim._e.fault() == ""
    assert abs(sim.diagnostics()["energy_drift"]) < 1e-12


def test_one_size_is_the_one_size_gas():
    one = Simulation.random(300, 2, 0.4, seed=6)
    mix = Simulation(one.positions, one.velocities, one.box, diameters=np.ones(300), seed=6)
    assert mix.mixture and not one.mixture and np.array_equal(one.diameters, np.ones(300))
    one.run(collisions=3000)
    mix.run(collisions=3000)
    assert np.array_equal(one.positions, mix.positions) and np.array_equal(one.velocities, mix.velocities)


def test_checkpoints_and_pickles_resume_bit_for_bit(tmp_path):
    sim = Simulation.random(500, 3, 0.35, diameters=binary_diameters(500, 1.4), seed=9, boundary="wall")
    sim.run(collisions=2000)
    sim.observe(block_time=0.05)
    sim.run(collisions=2000)
    sim.save(tmp_path / "m.npz")
    copy = pickle.loads(pickle.dumps(sim))
    snap = sim.snapshot()
    assert np.array_equal(snap["diameters"], sim.diameters)
    sim.run(collisions=5000)
    o = sim.observation()
    assert o.species_count.tolist() == [250, 250]
    assert sum(e.value for e in o.species_pressure) == pytest.approx(o.pressure_virial.value, rel=1e-12)
    for resumed in (Simulation.load(tmp_path / "m.npz"), copy, Simulation.from_snapshot(snap)):
        assert resumed.mixture
        resumed.run(collisions=5000)
        assert np.array_equal(resumed.positions, sim.positions)
        assert resumed.observation().to_dict() == o.to_dict()


def test_pairs_meet_at_their_own_contact_distance():
    # disks of 1 and 0.5, 0.8 apart: apart at their contact distance 0.75 (overlapping as two of 1)
    x = np.array([[2.0, 2.0], [2.8, 2.0], [4.5, 4.5]])
    v = np.array([[-1.0, 0.0], [1.0, 0.0], [0.0, 0.5]])
    sim = Simulation(x, v, [6.0, 6.0], diameters=[1.0, 0.5, 1.0])
    assert sim._e.diameter == 1.0
    # separating; around the ring 5.2 apart, closing at 2: contact at 0.75 when t = 2.225
    sim.run(time=2.224)
    assert sim.collisions == 0
    sim.run(time=2.226)
    assert sim.collisions == 1


@pytest.mark.parametrize("kwargs,what", [
    (dict(diameters=[1.0, 0.5]), "one entry per particle"),
    (dict(diameters=[1.0, 0.5, 1.0], diameter=2.0), "not both"),
    (dict(diameters=[1.0, 0.05, 1.0]), "16 times smaller"),
    (dict(diameters=[1.0, -0.5, 1.0]), "finite and > 0"),
    (dict(diameters=[1.0, 0.7, 1.0]), "contact distance 0.85"),
])
def test_bad_sizes_are_refused_by_name(kwargs, what):
    x = np.array([[2.0, 2.0], [2.8, 2.0], [4.5, 4.5]])
    v = np.array([[-1.0, 0.0], [1.0, 0.0], [0.0, 0.5]])
    with pytest.raises(ValueError, match=what):
        Simulation(x, v, [6.0, 6.0], **kwargs)


def test_a_species_scene_runs_on_the_float_engine(tmp_path):
    # (its trajectory's types and diameters: test_lattice_mixture.py, on both engines)
    from revcol.gas import build_simulation
    from revcol.scene import scene_from_dict
    doc = {"system": {"dimension": 2, "particles": 400, "packing_fraction": 0.35, "boundaries": "periodic"},
           "collisions": {"engine": "float"}, "run": {"collisions": 4000},
           "species": [{"name": "big", "diameter": 1.0, "fraction": 0.25},
                       {"name": "small", "diameter": 0.8, "fraction": 0.75}]}
    sim = build_simulation(scene_from_dict(doc, str(tmp_path / "mix.toml")))
    assert sim.engine == "float" and np.bincount((sim.diameters == 1.0).astype(int)).tolist() == [300, 100]
    sim.run(collisions=4000)
    assert sim._e.fault() == ""
    np.savez(tmp_path / "x.npz", positions=sim.positions, velocities=sim.velocities)
    doc["system"]["initial_state"] = str(tmp_path / "x.npz")  # a mixture takes a random start
    del doc["system"]["particles"], doc["system"]["packing_fraction"]
    doc["system"]["box"] = list(sim.box)
    from revcol.scene import SceneError
    with pytest.raises(SceneError, match="random start"):
        scene_from_dict(doc, str(tmp_path / "mix.toml"))


@pytest.mark.parametrize("dim,phi", [(2, 0.5), (3, 0.4)])
def test_masses_leave_the_statics_of_one_size(dim, phi, tmp_path):
    """Spheres of one size and masses 1 and 4: the equation of state is the one-size gas's
    (statics do not depend on the masses: within 3 block errors of Liu's), equipartition holds
    per species (within 4 block errors), sum m v and sum m v^2 / 2 are kept, and checkpoints
    and pickles resume bit for bit."""
    from revcol.studies.eos import liu_disks, liu_spheres
    m = np.where(np.arange(1000) % 2 == 0, 1.0, 4.0)
    sim = Simulation.random(1000, dim, phi, masses=m, seed=3)
    assert np.array_equal(sim.masses, m) and not sim.mixture
    p0 = (m[:, None] * sim.velocities).sum(0)
    sim.run(collisions=60_000)
    sim.observe(block_time=0.05)
    sim.run(collisions=100_000)
    sim.save(tmp_path / "m.npz")
    copy = pickle.loads(pickle.dumps(sim))
    sim.run(collisions=200_000)
    o = sim.observation()
    assert np.abs((m[:, None] * sim.velocities).sum(0) - p0).max() < 1e-10
    assert abs(sim.diagnostics()["energy_drift"]) < 1e-12
    z = liu_spheres(phi) if dim == 3 else liu_disks(phi)
    assert abs(o.compressibility.value - z) < 3.0 * o.compressibility.error, (o.compressibility, z)
    assert o.species_mass.tolist() == [1.0, 4.0] and o.species_count.tolist() == [500, 500]
    (t1, e1), (t4, e4) = [(e.value, e.error) for e in o.species_temperature]
    assert abs(t1 - t4) < 4.0 * np.hypot(e1, e4), o.species_temperature
    assert any("m=4" in line for line in o.lines())
    for resumed in (Simulation.load(tmp_path / "m.npz"), copy):
        resumed.run(collisions=200_000)
        assert np.array_equal(resumed.velocities, sim.velocities)
        assert resumed.observation().to_dict() == o.to_dict()


def test_masses_are_checked_by_name_and_scenes_carry_them(tmp_path):
    x = np.array([[2.0, 2.0], [4.0, 2.0], [4.5, 4.5]])
    v = np.array([[-1.0, 0.0], [1.0, 0.0], [0.0, 0.5]])
    for masses, what in [([1.0, 2.0], "one entry per particle"), ([1.0, -2.0, 1.0], "finite and > 0"),
                         ([1.0, 1e7, 1.0], "ratio")]:
        with pytest.raises(ValueError, match=what):
            Simulation(x, v, [6.0, 6.0], masses=masses)
    with pytest.raises(ValueError, match="paper mode collides equal masses only"):
        Simulation(x, v, [6.0, 6.0], masses=[1.0, 2.0, 1.0], mode="paper")
    from revcol.gas import build_simulation
    from revcol.scene import SceneError, scene_from_dict, with_engine
    doc = {"system": {"dimension": 2, "particles": 400, "packing_fraction": 0.3, "boundaries": "periodic"},
           "collisions": {"engine": "float"}, "run": {"collisions": 4000},
           "species": [{"name": "light", "diameter": 1.0, "fraction": 0.5},
                       {"name": "heavy", "diameter": 1.0, "mass": 9.0, "fraction": 0.5}]}
    scene = scene_from_dict(doc, str(tmp_path / "m.toml"))
    sim = build_simulation(scene)
    assert sorted(set(sim.masses.tolist())) == [1.0, 9.0]
    with pytest.raises(SceneError, match=r"mass: unequal masses run on engine = 'float' only.*--engine lattice"):
        with_engine(scene, "lattice")
    doc["collisions"]["engine"] = "lattice"
    with pytest.raises(SceneError, match=r"\[\[species\]\] mass: unequal masses"):
        scene_from_dict(doc, str(tmp_path / "m.toml"))
