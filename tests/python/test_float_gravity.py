"""The float engine under a uniform field (``Simulation(..., gravity=...)``): the API and its
checks, energy with the potential term, checkpoints that resume bit for bit, and sedimentation
against hydrostatic equilibrium with the equation of state (the study at reduced length; the
full runs are bench/results/sedimentation.json). The C++ side (an exact parabola, round trips,
refusals) is tests/cpp/test_engine_mixture.cpp."""
import pickle

import numpy as np
import pytest

from revcol import Simulation


def test_gravity_api_energy_and_checkpoints(tmp_path):
    sim = Simulation.random(300, 2, 0.2, boundary=["periodic", "wall"], gravity=[0.0, -0.5], seed=4)
    assert np.array_equal(sim.gravity, [0.0, -0.5])
    d0 = sim.diagnostics()
    assert d0["potential"] > 0.0 and d0["energy"] > d0["potential"]
    sim.run(collisions=3000)
    assert abs(sim.diagnostics()["energy_drift"]) < 1e-12
    sim.save(tmp_path / "g.npz")
    copy = pickle.loads(pickle.dumps(sim))
    assert np.array_equal(sim.snapshot()["gravity"], [0.0, -0.5])
    sim.run(collisions=3000)
    for resumed in (Simulation.load(tmp_path / "g.npz"), copy):
        assert np.array_equal(resumed.gravity, sim.gravity)
        resumed.run(collisions=3000)
        assert np.array_equal(resumed.positions, sim.positions)
        assert np.array_equal(resumed.velocities, sim.velocities)
    x = np.array([[2.0, 2.0], [5.0, 5.0]])
    v = np.array([[1.0, 0.0], [0.0, 1.0]])
    with pytest.raises(ValueError, match="needs walls on that axis"):
        Simulation(x, v, [10.0, 10.0], gravity=[0.0, -1.0])
    with pytest.raises(ValueError, match="one component per axis"):
        Simulation(x, v, [10.0, 10.0], boundary="wall", gravity=[-1.0])


def test_the_observer_follows_the_parabolas(tmp_path):
    """Observed in a field: the column's profile (denser below, every particle in a slab), the
    kinetic energy's time average against frames', and a checkpoint that resumes the observation
    to the same bits. The exact checks (a worked drop, the virial with the field's term) are
    tests/cpp/test_float_field_observe.cpp."""
    sim = Simulation.random(300, 2, 0.2, boundary=["periodic", "wall"], gravity=[0.0, -0.5], seed=8)
    sim.run(collisions=2000)
    sim.observe(slabs=6, slab_axis=1)
    kin, t0 = 0.0, sim.time
    k_prev, t_prev = 0.5 * float((sim.velocities ** 2).sum()), sim.time
    for q in range(100):
        sim.run(collisions=20)
        k = 0.5 * float((sim.velocities ** 2).sum())
        kin += 0.5 * (k + k_prev) * (sim.time - t_prev)
        k_prev, t_prev = k, sim.time
        if q == 49:
            sim.save(tmp_path / "mid.npz")
    o = sim.observation()
    assert o.temperature.value == pytest.approx(kin / (300 * (sim.time - t0)), rel=1e-5)  # trapezoids: ~1e-7
    assert o.slab_density.value[0] > o.slab_density.value[-1]
    assert np.sum(o.slab_density.value) * np.prod(sim.box) / 6 == pytest.approx(300, rel=1e-9)
    r = Simulation.load(tmp_path / "mid.npz")
    for _ in range(50):
        r.run(collisions=20)  # the same calls: each run's end closes every flight
    for key in ("observer", "observer_counts"):
        assert np.array_equal(np.asarray(r.snapshot()[key]), np.asarray(sim.snapshot()[key]))
    # two masses: the kinetic energy's average is of m v^2 / 2, the species are by mass
    heavy = Simulation.random(200, 2, 0.2, boundary=["periodic", "wall"], gravity=[0.0, -0.5], masses=[1.0, 3.0] * 100,
                              seed=2)
    heavy.run(collisions=1000)
    heavy.observe()
    m = np.array([1.0, 3.0] * 100)[:, None]
    kin, t0 = 0.0, heavy.time
    k_prev, t_prev = 0.5 * float((m * heavy.velocities ** 2).sum()), heavy.time
    for _ in range(100):
        heavy.run(collisions=20)
        k = 0.5 * float((m * heavy.velocities ** 2).sum())
        kin += 0.5 * (k + k_prev) * (heavy.time - t_prev)
        k_prev, t_prev = k, heavy.time
    o = heavy.observation()
    assert o.temperature.value == pytest.approx(kin / (200 * (heavy.time - t0)), rel=1e-5)
    assert list(o.species_mass) == [1.0, 3.0]


@pytest.mark.parametrize("dim,width,seed", [(2, 100.0, 1), (3, 20.0, 2)])
def test_sedimentation_follows_the_equation_of_state(dim, width, seed):
    """400 particles dropped in a box 60 tall (g = 1): the centres' mean height above 2 D within
    3 combined errors of hydrostatic equilibrium with the equation of state (LDA; bottom packing
    fraction 0.16 in 2D), far from the barometric law of an ideal gas, energy kept."""
    from revcol.studies.sedimentation import measure
    r = measure(dim, 400, width, 60.0, 1.0, seed=seed, settle=200.0, frames=1500)
    assert abs(r["lda_deviation_sd"]) < 3.0, r
    assert abs(r["barometric_deviation_sd"]) > 10.0, r
    assert abs(r["energy_drift"]) < 1e-12


def test_frames_of_a_column_take_the_observers_image_flags():
    """A float run in a field that writes frames of a periodic box observes for their image flags
    (observes_frames), as an unsheared run does: whole box lengths across the periodic axis, none
    on the field's walled one."""
    from pathlib import Path

    from revcol.scene import load_scene, observes_frames
    from revcol.trajectory import true_images
    scene = load_scene(str(Path(__file__).resolve().parents[2] / "scenes" / "sedimentation.toml"))
    assert scene.gravity and scene.engine == "float" and observes_frames(scene, "t.xyz")
    sim = Simulation.random(200, 2, 0.2, boundary=["periodic", "wall"], gravity=[0.0, -0.5], seed=3)
    sim.observe()
    sim.run(collisions=4000)
    image = true_images(sim)
    box = np.asarray(sim.box)
    assert np.abs(image[:, 1]).max() == 0 and np.abs(image[:, 0]).max() > 0
    assert np.abs(sim._e.observed_positions() - sim.positions - image * box).max() < 1e-9
