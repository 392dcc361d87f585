"""Issue 17's reproducers that crashed or never returned: each now raises a clear error and
leaves the simulation as it was (the first part of the hardening issue)."""
import json
import os
import numpy as np
import pytest

import revcol
from revcol import Simulation, _core
from revcol._io import digested


def test_a_diameter_whose_box_underflows_is_refused():
    # was a segfault: the particle volume underflowed, the box was 0, a cell index overflowed
    with pytest.raises(ValueError, match="not representable"):
        Simulation.random(10, 2, 0.3, diameter=1e-300)


def test_a_box_longer_than_2_30_diameters_is_refused():
    # was a hang: floor(L / D) overflowed int and defeated the cell-count check
    x = np.array([[1.0, 1.0], [3.0, 3.0]])
    v = np.array([[1.0, 0.0], [0.0, 1.0]])
    with pytest.raises(ValueError, match="2\\^30"):
        Simulation(x, v, [5.0, 5.0], diameter=1e-10)
    Simulation(x, v, [5.0, 5.0], diameter=1e-3).run(time=1.0)  # 5000 diameters: allowed


@pytest.mark.parametrize("partner", [2_000_000_000, -3, 1, 4])
def test_a_forged_wall_event_in_a_snapshot_is_refused(partner):
    # was a segfault (out-of-bounds write in the wall event) or a silently flipped position
    s = Simulation.random(50, 2, 0.3, boundary=["periodic", "wall"], seed=1)
    st = s.snapshot()
    st["ev_kind"][0] = 0  # a wall event
    st["ev_partner"][0] = partner  # axis partner // 2 (0 is periodic here), upper partner % 2
    st["ev_t"][0] = st["time"]
    with pytest.raises(ValueError, match="wall event"):
        Simulation.from_snapshot(st)
    st["ev_partner"][0] = 2  # axis 1, lower wall: a real wall, accepted
    Simulation.from_snapshot(st).run(collisions=5)


def test_unbounded_runs_are_refused_and_change_nothing():
    # were endless loops: an infinite end time, an infinite target, 2^63 collisions back
    s = Simulation.random(50, 2, 0.3, seed=1)
    s.run(collisions=20)
    before = s.snapshot()
    with pytest.raises(ValueError, match="finite"):
        s.run(time=float("inf"))
    with pytest.raises(ValueError, match="finite"):
        s.run_back(time=-float("inf"))
    after = s.snapshot()
    assert all(np.array_equal(np.asarray(before[k]), np.asarray(after[k])) for k in ("x", "v", "time"))
    r = s.run_back(collisions=2**63)  # collisions alone: never past the start
    assert s.time == s.start_time and r["collisions"] <= 20 + 5
    s.run(collisions=10)
    s.run_back(time=s.start_time - 0.5)  # a finite time before the start is still allowed
    assert s.time == s.start_time - 0.5


def test_a_start_time_the_clock_cannot_resolve_is_refused():
    # was a hang: at t0 = 1e16 the clock's ulp (2) outgrew the flight times, events shared one time
    with pytest.raises(ValueError, match="shift the time origin"):
        Simulation.random(100, 2, 0.3, boundary="wall", time=1e16)
    s = Simulation.random(100, 2, 0.3, boundary="wall", time=1e6)  # allowed (round trips degrade: docs)
    s.run(collisions=50)
    st = s.snapshot()
    st["time"] = 1e16
    with pytest.raises(ValueError, match="too large for the clock"):
        Simulation.from_snapshot(st)


@pytest.mark.parametrize("energy", [float("nan"), -1.0, float("inf")])
def test_a_bad_start_energy_is_refused(energy):
    # was silently replaced by the default (kT = 1)
    with pytest.raises(ValueError, match="kinetic energy"):
        Simulation.random(100, 2, 0.3, energy=energy)


def test_run_checks_its_arguments_before_the_first_event():
    # callback=5 ran 10 collisions before the TypeError
    s = Simulation.random(50, 2, 0.3, seed=2)
    before = s.snapshot()
    with pytest.raises(TypeError, match="callable"):
        s.run(collisions=100, callback=5, every=10)
    with pytest.raises(ValueError, match="every"):
        s.run(collisions=100, callback=lambda k: None, every=0)
    after = s.snapshot()
    assert all(np.array_equal(np.asarray(before[k]), np.asarray(after[k])) for k in ("x", "v", "time", "rng"))


# --- operators: errors move no generator; speeds outside the chart's range are refused ----


def _approaching(c, rng):
    """A pre state of named case c (a dict of revcol.named_cases()) that its operator accepts."""
    op = revcol.Collision.named(c["name"])
    for _ in range(1000):
        v = rng.normal(size=(c["n"], c["d"]))
        try:
            op.forward(v, g=np.full(op.draws, 0.5))
            return op, v
        except ValueError:
            pass
    raise AssertionError(f"no pre state found for {c['name']}")


@pytest.mark.parametrize("make", [lambda: revcol.Pair2D(), lambda: revcol.Pair2D(mode="paper")])
def test_a_reverse_batch_the_counter_cannot_serve_moves_nothing(make):
    # was: the generator stepped back one draw before the error (issue 17)
    op = make()
    v = np.array([[[-1.0, 0.2], [1.0, 0.1]]] * 3)
    n = np.array([[1.0, 0.0]] * 3)
    post = op.forward(v, n, rng=revcol.Philox())
    for counter in (0, 1, 2):
        p = revcol.Philox(counter=counter)
        with pytest.raises(ValueError, match="steps back 3 draws"):
            op.reverse(post, n, rng=p)
        assert p.counter == counter
    back = op.reverse(post, n, rng=revcol.Philox(counter=3))
    assert np.abs(back - v).max() < 1e-12


def test_a_collision_reverse_the_counter_cannot_serve_moves_nothing():
    op = revcol.Collision.named("triple2d-c1")
    _, v = _approaching(revcol.named_cases()[4], np.random.default_rng(3))
    post = op.forward(np.stack([v, v]), rng=revcol.Philox())  # 2 x 3 draws
    p = revcol.Philox(counter=5)
    with pytest.raises(ValueError, match="counter is 5 but reversing this batch steps back 6"):
        op.reverse(post, rng=p)
    assert p.counter == 5 and op.log_size == 0


@pytest.mark.parametrize("case", revcol.named_cases(), ids=lambda c: c["name"])
def test_every_named_case_works_up_to_its_speed_limits_and_refuses_beyond(case):
    # was: NaN, silently, at 1e-170 and at >= 1e150 (issue 17); the limits are 2^-480 for the
    # relative speed's largest component and 2^450 for any component (collide/common.hpp)
    op, v = _approaching(case, np.random.default_rng(7))
    g = np.full(op.draws, 0.37)

    def round_trip(u):
        back = op.reverse(op.forward(u, g=g), g=g)
        assert np.isfinite(back).all()
        return np.abs(back - u).max() / np.abs(u).max()

    base = round_trip(v)
    rel = max(np.abs(v[i] - v[j]).max() for i, j in case["contacts"])
    for scale in (2.0**-479 / rel, 2.0**449 / np.abs(v).max()):  # inside, at the edges
        assert round_trip(v * scale) <= max(4 * base, 1e-13)
    with pytest.raises(ValueError, match="relative speed too small"):
        op.forward(v * (2.0**-481 / rel), g=g)
    with pytest.raises(ValueError, match="velocities too large"):
        op.forward(v * (2.0**451 / np.abs(v).max()), g=g)


@pytest.mark.parametrize("scale", [1e-161, 1e-130, 1e136, 1.2e154])
def test_a_gas_too_slow_or_too_fast_for_the_operators_is_refused(scale):
    # was: a hang at 1e-161 and an overflow at 1.2e154 (issue 17)
    s = Simulation.random(100, 2, 0.3, seed=1)
    with pytest.raises(ValueError, match="velocity|kinetic energy overflows"):
        Simulation(s.positions, s.velocities * scale, s.box)
    Simulation(s.positions, s.velocities * 1e-120, s.box).run(collisions=50)  # inside: runs


# --- integer and real arguments are named -------------------------------------------------


@pytest.mark.parametrize("call, exc, text", [
    (lambda: revcol.Pair2D(bits=2**40), ValueError, "bits = 1099511627776 is outside"),
    (lambda: revcol.Pair2D(bits="40"), TypeError, "bits must be an integer, got str"),
    (lambda: revcol.Collision.named("pair2d", bits=-1), ValueError, "bits"),
    (lambda: revcol.Collision(2, 2.0, [(0, 1)], normals=[[1.0, 0.0]]), TypeError, "d must be an integer"),
    (lambda: Simulation.random(100, 2, "0.3"), TypeError, "phi must be a real number, got str"),
    (lambda: Simulation.random(100, 2, 0.3, seed=-1), ValueError, "seed = -1 is outside"),
    (lambda: Simulation.random(10**12, 2, 0.3), ValueError, "n = 1000000000000 is outside"),
    (lambda: Simulation([[1.0, 1.0]], [[1.0, 0.0]], ["a", "b"]), TypeError, "box must be an array of real"),
    (lambda: Simulation.random(50, 2, 0.3, diameter=None), TypeError, "diameter must be a real number"),
])
def test_bad_scalar_arguments_are_named(call, exc, text):
    with pytest.raises(exc, match=text):
        call()


@pytest.mark.parametrize("engine", ["float", "lattice"])
@pytest.mark.parametrize("kw, exc, text", [
    (dict(collisions=-1), ValueError, "collisions = -1 is outside"),
    (dict(collisions=2**64), (ValueError, OverflowError), "collisions"),
    (dict(collisions=1e6), TypeError, "collisions must be an integer, got float \\(1000000.0; write"),
    (dict(collisions=[3]), TypeError, "collisions must be an integer, got list"),
    (dict(time="soon"), TypeError, "time must be a real number, got str"),
])
def test_bad_run_arguments_are_named_and_change_nothing(engine, kw, exc, text):
    s = Simulation.random(50, 2, 0.3, seed=1, engine=engine)
    s.run(collisions=20)
    before = s.snapshot()
    with pytest.raises(exc, match=text):
        s.run(**kw)
    with pytest.raises(exc, match=text):
        s.run_back(**kw)
    after = s.snapshot()
    assert before.keys() == after.keys()
    for k in before:
        if isinstance(before[k], dict):
            assert before[k] == after[k], k
        else:
            assert np.array_equal(np.asarray(before[k]), np.asarray(after[k])), k


# --- checkpoints: stamped, checked, written atomically ------------------------------------


@pytest.mark.parametrize("engine", ["float", "lattice"])
def test_a_checkpoint_carries_its_stamp_and_is_checked(engine, tmp_path):
    s = Simulation.random(50, 2, 0.3, seed=1, engine=engine)
    s.run(collisions=30)
    path = tmp_path / "a.npz"
    s.save(path)
    with np.load(path) as z:
        assert str(z["revcol_version"]) == revcol.__version__ and str(z["revcol_engine"]) == engine
        assert str(z["revcol_build"]) == revcol._core.build
        data = {k: z[k] for k in z.files}
    cls = type(s)
    assert np.array_equal(cls.load(path).positions, s.positions)
    other = {"float": "lattice", "lattice": "float"}[engine]
    # re-digested (as save would): the stamp's own checks, behind the digest (test_checkpoint_digest.py)
    np.savez(tmp_path / "b.npz", **digested({**data, "revcol_engine": np.asarray(other)}))
    with pytest.raises(ValueError, match=f"is a {other} engine checkpoint"):
        cls.load(tmp_path / "b.npz")
    np.savez(tmp_path / "c.npz", **digested({**data, "revcol_version": np.asarray("0.0.1")}))
    with pytest.warns(RuntimeWarning, match="written by revcol 0.0.1"):
        cls.load(tmp_path / "c.npz")
    (tmp_path / "d.npz").write_bytes(b"not a zip file at all")
    with pytest.raises(ValueError, match="not a readable revcol checkpoint"):
        cls.load(tmp_path / "d.npz")
    np.save(tmp_path / "e.npy", np.zeros(3))
    with pytest.raises(ValueError, match="holds one array"):
        cls.load(tmp_path / "e.npy")


def test_a_failed_save_keeps_the_previous_checkpoint(tmp_path, monkeypatch):
    s = Simulation.random(50, 2, 0.3, seed=1)
    path = tmp_path / "ck.npz"
    s.save(path)
    good = path.read_bytes()
    s.run(collisions=10)

    def broken(f, **arrays):
        f.write(b"half a file")
        raise OSError("disk full")

    monkeypatch.setattr(np, "savez", broken)
    with pytest.raises(OSError, match="disk full"):
        s.save(path)
    assert path.read_bytes() == good
    assert [p.name for p in tmp_path.iterdir()] == ["ck.npz"]  # no temporary left behind


def test_a_snapshot_with_speeds_outside_the_range_is_refused():
    s = Simulation.random(50, 2, 0.3, seed=1)
    s.run(collisions=20)
    st = s.snapshot()
    for scale in (1e-161, 1e-130):  # (above 2^450 the clock check refuses first)
        bad = dict(st, v=np.asarray(st["v"]) * scale)
        with pytest.raises(ValueError, match="snapshot: v outside the speeds"):
            Simulation.from_snapshot(bad)
    Simulation.from_snapshot(dict(st))  # (scaling v moves the positions at the clock: an overlap)


# --- scenes: every failure exits 2 with one line, outputs checked before the run ---------

SCENE = '[system]\ndimension = 2\npacking_fraction = 0.3\nparticles = 100\n[run]\ncollisions = 10\n'


def _revcol_run(tmp_path, text, capsys, name="s.toml"):
    from revcol.cli.main import main
    path = tmp_path / name
    path.write_text(text)
    cwd = os.getcwd()
    os.chdir(tmp_path)  # a scene's [output] paths are taken under the current directory
    try:
        rc = main(["run", str(path), "--no-progress"])
    finally:
        os.chdir(cwd)
    err = capsys.readouterr().err.strip().splitlines()
    return rc, err, path


@pytest.mark.parametrize("text, field", [
    ("[system]\ndimension = 2\nparticles = 100\nbox = " + "[" * 5000 + "1" + "]" * 5000 + "\n", "nested too deeply"),
    (SCENE.replace("particles = 100", "particles = 2147483648"), "[system] particles"),
    (SCENE.replace("[system]", '[scene]\nname = "../../../x"\n[system]') + "checkpoint_interval = 5\n", "[scene] name"),
    (SCENE + '[output]\njson = "/proc/nope/r.json"\n', "[output] json"),
    (SCENE + '[output]\njson = "."\n', "is a folder, not a file"),
    (SCENE + '[output]\nplot = "s.toml"\n', "is the scene file itself"),
])
def test_a_bad_scene_exits_2_with_one_line_naming_the_field(tmp_path, capsys, text, field):
    # were: a RecursionError traceback, a MemoryError traceback (exit 1), checkpoints written
    # outside the scene's folder, an unwritable report found after the run (issue 17)
    rc, err, path = _revcol_run(tmp_path, text, capsys)
    assert rc == 2 and len(err) == 1 and field in err[0], err
    assert path.read_text() == text  # the scene file is never an output


def test_a_report_over_the_scene_file_is_refused_before_the_run(tmp_path, capsys):
    text = SCENE + '[output]\njson = "s.toml"\n'
    rc, err, path = _revcol_run(tmp_path, text, capsys)
    assert rc == 2 and "is the scene file itself" in err[0] and path.read_text() == text  # was: overwritten


def test_a_scene_too_large_for_memory_is_refused_before_allocating(tmp_path, capsys, monkeypatch):
    import revcol.gas as run_mod
    monkeypatch.setattr(run_mod, "_available_bytes", lambda: 50 * 1024)  # 50 KiB: 100 particles need 100 KiB
    rc, err, _ = _revcol_run(tmp_path, SCENE, capsys)
    assert rc == 2 and "[system] particles: 100 particles need about" in err[0], err
    monkeypatch.setattr(run_mod, "_available_bytes", lambda: 10 * 2**30)
    assert _revcol_run(tmp_path, SCENE, capsys)[0] == 0


@pytest.mark.parametrize("field, value, text", [
    ("diameter", 2.0, "snapshot: particles? .* (overlap|outside the box)"),  # was: the list build never returned
    ("ev_t", 2.0**40, "event time before the clock or beyond"),  # was: run() never returned
    ("ev_t", -2.0**40, "event time before the clock or beyond"),
    ("x", 1e6, "outside the box on axis 1 at the clock"),
])
def test_a_snapshot_the_engine_would_spin_on_is_refused(field, value, text):
    s = Simulation.random(40, 2, 0.4, boundary=["periodic", "wall"], seed=1)
    s.run(collisions=60)
    st = s.snapshot()
    bad = dict(st)
    bad[field] = np.full_like(np.asarray(st[field]), value) if np.ndim(st[field]) else value
    with pytest.raises(ValueError, match=text):
        Simulation.from_snapshot(bad)


@pytest.mark.parametrize("call, exc, text", [
    (lambda: _core.statesave_run(particles=-1), ValueError, r"particles = -1 is outside \[0, "),
    (lambda: _core.statesave_run(collisions=1.5), TypeError, "collisions must be an integer, got float"),
    (lambda: _core.statesave_run(variant=3), TypeError, "variant must be a string"),
    (lambda: _core.statesave_projected_bytes(mean_dt="x"), TypeError, "mean_dt must be a real number"),
    (lambda: _core.paper_study(case="pair3d", collisions=-5), ValueError, r"collisions = -5 is outside"),
    (lambda: _core.paper_study(case=None), TypeError, "case must be a string"),
    (lambda: _core.paper_study(case="pair3d", cos_tol="tight"), TypeError, "cos_tol must be a real number"),
])
def test_study_bindings_name_their_arguments(call, exc, text):
    """The last bindings that took plain types (issue 17): pybind's generic 'incompatible
    function arguments' no longer reaches a user of the state-saving or paper study."""
    with pytest.raises(exc, match=text):
        call()


# --- every output the CLI writes is atomic -----------------------------------------------------


def test_an_output_that_fails_half_way_keeps_the_previous_file(tmp_path):
    from revcol._io import atomic_open
    path = tmp_path / "r.json"
    path.write_text('{"old": 1}\n')
    with pytest.raises(RuntimeError, match="disk full"):
        with atomic_open(path) as f:
            f.write('{"new": ')
            raise RuntimeError("disk full")
    assert path.read_text() == '{"old": 1}\n'
    assert [p.name for p in tmp_path.iterdir()] == ["r.json"]  # no temporary left behind
    with atomic_open(path) as f:
        f.write('{"new": 2}\n')
    assert path.read_text() == '{"new": 2}\n' and [p.name for p in tmp_path.iterdir()] == ["r.json"]
    mask = os.umask(0)
    os.umask(mask)
    assert path.stat().st_mode & 0o777 == 0o666 & ~mask  # readable as open() would make it, not mkstemp's 0600
    Simulation.random(20, 2, 0.3, seed=1).save(tmp_path / "c.npz")
    assert (tmp_path / "c.npz").stat().st_mode & 0o777 == 0o666 & ~mask


def test_a_report_figure_and_csv_keep_the_previous_file_when_the_write_fails(tmp_path, monkeypatch):
    """report.write_json, the state-saving JSON and CSV and every figure go through
    _io.atomic_open (before: write_text / open(path, "w"), which leave half a file)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from revcol._io import save_figure
    from revcol._io import write_json
    from revcol.studies.statesave.output import write_csv, write_json as ss_json
    fig = plt.figure()
    writers = {"a.json": lambda p: write_json({"a": 1}, p), "b.json": lambda p: ss_json({"b": 2}, p),
               "c.csv": lambda p: write_csv({"ratios": [], "runs": []}, p), "d.png": lambda p: save_figure(fig, p)}
    for name in writers:
        (tmp_path / name).write_text("old")

    def no_rename(a, b):
        raise OSError("disk full")
    monkeypatch.setattr(os, "replace", no_rename)
    for name, write in writers.items():
        with pytest.raises(OSError, match="disk full"):
            write(tmp_path / name)
        assert (tmp_path / name).read_text() == "old", name
    monkeypatch.undo()
    plt.close(fig)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(writers)  # no temporaries left


def test_a_trajectory_appears_only_when_closed(tmp_path):
    from revcol.trajectory import open_trajectory
    path = tmp_path / "t.xyz"
    w = open_trajectory(path, [5.0, 5.0], [True, True], 1.0)
    w.write(np.zeros((2, 2)) + [[1, 1], [3, 3]], np.zeros((2, 2)), 0.0, 0, "forward")
    assert not path.exists()  # being written beside it
    w.close()
    assert path.read_text().startswith("2\n") and len(list(tmp_path.iterdir())) == 1


def test_statesave_json_dash_is_standard_output(capsys):
    from revcol.cli.main import main as cli_main
    code = cli_main(["bench", "statesave", "--n", "100", "--collisions", "1e2", "--inline", "--variants", "rc",
                     "--json", "-", "--no-progress"])
    out = capsys.readouterr()
    assert code == 0 and json.loads(out.out)["runs"] and not os.path.exists("-")
