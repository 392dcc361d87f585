"""The lattice engine's specular mode through the Python API: deterministic specular hard-sphere
dynamics, reversed bit for bit with no draws (revcol/lattice/specular.hpp; docs/lattice.md
"Specular dynamics"). Round trips in 2D and 3D with periodic axes and walls, Simulation(engine=
"lattice"), checkpoints (and old ones without a mode), pickling, scenes, the command line,
observation, and bad input that names its argument and leaves a simulation untouched."""
import copy
import pickle
import tomllib
from pathlib import Path

import numpy as np
import pytest

import revcol
from revcol.cli.main import main as cli_main
from revcol.lattice import MODES, LatticeSimulation, LatticeSimulation3D
from revcol.lattice_gas import log_size
from revcol.scene import SceneError, load_scene, scene_from_dict, with_engine, with_mode
from revcol.studies.scenes import run_scene

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "scenes" / "lattice-specular-3d.toml"


def same_state(a: dict, b: dict) -> bool:
    """Every entry of two snapshots equal, exactly (the quantization's float errors included)."""
    return a.keys() == b.keys() and all(
        same_state(a[k], b[k]) if isinstance(a[k], dict) else np.array_equal(np.asarray(a[k]), np.asarray(b[k]))
        for k in a)


def specular(cls=LatticeSimulation, n=120, boundary="periodic", seed=5, **kw):
    return cls.random(n, phi=0.3, boundary=boundary, seed=seed, mode="specular", **kw)


@pytest.mark.parametrize("cls,boundary", [
    (LatticeSimulation, "periodic"), (LatticeSimulation, "wall"), (LatticeSimulation, ["periodic", "bounce"]),
    (LatticeSimulation3D, "periodic"), (LatticeSimulation3D, "wall"),
    (LatticeSimulation3D, ["periodic", "wall", "bounce"]),
], ids=["2d-periodic", "2d-wall", "2d-bounce", "3d-periodic", "3d-wall", "3d-mixed"])
def test_round_trip_bit_for_bit_with_no_draws(cls, boundary):
    sim = specular(cls, boundary=boundary)
    assert sim.mode == "specular" and sim.snapshot()["mode"] == "specular"
    start = sim.snapshot()
    sim.run(collisions=4000)
    mid = sim.snapshot()
    sim.run(collisions=4000)
    turn = sim.snapshot()
    d = sim.diagnostics()
    assert sim.collisions == 8000 and d["collisions_applied"] >= 8000
    # no random number drawn, X never changed (a refusal goes to the group rule, which draws nothing here)
    assert np.array_equal(turn["streams"], start["streams"]) and np.array_equal(turn["bits"], start["bits"])
    assert d["backscatters"] >= 0 and abs(d["energy_drift"]) < 1e-8
    sim.run_back(to_collision=4000)
    assert same_state(sim.snapshot(), mid)  # the forward state at 4000, exactly
    sim.run_back()
    assert same_state(sim.snapshot(), start) and sim.collisions == 0 and sim.mode == "specular"


@pytest.mark.parametrize("cls,seed", [(LatticeSimulation, 3), (LatticeSimulation3D, 8)], ids=["2d", "3d"])
def test_round_trip_through_backscatters_and_group_collisions(cls, seed):
    # a coarse tick (2^-16) makes the rare cases common: a backscatter comes about once in 10^5
    # collisions, and these seeds meet one within 40 000 (with walls; seed 8 in 3D also a drawn fallback)
    sim = specular(cls, n=200, boundary="wall", seed=seed, tick_bits=16)
    start = sim.snapshot()
    sim.run(collisions=40_000)
    d, turn = sim.diagnostics(), sim.snapshot()
    assert d["backscatters"] >= 1
    # the rare log holds group collisions and the drawn fallbacks (a post centre beyond a wall)
    assert d["group_log_entries"] + d["drawn_fallbacks"] == d["log_entries"] >= 1
    assert log_size(turn)[0] == d["log_entries"]  # the report counts each group collision once
    sim.run_back()
    assert same_state(sim.snapshot(), start)
    assert sim.diagnostics()["log_entries"] == 0


def test_a_post_state_beyond_a_wall_is_drawn_logged_and_taken_back():
    # 3D walls at a coarse tick: a wall, the pair and the wall again within one tick (the map's
    # post centre beyond the wall) happens at 40 000 collisions for this seed; the randomized
    # operator draws that collision (streams and X move), the log keeps it, the reverse undoes it
    sim = LatticeSimulation3D.random(500, phi=0.4, boundary="wall", seed=1, tick_bits=16, mode="specular")
    start = sim.snapshot()
    sim.run(collisions=40_000)
    d, turn = sim.diagnostics(), sim.snapshot()
    assert d["drawn_fallbacks"] >= 1 and d["redraws"]["outside"] >= 1
    assert not np.array_equal(turn["streams"], start["streams"])
    sim.run_back()
    assert same_state(sim.snapshot(), start)


def test_specular_is_not_the_exact_run_and_is_deterministic():
    a, b = specular(seed=7), specular(seed=7)
    exact = LatticeSimulation.random(120, phi=0.3, seed=7)
    assert exact.mode == "exact"
    for s in (a, b, exact):
        s.run(collisions=1500)
    assert np.array_equal(a.lattice_velocities, b.lattice_velocities)
    assert not np.array_equal(a.lattice_velocities, exact.lattice_velocities)
    # the seed keys only the (unused) streams: the same start under another seed runs the same dynamics
    start = specular(seed=7)
    x, v, box = start.positions, start.velocities, start.box
    c, d = (LatticeSimulation(x, v, box, mode="specular", seed=s) for s in (1, 99))
    c.run(collisions=1000)
    d.run(collisions=1000)
    assert np.array_equal(c.lattice_positions, d.lattice_positions)


def test_simulation_engine_lattice_takes_the_mode():
    s2 = revcol.Simulation.random(n=100, dim=2, phi=0.3, seed=4, engine="lattice", mode="specular")
    s3 = revcol.Simulation.random(n=100, dim=3, phi=0.3, seed=4, engine="lattice", mode="specular")
    assert isinstance(s2, LatticeSimulation) and isinstance(s3, LatticeSimulation3D)
    assert s2.mode == s3.mode == "specular" and isinstance(s2, revcol.SimulationBase)
    assert revcol.Simulation.random(n=100, dim=2, engine="lattice").mode == "exact"
    arrays = revcol.Simulation(s3.positions, s3.velocities, s3.box, engine="lattice", mode="specular", seed=4)
    assert type(arrays) is LatticeSimulation3D and arrays.mode == "specular"
    for s in (s2, s3):
        x0 = s.lattice_positions
        s.run(collisions=1000)
        s.run_back()
        assert np.array_equal(s.lattice_positions, x0)
    assert MODES == ("exact", "specular")


def test_checkpoint_save_load_and_pickle_keep_the_mode(tmp_path):
    sim = specular(LatticeSimulation3D, boundary="wall")
    sim.run(collisions=1500)
    sim.save(tmp_path / "c.npz")
    back = LatticeSimulation.load(tmp_path / "c.npz")
    clone = pickle.loads(pickle.dumps(sim))
    deep = copy.deepcopy(sim)
    for other in (back, clone, deep):
        assert type(other) is LatticeSimulation3D and other.mode == "specular"
        assert same_state(other.snapshot(), sim.snapshot())
    sim.run(collisions=1000)
    for other in (back, clone):  # resumed bit for bit
        other.run(collisions=1000)
        assert same_state(other.snapshot(), sim.snapshot())
    back.run_back()
    assert back.collisions == 0 and back.mode == "specular"


def test_an_old_checkpoint_without_a_mode_loads_as_exact(tmp_path):
    sim = LatticeSimulation.random(100, phi=0.3, seed=2)
    sim.run(collisions=800)
    snap = sim.snapshot()
    old = {k: v for k, v in snap.items() if k != "mode"}
    assert LatticeSimulation.from_snapshot(old).mode == "exact"
    sim.save(tmp_path / "new.npz")
    with np.load(tmp_path / "new.npz") as z:
        arrays = {k: z[k] for k in z.files if k not in ("mode", "digest_sha256")}  # an older revcol wrote neither
    assert "revcol_engine" in arrays
    np.savez(tmp_path / "old.npz", **arrays)
    loaded = LatticeSimulation.load(tmp_path / "old.npz")
    assert loaded.mode == "exact" and same_state(loaded.snapshot(), snap)
    loaded.run(collisions=500)
    sim.run(collisions=500)
    assert same_state(loaded.snapshot(), sim.snapshot())
    # and a mode the snapshot cannot hold is refused by name
    with pytest.raises(ValueError, match="mode"):
        LatticeSimulation.from_snapshot({**snap, "mode": "paper"})


def test_observation_of_a_specular_run():
    sim = specular(LatticeSimulation3D, n=300, boundary="wall", seed=3)
    sim.observe()
    sim.run(collisions=6000)
    o = sim.observation()
    assert o.pair_collisions == 6000 and o.wall_reflections > 0
    assert abs(o.temperature.value - 1.0) < 1e-6
    assert 2.0 < o.compressibility.value < 8.0 and o.pressure_virial.value > 0 and o.collision_rate.value > 0
    assert all(np.isfinite(p.value) for p in o.pressure_wall)
    sim.run_back()
    assert sim.collisions == 0


@pytest.mark.parametrize("kwargs,needle", [
    ({"mode": "paper"}, "mode must be 'exact' or 'specular', got 'paper'"),
    ({"mode": 3}, "mode must be 'exact' or 'specular', got 3"),
    ({"mode": "Specular"}, "mode must be 'exact' or 'specular'"),
    ({"mode": "specular", "law": "uniform"}, "law applies to mode='exact' only"),
])
def test_bad_mode_raises_naming_it_and_leaves_a_simulation_untouched(kwargs, needle):
    sim = specular(n=80)
    sim.run(collisions=300)
    before = sim.snapshot()
    x, v, box = sim.positions, sim.velocities, sim.box
    calls = [lambda: LatticeSimulation.random(80, phi=0.3, **kwargs),
             lambda: LatticeSimulation3D.random(80, phi=0.3, **kwargs),
             lambda: LatticeSimulation(x, v, box, **kwargs),
             lambda: revcol.Simulation.random(n=80, dim=2, engine="lattice", **kwargs),
             lambda: revcol.Simulation(x, v, box, engine="lattice", **kwargs)]
    for call in calls:
        with pytest.raises(ValueError, match=needle.replace("(", r"\(").replace(")", r"\)")):
            call()
    assert same_state(sim.snapshot(), before) and sim.mode == "specular"
    sim.run(collisions=200)  # and it runs on
    assert sim.collisions == 500


# --- scenes and the command line -------------------------------------------------------------

def reduced(doc: dict, particles: int = 200, collisions: int = 4000) -> dict:
    """A scene document in its CI form: fewer particles and collisions, no outputs."""
    out = {t: dict(f) for t, f in doc.items() if t != "output"}
    out["system"]["particles"], out["run"] = particles, {"collisions": collisions}
    return out


def write(path: Path, doc: dict) -> Path:
    def val(v):
        return f'"{v}"' if isinstance(v, str) else repr(v)
    path.write_text("".join(f"[{t}]\n" + "".join(f"{k} = {val(v)}\n" for k, v in f.items()) for t, f in doc.items()))
    return path


def test_the_shipped_scene_runs_specular_on_the_3d_lattice(tmp_path):
    scene = load_scene(SCENE)
    assert (scene.engine, scene.mode, scene.dimension, scene.particles, scene.packing_fraction) == \
        ("lattice", "specular", 3, 1000, 0.3)
    assert scene.boundaries == ("periodic",) * 3 and "lattice engine, specular" in scene.summary()
    r = run_scene(scene_from_dict(reduced(tomllib.loads(SCENE.read_text())), "r.toml", tmp_path), progress=False)
    assert r["passed"] and r["bit_for_bit"] and r["mode"] == "specular" and r["scene"]["mode"] == "specular"
    assert r["collisions_forward"] == r["collisions_back"] == 4000
    assert r["bits_back"]["start"] == r["bits_back"]["turn"] == r["bits_back"]["max"]  # X never changes
    assert r["backscatters"] >= 0 and r["log_entries_end"] == 0 and r["energy_drift_end"] == 0.0


def test_scene_rules_for_specular():
    gas = {"system": {"dimension": 2, "particles": 50, "packing_fraction": 0.2}}
    for engine in ("float", "lattice"):
        s = scene_from_dict({**gas, "collisions": {"engine": engine, "mode": "specular"}}, "s.toml")
        assert s.mode == "specular" and s.law == "flux"
        assert f"{'lattice engine, ' if engine == 'lattice' else ''}specular, " in s.summary()
    bad = [({**gas, "collisions": {"mode": "specular", "law": "uniform"}},
            "[collisions] law: applies to mode = 'exact' only"),
           ({**gas, "collisions": {"engine": "lattice", "mode": "specular", "law": "flux"}},
            "[collisions] law: applies to mode = 'exact' only"),
           ({**gas, "collisions": {"engine": "lattice", "mode": "paper"}},
            "[collisions] mode: engine = 'lattice' runs exact and specular modes, got 'paper'"),
           ({**gas, "collisions": {"mode": "specullar"}}, "must be one of 'exact', 'paper', 'specular'"),
           ({"scene": {"kind": "reversal", "case": "pair2d"}, "collisions": {"mode": "specular"}},
            "[collisions] mode: 'specular' runs gas scenes only, not kind = 'reversal'")]
    for doc, needle in bad:
        with pytest.raises(SceneError) as e:
            scene_from_dict(doc, "s.toml")
        assert needle in str(e.value), str(e.value)
    # --engine and --mode on a scene, checked together
    float_gas = scene_from_dict(gas, "f.toml")
    lat = with_mode(float_gas, "specular", "lattice")
    assert (lat.engine, lat.mode, lat.generator) == ("lattice", "specular", "philox")
    assert with_engine(lat, "float").mode == "specular"
    with pytest.raises(SceneError, match="--mode: engine = 'lattice' runs exact and specular modes, got 'paper'"):
        with_mode(lat, "paper")
    with pytest.raises(SceneError, match="law = 'uniform' applies to mode = 'exact' only"):
        with_mode(scene_from_dict({**gas, "collisions": {"law": "uniform"}}, "u.toml"), "specular")


def test_cli_run_and_simulate_with_mode(tmp_path, capsys):
    doc = reduced(tomllib.loads(SCENE.read_text()), particles=150, collisions=2000)
    p = write(tmp_path / "spec.toml", doc)
    assert cli_main(["run", str(p), "--no-progress"]) == 0
    out = capsys.readouterr().out
    for needle in ("lattice engine, specular", "settings         mode specular", "backscatters     ",
                   "refusals         0 (0 per collision; no redraws in specular mode",
                   "restored         bit for bit", "result           PASSED: restored bit for bit"):
        assert needle in out, needle
    # an exact lattice scene run in specular mode from the command line, forward only
    doc["collisions"] = {"engine": "lattice"}
    q = write(tmp_path / "exact.toml", doc)
    assert cli_main(["simulate", str(q), "--mode", "specular", "--collisions", "1500", "--no-progress",
                     "--json", str(tmp_path / "s.json"), "--checkpoint", str(tmp_path / "ck"),
                     "--checkpoint-every", "1500"]) == 0
    out = capsys.readouterr().out
    assert "engine           lattice, specular mode" in out and "backscatters" in out
    ckpt = tmp_path / "ck" / "checkpoint-000000001500.npz"
    assert LatticeSimulation.load(ckpt).mode == "specular"
    # resuming it: in its own mode, not the scene's exact one
    assert cli_main(["simulate", str(q), "--resume", str(ckpt), "--collisions", "500", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "the checkpoint runs specular mode, the scene exact mode (--mode specular resumes it)" in err
    assert cli_main(["simulate", str(q), "--resume", str(ckpt), "--mode", "specular", "--collisions", "500",
                     "--no-progress"]) == 0
    assert "net count now 2,000" in capsys.readouterr().out


@pytest.mark.parametrize("argv,needle", [
    (["--mode", "specularr"], "invalid choice: 'specularr'"),
    (["--mode", "paper"], "--mode: engine = 'lattice' runs exact and specular modes, got 'paper'"),
    (["--mode", "specular", "--engine", "float", "--tick-bits", "20"], "--tick-bits: the lattice engine's options"),
])
def test_cli_mode_errors_exit_2(tmp_path, capsys, argv, needle):
    p = write(tmp_path / "s.toml", reduced(tomllib.loads(SCENE.read_text()), particles=100, collisions=500))
    for command in ("run", "simulate"):
        try:
            status = cli_main([command, str(p), "--no-progress", *argv])
        except SystemExit as e:  # argparse refuses a choice so
            status = e.code
        err = capsys.readouterr().err
        assert status == 2 and needle in err, err
        if argv[1] == "specularr":
            assert "(did you mean 'specular'?)" in err and f"usage: revcol {command}" in err
