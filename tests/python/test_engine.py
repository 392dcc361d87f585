"""revcol.Simulation: the same code paths as the studies (bench/engine_study.py) at small N."""
import numpy as np
import pytest
from scipy import stats

import revcol
from revcol import Simulation


def _err(sim, x0, v0):
    x, v = sim.positions, sim.velocities
    box = sim.box
    dx = np.abs(x - x0)
    per = np.array(sim.periodic, dtype=bool)
    dx[:, per] = np.minimum(dx[:, per], np.abs(dx[:, per] - box[per]))
    return (dx / box).max(), np.abs(v - v0).max() / np.abs(v0).max()


@pytest.mark.parametrize("dim", [1, 2, 3])
@pytest.mark.parametrize("boundary", ["periodic", "wall"])
def test_round_trip_within_horizon(dim, boundary):
    sim = Simulation.random(n=150, dim=dim, phi=0.3, boundary=boundary, seed=4)
    x0, v0 = sim.positions, sim.velocities
    r = sim.run(collisions=75)
    assert r["collisions"] == 75 and sim.time > 0
    sim.run_back()
    assert sim.time == sim.start_time
    ex, ev = _err(sim, x0, v0)
    assert ex < 1e-9 and ev < 1e-9
    d = sim.diagnostics()
    assert d["net_collisions"] == 0 and d["events"]["reverse_failures"] == 0


def test_1d_gas_exact_after_many_collisions():
    sim = Simulation.random(n=100, dim=1, phi=0.3, seed=2)
    x0, v0 = sim.positions, sim.velocities
    sim.run(collisions=100_000)
    sim.run_back()
    ex, ev = _err(sim, x0, v0)
    assert ex < 1e-12 and ev == 0.0


@pytest.mark.parametrize("law,mode", [("uniform", "exact"), ("flux", "paper")])
def test_other_laws_round_trip(law, mode):
    sim = Simulation.random(n=120, dim=2, phi=0.3, seed=5, law=law, mode=mode)
    x0, v0 = sim.positions, sim.velocities
    sim.run(collisions=60)
    sim.run_back()
    ex, ev = _err(sim, x0, v0)
    assert ex < 1e-9 and ev < 1e-9


def test_conservation_and_diagnostics():
    sim = Simulation.random(n=200, dim=3, phi=0.3, seed=6)
    sim.run(collisions=2000)
    d = sim.diagnostics()
    assert abs(d["energy_drift"]) < 1e-12 and d["momentum_drift"] < 1e-12
    assert d["events"]["pair_collisions"] == 2000
    assert d["collisions_per_particle"] == pytest.approx(2 * 2000 / 200)
    assert sim.collision_counts.sum() == 4000
    assert d["log_bytes"] == 0
    assert sim.positions.shape == (200, 3) and sim.velocities.shape == (200, 3)


def test_checkpoint_resume_is_bit_identical(tmp_path):
    a = Simulation.random(n=100, dim=2, phi=0.4, boundary="wall", seed=7)
    b = Simulation.from_snapshot(a.snapshot())
    a.run(collisions=3000)
    b.run(collisions=1234)
    path = tmp_path / "ck.npz"
    b.save(path)
    c = Simulation.load(path)
    c.run(collisions=3000 - 1234)
    assert np.array_equal(a.positions, c.positions)
    assert np.array_equal(a.velocities, c.velocities)
    assert a.time == c.time
    a.run_back(collisions=500)
    c.run_back(collisions=500)
    assert np.array_equal(a.velocities, c.velocities)


@pytest.mark.parametrize("streams", ["per-particle", "single"])
def test_clcg4_streams_round_trip_and_npz_resume(tmp_path, streams):
    kw = dict(boundary="wall", seed=9, generator="clcg4", streams=streams)
    a = Simulation.random(n=200, dim=2, phi=0.3, **kw)
    x0, v0 = a.positions, a.velocities
    b = Simulation.from_snapshot(a.snapshot())
    a.run(collisions=300)
    b.run(collisions=120)
    b.save(tmp_path / "ck.npz")
    c = Simulation.load(tmp_path / "ck.npz")
    assert c.snapshot()["generator"] == "clcg4"
    assert c.snapshot()["rng"].shape == ((1,) if streams == "single" else (200,))
    c.run(collisions=180)
    assert np.array_equal(a.velocities, c.velocities) and np.array_equal(a.positions, c.positions)
    c.run_back()
    ex, ev = _err(c, x0, v0)
    assert ex < 1e-9 and ev < 1e-9
    assert not c.snapshot()["rng"].any()  # every stream back at its start


def test_generator_and_streams_rejected():
    with pytest.raises(ValueError, match="generator"):
        Simulation.random(n=20, dim=2, phi=0.2, generator="mt19937")
    with pytest.raises(ValueError, match="streams"):
        Simulation.random(n=20, dim=2, phi=0.2, streams="per_draw")


def test_run_back_to_time_and_callback():
    sim = Simulation.random(n=100, dim=2, phi=0.3, seed=8)
    sim.run(collisions=40)
    t1, x1, v1 = sim.time, sim.positions, sim.velocities
    seen = []
    r = sim.run(collisions=1000, callback=lambda k: seen.append(k) or k < 200, every=50)
    assert r["interrupted"] and r["collisions"] == 200 and seen == [50, 100, 150, 200]
    sim.run_back(time=t1)
    assert sim.time == t1
    ex, ev = _err(sim, x1, v1)
    assert ex < 1e-9 and ev < 1e-9


@pytest.mark.parametrize("bad,match", [
    (dict(positions=[[1.0, 1.0], [1.5, 1.0]]), "overlap"),
    (dict(positions=[[0.2, 1.0], [5.0, 5.0]], boundary="wall"), "outside"),
    (dict(positions=[[np.nan, 1.0], [5.0, 5.0]]), "finite"),
    (dict(velocities=[[0.0, 0.0], [0.0, 0.0]]), "kinetic energy"),
    (dict(diameter=20.0, boundary="wall", positions=[[5.0, 5.0], [5.0, 5.0]]), "too large"),
    (dict(box=[2.5, 10.0]), "periodic box too small"),
    (dict(positions=np.zeros((0, 2)), velocities=np.zeros((0, 2))), "N = 0"),
    (dict(law="nope"), "law"),
])
def test_validation(bad, match):
    kw = dict(positions=[[1.0, 1.0], [5.0, 5.0]], velocities=[[1.0, 0.0], [-1.0, 0.0]], box=[10.0, 10.0])
    kw.update(bad)
    with pytest.raises(ValueError, match=match):
        Simulation(kw.pop("positions"), kw.pop("velocities"), kw.pop("box"), **kw)


def test_symmetric_triple_is_one_group():
    ang = np.pi / 2 + 2 * np.pi * np.arange(3) / 3
    u = np.stack([np.cos(ang), np.sin(ang)], axis=1)
    x = 10 + (1 / np.sqrt(3) + 2) * u
    sim = Simulation(x, -u, [20.0, 20.0], boundary="wall")
    sim.run(time=4.0)
    assert sim.diagnostics()["events"]["group_collisions"] == 1
    sim.run_back()
    assert np.abs(sim.positions - x).max() < 1e-9 and np.abs(sim.velocities + u).max() < 1e-9


def test_maxwell_relaxation_small():
    """From equal speeds, the flux law relaxes a 2D gas to Maxwell-Boltzmann speeds (the
    study's check at N = 1000; here N = 200 and pooled samples)."""
    sim = Simulation.random(n=200, dim=2, phi=0.2, seed=9, equal_speeds=True)
    sim.run(collisions=4000)
    samples = []
    for _ in range(10):
        sim.run(collisions=400)
        samples.append(np.linalg.norm(sim.velocities, axis=1))
    s = np.concatenate(samples)
    kT = (s ** 2).mean() / 2
    p = stats.kstest(s, lambda q: 1 - np.exp(-q ** 2 / (2 * kT))).pvalue
    assert p > 1e-3
    # and the start was far from it
    assert np.ptp(np.linalg.norm(Simulation.random(n=200, dim=2, phi=0.2, seed=9, equal_speeds=True).velocities, axis=1)) < 1e-12


def test_exported():
    assert "Simulation" in revcol.__all__ and revcol.Simulation is Simulation


def test_cradle_2d_through_npz_checkpoint(tmp_path):
    """A 2D Newton's cradle (one group with resting contacts: the exact-pre log) saved
    after the hit, loaded, and run back."""
    x = np.array([[5.0, 15.0], [10.0, 15.0], [11.0, 15.0], [12.0, 15.0]])
    v = np.array([[1.0, 0.0], [0.0, 0.0], [0.0, 0.0], [0.0, 0.0]])
    sim = Simulation(x, v, [30.0, 30.0], boundary="wall")
    sim.run(time=6.0)
    assert sim.diagnostics()["events"]["group_collisions"] == 1
    assert sim.diagnostics()["exact_pre_entries"] == 1
    sim.save(tmp_path / "cradle.npz")
    back = Simulation.load(tmp_path / "cradle.npz")
    back.run_back()
    assert np.abs(back.positions - x).max() < 1e-9 and np.abs(back.velocities - v).max() < 1e-9
    assert back.diagnostics()["exact_pre_entries"] == 0


@pytest.mark.parametrize("boundary", ["wall", "periodic"])
def test_1d_lists_the_rods_beside_no_renewals(boundary):
    # 1D rods keep their order: no cell grid, no list renewals (walls never; a periodic ring
    # only wraps its end rods), and the round trip holds velocities bit for bit
    sim = revcol.Simulation.random(n=300, dim=1, phi=0.3, boundary=boundary, seed=3)
    x0, v0 = sim.positions, sim.velocities
    sim.run(collisions=6000)
    renewals = sim.diagnostics()["events"]["list_renewals"]
    if boundary == "wall":
        assert renewals == 0
    else:
        assert renewals < 6000 / 20
        assert sim.positions.min() >= -0.25 and sim.positions.max() <= sim.box[0] + 0.25
    sim.run_back()
    assert np.array_equal(sim.velocities, v0)
    assert np.max(np.abs(sim.positions - x0)) < 1e-9


def test_box_periodic_and_snapshot_names():
    sim = Simulation.random(n=60, dim=2, phi=0.3, boundary=["wall", "periodic"], seed=2)
    snap = sim.snapshot()
    assert np.array_equal(sim.box, snap["box"]) and sim.box.shape == (2,)
    assert sim.periodic == (False, True)
    assert sim.boundary == ("wall", "periodic")
    assert list(snap["boundary"]) == [0, 1]  # each axis's kind by value: 0 wall, 1 periodic, 2 bounce
    b = Simulation.from_snapshot(snap)
    assert np.array_equal(b.positions, sim.positions) and b.boundary == sim.boundary
    # a snapshot written before the key was named "boundary" holds the same values as "periodic"
    old = dict(snap)
    old["periodic"] = old.pop("boundary")
    assert Simulation.from_snapshot(old).boundary == sim.boundary


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_specular_mode_draws_nothing_and_round_trips(dim):
    sim = Simulation.random(n=120, dim=dim, phi=0.3, seed=3, mode="specular", groups=False)
    x0, v0 = sim.positions, sim.velocities
    sim.run(collisions=120)
    assert not sim.snapshot()["rng"].any()  # deterministic: no stream moved
    assert sim.snapshot()["mode"] == "specular"
    sim.run_back()
    ex, ev = _err(sim, x0, v0)
    assert ex < 1e-9 and ev < 1e-9
    with pytest.raises(ValueError, match="mode"):
        Simulation.random(n=10, dim=2, phi=0.1, mode="specularr")


def test_bounce_boundary_end_to_end():
    # (5, 5) moving (1, 0.5) meets x = 9.5 at t = 4.5: a bounce wall sends it back along
    # its line (exactly -v), a specular wall keeps the tangent
    b = Simulation([[5.0, 5.0]], [[1.0, 0.5]], [10.0, 10.0], boundary="bounce")
    w = Simulation([[5.0, 5.0]], [[1.0, 0.5]], [10.0, 10.0], boundary="wall")
    b.run(time=8.0)
    w.run(time=8.0)
    assert np.array_equal(b.velocities, [[-1.0, -0.5]])
    assert np.array_equal(b.positions, [[6.0, 5.5]])
    assert np.array_equal(w.velocities, [[-1.0, 0.5]])
    assert b.periodic == (False, False)
    # a channel, one name per axis; the kind survives a snapshot (value 2) and run_back
    c = Simulation([[2.0, 2.0], [6.0, 3.0]], [[1.0, -1.5], [-0.5, 1.0]], [9.0, 6.0],
                   boundary=["periodic", "bounce"])
    snap = c.snapshot()
    assert list(snap["boundary"]) == [1, 2]
    c.run(time=20.0)
    d = Simulation.from_snapshot(c.snapshot())
    c.run(time=30.0)
    d.run(time=30.0)
    assert np.array_equal(c.velocities, d.velocities)
    c.run_back(time=0.0)
    assert np.max(np.abs(c.velocities - np.array([[1.0, -1.5], [-0.5, 1.0]]))) < 1e-9
    with pytest.raises(ValueError, match="boundary"):
        Simulation([[5.0, 5.0]], [[1.0, 0.5]], [10.0, 10.0], boundary="noslip")


def test_bounce_boundary_random_start_and_limits():
    # the random start keeps 1e-6 D off bounce walls as off specular ones; a channel gas goes
    # within the float engine's horizon (2 collisions per particle) and back to 1e-9
    from revcol import _core
    assert "bounce" in _core.engine_limits()["boundaries"]
    for dim in (2, 3):
        s = Simulation.random(150, dim, 0.3, boundary=["periodic"] + ["bounce"] * (dim - 1), seed=4)
        assert s.periodic == (True,) + (False,) * (dim - 1)
        x0, v0 = s.positions, s.velocities
        s.run(collisions=150)
        assert not np.allclose(s.velocities, v0)
        s.run_back(time=0.0)
        assert s.time == 0.0
        from revcol.roundtrip import geometry, round_trip_errors
        ex, ev = round_trip_errors(s.positions, s.velocities, x0, v0, *geometry(s))  # minimum image
        assert ex < 1e-9 and ev < 1e-9


def test_random_takes_the_scenes_name_for_the_packing_fraction():
    # one vocabulary (issue 19): packing_fraction= as in the scenes, phi= as before, not both
    a = revcol.Simulation.random(n=50, dim=2, phi=0.25, seed=3)
    b = revcol.Simulation.random(n=50, dim=2, packing_fraction=0.25, seed=3)
    assert np.array_equal(a.positions, b.positions) and np.array_equal(a.box, b.box)
    c = revcol.Simulation.random(n=50, dim=2, seed=3)  # the default stays 0.3
    d = revcol.Simulation.random(n=50, dim=2, phi=0.3, seed=3)
    assert np.array_equal(c.box, d.box) and not np.array_equal(a.box, c.box)
    with pytest.raises(TypeError, match="phi= or packing_fraction=, not both"):
        revcol.Simulation.random(n=50, dim=2, phi=0.2, packing_fraction=0.2)
    la = revcol.Simulation.random(n=50, dim=2, packing_fraction=0.25, seed=3, engine="lattice")
    lb = revcol.lattice.LatticeSimulation.random(50, phi=0.25, seed=3)
    assert np.array_equal(la.positions, lb.positions)
