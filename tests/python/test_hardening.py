"""Issue 17's reproducers that crashed or never returned: each now raises a clear error and
leaves the simulation as it was (the first part of the hardening issue)."""
import numpy as np
import pytest

import revcol
from revcol import Simulation


def test_a_diameter_whose_box_underflows_is_refused():
    # was a segfault: the particle volume underflowed, the box was 0, a cell index overflowed
    with pytest.raises(ValueError, match="not representable"):
        Simulation.random(10, 2, 0.3, diameter=1e-300)


def test_a_box_longer_than_2_30_diameters_is_refused():
    # was a hang: floor(L / D) overflowed int and defeated the cell-count check
    x = np.array([[1.0, 1.0], [3.0, 3.0]])
    v = np.array([[1.0, 0.0], [0.0, 1.0]])
    with pytest.raises(ValueError, match="2\\^30"):
        Simulation(x, v, [5.0, 5.0], diameter=1e-10)
    Simulation(x, v, [5.0, 5.0], diameter=1e-3).run(time=1.0)  # 5000 diameters: allowed


@pytest.mark.parametrize("partner", [2_000_000_000, -3, 1, 4])
def test_a_forged_wall_event_in_a_snapshot_is_refused(partner):
    # was a segfault (out-of-bounds write in the wall event) or a silently flipped position
    s = Simulation.random(50, 2, 0.3, boundary=["periodic", "wall"], seed=1)
    st = s.snapshot()
    st["ev_kind"][0] = 0  # a wall event
    st["ev_partner"][0] = partner  # axis partner // 2 (0 is periodic here), upper partner % 2
    st["ev_t"][0] = st["time"]
    with pytest.raises(ValueError, match="wall event"):
        Simulation.from_snapshot(st)
    st["ev_partner"][0] = 2  # axis 1, lower wall: a real wall, accepted
    Simulation.from_snapshot(st).run(collisions=5)


def test_unbounded_runs_are_refused_and_change_nothing():
    # were endless loops: an infinite end time, an infinite target, 2^63 collisions back
    s = Simulation.random(50, 2, 0.3, seed=1)
    s.run(collisions=20)
    before = s.snapshot()
    with pytest.raises(ValueError, match="finite"):
        s.run(time=float("inf"))
    with pytest.raises(ValueError, match="finite"):
        s.run_back(time=-float("inf"))
    after = s.snapshot()
    assert all(np.array_equal(np.asarray(before[k]), np.asarray(after[k])) for k in ("x", "v", "time"))
    r = s.run_back(collisions=2**63)  # collisions alone: never past the start
    assert s.time == s.start_time and r["collisions"] <= 20 + 5
    s.run(collisions=10)
    s.run_back(time=s.start_time - 0.5)  # a finite time before the start is still allowed
    assert s.time == s.start_time - 0.5


def test_a_start_time_the_clock_cannot_resolve_is_refused():
    # was a hang: at t0 = 1e16 the clock's ulp (2) outgrew the flight times, events shared one time
    with pytest.raises(ValueError, match="shift the time origin"):
        Simulation.random(100, 2, 0.3, boundary="wall", time=1e16)
    s = Simulation.random(100, 2, 0.3, boundary="wall", time=1e6)  # allowed (round trips degrade: docs)
    s.run(collisions=50)
    st = s.snapshot()
    st["time"] = 1e16
    with pytest.raises(ValueError, match="too large for the clock"):
        Simulation.from_snapshot(st)


@pytest.mark.parametrize("energy", [float("nan"), -1.0, float("inf")])
def test_a_bad_start_energy_is_refused(energy):
    # was silently replaced by the default (kT = 1)
    with pytest.raises(ValueError, match="kinetic energy"):
        Simulation.random(100, 2, 0.3, energy=energy)


def test_run_checks_its_arguments_before_the_first_event():
    # callback=5 ran 10 collisions before the TypeError
    s = Simulation.random(50, 2, 0.3, seed=2)
    before = s.snapshot()
    with pytest.raises(TypeError, match="callable"):
        s.run(collisions=100, callback=5, every=10)
    with pytest.raises(ValueError, match="every"):
        s.run(collisions=100, callback=lambda k: None, every=0)
    after = s.snapshot()
    assert all(np.array_equal(np.asarray(before[k]), np.asarray(after[k])) for k in ("x", "v", "time", "rng"))
