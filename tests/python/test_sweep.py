"""revcol sweep (issue 20): sweep files, the same results on Dask as run one after another, a
worker killed mid-sweep, an interrupted sweep resumed, a separately started cluster, named errors."""
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from revcol.studies.scenes import run_scene
from revcol.scene import load_scene
from revcol.sweep import SweepError, load_sweep, sweep, sweep_from_dict

import distributed  # noqa: F401 - setup.sh installs dask[distributed]; no test here is skipped

# what changes from one run of a point to the next: when, and the process's memory
VOLATILE = {"date", "peak_rss_bytes", "written"}

SWEEP_TOML = """
[sweep]
name = "small"
study = "horizon"
scene = "default"

[vary]
seed = {start = 0, count = 6}

[options]
max_collisions = 1000000
"""

PARTICLES = 300  # about 0.3 s a point: long enough for a worker to die under one


def _stable(report: dict) -> dict:
    return {k: v for k, v in report.items() if k not in VOLATILE}


def _reports(out: Path) -> dict:
    """hash -> the stable part of each point file's report."""
    return {json.loads(p.read_text())["hash"]: _stable(json.loads(p.read_text())["report"])
            for p in (out / "points").glob("*.json")}


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    """The small sweep file and its points run here one after another (the serial reference)."""
    d = tmp_path_factory.mktemp("sweep")
    f = d / "small.toml"
    f.write_text(SWEEP_TOML + f"particles = {PARTICLES}\n")  # into [options]
    s = sweep(f, out=d / "serial", workers=0)
    assert s["complete"] and s["ran"] == 6 and not s["failed"]
    return f, _reports(d / "serial")


@pytest.fixture(scope="module")
def client():
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0",
                      worker_dashboard_address=":0", resources={"MEMORY": 4 * 2**30}) as cluster:
        with Client(cluster) as c:
            yield c


def test_sweep_file_points_and_hashes(small):
    f, serial = small
    s = load_sweep(f)
    assert [p.params for p in s.points] == [{"max_collisions": 1000000, "particles": PARTICLES, "seed": k}
                                            for k in range(6)]
    assert len({p.hash for p in s.points}) == 6 and set(serial) == {p.hash for p in s.points}
    assert all(p.scene.seed == k and p.scene.particles == PARTICLES for k, p in enumerate(s.points))
    # a changed scene is a different point: its old result is never reused
    other = load_sweep(f)
    assert [p.hash for p in other.points] == [p.hash for p in s.points]
    doc = {"sweep": {"study": "horizon"}, "vary": {"seed": [0]}, "options": {"particles": PARTICLES + 1}}
    assert sweep_from_dict(doc).points[0].hash != s.points[0].hash


def test_local_cluster_matches_serial_point_for_point(small, tmp_path):
    f, serial = small
    s = sweep(f, out=tmp_path, workers=2)
    assert s["complete"] and s["ran"] == 6 and not s["failed"] and s["cluster"]["kind"] == "local"
    assert s["cluster"]["workers"] == 2
    assert _reports(tmp_path) == serial
    # the table: one row per point, in the sweep's order
    rows = (tmp_path / "small.csv").read_text().splitlines()
    assert len(rows) == 7 and [r.split(",")[0] for r in rows[1:]] == [str(k) for k in range(6)]
    assert len(s["loadavg_start"]) == 3


def test_combined_seeds_are_the_serial_horizon(tmp_path):
    """A sweep over seeds 0..K-1 combines to what revcol run --horizon --seeds K reports: on the
    lattice (bit-for-bit counts) and on the float engine (worst errors, medians, horizon)."""
    for engine, n in (("lattice", 100), ("float", 60)):
        doc = {"sweep": {"name": engine, "study": "horizon"}, "vary": {"seed": {"start": 3, "count": 3}},
               "options": {"particles": n, "engine": engine, "max_collisions": 20000}}
        s = sweep(sweep_from_dict(doc), out=tmp_path / engine, workers=0)
        scene = load_scene(None)
        import dataclasses

        ref = run_scene(dataclasses.replace(scene, particles=n, seed=3), horizon_seeds=3, max_collisions=20000,
                        engine=engine, progress=False)
        (c,) = s["combined"]
        assert c["rows"] == ref["rows"] and c["seeds"] == 3
        if engine == "float":
            assert c["horizon_collisions"] == ref["horizon_collisions"] and c["horizon_reached"] == ref["horizon_reached"]
            assert [Path(p).name for p in s["figures"]] == ["float-error.png"]
        else:
            assert c["passed"] is True and ref["passed"] is True


def test_worker_killed_mid_sweep(small, client, tmp_path):
    f, serial = small
    before = client.run(os.getpid)
    killed = []

    def kill_one(_):
        if not killed:  # after the first point: kill a worker that is running one
            busy = {a: keys for a, keys in client.processing().items() if keys}
            addr = sorted(busy)[0]
            os.kill(before[addr], signal.SIGKILL)
            killed.append((before[addr], {k.split("-")[2] for k in busy[addr]}))

    s = sweep(f, out=tmp_path, client=client, on_result=kill_one)
    assert killed and s["complete"] and s["ran"] == 6 and not s["failed"]
    assert _reports(tmp_path) == serial
    pid, lost = killed[0]
    for h in lost:  # the tasks the dead worker held were run again, elsewhere, to the same report
        assert json.loads((tmp_path / "points" / f"{h}.json").read_text())["pid"] != pid
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline and len(client.scheduler_info()["workers"]) < 2:
        time.sleep(0.2)
    assert pid not in client.run(os.getpid).values()  # the nanny started a new worker


def test_interrupted_sweep_resumes_without_redoing(small, client, tmp_path):
    f, serial = small
    s = sweep(f, out=tmp_path, client=client, stop_after=2)
    assert s["ran"] == 2 and s["done"] == 2 and not s["complete"] and len(s["missing"]) == 4
    first = {p.name: p.stat().st_mtime_ns for p in (tmp_path / "points").glob("*.json")}
    assert len(first) == 2
    s = sweep(f, out=tmp_path, client=client)
    assert s["ran"] == 4 and s["reused"] == 2 and s["complete"]
    assert {p.name: p.stat().st_mtime_ns for p in (tmp_path / "points").glob("*.json") if p.name in first} == first
    assert _reports(tmp_path) == serial
    rows = (tmp_path / "small.csv").read_text().splitlines()[1:]
    assert len(rows) == 6 and len({r.split(",")[1] for r in rows}) == 6  # no duplicate rows
    s = sweep(f, out=tmp_path, client=client)
    assert s["ran"] == 0 and s["reused"] == 6


def test_ctrl_c_on_a_terminal_stops_keeps_and_resumes(small, tmp_path):
    """SIGINT to the whole process group (what a terminal's Ctrl-C does): exit 130, the finished
    points kept, no worker traceback; the same command again completes."""
    f, serial = small
    cmd = [sys.executable, "-m", "revcol", "sweep", str(f), "--workers", "2", "--out", str(tmp_path), "--no-progress"]
    # SIGINT at its default in the child even if this process inherited it ignored (a
    # background job does): otherwise the sweep never sees the Ctrl-C
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
                         preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and len(list((tmp_path / "points").glob("*.json"))) < 1:
            time.sleep(0.05)
        os.killpg(p.pid, signal.SIGINT)
        out, err = p.communicate(timeout=60)
    finally:
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGKILL)
            p.wait()
    kept = len(list((tmp_path / "points").glob("*.json")))
    assert p.returncode == 130 and "Traceback" not in err, err
    assert kept >= 1
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert f"{kept} already done" in done.stderr and _reports(tmp_path) == serial


def test_a_ctrl_c_inside_a_dask_call_is_acted_on_between_calls(small, client, tmp_path, monkeypatch):
    """SIGINT while the client is inside one of distributed's blocking calls: that call finishes
    (an interrupt inside it makes distributed log a NameError traceback when it lands before the
    call's future exists: the CI failure of 5e496bb), its finished point is written, and the sweep
    stops as interrupted at the next poll; the same sweep again completes with the serial bits."""
    f, serial = small
    seen, before = [], signal.getsignal(signal.SIGINT)
    result = distributed.Future.result

    def result_under_ctrl_c(self, *a, **k):
        if not seen:
            seen.append(signal.getsignal(signal.SIGINT))
            os.kill(os.getpid(), signal.SIGINT)  # handled before the call below starts
        return result(self, *a, **k)

    monkeypatch.setattr(distributed.Future, "result", result_under_ctrl_c)
    s = sweep(f, out=tmp_path, client=client)
    monkeypatch.undo()
    assert seen and seen[0] not in (signal.default_int_handler, signal.SIG_DFL)
    assert s["interrupted"] and not s["complete"] and s["ran"] >= 1 and len(_reports(tmp_path)) == s["ran"]
    assert signal.getsignal(signal.SIGINT) is before  # given back
    s = sweep(f, out=tmp_path, client=client)
    assert s["complete"] and _reports(tmp_path) == serial


def test_a_point_larger_than_every_worker_is_refused(client, tmp_path):
    """Tasks claim the MEMORY resource; one no worker offers would wait forever: refused up front."""
    doc = {"sweep": {"name": "big", "study": "horizon"}, "vary": {"seed": [0, 1]},
           "options": {"particles": 50}, "resources": {"memory_gib": 8.0}}
    with pytest.raises(SweepError, match=r"point 0 \(.*\) needs 8.00 GiB, the largest worker offers 4.00 GiB"):
        sweep(sweep_from_dict(doc), out=tmp_path, client=client)
    assert not (tmp_path / "points").exists()
    assert sweep_from_dict(doc).points[0].memory_bytes == 8 * 2**30
    auto = sweep_from_dict({"sweep": {"study": "horizon"}, "options": {"particles": 10000}}).points[0]
    assert auto.memory_bytes == 256 * 2**20 + 2 * 1024 * 10000  # the engine and the clone running back


def _start(cmd, log):
    return subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, start_new_session=True)


def test_separately_started_cluster_runs_the_same_file(small, tmp_path):
    f, serial = small
    sched = tmp_path / "scheduler.json"
    procs = []
    log = open(tmp_path / "dask.log", "wb")
    try:
        procs.append(_start([sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port",
                             "0", "--dashboard-address", ":0", "--scheduler-file", str(sched)], log))
        deadline = time.monotonic() + 60
        while not sched.exists() and time.monotonic() < deadline:
            time.sleep(0.1)
        assert sched.exists(), (tmp_path / "dask.log").read_text()
        for _ in range(2):
            procs.append(_start([sys.executable, "-m", "distributed.cli.dask_worker", "--scheduler-file", str(sched),
                                 "--nthreads", "1", "--resources", f"MEMORY={2**31}", "--no-dashboard",
                                 "--host", "127.0.0.1"], log))
        p = subprocess.run([sys.executable, "-m", "revcol", "sweep", str(f), "--scheduler-file", str(sched), "--out",
                            str(tmp_path / "out"), "--no-progress"], capture_output=True, text=True, timeout=120)
        assert p.returncode == 0, p.stderr
        summary = json.loads((tmp_path / "out" / "small.json").read_text())
        assert summary["cluster"]["kind"] == "existing" and summary["complete"]
        assert _reports(tmp_path / "out") == serial
    finally:
        for q in procs:
            if q.poll() is None:
                os.killpg(q.pid, signal.SIGTERM)
        for q in procs:
            try:
                q.wait(timeout=10)
            except subprocess.TimeoutExpired:
                os.killpg(q.pid, signal.SIGKILL)
                q.wait()
        log.close()


def test_run_and_statesave_studies(tmp_path):
    """study = "run": each point is revcol run's report; "statesave": one N per point."""
    doc = {"sweep": {"name": "rt", "study": "run"}, "vary": {"seed": [0, 1]},
           "options": {"particles": 100, "collisions": 2000}}
    s = sweep(sweep_from_dict(doc), out=tmp_path / "rt", workers=0)
    assert s["complete"]
    import dataclasses

    for p in sweep_from_dict(doc).points:
        ref = run_scene(dataclasses.replace(load_scene(None), particles=100, collisions=2000, seed=p.params["seed"]),
                        progress=False)
        got = json.loads((tmp_path / "rt" / "points" / f"{p.hash}.json").read_text())["report"]
        assert got["passed"] and got["bit_for_bit"] == ref["bit_for_bit"] and got["collisions_forward"] == 2000
        assert got["kind"] == ref["kind"]
    doc = {"sweep": {"name": "ss", "study": "statesave"}, "vary": {"particles": [1000, 2000]},
           "options": {"collisions": 50, "repeats": 1, "runner": "inline"}}
    s = sweep(sweep_from_dict(doc), out=tmp_path / "ss", workers=0)
    assert s["complete"] and not s["failed"]
    reports = [json.loads(p.read_text())["report"] for p in (tmp_path / "ss" / "points").glob("*.json")]
    assert sorted(r["runs"][0]["particles"] for r in reports) == [1000, 2000]
    assert all(r["passed"] for r in reports)


def test_randomness_and_equilibrium_studies(tmp_path):
    """The studies without a scene: one dieharder battery, one dense gas per point; the same
    parameters give the same report as the study's own function."""
    from revcol.studies import equilibrium as physics, randomness

    doc = {"sweep": {"name": "rnd", "study": "randomness"}, "vary": {"rng": ["philox", "clcg4"]},
           "options": {"case": "raw", "words": 30000, "tests": [15]}}
    s = sweep(sweep_from_dict(doc), out=tmp_path / "rnd", workers=0)
    assert s["complete"] and not s["failed"]
    rows = (tmp_path / "rnd" / "rnd.csv").read_text().splitlines()
    assert len(rows) == 3 and rows[0].startswith("index,hash,case,words,tests,rng,kind,")
    p = sweep_from_dict(doc).points[0]
    got = json.loads((tmp_path / "rnd" / "points" / f"{p.hash}.json").read_text())["report"]
    ref = randomness.battery({"case": "raw", "mode": "exact", "law": "flux", "rng": "philox", "seed": 0}, 30000, (15,))
    assert got["pvalues"] == ref["pvalues"] and got["verdict"] == ref["verdict"]
    doc = {"sweep": {"name": "eq", "study": "equilibrium"}, "vary": {"packing_fraction": [0.2, 0.4]},
           "options": {"particles": 64, "per_particle": 10.0}}
    s = sweep(sweep_from_dict(doc), out=tmp_path / "eq", workers=0)
    assert s["complete"] and not s["failed"]
    p = sweep_from_dict(doc).points[1]
    got = json.loads((tmp_path / "eq" / "points" / f"{p.hash}.json").read_text())["report"]
    ref = physics.dense(2, 0.4, "flux", n=64, per_particle=10.0, seed=1)
    assert got["z"] == ref["z"] and got["collisions"] == ref["collisions"] and got["kind"] == "equilibrium"


def test_default_output_folder_and_table(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    doc = {"sweep": {"name": "tiny", "study": "horizon"}, "vary": {"seed": [5, 6]}, "options": {"particles": 50}}
    s = sweep(sweep_from_dict(doc), workers=0)
    out = tmp_path / "out" / "sweeps" / "tiny"
    assert s["out"] == str(out) and json.loads((out / "tiny.json").read_text())["done"] == 2
    import csv

    rows = list(csv.DictReader((out / "tiny.csv").open()))
    assert [r["seed"] for r in rows] == ["5", "6"] and all(r["passed"] == "True" for r in rows)
    assert {r["hash"] for r in rows} == {p.stem for p in (out / "points").glob("*.json")}


BAD = [
    ({"swep": {}}, "[swep]: unknown table"),
    ({"sweep": {"studdy": "run"}}, "[sweep] studdy: unknown field"),
    ({"sweep": {"study": "horizn"}}, "[sweep] study: must be one of"),
    ({"sweep": {"combine": "zip"}}, "[sweep] combine: must be 'grid' or 'list'"),
    ({"sweep": {"scene": "no-such-scene"}}, "[sweep] scene: 'no-such-scene' is neither a file"),
    ({"sweep": {"name": "a/b"}}, "[sweep] name: must be a plain name"),
    ({"sweep": {"combine": "list"}, "vary": {"seed": [1, 2], "particles": [100]}}, "'list' needs [vary] lists of one"),
    ({"vary": {"colour": [1]}}, "parameter 'colour': unknown for study 'run'"),
    ({"vary": {"output.json": ["x.json"]}}, "points write none"),
    ({"vary": {"seed": []}}, "[vary] seed: must be a non-empty list"),
    ({"vary": {"seed": {"start": 0, "stop": 3}}}, "[vary] seed: a range is {start = S, count = K}"),
    ({"vary": {"seed": [1, 1]}}, "points 0 and 1 are the same run"),
    ({"vary": {"particles": [100, -5]}}, "point 1 (particles=-5): [system] particles: must be"),
    ({"vary": {"seed": [0]}, "options": {"seed": 1}}, "[options]: seed also in [vary]"),
    ({"resources": {"memory_gib": -1}}, "[resources] memory_gib: must be a positive number"),
    ({"resources": {"retries": True}}, "[resources] retries: must be an integer"),
    ({"resources": {"cores": 2}}, "[resources] cores: unknown field"),
    ({"sweep": {"study": "horizon", "scene": "paper-statesave"}}, "study 'horizon' needs a gas scene"),
    ({"sweep": {"study": "statesave", "scene": "default"}}, "study 'statesave' needs a statesave scene"),
    ({"sweep": {"study": "horizon"}, "options": {"seeds": 0}}, "seeds must be a positive integer"),
    ({"sweep": {"study": "horizon"}, "options": {"engine": "gpu"}}, "--engine must be one of"),
    ({"sweep": {"study": "run"}, "options": {"max_collisions": 5}}, "parameter 'max_collisions': unknown"),
    ({"sweep": {"study": "randomness", "scene": "default"}}, "study 'randomness' runs no scene"),
    ({"sweep": {"study": "randomness"}, "vary": {"rng": ["philox", "mt"]}}, "point 1 (rng='mt'): parameter 'rng'"),
    ({"sweep": {"study": "randomness"}, "options": {"tests": [99]}}, "parameter 'tests': must be a non-empty list"),
    ({"sweep": {"study": "randomness"}, "options": {"case": "pair9d"}}, "parameter 'case': must be a word-stream"),
    ({"sweep": {"study": "equilibrium"}, "options": {"dimension": 3, "packing_fraction": 0.72}},
     "at most 0.7 in 3D"),
    ({"sweep": {"study": "equilibrium"}, "vary": {"temperature": [1.0]}}, "parameter 'temperature': unknown"),
]


@pytest.mark.parametrize("doc,message", BAD, ids=[m[:30] for _, m in BAD])
def test_bad_sweep_files_are_named_errors(doc, message):
    with pytest.raises(SweepError) as e:
        sweep_from_dict(doc, "bad.toml")
    assert message in str(e.value) and str(e.value).startswith("bad.toml")


def test_bad_arguments_and_files_exit_2(tmp_path, capsys):
    from revcol.cli.main import main

    bad = tmp_path / "bad.toml"
    bad.write_text('[sweep]\nstudy = "nope"\n')
    assert main(["sweep", str(bad)]) == 2
    assert "bad.toml: [sweep] study: must be one of" in capsys.readouterr().err
    assert main(["sweep", str(tmp_path / "missing.toml")]) == 2
    assert "no such sweep file" in capsys.readouterr().err
    (tmp_path / "broken.toml").write_text("[sweep\n")
    assert main(["sweep", str(tmp_path / "broken.toml")]) == 2
    assert "not valid TOML" in capsys.readouterr().err
    good = tmp_path / "good.toml"
    good.write_text("[vary]\nseed = [0]\n")
    assert main(["sweep", str(good), "--workers", "-1"]) == 2
    (tmp_path / "file").write_text("")
    assert main(["sweep", str(good), "--out", str(tmp_path / "file")]) == 2
    assert "exists and is not a folder" in capsys.readouterr().err
    for kw in ({"workers": -1}, {"stop_after": 0}, {"workers": 2, "scheduler": "tcp://127.0.0.1:1"},
               {"scheduler_file": tmp_path / "no-scheduler.json"}):
        with pytest.raises(SweepError):
            sweep(good, out=tmp_path / "o", **kw)
    assert not (tmp_path / "o").exists()  # a refused sweep wrote nothing


def test_shipped_sweeps_are_found_by_name(tmp_path, monkeypatch):
    # the example sweeps ship in the wheel (revcol/sweeps) and are found by name, as scenes are
    from revcol.sweep import SweepError, load_sweep, sweep_names

    monkeypatch.chdir(tmp_path)
    assert {"default-horizon", "horizon-phi-n", "paper-statesave"} <= set(sweep_names())
    for name in ("default-horizon", "default-horizon.toml"):
        s = load_sweep(name)
        assert Path(s.source).name == "default-horizon.toml" and Path(s.source).is_file()
    with pytest.raises(SweepError, match=r"nor a sweep name .*did you mean 'default-horizon'"):
        load_sweep("default-horizn")
    # a file of that name in the current directory wins
    (tmp_path / "default-horizon.toml").write_text('[sweep]\nstudy = "nope"\n')
    with pytest.raises(SweepError, match="study"):
        load_sweep("default-horizon.toml")


def test_revcol_sweep_is_the_function():
    import revcol
    from revcol.sweep import sweep as fn

    assert revcol.sweep is fn and "sweep" in revcol.__all__
