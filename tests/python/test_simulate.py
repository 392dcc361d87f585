"""``revcol simulate``: forward-only runs with frames, checkpoints and observables on triggers;
resuming from a checkpoint bit for bit; bad options as named errors (exit 2); Ctrl-C."""
import json
import os
import signal
import threading

import numpy as np
import pytest

from revcol import Simulation
from revcol.cli.main import main as cli_main
from revcol.lattice import LatticeSimulation
from revcol.cli.simulate import simulate
from revcol.scene import SceneError

FLOAT = "[system]\ndimension = 2\nparticles = 100\npacking_fraction = 0.3\n[collisions]\nengine = \"float\"\n" \
        "[rng]\nseed = 4\n[run]\ncollisions = 500\n"
LATTICE = "[system]\ndimension = 2\nparticles = 64\npacking_fraction = 0.3\n[collisions]\nengine = \"lattice\"\n" \
          "[run]\ncollisions = 500\n"


def scene_file(tmp_path, text, name="s.toml"):
    p = tmp_path / name
    p.write_text(text)
    return str(p)


def read_xyz_counts(path):
    """The Collisions= of each frame of an extended XYZ file."""
    lines = open(path).read().splitlines()
    out, i = [], 0
    while i < len(lines):
        n = int(lines[i])
        out.append(int(lines[i + 1].split("Collisions=")[1].split()[0]))
        i += n + 2
    return out


@pytest.mark.parametrize("text", [FLOAT, LATTICE], ids=["float", "lattice"])
def test_ten_thousand_collisions_write_the_frames_and_checkpoints_asked_for(tmp_path, capsys, text):
    s = scene_file(tmp_path, text)
    rc = cli_main(["simulate", s, "--collisions", "10000", "--trajectory", str(tmp_path / "t.xyz"), "--every", "1500",
                   "--checkpoint", str(tmp_path / "ck"), "--checkpoint-every", "4000",
                   "--json", str(tmp_path / "r.json"), "--no-progress"])
    assert rc == 0
    out = capsys.readouterr().out
    assert "collisions       10,000" in out and "(8 frames)" in out
    assert read_xyz_counts(tmp_path / "t.xyz") == [0, 1500, 3000, 4500, 6000, 7500, 9000, 10000]
    assert sorted(os.listdir(tmp_path / "ck")) == [f"checkpoint-{k:012d}.npz" for k in (4000, 8000, 10000)]
    r = json.loads((tmp_path / "r.json").read_text())
    assert r["kind"] == "simulate" and r["collisions"] == r["net_collisions"] == 10000 and not r["interrupted"]
    # the float engine keeps E to round-off; the lattice engine's velocities are quantized (docs/lattice.md)
    assert r["trajectory_frames"] == 8 and abs(r["energy_drift"]) < (1e-12 if r["engine"] == "float" else 1e-9)
    assert not [f for f in os.listdir(tmp_path) if f.startswith(".revcol-")]  # no temporary left


@pytest.mark.parametrize("text,cls", [(FLOAT, Simulation), (LATTICE, LatticeSimulation)], ids=["float", "lattice"])
def test_the_last_checkpoint_resumes_bit_for_bit(tmp_path, text, cls):
    s = scene_file(tmp_path, text)
    whole = simulate(s, collisions=10000, checkpoints=tmp_path / "a", checkpoint_every=3000, progress=False)
    assert [os.path.basename(c) for c in whole["checkpoints"]] == [
        f"checkpoint-{k:012d}.npz" for k in (3000, 6000, 9000, 10000)]
    # from the last checkpoint before the end, on to 10,000: the same state as the run that never stopped
    part = simulate(s, collisions=1000, resume=whole["checkpoints"][-2], checkpoints=tmp_path / "b",
                    checkpoint_every=3000, progress=False)
    assert part["collisions"] == 1000 and part["net_collisions"] == 10000
    a, b = cls.load(whole["checkpoints"][-1]).snapshot(), cls.load(part["checkpoints"][-1]).snapshot()
    assert a.keys() == b.keys()
    for k in a:
        assert np.array_equal(np.asarray(a[k]), np.asarray(b[k])), k
    # and the end state goes on: resuming the last checkpoint continues the numbering
    more = simulate(s, collisions=500, resume=whole["checkpoints"][-1], progress=False)
    assert more["net_collisions"] == 10500


def test_time_runs_and_the_scene_observables_go_in_the_report(tmp_path, capsys):
    s = scene_file(tmp_path, FLOAT + "[observe]\n")
    assert cli_main(["simulate", s, "--time", "2.5", "--json", "-", "--no-progress"]) == 0
    cap = capsys.readouterr()
    r = json.loads(cap.out)
    assert r["time_start"] == 0.0 and r["time_end"] == pytest.approx(2.5, abs=0) and r["collisions"] > 0
    assert r["observe"]["t_end"] == r["time_end"] and r["observe"]["particle_collisions"] == 2 * r["collisions"]
    assert r["observe"]["compressibility"][0] > 1 and r["observe"]["temperature"][0] == pytest.approx(1.0, rel=0.05)
    assert "revcol simulate s" in cap.err and "pressure_virial" in cap.err


def test_gsd_frames_of_a_simulate_run(tmp_path):
    gsd_hoomd = pytest.importorskip("gsd.hoomd")
    s = scene_file(tmp_path, FLOAT)
    r = simulate(s, collisions=2000, trajectory=tmp_path / "t.gsd", every=250, progress=False)
    with gsd_hoomd.open(str(tmp_path / "t.gsd"), "r") as f:
        steps = [int(fr.configuration.step) for fr in f]
        assert steps == list(range(0, 2001, 250)) == [int(fr.log["revcol/net_collisions"][0]) for fr in f]
        assert all(int(fr.log["revcol/direction"][0]) == 1 for fr in f) and len(f) == r["trajectory_frames"]


@pytest.mark.parametrize("text", [FLOAT, LATTICE], ids=["float", "lattice"])
def test_frames_on_a_time_trigger(tmp_path, text):
    # every_time: a frame at each multiple of T on the clock (between events, not at a
    # collision), the start and the end; the run is bit for bit the one without the pauses
    s = scene_file(tmp_path, text)
    r = simulate(s, time=2.0, trajectory=tmp_path / "t.xyz", every_time=0.25, progress=False)
    lines = open(tmp_path / "t.xyz").read().splitlines()
    times = [float(ln.split("Time=")[1].split()[0]) for ln in lines if "Time=" in ln]
    tick = 0.0 if text == FLOAT else 1e-3
    assert len(times) == 9 == r["trajectory_frames"]
    assert np.allclose(times, np.arange(0.0, 2.01, 0.25), atol=tick)
    twin = simulate(s, time=2.0, progress=False)
    assert twin["net_collisions"] == r["net_collisions"] and twin["time_end"] == r["time_end"]
    # a period whose multiples round back below themselves (floor(3 * 0.7 / 0.7) == 2) must not
    # stall the run at a frame time (it did: the next frame time was computed as the current one)
    r = simulate(s, collisions=400, trajectory=tmp_path / "u.xyz", every_time=0.7, progress=False)
    assert r["collisions"] == 400 and not r["stalled"] and r["trajectory_frames"] > 4


@pytest.mark.parametrize("args,message", [
    (["--collisions", "10", "--time", "1"], "not allowed with argument"),
    (["--collisions", "0"], "expected a positive integer"),
    (["--time", "-1"], "expected a positive"),
    (["--every", "10"], "--every needs --trajectory"),
    (["--checkpoint-every", "10"], "--checkpoint-every needs --checkpoint DIR"),
    (["--checkpoint", "CK"], "--checkpoint needs --checkpoint-every K"),
    (["--trajectory", "t.pdb"], "the suffix must be .xyz (extended XYZ) or .gsd"),
    (["--trajectory", "t.xyz", "--species", "A"], "chemical element symbol"),
    (["--resume", "missing.npz"], "is not a file"),
    (["--colisions", "10"], "did you mean '--collisions'"),
    (["--every-time", "0.5"], "--every-time needs --trajectory"),
    (["--trajectory", "t.xyz", "--every", "5", "--every-time", "0.5"], "give one frame trigger, not both"),
    (["--trajectory", "t.xyz", "--every-time", "-1"], "expected a positive"),
])
def test_bad_options_are_named_errors_and_run_nothing(tmp_path, capsys, args, message):
    s = scene_file(tmp_path, FLOAT)
    args = [str(tmp_path / a) if a in ("CK", "t.pdb", "t.xyz", "missing.npz") else a for a in args]
    try:  # argparse's own checks exit through SystemExit(2), revcol's return 2
        rc = cli_main(["simulate", s, *args, "--json", str(tmp_path / "r.json")])
    except SystemExit as e:
        rc = e.code
    assert rc == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err
    assert sorted(os.listdir(tmp_path)) == ["s.toml"]  # nothing written


def test_a_scene_that_is_not_a_gas_is_refused(tmp_path):
    from revcol.scene import load_scene

    with pytest.raises(SceneError, match="runs 'gas' scenes"):
        simulate(load_scene("paper-pair2d-reversal"), collisions=10, progress=False)


@pytest.mark.parametrize("kw,message", [
    (dict(trajectory="t.xyz", every=0), "--every must be a positive integer"),
    (dict(checkpoints="ck", checkpoint_every=2.5), "--checkpoint-every must be a positive integer"),
    (dict(collisions=True), "--collisions must be a positive integer"),
    (dict(time=float("nan")), "--time must be a positive finite number"),
    (dict(trajectory="t.xyz", every_time=float("inf")), "--every-time must be a positive finite number"),
])
def test_the_python_api_names_bad_values_too(tmp_path, kw, message):
    kw = {k: (str(tmp_path / v) if k in ("trajectory", "checkpoints") else v) for k, v in kw.items()}
    with pytest.raises(SceneError, match=message):
        simulate(scene_file(tmp_path, FLOAT), progress=False, **kw)
    assert sorted(os.listdir(tmp_path)) == ["s.toml"]


def test_ctrl_c_stops_cleanly_with_the_outputs_closed(tmp_path, capsys, monkeypatch):
    import revcol.cli.simulate as sm

    enter, timers = sm.Interrupt.__enter__, []

    def enter_then_interrupt(self):  # SIGINT 0.3 s after the handler is installed, never before
        out = enter(self)
        timers.append(threading.Timer(0.3, os.kill, (os.getpid(), signal.SIGINT)))
        timers[-1].start()
        return out
    monkeypatch.setattr(sm.Interrupt, "__enter__", enter_then_interrupt)
    before = signal.getsignal(signal.SIGINT)
    s = scene_file(tmp_path, "[system]\ndimension = 1\nparticles = 1000\npacking_fraction = 0.3\n"
                   "[collisions]\nengine = \"float\"\n[run]\ncollisions = 100\n")
    try:
        rc = cli_main(["simulate", s, "--collisions", "1e9", "--trajectory", str(tmp_path / "t.xyz"),
                       "--every", "1000000", "--checkpoint", str(tmp_path / "ck"), "--checkpoint-every", "1e8",
                       "--json", str(tmp_path / "r.json"), "--no-progress"])
    finally:
        for t in timers:
            t.cancel()
    assert rc == 130 and "interrupted" in capsys.readouterr().out
    r = json.loads((tmp_path / "r.json").read_text())
    assert r["interrupted"] and 0 < r["collisions"] < 10**9
    counts = read_xyz_counts(tmp_path / "t.xyz")  # the file is whole, its last frame where it stopped
    assert counts[0] == 0 and counts[-1] == r["collisions"] and len(counts) == r["trajectory_frames"]
    assert [os.path.basename(c) for c in r["checkpoints"]][-1] == f"checkpoint-{r['collisions']:012d}.npz"
    assert signal.getsignal(signal.SIGINT) is before


@pytest.mark.parametrize("text", [FLOAT, LATTICE], ids=["float", "lattice"])
def test_a_scene_s_outputs_are_revcol_run_s_simulate_writes_what_it_is_asked(tmp_path, capsys, monkeypatch, text):
    # issue 58: a shipped scene's demo [output] (a frame and a checkpoint every 1000 collisions)
    # had carried over into simulate and filled ./out; now only the options write, and the
    # report says which of the scene's outputs it left to revcol run
    monkeypatch.chdir(tmp_path)
    s = scene_file(tmp_path, text.replace("collisions = 500\n", "collisions = 500\ncheckpoint_interval = 100\n")
                   + "[output]\njson = \"scene.json\"\ntrajectory = \"scene.xyz\"\ncheckpoints = \"scene-ck\"\n")
    assert cli_main(["simulate", s, "--collisions", "300", "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.toml"]
    assert "not written      the scene's [output] json, [output] trajectory, [output] checkpoints" in out
    # asked on the command line: written, the checkpoints as a count and a folder
    assert cli_main(["simulate", s, "--collisions", "300", "--checkpoint", "ck", "--trajectory", "t.xyz",
                     "--every", "100", "--json", "r.json", "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "written          t.xyz, r.json, 3 checkpoints in ck/" in out  # every 100 (the scene's interval)
    assert json.load(open("r.json"))["scene_outputs_not_written"] == ["json", "trajectory", "checkpoints"]
    assert not (tmp_path / "scene.xyz").exists() and not (tmp_path / "scene-ck").exists()
