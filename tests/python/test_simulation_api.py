"""One simulation API for both engines (revcol.simulation): the float engine's Simulation and
the lattice engine's LatticeSimulation / LatticeSimulation3D are each a SimulationBase, built
through ``Simulation(..., engine=...)`` alike, and answer every member of the base the same
way (shapes, units, round trips, checkpoints, pickles, observation)."""
import inspect
import pickle

import numpy as np
import pytest

import revcol
from revcol.lattice import LatticeSimulation, LatticeSimulation3D
from revcol.simulation import ENGINES, SimulationBase, engine_class

CASES = [("float", 2), ("float", 3), ("lattice", 2), ("lattice", 3)]


def _make(engine, dim, **kw):
    kw.setdefault("boundary", "wall")
    return revcol.Simulation.random(n=120, dim=dim, phi=0.3, seed=3, engine=engine, **kw)


def test_the_base_lists_what_both_engines_implement():
    abstract = SimulationBase.__abstractmethods__
    assert {"run", "run_back", "positions", "velocities", "time", "collisions", "n", "dim", "box", "boundary",
            "diagnostics", "snapshot", "from_snapshot", "save", "load"} <= abstract
    for cls in (revcol.Simulation, LatticeSimulation, LatticeSimulation3D):
        assert issubclass(cls, SimulationBase) and not inspect.isabstract(cls)
        for name in ("run", "run_back"):  # collisions= and time= on both, by keyword, default None
            params = inspect.signature(getattr(cls, name)).parameters
            assert params["collisions"].default is None and params["time"].default is None
    assert ENGINES == ("float", "lattice")
    assert engine_class("lattice", 3) is LatticeSimulation3D and engine_class("float", 2) is revcol.Simulation
    with pytest.raises(ValueError, match="engine must be 'float' or 'lattice'"):
        engine_class("gpu", 2)


@pytest.mark.parametrize("engine,dim", CASES)
def test_every_member_of_the_base_on_each_engine(engine, dim, tmp_path):
    sim = _make(engine, dim)
    assert isinstance(sim, SimulationBase) and sim.engine == engine
    assert sim.n == 120 and sim.dim == dim
    assert sim.box.shape == (dim,) and sim.positions.shape == (120, dim) == sim.velocities.shape
    assert sim.boundary == ("wall",) * dim and sim.periodic == (False,) * dim
    assert np.all((sim.positions > 0) & (sim.positions < sim.box))
    x0, t0 = sim.positions, sim.time
    r = sim.run(collisions=600)
    assert r["collisions"] == 600 and sim.collisions == 600 and sim.time > t0 and r["time"] == sim.time
    r = sim.run(time=sim.time + 0.05)
    assert sim.time == pytest.approx(r["time"])
    assert isinstance(sim.diagnostics(), dict)
    # checkpoints and pickles resume the same state
    sim.save(tmp_path / "s.npz")
    for other in (type(sim).load(tmp_path / "s.npz"), type(sim).from_snapshot(sim.snapshot()),
                  pickle.loads(pickle.dumps(sim))):
        assert type(other) is type(sim)
        assert np.array_equal(other.positions, sim.positions) and other.collisions == sim.collisions
    sim.observe()
    sim.run(collisions=300)
    assert sim.observation().pair_collisions + sim.observation().group_collisions == 300
    sim.run_back(collisions=100)
    assert sim.collisions == r_net(sim) and not sim.observing
    # forward and back to the start (the float engine within its horizon at this length)
    fresh = _make(engine, dim)
    fresh.run(collisions=150)
    fresh.run_back()
    assert fresh.collisions == 0 and fresh.time == pytest.approx(t0, abs=1e-12)
    err = np.abs(fresh.positions - x0).max()
    assert err == 0.0 if engine == "lattice" else err < 1e-9 * float(sim.box.max())


def r_net(sim):
    return int(sim.diagnostics()["net_collisions"] if sim.engine == "float" else sim.snapshot()["collisions"])


@pytest.mark.parametrize("dim", [2, 3])
def test_the_constructor_hands_engine_lattice_to_the_lattice_s_class(dim):
    f = revcol.Simulation.random(n=80, dim=dim, phi=0.2, seed=5)
    lat = revcol.Simulation(f.positions, f.velocities, f.box, engine="lattice", boundary="periodic", seed=5)
    assert type(lat) is (LatticeSimulation3D if dim == 3 else LatticeSimulation)
    assert np.allclose(lat.positions, f.positions, atol=1e-9) and lat.boundary == f.boundary
    with pytest.raises(ValueError, match="engine must be 'float' or 'lattice'"):
        revcol.Simulation(f.positions, f.velocities, f.box, engine="exact")
