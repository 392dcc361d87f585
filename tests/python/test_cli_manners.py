"""CLI manners (issue 19): --version, typo suggestions for subcommands, choices and options,
``--json -`` on standard output, and a quiet exit when standard output is a closed pipe."""
import json
import os
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

import revcol
from revcol.cli.main import main

ROOT = Path(__file__).resolve().parents[2]
SMALL = "[system]\ndimension = 2\nparticles = 40\npacking_fraction = 0.2\n[run]\ncollisions = 40\n"


def _revcol(*args, stdout=subprocess.PIPE, **kw):
    """`python -m revcol ARGS` in a child with this process's import path (the staged build)."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
    return subprocess.run([sys.executable, "-m", "revcol", *args], stdout=stdout, stderr=subprocess.PIPE,
                          text=True, env=env, timeout=120, **kw)


def test_version_is_the_package_version(capsys):
    with pytest.raises(SystemExit) as e:
        main(["--version"])
    assert e.value.code == 0
    out = capsys.readouterr().out.strip()
    assert out == f"revcol {revcol.__version__}"
    # the one version: the package metadata's
    assert revcol.__version__ == tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]


@pytest.mark.parametrize("argv, usage, hint", [
    (["rn"], "usage: revcol [", "did you mean 'run'?"),
    (["verfy", "pair2d"], "usage: revcol [", "did you mean 'verify'?"),
    (["run", "--colisions", "10"], "usage: revcol run ", "did you mean '--collisions'?"),
    (["run", "--seeed=3"], "usage: revcol run ", "did you mean '--seed'?"),
    (["run", "--engine", "flaot"], "usage: revcol run ", "did you mean 'float'?"),
    (["verify", "pair2", "--collisions", "10"], "usage: revcol verify ", "did you mean 'pair2d'?"),
    (["bench", "statesave", "--colisions", "3"], "usage: revcol bench statesave ", "did you mean '--collisions'?"),
])
def test_typos_get_a_suggestion_and_the_subcommands_usage(argv, usage, hint, capsys):
    with pytest.raises(SystemExit) as e:
        main(argv)
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith(usage), err
    assert hint in err.splitlines()[-1]


def test_no_suggestion_for_a_word_like_nothing(capsys):
    with pytest.raises(SystemExit):
        main(["run", "--zzzzqqq"])
    err = capsys.readouterr().err
    assert "unrecognized arguments: --zzzzqqq" in err and "did you mean" not in err


def test_json_dash_writes_the_report_to_stdout(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "small.toml").write_text(SMALL + "[output]\njson = 'scene.json'\n")
    assert main(["run", "small.toml", "--json", "-", "--no-progress"]) == 0
    cap = capsys.readouterr()
    report = json.loads(cap.out)  # standard output is the JSON and nothing else
    assert report["kind"] == "gas" and report["passed"] is True
    assert report["scene"]["name"] == "small"
    assert "PASSED" in cap.err  # the text report went to standard error
    assert sorted(p.name for p in tmp_path.iterdir()) == ["small.toml"]  # no file '-', nor the scene's json


def test_json_to_a_file_still_prints_the_text(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "small.toml").write_text(SMALL)
    assert main(["run", "small.toml", "--json", "r.json", "--no-progress"]) == 0
    assert "PASSED" in capsys.readouterr().out
    assert json.loads((tmp_path / "r.json").read_text())["passed"] is True


@pytest.mark.parametrize("args, status", [
    (["--version"], 0), (["--help"], 0),  # argparse's own printing swallows EPIPE and exits 0
    (["verify", "pair2d", "--collisions", "100"], 141),
    (["verify", "pair2d", "--collisions", "100", "--json", "-"], 141),
])
def test_closed_pipe_exits_quietly(args, status):
    # the reader is gone before anything is written: every write meets EPIPE
    r, w = os.pipe()
    os.close(r)
    try:
        p = _revcol(*args, stdout=w)
    finally:
        os.close(w)
    assert p.returncode == status, p.stderr
    assert p.stderr == ""  # no traceback, no "Exception ignored"


def test_piped_into_head(tmp_path):
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
    cmd = f"set -o pipefail; {sys.executable} -m revcol verify pair2d --collisions 100 | head -1"
    p = subprocess.run(["bash", "-c", cmd], capture_output=True, text=True, env=env, timeout=120)
    assert re.match(r"revcol verify pair2d ", p.stdout) and p.stdout.count("\n") == 1
    assert "Traceback" not in p.stderr and "BrokenPipe" not in p.stderr
    assert p.returncode in (0, 141)  # 141 when head left before the report was written


# --- issue 58: help texts and summary lines that say what runs ---------------------------------

@pytest.mark.parametrize("study", ["randomness", "equilibrium", "stability"])
def test_a_study_s_help_names_the_command_it_was_given(study, capsys):
    with pytest.raises(SystemExit) as e:
        main(["study", study, "--help"])
    assert e.value.code == 0
    assert capsys.readouterr().out.startswith(f"usage: revcol study {study} ")


def test_verify_help_says_what_it_does_and_its_exit_codes(capsys):
    with pytest.raises(SystemExit):
        main(["verify", "--help"])
    out = " ".join(capsys.readouterr().out.split())
    assert "reversal illustrations" in out and "Exit 0 when it passes, 1 when it fails, 2 on a bad option" in out


@pytest.mark.parametrize("length, said", [(["--collisions", "2e3"], "2,000 collisions"),
                                          (["--time", "0.25"], "a time of 0.25")])
def test_simulate_s_summary_gives_the_length_it_runs(length, said, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "s.toml").write_text(SMALL)  # its own [run] length is 40 collisions
    assert main(["simulate", "s.toml", *length, "--no-progress"]) == 0
    scene_line = next(line for line in capsys.readouterr().out.splitlines() if line.lstrip().startswith("scene"))
    assert scene_line.endswith(said) and "40 collisions" not in scene_line


def test_a_horizon_s_summary_gives_its_round_trips(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "s.toml").write_text(SMALL.replace("collisions = 40", "collisions = 1000000"))
    assert main(["run", "s.toml", "--horizon", "--engine", "lattice", "--no-progress"]) == 0
    scene_line = next(line for line in capsys.readouterr().out.splitlines() if line.lstrip().startswith("scene"))
    assert "round trips of up to" in scene_line and "1,000,000" not in scene_line
