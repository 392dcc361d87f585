"""The commands the README and docs/run.md show, run as written (issue 58), on reduced sizes: a
run's collisions capped at 2000 (its frame and checkpoint intervals scaled alike, a resumed
checkpoint's name too), a time at 0.2, a horizon at 2 seeds and 2000 collisions. Each runs in a
child process (``python -m revcol``) in one folder, in the docs' order: exit 0, and at most
20 MB written by any one. Sweeps are left to test_sweep.py (their points are the sweep file's)."""
from __future__ import annotations

import json
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
CAP = 2000


def documented(path: str) -> list[list[str]]:
    """The ``revcol ...`` commands of a markdown file: its ```sh blocks and 4-space indented lines,
    continuations joined, comments dropped, output lines (``revcol run: error: ...``) skipped."""
    text = (ROOT / path).read_text()
    lines = [ln for block in re.findall(r"```sh\n(.*?)```", text, re.S) for ln in block.splitlines()]
    lines += [ln[4:] for ln in text.splitlines() if ln.startswith("    revcol ")]
    out, buf = [], ""
    for ln in lines:
        ln = ln.split("  #")[0].rstrip()
        if ln.endswith("\\"):
            buf += ln[:-1] + " "
            continue
        words = shlex.split(buf + ln)
        buf = ""
        if words[:1] == ["revcol"] and len(words) > 1 and not words[1].endswith(":"):
            out.append(words)
    return out


def _get(words, flag):
    return words[words.index(flag) + 1] if flag in words else None


def _set(words, flag, value):
    if flag in words:
        words[words.index(flag) + 1] = str(value)
    else:
        words += [flag, str(value)]


def reduced(words: list[str]) -> list[str]:
    """The same command at a size for CI."""
    w = list(words[1:])
    if w[0] in ("run", "simulate") and "--horizon" not in w:
        asked = _get(w, "--collisions")
        if _get(w, "--time") is not None:
            _set(w, "--time", min(float(_get(w, "--time")), 0.2))
        else:
            factor = min(1.0, CAP / float(asked)) if asked else 1.0
            _set(w, "--collisions", min(int(float(asked)) if asked else CAP, CAP))
            for flag in ("--every", "--checkpoint-every"):
                if _get(w, flag) is not None:
                    _set(w, flag, max(1, int(float(_get(w, flag)) * factor)))
            resume = _get(w, "--resume")
            if resume is not None:  # the checkpoint the command before wrote at the same fraction of its run
                k = int(re.search(r"(\d+)\.npz$", resume).group(1))
                _set(w, "--resume", re.sub(r"\d+\.npz$", f"{round(k * CAP / 1e7):012d}.npz", resume))
    if "--horizon" in w:
        _set(w, "--seeds", min(int(_get(w, "--seeds") or 1), 2))
        _set(w, "--max-collisions", min(int(_get(w, "--max-collisions") or CAP), CAP))
    return w + ["--no-progress"]


COMMANDS = [c for p in ("README.md", "docs/run.md") for c in documented(p) if c[1] != "sweep"]


def test_the_docs_show_the_commands_this_test_runs():
    names = [" ".join(c[1:3]) for c in COMMANDS]
    assert len(COMMANDS) >= 15 and "run --horizon" in names and "simulate spheres-3d" in names


def _bytes(folder: Path) -> int:
    return sum(p.stat().st_size for p in folder.rglob("*") if p.is_file())


def test_every_documented_command_runs(tmp_path):
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
    for words in COMMANDS:
        args = reduced(words)
        before = _bytes(tmp_path)
        r = subprocess.run([sys.executable, "-m", "revcol", *args], cwd=tmp_path, capture_output=True, text=True,
                           env=env, timeout=300)
        assert r.returncode == 0, (args, r.stderr[-2000:])
        assert _bytes(tmp_path) - before < 20 << 20, args
        if _get(args, "--json") == "-":
            assert json.loads(r.stdout)["kind"] == "simulate", args
    assert (tmp_path / "figs").is_dir() and (tmp_path / "report.json").is_file() and (tmp_path / "gas.gsd").is_file()


@pytest.mark.parametrize("words, want", [
    (["revcol", "simulate", "s", "--collisions", "1e7", "--every", "100000", "--checkpoint-every", "1000000"],
     ["simulate", "s", "--collisions", "2000", "--every", "20", "--checkpoint-every", "200", "--no-progress"]),
    (["revcol", "simulate", "s", "--resume", "ck/checkpoint-000005000000.npz", "--collisions", "5e6"],
     ["simulate", "s", "--resume", "ck/checkpoint-000000001000.npz", "--collisions", "2000", "--no-progress"]),
    (["revcol", "run", "--horizon", "--seeds", "200"],
     ["run", "--horizon", "--seeds", "2", "--max-collisions", "2000", "--no-progress"]),
])
def test_the_reduction(words, want):
    assert reduced(words) == want


def test_the_quickstart_runs_and_prints_what_it_shows(tmp_path, monkeypatch, capsys):
    # docs/quickstart.md: its python blocks in order in one namespace; what they print must be the
    # indented output blocks of the page, line for line (the lattice engine's bits are the same on
    # every build, and so are the observables' sums)
    text = (ROOT / "docs" / "quickstart.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    shown = [ln[4:] for part in re.split(r"```python\n.*?```", text, flags=re.S)[1:]
             for ln in part.strip("\n").split("\n\n")[0].splitlines() if ln.startswith("    ")]
    monkeypatch.chdir(tmp_path)
    ns: dict = {}
    for b in blocks:
        exec(compile(b, "docs/quickstart.md", "exec"), ns)
    assert capsys.readouterr().out.splitlines() == shown
    assert len(shown) == 11 and (tmp_path / "gas.npz").is_file()
