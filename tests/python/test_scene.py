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
    assert (s.dimension, s.particles, s.mode, s.law, s.generator) == (2, 1000, "exact", "flux", "philox")
    assert s.engine == "lattice" and s.collisions == 10**6
    assert s.boundaries == ("wall", "wall") and s.packing_fraction == 0.3 and s.streams == "per_particle"
    # area fraction 0.3 of 1000 unit disks: side^2 = 1000 pi / 4 / 0.3
    assert s.box[0] == pytest.approx((1000 * np.pi / 4 / 0.3) ** 0.5, rel=1e-15)
    assert "1000 particles in 2D" in s.summary()


def test_full_scene_and_relative_paths(tmp_path, monkeypatch):
    p = write(tmp_path, """
[scene]
name = "spheres"
[system]
dimension = 3
particles = 64
diameter = 0.5
box = [4.0, 4.0, 5.0]
boundaries = ["periodic", "periodic", "wall"]
start = "crystal"
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
    assert s.name == "spheres" and s.box == (4.0, 4.0, 5.0) and s.boundaries == ("periodic", "periodic", "wall")
    assert (s.law, s.bits, s.generator, s.streams, s.seed, s.time, s.collisions) == ("uniform", 36, "philox", "single", 7, 2.5, None)
    # [output] paths under the current directory, wherever the scene file is
    assert s.json == Path.cwd() / "out/r.json" and s.trajectory == Path.cwd() / "t.xyz"
    monkeypatch.chdir(tmp_path)
    s = load_scene(p)
    assert s.json == tmp_path / "out/r.json" and s.trajectory == tmp_path / "t.xyz"


@pytest.mark.parametrize("text,needle", [
    ("[system]\ndimension = 2\nparticles = 10\npacking_fraction = 0.1\ncolour = 'red'\n", "[system] colour: unknown field"),
    ("[sytem]\ndimension = 2\n", "[sytem]: unknown table"),
    ("[system]\ndimension = 2\nparticles = 'ten'\npacking_fraction = 0.1\n", "[system] particles: must be an integer"),
    ("[system]\ndimension = 2\nparticles = -5\npacking_fraction = 0.1\n", "[system] particles: must be 1..2147483647, got -5"),
    ("[system]\ndimension = 4\nparticles = 5\npacking_fraction = 0.1\n", "[system] dimension: must be 1..3"),
    # the float engine's neighbour-list entries pack an id and its image code in 32 bits
    ("[system]\ndimension = 3\nparticles = 67108865\npacking_fraction = 0.1\n",
     "[system] particles: must be at most 67,108,864 in 3D for the float engine"),
    ("[system]\ndimension = 2\nparticles = 268435457\npacking_fraction = 0.1\n",
     "[system] particles: must be at most 268,435,456 in 2D"),
    ("[system]\ndimension = 1\nparticles = 1073741825\npacking_fraction = 0.1\n",
     "[system] particles: must be at most 1,073,741,824 in 1D"),
    ("[system]\ndimension = 2\nparticles = 5\nbox = [0.5, 3.0]\n", "[system] box: axis 0 length 0.5 is not larger than the diameter"),
    ("[system]\ndimension = 2\nparticles = 5\nbox = [3.0]\n", "[system] box: needs 2 lengths"),
    ("[system]\ndimension = 2\nparticles = 5\n", "[system] box: give box"),
    ("[system]\ndimension = 2\nparticles = 5\nbox = [3.0, 3.0]\npacking_fraction = 0.2\n", "not both"),
    ("[system]\ndimension = 3\nparticles = 5\npacking_fraction = 0.9\n", "[system] packing_fraction: must be at most 0.7"),
    ("[system]\ndimension = 2\nparticles = 5\npacking_fraction = 0.1\nboundaries = 'sticky'\n", "[system] boundaries: must be one of 'wall', 'periodic'"),
    ("[system]\ndimension = 2\nparticles = 5\npacking_fraction = 0.1\ndiameter = -1.0\n", "[system] diameter: must be > 0"),
    ("[system]\ndimension = 2\nparticles = 5\npacking_fraction = 0.1\n[collisions]\nmode = 'fast'\n", "[collisions] mode: must be one of"),
    ("[system]\ndimension = 3\nparticles = 5\npacking_fraction = 0.1\n[collisions]\nmode = 'paper'\n", "'paper' runs gases in 1D and 2D only (it has no invertible 3D pair operator)"),
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
    ({"system": {"dimension": 2, "particles": 5, "box": [2.5, 9.0], "boundaries": ["periodic", "wall"]}},
     "[system] box: periodic axis 0 length 2.5 is under 3 diameters"),
    ({"system": {"dimension": 2, "particles": 5, "packing_fraction": 0.1}, "rng": {"streams": "per_draw"}},
     "[rng] streams: must be one of 'per_particle', 'single', got 'per_draw'"),
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


def test_deprecated_spellings_warn_and_mean_the_same(tmp_path):
    new = load_scene(write(tmp_path, "[system]\ndimension = 2\nparticles = 5\npacking_fraction = 0.1\n"
                                     "boundaries = ['wall', 'periodic']\nstart = 'crystal'\n"
                                     "[rng]\nstreams = 'per_particle'\n"))
    p = tmp_path / "old.toml"
    p.write_text("[system]\ndimension = 2\nparticles = 5\npacking_fraction = 0.1\n"
                 "boundaries = ['walls', 'periodic']\nstart = 'lattice'\n[rng]\nstreams = 'per-particle'\n")
    with pytest.warns(DeprecationWarning) as got:
        old = load_scene(p)
    said = [str(w.message) for w in got]
    assert f"{p}: [system] boundaries: 'walls' is deprecated, write 'wall'" in said
    assert f"{p}: [rng] streams: 'per-particle' is deprecated, write 'per_particle'" in said
    assert f"{p}: [system] start: 'lattice' is deprecated, write 'crystal'" in said
    assert old.boundaries == new.boundaries == ("wall", "periodic") and old.streams == new.streams == "per_particle"
    assert old.start == new.start == "crystal"
    assert old.summary().replace("old", "s") == new.summary()


def test_no_warning_for_the_current_spellings(tmp_path, recwarn):
    load_scene(write(tmp_path, "[system]\ndimension = 1\nparticles = 5\npacking_fraction = 0.1\n"
                               "boundaries = 'wall'\n[rng]\nstreams = 'single'\n"))
    assert not [w for w in recwarn if issubclass(w.category, DeprecationWarning)]


def test_limits_are_the_engines(monkeypatch):
    """The scene reads its limits from C++ (revcol/engine/limits.hpp), not its own copy."""
    import revcol.scene as sc
    from revcol import _core

    lim = _core.engine_limits()
    assert lim["max_fraction"] == {1: 0.95, 2: 0.75, 3: 0.7} and lim["min_periodic_cells"] == 3
    assert tuple(lim["paper_mode_dimensions"]) == (1, 2) and tuple(lim["boundaries"]) == ("wall", "periodic", "bounce")
    assert tuple(lim["streams"]) == ("per_particle", "single") and tuple(lim["bits"]) == (8, 52)
    assert _core.engine_particle_volume(2, 2.0) == pytest.approx(np.pi)
    # a scene follows whatever the engine says
    monkeypatch.setitem(sc.LIMITS, "max_fraction", {1: 0.5, 2: 0.5, 3: 0.5})
    with pytest.raises(SceneError, match=r"must be at most 0.5 in 2D, got 0.6"):
        scene_from_dict({"system": {"dimension": 2, "particles": 5, "packing_fraction": 0.6}}, "s.toml")
    monkeypatch.setitem(sc.LIMITS, "min_periodic_cells", 4)
    with pytest.raises(SceneError, match="periodic axis 0 length 3.5 is under 4 diameters"):
        scene_from_dict({"system": {"dimension": 2, "particles": 2, "box": [3.5, 9.0], "boundaries": "periodic"}},
                        "s.toml")


def test_paper_mode_gases_in_1d_and_2d_as_the_engine(tmp_path):
    from revcol.studies.scenes import run_scene

    for d in (1, 2):
        s = scene_from_dict({"system": {"dimension": d, "particles": 40, "packing_fraction": 0.2},
                             "collisions": {"mode": "paper"}, "run": {"collisions": 40}}, "p.toml")
        r = run_scene(s, progress=False)
        assert r["passed"] and r["scene"]["mode"] == "paper" and r["dimension"] == d


def test_random_start_in_an_explicit_box():
    s = scene_from_dict({"system": {"dimension": 2, "particles": 20, "box": [30.0, 6.0], "start": "random"}},
                        "s.toml")
    assert s.start == "random" and s.packing_fraction is None


def test_engine_field_and_the_lattice_defaults():
    gas = {"system": {"dimension": 2, "particles": 50, "packing_fraction": 0.2}}
    f = scene_from_dict(gas)
    assert (f.engine, f.generator, f.collisions) == ("float", "clcg4", 50)  # 2 collisions per particle
    lat = scene_from_dict({**gas, "collisions": {"engine": "lattice", "law": "uniform"}})
    assert (lat.engine, lat.generator, lat.streams, lat.law, lat.collisions) == \
        ("lattice", "philox", "per_particle", "uniform", 10**6)
    assert "lattice engine, exact/uniform" in lat.summary() and lat.to_dict()["engine"] == "lattice"
    with pytest.raises(SceneError, match=r"\[collisions\] engine: does not apply to kind = 'statesave'"):
        scene_from_dict({"scene": {"kind": "statesave"}, "collisions": {"engine": "lattice"}})


def test_a_kinetic_energy_out_of_the_engines_speed_range_is_named(tmp_path):
    # issue 59: reported under [system] packing_fraction
    from revcol.gas import build_simulation
    scene = load_scene(write(tmp_path, "[system]\ndimension = 2\nparticles = 20\npacking_fraction = 0.2\n"
                                       "kinetic_energy = 1e-320\n"))
    with pytest.raises(SceneError, match=r"\[system\] kinetic_energy: largest velocity component"):
        build_simulation(scene)
