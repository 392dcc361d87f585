"""The 2D lattice engine from Python (revcol.lattice): forward and back bit for bit, midpoint
reversal, checkpoints through save/load, diagnostics, float starts and bad input."""
import numpy as np
import pytest

from revcol.lattice import LatticeSimulation


def _same(a: dict, b: dict) -> bool:
    keys = ["clock", "origin", "collisions", "x", "v", "streams", "bits", "log_index", "log_redraws",
            "group_index", "group_drawer", "group_size", "group_members", "seed", "law"]
    return all(np.array_equal(np.asarray(a[k]), np.asarray(b[k])) for k in keys)


@pytest.mark.parametrize("phi,boundary", [(0.3, "periodic"), (0.5, "wall")])
def test_round_trip_bit_for_bit(phi, boundary):
    sim = LatticeSimulation.random(n=150, phi=phi, boundary=boundary, seed=3)
    s0 = sim.state()
    r = sim.run(collisions=150 * 50)
    assert r["collisions"] == 150 * 50 and sim.collisions == 150 * 50
    assert not np.array_equal(sim.lattice_positions, s0["x"])
    back = sim.run_back()
    assert back["collisions"] == 150 * 50
    assert _same(sim.state(), s0)
    assert sim.clock == s0["clock"]
    d = sim.diagnostics()
    assert d["bits_length"] == 256 and d["log_entries"] == 0 and d["energy_drift"] == 0.0


def test_midpoint_and_time_reversal_equal_the_forward_states():
    sim = LatticeSimulation.random(n=120, phi=0.4, seed=5)
    sim.run(collisions=3000)
    mid = sim.state()
    t_mid = sim.time
    sim.run(collisions=3000)
    sim.run_back(to_collision=3000)
    assert _same(sim.state(), mid)
    sim.run(collisions=1000)
    sim.run_back(time=t_mid)
    assert sim.clock == mid["clock"]
    assert np.array_equal(sim.lattice_positions, mid["x"])
    assert np.array_equal(sim.lattice_velocities, mid["v"])
    sim.run_back(collisions=1000)
    assert sim.collisions == 2000


def test_save_load_resumes_bit_for_bit(tmp_path):
    sim = LatticeSimulation.random(n=100, phi=0.5, boundary=["wall", "periodic"], seed=7)
    sim.run(collisions=2000)
    path = tmp_path / "lattice.npz"
    sim.save(path)
    other = LatticeSimulation.load(path)
    assert _same(other.state(), sim.state())
    sim.run(collisions=2000)
    other.run(collisions=2000)
    assert _same(other.state(), sim.state())
    other.run_back()
    assert other.collisions == 0 and other.clock == 0


def test_float_start_quantized_once_and_reported():
    rng = np.random.default_rng(1)
    x = np.array([[1.0, 1.0], [3.0, 1.2], [1.5, 3.7], [3.9, 3.9]])
    v = rng.normal(size=(4, 2))
    sim = LatticeSimulation(x, v, box=6.0)
    q = sim.quantization
    assert 0.0 <= q["max_position_error"] < 1e-15
    assert 0.0 <= q["max_velocity_error"] < 1e-9
    assert np.allclose(sim.positions, x, atol=1e-12)
    assert np.allclose(sim.velocities, v, rtol=1e-9, atol=1e-9)
    assert sim.units["sigma"] == 2 ** sim.units["S"]


def test_bad_input_is_refused_and_changes_nothing():
    with pytest.raises(ValueError, match="overlap"):
        LatticeSimulation([[1.0, 1.0], [1.5, 1.0]], [[1.0, 0.0], [0.0, 0.0]], box=6.0)
    with pytest.raises(ValueError, match="too long"):
        LatticeSimulation([[1.0, 1.0], [5.0, 1.0]], [[1.0, 0.0], [0.0, 1.0]], box=1e8)
    with pytest.raises(ValueError, match="2D"):
        LatticeSimulation.random(n=10, dim=3)
    sim = LatticeSimulation.random(n=60, phi=0.3, seed=2)
    sim.run(collisions=300)
    s = sim.state()
    with pytest.raises(ValueError, match="only 300"):
        sim.run_back(collisions=301)
    with pytest.raises(ValueError, match="target tick"):
        sim.run_back(time=sim.time * 2 + 1.0)
    with pytest.raises(ValueError, match="before the clock"):
        sim.run(time=0.0)
    bad = dict(s)
    bad["x"] = np.array(s["x"])
    bad["x"][1] = bad["x"][0]
    with pytest.raises(ValueError, match="overlap"):
        LatticeSimulation.from_state(bad)
    assert _same(sim.state(), s)
