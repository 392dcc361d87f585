"""A uniform field in scene files (``[system] gravity``): the key parsed and checked (one-line
errors naming it, or the option a field refuses), passed to both engines wherever a scene
builds one (a random start, an explicit box, an initial-state file, a mixture), used (the gas
falls, the energy with its potential is kept), reversed (the lattice bit for bit), and shown by
``revcol run`` and ``revcol simulate``. The engines' own field tests: test_float_gravity.py,
test_lattice_gravity.py."""
import copy
import json
from pathlib import Path

import numpy as np
import pytest

from revcol.cli.main import main as cli_main
from revcol.cli.simulate import simulate
from revcol.gas import build_simulation
from revcol.scene import SceneError, load_scene, scene_from_dict, with_engine, with_lattice_options

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "scenes"

#: a falling gas: 200 disks at area fraction 0.1, periodic in x, walls in y, g = 1 down y
DOC = {"system": {"dimension": 2, "particles": 200, "packing_fraction": 0.1, "boundaries": ["periodic", "wall"],
                  "gravity": [0.0, -1.0]},
       "rng": {"generator": "philox", "seed": 5}, "run": {"collisions": 200}}


def scene(engine: str = "float", **tables):
    """DOC on ``engine`` with its tables' fields updated (``system={"gravity": ...}``; None
    removes a field)."""
    doc = copy.deepcopy(DOC)
    doc["collisions"] = {"engine": engine}
    for table, fields in tables.items():
        doc.setdefault(table, {}).update(fields)
        doc[table] = {k: v for k, v in doc[table].items() if v is not None}
    return scene_from_dict(doc, "g.toml")


def test_the_key_is_parsed_and_shown():
    s = scene()
    assert s.gravity == (0.0, -1.0) and s.to_dict()["gravity"] == [0.0, -1.0]
    assert "(periodic, wall), gravity (0, -1)," in s.summary()
    assert scene(system={"gravity": [0, 0]}).gravity is None  # a zero field is none
    no_key = copy.deepcopy(DOC)
    del no_key["system"]["gravity"]
    assert scene_from_dict(no_key).gravity is None and "gravity" not in scene_from_dict(no_key).summary()
    rods = scene_from_dict({"system": {"dimension": 1, "particles": 20, "packing_fraction": 0.2, "boundaries": "wall",
                                       "gravity": [-2]}, "run": {"collisions": 50}})
    assert rods.gravity == (-2.0,)


@pytest.mark.parametrize("fields,needle", [
    ({"system": {"gravity": [0.0, -1.0, 0.0]}}, "[system] gravity: needs 2 components for dimension 2 (one per axis), got 3"),
    ({"system": {"gravity": [-1.0]}}, "[system] gravity: needs 2 components for dimension 2"),
    ({"system": {"gravity": [0.0, "down"]}}, "[system] gravity: component 1 must be a finite number, got 'down'"),
    ({"system": {"gravity": [0.0, True]}}, "[system] gravity: component 1 must be a finite number, got True"),
    ({"system": {"gravity": [0.0, float("inf")]}}, "[system] gravity: component 1 must be a finite number, got inf"),
    ({"system": {"gravity": -1.0}}, "[system] gravity: must be a list of numbers, one per axis, got -1.0"),
    ({"system": {"gravity": []}}, "[system] gravity: must be a list of numbers, one per axis"),
    ({"system": {"gravity": [-1.0, 0.0]}}, "[system] gravity: points along axis 0, which is periodic: a field needs walls"),
    ({"system": {"gravity": [0.0, -1.0], "boundaries": "periodic"}}, "[system] gravity: points along axis 1, which is periodic"),
    ({"system": {"gravity": [0.5, -1.0], "boundaries": "wall"}}, "[system] gravity: must be nonzero along one axis at most"),
])
def test_bad_fields_are_refused_by_name(fields, needle):
    with pytest.raises(SceneError) as e:
        scene(**fields)
    assert needle in str(e.value) and str(e.value).startswith("g.toml: ")


def test_the_lattice_runs_a_field_on_workers_across_it_only():
    # the parallel engine's slabs lie along axis 0: a field along axis 1 runs on 4 workers, one along 0 is refused
    assert scene("lattice", collisions={"workers": 4}).gravity == (0.0, -1.0)
    along = {"system": {"gravity": [-1.0, 0.0], "boundaries": ["wall", "periodic"]}, "collisions": {"workers": 4}}
    with pytest.raises(SceneError) as e:
        scene("lattice", **along)
    assert "[collisions] workers: engine = 'lattice' runs a gas in a field along axis 0 on one worker" in str(e.value)
    assert scene("lattice", **{**along, "collisions": {"workers": 1}}).gravity == (-1.0, 0.0)
    assert scene("float", system=along["system"]).gravity == (-1.0, 0.0)


@pytest.mark.parametrize("engine", ["lattice", "float"])
def test_either_engine_observes_a_scene_in_a_field(engine):
    s = scene(engine, observe={"slabs": 5, "slab_axis": 1}, run={"collisions": 4000})
    sim = build_simulation(s)
    sim.observe(**s.observe)
    sim.run(collisions=4000)
    o = sim.observation()
    assert o.slab_density.value[0] > o.slab_density.value[-1]  # the column is denser below
    assert np.sum(o.slab_density.value) * np.prod(sim.box) / 5 == pytest.approx(200, rel=1e-12)  # every particle
    assert o.temperature.value > 0 and o.pressure_wall[1].value > 0


def test_the_command_lines_lattice_options_are_refused_by_flag():
    s = scene("lattice")
    assert with_lattice_options(s, workers=2).workers == 2  # a field takes workers (slabs across it)
    along = scene("lattice", system={"gravity": [-1.0, 0.0], "boundaries": ["wall", "periodic"]})
    with pytest.raises(SceneError, match="--workers: engine = 'lattice' runs a gas in a field along axis 0"):
        with_lattice_options(along, workers=2)
    assert with_lattice_options(s, search=0.5).search == 0.5  # a field takes neighbour lists
    assert with_lattice_options(s, search="cells", workers=1).search == "cells"
    # a float scene moved to the lattice keeps its field
    assert with_engine(scene(), "lattice").gravity == (0.0, -1.0)


def mean_height(sim) -> float:
    return float(np.mean(sim.positions[:, 1]))


def test_the_float_engine_runs_the_field():
    sim = build_simulation(scene())
    assert np.array_equal(sim.gravity, [0.0, -1.0])
    d0, y0 = sim.diagnostics(), mean_height(sim)
    v = sim.velocities
    assert d0["potential"] > 0 and d0["energy"] == pytest.approx(d0["potential"] + 0.5 * float((v * v).sum()), rel=1e-12)
    sim.run(collisions=200)
    d = sim.diagnostics()
    assert mean_height(sim) < y0 - 0.5  # it falls
    assert d["potential"] < d0["potential"] and abs(d["energy_drift"]) < 1e-13


def test_the_lattice_runs_the_field_and_reverses_it_bit_for_bit():
    sim = build_simulation(scene("lattice"))
    # quantized once to an even integer per tick^2: the value run is the scene's within its rounding
    err = sim.quantization["gravity_error"]
    assert sim.gravity[0] == 0.0 and 0.0 <= err <= 2.0 ** -8 and sim.gravity[1] == pytest.approx(-1.0, rel=2 * err + 1e-15)
    s0, y0 = sim.snapshot(), mean_height(sim)
    sim.run(collisions=2000)
    assert mean_height(sim) < y0 - 0.5
    assert abs(sim.diagnostics()["energy_drift"]) < 1e-6
    sim.run_back()
    s1 = sim.snapshot()
    for key in ("x", "v", "streams", "bits", "clock"):
        assert np.array_equal(np.asarray(s0[key]), np.asarray(s1[key])), key


@pytest.mark.parametrize("engine", ["float", "lattice"])
def test_every_start_gets_the_field(engine, tmp_path):
    # an explicit box with a kinetic energy (the float start in it), a mixture, an initial-state file
    box = scene(engine, system={"packing_fraction": None, "box": [30.0, 40.0], "kinetic_energy": 300.0})
    mixture = copy.deepcopy(DOC)
    mixture["collisions"] = {"engine": engine}
    mixture["species"] = [{"name": "A", "diameter": 1.0, "fraction": 0.5}, {"name": "B", "diameter": 0.6, "fraction": 0.5}]
    initial = {"system": {"dimension": 2, "initial_state": str(SCENES / "initial-state.npz"), "box": [12.0, 8.0],
                          "boundaries": ["periodic", "wall"], "gravity": [0.0, -0.5]},
               "collisions": {"engine": engine}, "rng": {"generator": "philox"}, "run": {"time": 1.0}}
    for s in (box, scene_from_dict(mixture, "m.toml"), scene_from_dict(initial, "i.toml")):
        sim = build_simulation(s)
        g = s.gravity[1]
        assert sim.gravity[0] == 0.0 and sim.gravity[1] == pytest.approx(g, rel=2.0 ** -8), s.source


@pytest.mark.parametrize("engine", ["float", "lattice"])
def test_a_3d_initial_state_falls_along_z(engine, tmp_path):
    # 27 spheres on a grid in a 9^3 box, periodic in x and y, walls in z, g down z
    grid = np.arange(1.5, 9.0, 3.0)
    x = np.array([[a, b, c] for a in grid for b in grid for c in grid])
    v = np.random.default_rng(3).normal(size=x.shape)
    np.savez(tmp_path / "s3.npz", positions=x, velocities=v)
    doc = {"system": {"dimension": 3, "initial_state": "s3.npz", "box": [9.0, 9.0, 9.0],
                      "boundaries": ["periodic", "periodic", "wall"], "gravity": [0.0, 0.0, -1.0]},
           "collisions": {"engine": engine}, "rng": {"generator": "philox"}, "run": {"collisions": 50}}
    sim = build_simulation(scene_from_dict(doc, "s3.toml", tmp_path))
    z0 = float(np.mean(sim.positions[:, 2]))
    assert sim.gravity[2] == pytest.approx(-1.0, rel=2.0 ** -8) and not sim.gravity[:2].any()
    sim.run(collisions=50)
    assert float(np.mean(sim.positions[:, 2])) < z0


@pytest.mark.parametrize("engine", ["float", "lattice"])
def test_revcol_run_the_shipped_scene(engine, tmp_path, capsys):
    s = load_scene(SCENES / "sedimentation.toml")
    assert s.gravity == (0.0, -1.0) and s.boundaries == ("periodic", "wall") and s.particles == 400
    out = tmp_path / "r.json"
    rc = cli_main(["run", str(SCENES / "sedimentation.toml"), "--engine", engine, "--json", str(out), "--no-progress"])
    text = capsys.readouterr().out
    assert rc == 0, text
    r = json.loads(out.read_text())
    assert r["passed"] and r["gravity"][0] == 0.0 and r["gravity"][1] == pytest.approx(-1.0, rel=2.0 ** -8)
    assert "  field            gravity (0, -1) along axis 1" in text and "gravity (0, -1)" in r["summary"]
    if engine == "lattice":
        assert r["bit_for_bit"] and "quantized once to an even integer per tick^2" in text
        assert r["quantization"]["gravity_error"] < 1e-3


@pytest.mark.parametrize("engine", ["float", "lattice"])
def test_revcol_simulate_runs_the_field_and_resumes_it(engine, tmp_path):
    ckpt = tmp_path / "ck"
    r = simulate(SCENES / "sedimentation.toml", engine=engine, collisions=400, checkpoints=ckpt, checkpoint_every=200,
                 progress=False)
    assert r["gravity"][1] == pytest.approx(-1.0, rel=2.0 ** -8) and abs(r["energy_drift"]) < 1e-6
    last = ckpt / "checkpoint-000000000400.npz"
    assert last.is_file()
    on = simulate(SCENES / "sedimentation.toml", engine=engine, collisions=100, resume=last, progress=False)
    assert on["net_collisions"] == 500 and on["gravity"] == r["gravity"]
    # a checkpoint resumed under another field (or none) is refused by name
    doc = copy.deepcopy(DOC)
    doc["collisions"] = {"engine": engine}
    doc["system"].update(particles=400, gravity=[0.0, -2.0])
    with pytest.raises(SceneError, match=r"the checkpoint runs gravity \(0, -1\), the scene \(0, -2\) \(\[system\] gravity\)"):
        simulate(scene_from_dict(doc, "other.toml"), collisions=10, resume=last, progress=False)
    del doc["system"]["gravity"]
    with pytest.raises(SceneError, match=r"the checkpoint runs gravity \(0, -1\), the scene none"):
        simulate(scene_from_dict(doc, "other.toml"), collisions=10, resume=last, progress=False)
