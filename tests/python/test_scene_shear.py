"""Lees-Edwards shear in scene files (``[system] shear_rate``): the key parsed and checked
(one-line errors naming it, or the option shear refuses), passed to the lattice engine wherever
a scene builds one (a random start, an explicit box, an initial-state file), run (the gas
shears and heats), reversed bit for bit, and shown by ``revcol run`` and ``revcol simulate``,
whose ``--resume`` refuses another shear. The engine's own shear tests are the lattice's."""
import copy
import json
from pathlib import Path

import numpy as np
import pytest

from revcol.cli.main import main as cli_main
from revcol.cli.simulate import simulate
from revcol.gas import build_simulation
from revcol.scene import SceneError, load_scene, scene_from_dict, with_engine, with_lattice_options, with_mode
from revcol.scene_schema import observes_frames

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "scenes"

#: a sheared gas: 300 disks at area fraction 0.3 in a periodic square (about 28 diameters), rate 0.1
DOC = {"system": {"dimension": 2, "particles": 300, "packing_fraction": 0.3, "boundaries": "periodic",
                  "shear_rate": 0.1},
       "collisions": {"engine": "lattice"}, "rng": {"seed": 5}, "run": {"collisions": 2000}}


def scene(**tables):
    """DOC with its tables' fields updated (``system={"shear_rate": ...}``; None removes a field)."""
    doc = copy.deepcopy(DOC)
    for table, fields in tables.items():
        doc.setdefault(table, {}).update(fields)
        doc[table] = {k: v for k, v in doc[table].items() if v is not None}
    return scene_from_dict(doc, "s.toml")


def slope(sim) -> float:
    """The fitted d v_x / d y of the gas: the shear rate of its flow."""
    return float(np.polyfit(sim.positions[:, 1], sim.velocities[:, 0], 1)[0])


def test_the_key_is_parsed_and_shown():
    s = scene()
    assert s.shear_rate == 0.1 and s.to_dict()["shear_rate"] == 0.1
    assert "(periodic, periodic), shear rate 0.1, lattice engine" in s.summary()
    assert scene(system={"shear_rate": -0.25}).shear_rate == -0.25  # either sense
    assert scene(system={"shear_rate": 1}).shear_rate == 1.0 and isinstance(scene(system={"shear_rate": 1}).shear_rate,
                                                                             float)
    assert scene(system={"shear_rate": 0.0}).shear_rate is None  # a zero rate is none
    none = scene(system={"shear_rate": None})
    assert none.shear_rate is None and "shear" not in none.summary()
    # 3D: walls on axis 2 are allowed (the flow and the gradient are axes 0 and 1)
    slab = scene(system={"dimension": 3, "particles": 600, "boundaries": ["periodic", "periodic", "wall"]})
    assert slab.shear_rate == 0.1 and slab.boundaries == ("periodic", "periodic", "wall")


@pytest.mark.parametrize("fields,needle", [
    ({"system": {"shear_rate": "fast"}}, "[system] shear_rate: must be a finite number, got 'fast'"),
    ({"system": {"shear_rate": True}}, "[system] shear_rate: must be a finite number, got True"),
    ({"system": {"shear_rate": float("inf")}}, "[system] shear_rate: must be a finite number, got inf"),
    ({"system": {"shear_rate": float("nan")}}, "[system] shear_rate: must be a finite number, got nan"),
    ({"system": {"shear_rate": [0.1]}}, "[system] shear_rate: must be a finite number, got [0.1]"),
    ({"collisions": {"engine": "float"}}, "[system] shear_rate: Lees-Edwards shear runs on the lattice engine only "
                                          "(engine = 'lattice'; the float engine's is not built yet), got engine = 'float'"),
    ({"collisions": {"engine": "float"}, "system": {"dimension": 1}}, "[system] shear_rate: Lees-Edwards shear runs on "
                                                                      "the lattice engine only"),
    ({"system": {"boundaries": ["wall", "periodic"]}}, "[system] shear_rate: needs axes 0 (the flow) and 1 (the "
                                                       "gradient) periodic, got boundaries (wall, periodic)"),
    ({"system": {"boundaries": ["periodic", "wall"]}}, "needs axes 0 (the flow) and 1 (the gradient) periodic"),
    ({"system": {"boundaries": ["periodic", "wall"], "gravity": [0.0, -1.0]}},
     "[system] shear_rate: is refused together with [system] gravity: shear and a field together are not built yet"),
    ({"system": {"packing_fraction": None, "box": [9.0, 20.0]}},
     "[system] shear_rate: needs a box of at least 9.07031 along axis 0 (the flow) and 5.03906 along axis 1 (the "
     "gradient), 9 and 5 of the lattice's cells of 1 + 2^-7 diameters; got 9 x 20"),
    ({"system": {"packing_fraction": None, "box": [20.0, 5.0]}}, "[system] shear_rate: needs a box of at least"),
    ({"observe": {"slabs": 4}}, "[observe] slab_axis: must be 1 (the gradient) under [system] shear_rate: a sheared "
                                "gas's slabs give its velocity profile across the gradient, got 0"),
    ({"observe": {"slabs": 4, "slab_axis": 0}}, "[observe] slab_axis: must be 1 (the gradient) under [system] shear_rate"),
    ({"collisions": {"workers": 4}}, "[collisions] workers: engine = 'lattice' runs a gas under shear ([system] "
                                     "shear_rate) on one worker (the parallel engine is not built for shear yet), got 4"),
    ({"collisions": {"search": 0.3}}, "[collisions] search: engine = 'lattice' searches a gas under shear ([system] "
                                      "shear_rate) with the cell grid only ('auto' or 'cells'; no neighbour lists for "
                                      "moving images yet), got 0.3"),
])
def test_bad_shear_is_refused_by_name(fields, needle):
    with pytest.raises(SceneError) as e:
        scene(**fields)
    assert needle in str(e.value) and str(e.value).startswith("s.toml: ")


@pytest.mark.parametrize("fields", [{"observe": {"slabs": 4}}, {"collisions": {"workers": 4}}, {"collisions": {"search": 0.3}},
                                    {"collisions": {"engine": "float"}}, {"system": {"boundaries": "wall"}}])
def test_the_same_options_without_shear_load(fields):
    assert scene(**{**fields, "system": {**fields.get("system", {}), "shear_rate": 0.0}}).shear_rate is None


def test_the_command_lines_options_are_refused_by_flag():
    s = scene()
    with pytest.raises(SceneError, match=r"--workers: engine = 'lattice' runs a gas under shear \(\[system\] "
                                         r"shear_rate\) on one worker"):
        with_lattice_options(s, workers=2)
    with pytest.raises(SceneError, match="--search: engine = 'lattice' searches a gas under shear"):
        with_lattice_options(s, search=0.5)
    assert with_lattice_options(s, search="cells", workers=1).search == "cells"
    for move in (lambda: with_engine(s, "float"), lambda: with_mode(s, "exact", "float")):
        with pytest.raises(SceneError, match=r"s.toml: \[system\] shear_rate: Lees-Edwards shear runs on the lattice "
                                             r"engine only .*got engine = 'float' \(--engine\)"):
            move()
    assert with_mode(s, "specular").shear_rate == 0.1
    # no observer for the frames' image flags under shear (its unwrapped flow coordinate holds the
    # moving images' offset, not whole box lengths: the frames infer their flags)
    assert not observes_frames(s, "t.xyz") and observes_frames(scene(system={"shear_rate": None}), "t.xyz")


def test_an_observed_sheared_scene_reports_its_stress_and_profile(tmp_path, capsys):
    s = scene(observe={"slabs": 6, "slab_axis": 1}, run={"collisions": 6000})
    assert s.observe == {"slabs": 6, "slab_axis": 1}
    sim = build_simulation(s)
    sim.observe(**s.observe)
    sim.run(collisions=6000)
    o = sim.observation()
    assert o.shear_rate == pytest.approx(0.1, rel=1e-6) and o.viscosity.value > 0.0
    assert o.shear_stress.value == pytest.approx(-o.viscosity.value * o.shear_rate)
    assert np.polyfit(o.slab_velocity.centres, o.slab_velocity.value, 1)[0] == pytest.approx(0.1, rel=0.3)
    assert any(line.lstrip().startswith("viscosity") and "at shear rate 0.1" in line for line in o.lines())


def test_the_lattice_runs_the_shear_and_reverses_it_bit_for_bit():
    sim = build_simulation(scene())
    err = sim.quantization["shear_error"]
    assert 0.0 <= err < 1e-6 and sim.shear_rate == pytest.approx(0.1, rel=2 * err + 1e-12)
    assert slope(sim) == pytest.approx(0.1, abs=0.03)  # the random start's steady profile
    s0, e0 = sim.snapshot(), sim.diagnostics()
    sim.run(collisions=3000)
    assert sim.diagnostics()["energy_drift"] > e0["energy_drift"]  # viscous heating
    assert slope(sim) == pytest.approx(0.1, abs=0.05)  # still sheared
    sim.run_back()
    s1 = sim.snapshot()
    for key in ("x", "v", "streams", "bits", "clock"):
        assert np.array_equal(np.asarray(s0[key]), np.asarray(s1[key])), key


def test_every_start_gets_the_shear(tmp_path):
    # an explicit box with a kinetic energy (the float start in it, given the profile), an
    # initial-state file (its velocities run as given)
    box = scene(system={"packing_fraction": None, "box": [24.0, 30.0], "kinetic_energy": 300.0, "shear_rate": 0.2})
    sim = build_simulation(box)
    assert sim.shear_rate == pytest.approx(0.2, rel=1e-6) and slope(sim) == pytest.approx(0.2, abs=0.05)
    initial = {"system": {"dimension": 2, "initial_state": str(SCENES / "initial-state.npz"), "box": [12.0, 8.0],
                          "boundaries": "periodic", "shear_rate": -0.05},
               "collisions": {"engine": "lattice"}, "run": {"time": 1.0}}
    s = scene_from_dict(initial, "i.toml")
    sim = build_simulation(s)
    with np.load(SCENES / "initial-state.npz") as z:
        v = z["velocities"]
    assert s.shear_rate == -0.05 and sim.shear_rate == pytest.approx(-0.05, rel=1e-6)
    assert np.allclose(sim.velocities, v, atol=1e-6)
    # the initial state is built once when the scene is read: a box the shear cannot take is refused there
    initial["system"]["box"] = [12.0, 4.0]
    with pytest.raises(SceneError, match=r"i.toml: \[system\] shear_rate: needs a box of at least"):
        scene_from_dict(initial, "i.toml")


def test_revcol_run_the_shipped_scene(tmp_path, capsys):
    s = load_scene(SCENES / "shear.toml")
    assert (s.shear_rate, s.engine, s.mode, s.dimension, s.boundaries) == (0.1, "lattice", "specular", 3,
                                                                           ("periodic",) * 3)
    assert 1000 <= s.particles <= 1500 and s.packing_fraction == 0.3
    out = tmp_path / "r.json"
    rc = cli_main(["run", str(SCENES / "shear.toml"), "--collisions", "5000", "--json", str(out), "--no-progress"])
    text = capsys.readouterr().out
    assert rc == 0, text
    r = json.loads(out.read_text())
    assert r["passed"] and r["bit_for_bit"] and r["shear_rate"] == pytest.approx(0.1, rel=1e-6)
    assert r["shear_per_tick"] > 0 and r["quantization"]["shear_error"] < 1e-6 and "shear rate 0.1" in r["summary"]
    assert f"  shear            rate 0.1 (lattice: {r['shear_per_tick']:,} units per tick, within " in text
    assert "flow axis 0, gradient axis 1 (Lees-Edwards); the energy grows by viscous heating" in text
    assert r["energy_drift_turn"] > 0 and r["energy_drift_end"] == 0.0  # heated, then restored
    # on the float engine: refused by name
    assert cli_main(["run", str(SCENES / "shear.toml"), "--engine", "float", "--no-progress"]) == 2
    assert "[system] shear_rate: Lees-Edwards shear runs on the lattice engine only" in capsys.readouterr().err


def test_revcol_simulate_runs_the_shear_and_resumes_only_it(tmp_path):
    ckpt = tmp_path / "ck"
    r = simulate(scene(), collisions=400, checkpoints=ckpt, checkpoint_every=200, trajectory=tmp_path / "t.xyz",
                 progress=False)
    assert r["shear_rate"] == pytest.approx(0.1, rel=1e-6) and r["shear_per_tick"] > 0 and r["trajectory_frames"] >= 2
    last = ckpt / "checkpoint-000000000400.npz"
    assert last.is_file()
    on = simulate(scene(), collisions=100, resume=last, progress=False)
    assert on["net_collisions"] == 500 and on["shear_rate"] == r["shear_rate"]
    # a checkpoint resumed under another shear (or none) is refused by name
    with pytest.raises(SceneError, match=r"s.toml: --resume .*: the checkpoint runs shear rate 0.1, the scene 0.2 "
                                         r"\(\[system\] shear_rate\)"):
        simulate(scene(system={"shear_rate": 0.2}), collisions=10, resume=last, progress=False)
    with pytest.raises(SceneError, match=r"the checkpoint runs shear rate 0.1, the scene none"):
        simulate(scene(system={"shear_rate": None}), collisions=10, resume=last, progress=False)
    # and an unsheared checkpoint under a sheared scene
    plain = tmp_path / "plain"
    simulate(scene(system={"shear_rate": None}), collisions=200, checkpoints=plain, checkpoint_every=200, progress=False)
    with pytest.raises(SceneError, match=r"the checkpoint runs shear rate none, the scene 0.1"):
        simulate(scene(), collisions=10, resume=plain / "checkpoint-000000000200.npz", progress=False)


def test_the_horizon_of_a_sheared_scene_is_none_and_names_no_float_run(capsys):
    assert cli_main(["run", str(SCENES / "shear.toml"), "--horizon", "--seeds", "1", "--max-collisions", "2000",
                     "--no-progress"]) == 0
    text = capsys.readouterr().out
    assert "horizon: none." in text and "the float engine runs no shear" in text and "--engine float" not in text
