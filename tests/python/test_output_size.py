"""Outputs that never fill a disk (issue 59): every output's bytes are estimated before a run starts
(``revcol._output_size``), and a run whose outputs come to more than ``--max-output`` / ``[output]
max_output`` (10 GiB unless told) or more than the free space is refused (exit 2, one line naming
the writer, its estimate and the limit or the free space) with nothing written; a write that fails
mid-run (ENOSPC) names the file and leaves no temporary file behind; and the estimates are honest:
within a factor 2 of the bytes a small real run writes (estimated / written, measured: 0.999-1.001
for extended XYZ trajectories, 0.99-1.49 for GSD, 0.996-1.000 for checkpoints, 0.83-1.12 for runs
to a time, whose collisions are expected from the Enskog rate)."""
import errno
import glob
import json
import os
import shutil

import numpy as np
import pytest

import revcol._output_size
import revcol._outputs
import revcol.trajectory
from conftest import run_cli as _cli
from revcol.cli.simulate import simulate
from revcol.scene import SceneError, load_scene
from revcol.studies.scenes import run_scene

GAS = "[system]\ndimension = {d}\nparticles = {n}\npacking_fraction = 0.3\nboundaries = \"{b}\"\n" \
      "[collisions]\nengine = \"{engine}\"\n[run]\ncollisions = {c}\n"
ENOSPC = OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


def _scene(tmp_path, engine="float", n=20, c=100, d=2, b="wall", extra=""):
    (tmp_path / "s.toml").write_text(GAS.format(d=d, n=n, b=b, engine=engine, c=c) + extra)
    return "s.toml"


def _files(root):
    return sorted(os.path.relpath(p, root) for p in glob.glob(os.path.join(root, "**"), recursive=True)
                  + glob.glob(os.path.join(root, "**", ".*"), recursive=True) if os.path.isfile(p))


def _temporaries(root):
    return [f for f in _files(root) if os.path.basename(f).startswith(".revcol-")]


# --- refused up front --------------------------------------------------------------------------

@pytest.mark.parametrize("command", ["simulate", "run"])
def test_the_issues_trajectory_is_refused_with_its_estimate_and_nothing_written(tmp_path, capsys, command):
    # the issue: a frame every collision, 10^9 collisions (517 MB in 15 s, then ENOSPC naming no file)
    if command == "simulate":
        args = ["simulate", "--collisions", "1000000000", "--trajectory", "t.xyz", "--every", "1"]
    else:
        args = ["run", _scene(tmp_path, "lattice", 1000, 10**9, extra="[output]\ntrajectory = \"t.xyz\"\n"
                              "trajectory_every = 1\n")]
    before = _files(tmp_path)
    rc, err = _cli(tmp_path, args, capsys)
    assert rc == 2 and len(err) == 1, err
    assert "[output] trajectory / --trajectory would write about" in err[0] and "TiB" in err[0], err
    frames = "1,000,000,001 frames" if command == "simulate" else "2,000,000,001 frames"
    assert f"({frames} of 1,000 particles" in err[0] and "a frame every collision" in err[0], err
    assert "more than the output limit of 10 GiB" in err[0] and "refusing to start" in err[0], err
    assert _files(tmp_path) == before  # nothing written, no .part


def test_with_no_limit_the_free_space_refuses_it(tmp_path, capsys, monkeypatch):
    free = []

    def disk_usage(path):
        free.append(path)
        return shutil._ntuple_diskusage(100 << 30, 99 << 30, 1 << 30)  # total, used, free
    monkeypatch.setattr(revcol._outputs.shutil, "disk_usage", disk_usage)
    rc, err = _cli(tmp_path, ["simulate", "--collisions", "100000", "--trajectory", "sub/t.xyz", "--every", "1",
                              "--max-output", "none"], capsys)
    assert rc == 2 and len(err) == 1, err
    assert "would write about 6.45 GiB (100,001 frames of 1,000 particles" in err[0], err
    assert f"more than the 1 GiB free on the file system of {tmp_path}: refusing to start" in err[0], err
    assert free == [tmp_path] and _files(tmp_path) == [] and not (tmp_path / "sub").exists()


def test_max_output_refuses_and_allows(tmp_path, capsys):
    s = _scene(tmp_path)  # 20 disks, 100 collisions, a frame every one: about 140 kB
    traj = ["--trajectory", "t.xyz", "--every", "1"]
    for limit in ("50K", "51200", "50KiB"):
        rc, err = _cli(tmp_path, ["simulate", s, *traj, "--max-output", limit], capsys)
        assert rc == 2 and "more than the output limit of 50 KiB" in err[0], err
        assert "(101 frames of 20 particles" in err[0] and "[output] trajectory / --trajectory" in err[0], err
    assert _files(tmp_path) == ["s.toml"]
    rc, err = _cli(tmp_path, ["simulate", s, *traj, "--max-output", "1M", "--json", "r.json"], capsys)
    assert rc == 0, err
    estimate = json.loads((tmp_path / "r.json").read_text())["output_estimate"]
    assert set(estimate) == {"[output] trajectory / --trajectory", "[output] json / --json"}
    assert 0.5 < estimate["[output] trajectory / --trajectory"]["bytes"] / os.path.getsize(tmp_path / "t.xyz") < 2


def test_the_scene_key_sets_the_limit_and_the_option_overrides_it(tmp_path, capsys):
    s = _scene(tmp_path, "lattice", extra="[output]\ntrajectory = \"t.xyz\"\ntrajectory_every = 1\n"
               "max_output = \"10K\"\n")
    # simulate writes its options' outputs only (issue 58); the scene's limit holds for them too
    for args in (["run", s], ["simulate", s, "--trajectory", "t.xyz", "--every", "1"]):
        rc, err = _cli(tmp_path, args, capsys)
        assert rc == 2 and "more than the output limit of 10 KiB" in err[0], err
    assert not (tmp_path / "t.xyz").exists()
    rc, err = _cli(tmp_path, ["run", s, "--max-output", "none"], capsys)
    assert rc == 0 and (tmp_path / "t.xyz").exists(), err
    assert load_scene(tmp_path / s).max_output == 10 << 10


@pytest.mark.parametrize("command", ["run", "simulate"])
@pytest.mark.parametrize("value", ["20GB", "-5", "lots", "1.5X", "inf", ""])
def test_a_bad_max_output_is_refused_by_name(tmp_path, capsys, command, value):
    rc, err = _cli(tmp_path, [command, _scene(tmp_path), "--max-output", value], capsys)
    assert rc == 2 and len(err) == 1 and "--max-output must be a size" in err[0] and repr(value) in err[0], err
    assert _files(tmp_path) == ["s.toml"]


@pytest.mark.parametrize("value,message", [('"lots"', "must be a size"), ("-1", "must be a size >= 0"),
                                           ("1.5", "must be a size in bytes"), ("true", "must be a size in bytes")])
def test_a_bad_scene_max_output_is_refused_by_name(tmp_path, value, message):
    _scene(tmp_path, extra=f"[output]\nmax_output = {value}\n")
    with pytest.raises(SceneError, match=r"\[output\] max_output: " + message):
        load_scene(tmp_path / "s.toml")


def test_sizes_read_as_documented():
    from revcol._args import size
    assert [size(v, "x") for v in ("20G", "20g", "10GiB", "1.5T", "512", "0", "none", " 3M ", 7)] == [
        20 << 30, 20 << 30, 10 << 30, 3 << 39, 512, 0, 0, 3 << 20, 7]
    assert revcol._outputs.human(63.4 * 2**40) == "63.4 TiB" and revcol._outputs.human(999) == "999 B"


# --- a write that fails mid-run ----------------------------------------------------------------

class _Full:
    """A file that takes ``room`` characters and then fails as a full disk does (in ``write``, or
    with ``at_close`` in the flush of ``close``)."""

    def __init__(self, f, room, at_close=False):
        self.f, self.room, self.at_close = f, room, at_close

    def write(self, s):
        if not self.at_close and len(s) > self.room:
            raise ENOSPC
        self.room -= len(s)
        return self.f.write(s)

    def close(self):
        self.f.close()
        if self.at_close:
            raise ENOSPC

    def __getattr__(self, name):
        return getattr(self.f, name)


@pytest.mark.parametrize("command", ["simulate", "run"])
@pytest.mark.parametrize("engine", ["float", "lattice"])
@pytest.mark.parametrize("at_close", [False, True], ids=["write", "close"])
def test_a_full_disk_under_the_trajectory_names_it_and_leaves_no_part(tmp_path, capsys, monkeypatch, command,
                                                                      engine, at_close):
    init = revcol.trajectory.XYZWriter.__init__

    def full(self, *a, **k):
        init(self, *a, **k)
        self._f = _Full(self._f, 20_000, at_close)  # a few frames of 20 disks fit
    monkeypatch.setattr(revcol.trajectory.XYZWriter, "__init__", full)
    s = _scene(tmp_path, engine, c=200, extra="[output]\ntrajectory_every = 1\n")
    rc, err = _cli(tmp_path, [command, s, "--trajectory", "out/t.xyz"] + (["--every", "1"] * (command == "simulate")),
                   capsys)
    assert rc == 2 and len(err) == 1, err
    assert "[Errno 28] No space left on device" in err[0] and "out/t.xyz" in err[0], err
    assert ("closing the trajectory" if at_close else "writing frame") in err[0], err
    assert "the partial file is removed" in err[0], err
    assert _files(tmp_path) == ["s.toml"]  # no .part, and no trajectory with half a frame


@pytest.mark.parametrize("command", ["simulate", "run"])
@pytest.mark.parametrize("engine", ["float", "lattice"])
def test_a_full_disk_under_a_checkpoint_names_it_and_leaves_no_temporary(tmp_path, capsys, monkeypatch, command,
                                                                         engine):
    real, calls = np.savez, []

    def savez(f, **arrays):  # the second checkpoint meets a full disk half way
        calls.append(1)
        if len(calls) == 2:
            f.write(b"PK\x03\x04" + bytes(4096))
            raise ENOSPC
        return real(f, **arrays)
    monkeypatch.setattr(np, "savez", savez)
    # the estimate's own sample checkpoints (revcol._output_size.state_bytes) are not the run's
    monkeypatch.setattr(revcol._output_size, "state_bytes", lambda scene: (1e4, 200.0))
    s = _scene(tmp_path, engine, c=400, extra="checkpoint_interval = 100\n[output]\ncheckpoints = \"ck\"\n"
               "trajectory = \"t.xyz\"\ntrajectory_every = 50\n")
    asked = ["--checkpoint", "ck", "--trajectory", "t.xyz", "--every", "50"] if command == "simulate" else []
    rc, err = _cli(tmp_path, [command, s, *asked], capsys)
    assert rc == 2 and len(err) == 1, err
    assert "[Errno 28] No space left on device" in err[0] and "checkpoint-000000000200.npz" in err[0], err
    assert os.listdir(tmp_path / "ck") == ["checkpoint-000000000100.npz"]
    assert _temporaries(tmp_path) == []  # neither the checkpoint's .tmp nor the trajectory's .part
    assert (tmp_path / "t.xyz").exists()  # closed on the way out with the frames written before


# --- the estimates against the bytes written ---------------------------------------------------

def _factors(r):
    """Estimated / written bytes of each estimated output of a report."""
    out = {}
    for what, e in r["output_estimate"].items():
        p = e["path"]
        written = (sum(os.path.getsize(f) for f in glob.glob(os.path.join(p, "*"))) if os.path.isdir(p)
                   else os.path.getsize(p))
        out[what.split(" /")[0]] = e["bytes"] / written
    return out


@pytest.mark.parametrize("engine,d,b", [("float", 2, "wall"), ("float", 3, "periodic"), ("lattice", 2, "periodic"),
                                        ("lattice", 3, "wall")])
@pytest.mark.parametrize("fmt", ["xyz", "gsd"])
def test_simulates_estimates_are_within_a_factor_2_of_the_bytes_written(tmp_path, engine, d, b, fmt):
    if fmt == "gsd":
        pytest.importorskip("gsd")
    scene = load_scene(tmp_path / _scene(tmp_path, engine, 200, 2000, d, b))
    r = simulate(scene, trajectory=tmp_path / f"t.{fmt}", every=50, checkpoints=tmp_path / "ck", checkpoint_every=500,
                 progress=False)
    f = _factors(r)
    assert set(f) == {"[output] trajectory", "[output] checkpoints"}
    assert all(0.5 < x < 2.0 for x in f.values()), f
    if fmt == "xyz":  # measured from the writer's own format: close
        assert 0.9 < f["[output] trajectory"] < 1.1, f


@pytest.mark.parametrize("engine", ["float", "lattice"])
def test_a_round_trips_estimates_are_within_a_factor_2_of_the_bytes_written(tmp_path, monkeypatch, engine):
    monkeypatch.chdir(tmp_path)  # the scene's [output] checkpoints = "ck" is taken under the current directory
    _scene(tmp_path, engine, 200, 2000, extra="checkpoint_interval = 400\n[output]\ncheckpoints = \"ck\"\n"
           "trajectory_every = 100\n")
    r = run_scene(load_scene(tmp_path / "s.toml"), trajectory=tmp_path / "t.xyz", progress=False)
    f = _factors(r)
    assert set(f) == {"[output] trajectory", "[output] checkpoints"} and r["trajectory_frames"] == 41
    assert all(0.9 < x < 1.1 for x in f.values()), f


@pytest.mark.parametrize("engine", ["float", "lattice"])
def test_a_run_to_a_time_is_estimated_from_the_enskog_rate(tmp_path, engine):
    text = GAS.format(d=2, n=200, b="periodic", engine=engine, c=1).replace("collisions = 1", "time = 4.0")
    (tmp_path / "s.toml").write_text(text)
    r = simulate(load_scene(tmp_path / "s.toml"), trajectory=tmp_path / "t.xyz", every=50,
                 checkpoints=tmp_path / "ck", checkpoint_every=500, progress=False)
    how = r["output_estimate"]["[output] trajectory / --trajectory"]["how"]
    assert "collisions expected in t = 4 at the Enskog collision rate" in how
    f = _factors(r)
    assert all(0.5 < x < 2.0 for x in f.values()), f


# --- revcol sweep: the same estimates over every point ------------------------------------------

SWEEP = "[sweep]\nname = \"sz\"\nstudy = \"run\"\n[vary]\nseed = {{start = 0, count = {k}}}\n" \
        "[options]\nparticles = 20\ncollisions = 100\n{extra}"


def _sweep_file(tmp_path, k, extra=""):
    (tmp_path / "sz.toml").write_text(SWEEP.format(k=k, extra=extra))
    return "sz.toml"


def test_a_small_sweep_under_the_limit_runs_and_its_summary_has_the_estimate(tmp_path, capsys):
    f = _sweep_file(tmp_path, 2)
    rc, err = _cli(tmp_path, ["sweep", f, "--workers", "0", "--out", "o", "--max-output", "2M"], capsys)
    assert rc == 0, err
    summary = json.loads((tmp_path / "o" / "sz.json").read_text())
    est = summary["output_estimate"]
    assert set(est) == {"the output folder's points/", "the output folder (--out)"}
    points = est["the output folder's points/"]
    assert points["bytes"] == 2 * revcol._output_size.REPORT_BYTES and "2 point reports still to run" in points["how"]
    written = sum(p.stat().st_size for p in (tmp_path / "o" / "points").glob("*.json"))
    assert 0 < written < points["bytes"]  # an allowance: the reports of 20 disks are about 20 kB
    # run again: nothing left to run, so no point report is estimated
    rc, err = _cli(tmp_path, ["sweep", f, "--workers", "0", "--out", "o", "--max-output", "300K"], capsys)
    assert rc == 0, err
    assert set(json.loads((tmp_path / "o" / "sz.json").read_text())["output_estimate"]) == {"the output folder (--out)"}


def test_a_sweep_over_the_default_limit_is_refused_with_its_estimate_and_nothing_written(tmp_path, capsys):
    # a point writes only its report (no trajectory, checkpoint or figure: revcol.sweep.spec strips
    # them); 48 reports with 2^20 speed bins each are estimated at 12 GiB, over the default 10 GiB
    f = _sweep_file(tmp_path, 48, "\"observe.speed_bins\" = 1048576\n")
    rc, err = _cli(tmp_path, ["sweep", f, "--workers", "0", "--out", "o"], capsys)
    assert rc == 2 and len(err) == 1, err
    assert err[0].startswith("revcol sweep: error: sz.toml: the output folder's points/ would write about 12 GiB "
                             "(48 point reports still to run, about 256 MiB each"), err
    assert "more than the output limit of 10 GiB (--max-output: a size such as 20G, or none): refusing to start" \
        in err[0], err
    assert _files(tmp_path) == ["sz.toml"]


def test_sweep_max_output_refuses_and_none_allows(tmp_path, capsys, monkeypatch):
    f = _sweep_file(tmp_path, 3)  # 3 x 256 KiB of reports, the table and the summary: about 1 MiB
    for limit in ("500K", "512000"):
        rc, err = _cli(tmp_path, ["sweep", f, "--workers", "0", "--out", "o", "--max-output", limit], capsys)
        assert rc == 2 and len(err) == 1 and "more than the output limit of 500 KiB" in err[0], err
        assert "the output folder's points/ would write about 768 KiB (3 point reports" in err[0], err
        assert "; the run's outputs come to about 1.0" in err[0], err
    rc, err = _cli(tmp_path, ["sweep", f, "--workers", "0", "--out", "o", "--max-output", "lots"], capsys)
    assert rc == 2 and "--max-output must be a size" in err[0], err
    assert _files(tmp_path) == ["sz.toml"]
    # no limit: the free space still counts
    monkeypatch.setattr(revcol._outputs.shutil, "disk_usage",
                        lambda path: shutil._ntuple_diskusage(100 << 30, 100 << 30, 100 << 10))
    rc, err = _cli(tmp_path, ["sweep", f, "--workers", "0", "--out", "o", "--max-output", "none"], capsys)
    assert rc == 2 and f"more than the 100 KiB free on the file system of {tmp_path}" in err[0], err
    monkeypatch.undo()
    rc, err = _cli(tmp_path, ["sweep", f, "--workers", "0", "--out", "o", "--max-output", "none"], capsys)
    assert rc == 0, err
    assert len(list((tmp_path / "o" / "points").glob("*.json"))) == 3


def test_sweep_estimate_functions():
    from revcol._output_size import sweep_files_size, sweep_points_size

    assert sweep_points_size([]) is None
    s = sweep_points_size([None, None])  # the studies without a scene: the report allowance each
    assert s.bytes == 2 * revcol._output_size.REPORT_BYTES and s.how.startswith("2 point reports still to run")
    files = sweep_files_size(10, 2)
    assert files.bytes == (10 * revcol._output_size.SWEEP_ROW_BYTES + revcol._output_size.REPORT_BYTES
                           + 10 * revcol._output_size.SWEEP_SUMMARY_BYTES_PER_POINT + 2 * revcol._output_size.FIGURE_BYTES)
