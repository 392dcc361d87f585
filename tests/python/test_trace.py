"""The float engine's collision trace from Python: run_back says when its reversal left the
forward trajectory (issue 17; cpp/include/revcol/engine/trace.hpp, docs/robustness.md)."""
import os
import sys
import warnings

import numpy as np
import pytest

import revcol

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "long"))
import trace_study  # noqa: E402


def _gas(collisions, seed=4, n=300, d=2):
    s = revcol.Simulation.random(n, d, 0.3, seed=seed)
    s.run(collisions=collisions)
    return s


def test_within_the_horizon_nothing_is_said():
    s = _gas(600)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r = s.run_back()
    assert r["diverged"] is False
    g = s.diagnostics()
    assert g["divergence"] is None and g["diverged_at"] is None
    assert g["verified_at"] == 0
    assert s.time == 0.0


def test_beyond_the_horizon_run_back_warns_and_names_the_collision():
    s = _gas(30000)
    with pytest.warns(RuntimeWarning, match=r"run_back diverged at forward collision [\d,]+ \(collision sequence"):
        r = s.run_back()
    assert r["diverged"] is True
    g = s.diagnostics()
    assert 0 < g["diverged_at"] < 30000
    assert s.time == 0.0  # "warn" runs on to the target


def test_stop_and_ignore():
    s = _gas(30000)
    with pytest.warns(RuntimeWarning):
        r = s.run_back(on_divergence="stop")
    assert r["diverged"] and s.time > 0.0
    assert s.diagnostics()["net_collisions"] <= s.diagnostics()["diverged_at"]
    t = _gas(30000)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r = t.run_back(on_divergence="ignore")
    assert r["diverged"] is True


def test_bad_on_divergence_changes_nothing():
    s = _gas(1000)
    before = s.snapshot()
    with pytest.raises(ValueError, match="on_divergence"):
        s.run_back(on_divergence="halt")
    after = s.snapshot()
    for k, v in before.items():
        assert np.array_equal(np.asarray(v), np.asarray(after[k])), k


def test_checkpoint_keeps_the_trace_and_an_old_one_loads(tmp_path):
    s = _gas(1500, d=3)
    p = tmp_path / "c.npz"
    s.save(p)
    r = revcol.Simulation.load(p)
    assert np.array_equal(r.snapshot()["trace"], s.snapshot()["trace"])
    r.run_back()
    assert r.diagnostics()["verified_at"] == 0
    snap = s.snapshot()
    del snap["trace"]  # written before the trace existed
    old = revcol.Simulation.from_snapshot(snap)
    old.run_back()
    assert old.diagnostics()["divergence"] is None
    bad = s.snapshot()
    bad["trace"] = bad["trace"][:-1]
    with pytest.raises(ValueError, match="trace"):
        revcol.Simulation.from_snapshot(bad)


def test_detection_matches_the_round_trip_error():
    """tests/long/trace_study.py's claims on a reduced grid: no false alarm within the bar, every
    O(1) failure reported."""
    rows = []
    for seed in (1, 2):
        rows += trace_study.run_case(2, 300, 0.3, "periodic", seed, grid=[2, 6, 24, 100])
        rows += trace_study.run_case(3, 500, 0.45, "wall", seed, grid=[2, 6, 48])
    c = trace_study.classify(rows)
    assert c["within_bar"] >= 4 and c["failed"] >= 4  # both classes are present, so the test can fail
    assert c["false_alarms"] == 0
    assert c["silent_failures"] == 0
