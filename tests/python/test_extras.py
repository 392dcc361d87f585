"""A missing optional package (issue 58): the command line says in one line which extra installs it
(``pip install 'revcol[EXTRA]'``) and exits 2, whichever command reaches it; no traceback. Each
package is hidden from the import system for the test (``sys.modules[name] = None``)."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest

from revcol._extras import EXTRAS, missing_extra
from revcol.cli.main import main as cli_main

ROOT = Path(__file__).resolve().parents[2]


def _hide(monkeypatch, name: str) -> None:
    for m in [m for m in sys.modules if m == name or m.startswith(name + ".")]:
        monkeypatch.delitem(sys.modules, m)
    monkeypatch.setitem(sys.modules, name, None)


def _one_line_naming(err: str, extra: str, command: str) -> bool:
    return (err.count("\n") == 1 and err.startswith(f"revcol {command}: error:") and f"revcol[{extra}]" in err
            and "Traceback" not in err)


def test_every_optional_package_names_an_extra_of_pyproject():
    import tomllib
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    for module, extra in EXTRAS.items():
        assert extra in extras, extra
        assert any(req.replace("[", " ").split()[0].startswith(module) or module in req for req in extras[extra]), module


def test_an_import_error_of_anything_else_is_not_taken_for_a_missing_extra():
    assert missing_extra(ModuleNotFoundError("no", name="numpyy")) is None
    assert missing_extra(ValueError("matplotlib")) is None
    assert "revcol[plot]" in missing_extra(ModuleNotFoundError("no", name="matplotlib.pyplot"))


def test_sweep_without_dask(tmp_path, monkeypatch, capsys):
    _hide(monkeypatch, "distributed")
    rc = cli_main(["sweep", str(ROOT / "sweeps" / "default-horizon.toml"), "--out", str(tmp_path / "o"),
                   "--workers", "1", "--no-progress"])
    err = capsys.readouterr().err.splitlines()[-1] + "\n"
    assert rc == 2 and _one_line_naming(err, "sweep", "sweep"), err


def test_plot_without_matplotlib(tmp_path, monkeypatch, capsys):
    _hide(monkeypatch, "matplotlib")
    rc = cli_main(["run", str(ROOT / "scenes" / "default.toml"), "--plot", str(tmp_path / "p"), "--collisions", "100",
                   "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2 and "revcol[plot]" in err and "Traceback" not in err, err
    assert not (tmp_path / "p").exists()  # refused before anything ran


def test_gsd_trajectory_without_gsd(tmp_path, monkeypatch, capsys):
    _hide(monkeypatch, "gsd")
    rc = cli_main(["simulate", str(ROOT / "scenes" / "default.toml"), "--collisions", "100", "--trajectory",
                   str(tmp_path / "t.gsd"), "--every", "10", "--json", str(tmp_path / "r.json"), "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2 and "revcol[gsd]" in err and "Traceback" not in err, err
    assert not (tmp_path / "t.gsd").exists()


@pytest.mark.parametrize("argv", [["study", "randomness", "controls", "--words", "1000"],
                                  ["study", "stability", "--json", "-"]])
def test_a_study_without_scipy(argv, monkeypatch, capsys):
    _hide(monkeypatch, "scipy")
    rc = cli_main(argv)
    err = capsys.readouterr().err.splitlines()
    assert rc == 2 and err and _one_line_naming(err[-1] + "\n", "studies", " ".join(argv[:2])), err[-3:]
