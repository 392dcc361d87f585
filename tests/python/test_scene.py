"""Scene files: parsing, defaults, and one-line errors naming the field."""
from pathlib import Path

import numpy as np
import pytest

from revcol.scene import DEFAULT_SCENE, SceneError, load_scene, scene_from_dict


def write(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "s.toml"
    p.write_text(text)
    return p


def test_default_scene():
    s = load_scene(None)
    assert (s.dimension, s.particles, s.mode, s.law, s.generator) == (2, 1000, "exact", "flux", "clcg4")
    assert s.boundaries == ("walls", "walls") and s.packing_fraction == 0.3
    # area fraction 0.3 of 1000 unit disks: side^2 = 1000 pi / 4 / 0.3
    assert s.box[0] == pytest.approx((1000 * np.pi / 4 / 0.3) ** 0.5, rel=1e-15)
    assert "1000 particles in 2D" in s.summary()


def test_full_scene_and_relative_paths(tmp_path):
    p = write(tmp_path, """
[scene]
name = "spheres"
[system]
dimension = 3
particles = 64
diameter = 0.5
box = [4.0, 4.0, 5.0]
boundaries = ["periodic", "periodic", "walls"]
start = "lattice"
kinetic_energy = 96.0
[collisions]
mode = "exact"
law = "uniform"
bits = 36
[rng]
generator = "philox"
streams = "single"
seed = 7
[run]
time = 2.5
checkpoint_interval = 1000
[output]
json = "out/r.json"
trajectory = "t.xyz"
trajectory_every = 10
""")
    s = load_scene(p)
    assert s.name == "spheres" and s.box == (4.0, 4.0, 5.0) and s.boundaries == ("periodic", "periodic", "walls")
    assert (s.law, s.bits, s.generator, s.streams, s.seed, s.time, s.collisions) == ("uniform", 36, "philox", "single", 7, 2.5, None)
    assert s.json == tmp_path / "out/r.json" and s.trajectory == tmp_path / "t.xyz"


@pytest.mark.parametrize("text,needle", [
    ("[system]\ndimension = 2\nparticles = 10\npacking_fraction = 0.1\ncolour = 'red'\n", "[system] colour: unknown field"),
    ("[sytem]\ndimension = 2\n", "[sytem]: unknown table"),
    ("[system]\ndimension = 2\nparticles = 'ten'\npacking_fraction = 0.1\n", "[system] particles: must be an integer"),
    ("[system]\ndimension = 2\nparticles = -5\npacking_fraction = 0.1\n", "[system] particles: must be >= 1, got -5"),
    ("[system]\ndimension = 4\nparticles = 5\npacking_fraction = 0.1\n", "[system] dimension: must be 1..3"),
    ("[system]\ndimension = 2\nparticles = 5\nbox = [0.5, 3.0]\n", "[system] box: axis 0 length 0.5 is not larger than the diameter"),
    ("[system]\ndimension = 2\nparticles = 5\nbox = [3.0]\n", "[system] box: needs 2 lengths"),
    ("[system]\ndimension = 2\nparticles = 5\n", "[system] box: give box"),
    ("[system]\ndimension = 2\nparticles = 5\nbox = [3.0, 3.0]\npacking_fraction = 0.2\n", "not both"),
    ("[system]\ndimension = 3\nparticles = 5\npacking_fraction = 0.9\n", "[system] packing_fraction: must be at most 0.7"),
    ("[system]\ndimension = 2\nparticles = 5\npacking_fraction = 0.1\nboundaries = 'sticky'\n", "[system] boundaries: must be one of 'walls', 'periodic'"),
    ("[system]\ndimension = 2\nparticles = 5\npacking_fraction = 0.1\ndiameter = -1.0\n", "[system] diameter: must be > 0"),
    ("[system]\ndimension = 2\nparticles = 5\npacking_fraction = 0.1\n[collisions]\nmode = 'fast'\n", "[collisions] mode: must be one of"),
    ("[system]\ndimension = 3\nparticles = 5\npacking_fraction = 0.1\n[collisions]\nmode = 'paper'\n", "'paper' runs gases in 2D only"),
    ("[system]\ndimension = 2\nparticles = 5\npacking_fraction = 0.1\n[run]\ncollisions = 0\n", "[run] collisions: must be >= 1"),
    ("[system]\ndimension = 2\nparticles = 5\npacking_fraction = 0.1\n[run]\ncollisions = 5\ntime = 1.0\n", "[run] time: give either"),
    ("[system]\ndimension = 2\nparticles = 5\npacking_fraction = 0.1\n[rng]\nseed = 1.5\n", "[rng] seed: must be an integer"),
    ("[system]\ndimension = 2\nparticles = 5\npacking_fraction = 0.1\n[system2]\n", "[system2]: unknown table"),
    ("[system]\ndimension = 2\nparticles = true\npacking_fraction = 0.1\n", "[system] particles: must be an integer, got True"),
    ("[system\n", "not valid TOML"),
])
def test_bad_scene_one_line_error(tmp_path, text, needle):
    p = write(tmp_path, text)
    with pytest.raises(SceneError) as e:
        load_scene(p)
    msg = str(e.value)
    assert needle in msg and "\n" not in msg and msg.startswith(str(p))


def test_initial_state_file(tmp_path):
    x = np.array([[1.0, 1.0], [3.0, 1.0], [1.0, 3.0]])
    v = np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 0.5]])
    np.savez(tmp_path / "start.npz", positions=x, velocities=v)
    s = load_scene(write(tmp_path, "[system]\ndimension = 2\ninitial_state = 'start.npz'\nbox = [5.0, 5.0]\n"))
    assert s.particles == 3 and s.initial_state == tmp_path / "start.npz"
    with pytest.raises(SceneError, match=r"\[system\] particles: is 4 but initial_state holds 3"):
        load_scene(write(tmp_path, "[system]\ndimension = 2\nparticles = 4\ninitial_state = 'start.npz'\nbox = [5.0, 5.0]\n"))
    with pytest.raises(SceneError, match=r"shape \(N, 3\)"):
        load_scene(write(tmp_path, "[system]\ndimension = 3\ninitial_state = 'start.npz'\nbox = [5.0, 5.0, 5.0]\n"))
    with pytest.raises(SceneError, match="file not found"):
        load_scene(write(tmp_path, "[system]\ndimension = 2\ninitial_state = 'nope.npz'\nbox = [5.0, 5.0]\n"))


def test_missing_file_and_dict_input():
    with pytest.raises(SceneError, match="no such scene file"):
        load_scene("/nonexistent/scene.toml")
    assert scene_from_dict(DEFAULT_SCENE).particles == 1000
