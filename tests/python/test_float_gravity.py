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
    with pytest.raises(ValueError, match="not observed yet"):
        sim.observe()
    x = np.array([[2.0, 2.0], [5.0, 5.0]])
    v = np.array([[1.0, 0.0], [0.0, 1.0]])
    with pytest.raises(ValueError, match="needs walls on that axis"):
        Simulation(x, v, [10.0, 10.0], gravity=[0.0, -1.0])
    with pytest.raises(ValueError, match="one component per axis"):
        Simulation(x, v, [10.0, 10.0], boundary="wall", gravity=[-1.0])


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
