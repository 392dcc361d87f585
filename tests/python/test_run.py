"""``revcol run``: round trips of scenes, reports, outputs, errors, Ctrl-C, and the tutorial."""
import dataclasses
import importlib
import json
import os
import re
import signal
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest

import revcol
from revcol.cli.main import main as cli_main
from revcol.gas import build_simulation, run_gas
from revcol.roundtrip import BAR, round_trip_errors
from revcol.studies.horizon import horizon
from revcol.studies.scenes import run_scene
from revcol.scene import SceneError, load_scene, scene_from_dict

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "scenes"
PNG = b"\x89PNG\r\n\x1a\n"


def gas(tmp_path=None, **system):
    """A small 2D gas scene (walls), with [system] fields overridden."""
    doc = {"system": {"dimension": 2, "particles": 200, "packing_fraction": 0.3, **system},
           "rng": {"generator": "clcg4", "seed": 5}, "run": {"collisions": 200}}
    return scene_from_dict(doc, "small.toml", tmp_path)


def reduced(scene, tmp_path):
    """The CI form of an example scene: fewer collisions, outputs redirected to tmp_path."""
    out = dict(json=None, plot=None, trajectory=None)
    if scene.kind == "gas":
        out["checkpoints"] = tmp_path / "ckpt" if scene.checkpoint_interval else None
        out["checkpoint_interval"] = min(scene.checkpoint_interval, 100)
        if scene.trajectory is not None:
            out["trajectory"] = tmp_path / scene.trajectory.name
            out["trajectory_every"] = 50
        collisions = None if scene.time is not None else min(scene.collisions, 500)
    elif scene.kind == "reversal":
        collisions = 2000
    else:  # statesave: small N, one repeat, in this process
        out.update(statesave_particles=(1000, 4000), repeats=1, runner="inline")
        collisions = 20
    return dataclasses.replace(scene, **out), collisions


@pytest.mark.parametrize("path", sorted(SCENES.glob("*.toml")), ids=lambda p: p.stem)
def test_example_scenes_round_trip_reduced(path, tmp_path):
    scene, nc = reduced(load_scene(path), tmp_path)
    r = run_scene(scene, collisions=nc, progress=False)
    assert r["passed"], r.get("summary")
    if scene.kind == "gas":
        assert r["collisions_forward"] == r["collisions_back"] > 0
        assert r["error_x"] <= BAR and r["error_v"] <= BAR and r["time_end"] == r["time_start"]
        assert abs(r["energy_drift_end"]) < 1e-12 and r["log_bytes_end"] == 0
        if scene.trajectory is not None:
            assert r["trajectory_frames"] > 2 and Path(r["trajectory"]).is_file()
        if scene.checkpoint_interval:
            assert len(r["checkpoints"]) == r["collisions_forward"] // scene.checkpoint_interval
    elif scene.kind == "reversal":
        assert r["collisions"] == nc and r["rng_restored"]
    else:
        assert r["runner"] == "inline" and {x["variant"] for x in r["runs"]} == {"ss1", "ss2", "rc"}


def test_default_report_cli(tmp_path, capsys):
    # the default scene (lattice engine) at 2*10^4 collisions; its full length is the main job
    out = tmp_path / "r.json"
    assert cli_main(["run", "--json", str(out), "--no-progress", "--collisions", "20000"]) == 0
    text = capsys.readouterr().out
    for needle in ("revcol run default", "1000 particles in 2D", "lattice engine", "collisions/s",
                   "restored         bit for bit", "bits-back X", "rare log", "redraws", "multi-body",
                   "energy drift", "momentum drift   n/a (walls on every axis)", "peak RSS",
                   "result           PASSED: restored bit for bit"):
        assert needle in text, needle
    assert "\r" not in text  # no progress bar when stdout is not a terminal
    r = json.loads(out.read_text())
    assert r["passed"] and r["bit_for_bit"] and r["collisions_forward"] == r["collisions_back"] == 20000
    assert r["scene"]["generator"] == "philox" and r["scene"]["streams"] == "per_particle"
    assert r["forward_per_s"] > 0 and r["reverse_per_s"] > 0 and r["peak_rss_bytes"] > 0


def test_default_gas_on_the_float_engine_cli(tmp_path, capsys):
    # the same gas on the float engine, 2 collisions per particle (inside its horizon)
    out = tmp_path / "r.json"
    assert cli_main(["run", "--engine", "float", "--collisions", "1000", "--json", str(out), "--no-progress"]) == 0
    text = capsys.readouterr().out
    for needle in ("revcol run default", "1000 particles in 2D", "positions error", "velocity error",
                   "log bytes", "result           PASSED"):
        assert needle in text, needle
    r = json.loads(out.read_text())
    assert r["passed"] and r.get("engine") is None and r["scene"]["engine"] == "float"
    assert set(r["error_definitions"]) == {"error_x", "error_v"}


def test_errors_match_their_definitions():
    x0 = np.array([[0.1, 5.0], [5.0, 5.0]])
    v0 = np.array([[3.0, 4.0], [0.0, 1.0]])
    x = x0 + [[0.0, 0.0], [0.0, 2e-9]]
    x[0, 0] = 9.9  # across the periodic x boundary: 0.2 apart, not 9.8
    v = v0 + [[0.0, 5e-9], [0.0, 0.0]]
    ex, ev = round_trip_errors(x, v, x0, v0, [10.0, 10.0], [True, False])
    assert ex == pytest.approx(0.02) and ev == pytest.approx(1e-9)
    ex, _ = round_trip_errors(x0 + [[0, 0], [0, 2e-9]], v0, x0, v0, [10.0, 10.0], [True, False])
    assert ex == pytest.approx(2e-10)


def test_failure_beyond_the_horizon_exits_1(tmp_path, capsys):
    # 30 collisions per particle: the reversed run has left the forward one
    p = tmp_path / "far.toml"
    p.write_text("[system]\ndimension = 2\nparticles = 100\npacking_fraction = 0.3\n[run]\ncollisions = 1500\n")
    assert cli_main(["run", str(p), "--no-progress"]) == 1
    assert "result           FAILED" in capsys.readouterr().out


def test_plot(tmp_path):
    pytest.importorskip("matplotlib")
    r = run_gas(gas(), plot=tmp_path / "fig", progress=False)
    assert r["passed"]
    for name in ("roundtrip_error.png", "energy_drift.png", "snapshots.png"):
        assert (tmp_path / "fig" / name).read_bytes()[:8] == PNG
    # intermediate round trips at 1/10 .. 9/10 of N_c, then the real one
    assert [c["collisions"] for c in r["curve"]] == list(range(20, 201, 20))
    assert all(c["error_v"] <= BAR for c in r["curve"]) and r["curve"][-1]["error_v"] == r["error_v"]
    assert r["energy_series"][0] == [0, 0.0] and r["energy_series"][-1][0] == 200
    assert len(r["energy_series"]) > 100


def test_trajectory_xyz(tmp_path):
    scene = dataclasses.replace(gas(), trajectory_every=40)
    r = run_gas(scene, trajectory=tmp_path / "t.xyz", progress=False)
    assert r["passed"] and r["trajectory_frames"] == 11 and r["curve"] == [] and r["energy_series"] == []
    frames = read_xyz(tmp_path / "t.xyz")
    fwd = [f for f in frames if f["phase"] == "forward"]
    back = [f for f in frames if f["phase"] == "reverse"]
    assert [f["collisions"] for f in fwd] == [0, 40, 80, 120, 160, 200]
    assert [f["collisions"] for f in back] == [160, 120, 80, 40, 0]
    L = np.array(r["box"])
    for f in fwd[:-1]:  # the reversal passes through the forward frames' times and positions
        g = [b for b in back if b["time"] == f["time"]]
        assert len(g) == 1 and np.abs(g[0]["x"][:, :2] - f["x"][:, :2]).max() / L.max() < 1e-9
    assert frames[0]["lattice"][:2] == pytest.approx(L) and frames[0]["x"].shape == (200, 3)


def read_xyz(path):
    """A strict reader of the extended XYZ our writer emits (what OVITO parses)."""
    lines = Path(path).read_text().splitlines()
    frames, i = [], 0
    while i < len(lines):
        n = int(lines[i])
        head = lines[i + 1]
        assert "Properties=species:S:1:pos:R:3:velo:R:3:radius:R:1" in head  # (and :image:I:3, periodic)
        lattice = [float(t) for t in re.search(r'Lattice="([^"]+)"', head).group(1).split()]
        rows = [ln.split() for ln in lines[i + 2:i + 2 + n]]
        assert all(len(r) == 8 and r[0] == "Ar" for r in rows)  # an element symbol (ASE)
        a = np.array([[float(t) for t in r[1:]] for r in rows])
        frames.append({"time": float(re.search(r"Time=(\S+)", head).group(1)),
                       "collisions": int(re.search(r"Collisions=(\d+)", head).group(1)),
                       "phase": re.search(r'Phase="(\w+)"', head).group(1),
                       "lattice": [lattice[0], lattice[4], lattice[8]], "x": a[:, :3], "v": a[:, 3:6]})
        i += 2 + n
    return frames


def test_trajectory_gsd(tmp_path):
    gsd_hoomd = pytest.importorskip("gsd.hoomd")
    r = run_gas(dataclasses.replace(gas(), trajectory_every=100), trajectory=tmp_path / "t.gsd", progress=False)
    with gsd_hoomd.open(str(tmp_path / "t.gsd"), "r") as f:
        assert len(f) == r["trajectory_frames"] == 5
        first, last = f[0], f[len(f) - 1]
        assert first.particles.N == 200 and first.configuration.dimensions == 2
        assert list(first.configuration.box[:3]) == pytest.approx(r["box"] + [0.0])
        assert abs(first.particles.position).max() <= 0.5 * max(r["box"])  # centred on the origin
        assert np.abs(last.particles.position - first.particles.position).max() < 1e-5  # float32
        assert [int(fr.configuration.step) for fr in f] == [0, 100, 200, 300, 400]  # both directions counted


def test_bad_output_requests_run_nothing(tmp_path, capsys, monkeypatch):
    import collections
    import revcol._outputs as outs
    import revcol.trajectory as tr

    # a bad name is refused the same way on every machine: before the sizes are held against a
    # file system's free space (CI once ran this with 604 MiB free, and the space refusal came first)
    usage = collections.namedtuple("usage", "total used free")
    with monkeypatch.context() as m:
        m.setattr(outs.shutil, "disk_usage", lambda where: usage(1 << 20, 1 << 20, 0))
        assert cli_main(["run", "--trajectory", str(tmp_path / "t.pdb"), "--no-progress"]) == 2
        err = capsys.readouterr().err
        assert "the suffix must be .xyz (extended XYZ) or .gsd" in err and err.count("\n") == 1
        assert cli_main(["run", "--trajectory", str(tmp_path / "t.xyz"), "--no-progress"]) == 2
        assert "free on the file system" in capsys.readouterr().err  # the space check itself is live
    real = tr.check_format

    def no_gsd(path):  # as if gsd were not installed
        if str(path).endswith(".gsd"):
            raise ValueError(f"trajectory {str(path)!r}: writing .gsd needs the gsd package "
                             "(pip install gsd), or write extended XYZ (.xyz) instead")
        real(path)
    monkeypatch.setattr(tr, "check_format", no_gsd)
    assert cli_main(["run", "--trajectory", str(tmp_path / "t.gsd"), "--json", str(tmp_path / "r.json")]) == 2
    assert "needs the gsd package" in capsys.readouterr().err
    assert not (tmp_path / "r.json").exists() and not (tmp_path / "t.gsd").exists()
    rev = str(SCENES / "paper-pair2d-reversal.toml")
    assert cli_main(["run", rev, "--trajectory", str(tmp_path / "t.xyz")]) == 2
    assert "--trajectory needs a 'gas' scene" in capsys.readouterr().err
    assert cli_main(["run", rev, "--plot", str(tmp_path)]) == 2
    assert cli_main(["run", rev, "--horizon"]) == 2
    assert cli_main(["run", "--seeds", "3"]) == 2
    assert "--seeds applies to --horizon only" in capsys.readouterr().err


@pytest.mark.parametrize("text,needle", [
    ("[system]\ndimension = 2\nparticles = 10\npacking_fraction = 0.1\nspeed = 3\n", "[system] speed: unknown field"),
    ("[system]\ndimension = '2'\nparticles = 10\npacking_fraction = 0.1\n", "[system] dimension: must be an integer, got '2'"),
    ("[system]\ndimension = 2\nparticles = -3\npacking_fraction = 0.1\n", "[system] particles: must be 1..2147483647, got -3"),
    ("[system]\ndimension = 2\nparticles = 3\nbox = [0.9, 5.0]\n", "[system] box: axis 0 length 0.9 is not larger than the diameter 1"),
    ("[system]\ndimension = 2\ninitial_state = 'overlap.npz'\nbox = [5.0, 5.0]\n",
     "[system] initial_state: overlap.npz: particles 0 and 1 overlap"),
    ("[scene]\nkind = 'reversal'\ncase = 'pair2d'\n[system]\ndimension = 2\n", "[system] dimension: does not apply to kind = 'reversal'"),
])
def test_bad_scene_files_one_line_exit_2(tmp_path, capsys, text, needle):
    np.savez(tmp_path / "overlap.npz", positions=np.array([[1.0, 1.0], [1.2, 1.6]]),
             velocities=np.array([[1.0, 0.0], [-1.0, 0.0]]))
    p = tmp_path / "bad.toml"
    p.write_text(text)
    assert cli_main(["run", str(p), "--json", str(tmp_path / "r.json")]) == 2
    cap = capsys.readouterr()
    assert cap.out == "" and cap.err.startswith(f"revcol run: error: {p}: ") and cap.err.count("\n") == 1
    assert needle in cap.err, cap.err
    assert not (tmp_path / "r.json").exists()


@pytest.mark.parametrize("start", ["auto", "random", "crystal"])
def test_explicit_box_starts_from_the_engine(start):
    doc = {"system": {"dimension": 3, "particles": 60, "box": [5.0, 6.0, 9.0], "start": start,
                      "boundaries": ["wall", "periodic", "wall"], "kinetic_energy": 30.0},
           "run": {"collisions": 60}}
    scene = scene_from_dict(doc, "box.toml")
    sim = build_simulation(scene)
    assert sim.n == 60 and sim.diagnostics()["energy"] == pytest.approx(30.0)
    assert np.abs(sim.velocities.sum(axis=0)).max() < 1e-12
    # the start is the engine's (C++ engine/init.hpp), bit for bit
    init = {"auto": "auto", "random": "rsa", "crystal": "crystal"}[start]
    x, v = revcol._core.engine_random_start(60, [5.0, 6.0, 9.0], ["wall", "periodic", "wall"], 1.0, 0, 30.0, init)
    assert np.array_equal(sim.positions, x) and np.array_equal(sim.velocities, v)
    assert run_gas(scene, progress=False)["passed"]
    with pytest.raises(SceneError, match=r"box\.toml: \[system\] box: 500 particles .* do not fit"):
        build_simulation(scene_from_dict({**doc, "system": {**doc["system"], "particles": 500}}, "box.toml"))


def test_a_crystal_that_does_not_fit_is_a_scene_error():
    # 9 fit since the crystal with its outer rows on the walls' margins (issue 58); 10 do not
    doc = {"system": {"dimension": 2, "particles": 10, "box": [3.5, 3.5], "start": "crystal"}}
    with pytest.raises(SceneError, match=r"\[system\] box: 10 particles of diameter 1.* do not fit on a crystal"
                       r".*fits up to a packing fraction of"):
        build_simulation(scene_from_dict(doc, "tight.toml"))


def test_deprecated_spellings_warn_on_stderr_and_run(tmp_path, capsys):
    p = tmp_path / "old.toml"
    p.write_text("[system]\ndimension = 1\nparticles = 50\npacking_fraction = 0.3\nboundaries = 'walls'\n"
                 "[rng]\nstreams = 'per-particle'\n[run]\ncollisions = 100\n")
    assert cli_main(["run", str(p), "--no-progress"]) == 0
    cap = capsys.readouterr()
    assert f"revcol run: warning: {p}: [system] boundaries: 'walls' is deprecated, write 'wall'" in cap.err
    assert f"revcol run: warning: {p}: [rng] streams: 'per-particle' is deprecated, write 'per_particle'" in cap.err
    assert "result           PASSED" in cap.out and "(wall)" in cap.out


def test_checkpoints_resume_and_reverse(tmp_path):
    scene = dataclasses.replace(gas(), checkpoint_interval=80, checkpoints=tmp_path / "ck")
    sim0 = build_simulation(scene)
    x0, v0 = sim0.positions, sim0.velocities
    r = run_gas(scene, progress=False)
    assert [Path(p).name for p in r["checkpoints"]] == ["checkpoint-000000000080.npz", "checkpoint-000000000160.npz"]
    sim = revcol.Simulation.load(r["checkpoints"][1])
    assert sim.diagnostics()["net_collisions"] == 160
    sim.run_back()
    ex, ev = round_trip_errors(sim.positions, sim.velocities, x0, v0, r["box"], r["periodic"])
    assert ex <= BAR and ev <= BAR


def test_horizon(tmp_path, capsys):
    p = tmp_path / "h.toml"
    p.write_text("[system]\ndimension = 2\nparticles = 100\npacking_fraction = 0.3\n")
    plot = ["--plot", str(tmp_path / "fig")] if _has("matplotlib") else []
    assert cli_main(["run", str(p), "--horizon", "--seeds", "2", "--max-collisions", "5000",
                     "--json", str(tmp_path / "h.json"), "--no-progress"] + plot) == 0
    text = capsys.readouterr().out
    assert "worst round-trip error over 2 seed(s)" in text and "horizon: N_c = " in text
    r = json.loads((tmp_path / "h.json").read_text())
    if plot:
        assert (tmp_path / "fig" / "horizon.png").read_bytes()[:8] == PNG
    assert r["horizon_reached"] and 0 < r["horizon_collisions"] < 5000
    # the JSON writes a non-finite error as the string "inf" (a seed that stopped counts as O(1))
    rows = [{k: float(v) if k.startswith("error") else v for k, v in row.items()} for row in r["rows"]]
    first_bad = next(k for k, row in enumerate(rows) if max(row["error_x"], row["error_v"]) > BAR)
    assert rows[first_bad - 1]["collisions"] == r["horizon_collisions"]
    assert max(rows[-1]["error_x"], rows[-1]["error_v"]) >= 0.1  # stopped once O(1)
    # a row's worst error is the max over seeds of what one round trip gives
    one = horizon(load_scene(p), seeds=1, max_collisions=5000, progress=False)
    assert all(a["error_v"] <= b["error_v"] for a, b in zip(one["rows"], rows[:len(one["rows"])]))


def sigint_once_running(monkeypatch, interrupt_class) -> list:
    """Sends SIGINT 0.3 s after a run's Ctrl-C handler (``interrupt_class``) is installed
    (never before it); returns the timers, to cancel when the run is over."""
    enter = interrupt_class.__enter__
    timers = []

    def enter_then_interrupt(self):
        out = enter(self)
        timers.append(threading.Timer(0.3, os.kill, (os.getpid(), signal.SIGINT)))
        timers[-1].start()
        return out
    monkeypatch.setattr(interrupt_class, "__enter__", enter_then_interrupt)
    return timers


def test_ctrl_c_stops_forward_and_still_reverses_and_writes(tmp_path, capsys, monkeypatch):
    import revcol.gas as run

    # a 1D gas reverses exactly however long it runs: 1e8 collisions would take a minute.
    timers = sigint_once_running(monkeypatch, run.Interrupt)
    before = signal.getsignal(signal.SIGINT)
    p = tmp_path / "long.toml"
    p.write_text("[system]\ndimension = 1\nparticles = 1000\npacking_fraction = 0.3\n[run]\ncollisions = 100000000\n")
    try:
        rc = cli_main(["run", str(p), "--json", str(tmp_path / "r.json"), "--no-progress"])
    finally:
        for t in timers:
            t.cancel()
    assert rc == 130
    assert "interrupted      during the forward run (Ctrl-C); went back from where it stopped" in capsys.readouterr().out
    r = json.loads((tmp_path / "r.json").read_text())
    assert r["interrupted"] == "forward" and r["passed"] and r["round_trip_complete"]
    assert 0 < r["collisions_forward"] == r["collisions_back"] < 100_000_000
    assert signal.getsignal(signal.SIGINT) is before  # the handler is restored


def test_ctrl_c_during_the_reversal_stops_it(tmp_path, capsys, monkeypatch):
    # the SIGINT arrives as the first reverse chunk starts; the loop stops before the next
    real = revcol.Simulation.run_back
    calls = []

    def run_back(self, *a, **k):
        if not calls:
            os.kill(os.getpid(), signal.SIGINT)
        calls.append(k)
        return real(self, *a, **k)
    monkeypatch.setattr(revcol.Simulation, "run_back", run_back)
    p = tmp_path / "rods.toml"
    p.write_text("[system]\ndimension = 1\nparticles = 200\npacking_fraction = 0.3\n[run]\ncollisions = 20000\n")
    assert cli_main(["run", str(p), "--json", str(tmp_path / "r.json"), "--no-progress"]) == 130
    assert "the round trip is incomplete" in capsys.readouterr().out
    r = json.loads((tmp_path / "r.json").read_text())
    assert r["interrupted"] == "reverse" and not r["round_trip_complete"] and not r["passed"]
    assert calls == [{"collisions": 4000, "on_divergence": "ignore"}] and r["collisions_back"] == 4000 and r["collisions_forward"] == 20000


def test_reversal_builds_no_particles(monkeypatch):
    import revcol.gas as gas_module

    def refuse(*a, **k):
        raise AssertionError("a reversal scene must not build a gas")
    monkeypatch.setattr(gas_module, "build_simulation", refuse)
    monkeypatch.setattr(gas_module, "_GasRun", refuse)
    monkeypatch.setattr(gas_module, "Simulation", None)
    r = run_scene(SCENES / "paper-triple1d-reversal.toml", collisions=500, seed=4)
    assert r["passed"] and r["case"] == "triple1d" and r["mode"] == "paper" and r["seed"] == 4


def test_imports_only_what_a_run_uses():
    code = ("import sys, revcol.studies.scenes as r; rep = r.run_scene(None, collisions=20000, progress=False); "
            "print(rep['passed'], *[m in sys.modules for m in ('matplotlib', 'revcol.trajectory', 'tqdm', 'gsd')])")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True).stdout
    assert out.split() == ["True", "False", "False", "False", "False"]


def test_tutorial_code_runs(tmp_path, monkeypatch):
    """docs/tutorial.md's python blocks, in order, in one namespace (so it cannot rot)."""
    text = (ROOT / "docs" / "tutorial.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert len(blocks) >= 4
    if not _has("matplotlib"):
        blocks = [b for b in blocks if "matplotlib" not in b]
    monkeypatch.chdir(tmp_path)
    ns: dict = {}
    for b in blocks:
        exec(compile(b, "docs/tutorial.md", "exec"), ns)


def _has(module: str) -> bool:
    try:
        __import__(module)
        return True
    except ImportError:
        return False


def test_ctrl_c_ends_a_statesave_study_after_the_run_under_way(tmp_path, capsys, monkeypatch):
    # the SIGINT arrives during the first run (each run is one C++ call): the study ends
    # after it, reports that run, writes the JSON, and exits 130
    import revcol.studies.statesave.driver as ss

    real = ss._run_inline
    calls = []

    def run_inline(kw, repeats):
        if not calls:
            os.kill(os.getpid(), signal.SIGINT)
        calls.append(kw["variant"])
        return real(kw, repeats)
    monkeypatch.setattr(ss, "_run_inline", run_inline)
    p = tmp_path / "ss.toml"
    p.write_text('[scene]\nkind = "statesave"\n[statesave]\nparticles = [1000, 2000]\nrepeats = 1\n'
                 'runner = "inline"\n[run]\ncollisions = 20\n')
    before = signal.getsignal(signal.SIGINT)
    rc = cli_main(["run", str(p), "--json", str(tmp_path / "r.json"), "--no-progress"])
    assert rc == 130
    assert "interrupted (Ctrl-C): the table covers the runs done; 5 not run" in capsys.readouterr().out
    r = json.loads((tmp_path / "r.json").read_text())
    assert r["interrupted"] == "statesave" and r["not_run"] == 5 and len(r["runs"]) == 1 == len(calls)
    assert r["runs"][0]["restored"]
    assert signal.getsignal(signal.SIGINT) is before


def test_ctrl_c_during_a_reversal_scene_still_reports(tmp_path, capsys, monkeypatch):
    ver = importlib.import_module("revcol.studies.paper_scenes")  # where the reversal scene calls verify
    real = ver.verify

    def verify(*a, **k):
        os.kill(os.getpid(), signal.SIGINT)  # arrives during the (one) call
        return real(*a, **k)
    monkeypatch.setattr(ver, "verify", verify)
    rc = cli_main(["run", str(SCENES / "paper-triple1d-reversal.toml"), "--collisions", "500",
                   "--json", str(tmp_path / "r.json"), "--no-progress"])
    assert rc == 130
    assert "interrupted         (Ctrl-C) after the reversal" in capsys.readouterr().out
    r = json.loads((tmp_path / "r.json").read_text())
    assert r["interrupted"] == "reversal" and r["passed"] and r["collisions"] == 500
