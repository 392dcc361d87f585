"""The checkpoint property run (issue 59, revcol.studies.fuzz_checkpoints), reduced for CI: a few
hundred examples of save / tamper / load / run / run_back / save-load / snapshot over both
engines in 2D and 3D, every boundary kind and mode, in child processes. No crash, no hang, every
exception a named one with the state unchanged, no silent divergence, no corrupted file loaded.
The long run (10^5 examples) is bench/results/checkpoint_property_run.json (docs/robustness.md).
"""
from __future__ import annotations

import os
import time

import numpy as np
import pytest

from revcol.studies import fuzz_checkpoints as fc

EXAMPLES = int(os.environ.get("REVCOL_FUZZ_CHECKPOINT_EXAMPLES", "400"))

def test_the_reduced_property_run_finds_no_failure():
    t0 = time.time()
    s = fc.run(EXAMPLES, seed=59, batch=200)
    assert s["examples"] == EXAMPLES
    assert s["all_passed"] and not s["failure_records"], s["failure_records"][:5]
    # every tamper is drawn, and the run exercises refusals, identical loads and changed loads
    assert set(s["loads_per_tamper"]) == set(fc.TAMPERS)
    assert all(s["outcomes"].get(k, 0) > 0 for k in ("refused", "identical", "changed")), s["outcomes"]
    for kind in fc.MUST_REFUSE:
        assert set(s["loads_per_tamper"][kind]) == {"refused"}
    assert s["round_trips"].get("lattice_bit_for_bit", 0) > 0 and s["round_trips"].get("float_within_1e-9", 0) > 0
    assert {"float", "lattice"} == {k.split()[0] for k in s["systems"]}
    assert time.time() - t0 < 120


def test_an_example_is_a_function_of_seed_and_index(tmp_path):
    a = fc.run_example(59, 7, tmp_path)
    b = fc.run_example(59, 7, tmp_path)
    assert a == b


def test_a_child_killed_by_a_signal_is_counted_as_a_crash_and_the_run_goes_on(monkeypatch):
    monkeypatch.setenv(fc.ABORT_AT_ENV, "2")
    s = fc.run(5, seed=59, batch=5)
    assert s["examples"] == 5
    assert s["failures"]["crash"] == 1 and not s["all_passed"]
    crash = s["failure_records"][0]
    assert crash["index"] == 2 and "signal" in crash["what"]


def test_a_flipped_byte_under_the_old_digest_is_refused_by_name(tmp_path):
    import revcol
    sim = revcol.Simulation.random(20, 2, 0.2, boundary="wall", seed=3, engine="lattice")
    sim.run(collisions=30)
    path = tmp_path / "c.npz"
    sim.save(path)
    fc.tamper(path, "flip_keep_digest", np.random.default_rng(0), sim.n)
    with pytest.raises(ValueError, match="digest mismatch"):
        type(sim).load(path)


def _drop_centre(z):
    z.pop("centre")


def _centre_int32(z):
    z["centre"] = z["centre"].astype("<i4")


def _specular_as_exact(z):
    z["mode"] = np.asarray("exact")


def _rng_one_on(z):
    z["rng"] = z["rng"].copy()
    z["rng"][1] += np.uint64(1)


# forged float checkpoints (re-digested) that the property run found loading, and the engine then
# passing particles through each other unreported (examples 179, 5159, 30751, 33807 of seed 59,
# minimized): (gas, edit, what is run, what must happen). A schedule or list centres that do not fit
# the particles are refused at load; forged draws or a forged mode cannot be seen in the file, and the
# run_back they mislead reports its divergence ("particles overlap") where it ends
FORGED_FLOAT = {
    "rng_counter_one_on": (dict(n=18, dim=3, phi=0.235, boundary=["bounce", "wall", "wall"], seed=1009,
                                law="uniform", before=42), _rng_one_on, "run_back", "diverged"),
    "specular_mode_read_as_exact": (dict(n=60, dim=2, phi=0.3, seed=7, mode="specular", before=180),
                                    _specular_as_exact, "run_back", "diverged"),
    "list_centres_as_int32": (dict(n=60, dim=2, phi=0.3, seed=7, before=180), _centre_int32, "run", "refused"),
    "list_centres_dropped": (dict(n=119, dim=2, phi=0.2, seed=1, before=100), _drop_centre, "nothing", "loads"),
}


@pytest.mark.parametrize("name", sorted(FORGED_FLOAT))
def test_a_forged_float_checkpoint_is_refused_or_its_divergence_reported(name, tmp_path):
    import warnings

    import revcol
    from revcol._io import digested

    gas, edit, then, expect = FORGED_FLOAT[name]
    gas = dict(gas)
    n, dim, phi, before = gas.pop("n"), gas.pop("dim"), gas.pop("phi"), gas.pop("before")
    s = revcol.Simulation.random(n, dim, phi, **gas)
    s.run(collisions=before)
    path = tmp_path / "forged.npz"
    s.save(path)
    z = dict(np.load(path))
    edit(z)
    np.savez(path, **digested(z))
    if expect == "refused":
        with pytest.raises(ValueError, match=r"schedule .* does not fit the particles .* beyond its reach"):
            revcol.Simulation.load(path)
        return
    t = revcol.Simulation.load(path)
    assert t._e.fault() == ""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = {"run": lambda: t.run(collisions=30), "run_back": lambda: t.run_back(collisions=30),
             "nothing": lambda: {}}[then]()
    if expect == "diverged":
        assert r["diverged"] and t.diagnostics()["divergence"] == "particles overlap"
        with pytest.raises(ValueError, match="overlap"):  # a state no run continues: refused by name
            revcol.Simulation.from_snapshot(t.snapshot())
        with pytest.raises(ValueError, match=r"cannot save .* overlap.*run_back diverged at forward collision"):
            t.save(tmp_path / "after.npz")
        assert not (tmp_path / "after.npz").exists()
    else:  # the centres recomputed where the particles are, inside the box: a state that reloads
        revcol.Simulation.from_snapshot(t.snapshot())
        t.run(collisions=200)
        assert t._e.fault() == ""
