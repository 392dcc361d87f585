"""Scenes and sweeps as the docs write them (issue 58): ``scenes/NAME.toml`` and
``sweeps/NAME.toml`` name the shipped file in any directory, as they do in a clone; a file at that
path, where there is one, comes first; a near miss is refused with a suggestion."""
from __future__ import annotations

from pathlib import Path

import pytest

from revcol.scene import SceneError, find_scene, load_scene
from revcol.sweep import SweepError
from revcol.sweep.spec import load_sweep


def test_the_docs_paths_resolve_outside_a_clone(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    s = load_scene("scenes/spheres-3d.toml")
    assert Path(s.source) == find_scene("spheres-3d")
    w = load_sweep("sweeps/default-horizon.toml")
    assert Path(w.source).name == "default-horizon.toml" and Path(w.source).is_absolute()
    assert load_sweep("default-horizon").source == w.source


def test_a_file_at_that_path_comes_first(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "scenes").mkdir()
    shipped = Path(find_scene("default")).read_text()
    (tmp_path / "scenes" / "default.toml").write_text(shipped.replace("seed = ", "seed = 1", 1)
                                                       if "seed = " in shipped else shipped)
    assert load_scene("scenes/default.toml").source == "scenes/default.toml"


def test_a_near_miss_is_refused_with_a_suggestion(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SceneError, match="did you mean 'spheres-3d'"):
        load_scene("scenes/spheres-3.toml")
    with pytest.raises(SweepError, match="did you mean 'default-horizon'"):
        load_sweep("sweeps/default-horizn.toml")
    with pytest.raises(SceneError, match="no such scene file"):
        load_scene("elsewhere/spheres-3d.toml")  # only the docs' own folder names the shipped file
