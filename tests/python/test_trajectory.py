"""Trajectories that other tools read back: GSD (gsd.hoomd) with a monotonic step, image flags,
diameters and walls; extended XYZ that ASE reads, with an element symbol and a 2D cell."""
import os
import warnings

import numpy as np
import pytest

import revcol
from revcol.gas import run_gas
from revcol.scene import scene_from_dict
from revcol.trajectory import open_trajectory

gsd_hoomd = pytest.importorskip("gsd.hoomd")


def free_flight(path, box, periodic, dt=0.05, frames=150, **kw):
    """Particles flying freely (no collisions) through a box, written wrapped; returns the
    exact unwrapped positions of each frame (x0 + v t) and the velocities."""
    rng = np.random.default_rng(3)
    box = np.asarray(box, float)
    n, d = 7, len(box)
    x0 = rng.uniform(0.0, 1.0, (n, d)) * box
    v = rng.normal(size=(n, d)) * 2.0
    v[:, ~np.asarray(periodic)] = 0.0  # no walls crossed: the closed axes stand still
    w = open_trajectory(path, box, periodic, 1.0, precise=True, **kw)
    truth = []
    for k in range(frames):
        t = k * dt
        x = x0 + v * t
        truth.append(x)
        w.write(np.mod(x, box), v, t, 10 * k, "forward")
    w.close()
    return np.array(truth), v


@pytest.mark.parametrize("box,periodic", [([7.0, 9.0], [True, True]), ([6.0, 5.0, 8.0], [True, False, True]),
                                          ([9.0], [True])])
def test_gsd_image_flags_unwrap_to_the_integrated_positions(tmp_path, box, periodic):
    path = tmp_path / "t.gsd"
    truth, v = free_flight(path, box, periodic)
    d = len(box)
    lengths = np.array(box + [1.0] * max(0, 2 - d) + [0.0] * (3 - max(2, d)))
    with gsd_hoomd.open(str(path), "r") as f:
        assert len(f) == len(truth)
        for k, fr in enumerate(f):
            assert list(fr.configuration.box[:3]) == pytest.approx(lengths.tolist())
            assert fr.configuration.dimensions == (3 if d == 3 else 2)
            assert fr.particles.diameter.tolist() == [1.0] * 7
            img = fr.particles.image
            assert img.dtype == np.int32
            x = np.asarray(fr.log["particles/revcol/position"], dtype=float)
            span = np.where(lengths > 0, lengths, 1.0)
            unwrapped = x + img * span + 0.5 * np.where(lengths > 0, lengths, 0.0)
            np.testing.assert_allclose(unwrapped[:, :d], truth[k], rtol=0, atol=1e-9)
            # the float32 positions are the same, rounded
            np.testing.assert_allclose(fr.particles.position, x, rtol=0, atol=1e-5 * max(box))
            assert not img[:, d:].any() and not img[:, ~np.asarray(periodic + [False] * (3 - d))].any()
            walls = fr.log["revcol/walls"].tolist()
            assert walls == [0 if p else 1 for p in periodic] + [1] * (3 - d)
    # the particles crossed boundaries: the test can see a wrong flag
    assert np.abs(img).max() >= 2


def test_gsd_warns_when_frames_are_too_sparse_to_unwrap(tmp_path):
    with pytest.warns(RuntimeWarning, match="more than L/4"):
        free_flight(tmp_path / "t.gsd", [5.0, 5.0], [True, True], dt=1.5, frames=5)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        free_flight(tmp_path / "u.gsd", [5.0, 5.0], [True, True], dt=0.1, frames=5)


def small_gas(tmp_path, **run):
    doc = {"system": {"dimension": 2, "particles": 60, "packing_fraction": 0.2, "boundaries": ["periodic", "wall"]},
           "rng": {"seed": 3}, "run": {"collisions": 120, **run}}
    return scene_from_dict(doc, "traj.toml", tmp_path)


def test_gsd_of_a_round_trip_has_a_monotonic_step_direction_and_images_back_at_zero(tmp_path):
    import dataclasses

    scene = dataclasses.replace(small_gas(tmp_path), trajectory_every=20)
    r = run_gas(scene, trajectory=tmp_path / "t.gsd", progress=False)
    assert r["passed"]
    with gsd_hoomd.open(str(tmp_path / "t.gsd"), "r") as f:
        frames = list(f)
    steps = [int(fr.configuration.step) for fr in frames]
    net = [int(fr.log["revcol/net_collisions"][0]) for fr in frames]
    direction = [int(fr.log["revcol/direction"][0]) for fr in frames]
    assert net == list(range(0, 121, 20)) + list(range(100, -1, -20))
    assert steps == list(range(0, 241, 20))  # forward 120 then 120 undone, never decreasing
    assert direction == [1] * 7 + [-1] * 6
    assert frames[0].log["revcol/walls"].tolist() == [0, 1, 1]
    # the round trip ends where it started: unwrapped, every particle is back at its first position
    # (one that starts on a boundary may come back on its other side, one image away)
    assert np.abs(frames[6].particles.image).max() >= 1  # some crossed on the way
    assert not any(fr.particles.image[:, 1:].any() for fr in frames)  # the walled axis has no images
    box = np.asarray(frames[0].configuration.box[:3], dtype=float)
    ends = [fr.particles.position + fr.particles.image * box for fr in (frames[0], frames[-1])]
    np.testing.assert_allclose(ends[1], ends[0], rtol=0, atol=1e-5)


def test_extended_xyz_reads_in_ase_as_a_2d_cell(tmp_path):
    ase_io = pytest.importorskip("ase.io")
    from revcol.trajectory import true_images
    sim = revcol.Simulation.random(30, 2, 0.2, seed=2, boundary=["periodic", "wall"])
    sim.observe()  # the frames' image flags from the observer (sparse frames: no inference, no warning)
    w = open_trajectory(tmp_path / "t.xyz", sim.box, sim.periodic, 1.0)
    shots = []
    for k in range(4):
        w.write(sim.positions, sim.velocities, sim.time, 20 * k, "forward", image=true_images(sim))
        shots.append((sim.positions, sim.velocities, sim.time))
        sim.run(collisions=20)
    w.close()
    atoms = ase_io.read(str(tmp_path / "t.xyz"), index=":")
    assert len(atoms) == 4
    for a, (x, v, t) in zip(atoms, shots):
        assert a.get_chemical_symbols() == ["Ar"] * 30
        assert a.pbc.tolist() == [True, False, False]
        np.testing.assert_array_equal(a.cell[:], np.diag(list(sim.box) + [0.0]))  # z: no third axis
        np.testing.assert_allclose(a.positions[:, :2], x, rtol=1e-11)
        assert not a.positions[:, 2].any()
        np.testing.assert_allclose(a.arrays["velo"][:, :2], v, rtol=1e-11)
        assert a.arrays["image"].shape == (30, 3) and not a.arrays["image"][:, 1:].any()  # y walled, no z
        assert a.info["Time"] == t and a.info["Phase"] == "forward"


def test_species_is_configurable_and_checked(tmp_path):
    ase_io = pytest.importorskip("ase.io")
    w = open_trajectory(tmp_path / "t.xyz", [5.0, 5.0, 5.0], [True] * 3, 1.0, species="He")
    w.write(np.array([[1.0, 2.0, 3.0]]), np.zeros((1, 3)), 0.0, 0, "forward")
    w.close()
    a = ase_io.read(str(tmp_path / "t.xyz"))
    assert a.get_chemical_symbols() == ["He"] and a.pbc.all() and a.cell[2, 2] == 5.0
    with pytest.raises(ValueError, match="chemical element symbol"):
        open_trajectory(tmp_path / "u.xyz", [5.0, 5.0], [True, True], 1.0, species="A")
    assert not list(tmp_path.glob("u*")) and not list(tmp_path.glob(".revcol-*u*"))
    w = open_trajectory(tmp_path / "t.gsd", [5.0, 5.0], [True, True], 1.0, species="Ne")
    w.write(np.array([[1.0, 2.0]]), np.zeros((1, 2)), 0.0, 0, "forward")
    w.close()
    with gsd_hoomd.open(str(tmp_path / "t.gsd"), "r") as f:
        assert f[0].particles.types == ["Ne"]
    mask = os.umask(0)
    os.umask(mask)
    assert (tmp_path / "t.gsd").stat().st_mode & 0o777 == 0o666 & ~mask  # as open() makes it, not 0600


def test_a_writer_attached_to_a_simulation_writes_on_its_trigger_and_changes_nothing(tmp_path):
    import pickle

    make = lambda: revcol.Simulation.random(80, 2, 0.3, seed=6)  # noqa: E731
    sim, twin = make(), make()
    w = open_trajectory(tmp_path / "t.gsd", sim.box, sim.periodic, 1.0)
    sim.attach(w, every=50)
    seen = []
    w(sim)  # the start, by hand
    r1 = sim.run(collisions=300, callback=seen.append, every=40)
    r2 = sim.run(collisions=300)  # the count goes on across run() calls
    w.close()
    assert r1["collisions"] == r2["collisions"] == 300 and not r1["interrupted"]
    assert seen == list(range(40, 300, 40))  # the callback's count is per run() call, not per pause
    twin.run(collisions=600)  # the pauses change nothing: bit for bit the run without them
    assert np.array_equal(sim.positions, twin.positions) and np.array_equal(sim.velocities, twin.velocities)
    assert sim.time == twin.time
    with gsd_hoomd.open(str(tmp_path / "t.gsd"), "r") as f:
        assert [int(fr.log["revcol/net_collisions"][0]) for fr in f] == list(range(0, 601, 50))
    with pytest.raises(ValueError, match="is closed"):  # a closed writer says so
        sim.run(collisions=100)
    sim.detach(w)
    sim.attach(seen.append, every=50)
    # a time-ended run stops at its time, between triggers; a callback returning False stops it
    r = sim.run(time=sim.time + 0.01)
    assert r["collisions"] < 50
    r = sim.run(collisions=1000, callback=lambda k: k < 60, every=30)
    assert r["collisions"] == 60 and r["interrupted"]
    sim.detach(seen.append)
    assert not sim.__dict__["_attached"]
    copy = pickle.loads(pickle.dumps(sim))  # the attachments are not part of the state
    assert "_attached" not in copy.__dict__
    with pytest.raises(ValueError, match="every"):
        sim.attach(w, every=0)
    with pytest.raises(TypeError, match="callable"):
        sim.attach("t.gsd", every=10)
    with pytest.raises(ValueError, match="not attached"):
        sim.detach(w)


def test_a_writer_attached_to_a_lattice_simulation(tmp_path):
    # the lattice engine takes attachments too (issue 19): frames on the trigger, and the run
    # with pauses is the run without them, bit for bit
    from revcol.lattice import LatticeSimulation
    from revcol.lattice_gas import geometry

    make = lambda: LatticeSimulation.random(80, phi=0.3, seed=6)  # noqa: E731
    sim, twin = make(), make()
    box, periodic = geometry(sim)
    w = open_trajectory(tmp_path / "t.xyz", box, periodic, 1.0)
    sim.attach(w, every=70)
    counts = []
    sim.attach(lambda s: counts.append(s.collisions), every=100)
    assert sim.run(collisions=250)["collisions"] == 250
    assert sim.run(collisions=250)["collisions"] == 250
    w.close()
    twin.run(collisions=500)
    assert np.array_equal(sim.lattice_positions, twin.lattice_positions)
    assert np.array_equal(sim.lattice_velocities, twin.lattice_velocities) and sim.clock == twin.clock
    assert counts == [100, 200, 300, 400, 500]
    frames = (tmp_path / "t.xyz").read_text().count("Lattice=")
    assert frames == len(range(70, 501, 70))
    # a time-ended run stops at its time, between triggers, and the count goes on from there
    t = sim.time
    r = sim.run(time=t + 1e-3)
    assert r["collisions"] < 100 and sim.time <= t + 1e-3 + sim.units["tick"]
    sim.detach(w)
    with pytest.raises(ValueError, match="not attached"):
        sim.detach(w)
    sim.run_back()
    assert sim.collisions == 0


def test_ase_reads_the_velocities_with_unit_masses(tmp_path):
    # docs/run.md "Trajectories in other tools": ASE keeps the file's velo column as an array;
    # with revcol's unit masses set, its velocities and kinetic energy are revcol's
    ase_io = pytest.importorskip("ase.io")
    s = revcol.Simulation.random(30, 3, 0.2, seed=4)
    s.run(collisions=50)
    w = open_trajectory(tmp_path / "t.xyz", s.box, s.periodic, 1.0)
    w.write(s.positions, s.velocities, s.time, s.collisions, "forward")
    w.close()
    atoms = ase_io.read(str(tmp_path / "t.xyz"))
    atoms.set_masses(np.ones(len(atoms)))
    atoms.set_velocities(atoms.arrays["velo"])
    assert np.abs(atoms.get_velocities() - s.velocities).max() < 1e-9
    assert atoms.get_kinetic_energy() == pytest.approx(s.diagnostics()["energy"], rel=1e-9)


@pytest.mark.parametrize("engine", ["float", "lattice"])
def test_sparse_frames_carry_the_engine_s_own_image_flags(tmp_path, engine):
    # issue 58: frames 200 collisions per particle apart (particles cross the box several times
    # between two) written from an observing simulation: their flags are the observer's crossings,
    # so the frames' unwrapped positions are the observer's, and their MSD equals its MSD to 1e-12;
    # a dense trajectory of the same run, whose inferred flags are exact, agrees at every shared frame
    pytest.importorskip("gsd.hoomd")
    from revcol.trajectory import read_gsd, true_images
    sims = [revcol.Simulation.random(60, 2, 0.2, seed=8, engine=engine) for _ in range(2)]
    sparse = open_trajectory(tmp_path / "sparse.gsd", sims[0].box, sims[0].periodic, 1.0, precise=True)
    dense = open_trajectory(tmp_path / "dense.gsd", sims[1].box, sims[1].periodic, 1.0, precise=True)
    sims[0].observe()
    seen = []  # the observer's own unwrapped positions at each sparse frame

    def look(sim):
        seen.append(sim._e.observed_positions())
    for s, w, every, also in ((sims[0], sparse, 6000, look), (sims[1], dense, 20, None)):
        w(s)  # the first frame, at the start
        s.attach(w, every=every)
        if also is not None:
            also(s)
            s.attach(also, every=every)
    for s in sims:
        s.run(collisions=30_000)
    u = seen[-1]
    assert np.abs(true_images(sims[0])).max() >= 2  # crossings, several box lengths: sparse indeed
    for w in (sparse, dense):
        w.close()
    a, b = read_gsd(tmp_path / "sparse.gsd"), read_gsd(tmp_path / "dense.gsd")
    assert len(seen) == len(a["net_collisions"]) == 6  # at 0, 6000, ..., 30000
    assert np.abs(a["unwrapped"][-1] - u).max() < 1e-9
    # the MSD from the first frame to the last, from the file and from the observer
    msd_frames = float(np.mean(np.sum((a["unwrapped"][-1] - a["unwrapped"][0]) ** 2, axis=1)))
    msd_observer = float(np.mean(np.sum((u - seen[0]) ** 2, axis=1)))
    assert msd_frames == pytest.approx(msd_observer, rel=1e-12)
    shared = np.isin(b["net_collisions"], a["net_collisions"])
    assert shared.sum() == len(a["net_collisions"])  # the same run: the same states at the same counts
    assert np.array_equal(b["image"][shared], a["image"])


def test_xyz_frames_of_a_periodic_box_carry_the_same_image_flags_as_gsd(tmp_path):
    # the XYZ writer's image column (a periodic box only): the flags GSD writes for the same frames
    pytest.importorskip("gsd.hoomd")
    from revcol.trajectory import read_gsd
    s = revcol.Simulation.random(40, 2, 0.2, seed=5, boundary=["periodic", "wall"])
    s.observe()
    ws = [open_trajectory(tmp_path / f"t.{ext}", s.box, s.periodic, 1.0) for ext in ("xyz", "gsd")]
    for w in ws:
        w(s)
        s.attach(w, every=4000)
    s.run(collisions=20_000)
    for w in ws:
        w.close()
    lines = (tmp_path / "t.xyz").read_text().splitlines()
    assert "Properties=species:S:1:pos:R:3:velo:R:3:radius:R:1:image:I:3" in lines[1]
    frames, i = [], 0
    while i < len(lines):
        n = int(lines[i])
        frames.append(np.array([[int(w) for w in ln.split()[8:11]] for ln in lines[i + 2:i + 2 + n]]))
        i += n + 2
    g = read_gsd(tmp_path / "t.gsd")
    assert len(frames) == len(g["image"]) == 6
    assert np.abs(g["image"]).max() >= 1 and all(np.array_equal(a[:, :2], b) for a, b in zip(frames, g["image"]))
    walled = open_trajectory(tmp_path / "w.xyz", [5.0, 5.0], [False, False], 1.0)
    walled.write(np.array([[1.0, 1.0]]), np.zeros((1, 2)), 0.0, 0, "forward")
    walled.close()
    assert ":image:" not in (tmp_path / "w.xyz").read_text().splitlines()[1]
