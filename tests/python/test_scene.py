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


SCENES = Path(__file__).resolve().parents[2] / "scenes"


def test_default_scene_file_is_the_built_in_one():
    a, b = load_scene(None).to_dict(), load_scene(SCENES / "default.toml").to_dict()
    for k in ("source",):
        a.pop(k), b.pop(k)
    assert a == b


@pytest.mark.parametrize("path", sorted(SCENES.glob("*.toml")), ids=lambda p: p.stem)
def test_example_scenes_load(path):
    s = load_scene(path)
    assert s.name == path.stem and (s.collisions is not None or s.time is not None)
    assert "\n" not in s.summary()


def test_kinds():
    rev = scene_from_dict({"scene": {"kind": "reversal", "case": "triple1d"}, "collisions": {"mode": "paper"},
                           "rng": {"generator": "philox", "seed": 3}})
    assert (rev.kind, rev.case, rev.mode, rev.generator, rev.seed, rev.collisions) == \
        ("reversal", "triple1d", "paper", "philox", 3, 1_000_000)
    assert rev.dimension == 0 and rev.particles == 0 and "case triple1d" in rev.summary()
    ss = scene_from_dict({"scene": {"kind": "statesave"}, "statesave": {"particles": [1000, 5000], "lazy": True,
                                                                         "variants": ["rc", "ssp"]}})
    assert ss.statesave_particles == (1000, 5000) and ss.variants == ("ssp", "rc") and ss.collisions == 1000
    assert ss.lazy and ss.runner == "auto"


@pytest.mark.parametrize("doc,needle", [
    ({"scene": {"kind": "reversal", "case": "pair2d"}, "system": {"dimension": 2}},
     "[system] dimension: does not apply to kind = 'reversal' (used by: 'gas')"),
    ({"scene": {"kind": "reversal", "case": "pair2d"}, "rng": {"streams": "single"}},
     "[rng] streams: does not apply to kind = 'reversal'"),
    ({"scene": {"kind": "reversal", "case": "pair2d"}, "output": {"plot": "figs"}},
     "[output] plot: does not apply to kind = 'reversal' (used by: 'gas', 'statesave')"),
    ({"scene": {"kind": "reversal"}}, "[scene] case: is required"),
    ({"scene": {"kind": "reversal", "case": "pair9d"}}, "[scene] case: must be one of"),
    ({"scene": {"kind": "reversal", "case": "chain4-2d"}, "collisions": {"mode": "paper"}},
     "for mode = 'paper', got 'chain4-2d'"),
    ({"scene": {"kind": "gas", "case": "pair2d"}, "system": {"dimension": 2}},
     "[scene] case: does not apply to kind = 'gas' (used by: 'reversal')"),
    ({"scene": {"kind": "movie"}}, "[scene] kind: must be one of 'gas', 'reversal', 'statesave'"),
    ({"scene": {"kind": "statesave"}, "statesave": {"variants": ["ssp"]}}, "ssp needs lazy = true"),
    ({"scene": {"kind": "statesave"}, "statesave": {"lazy": 1}}, "[statesave] lazy: must be true or false"),
    ({"scene": {"kind": "statesave"}, "statesave": {"particles": [1000, 1]}}, "[statesave] particles: must be 2.."),
    ({"scene": {"kind": "statesave"}, "statesave": {"particles": []}}, "must be a non-empty list"),
    ({"scene": {"kind": "statesave"}, "collisions": {"bits": 30}}, "[collisions] bits: does not apply"),
    ({"scene": {"kind": "statesave"}, "system": {"particles": 10}}, "[system] particles: does not apply"),
    ({"system": {"dimension": 2, "particles": 5, "packing_fraction": 0.1}, "rng": {"seed": 2**32}},
     "[rng] seed: must be 0..4294967295"),
    ({"system": {"dimension": 2, "particles": 5, "box": [2.5, 9.0], "boundaries": ["periodic", "walls"]}},
     "[system] box: periodic axis 0 length 2.5 is under 3 diameters"),
    ({"system": {"dimension": 2, "particles": 1, "packing_fraction": 0.1}},
     "[run] collisions: a single particle never collides"),
    ({"system": {"dimension": 2, "particles": 5, "packing_fraction": 0.1}, "output": {"trajectory": "t.pdb"}},
     "[output] trajectory: must end in .xyz (extended XYZ) or .gsd"),
    ({"system": {"dimension": 2, "particles": 5, "packing_fraction": 0.1}, "output": {"checkpoints": "c"}},
     "[output] checkpoints: needs [run] checkpoint_interval > 0"),
    ({"system": {"dimension": 2, "particles": 5, "packing_fraction": 0.8}}, "must be at most 0.75 in 2D"),
    ({"system": {"dimension": 2, "particles": 5, "packing_fraction": 0.1}, "output": "x"}, "[output]: must be a table"),
])
def test_bad_scene_dicts(doc, needle):
    with pytest.raises(SceneError) as e:
        scene_from_dict(doc, "s.toml")
    msg = str(e.value)
    assert needle in msg and "\n" not in msg and msg.startswith("s.toml: ")


def test_initial_state_checked_by_the_engine(tmp_path):
    v = np.array([[1.0, 0.0], [-1.0, 0.0]])
    bad = {"overlap.npz": ([[1.0, 1.0], [1.5, 1.0]], "particles 0 and 1 overlap: distance 0.5"),
           "outside.npz": ([[1.0, 1.0], [4.8, 1.0]], "particle 1 is outside the box on axis 0"),
           "nan.npz": ([[1.0, 1.0], [np.nan, 1.0]], "position of particle 1 is not finite")}
    for name, (x, needle) in bad.items():
        np.savez(tmp_path / name, positions=np.array(x), velocities=v)
        with pytest.raises(SceneError) as e:
            load_scene(write(tmp_path, f"[system]\ndimension = 2\ninitial_state = '{name}'\nbox = [5.0, 5.0]\n"))
        msg = str(e.value)
        assert f"[system] initial_state: {name}: " in msg and needle in msg and "\n" not in msg, msg
    np.savez(tmp_path / "still.npz", positions=np.array([[1.0, 1.0], [3.0, 1.0]]), velocities=np.zeros((2, 2)))
    with pytest.raises(SceneError, match="zero kinetic energy"):
        load_scene(write(tmp_path, "[system]\ndimension = 2\ninitial_state = 'still.npz'\nbox = [5.0, 5.0]\n"))
    np.savez(tmp_path / "ok.npz", positions=np.array([[1.0, 1.0], [3.0, 1.0]]), velocities=v)
    with pytest.raises(SceneError, match=r"\[system\] kinetic_energy: applies to random starts only"):
        load_scene(write(tmp_path, "[system]\ndimension = 2\ninitial_state = 'ok.npz'\nbox = [5.0, 5.0]\n"
                                   "kinetic_energy = 3.0\n"))


def test_random_start_in_an_explicit_box():
    s = scene_from_dict({"system": {"dimension": 2, "particles": 20, "box": [30.0, 6.0], "start": "random"}},
                        "s.toml")
    assert s.start == "random" and s.packing_fraction is None
