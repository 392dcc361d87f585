"""Packaging (issue 19): the licence in the repository and in the package metadata.

The metadata is built with scikit-build-core's own PEP 517 hook
``prepare_metadata_for_build_wheel`` into a temporary directory; it reads pyproject.toml only
(no CMake run, nothing written into the source tree)."""
import email
import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _tracked_state() -> str:
    """git status of the source tree, ignored files included (what a build may leave behind)."""
    return subprocess.run(["git", "status", "--porcelain", "--ignored", "--untracked-files=all", "--", "."],
                          cwd=ROOT, capture_output=True, text=True, check=True).stdout


@pytest.fixture(scope="module")
def metadata(tmp_path_factory):
    from scikit_build_core.build import prepare_metadata_for_build_wheel

    out = tmp_path_factory.mktemp("meta")
    before = _tracked_state()
    cwd = os.getcwd()
    os.chdir(ROOT)  # a PEP 517 hook runs in the project directory
    try:
        name = prepare_metadata_for_build_wheel(str(out))
    finally:
        os.chdir(cwd)
    assert _tracked_state() == before, "preparing the metadata changed the source tree"
    return out / name


def test_licence_file_is_the_gpl3_text():
    text = (ROOT / "LICENSE").read_text()
    assert text.split()[:6] == ["GNU", "GENERAL", "PUBLIC", "LICENSE", "Version", "3,"]
    # the whole licence, not a stub: its last section and its closing paragraph are there
    assert "How to Apply These Terms to Your New Programs" in text
    assert text.rstrip().endswith("<https://www.gnu.org/licenses/why-not-lgpl.html>.")


def test_metadata_names_the_licence_and_carries_the_file(metadata):
    msg = email.message_from_string((metadata / "METADATA").read_text())
    assert msg["Metadata-Version"] in ("2.4", "2.5", "2.6")
    assert msg["License-Expression"] == "GPL-3.0-or-later"
    assert msg.get_all("License-File") == ["LICENSE"]
    assert (metadata / "licenses" / "LICENSE").read_bytes() == (ROOT / "LICENSE").read_bytes()


def _pyproject() -> dict:
    import tomllib

    return tomllib.loads((ROOT / "pyproject.toml").read_text())


def test_pip_builds_out_of_tree_and_ships_the_scenes():
    # statically (a wheel build is a full C++ build, several minutes here; docs/run.md says how
    # it was checked once): scikit-build-core's settings as it reads them
    from scikit_build_core.settings.skbuild_read_settings import SettingsReader

    cwd = os.getcwd()
    os.chdir(ROOT)
    try:
        settings = SettingsReader.from_file("pyproject.toml").settings
    finally:
        os.chdir(cwd)
    # no persistent build-dir: a fresh temporary directory per build, never the tree's build/
    assert settings.build_dir == ""
    assert settings.wheel.packages == {"revcol": "python/revcol", "revcol/scenes": "scenes",
                                       "revcol/sweeps": "sweeps"}
    scenes = sorted(p.name for p in (ROOT / "scenes").glob("*.toml"))
    assert "default.toml" in scenes and "spheres-3d.toml" in scenes


@pytest.mark.parametrize("package, names", [
    ("Eigen3", ["apt install libeigen3-dev", "conda install -c conda-forge eigen", "CMAKE_PREFIX_PATH"]),
    ("GSL", ["apt install libgsl-dev", "conda install -c conda-forge gsl", "CMAKE_PREFIX_PATH"]),
])
def test_a_missing_library_names_the_packages_to_install(tmp_path, package, names):
    p = subprocess.run(["cmake", "-S", str(ROOT), "-B", str(tmp_path / "b"), f"-DCMAKE_DISABLE_FIND_PACKAGE_{package}=TRUE",
                        "-DREVCOL_BUILD_PYTHON=OFF", "-DREVCOL_BUILD_BENCH=OFF"],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode != 0
    err = " ".join(p.stderr.split())  # CMake wraps its messages
    for name in names:
        assert name in err, (name, err)
    assert "Could not find a package configuration file" not in err


def test_scenes_are_found_by_name(tmp_path, monkeypatch):
    from revcol.scene import SceneError, find_scene, load_scene, scene_names

    monkeypatch.chdir(tmp_path)
    names = scene_names()
    assert {"default", "spheres-3d", "periodic-2d", "rods-1d"} <= set(names)
    for name in ("spheres-3d", "spheres-3d.toml"):
        s = load_scene(name)
        assert s.name == "spheres-3d" and s.dimension == 3 and s.particles == 1000
        assert Path(s.source) == find_scene("spheres-3d")
        assert Path(s.source).read_bytes() == (ROOT / "scenes" / "spheres-3d.toml").read_bytes()
    # outputs land under the current directory, never in the package
    s = load_scene("periodic-2d")
    assert s.json == tmp_path / "out" / "periodic-2d" / "report.json"
    assert s.checkpoints == tmp_path / "out" / "periodic-2d" / "checkpoints"
    # an initial state is still read beside the scene file
    assert load_scene("initial-state").particles > 0
    # a file of that name wins over the shipped scene
    (tmp_path / "spheres-3d.toml").write_text("[system]\ndimension = 1\nparticles = 10\npacking_fraction = 0.3\n")
    assert load_scene("spheres-3d.toml").dimension == 1
    assert load_scene("spheres-3d").dimension == 3  # no file called 'spheres-3d': the name
    with pytest.raises(SceneError, match=r"no such scene file, nor a scene name .*did you mean 'spheres-3d'"):
        load_scene("sphere-3d")
    assert find_scene("../scenes/default") is None  # names only, no paths
    # a scene file given by path writes under the current directory too, not beside the file
    other = tmp_path / "elsewhere"
    other.mkdir()
    s = load_scene(ROOT / "scenes" / "periodic-2d.toml")
    assert s.json == tmp_path / "out" / "periodic-2d" / "report.json"
    monkeypatch.chdir(other)
    assert load_scene(ROOT / "scenes" / "periodic-2d.toml").plot == other / "out" / "periodic-2d" / "figures"
    assert load_scene(ROOT / "scenes" / "initial-state.toml").particles > 0  # its .npz read beside it


def test_revcol_run_by_name(tmp_path, monkeypatch, capsys):
    from revcol.cli.main import main

    monkeypatch.chdir(tmp_path)
    assert main(["run", "rods-1d", "--collisions", "200", "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("revcol run rods-1d") and "PASSED" in out
    assert list(tmp_path.iterdir()) == []  # this scene asks for no outputs
