"""Observation on the lattice engine (the float engine's observer fed by the exact engine's
hooks; tests/cpp/test_lattice_observe.cpp checks its sums against the engine's own velocity
changes to 1e-9): the one observe API of both engines, an observed run of 10^6 collisions
reversed bit for bit, and the lattice gas's statics against the float engine's (a reduced
form of ``python -m revcol.studies.engine_agreement``)."""
import warnings

import numpy as np
import pytest

import revcol
from revcol.lattice import LatticeSimulation, LatticeSimulation3D
from revcol.observe import Observation, Observing
from revcol.studies.engine_agreement import compare


def test_both_engines_share_the_observe_api():
    for sim in (revcol.Simulation.random(n=100, dim=2, phi=0.3, seed=1),
                revcol.Simulation.random(n=100, dim=2, phi=0.3, seed=1, engine="lattice"),
                revcol.Simulation.random(n=100, dim=3, phi=0.3, seed=1, engine="lattice")):
        assert isinstance(sim, Observing)
        assert sim.observation() is None and not sim.observing
        sim.run(collisions=500)
        sim.observe(speed_bins=20, slabs=4)
        sim.run(collisions=3000)
        o = sim.observation()
        assert isinstance(o, Observation) and sim.observing
        assert o.pair_collisions + o.group_collisions == 3000
        assert o.temperature.value == pytest.approx(1.0, rel=1e-6)
        assert o.compressibility.value > 1.0 and o.compressibility.error > 0.0
        assert o.speed is not None and o.slab_density is not None
        assert len(o.msd) > 0 and o.mean_free_path.value > 0.0
        with warnings.catch_warnings():  # the float run is beyond its round-off horizon here
            warnings.simplefilter("ignore", RuntimeWarning)
            sim.run_back()
        assert not sim.observing and sim.observation().pair_collisions == o.pair_collisions


def test_lattice_box_and_periodic_read_as_the_float_engine_s():
    sim = LatticeSimulation.random(n=100, phi=0.3, seed=2, boundary=["wall", "periodic"])
    assert sim.periodic == (False, True)
    assert sim.box.shape == (2,) and np.all(sim.box > 0)
    assert np.all(sim.positions < sim.box)


def test_a_bad_observe_argument_names_itself_and_starts_nothing():
    sim = revcol.Simulation.random(n=60, dim=2, phi=0.3, seed=3, engine="lattice")
    with pytest.raises(ValueError, match="min_blocks"):
        sim.observe(min_blocks=1)
    with pytest.raises(ValueError, match="slab_axis"):
        sim.observe(slabs=4, slab_axis=2)
    with pytest.raises(TypeError, match="speed_bins"):
        sim.observe(speed_bins="many")
    assert not sim.observing and sim.observation() is None


@pytest.mark.parametrize("cls,walls", [(LatticeSimulation, "wall"), (LatticeSimulation3D, "periodic")])
def test_an_observed_run_of_a_million_collisions_comes_back_bit_for_bit(cls, walls):
    sim = cls.random(n=1000, phi=0.3, seed=4, boundary=walls)
    twin = cls.random(n=1000, phi=0.3, seed=4, boundary=walls)
    x0, v0, c0 = sim.lattice_positions, sim.lattice_velocities, sim.clock
    sim.observe(speed_bins=30)
    sim.run(collisions=1_000_000)
    twin.run(collisions=1_000_000)
    # observing changes nothing in the run
    assert np.array_equal(sim.lattice_positions, twin.lattice_positions)
    assert np.array_equal(sim.lattice_velocities, twin.lattice_velocities)
    o = sim.observation()
    assert o.pair_collisions + o.group_collisions == 1_000_000
    sim.run_back()
    assert sim.clock == c0
    assert np.array_equal(sim.lattice_positions, x0) and np.array_equal(sim.lattice_velocities, v0)


@pytest.mark.parametrize("mode", ["exact", "specular"])
@pytest.mark.parametrize("dim,phi", [(2, 0.5), (3, 0.3)])
def test_the_lattice_gas_has_the_float_gas_s_statics(dim, phi, mode):
    # Z (virial), collision rate and g(D+) (frames) within 3 combined standard errors, the flux
    # law on both engines or specular dynamics on both; the full studies (N = 1000, 2 x 10^6
    # collisions) are bench/results/engine_agreement.json and engine_agreement_specular.json
    res = compare(dim, phi, n=400, collisions=120_000, warm=8_000, frames=40, groups=8, seed=5, mode=mode)
    assert res["mode"] == mode
    for q, s in res["sigmas"].items():
        assert s < 3.0, (q, res["float"][q], res["lattice"][q])
    for e in ("float", "lattice"):
        assert res[e]["z"][1] > 0 and res[e]["g_contact"][1] > 0


def test_a_snapshot_resumes_the_lattice_observation_bit_for_bit(tmp_path):
    """observe, run, snapshot (dict, file, pickle), run: each resumed run's results equal the
    uninterrupted run's exactly, as on the float engine; a snapshot taken while not observing
    has no observer entries; a spoiled one is refused by name."""
    import pickle

    sim = LatticeSimulation.random(n=150, phi=0.4, seed=6, boundary="wall")
    sim.run(collisions=2000)
    assert "observer" not in sim.snapshot()
    sim.observe(speed_bins=20, slabs=4, block_time=0.05)
    sim.run(collisions=3000)
    snap = sim.snapshot()
    assert len(snap["observer"]) > 0 and len(snap["observer_counts"]) > 0
    sim.save(tmp_path / "c.npz")
    copy = pickle.loads(pickle.dumps(sim))
    sim.run(collisions=4000)
    want = sim.observation().to_dict()
    for resumed in (LatticeSimulation.from_snapshot(snap), LatticeSimulation.load(tmp_path / "c.npz"), copy):
        assert resumed.observing
        resumed.run(collisions=4000)
        assert resumed.observation().to_dict() == want
    bad = dict(snap)
    bad["observer"] = np.asarray(snap["observer"])[:-1]
    with pytest.raises(ValueError, match="observer"):
        LatticeSimulation.from_snapshot(bad)
