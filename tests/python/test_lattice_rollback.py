"""Rollback from Python: the journal of processed events undoes the latest events one by one,
bit for bit the state the forward run had (tests/cpp/test_lattice_rollback.cpp covers every mode;
here the two stored states where a reflection and a collision share a tick, the time target,
and the refusals)."""
import os

import numpy as np
import pytest

from revcol.lattice import LatticeSimulation, LatticeSimulation3D

DATA = os.path.join(os.path.dirname(__file__), "..", "data", "lattice")
KEYS = ["clock", "origin", "collisions", "particle_collisions", "x", "v", "streams", "bits", "bits_size",
        "log_particle", "log_count", "log_redraws", "group_drawer", "group_draws", "group_size", "group_members",
        "group_counts", "group_kind", "group_v", "seed", "law"]


def _same(a: dict, b: dict) -> bool:
    return all(np.array_equal(np.asarray(a[k]), np.asarray(b[k])) for k in KEYS)


@pytest.mark.parametrize("by", ["reverse", "save_all", "save_changes"])
def test_a_group_that_took_in_a_reflection_rolls_back_bit_for_bit(by):
    # the first collision of this state is a pair that meets a wall on the tick it collides: the
    # group takes the reflection in (test_lattice.py); its undo reflects the member again, and
    # the reflection's own entry then undoes that (by state saving: the saved lines, the wall tick)
    sim = LatticeSimulation.load(os.path.join(DATA, "wall_body_group_n1000_phi0.7.npz"))
    s0 = sim.snapshot()
    sim.keep_journal(by=by)
    assert sim.journal == {"on": True, "start": 0, "start_clock": s0["clock"], "size": 0, "bytes": 0}
    sim.run(collisions=1)
    assert sim.diagnostics()["wall_groups"] == 1
    s1 = sim.snapshot()
    assert sim.rollback(to_collision=0)["collisions"] == 1
    assert _same(sim.snapshot(), s0)
    sim.run(collisions=1)
    assert _same(sim.snapshot(), s1)
    sim.run(collisions=3000)
    s2 = sim.snapshot()
    sim.rollback(to_collision=1)
    assert _same(sim.snapshot(), s1)
    sim.run(collisions=3000)
    assert _same(sim.snapshot(), s2)


def test_3d_collisions_after_a_reflection_on_one_tick_roll_back():
    sim = LatticeSimulation3D.load(os.path.join(DATA, "wall_body_twice_3d_n1000_phi0.45.npz"))
    ref = LatticeSimulation3D.load(os.path.join(DATA, "wall_body_twice_3d_n1000_phi0.45.npz"))
    sim.keep_journal()
    sim.run(collisions=1000)
    assert sim.diagnostics()["wall_body"] == 2
    for k in (500, 2, 1, 0):
        sim.rollback(to_collision=k)
        ref.run_back(to_collision=0)
        ref.run(collisions=k)
        assert _same(sim.snapshot(), ref.snapshot()), k


def test_state_saving_holds_more_than_the_journal_of_reverse_computation():
    sizes = {}
    for by in ("reverse", "save_all", "save_changes"):
        sim = LatticeSimulation3D.random(n=300, phi=0.3, seed=4)
        sim.keep_journal(by=by)
        sim.run(collisions=2000)
        sizes[by] = sim.journal["bytes"]
        s = sim.snapshot()
        sim.run(collisions=500)
        sim.rollback(to_collision=2000)
        assert _same(sim.snapshot(), s)
    assert sizes["reverse"] < sizes["save_changes"] < sizes["save_all"]


def test_rollback_to_a_time_is_the_state_a_run_to_that_time_has():
    sim = LatticeSimulation.random(n=200, phi=0.5, boundary="wall", seed=5)
    ref = LatticeSimulation.random(n=200, phi=0.5, boundary="wall", seed=5)
    sim.keep_journal()
    sim.run(collisions=4000)
    t = sim.time * 0.6
    r = sim.rollback(time=t)
    ref.run(time=t)
    assert r["clock"] == ref.clock and r["collisions"] == 4000 - ref.collisions
    assert _same(sim.snapshot(), ref.snapshot())
    sim.commit(ref.collisions - 10)
    assert sim.journal["start"] == ref.collisions - 10


def test_rollback_refusals_leave_the_state_unchanged():
    sim = LatticeSimulation.random(n=100, phi=0.4, seed=2)
    sim.run(collisions=200)
    s = sim.snapshot()
    with pytest.raises(ValueError, match="keeps no journal"):
        sim.rollback(to_collision=100)
    sim.keep_journal()
    sim.run(collisions=100)
    s2 = sim.snapshot()
    with pytest.raises(ValueError, match=r"\[journal_start, collisions\] = \[200, 300\]"):
        sim.rollback(to_collision=199)
    with pytest.raises(ValueError, match="one of to_collision= and time="):
        sim.rollback()
    with pytest.raises(ValueError, match="to_collision"):
        sim.rollback(to_collision=-1)
    with pytest.raises(ValueError, match="lattice commit"):
        sim.commit(301)
    with pytest.raises(ValueError, match="rollback by must be"):
        sim.keep_journal(by="ss3")
    assert _same(sim.snapshot(), s2)
    sim.rollback(to_collision=200)
    assert _same(sim.snapshot(), s)
    # a run back starts the journal afresh where it leaves the state
    sim.run(collisions=50)
    sim.run_back(collisions=20)
    assert sim.journal["start"] == 230 and sim.journal["size"] == 0
