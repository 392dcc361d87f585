"""The parallel lattice engine from Python and the CLI (issue 55): LatticeSimulation's
set_parallel / workers= runs forward and back on Time Warp and reaches the sequential engine's
state bit for bit, at a collision count or a time, 2D and 3D, periodic and walls, on more logical
processes than cores, and back to the start exactly; checkpoints (resumed on another K) and
attached actions work on the state it leaves; bad settings are named and leave the state as it was; an observation
running through it is the sequential run's bit for bit (so are a trajectory's image flags), a
stopped one is kept; scenes and `revcol run/simulate --workers` report the run."""
import json

import numpy as np
import pytest

from revcol import Simulation
from revcol.cli.main import main as cli_main
from revcol.lattice import LatticeSimulation, LatticeSimulation3D, add_reports
from revcol.lattice_gas import build_lattice
from revcol.scene import SceneError, scene_from_dict

# every part of the state a run changes
STATE = ("x", "v", "streams", "bits", "bits_size", "clock", "origin", "collisions", "particle_collisions",
         "log_particle", "log_count", "log_redraws", "group_drawer", "group_counts", "group_members", "group_v")


def _same(a: dict, b: dict) -> bool:
    return all(np.array_equal(np.asarray(a[k]), np.asarray(b[k])) for k in STATE)


def _pair(cls, n, phi, boundary, seed, **par):
    seq = cls.random(n, phi=phi, boundary=boundary, seed=seed)
    par_sim = cls.random(n, phi=phi, boundary=boundary, seed=seed)
    par_sim.set_parallel(**par)
    return seq, par_sim


@pytest.mark.parametrize("cls,n,phi,boundary,par", [
    (LatticeSimulation, 2000, 0.4, "periodic", dict(workers=2)),
    (LatticeSimulation, 2000, 0.3, "wall", dict(workers=2, lps=5)),   # more LPs than cores
    (LatticeSimulation3D, 2000, 0.3, "periodic", dict(workers=2, lps=3, axis=2)),
    (LatticeSimulation3D, 2000, 0.25, "bounce", dict(workers=1, lps=4)),  # four LPs on one thread
])
def test_a_parallel_run_is_the_sequential_run_bit_for_bit(cls, n, phi, boundary, par):
    seq, sim = _pair(cls, n, phi, boundary, 5, **par)
    s0 = sim.snapshot()
    for collisions in (30_000, 45_000):  # a stop at a collision count, twice
        a, b = seq.run(collisions=collisions), sim.run(collisions=collisions)
        assert b["collisions"] == a["collisions"] == collisions
        p = b["parallel"]
        assert p["parallel_collisions"] > collisions // 2  # most of the run is the parallel engine's
        assert p["parallel_collisions"] + p["sequential_collisions"] == collisions
        assert p["events"] >= p["parallel_collisions"] and len(p["lp_events"]) == sim.parallel["lps"]
        assert p["gvts"] >= 1 and 0.0 < p["gvt_s"] < p["parallel_s"]  # the GVT step, timed, is part of the parallel phase
        assert _same(seq.snapshot(), sim.snapshot())
    t = sim.time * (1.0 + 40_000 / sim.collisions)  # a stop at a time, some 40 000 collisions on
    a, b = seq.run(time=t), sim.run(time=t)
    assert (a["collisions"], a["clock"]) == (b["collisions"], b["clock"]) and a["collisions"] > 20_000
    assert b["parallel"]["sequential_collisions"] == 0 and _same(seq.snapshot(), sim.snapshot())
    assert sim.parallel_report == b["parallel"]
    # back on the parallel engine too (run_back's reversed frame): part way, to a collision count
    # and to a time, then to the start, which is the first state bit for bit
    a, b = seq.run_back(collisions=50_000), sim.run_back(collisions=50_000)
    assert a["collisions"] == b["collisions"] == 50_000 and _same(seq.snapshot(), sim.snapshot())
    p = b["parallel"]
    assert p["parallel_collisions"] > 25_000 and p["parallel_collisions"] + p["sequential_collisions"] == 50_000
    t = sim.time / 2
    a, b = seq.run_back(time=t), sim.run_back(time=t)
    assert (a["collisions"], a["clock"]) == (b["collisions"], b["clock"]) and b["parallel"]["sequential_collisions"] == 0
    assert _same(seq.snapshot(), sim.snapshot())
    sim.run_back()
    assert _same(sim.snapshot(), s0)


def test_the_rollback_by_state_saving_and_aggressive_cancellation_give_the_same_bits():
    seq = LatticeSimulation.random(1500, phi=0.45, seed=9)
    seq.run(collisions=25_000)
    per_entry = {}
    for how, lazy in (("reverse", True), ("save_all", True), ("save_changes", False)):
        sim = LatticeSimulation.random(1500, phi=0.45, seed=9, workers=2, lps=3)
        sim.set_parallel(2, lps=3, rollback=how, lazy=lazy, window=2000)
        p = sim.run(collisions=25_000)["parallel"]
        assert _same(seq.snapshot(), sim.snapshot()), how
        # the journals' memory as the GVTs found them: an entry (a queue pop, 24 bytes), the states
        # messages replaced and, state saving, the states saved with it (SS1 whole records, SS2
        # lines and X only)
        assert p["journal_peak_bytes"] >= 24 and p["journal_bytes_per_entry"] >= 24.0, how
        per_entry[how] = p["journal_bytes_per_entry"]
    assert per_entry["reverse"] < per_entry["save_changes"] < per_entry["save_all"]


def test_short_runs_stay_sequential_and_the_report_says_so():
    seq, sim = _pair(LatticeSimulation, 600, 0.3, "periodic", 2, workers=2)
    r = sim.run(collisions=3000)  # at most max(8192, N/4): building K views would cost more
    assert r["parallel"]["sequential_collisions"] == 3000 and r["parallel"]["parallel_collisions"] == 0
    seq.run(collisions=3000)
    assert _same(seq.snapshot(), sim.snapshot())
    assert LatticeSimulation.random(60, phi=0.3).run(collisions=10).get("parallel") is None  # sequential: none


def test_a_checkpoint_of_a_parallel_run_resumes_on_any_k(tmp_path):
    seq, sim = _pair(LatticeSimulation3D, 1500, 0.3, "periodic", 4, workers=2)
    sim.run(collisions=20_000)
    path = tmp_path / "ck.npz"
    sim.save(path)
    back = LatticeSimulation.load(path)
    assert back.parallel["lps"] == 1  # a checkpoint holds no workers
    back.set_parallel(2, lps=4)
    back.run(collisions=20_000)
    seq.run(collisions=40_000)
    assert _same(seq.snapshot(), back.snapshot())


def test_attached_actions_fire_at_the_same_counts():
    seq, sim = _pair(LatticeSimulation, 1200, 0.35, "periodic", 8, workers=2)
    seen = {"seq": [], "par": []}
    seq.attach(lambda s: seen["seq"].append((s.collisions, s.clock)), every=12_000)
    sim.attach(lambda s: seen["par"].append((s.collisions, s.clock)), every=12_000)
    seq.run(collisions=36_000)
    r = sim.run(collisions=36_000)
    assert seen["seq"] == seen["par"] and len(seen["par"]) == 3
    assert r["parallel"]["parallel_collisions"] > 0  # the segments between triggers ran in parallel
    assert _same(seq.snapshot(), sim.snapshot())


def test_the_reports_add_up():
    a = {"collisions": 5, "stopped": False, "lp_events": [1, 2], "events": 7}
    b = {"collisions": 3, "stopped": True, "lp_events": [4, 4], "events": 2}
    assert add_reports(a, b) == {"collisions": 8, "stopped": True, "lp_events": [5, 6], "events": 9}
    assert add_reports(None, b) == b and add_reports(a, None) == a and add_reports(None, None) is None
    assert add_reports(a, {**b, "lp_events": [1, 1, 1]})["lp_events"] == [1, 1, 1]  # another K: the later's


# --- bad settings, observation --------------------------------------------------------------------

@pytest.mark.parametrize("kwargs,err,needle", [
    (dict(workers=0), ValueError, "workers = 0 is outside [1, 64]"),
    (dict(workers=3, lps=2), ValueError, "workers must be at most lps"),
    (dict(workers=2, lps=65), ValueError, "lps = 65 is outside [1, 64]"),
    (dict(workers=2.0), TypeError, "workers must be an integer"),
    (dict(workers=2, axis=2), ValueError, "axis = 2 is outside [0, 1]"),
    (dict(workers=2, rollback="undo"), ValueError, "rollback must be 'reverse', 'save_all' (SS1)"),
    (dict(workers=2, lazy="yes"), ValueError, "lazy must be True or False"),
    (dict(workers=2, window=-1), ValueError, "window = -1 is outside"),
])
def test_bad_settings_are_named_and_change_nothing(kwargs, err, needle):
    sim = LatticeSimulation.random(200, phi=0.3, seed=1, workers=2)
    before = sim.parallel
    with pytest.raises(err) as e:
        sim.set_parallel(**kwargs)
    assert needle in str(e.value)
    assert sim.parallel == before
    if set(kwargs) <= {"workers", "lps"}:  # the constructors' keywords
        with pytest.raises(err):
            LatticeSimulation.random(200, phi=0.3, seed=1, **{"workers": 2, **kwargs})


def test_the_binding_names_bad_settings_and_keeps_the_state():
    sim = LatticeSimulation.random(2000, phi=0.3, seed=1)
    s0 = sim.snapshot()
    with pytest.raises(ValueError, match="workers must be at most lps"):
        sim._e.run_parallel(50_000, None, lps=2, workers=3)
    with pytest.raises(ValueError, match="fuzz .* runs on one worker"):
        sim._e.run_parallel(50_000, None, lps=2, workers=2, fuzz=3)
    with pytest.raises(ValueError, match="the end tick is before the clock"):
        sim._e.run_parallel(None, -1)
    sim.run(collisions=20_000)
    s1 = sim.snapshot()
    with pytest.raises(ValueError, match="the target collision count is ahead of the state"):
        sim._e.run_back_parallel(30_000, None, lps=2, workers=2)
    with pytest.raises(ValueError, match=r"the target tick must be in \[origin, clock\]"):
        sim._e.run_back_parallel(None, sim.clock + 1, lps=2, workers=2)
    with pytest.raises(ValueError, match="workers must be at most lps"):
        sim._e.run_back_parallel(None, None, lps=2, workers=3)
    assert _same(sim.snapshot(), s1)
    sim.run_back()
    assert _same(sim.snapshot(), s0)
    # a fuzzed schedule (random order and message delays) on one worker: the same bits
    seq = LatticeSimulation.random(2000, phi=0.3, seed=1)
    seq.run(collisions=30_000)
    sim._e.run_parallel(30_000, None, lps=3, workers=1, fuzz=77)
    assert _same(seq.snapshot(), sim.snapshot())


@pytest.mark.parametrize("cls, boundary, lps", [(LatticeSimulation, "periodic", 3), (LatticeSimulation3D, "wall", 2)])
def test_an_observation_through_a_parallel_run_is_the_sequential_one(cls, boundary, lps):
    seen = {}
    for workers in (1, 2):
        sim = cls.random(2000, phi=0.3, boundary=boundary, seed=3)
        sim.set_parallel(workers, lps=lps if workers > 1 else None)
        sim.run(collisions=2000)
        sim.observe(slabs=4, speed_bins=8)
        r = sim.run(collisions=40_000)
        assert workers == 1 or r["parallel"]["parallel_collisions"] > 20_000
        sim.run(time=sim.time + 0.5)
        seen[workers] = sim.observation().to_dict()
        assert sim.observing
    assert seen[1] == seen[2] and seen[1]["pair_collisions"] > 40_000 and len(seen[1]["msd"]) > 0


def test_a_stopped_observation_is_kept_through_a_parallel_run():
    sim = LatticeSimulation.random(2000, phi=0.3, seed=3, workers=2)
    sim.observe()
    sim.run(collisions=5000)
    sim.stop_observing()
    seen = sim.observation().to_dict()
    sim.run(collisions=20_000)
    assert sim.observation().to_dict() == seen and not sim.observing  # still readable, not fed


def test_the_simulation_front_door_takes_workers():
    sim = Simulation.random(n=1500, dim=2, phi=0.3, seed=6, engine="lattice", workers=2)
    assert sim.workers == 2 and sim.parallel["lps"] == 2
    seq = Simulation.random(n=1500, dim=2, phi=0.3, seed=6, engine="lattice")
    assert sim.run(collisions=20_000)["parallel"]["parallel_collisions"] > 0
    seq.run(collisions=20_000)
    assert _same(seq.snapshot(), sim.snapshot())


# --- scenes and the CLI -------------------------------------------------------------------------

def _gas(engine="lattice", **collisions):
    doc = {"system": {"dimension": 2, "particles": 2000, "packing_fraction": 0.35, "boundaries": "periodic"},
           "collisions": {"engine": engine, **collisions}, "rng": {"seed": 3}, "run": {"collisions": 40_000}}
    return scene_from_dict(doc, "t.toml")


def test_the_scene_field_reaches_the_engine_and_is_checked():
    assert build_lattice(_gas(workers=2)).parallel["workers"] == 2
    with pytest.raises(SceneError, match=r"\[collisions\] workers: must be 1..64, got 0"):
        _gas(workers=0)
    with pytest.raises(SceneError, match=r"\[collisions\] workers: applies to engine = 'lattice' only"):
        _gas(engine="float", workers=2)


def _scene_file(tmp_path, **collisions):
    extra = "".join(f"{k} = {json.dumps(v)}\n" for k, v in collisions.items())
    p = tmp_path / "g.toml"
    p.write_text("[system]\ndimension = 2\nparticles = 2000\npacking_fraction = 0.35\nboundaries = 'periodic'\n"
                 f"[collisions]\nengine = 'lattice'\n{extra}[rng]\nseed = 3\n[run]\ncollisions = 40000\n")
    return str(p)


def test_revcol_run_with_workers_comes_back_bit_for_bit(tmp_path, capsys):
    out = tmp_path / "r.json"
    assert cli_main(["run", _scene_file(tmp_path), "--workers", "2", "--json", str(out), "--no-progress"]) == 0
    r = json.loads(out.read_text())
    assert r["bit_for_bit"] and r["collisions_forward"] == 40_000
    p = r["parallel"]
    assert (p["workers"], p["lps"]) == (2, 2) and p["parallel_collisions"] > 20_000
    text = capsys.readouterr().out
    assert "2 logical processes on 2 worker thread(s)" in text
    assert f"journals at most {p['journal_peak_bytes']:,} bytes ({p['journal_bytes_per_entry']:.0f} per entry)" in text
    assert p["journal_peak_bytes"] > 0 and p["journal_bytes_per_entry"] >= 24.0  # at least the pops (24 bytes each)
    b = r["parallel_back"]  # the run back, on the parallel engine too
    assert b["parallel_collisions"] > 20_000 and b["parallel_collisions"] + b["sequential_collisions"] == 40_000
    assert f"parallel back    {b['parallel_collisions']:,} collisions taken back in parallel" in text


def test_revcol_simulate_with_workers_is_the_sequential_run(tmp_path, capsys):
    s = _scene_file(tmp_path)
    ends = []
    for workers in ("1", "2"):
        ck = tmp_path / f"ck{workers}"
        assert cli_main(["simulate", s, "--workers", workers, "--checkpoint", str(ck), "--checkpoint-every", "40000",
                         "--json", "-", "--no-progress"]) == 0
        r = json.loads(capsys.readouterr().out)
        assert (r["parallel"] is None) == (workers == "1")
        ends.append(LatticeSimulation.load(r["checkpoints"][-1]).snapshot())
    assert _same(*ends)
    # an observed run (a periodic trajectory's image flags) on the parallel engine: the same frames
    frames = []
    for workers in ("1", "2"):
        t = tmp_path / f"t{workers}.xyz"
        assert cli_main(["simulate", s, "--workers", workers, "--trajectory", str(t), "--no-progress"]) == 0
        frames.append(t.read_text())
    assert frames[0] == frames[1] and len(frames[0]) > 1000
