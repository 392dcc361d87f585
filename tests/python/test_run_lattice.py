"""``revcol run`` on the lattice engine: the default scene and the lattice scenes in reduced
form, restored bit for bit; a broken round trip fails; the lattice's scene rules; --horizon;
Ctrl-C, trajectories, checkpoints, figures and engine errors."""
import copy
import json
import os
import signal
import tomllib
from pathlib import Path

import numpy as np
import pytest

import revcol.lattice_gas as lg
from revcol.cli.main import main as cli_main
from revcol.lattice import LatticeSimulation
from revcol.studies.scenes import run_scene
from revcol.scene import DEFAULT_SCENE, SceneError, load_scene, scene_from_dict, with_engine

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "scenes"
LATTICE_SCENES = [p for p in sorted(SCENES.glob("*.toml")) if load_scene(p).engine == "lattice"]
PNG = b"\x89PNG\r\n\x1a\n"


def reduced_doc(doc: dict, particles: int = 200, collisions: int = 20_000) -> dict:
    """A lattice scene's document in its CI form: fewer particles and collisions, no outputs."""
    doc = copy.deepcopy(doc)
    # (a mixture starts on a crystal of its largest size: 256 spheres fill whole face-centred cells;
    # a sheared box is at least 9 diameters along the flow: 500 spheres at 0.3)
    doc["system"]["particles"] = (256 if doc.get("species") and doc["system"]["dimension"] == 3 else
                                  500 if doc["system"].get("shear_rate") else particles)
    counts = [sp.pop("count") for sp in doc.get("species", []) if "count" in sp]
    for sp, c in zip(doc.get("species", []), counts):  # a mixture: its species' shares of the fewer particles
        sp["fraction"] = c / sum(counts)
    doc["run"] = {"collisions": collisions}
    doc.pop("output", None)
    return doc


def small(tmp_path, **run) -> Path:
    """A small lattice scene file (N = 100, walls) with [run] fields."""
    p = tmp_path / "small.toml"
    lines = "\n".join(f"{k} = {v}" for k, v in (run or {"collisions": 2000}).items())
    p.write_text("[system]\ndimension = 2\nparticles = 100\npacking_fraction = 0.3\n"
                 f"[collisions]\nengine = 'lattice'\n[rng]\nseed = 3\n[run]\n{lines}\n")
    return p


def test_the_default_scene_is_the_lattice_engine_at_a_real_length():
    s = load_scene(None)
    assert (s.engine, s.dimension, s.particles, s.law, s.generator, s.streams) == \
        ("lattice", 2, 1000, "flux", "philox", "per_particle")
    assert s.boundaries == ("wall", "wall") and s.packing_fraction == 0.3
    assert s.collisions >= 10**6 and "lattice engine" in s.summary()


@pytest.mark.parametrize("path", [None] + LATTICE_SCENES, ids=lambda p: "default" if p is None else p.stem)
def test_lattice_scenes_reduced_bit_for_bit(path, tmp_path, capsys):
    doc = DEFAULT_SCENE if path is None else tomllib.loads(path.read_text())
    scene = scene_from_dict(reduced_doc(doc), "reduced.toml", tmp_path)
    assert scene.engine == "lattice"
    r = run_scene(scene, json_path=tmp_path / "r.json", progress=False)
    assert r["passed"] and r["bit_for_bit"] and r["round_trip_complete"]
    assert all(r["restored"].values()) and set(r["restored"]) == set(lg.RESTORED_PARTS)
    assert r["collisions_forward"] == r["collisions_back"] == 20_000 and r["clock_end"] == 0 < r["clock_turn"]
    assert r["error_x"] == 0.0 and r["error_v"] == 0.0 and r["energy_drift_end"] == 0.0
    x = r["bits_back"]
    assert x["start"] == x["end"] and x["max"] >= max(x["start"], x["turn"])
    assert x["start"] == 128 * x["particles"]  # one X per particle, 128 bits each at the start
    assert r["log_entries_end"] == 0 and r["log_bytes_end"] == 0
    assert set(r["redraws"]) >= {"cell_readback", "overlap_after", "ghost_tie"}
    assert r["forward_per_s"] > 0 and r["reverse_per_s"] > 0 and r["peak_rss_bytes"] > 0
    assert json.loads((tmp_path / "r.json").read_text())["bit_for_bit"] is True
    # the text report, through the CLI
    p = tmp_path / "reduced.toml"
    p.write_text(_toml(reduced_doc(doc)))
    assert cli_main(["run", str(p), "--no-progress"]) == 0
    text = capsys.readouterr().out
    for needle in ("restored         bit for bit: positions yes, velocities yes, RNG counters yes, "
                   "bits-back integers yes, clock yes", "bits-back X ", "rare log ", "redraws ", "multi-body ",
                   "energy drift ", "momentum drift ", "quantized once", "collisions/s", "peak RSS",
                   "result           PASSED: restored bit for bit"):
        assert needle in text, needle


def _toml(doc: dict) -> str:
    def val(v):
        if isinstance(v, str):
            return f'"{v}"'
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, list):
            return "[" + ", ".join(val(x) for x in v) + "]"
        return repr(v)
    def table(head: str, f: dict) -> str:
        return head + "".join(f"{k} = {val(v)}\n" for k, v in f.items())
    return "".join("".join(table(f"[[{t}]]\n", e) for e in f) if isinstance(f, list) else table(f"[{t}]\n", f)
                   for t, f in doc.items())


def test_chunked_run_is_the_one_call_run(tmp_path):
    # the report's forward run goes in chunks; the turn is the state of one uninterrupted run
    scene = load_scene(small(tmp_path, collisions=5000))
    r = run_scene(scene, progress=False)
    sim = lg.build_lattice(scene)
    sim.run(collisions=5000)
    assert r["clock_turn"] == sim.clock and r["bits_back"]["turn"] == sim.diagnostics()["bits_length"]
    assert len(r["energy_series"]) > 20 and r["energy_series"][-1][0] == 5000


def test_a_broken_round_trip_fails_and_names_the_part(tmp_path, capsys, monkeypatch):
    # one velocity component off by one lattice unit after the reversal: exit 1, velocities NO
    real = LatticeSimulation.run_back

    def run_back_then_nudge(self, *a, **k):
        out = real(self, *a, **k)
        if self.collisions == 0:
            st = self.snapshot()
            st["v"] = st["v"].copy()
            st["v"][7, 1] += 1
            self._e = LatticeSimulation.from_snapshot(st)._e
        return out
    monkeypatch.setattr(LatticeSimulation, "run_back", run_back_then_nudge)
    assert cli_main(["run", str(small(tmp_path)), "--json", str(tmp_path / "r.json"), "--no-progress"]) == 1
    text = capsys.readouterr().out
    assert "NOT bit for bit: positions yes, velocities NO, RNG counters yes" in text
    assert "result           FAILED" in text
    r = json.loads((tmp_path / "r.json").read_text())
    assert not r["passed"] and r["restored"]["velocities"] is False
    assert [k for k, v in r["restored"].items() if not v] == ["velocities"]


def test_a_velocity_perturbed_at_the_turn_does_not_come_back(tmp_path, capsys, monkeypatch):
    real = lg._LatticeRun.turn

    def turn_then_nudge(self):
        real(self)
        st = self.sim.snapshot()
        st["v"] = st["v"].copy()
        st["v"][0, 0] += 1
        self.sim._e = LatticeSimulation.from_snapshot(st)._e
    monkeypatch.setattr(lg._LatticeRun, "turn", turn_then_nudge)
    assert cli_main(["run", str(small(tmp_path)), "--no-progress"]) == 1
    assert "result           FAILED" in capsys.readouterr().out


def test_an_engine_error_is_reported_and_fails(tmp_path, capsys, monkeypatch):
    real = LatticeSimulation.run
    calls = []

    def run(self, *a, **k):
        calls.append(1)
        if len(calls) == 3:
            raise RuntimeError("lattice engine: a collision it cannot resolve (test)")
        return real(self, *a, **k)
    monkeypatch.setattr(LatticeSimulation, "run", run)
    assert cli_main(["run", str(small(tmp_path)), "--json", str(tmp_path / "r.json"), "--no-progress"]) == 1
    assert "engine error     forward: lattice engine: a collision it cannot resolve (test)" in capsys.readouterr().out
    r = json.loads((tmp_path / "r.json").read_text())
    assert not r["passed"] and 0 < r["collisions_forward"] == r["collisions_back"] < 2000
    assert all(r["restored"].values())  # what ran came back, but the run did not do what was asked


@pytest.mark.parametrize("text,needle", [
    ("[system]\ndimension = 1\nparticles = 10\npacking_fraction = 0.1\n[collisions]\nengine = 'lattice'\n",
     "[system] dimension: engine = 'lattice' runs 2D and 3D gases, got dimension 1"),
    ("[system]\ndimension = 2\nparticles = 10\npacking_fraction = 0.1\n[collisions]\nengine = 'lattice'\nmode = 'paper'\n",
     "[collisions] mode: engine = 'lattice' runs exact and specular modes, got 'paper'"),
    ("[system]\ndimension = 2\nparticles = 10\npacking_fraction = 0.1\n[collisions]\nengine = 'lattice'\n"
     "[rng]\ngenerator = 'clcg4'\n", "[rng] generator: engine = 'lattice' draws from Philox per-particle streams"),
    ("[system]\ndimension = 2\nparticles = 10\npacking_fraction = 0.1\n[collisions]\nengine = 'lattice'\n"
     "[rng]\nstreams = 'single'\n", "[rng] streams: engine = 'lattice' draws from one Philox stream per particle"),
    ("[system]\ndimension = 2\nparticles = 10\npacking_fraction = 0.1\n[collisions]\nengine = 'lattice'\nbits = 40\n",
     "[collisions] bits: does not apply to engine = 'lattice'"),
    ("[system]\ndimension = 2\nparticles = 10\npacking_fraction = 0.1\n[collisions]\nengine = 'integer'\n",
     "[collisions] engine: must be one of 'float', 'lattice'"),
    ("[scene]\nkind = 'reversal'\ncase = 'pair2d'\n[collisions]\nengine = 'lattice'\n",
     "[collisions] engine: does not apply to kind = 'reversal'"),
])
def test_lattice_scene_rules_one_line_exit_2(tmp_path, capsys, text, needle):
    p = tmp_path / "bad.toml"
    p.write_text(text)
    assert cli_main(["run", str(p), "--json", str(tmp_path / "r.json")]) == 2
    cap = capsys.readouterr()
    assert cap.out == "" and cap.err.count("\n") == 1 and needle in cap.err, cap.err
    assert not (tmp_path / "r.json").exists()


def test_engine_choice_and_override(tmp_path):
    float_scene = scene_from_dict({"system": {"dimension": 2, "particles": 50, "packing_fraction": 0.2}}, "f.toml")
    assert float_scene.engine == "float" and float_scene.generator == "clcg4"  # explicit scenes stay as they were
    lat = with_engine(float_scene, "lattice")
    assert lat.engine == "lattice" and lat.generator == "philox"  # no generator named: the lattice's
    named = scene_from_dict({"system": {"dimension": 2, "particles": 50, "packing_fraction": 0.2},
                             "rng": {"generator": "clcg4"}}, "g.toml")
    with pytest.raises(SceneError, match=r"\[rng\] generator: .* \(--engine lattice\)"):
        with_engine(named, "lattice")
    with pytest.raises(SceneError, match="dimension 1"):
        with_engine(scene_from_dict({"system": {"dimension": 1, "particles": 5, "packing_fraction": 0.1}}), "lattice")
    spheres = with_engine(scene_from_dict({"system": {"dimension": 3, "particles": 5, "packing_fraction": 0.1}}), "lattice")
    assert spheres.engine == "lattice" and spheres.dimension == 3
    back = with_engine(load_scene(None), "float")
    assert back.engine == "float" and back.generator == "philox" and back.bits == 40


def test_lattice_initial_state_is_quantized_and_checked(tmp_path):
    x = np.array([[1.0, 1.0], [3.0, 1.2], [1.5, 3.0], [3.6, 3.5]])
    v = np.array([[1.0, 0.0], [-1.0, 0.2], [0.0, -0.5], [0.3, 0.3]])
    np.savez(tmp_path / "start.npz", positions=x, velocities=v)
    p = tmp_path / "s.toml"
    p.write_text("[system]\ndimension = 2\ninitial_state = 'start.npz'\nbox = [5.0, 5.0]\n"
                 "[collisions]\nengine = 'lattice'\n[run]\ncollisions = 300\n")
    r = run_scene(p, progress=False)
    assert r["passed"] and r["particles"] == 4 and r["quantization"]["max_position_error"] < 1e-12
    np.savez(tmp_path / "start.npz", positions=x[[0, 0, 1, 2]] + [[0, 0], [0.5, 0], [0, 0], [0, 0]], velocities=v)
    with pytest.raises(SceneError, match=r"\[system\] initial_state: start.npz: .*overlap"):
        load_scene(p)


def test_time_ended_lattice_scene(tmp_path):
    r = run_scene(small(tmp_path, time=3.0), progress=False)
    assert r["passed"] and r["collisions_forward"] > 0
    assert r["time_turn"] == pytest.approx(3.0, abs=1e-5) and r["clock_end"] == 0


def test_horizon_on_a_lattice_scene_is_none_checked_bit_for_bit(tmp_path, capsys):
    p = small(tmp_path)
    assert cli_main(["run", str(p), "--horizon", "--seeds", "2", "--json", str(tmp_path / "h.json"),
                     "--no-progress"]) == 0
    text = capsys.readouterr().out
    assert "horizon: none" in text and "bit for bit" in text
    r = json.loads((tmp_path / "h.json").read_text())
    assert r["engine"] == "lattice" and r["passed"] and not r["horizon_reached"]
    assert [row["collisions"] for row in r["rows"]] == [50, 500, 5000]
    assert all(row["bit_for_bit"] == row["seeds"] == 2 for row in r["rows"])
    # --engine float measures the float engine's horizon for the same gas
    assert cli_main(["run", str(p), "--horizon", "--engine", "float", "--max-collisions", "5000",
                     "--json", str(tmp_path / "f.json"), "--no-progress"]) == 0
    f = json.loads((tmp_path / "f.json").read_text())
    assert f.get("engine") is None and f["horizon_reached"] and 0 < f["horizon_collisions"] < 5000
    assert "horizon: N_c = " in capsys.readouterr().out
    assert cli_main(["run", str(p), "--horizon", "--plot", str(tmp_path / "fig")]) == 2
    assert "a lattice scene has no horizon to plot" in capsys.readouterr().err


def test_horizon_check_can_fail(tmp_path, capsys, monkeypatch):
    real = lg.restored
    monkeypatch.setattr(lg, "restored", lambda a, b: {**real(a, b), "clock": False})
    assert cli_main(["run", str(small(tmp_path)), "--horizon", "--no-progress"]) == 1
    assert "FAILED: a lattice round trip did not come back bit for bit" in capsys.readouterr().out


def test_ctrl_c_stops_the_lattice_forward_run_and_goes_back(tmp_path, capsys, monkeypatch):
    from test_run import sigint_once_running

    from revcol.progress import Interrupt

    timers = sigint_once_running(monkeypatch, Interrupt)
    before = signal.getsignal(signal.SIGINT)
    try:
        rc = cli_main(["run", str(small(tmp_path, collisions=10**9)), "--json", str(tmp_path / "r.json"),
                       "--no-progress"])
    finally:
        for t in timers:
            t.cancel()
    assert rc == 130
    assert "interrupted      during the forward run (Ctrl-C); went back from where it stopped" in capsys.readouterr().out
    r = json.loads((tmp_path / "r.json").read_text())
    assert r["interrupted"] == "forward" and r["passed"] and r["bit_for_bit"]
    assert 0 < r["collisions_forward"] == r["collisions_back"] < 10**9
    assert signal.getsignal(signal.SIGINT) is before


def test_ctrl_c_during_the_lattice_reversal_stops_it(tmp_path, capsys, monkeypatch):
    real = LatticeSimulation.run_back
    calls = []

    def run_back(self, *a, **k):
        if not calls:
            os.kill(os.getpid(), signal.SIGINT)
        calls.append(k)
        return real(self, *a, **k)
    monkeypatch.setattr(LatticeSimulation, "run_back", run_back)
    assert cli_main(["run", str(small(tmp_path, collisions=20000)), "--json", str(tmp_path / "r.json"),
                     "--no-progress"]) == 130
    assert "the round trip is incomplete" in capsys.readouterr().out
    r = json.loads((tmp_path / "r.json").read_text())
    assert r["interrupted"] == "reverse" and not r["passed"] and not r["round_trip_complete"]
    # chunks of max(20 N, N_c / 50) collisions: the first went back 2000, the loop stopped before the next
    assert calls == [{"to_collision": 18000}] and r["collisions_back"] == 2000


def test_lattice_trajectory_replays_the_forward_frames_exactly(tmp_path, monkeypatch):
    from test_run import read_xyz

    monkeypatch.chdir(tmp_path)  # the checkpoints (./small-checkpoints) land under the current directory
    r = run_scene(small(tmp_path, collisions=1000, checkpoint_interval=400), trajectory=tmp_path / "t.xyz",
                  progress=False)
    assert r["passed"] and r["trajectory_frames"] == 2 * len(range(0, 1000, 100)) + 1
    frames = read_xyz(tmp_path / "t.xyz")
    fwd = {f["collisions"]: f for f in frames if f["phase"] == "forward"}
    back = [f for f in frames if f["phase"] == "reverse"]
    assert sorted(fwd) == list(range(0, 1001, 100)) and [f["collisions"] for f in back] == list(range(900, -1, -100))
    for f in back:  # the reversal passes through the forward frames bit for bit
        g = fwd[f["collisions"]]
        assert f["time"] == g["time"] and np.array_equal(f["x"], g["x"]) and np.array_equal(f["v"], g["v"])
    # checkpoints: LatticeSimulation.load resumes, and its run_back reaches the start
    assert [Path(c).name for c in r["checkpoints"]] == ["checkpoint-000000000400.npz", "checkpoint-000000000800.npz"]
    assert all(Path(c).parent == tmp_path / "small-checkpoints" for c in r["checkpoints"])
    sim = LatticeSimulation.load(r["checkpoints"][1])
    assert sim.collisions == 800
    start = lg.build_lattice(load_scene(small(tmp_path, collisions=1000)))
    sim.run_back()
    assert all(lg.restored(start.snapshot(), sim.snapshot()).values())


def test_a_3d_lattice_scene_runs_spheres_bit_for_bit_with_figures(tmp_path):
    p = tmp_path / "spheres.toml"
    p.write_text("[system]\ndimension = 3\nparticles = 200\npacking_fraction = 0.3\nboundaries = ['wall', 'periodic', 'periodic']\n"
                 "[collisions]\nengine = 'lattice'\n[rng]\nseed = 5\n[run]\ncollisions = 5000\n")
    scene = load_scene(p)
    sim = lg.build_lattice(scene)
    assert type(sim).__name__ == "LatticeSimulation3D" and sim.lattice_positions.shape == (200, 3)
    r = run_scene(scene, plot=tmp_path / "fig", json_path=tmp_path / "r.json", progress=False)
    assert r["passed"] and r["bit_for_bit"] and all(r["restored"].values())
    assert r["dimension"] == 3 and len(r["box"]) == 3 and r["periodic"] == [False, True, True]
    assert r["collisions_forward"] == r["collisions_back"] == 5000
    assert len(r["momentum_drift_end"]["lattice_units"]) == 2  # the two periodic axes
    if (tmp_path / "fig").exists():  # matplotlib installed
        assert (tmp_path / "fig" / "snapshots.png").read_bytes()[:8] == PNG


def test_lattice_plot(tmp_path):
    pytest.importorskip("matplotlib")
    r = run_scene(small(tmp_path), plot=tmp_path / "fig", progress=False)
    assert r["passed"]
    for name in ("energy_drift.png", "bits_back.png", "snapshots.png"):
        assert (tmp_path / "fig" / name).read_bytes()[:8] == PNG
    assert not (tmp_path / "fig" / "roundtrip_error.png").exists()
    assert r["bits_series"][0] == [0, r["bits_back"]["start"]] and r["bits_series"][-1][0] == 2000
