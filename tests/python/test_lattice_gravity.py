"""A uniform field on the lattice engine (docs/engine.md, "A uniform field"): the value run and
its quantization, a gas under gravity forward and back bit for bit (2D and 3D, exact and
specular, a mixture), a checkpoint resumed bit for bit, energy with the potential kept, the
wall pressure equal to the column's weight, and what a field refuses."""
import numpy as np
import pytest

import revcol
from revcol.lattice import LatticeSimulation, LatticeSimulation3D

KEYS = ("x", "v", "streams", "bits", "bits_size", "particle_collisions", "clock", "collisions")


def same(a: dict, b: dict) -> bool:
    return all(np.array_equal(np.asarray(a[k]), np.asarray(b[k])) for k in KEYS)


def gas(dim=2, n=300, g=-1.0, seed=5, **kw):
    boundary = ["periodic"] * (dim - 1) + ["wall"]
    cls = LatticeSimulation3D if dim == 3 else LatticeSimulation
    return cls.random(n, phi=0.2, boundary=boundary, gravity=[0.0] * (dim - 1) + [g], seed=seed, **kw)


def test_the_field_run_is_the_one_asked_within_its_quantization():
    s = gas(g=-0.8)
    g = s.gravity
    assert g[0] == 0.0 and g[1] < 0.0
    err = s.quantization["gravity_error"]
    assert err <= 2.0 ** -8  # the automatic tick is coarsened until the rounding is within 2^-8
    assert abs(g[1] / -0.8 - 1.0) <= err * (1 + 1e-9)
    u = s.units
    assert u["gravity"][1] % 2 == 0 and u["gravity"][1] != 0
    # one engine's keyword: Simulation.random(engine="lattice") hands it over
    t = revcol.Simulation.random(200, 2, 0.2, boundary=["periodic", "wall"], gravity=[0.0, -0.8], engine="lattice", seed=5)
    assert t.engine == "lattice" and t.gravity[1] < 0


@pytest.mark.parametrize("dim,mode,sizes", [(2, "exact", None), (2, "specular", None), (3, "exact", None),
                                            (2, "exact", "binary")])
def test_forward_and_back_bit_for_bit_from_a_midpoint(dim, mode, sizes):
    n = 300
    diameters = None if sizes is None else [1.0 if i % 2 else 1.4 for i in range(n)]
    s = gas(dim, n, mode=mode, diameters=diameters)
    s0 = s.snapshot()
    h0 = s.positions[:, -1].mean()
    s.run(collisions=6000)
    s1 = s.snapshot()
    s.run(collisions=6000)
    assert s.positions[:, -1].mean() < h0  # it fell
    d = s.diagnostics()
    assert abs(d["energy_drift"]) < 1e-8  # kinetic and potential, relative
    lower, upper = d["field_wall_impulse"]
    assert lower > 0
    # a checkpoint at the midpoint resumes on the same bits
    r = type(s).from_snapshot(s1)
    r.run(collisions=6000)
    assert same(r.snapshot(), s.snapshot())
    s.run_back(to_collision=6000)
    assert same(s.snapshot(), s1)
    s.run_back()
    assert same(s.snapshot(), s0)


def test_a_checkpoint_file_carries_the_field(tmp_path):
    s = gas(seed=7)
    s.run(collisions=3000)
    f = tmp_path / "g.npz"
    s.save(str(f))
    r = LatticeSimulation.load(str(f))
    assert np.array_equal(r.gravity, s.gravity)
    s.run(collisions=2000)
    r.run(collisions=2000)
    assert same(r.snapshot(), s.snapshot())


def test_the_walls_carry_the_weight_of_the_column():
    # momentum balance over a window: lower wall less upper = N |g| t, up to the change of the
    # gas's own momentum (bounded by a few thermal momenta: sqrt(N) v_rms), here < 1%
    s = gas(n=400, g=-0.5, seed=11)
    s.run(collisions=40000)
    d0 = s.diagnostics()
    s.run(collisions=200000)
    d1 = s.diagnostics()
    lower = d1["field_wall_impulse"][0] - d0["field_wall_impulse"][0]
    upper = d1["field_wall_impulse"][1] - d0["field_wall_impulse"][1]
    weight = 400 * abs(s.units["gravity"][1]) * (d1["clock"] - d0["clock"])
    assert abs((lower - upper) / weight - 1.0) < 0.01


@pytest.mark.parametrize("dim", [2, 3])
def test_the_observed_column_its_walls_and_a_checkpoint(dim, tmp_path):
    s = gas(dim=dim, n=300, g=-0.5, seed=7)
    s.run(collisions=3000)
    s.observe(slabs=8, slab_axis=dim - 1, speed_bins=20)
    d0 = s.diagnostics()
    s.run(collisions=6000)
    path = tmp_path / "column.npz"
    s.save(path)  # with the running observation
    s.run(collisions=6000)
    d1 = s.diagnostics()
    r = type(s).load(path)
    r.run(collisions=6000)
    o = s.observation()
    for key in ("observer", "observer_counts"):  # resumed to the same bits
        assert np.array_equal(np.asarray(s.snapshot()[key]), np.asarray(r.snapshot()[key]))
    # the observer's wall pressure on the field's axis is the engine's own count of the walls'
    # impulses (lattice units per tick) over the observed time: the engine counts a reflection's
    # change of velocity from tick a-1 to a, which holds one tick of the field's pull (|g| tick,
    # ~1e-8 of a reflection's 2 |v| here), the observer the instant's (measured 4e-9 apart)
    impulse = (sum(d1["field_wall_impulse"]) - sum(d0["field_wall_impulse"])) * s.units["length_unit"] / s.units["tick"]
    area = float(np.prod(s.box)) / s.box[dim - 1]
    assert o.pressure_wall[dim - 1].value == pytest.approx(impulse / (2 * o.duration * area), rel=1e-7)
    assert o.slab_density.value[0] > o.slab_density.value[-1]  # denser below
    assert np.sum(o.slab_density.value) * np.prod(s.box) / 8 == pytest.approx(300, rel=1e-12)


@pytest.mark.parametrize("engine", ["lattice", "float"])
def test_pair_distances_of_a_small_column(engine):
    """Pair distances in a field (2 to 64 particles, walls all round): a density over [0, rmax]
    that integrates to 1 and is 0 below the contact distance (the separation of two particles,
    both falling, is a line between events; the exact worked case is
    tests/cpp/test_float_field_observe.cpp)."""
    kw = dict(boundary="wall", gravity=[0.0, -0.5], seed=5)
    s = (LatticeSimulation.random(40, phi=0.2, **kw) if engine == "lattice"
         else revcol.Simulation.random(40, 2, 0.2, **kw))
    s.run(collisions=500)
    s.observe(pair_bins=100, pair_rmax=float(np.hypot(*s.box)))
    s.run(collisions=4000)
    o = s.observation()
    h = o.pair_distance.edges[1] - o.pair_distance.edges[0]
    assert np.sum(o.pair_distance.value) * h == pytest.approx(1.0, rel=1e-9)
    below = np.asarray(o.pair_distance.edges[1:]) < 0.999  # bins wholly inside a contact
    assert below.sum() >= 1 and np.all(np.asarray(o.pair_distance.value)[below] == 0.0)


def test_what_a_field_refuses():
    with pytest.raises(ValueError, match="walled axis"):
        LatticeSimulation.random(100, phi=0.2, boundary="periodic", gravity=[0.0, -1.0])
    with pytest.raises(ValueError, match="one component per axis"):
        LatticeSimulation.random(100, phi=0.2, boundary=["periodic", "wall"], gravity=[-1.0])
    with pytest.raises(ValueError, match="one axis"):
        LatticeSimulation.random(100, phi=0.2, boundary="wall", gravity=[-1.0, -1.0])
    with pytest.raises(ValueError, match="gravity along axis 0 runs on one worker"):
        LatticeSimulation.random(100, phi=0.2, boundary=["wall", "periodic"], gravity=[-1.0, 0.0], workers=2)
    s = LatticeSimulation.random(100, phi=0.2, boundary=["periodic", "wall"], gravity=[0.0, -1.0])
    with pytest.raises(ValueError, match="cut across the field"):
        s.set_parallel(2, axis=1)
    with pytest.raises(ValueError, match="resolution"):
        LatticeSimulation.random(100, phi=0.2, boundary=["periodic", "wall"], gravity=[0.0, -1e-12], tick_bits=26)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_gas_in_a_field_runs_on_workers_with_the_sequential_bits(dim):
    # slabs across the field (axis 0), more LPs than cores: forward and back, the sequential run's bits
    seq, par = gas(dim=dim, n=1500, g=-2.0, seed=6), gas(dim=dim, n=1500, g=-2.0, seed=6, workers=2, lps=3)
    start, impulse0 = seq.snapshot(), seq.diagnostics()["field_wall_impulse"]
    seq.run(collisions=12_000)
    r = par.run(collisions=12_000)
    assert len(r["parallel"]["lp_events"]) == 3 and r["parallel"]["parallel_collisions"] > 0
    assert same(seq.snapshot(), par.snapshot())
    assert seq.diagnostics()["field_wall_impulse"] == par.diagnostics()["field_wall_impulse"]
    par.run_back(collisions=12_000)
    assert same(par.snapshot(), start) and par.diagnostics()["field_wall_impulse"] == impulse0


@pytest.mark.parametrize("by", ["reverse", "save_all", "save_changes"])
def test_a_gas_in_a_field_rolls_back_to_the_forward_runs_bits(by):
    s, f = gas(dim=3, n=300, g=-2.0, seed=4), gas(dim=3, n=300, g=-2.0, seed=4)
    s.keep_journal(by=by)
    s.run(collisions=3000)
    f.run(collisions=1200)
    impulse = f.diagnostics()["field_wall_impulse"]  # the walls' momentum: taken off as the run is undone
    s.rollback(1200)
    assert same(s.snapshot(), f.snapshot())
    assert s.diagnostics()["field_wall_impulse"] == impulse and impulse != gas(dim=3).diagnostics()["field_wall_impulse"]
    s.run(collisions=1800)
    f.run(collisions=1800)
    assert same(s.snapshot(), f.snapshot())


@pytest.mark.parametrize("dim,phi", [(2, 0.3), (3, 0.3), (3, 0.1)])
def test_lists_run_a_field_with_the_cell_grids_bits(dim, phi):
    # 3D's automatic search takes the lists in a field where the gas is dense enough (Enskog's mean
    # free path below 0.3 diameters: phi 0.3, not 0.1), as 2D takes the cells; either search runs
    # the same collisions
    cls = LatticeSimulation3D if dim == 3 else LatticeSimulation
    runs = {}
    for search in ("cells", 0.3, "auto"):
        s = cls.random(400, phi=phi, boundary=["periodic"] * (dim - 1) + ["wall"], gravity=[0.0] * (dim - 1) + [-2.0],
                       seed=9)
        s.search = search
        auto_cells = dim == 2 or phi < 0.2
        assert (s.search == "cells") == (search == "cells" or (search == "auto" and auto_cells))
        start = s.snapshot()
        s.run(collisions=3000)
        runs[search] = s.snapshot()
        s.run_back(collisions=3000)
        assert same(s.snapshot(), start)
    assert same(runs["cells"], runs[0.3]) and same(runs["cells"], runs["auto"])
