"""The lattice engine's options from Python, scenes and the CLI (issue 52): tick_bits,
cell_bits and the neighbour search reach the engine; bad values are named; the float engine
refuses them; the search never changes the run (bit-identical states); it survives snapshots
and checkpoints; the crystal start's old name "lattice" still works, with a warning."""
import json
import warnings

import numpy as np
import pytest

from revcol import Simulation, _core
from revcol.cli.main import main as cli_main
from revcol.lattice import LatticeSimulation, LatticeSimulation3D
from revcol.lattice_gas import build_lattice
from revcol.scene import SceneError, load_scene, scene_from_dict, with_engine, with_lattice_options

# every part of the state a run changes (the neighbour search is not one of them)
STATE = ("x", "v", "streams", "bits", "bits_size", "clock", "collisions", "particle_collisions", "log_particle",
         "log_count", "log_redraws", "group_drawer", "group_counts")


def _gas(engine="lattice", dim=2, **collisions):
    doc = {"system": {"dimension": dim, "particles": 60, "packing_fraction": 0.3, "boundaries": "periodic"},
           "collisions": {"engine": engine, **collisions}, "rng": {"seed": 3}, "run": {"collisions": 500}}
    return scene_from_dict(doc, "t.toml")


def _scene_file(tmp_path, engine="lattice", **collisions):
    extra = "".join(f"{k} = {json.dumps(v)}\n" for k, v in collisions.items())
    p = tmp_path / f"{engine}.toml"
    p.write_text("[system]\ndimension = 2\nparticles = 60\npacking_fraction = 0.3\nboundaries = 'periodic'\n"
                 f"[collisions]\nengine = '{engine}'\n{extra}[rng]\nseed = 3\n[run]\ncollisions = 500\n")
    return str(p)


def _same(a: dict, b: dict) -> bool:
    return all(np.array_equal(np.asarray(a[k]), np.asarray(b[k])) for k in STATE)


# --- the search never changes the run --------------------------------------------------------

@pytest.mark.parametrize("cls,n,phi", [(LatticeSimulation, 150, 0.45), (LatticeSimulation3D, 120, 0.3)])
def test_every_search_gives_the_same_state_bit_for_bit(cls, n, phi):
    sims = {s: cls.random(n, phi=phi, seed=5, boundary="periodic", search=s) for s in ("auto", "cells", 0.3, 1.5)}
    ends = {}
    for s, sim in sims.items():
        assert sim.run(collisions=3000)["collisions"] == 3000
        ends[s] = sim.snapshot()
    assert all(_same(ends["auto"], e) for e in ends.values())
    for sim in sims.values():  # and back: the start, bit for bit, whichever search
        sim.run_back(collisions=1500)
    backs = [sim.snapshot() for sim in sims.values()]
    assert all(_same(backs[0], b) for b in backs)
    # and a search switched in the middle of a run
    sim = cls.random(n, phi=phi, seed=5, boundary="periodic", search="cells")
    sim.run(collisions=1000)
    sim.search = 0.5
    sim.run(collisions=2000)
    assert _same(ends["auto"], sim.snapshot())


def test_the_search_in_use():
    assert LatticeSimulation.random(60, phi=0.3, seed=1).search == "cells"  # auto: cells in 2D
    assert isinstance(LatticeSimulation3D.random(60, phi=0.3, seed=1).search, float)  # lists in 3D
    assert LatticeSimulation3D.random(60, phi=0.3, seed=1, search="cells").search == "cells"
    assert LatticeSimulation.random(60, phi=0.3, seed=1, search=0.5).search == pytest.approx(0.5, rel=1e-3)
    x = np.array([[1.0, 1.0], [3.0, 1.0]])
    assert LatticeSimulation(x, [[1.0, 0.0], [-1.0, 0.0]], 6.0, search=0.25).search == pytest.approx(0.25, rel=1e-3)


@pytest.mark.parametrize("bad,err", [("lists", ValueError), (5.0, ValueError), (0.01, ValueError),
                                     (float("nan"), ValueError), (True, TypeError)])
def test_a_bad_search_is_named(bad, err):
    with pytest.raises(err, match="search"):
        LatticeSimulation.random(60, phi=0.3, seed=1, search=bad)
    sim = LatticeSimulation.random(60, phi=0.3, seed=1)
    with pytest.raises(err, match="search"):
        sim.search = bad


def test_the_binding_search():
    e = LatticeSimulation3D.random(60, phi=0.3, seed=1)._e
    assert e.neighbour_search in (1, 2) and e.list_shell > 0
    e.set_search(0)
    assert (e.neighbour_search, e.list_shell) == (0, 0.0)
    e.set_search(0.5)
    assert e.list_shell == pytest.approx(0.5, rel=1e-3)
    with pytest.raises(ValueError, match=r"\[0.02, 2\]"):
        e.set_search(3.0)
    with pytest.raises(TypeError, match="shell"):
        e.set_search("cells")
    assert isinstance(_core.LatticeEngine.set_search.__doc__, str)


def test_the_search_survives_snapshots_checkpoints_and_pickles(tmp_path):
    import pickle
    sim = LatticeSimulation.random(60, phi=0.3, seed=2, search=0.5)
    sim.run(collisions=200)
    snap = sim.snapshot()
    assert snap["search"] == 0.5
    assert LatticeSimulation.from_snapshot(snap).search == sim.search
    sim.save(tmp_path / "c.npz")
    back = LatticeSimulation.load(tmp_path / "c.npz")
    assert back.search == sim.search and back.snapshot()["search"] == 0.5
    assert pickle.loads(pickle.dumps(sim)).search == sim.search
    old = {k: v for k, v in snap.items() if k != "search"}  # written before the entry existed: automatic
    assert LatticeSimulation.from_snapshot(old).snapshot()["search"] == -1.0
    assert LatticeSimulation.from_snapshot({**snap, "search": 0.0}).search == "cells"
    with pytest.raises(ValueError, match="search"):
        LatticeSimulation.from_snapshot({**snap, "search": 7.0})


# --- scenes ------------------------------------------------------------------------------------

def test_scene_fields_reach_the_engine():
    s = _gas(tick_bits=18, cell_bits=14, search=0.5)
    assert (s.tick_bits, s.cell_bits, s.search) == (18, 14, 0.5)
    sim = build_lattice(s)
    assert (sim.units["tick_bits"], sim.units["cell_bits"]) == (18, 14)
    assert sim.search == pytest.approx(0.5, rel=1e-3)
    assert build_lattice(_gas(search="cells", dim=3)).search == "cells"
    default = build_lattice(_gas())
    assert default.units["cell_bits"] == 16 and default.search == "cells"


@pytest.mark.parametrize("field,value,needle", [
    ("tick_bits", 30, "[collisions] tick_bits: must be 16..26, got 30"),
    ("tick_bits", 18.5, "[collisions] tick_bits: must be an integer"),
    ("cell_bits", 11, "[collisions] cell_bits: must be 12..20, got 11"),
    ("search", 3.0, "[collisions] search: must be 'auto', 'cells' or a shell in diameters, 0.02..2, got 3.0"),
    ("search", "lists", "[collisions] search: must be 'auto', 'cells'"),
    ("search", True, "[collisions] search: must be"),
])
def test_bad_scene_values_are_named(field, value, needle):
    with pytest.raises(SceneError) as e:
        _gas(**{field: value})
    assert needle in str(e.value)


@pytest.mark.parametrize("field,value", [("tick_bits", 20), ("cell_bits", 16), ("search", "cells")])
def test_a_float_engine_scene_refuses_the_lattice_options(field, value):
    with pytest.raises(SceneError, match=rf"\[collisions\] {field}: applies to engine = 'lattice' only"):
        _gas(engine="float", **{field: value})


def test_a_lattice_scene_moved_to_the_float_engine_drops_them():
    s = with_engine(_gas(tick_bits=18, search=0.5), "float")
    assert (s.engine, s.tick_bits, s.cell_bits, s.search) == ("float", None, 16, "auto")
    with pytest.raises(SceneError, match="--tick-bits: the lattice engine's options; this scene runs the float"):
        with_lattice_options(s, tick_bits=18)
    with pytest.raises(SceneError, match="--search: must be 'auto', 'cells'"):
        with_lattice_options(_gas(), search=9.0)


def test_the_old_crystal_name_warns_and_starts_the_same(tmp_path):
    for engine in ("float", "lattice"):
        with pytest.warns(DeprecationWarning, match="init='crystal'"):
            old = Simulation.random(60, 2, 0.5, seed=4, init="lattice", engine=engine)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            new = Simulation.random(60, 2, 0.5, seed=4, init="crystal", engine=engine)
        assert np.array_equal(old.positions, new.positions)
    with pytest.warns(DeprecationWarning, match="init='crystal'"):
        LatticeSimulation3D.random(100, phi=0.3, seed=4, init="lattice")
    with pytest.raises(ValueError, match="'auto', 'rsa', 'crystal' or 'relax'"):
        Simulation.random(60, 2, 0.3, seed=4, init="grid")
    p = tmp_path / "old.toml"
    p.write_text("[system]\ndimension = 2\nparticles = 60\npacking_fraction = 0.5\nstart = 'lattice'\n")
    with pytest.warns(DeprecationWarning, match=r"\[system\] start: 'lattice' is deprecated, write 'crystal'"):
        assert load_scene(p).start == "crystal"


# --- the CLI -------------------------------------------------------------------------------------

def test_run_flags_override_the_scene(tmp_path, capsys):
    s = _scene_file(tmp_path, tick_bits=22, search="auto")
    out = tmp_path / "r.json"
    rc = cli_main(["run", s, "--tick-bits", "18", "--cell-bits", "14", "--search", "0.5", "--json", str(out),
                   "--no-progress"])
    assert rc == 0
    r = json.loads(out.read_text())
    assert (r["units"]["tick_bits"], r["units"]["cell_bits"]) == (18, 14) and r["search"] == pytest.approx(0.5, rel=1e-3)
    assert "tick_bits 18, cell_bits 14, search neighbour lists, shell 0.5" in capsys.readouterr().out
    # the scene's own fields when no flag is given
    assert cli_main(["run", s, "--json", str(out), "--no-progress", "--engine", "lattice"]) == 0
    assert json.loads(out.read_text())["units"]["tick_bits"] == 22


def test_simulate_flags_override_the_scene_and_a_resume_takes_a_new_search(tmp_path, capsys):
    s = _scene_file(tmp_path)
    rc = cli_main(["simulate", s, "--collisions", "300", "--search", "cells", "--cell-bits", "13",
                   "--checkpoint", str(tmp_path / "ck"), "--checkpoint-every", "300", "--json", "-", "--no-progress"])
    assert rc == 0
    r = json.loads(capsys.readouterr().out)
    assert r["lattice"] == {"tick_bits": r["lattice"]["tick_bits"], "cell_bits": 13, "search": "cells"}
    ck = r["checkpoints"][-1]
    assert LatticeSimulation.load(ck).search == "cells"
    rc = cli_main(["simulate", s, "--collisions", "300", "--resume", ck, "--search", "0.4", "--json", "-",
                   "--no-progress"])
    assert rc == 0
    assert json.loads(capsys.readouterr().out)["lattice"]["search"] == pytest.approx(0.4, rel=1e-3)
    assert cli_main(["simulate", s, "--resume", ck, "--tick-bits", "18", "--no-progress"]) == 2
    assert "a resumed run keeps its checkpoint's units" in capsys.readouterr().err


@pytest.mark.parametrize("command", ["run", "simulate"])
@pytest.mark.parametrize("args,needle", [
    (["--tick-bits", "18"], "--tick-bits: the lattice engine's options; this scene runs the float engine"),
    (["--search", "cells", "--cell-bits", "14"], "--cell-bits, --search: the lattice engine's options"),
])
def test_the_float_engine_refuses_the_flags(tmp_path, capsys, command, args, needle):
    s = _scene_file(tmp_path, engine="float")
    assert cli_main([command, s, *args, "--no-progress"]) == 2
    assert needle in capsys.readouterr().err
    lat = _scene_file(tmp_path)
    assert cli_main([command, lat, "--engine", "float", *args, "--no-progress"]) == 2


@pytest.mark.parametrize("args,needle", [
    (["--tick-bits", "40"], "--tick-bits: must be 16..26, got 40"),
    (["--search", "2.5"], "--search: must be 'auto', 'cells' or a shell in diameters, 0.02..2, got 2.5"),
    (["--search", "lists"], "argument --search: expected 'auto', 'cells' or a shell"),
])
def test_bad_flag_values_are_named(tmp_path, capsys, args, needle):
    try:
        rc = cli_main(["run", _scene_file(tmp_path), *args, "--no-progress"])
    except SystemExit as e:  # argparse's own refusal of a value its type cannot read
        rc = e.code
    assert rc == 2
    assert needle in capsys.readouterr().err
