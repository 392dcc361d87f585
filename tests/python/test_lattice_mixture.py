"""Mixtures on the lattice engine from Python (equal masses, one radius per particle): binary
and polydisperse starts, forward and back bit for bit, checkpoints that keep the sizes, arrays
that fit only with their sizes, bad input refused by name; the equation of state of a binary
mixture against BMCSL (spheres) and SLHY (disks) in a reduced run of the study's code path
(the full runs: bench/results/mixture_eos.json, docs/mixtures.md)."""
import numpy as np
import pytest

from revcol import Simulation
from revcol.lattice import LatticeSimulation, LatticeSimulation3D
from revcol.studies.mixture_eos import binary_diameters, bmcsl_z, measure, slhy_z
from revcol.studies.eos import carnahan_starling, liu_disks


@pytest.mark.parametrize("cls,phi", [(LatticeSimulation, 0.5), (LatticeSimulation3D, 0.4)])
def test_binary_mixture_runs_back_bit_for_bit(cls, phi):
    d = binary_diameters(400, 1.4)
    sim = cls.random(400, phi=phi, diameters=d, seed=5)
    assert sim.mixture
    # the largest is sigma exactly; the small ones quantized to even lattice lengths
    sigma = int(sim.units["sigma"])
    assert (sim.radii[::2] == sigma // 2).all()
    assert np.allclose(sim.diameters[1::2], 1 / 1.4, rtol=0, atol=2.0 ** -40)
    assert np.isclose(np.sum(np.pi / 6 * sim.diameters**3) if cls is LatticeSimulation3D
                      else np.sum(np.pi / 4 * sim.diameters**2), phi * np.prod(sim.box), rtol=1e-9)
    x0, v0 = sim.lattice_positions.copy(), sim.lattice_velocities.copy()
    sim.run(collisions=4000)
    mid = sim.snapshot()
    sim.run(collisions=4000)
    sim.run_back(collisions=4000)
    again = sim.snapshot()
    assert all(np.array_equal(np.asarray(mid[k]), np.asarray(again[k])) for k in ("x", "v", "bits", "radius", "streams"))
    sim.run_back()
    assert np.array_equal(sim.lattice_positions, x0) and np.array_equal(sim.lattice_velocities, v0)


def test_polydisperse_and_the_facade(tmp_path):
    rng = np.random.default_rng(3)
    d = np.clip(rng.normal(1.0, 0.1, 300), 0.7, 1.3)
    sim = Simulation.random(300, dim=2, phi=0.4, engine="lattice", diameters=d, seed=2, mode="specular")
    assert isinstance(sim, LatticeSimulation) and sim.mixture
    # each diameter within one lattice unit of what was asked (relative to the largest)
    assert np.allclose(sim.diameters / d.max(), d / d.max(), atol=2.0 ** -38)
    sim.run(collisions=3000)
    path = tmp_path / "poly.npz"
    sim.save(path)
    back = LatticeSimulation.load(path)
    assert np.array_equal(back.radii, sim.radii)
    sim.run(collisions=2000)
    back.run(collisions=2000)
    assert np.array_equal(back.lattice_positions, sim.lattice_positions)
    # the float engine takes the same diameters (tests/python/test_float_mixture.py)
    f = Simulation.random(10, dim=2, phi=0.2, diameters=np.ones(10))
    assert f.engine == "float" and f.mixture


def test_arrays_that_fit_only_with_their_sizes():
    # two small disks 0.8 apart: apart as disks of 0.75, overlapping as disks of 1
    x = np.array([[2.0, 2.0], [2.8, 2.0], [4.5, 4.5]])
    v = np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 0.5]])
    sim = LatticeSimulation(x, v, 6.0, diameters=[0.75, 0.75, 1.0])
    assert sim.mixture and not LatticeSimulation(x[2:], v[2:], 6.0).mixture
    sim.run(collisions=1)
    assert sim.collisions == 1
    with pytest.raises(ValueError, match="overlap"):
        LatticeSimulation(x, v, 6.0)


def test_bad_diameters_are_refused_by_name():
    x = np.array([[1.0, 1.0], [3.0, 3.0]])
    v = np.array([[1.0, 0.0], [-1.0, 0.0]])
    with pytest.raises(ValueError, match="one entry per particle"):
        LatticeSimulation(x, v, 5.0, diameters=[1.0])
    with pytest.raises(ValueError, match="not both"):
        LatticeSimulation(x, v, 5.0, diameter=2.0, diameters=[1.0, 1.0])
    with pytest.raises(ValueError, match="finite and > 0"):
        LatticeSimulation(x, v, 5.0, diameters=[1.0, -1.0])
    with pytest.raises(ValueError, match="sigma / 32"):
        LatticeSimulation(x, v, 5.0, diameters=[1.0, 0.05])
    with pytest.raises(ValueError, match="one entry per particle"):
        LatticeSimulation3D.random(20, phi=0.2, diameters=np.ones(19))


def test_mixture_theories_reduce_to_the_pure_fluid():
    for phi in (0.1, 0.3, 0.45):
        assert bmcsl_z(phi, [1.0, 1.0]) == pytest.approx(carnahan_starling(phi), rel=1e-12)
        assert slhy_z(phi, [2.0]) == pytest.approx(liu_disks(phi), rel=1e-12)
    # a size spread lowers Z at a given packing fraction (BMCSL and SLHY alike)
    assert bmcsl_z(0.4, binary_diameters(2, 1.4)) < carnahan_starling(0.4)
    assert slhy_z(0.5, binary_diameters(2, 1.4)) < liu_disks(0.5)


@pytest.mark.parametrize("dim,phi", [(2, 0.5), (3, 0.4)])
def test_equation_of_state_reduced(dim, phi):
    # N = 1000, 300 collisions per particle observed: the full study (N = 4000, four seeds) is in
    # bench/results/mixture_eos.json. Within 3 block errors of the theory (stated there)
    r = measure(dim, 1000, phi, 1.4, equilibrate=60, collisions=300, seed=1, ecmc=400, float_md=True)
    assert r["back_to_start"]
    assert r["blocks"] >= 16
    assert abs(r["deviation_sd"]) < 3.0, r
    # the event-chain sampler of the same mixture at the same N (no theory): within 3 combined errors
    assert r["ecmc"]["min_distance"] >= 1.0 - 1e-9
    assert r["ecmc"]["z_md"][1] < 0.02
    assert abs(r["ecmc_deviation_sd"]) < 3.0, r["ecmc"]
    # the float engine's run of the same particles from the same start: within 3 combined errors,
    # and within 3 of its own errors of the theory
    f = r["float"]
    assert abs(r["float_deviation_sd"]) < 3.0, f
    assert abs(f["z"] - r["z_theory"]) < 3.0 * f["z_error"], f
    assert abs(f["energy_drift"]) < 1e-12


def _mixture_scene(extra: str = "", system: str = "particles = 400\n") -> dict:
    import tomllib
    text = ("[system]\ndimension = 2\npacking_fraction = 0.35\nboundaries = \"periodic\"\n" + system +
            "[collisions]\nengine = \"lattice\"\n[run]\ncollisions = 3000\n"
            "[[species]]\nname = \"big\"\ndiameter = 1.0\nfraction = 0.25\n"
            "[[species]]\nname = \"small\"\ndiameter = 0.8\nfraction = 0.75\n" + extra)
    return tomllib.loads(text)


def test_scene_species_table_builds_the_mixture(tmp_path):
    from revcol.lattice_gas import build_lattice
    from revcol.scene import SceneError, lattice_options, scene_from_dict
    scene = scene_from_dict(_mixture_scene(), "mix.toml")
    assert [(s.name, s.count) for s in scene.species] == [("big", 100), ("small", 300)]
    from revcol.gas import build_simulation
    from revcol.scene import with_engine
    flt = build_simulation(with_engine(scene, "float"))  # (revcol run --engine float): the same mixture
    assert flt.engine == "float" and np.array_equal(np.unique(flt.diameters), [0.8, 1.0])
    assert "100 big (d = 1), 300 small (d = 0.8)" in scene.summary()
    # the box from the species' own areas at the packing fraction
    area = 100 * np.pi / 4 + 300 * np.pi / 4 * 0.64
    assert scene.box[0] == pytest.approx(np.sqrt(area / 0.35), rel=1e-12)
    sim = build_lattice(scene)
    assert sim.mixture and np.allclose(np.sort(np.unique(sim.diameters)), [0.8, 1.0], atol=2.0 ** -40)
    assert np.allclose(sim.box, scene.box, rtol=1e-12)
    assert "diameters" in lattice_options(scene)
    # counts instead of fractions, and the errors, each naming its field
    counted = _mixture_scene(system="").copy()
    counted["species"] = [{"name": "a", "diameter": 1.0, "count": 7}, {"name": "b", "diameter": 0.8, "count": 5}]
    assert scene_from_dict(counted, "c.toml").particles == 12
    bad = [({"system": {"diameter": 1.0}}, "not both"),
           ({"species": [{"name": "a", "diameter": 1.0, "fraction": 0.5}]}, "add up to 1"),
           ({"species": [{"name": "a", "diameter": 1.0, "count": 3, "charge": 2.0}]}, "unknown field"),
           ({"species": [{"name": "a", "diameter": 1.0, "fraction": 1.0, "mass": -2.0}]}, "mass"),
           ({"species": [{"name": "a", "diameter": -1.0, "count": 3}]}, "diameter"),
           ({"species": [{"name": "a", "diameter": 1.0, "count": 3}, {"name": "a", "diameter": 0.5, "count": 3}]},
            "unique")]
    for change, what in bad:
        doc = _mixture_scene()
        for table, fields in change.items():
            doc[table] = fields if table == "species" else {**doc.get(table, {}), **fields}
        with pytest.raises(SceneError, match=what):
            scene_from_dict(doc, "bad.toml")


@pytest.mark.parametrize("engine", ["lattice", "float"])
def test_mixture_trajectory_carries_types_and_diameters(tmp_path, engine):
    gsd_hoomd = pytest.importorskip("gsd.hoomd")
    from revcol.gas import run_gas
    from revcol.scene import scene_from_dict
    doc = _mixture_scene("[output]\ntrajectory_every = 1000\n")
    doc["collisions"]["engine"] = engine
    scene = scene_from_dict(doc, str(tmp_path / "mix.toml"))
    run_gas(scene, trajectory=tmp_path / "mix.gsd", progress=False, checkpoints=False)
    with gsd_hoomd.open(str(tmp_path / "mix.gsd")) as t:
        f = t[0]
        assert f.particles.types == ["big", "small"]
        assert np.bincount(f.particles.typeid).tolist() == [100, 300]
        assert np.allclose(np.unique(f.particles.diameter), [0.8, 1.0], atol=1e-6)


def test_partial_structure_and_contact_values_from_rates():
    # the study's frames path at N = 1000: the partial g of one species equals the g of the gas;
    # the contact values from the collision rates, through the virial route, give the collision
    # virial's Z within 3 of its block errors (two estimators of the same collisions)
    from revcol.observe import radial_distribution
    from revcol.observe_species import partial_radial_distribution
    r = measure(3, 1000, 0.4, 1.4, equilibrate=40, collisions=150, seed=2, frames=10)
    assert abs(r["z_from_contact"] - r["z"]) < 3.0 * r["z_error"], r
    assert len(r["contact"]) == 3 and all(c["collisions"] > 1000 for c in r["contact"])
    assert abs(r["temperatures"][0] - r["temperatures"][1]) < 0.05
    rng = np.random.default_rng(4)
    frames = rng.uniform(0.0, 6.0, size=(3, 200, 3))
    r1, g1 = radial_distribution(frames, [6.0] * 3, bins=30, r_max=3.0, use_freud=False)
    r2, g2 = partial_radial_distribution(frames, [6.0] * 3, np.zeros(200, dtype=int), bins=30, r_max=3.0)
    assert np.allclose(r1, r2) and np.allclose(g1, g2[0, 0], rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("cls,boundary", [(LatticeSimulation, "periodic"), (LatticeSimulation3D, "wall")])
def test_the_observer_reports_each_species(cls, boundary, tmp_path):
    """Per species temperature, partial pressure and MSD (ascending diameter): they add up to
    the gas's own (partial pressures to P_virial, count-weighted MSD and temperatures to the
    whole's, to round-off); equipartition within 4 block errors; a snapshot resumes them bit
    for bit; a one-size gas reports none."""
    import pickle
    d = binary_diameters(600, 1.4)
    sim = cls.random(600, phi=0.35, diameters=d, seed=8, boundary=boundary)
    sim.run(collisions=6000)
    sim.observe(block_time=0.05)
    sim.run(collisions=20000)
    snap = sim.snapshot()
    copy = pickle.loads(pickle.dumps(sim))
    sim.save(tmp_path / "m.npz")
    sim.run(collisions=30000)
    o = sim.observation()
    assert np.allclose(o.species_diameter, [1 / 1.4, 1.0], rtol=1e-9) and o.species_count.tolist() == [300, 300]
    assert sum(e.value for e in o.species_pressure) == pytest.approx(o.pressure_virial.value, rel=1e-12)
    assert o.species_msd.shape == (len(o.msd), 2)
    assert np.allclose(o.species_msd @ o.species_count / 600, o.msd, rtol=1e-12)
    assert o.species_msd[-1, 0] > o.species_msd[-1, 1]  # the small ones diffuse faster
    t = [e.value for e in o.species_temperature]
    assert np.dot(t, o.species_count) / 600 == pytest.approx(o.temperature.value, rel=1e-12)
    for e in o.species_temperature:
        assert abs(e.value - o.temperature.value) < 4 * e.error, o.species_temperature
    assert any("species d=0.7143 (300)" in line for line in o.lines())
    want = o.to_dict()
    assert len(want["species_pressure"]) == 2
    for resumed in (cls.from_snapshot(snap), cls.load(tmp_path / "m.npz"), copy):
        resumed.run(collisions=30000)
        assert resumed.observation().to_dict() == want
    one = cls.random(200, phi=0.3, seed=2)
    one.observe()
    one.run(collisions=2000)
    assert one.observation().species_temperature == [] and one.observation().species_msd.size == 0
    # a polydisperse sample (more than 16 sizes) has no species: its hooks keep no per-species sums
    from revcol.studies.mixture_eos import gaussian_diameters
    poly = cls.random(200, phi=0.3, diameters=gaussian_diameters(200, 3), seed=2, boundary=boundary)
    poly.observe()
    poly.run(collisions=2000)
    assert poly.mixture and poly.observation().species_count.size == 0


def test_the_wall_virial_takes_each_particle_its_own_radius():
    """Two particles of diameters 1 and 1/2 flying along x between walls, never meeting: each
    one's wall virial balances its kinetic term over whole flights only if its contact plane
    is its own radius from the wall (with the larger one's, the small one's 1/4 offset leaves
    (K2 + W_wall) / K2 at 0.06 here)."""
    x = np.array([[2.0, 1.5], [2.5, 4.0]])
    v = np.array([[1.0, 0.0], [0.7, 0.0]])
    sim = LatticeSimulation(x, v, [6.0, 6.0], boundary="wall", diameters=[0.5, 1.0])
    sim.observe(block_time=1.0)
    sim.run(time=2000.0)
    o = sim.observation()
    assert o.wall_reflections > 500 and o.pair_collisions == 0
    assert abs(o.virial_balance.value) < 2e-3, o.virial_balance


def test_the_parallel_engine_observes_the_species_of_the_sequential_run():
    """4 logical processes on 2 workers (oversubscribed): the committed observation, species
    included, is the sequential one bit for bit."""
    out = []
    for workers, lps in ((1, 1), (2, 4)):
        sim = LatticeSimulation3D.random(800, phi=0.35, diameters=binary_diameters(800, 1.4), seed=4, boundary="wall")
        sim.set_parallel(workers, lps=lps)
        sim.run(collisions=3000)
        sim.observe(block_time=0.05)
        sim.run(collisions=12000)
        out.append(sim.observation().to_dict())
    assert len(out[0]["species_pressure"]) == 2 and out[0] == out[1]
