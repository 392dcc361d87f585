"""No output of a run names one of its inputs, nor another of its outputs (issue 59): the scene
file, its initial state, the checkpoint a run resumes from and a sweep's files, resolved through
symlinks, are refused as outputs before anything runs (exit 2, one line naming both roles and
the path); the input keeps its bytes and nothing is written."""
import json
import os

import numpy as np
import pytest

import revcol
from conftest import run_cli as _cli
from revcol.plots import figure_names

PLAIN = "[system]\ndimension = 2\nparticles = 20\npacking_fraction = 0.2\n[collisions]\nengine = \"float\"\n" \
        "[rng]\nseed = 3\n[run]\ncollisions = 100\n"
CKPT = "checkpoint-000000000100.npz"


def _start(path):
    """An initial-state file (positions, velocities) of 20 disks; returns the scene's [system]."""
    sim = revcol.Simulation.random(20, 2, 0.2, seed=1, boundary="wall")
    np.savez(path, positions=sim.positions, velocities=sim.velocities)
    box = ", ".join(repr(float(b)) for b in sim.box)
    return f"[system]\ndimension = 2\nbox = [{box}]\ninitial_state = \"{path.name}\"\n[run]\ncollisions = 20\n"


def _tree(root):
    """Every file and folder under ``root`` (symlinks as such) with its bytes."""
    out = {}
    for folder, dirs, files in os.walk(root):
        for name in dirs + files:
            p = os.path.join(folder, name)
            out[os.path.relpath(p, root)] = (os.readlink(p) if os.path.islink(p)
                                             else None if os.path.isdir(p) else open(p, "rb").read())
    return out


def _refused(tmp_path, args, capsys, *words):
    """Runs ``args``, expects exit 2 with one line holding ``words``, and nothing changed under tmp_path."""
    before = _tree(tmp_path)
    rc, err = _cli(tmp_path, args, capsys)
    assert rc == 2 and len(err) == 1, err
    for w in words + ("refusing",):
        assert w in err[0], err
    assert _tree(tmp_path) == before  # the inputs keep their bytes, and nothing was written
    return err[0]


@pytest.fixture
def checkpointed(tmp_path, capsys):
    """plain.toml and its run's checkpoint ckd/checkpoint-000000000100.npz."""
    (tmp_path / "plain.toml").write_text(PLAIN)
    rc, err = _cli(tmp_path, ["simulate", "plain.toml", "--collisions", "100", "--checkpoint", "ckd",
                              "--checkpoint-every", "100"], capsys)
    assert rc == 0, err
    assert os.listdir(tmp_path / "ckd") == [CKPT]
    return tmp_path


def test_a_scene_json_naming_its_initial_state_is_refused(tmp_path, capsys):
    # was: the initial state replaced by the JSON report
    (tmp_path / "s.toml").write_text(_start(tmp_path / "start.npz") + '[output]\njson = "start.npz"\n')
    _refused(tmp_path, ["run", "s.toml"], capsys, "[output] json", "start.npz", "initial state file")


def _not_written(tmp_path, args, capsys):
    """Runs ``args`` (revcol simulate), expects exit 0 with the scene's [output] json named as not
    written, and every file that was there before unchanged."""
    before = _tree(tmp_path)
    rc, err = _cli(tmp_path, args, capsys)
    assert rc == 0, err
    after = _tree(tmp_path)
    assert {k: after[k] for k in before} == before
    return after


def test_simulate_never_writes_a_scene_s_json_so_it_cannot_name_an_input(tmp_path, capsys):
    # a scene's [output] is revcol run's (issue 58): simulate leaves it out, the input keeps its bytes
    (tmp_path / "s.toml").write_text(_start(tmp_path / "start.npz") + '[output]\njson = "start.npz"\n')
    _not_written(tmp_path, ["simulate", "s.toml"], capsys)


@pytest.mark.parametrize("how", ["--json", "[output] json"])
def test_the_checkpoint_a_run_resumes_from_is_never_an_output(checkpointed, capsys, how):
    # was: `revcol simulate plain.toml --resume ckd/X --json ckd/X` replaced the checkpoint by its report
    args = ["simulate", "plain.toml", "--resume", f"ckd/{CKPT}"]
    if how == "--json":
        args += ["--json", f"ckd/{CKPT}"]
        _refused(checkpointed, args, capsys, how, CKPT, "the checkpoint the run resumes from (--resume)")
    else:  # a scene's [output] is revcol run's: simulate does not write it (issue 58)
        (checkpointed / "plain.toml").write_text(PLAIN + f'[output]\njson = "ckd/{CKPT}"\n')
        _not_written(checkpointed, args, capsys)


def test_an_output_named_through_a_symlink_to_an_input_is_refused(tmp_path, capsys):
    (tmp_path / "s.toml").write_text(_start(tmp_path / "start.npz"))
    os.symlink("start.npz", tmp_path / "link.json")
    (tmp_path / "d").mkdir()
    os.symlink("..", tmp_path / "d" / "up")  # a folder reached through a symlink
    for target in ("link.json", "d/up/start.npz", "d/up/s.toml"):
        err = _refused(tmp_path, ["run", "s.toml", "--json", target], capsys, "--json", target)
        assert "the scene file itself" in err if target.endswith(".toml") else "initial state file" in err
    assert "through symlinks" in err
    assert os.path.islink(tmp_path / "link.json")


def test_two_outputs_naming_one_file_are_refused(tmp_path, capsys):
    (tmp_path / "plain.toml").write_text(PLAIN)
    _refused(tmp_path, ["run", "plain.toml", "--json", "t.xyz", "--trajectory", "t.xyz"], capsys,
             "[output] json / --json and [output] trajectory / --trajectory both write", "t.xyz")
    # a report named as a checkpoint the run writes, in its checkpoint folder (not created)
    _refused(tmp_path, ["simulate", "plain.toml", "--json", f"ck/{CKPT}", "--checkpoint", "ck",
                        "--checkpoint-every", "50"], capsys, "both write", CKPT)


def test_a_folder_output_refuses_only_the_names_it_writes(tmp_path, capsys):
    system = _start(tmp_path / "start.npz")
    (tmp_path / "ck").mkdir()
    # the run (20 collisions) writes checkpoint-10 and -20 into ck: an initial state so named is refused
    os.replace(tmp_path / "start.npz", tmp_path / "ck" / "checkpoint-000000000010.npz")
    text = system.replace('"start.npz"', '"ck/checkpoint-000000000010.npz"') + \
        "checkpoint_interval = 10\n[output]\ncheckpoints = \"ck\"\n"
    (tmp_path / "s.toml").write_text(text)
    _refused(tmp_path, ["run", "s.toml"], capsys, "[output] checkpoints", "would write",
             "checkpoint-000000000010.npz", "initial state file")
    # one it never writes (15 is no multiple of 10) is not: the run goes and leaves it whole
    os.replace(tmp_path / "ck" / "checkpoint-000000000010.npz", tmp_path / "ck" / "checkpoint-000000000015.npz")
    (tmp_path / "s.toml").write_text(text.replace("000000000010", "000000000015"))
    state = (tmp_path / "ck" / "checkpoint-000000000015.npz").read_bytes()
    rc, err = _cli(tmp_path, ["run", "s.toml"], capsys)
    assert rc == 0, err
    assert sorted(os.listdir(tmp_path / "ck")) == [f"checkpoint-{k:012d}.npz" for k in (10, 15, 20)]
    assert (tmp_path / "ck" / "checkpoint-000000000015.npz").read_bytes() == state
    # a figure folder: an input named as one of its figures is refused, the mere folder is not
    (tmp_path / "figs").mkdir()
    os.replace(tmp_path / "ck" / "checkpoint-000000000015.npz", tmp_path / "figs" / "snapshots.png")
    (tmp_path / "s.toml").write_text(system.replace('"start.npz"', '"figs/snapshots.png"'))
    _refused(tmp_path, ["run", "s.toml", "--plot", "figs"], capsys, "--plot", "snapshots.png")


def test_an_output_beside_an_input_with_another_name_is_allowed(tmp_path, capsys):
    (tmp_path / "s.toml").write_text(_start(tmp_path / "start.npz") + '[output]\njson = "report.json"\n')
    state = (tmp_path / "start.npz").read_bytes()
    rc, err = _cli(tmp_path, ["run", "s.toml"], capsys)
    assert rc == 0, err
    assert json.loads((tmp_path / "report.json").read_text())["passed"]
    assert (tmp_path / "start.npz").read_bytes() == state


def test_a_run_resumed_in_its_checkpoint_folder_never_writes_over_its_checkpoint(checkpointed, capsys):
    # resuming where the checkpoints go is allowed: the run writes the counts after the one it resumed
    state = (checkpointed / "ckd" / CKPT).read_bytes()
    more = ["simulate", "plain.toml", "--resume", f"ckd/{CKPT}", "--checkpoint", "ckd", "--checkpoint-every", "100"]
    rc, err = _cli(checkpointed, more + ["--collisions", "100"], capsys)
    assert rc == 0, err
    assert sorted(os.listdir(checkpointed / "ckd")) == [CKPT, "checkpoint-000000000200.npz"]
    # a run that does no collision (a time shorter than the next) writes no checkpoint of that count
    rc, err = _cli(checkpointed, more + ["--time", "1e-9", "--json", "r.json"], capsys)
    assert rc == 0, err
    assert json.loads((checkpointed / "r.json").read_text())["collisions"] == 0
    assert (checkpointed / "ckd" / CKPT).read_bytes() == state


def test_a_sweep_never_writes_over_its_scene(tmp_path, capsys):
    # the sweep's table is NAME.csv in --out: a scene file of that name there is refused
    (tmp_path / "small.csv").write_text(PLAIN)
    (tmp_path / "small.toml").write_text('[sweep]\nname = "small"\nscene = "small.csv"\n[vary]\nseed = [1, 2]\n')
    _refused(tmp_path, ["sweep", "small.toml", "--out", ".", "--workers", "0"], capsys,
             "the output folder (--out)", "small.csv", "the sweep's scene file")


@pytest.mark.parametrize("engine", ["float", "lattice"])
def test_the_figures_a_plot_folder_is_checked_for_are_those_written(tmp_path, capsys, engine):
    pytest.importorskip("matplotlib")
    (tmp_path / "plain.toml").write_text(PLAIN.replace('"float"', f'"{engine}"'))
    rc, err = _cli(tmp_path, ["run", "plain.toml", "--plot", "figs", "--collisions", "20"], capsys)
    assert rc == 0, err
    assert set(os.listdir(tmp_path / "figs")) == figure_names("gas" if engine == "float" else "lattice")
