"""revcol.lattice.LatticeSimulation3D (issue 14): a sphere gas on the integer lattice, forward and
back bit for bit, snapshots, checkpoints and pickles, bad input; the 2D LatticeSimulation is
tested by test_lattice.py and is unchanged."""
from __future__ import annotations

import pickle

import numpy as np
import pytest

from revcol import _core
from revcol.lattice import LatticeSimulation, LatticeSimulation3D


def _state(sim: LatticeSimulation):
    s = sim.snapshot()
    return (s["x"].copy(), s["v"].copy(), s["streams"].copy(), s["bits"].copy(), s["bits_size"].copy(), int(s["clock"]),
            int(s["collisions"]), s["particle_collisions"].copy(), s["log_particle"].copy(), s["log_count"].copy(),
            s["group_counts"].copy())


def _same(a, b) -> bool:
    return all(np.array_equal(p, q) if isinstance(p, np.ndarray) else p == q for p, q in zip(a, b))


@pytest.mark.parametrize("boundary", ["periodic", "wall", ["periodic", "periodic", "wall"]])
def test_forward_midpoint_and_back_bit_for_bit(boundary):
    sim = LatticeSimulation3D.random(n=200, phi=0.3, boundary=boundary, seed=4)
    assert sim.dim == 3
    assert sim.lattice_positions.shape == (200, 3) and sim.lattice_velocities.dtype == np.int64
    s0 = _state(sim)
    assert sim.run(collisions=3000)["collisions"] == 3000
    mid = _state(sim)
    sim.run(collisions=3000)
    end = _state(sim)
    assert not _same(end, s0)
    d = sim.diagnostics()
    assert abs(d["energy_drift"]) < 1e-8 and len(d["momentum_drift"]) == 3
    if boundary != "periodic":
        assert d["walls"] > 0
    sim.run_back(to_collision=3000)
    assert _same(_state(sim), mid)
    sim.run_back()
    assert _same(_state(sim), s0)
    assert sim.collisions == 0


def test_snapshot_save_load_pickle_resume_bit_for_bit(tmp_path):
    sim = LatticeSimulation3D.random(n=108, phi=0.45, seed=2)  # 4 x 3^3 FCC sites
    sim.run(collisions=2000)
    snap = sim.snapshot()
    assert int(snap["dim"]) == 3 and len(snap["units"]["L"]) == 3 and snap["momentum0"].shape == (6,)
    path = tmp_path / "gas3d.npz"
    sim.save(path)
    # a 3D snapshot makes a 3D simulation, whichever class reads it
    copies = [LatticeSimulation.from_snapshot(snap), LatticeSimulation3D.load(path), pickle.loads(pickle.dumps(sim))]
    sim.run(collisions=1500)
    want = _state(sim)
    for c in copies:
        assert isinstance(c, LatticeSimulation3D) and c.dim == 3
        c.run(collisions=1500)
        assert _same(_state(c), want)
        c.run_back()
        assert c.collisions == 0
    assert repr(sim).startswith("LatticeSimulation3D(n=108")


def test_float_arrays_make_a_3d_gas_quantized_once():
    x = np.array([[1.0, 1.0, 1.0], [3.0, 1.0, 1.0], [1.0, 3.0, 4.0], [4.0, 4.0, 2.0]])
    v = np.array([[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, -1.0], [0.0, -1.0, 1.0]])
    sim = LatticeSimulation3D(x, v, [5.0, 5.0, 5.5], boundary="periodic", seed=3)
    assert sim.dim == 3 and sim.n == 4
    assert np.allclose(sim.positions, x, atol=1e-12)
    assert sim.quantization["max_position_error"] < 1e-12
    s0 = _state(sim)
    sim.run(collisions=50)
    sim.run_back()
    assert _same(_state(sim), s0)


def test_bad_input_is_refused_with_a_named_error():
    with pytest.raises(ValueError, match="LatticeSimulation3D"):
        LatticeSimulation.random(n=50, dim=3, phi=0.1)
    with pytest.raises(ValueError, match="is 3D"):
        LatticeSimulation3D.random(n=50, dim=2, phi=0.1)
    with pytest.raises(ValueError, match="one name or 3"):
        LatticeSimulation3D.random(n=50, phi=0.1, boundary=["wall", "periodic"])
    with pytest.raises(ValueError, match="one length or three"):
        LatticeSimulation3D(np.zeros((2, 3)), np.zeros((2, 3)), [5.0, 5.0])
    with pytest.raises(ValueError, match=r"\(n, 3\)"):
        LatticeSimulation3D(np.zeros((2, 2)), np.zeros((2, 2)), 6.0)
    with pytest.raises(ValueError, match="overlap"):
        LatticeSimulation3D(np.array([[1.0, 1.0, 1.0], [1.5, 1.0, 1.0]]), np.ones((2, 3)), 6.0)
    sim = LatticeSimulation3D.random(n=100, phi=0.2, seed=1)
    snap = sim.snapshot()
    bad = dict(snap)
    bad["x"] = snap["x"][:, :2].copy()
    with pytest.raises(ValueError, match=r"\(n, 3\)"):
        LatticeSimulation.from_snapshot(bad)
    bad = dict(snap)
    bad["momentum0"] = snap["momentum0"][:4].copy()
    with pytest.raises(ValueError, match="momentum0 6"):
        LatticeSimulation.from_snapshot(bad)
    with pytest.raises(ValueError, match="dim must be 3"):
        _core.LatticeEngine3D.from_snapshot({k: v for k, v in snap.items() if k != "quantization"} | {"dim": 2})
    # a 2D checkpoint is not a 3D one: its (n, 2) arrays are refused by the 3D engine
    snap2 = LatticeSimulation.random(n=100, phi=0.2, seed=1).snapshot()
    assert "dim" not in snap2  # the 2D checkpoint format is unchanged
    with pytest.raises(ValueError):
        _core.LatticeEngine3D.from_snapshot({k: v for k, v in snap2.items() if k != "quantization"} | {"dim": 3})
    # the state is unchanged by the refusals
    assert sim.collisions == 0 and np.array_equal(sim.snapshot()["x"], snap["x"])


def test_simulation_with_engine_lattice_builds_the_3d_lattice_for_spheres():
    import revcol
    sim = revcol.Simulation.random(n=80, dim=3, phi=0.3, seed=4, engine="lattice")
    assert isinstance(sim, LatticeSimulation3D) and sim.lattice_positions.shape == (80, 3)
    x, v = sim.positions, sim.velocities
    box = float(np.asarray(sim.units["L"], dtype=float)[0] * sim.units["length_unit"])
    arr = revcol.Simulation(x, v, box, engine="lattice", seed=4)
    assert isinstance(arr, LatticeSimulation3D)
    s0 = arr.snapshot()
    arr.run(collisions=500)
    arr.run_back()
    assert np.array_equal(arr.snapshot()["x"], s0["x"]) and np.array_equal(arr.snapshot()["v"], s0["v"])
    # disks still go to the 2D class
    flat = revcol.Simulation.random(n=50, dim=2, phi=0.3, seed=4, engine="lattice")
    assert type(flat) is LatticeSimulation


def test_a_reflection_and_a_collision_on_two_consecutive_ticks_reverse():
    # N = 1000, volume fraction 0.45, walls, seed 1, stopped after collision 7 434 021 (found by the
    # 10^7 matrix): particle 162 reflects on a wall and meets 496 at one tick, and again at the next.
    # The reverse once scheduled the undo of each reflection a tick late (the restored line's point
    # was beyond the wall), so it met the earlier collision only after that reflection:
    # "events out of order". The state was carried to per-particle bits by restart_from_legacy
    # (origin at its clock), with particle 162's X set to the old run's global X, so the pair
    # draws what it drew then and meets again at the next tick.
    import os
    path = os.path.join(os.path.dirname(__file__), "..", "data", "lattice", "wall_body_twice_3d_n1000_phi0.45.npz")
    sim = LatticeSimulation3D.load(path)
    s0 = sim.snapshot()
    assert sim.collisions == 0 and sim.clock == 13632132495
    sim.run(collisions=2)
    assert sim.diagnostics()["wall_body"] == 2  # counters start at the load
    sim.run(collisions=1000)
    sim.run_back(to_collision=0)
    assert _same(sim.snapshot(), s0)
