"""The 2D lattice engine from Python (revcol.lattice): forward and back bit for bit, midpoint
reversal, checkpoints through save/load, diagnostics, float starts and bad input."""
import numpy as np
import pytest

import revcol
from revcol.lattice import LatticeSimulation, LatticeSimulation3D


def _same(a: dict, b: dict) -> bool:
    keys = ["clock", "origin", "collisions", "particle_collisions", "x", "v", "streams", "bits", "bits_size",
            "log_particle", "log_count", "log_redraws", "group_drawer", "group_draws", "group_size", "group_members",
            "group_counts", "group_kind", "group_v", "seed", "law"]
    return all(np.array_equal(np.asarray(a[k]), np.asarray(b[k])) for k in keys)


@pytest.mark.parametrize("phi,boundary", [(0.3, "periodic"), (0.5, "wall")])
def test_round_trip_bit_for_bit(phi, boundary):
    sim = LatticeSimulation.random(n=150, phi=phi, boundary=boundary, seed=3)
    s0 = sim.snapshot()
    r = sim.run(collisions=150 * 50)
    assert r["collisions"] == 150 * 50 and sim.collisions == 150 * 50
    assert not np.array_equal(sim.lattice_positions, s0["x"])
    back = sim.run_back()
    assert back["collisions"] == 150 * 50
    assert _same(sim.snapshot(), s0)
    assert sim.clock == s0["clock"]
    d = sim.diagnostics()
    assert d["bits_length"] == 128 * 150 and d["log_entries"] == 0 and d["energy_drift"] == 0.0


def test_midpoint_and_time_reversal_equal_the_forward_states():
    sim = LatticeSimulation.random(n=120, phi=0.4, seed=5)
    sim.run(collisions=3000)
    mid = sim.snapshot()
    t_mid = sim.time
    sim.run(collisions=3000)
    sim.run_back(to_collision=3000)
    assert _same(sim.snapshot(), mid)
    sim.run(collisions=1000)
    sim.run_back(time=t_mid)
    assert sim.clock == mid["clock"]
    assert np.array_equal(sim.lattice_positions, mid["x"])
    assert np.array_equal(sim.lattice_velocities, mid["v"])
    sim.run_back(collisions=1000)
    assert sim.collisions == 2000


def test_tick_bits_finer_tick_round_trip_and_checkpoint(tmp_path):
    coarse = LatticeSimulation.random(n=120, phi=0.5, boundary="wall", seed=4, tick_bits=20)
    fine = LatticeSimulation.random(n=120, phi=0.5, boundary="wall", seed=4, tick_bits=22)
    assert coarse.units["tick_bits"] == 20 and fine.units["tick_bits"] == 22
    assert fine.units["tick"] == pytest.approx(coarse.units["tick"] / 4, rel=1e-12)
    # the same float start: positions identical, velocities carry 2 bits less (v_rms -> 2^(S-22))
    assert np.array_equal(fine.lattice_positions, coarse.lattice_positions)
    assert np.allclose(fine.velocities, coarse.velocities, rtol=0, atol=1e-9)
    s0 = fine.snapshot()
    fine.run(collisions=6000)
    path = tmp_path / "fine.npz"
    fine.save(path)
    other = LatticeSimulation.load(path)
    assert other.units["tick_bits"] == 22 and _same(other.snapshot(), fine.snapshot())
    other.run_back()
    assert _same(other.snapshot(), s0)
    for bad in (15, 27, 0):
        with pytest.raises(ValueError, match="tick_bits"):
            LatticeSimulation.random(n=50, phi=0.3, tick_bits=bad)


def test_automatic_tick_keeps_30_velocity_bits():
    for n, phi in ((120, 0.5), (2000, 0.1)):
        u = LatticeSimulation.random(n=n, phi=phi, seed=4).units
        assert u["tick_bits"] == min(24, max(16, u["S"] - 30))
    big = LatticeSimulation.random(n=10000, phi=0.1, seed=4).units  # a box of 280 diameters
    assert big["S"] == 52 and big["tick_bits"] == 22


def test_cell_bits_round_trip_checkpoint_and_bad_values(tmp_path):
    sims = {cb: LatticeSimulation.random(n=120, phi=0.5, boundary="wall", seed=4, cell_bits=cb) for cb in (16, 20)}
    assert LatticeSimulation.random(n=50, phi=0.3).units["cell_bits"] == 16  # the default
    for cb, sim in sims.items():
        assert sim.units["cell_bits"] == cb
        s0 = sim.snapshot()
        sim.run(collisions=4000)
        path = tmp_path / f"c{cb}.npz"
        sim.save(path)
        other = LatticeSimulation.load(path)
        assert other.units["cell_bits"] == cb and _same(other.snapshot(), sim.snapshot())
        other.run_back()
        assert _same(other.snapshot(), s0)
    # the cell resolution is part of the dynamics: the two runs part from the same start
    assert not np.array_equal(sims[16].lattice_velocities, sims[20].lattice_velocities)
    for bad in (11, 21):
        with pytest.raises(ValueError, match="cell_bits"):
            LatticeSimulation.random(n=50, phi=0.3, cell_bits=bad)


def test_save_load_resumes_bit_for_bit(tmp_path):
    sim = LatticeSimulation.random(n=100, phi=0.5, boundary=["wall", "periodic"], seed=7)
    sim.run(collisions=2000)
    path = tmp_path / "lattice.npz"
    sim.save(path)
    other = LatticeSimulation.load(path)
    assert _same(other.snapshot(), sim.snapshot())
    sim.run(collisions=2000)
    other.run(collisions=2000)
    assert _same(other.snapshot(), sim.snapshot())
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
    s = sim.snapshot()
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
        LatticeSimulation.from_snapshot(bad)
    assert _same(sim.snapshot(), s)


def test_simulation_routes_engine_lattice():
    """revcol.Simulation(..., engine="lattice") and Simulation.random(..., engine="lattice") build
    the lattice engine; a bad engine name is refused by name."""
    import revcol

    sim = revcol.Simulation.random(n=80, dim=2, phi=0.3, seed=4, engine="lattice")
    assert isinstance(sim, LatticeSimulation)
    x0, v0 = sim.lattice_positions, sim.lattice_velocities
    sim.run(collisions=500)
    assert not (sim.lattice_velocities == v0).all()
    sim.run_back()
    assert (sim.lattice_positions == x0).all() and (sim.lattice_velocities == v0).all()
    other = revcol.Simulation(sim.positions, sim.velocities, sim.units["L"][0] * sim.units["length_unit"],
                              engine="lattice", seed=4)
    assert isinstance(other, LatticeSimulation) and other.n == 80
    assert isinstance(revcol.Simulation.random(n=20, dim=2, phi=0.2, seed=1), revcol.Simulation)
    with pytest.raises(ValueError, match="engine"):
        revcol.Simulation.random(n=20, dim=2, phi=0.2, engine="cuda")
    with pytest.raises(ValueError, match="engine"):
        revcol.Simulation([[1.0, 1.0]], [[1.0, 0.0]], 5.0, engine="cuda")


def test_a_reflection_and_a_pair_within_one_tick_resolve_as_a_group():
    # N = 1000, area fraction 0.7, walls, seed 1, stopped before collision 4 018 558: particle 471
    # reflects on a wall at the tick where it meets 470, and every draw of the pair put a post
    # centre beyond the wall; the engine raised an error there before the group took the
    # reflection in (bench/results/lattice_validation_matrix_n1000.json of commit 94a9260). The
    # state was carried to per-particle bits by restart_from_legacy (origin at its clock), with
    # particle 470's X set to the old run's global X, so the pair draws what it drew then.
    import os
    path = os.path.join(os.path.dirname(__file__), "..", "data", "lattice", "wall_body_group_n1000_phi0.7.npz")
    sim = LatticeSimulation.load(path)
    s0 = sim.snapshot()
    assert sim.collisions == 0 and sim.clock == 565922893
    sim.run(collisions=1)
    d = sim.diagnostics()
    assert d["wall_groups"] == 1 and d["group_resolves"] + d["group_bounces"] == 1  # counters start at the load
    sim.run(collisions=20000)
    sim.run_back(to_collision=0)
    assert _same(sim.snapshot(), s0)


@pytest.mark.parametrize("dim,boundary", [(2, ["periodic", "bounce"]), (3, ["bounce", "wall", "periodic"])])
def test_bounce_back_walls_reverse_bit_for_bit_and_survive_a_checkpoint(dim, boundary, tmp_path):
    # the float engine's boundary kinds on the lattice (one parser, revcol/engine/boundary_kind.hpp)
    sim = revcol.Simulation.random(n=300, dim=dim, phi=0.3, seed=7, engine="lattice", boundary=boundary)
    assert sim.boundary == tuple(boundary)
    assert sim.periodic == tuple(b == "periodic" for b in boundary)
    x0, v0 = sim.lattice_positions, sim.lattice_velocities
    sim.run(collisions=100_000)
    assert sim.diagnostics()["walls"] > 0
    sim.save(tmp_path / "c.npz")
    back = type(sim).load(tmp_path / "c.npz")
    assert back.boundary == tuple(boundary)
    for s in (sim, back):
        s.run_back()
        assert np.array_equal(s.lattice_positions, x0) and np.array_equal(s.lattice_velocities, v0)


def test_a_bad_boundary_name_is_named_by_the_one_parser():
    with pytest.raises(ValueError, match="boundary must be one of 'wall', 'periodic', 'bounce', got 'walls'"):
        revcol.Simulation.random(n=50, dim=2, phi=0.3, engine="lattice", boundary="walls")
    with pytest.raises(ValueError, match="one name or 2"):
        revcol.Simulation.random(n=50, dim=2, phi=0.3, engine="lattice", boundary=["wall"] * 3)


@pytest.mark.parametrize("cls,phi,mode", [(LatticeSimulation, 0.6, "exact"), (LatticeSimulation3D, 0.4, "exact"),
                                          (LatticeSimulation, 0.6, "specular")])
def test_every_snapshot_loads_even_between_two_collisions_of_one_tick(cls, phi, mode):
    """A run stops after a collision; other collisions of that tick may still be pending, so a
    pair can overlap at the clock. The snapshot is valid (the engine finds those collisions on
    restore) and must load: at a coarse tick (2^-16) that happens every few hundred collisions.
    Each snapshot of 1600 consecutive collisions loads, and from every 200th the loaded run goes
    on exactly as the uninterrupted one; a pair overlapping one tick earlier too is still refused."""
    sim = cls.random(200, phi=phi, seed=2, boundary="periodic", tick_bits=16, mode=mode)
    L, s2 = np.asarray(sim.units["L"], dtype=float), float(sim.units["sigma"]) ** 2
    pending, expected = 0, {}
    for k in range(1, 1601):
        sim.run(collisions=1)
        if k in expected:  # a copy loaded 300 collisions ago and run on: the uninterrupted state
            x, v = expected.pop(k)
            assert np.array_equal(sim.lattice_positions, x) and np.array_equal(sim.lattice_velocities, v)
        snap = sim.snapshot()
        copy = cls.from_snapshot(snap)  # raised "particles i and j overlap" before
        x = sim.lattice_positions.astype(float)
        d = x[:, None, :] - x[None, :, :]
        d -= np.round(d / L) * L
        pending += int(((d ** 2).sum(-1)[np.triu_indices(len(x), 1)] < s2 * (1 - 1e-12)).any())
        if k % 200 == 0:
            copy.run(collisions=300)
            expected[k + 300] = (copy.lattice_positions, copy.lattice_velocities)
    assert pending > 0  # the case this test is about did occur
    # the original run, continued, equals a copy loaded at the end
    end = cls.from_snapshot(sim.snapshot())
    sim.run(collisions=500)
    end.run(collisions=500)
    assert np.array_equal(sim.lattice_positions, end.lattice_positions)
    # an overlap that is not a pending collision (apart one tick earlier) is still refused by name
    snap = sim.snapshot()
    x = np.array(snap["x"], dtype=np.int64)
    v = np.array(snap["v"], dtype=np.int64)
    x[1] = x[0]
    x[1][0] = (x[1][0] + int(sim.units["sigma"]) // 2) % int(sim.units["L"][0])
    v[1] = v[0]  # moving together: they overlapped one tick before too
    snap["x"], snap["v"] = x, v
    with pytest.raises(ValueError, match="overlap, and did one tick before"):
        cls.from_snapshot(snap)


def test_random_and_arrays_refuse_a_float_dim_a_bool_n_and_complex_values():
    # issue 59's small cases: each a named TypeError (not "can't multiply sequence", not n = 1,
    # not a ComplexWarning that drops the imaginary part)
    for engine in ("float", "lattice"):
        with pytest.raises(TypeError, match="dim must be an integer"):
            revcol.Simulation.random(100, dim=2.0, phi=0.3, engine=engine)
        with pytest.raises(TypeError, match="n must be an integer, got bool"):
            revcol.Simulation.random(True, dim=2, phi=0.3, engine=engine)
    with pytest.raises(TypeError, match="n must be an integer"):
        LatticeSimulation3D.random(True, phi=0.3)
    x = np.array([[1.0, 1.0], [3.0, 3.0]]) + 0j
    with pytest.raises(TypeError, match="positions must be an array of real numbers, got complex"):
        LatticeSimulation(x, np.zeros((2, 2)), 10.0)
    with pytest.raises(TypeError, match="positions must be an array of real numbers, got complex"):
        revcol.Simulation(x, np.zeros((2, 2)), 10.0)
