"""CI-reduced version of tests/long/lattice_validation.py (issue 13, "Done when"): the same code paths
on small gases. The full runs (N = 10^3, 10^4, 10^7 collisions) are bench/results/lattice_validation_*.json."""
import importlib.util
import math
import os

import numpy as np

from revcol import lattice

_PATH = os.path.join(os.path.dirname(__file__), "..", "long", "lattice_validation.py")
_spec = importlib.util.spec_from_file_location("lattice_validation", _PATH)
lv = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(lv)

N, C = 200, 20000


def _check_row(row, boundary, dim=2):
    assert row["roundtrip"] == {k: True for k in row["roundtrip"]}, row["roundtrip"]
    assert row["midpoint"] == {k: True for k in row["midpoint"]}, row["midpoint"]
    assert row["completed"] and row["forward_error"] is None
    assert row["bit_for_bit"]
    assert row["collisions"] == C and row["midpoint_collision"] == C // 2
    assert row["collisions_checked_back"] == C
    assert row["log_entries_per_collision"] <= 1e-5  # here: no entry at all in 2e4 collisions
    assert row["bits_X"]["after_reverse"] == row["bits_X"]["start"]
    # flux law: X stays bounded (its size changes by O(1) bits per collision, no drift)
    assert row["bits_X"]["max"] - row["bits_X"]["min"] <= 16
    dr = row["drift_after_c"]
    # energy: a random walk of ~2^-40 of a pair's energy per collision; 2^-30 would be a bug
    assert dr["energy_error_per_collision_in_2^-40_of_pair_energy"] < 2.0 ** 10
    assert abs(dr["energy_drift_relative"]) < 1e-9
    # momentum: at most one lattice unit per component per collision on a periodic axis
    periodic = [k for k in range(dim) if boundary == "periodic"]
    assert dr["momentum_conserved_axes"] == periodic
    for k in periodic:
        assert abs(dr["momentum_drift_units"][k]) <= C
    marks = [r["collisions"] for r in row["rss"]]
    assert marks == [1000, 10000, C]
    assert all(r["vmhwm_bytes"] >= r["vmrss_bytes"] > 0 for r in row["rss"])


def test_periodic_gas_round_trip_and_midpoint_in_process():
    _check_row(lv.run_gas(N, 0.5, "periodic", C, seed=3), "periodic")


def test_wall_gas_round_trip_and_midpoint_in_a_subprocess():
    row = lv.run_child(N, 0.3, "wall", C, seed=2)
    assert row["child_exit"] == 0, row.get("error")
    _check_row(row, "wall")
    assert row["wall_reflections_forward"] > 0
    assert row["child_ru_maxrss_bytes"] >= row["rss"][-1]["vmhwm_bytes"]


def test_compare_states_sees_one_bit_in_each_part():
    sim = lattice.LatticeSimulation.random(n=50, phi=0.3, seed=4)
    sim.run(collisions=200)
    a = sim.snapshot()
    assert lv.compare_states(a, sim.snapshot())["all"]
    for part, keys in lv.STATE_PARTS.items():
        b = dict(a)
        k = keys[0]
        arr = np.array(b[k], copy=True)
        if arr.size == 0:  # an empty rare log: a longer one differs too
            arr = np.zeros(1, dtype=np.asarray(b[k]).dtype)
        else:
            flat = arr.reshape(-1)
            flat[0] = flat[0] ^ 1
        b[k] = arr if arr.ndim else arr.item()
        got = lv.compare_states(a, b)
        assert not got[part] and not got["all"], part
        assert all(got[p] for p in lv.STATE_PARTS if p != part), part


def test_checkpoints_cover_decades_midpoint_and_end():
    assert lv._checkpoints(10 ** 7) == [1000, 10 ** 4, 10 ** 5, 10 ** 6, 5 * 10 ** 6, 10 ** 7]
    assert lv._checkpoints(3000) == [1000, 1500, 3000]


def test_rayleigh_ks_accepts_maxwell_rejects_equal_speeds():
    rng = np.random.default_rng(5)
    v = rng.normal(size=(4000, 2)) * math.sqrt(1.7)
    _, p = lv.rayleigh_ks(np.linalg.norm(v, axis=1), 1.7)
    assert p > 1e-3
    _, p = lv.rayleigh_ks(np.full(4000, math.sqrt(2 * 1.7)), 1.7)
    assert p < 1e-6


def test_dense_lattice_gas_relaxes_to_maxwell_with_the_float_collision_rate():
    n = 200
    gases = [lv.equilibrium_gas(n, 0.5, seed, relax=30, gap=4, snapshots=10, batch=10, batches=5)
             for seed in (1, 2, 3)]
    s = lv.equilibrium_summary(gases, n)
    assert s["ks_p_equal_speed_start"] < 1e-6  # the start is far from Maxwell-Boltzmann
    assert s["ks_p"] > 1e-3, s
    assert abs(s["kT"] - 1.0) < 0.01  # energy kept (speeds pooled over snapshots)
    # same collision rate as the float engine's flux law within 4 standard errors, and within 5%
    assert abs(s["rate_difference"]) <= 4 * s["rate_difference_se"], s
    assert abs(s["rate_relative_difference"]) < 0.05, s


def test_third_bodies_measures_a_gap_in_ticks_of_travel():
    v_rms = math.sqrt(2.0 / 3.0)
    tick = 2.0 ** -20 / v_rms  # units.hpp: a tick moves a particle of rms speed 2^-20 D
    x = np.array([[5.0, 5.0], [6.5, 5.0], [5.0, 6.0 + 2.0 * tick]])  # body 2 two ticks' travel above 0
    v = np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 0.0]])
    sim = lattice.LatticeSimulation(x, v, 10.0, boundary="periodic", tick_bits=20)
    assert abs(sim.units["tick"] / tick - 1.0) < 1e-6
    got = lv._third_bodies(sim, 0, 1, sim.clock)
    assert [(g["body"], g["near"]) for g in got] == [(2, 0)]
    assert np.allclose(got[0]["gap_ticks_at_a-1_a_a+1"], [2.0, 2.0, 2.0], atol=1e-3)
    m = lv._FAIL.search("lattice engine: collision 6617 of particles 603, 635 at tick 250525 found no ...")
    assert [int(g) for g in m.groups()] == [6617, 603, 635, 250525]


def test_group_census_finds_the_same_members_meeting_again():
    state = {"group_size": np.array([2, 3, 3, 3, 3]),
             "group_kind": np.array([1, 1, 0, 1, 0]),
             "group_members": np.array([1, 2, 4, 5, 6, 7, 8, 9, 7, 8, 9, 7, 8, 9]),
             "group_counts": np.array([5, 9, 3, 4, 8, 900, 905, 901, 950, 955, 951, 990, 995, 991])}
    c = lv.group_census(state)
    assert c["groups"] == 5 and c["resolves"] == 3 and c["bounces"] == 2 and c["distinct_groups"] == 3
    assert c["most_frequent"][0] == {"members": [7, 8, 9], "times": 3, "first": 900, "last": 990}
    assert c["most_groups_of_one_particle_in_100_of_its_collisions"] == 3
    assert lv.group_census(state, window=60)["most_groups_of_one_particle_in_60_of_its_collisions"] == 2


class _Dim3:
    """lv's module-level dimension set to 3 for the block (the 3D sphere gas, issue 14)."""

    def __enter__(self):
        lv.DIM = 3

    def __exit__(self, *exc):
        lv.DIM = 2


def test_3d_sphere_gases_round_trip_and_midpoint():
    with _Dim3():
        row = lv.run_gas(N, 0.45, "periodic", C, seed=3)
        assert row["dim"] == 3 and len(row["units"]["L"]) == 3
        _check_row(row, "periodic", dim=3)
        row = lv.run_child(N, 0.3, "wall", C, seed=2)
        assert row["child_exit"] == 0, row.get("error")
        assert row["dim"] == 3 and "--dim 3" in row["command"]
        _check_row(row, "wall", dim=3)
        assert row["wall_reflections_forward"] > 0


def test_maxwell_ks_in_3d_accepts_maxwell_rejects_the_2d_law_and_equal_speeds():
    rng = np.random.default_rng(6)
    s = np.linalg.norm(rng.normal(size=(4000, 3)) * math.sqrt(1.3), axis=1)
    assert lv.rayleigh_ks(s, 1.3, 3)[1] > 1e-3
    assert lv.rayleigh_ks(s, 1.3, 2)[1] < 1e-6  # the 2D law on 3D speeds: the test can fail
    assert lv.rayleigh_ks(np.full(4000, math.sqrt(3 * 1.3)), 1.3, 3)[1] < 1e-6


def test_dense_3d_lattice_gas_relaxes_to_maxwell_with_the_float_collision_rate():
    n = 200
    with _Dim3():
        gases = [lv.equilibrium_gas(n, 0.3, seed, relax=30, gap=4, snapshots=10, batch=10, batches=5)
                 for seed in (1, 2, 3)]
        s = lv.equilibrium_summary(gases, n)
    assert s["ks_p_equal_speed_start"] < 1e-6
    assert s["ks_p"] > 1e-3, s
    assert abs(s["kT"] - 1.0) < 0.01
    assert abs(s["rate_difference"]) <= 4 * s["rate_difference_se"], s
    assert abs(s["rate_relative_difference"]) < 0.05, s
