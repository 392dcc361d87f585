"""Simulation.observe: the Python API, bad input named and harmless, forward-only observation,
g(r) from frames (numpy fallback), the scene's [observe] table and its values in `revcol run`."""
import json

import numpy as np
import pytest

import revcol
from revcol.cli.main import main as cli_main
from revcol.observe import Estimate, Observation, radial_distribution
from revcol.studies.scenes import run_scene
from revcol.scene import SceneError, scene_from_dict


def gas(**kw):
    return revcol.Simulation.random(n=300, dim=2, phi=0.4, seed=11, **kw)


def test_observation_values_and_errors():
    sim = gas(mode="specular")
    assert sim.observation() is None and not sim.observing
    sim.run(collisions=3000)
    sim.observe(speed_bins=30, slabs=4)
    sim.run(collisions=30000)
    o = sim.observation()
    assert isinstance(o, Observation) and sim.observing
    assert o.particle_collisions == 60000 and o.blocks >= 16
    e = sim.diagnostics()["energy"]
    assert o.temperature.value == pytest.approx(e / 300, rel=1e-12)  # T = 2E / (d N), energy conserved
    for est in (o.compressibility, o.collision_rate, o.mean_free_time, o.mean_free_path, o.pressure_virial):
        assert isinstance(est, Estimate) and est.error > 0 and 0 < est.error < 0.05 * abs(est.value)
    assert o.mean_free_time.value == pytest.approx(1.0 / o.collision_rate.value, rel=1e-12)
    # the speed histogram is a probability density; slabs of a periodic box hold n / V each
    assert np.sum(o.speed.value * np.diff(o.speed.edges)) == pytest.approx(1.0, abs=1e-3)
    assert np.allclose(o.slab_density.value, 300 / np.prod(sim.box), rtol=0.05)
    assert o.msd.size > 0 and np.all(np.diff(o.msd) > -1e-9 * o.msd[-1])  # grows (diffusion)
    d = o.to_dict()
    json.dumps(d)
    assert d["compressibility"] == [o.compressibility.value, o.compressibility.error]


def test_observing_changes_no_bit_and_run_back_ends_it():
    a, b = gas(), gas()
    b.observe(speed_bins=10)
    a.run(collisions=2000)
    b.run(collisions=2000)
    assert np.array_equal(a.positions, b.positions) and np.array_equal(a.velocities, b.velocities)
    before = b.observation().to_dict()
    b.run_back(collisions=500)
    assert not b.observing
    b.run(collisions=500)
    assert b.observation().to_dict() == before


def _direct_sums(sim, collisions, D=1.0):
    """The virial sums of the next ``collisions`` collisions straight from the engine's states,
    one collision per ``run`` call (a call ends half way between its collision and the next
    event, so nothing changes a velocity after the collision's instant within a step). Each
    pair's contact vector is taken at contact: its post-collision relative line traced back
    to |r| = D (taking r at the step's end instead adds s w_post . dv > 0 per collision and
    puts such a sum about 1 / N above the observer's Z). Reflections are found from the
    velocity changes (specular walls flip one component; the wall is the one it points away
    from). Returns the collision virial W, the wall virial, the wall impulses per axis and
    K2 = the integral of sum |v|^2 dt over the steps."""
    box, per = np.asarray(sim.box), np.asarray(sim.periodic)
    lo, hi, tol = 0.5 * D, box - 0.5 * D, 1e-9 * D

    def nearest(r):
        return np.where(per, r - box * np.round(r / box), r)

    out = {"w": 0.0, "w_wall": 0.0, "k2": 0.0, "dp": np.zeros(sim.dim), "steps": []}
    pairs = [(a, b) for a in range(sim.dim) for b in range(a + 1, sim.dim)]  # the Helfand components

    def off(v):  # sum_i v_ia v_ib per component a < b
        return np.array([np.sum(v[:, a] * v[:, b]) for a, b in pairs])

    def walls(q, dv):  # a reflection's impulse dv (walled axes only) on q
        for k in np.nonzero(dv != 0.0)[0]:
            assert not per[k]
            out["w_wall"] += (lo if dv[k] > 0 else hi[k]) * dv[k]
            out["dp"][k] += abs(dv[k])

    x0, v0, t0, c0 = sim.positions, sim.velocities, sim.time, sim.collision_counts
    for _ in range(collisions):
        assert sim.run(collisions=1)["collisions"] == 1
        x1, v1, t1, c1 = sim.positions, sim.velocities, sim.time, sim.collision_counts
        i, j = np.nonzero(c1 != c0)[0]  # a pair (these gases make no group)
        r1, w1 = nearest(x1[i] - x1[j]), v1[i] - v1[j]
        a, b, c = w1 @ w1, r1 @ w1, r1 @ r1 - D * D
        back = c / (b + np.sqrt(b * b - a * c))  # t1 - t_contact (the cancellation-free root)
        rc, tc = r1 - w1 * back, t1 - back
        touched = []  # i or j reflected in the step: on a wall at contact, or crossed one before
        for q in (i, j):
            at, pre = x1[q] - v1[q] * back, x0[q] + v0[q] * (tc - t0)
            if np.any(~per & ((np.minimum(at, pre) < lo + tol) | (np.maximum(at, pre) > hi - tol))):
                touched.append(q)
        assert len(touched) < 2
        dv_i, dv_j = v1[i] - v0[i], v1[j] - v0[j]
        if touched == [i]:  # the pair's impulse on i is then -(j's change); the rest is walls
            walls(i, dv_i + dv_j)
            dv_i = -dv_j
        elif touched == [j]:
            walls(j, dv_i + dv_j)
        out["w"] += rc @ dv_i
        for q in np.nonzero(np.any(v1 != v0, axis=1))[0]:
            if q != i and q != j:
                walls(q, v1[q] - v0[q])
        out["k2"] += np.sum(v0 * v0) * (tc - t0) + np.sum(v1 * v1) * (t1 - tc)  # walls keep |v|
        # the Helfand moment's pieces (periodic boxes: no other velocity change in the step)
        out["steps"].append((t0, tc, t1, off(v0), off(v1), np.array([rc[a] * dv_i[b] for a, b in pairs])))
        x0, v0, t0, c0 = x1, v1, t1, c1
    return out


def _helfand_at(steps, te):
    """The direct Helfand moment (per component) at time te from _direct_sums' steps, and the
    sum of its terms' sizes (the scale of round-off)."""
    I, size = 0.0, 0.0
    for t0, tc, t1, pre, post, kick in steps:
        if te <= t0:
            break
        parts = [pre * (min(te, tc) - t0)]
        if te > tc:
            parts += [kick, post * (min(te, t1) - tc)]
        for q in parts:
            I, size = I + q, size + np.abs(q)
    return I, size


def _check_helfand(o, steps):
    """Every recorded I_ab equals the direct sum at its block end to 1e-9 of its terms' sizes."""
    assert o.helfand.shape == (len(o.msd_time), o.dim * (o.dim - 1) // 2) and len(o.msd_time) > 5
    for t, got in zip(o.msd_time, o.helfand):
        want, size = _helfand_at(steps, o.t_start + t)
        assert np.all(np.abs(got - want) <= 1e-9 * size), (got, want)


def _observed_sums(o, box):
    """K2, W, the wall virial and the wall impulses from an observation's results."""
    d, tau, vol = o.dim, o.t_end - o.t_start, float(np.prod(box))
    k2 = o.temperature.value * d * o.n * tau
    w = (o.compressibility.value - 1.0) * k2
    dp = [o.pressure_wall[k].value * 2.0 * tau * vol / box[k] for k in range(d)]
    return {"k2": k2, "w": w, "w_wall": o.virial_balance.value * k2 - k2 - w, "dp": np.array(dp),
            "p": o.pressure_virial.value * d * vol * tau}


@pytest.mark.parametrize("phi, boundary, mode", [
    (0.5, "periodic", "exact"), (0.3, "wall", "exact"), (0.5, "periodic", "specular"), (0.3, "wall", "specular")])
def test_observed_virial_equals_the_direct_sum_over_collisions(phi, boundary, mode):
    """On one trajectory the observer's K2, collision virial W (hence Z and the virial
    pressure), wall virial and wall impulses equal the direct sums over the engine's
    collisions and reflections (_direct_sums) to 1e-9 relative: observed one collision per
    call, and in one call from the same state (the first segment from the observe instant,
    the last to half way to the next event, block ends and block merges in between)."""
    sim = revcol.Simulation.random(n=400, dim=2, phi=phi, boundary=boundary, mode=mode, seed=3)
    sim.run(collisions=4000)
    start = sim.snapshot()
    config = {"block_time": 0.003, "slabs": 5, "speed_bins": 20}  # > 256 blocks: they merge
    sim.observe(**config)
    direct = _direct_sums(sim, 3000)
    whole = revcol.Simulation.from_snapshot(start)
    whole.observe(**config)
    whole.run(collisions=3000)
    assert whole.time == sim.time and np.array_equal(whole.velocities, sim.velocities)
    box = np.asarray(sim.box)
    for o in (sim.observation(), whole.observation()):
        assert o.pair_collisions == 3000 and o.group_collisions == 0
        seen = _observed_sums(o, box)
        assert seen["k2"] == pytest.approx(direct["k2"], rel=1e-9)
        assert seen["w"] == pytest.approx(direct["w"], rel=1e-9)
        assert seen["p"] == pytest.approx(direct["k2"] + direct["w"], rel=1e-9)
        assert o.compressibility.value == pytest.approx(1.0 + direct["w"] / direct["k2"], rel=1e-9)
        if boundary == "wall":
            assert o.wall_reflections > 0
            assert seen["w_wall"] == pytest.approx(direct["w_wall"], rel=1e-9)
            assert seen["dp"] == pytest.approx(direct["dp"], rel=1e-9)
        else:
            assert direct["w_wall"] == 0.0 and seen["w_wall"] == pytest.approx(0.0, abs=1e-12 * direct["k2"])
            _check_helfand(o, direct["steps"])
    assert whole.observation().blocks >= 16


def test_helfand_moment_equals_the_direct_sum_3d():
    """3D specular spheres, periodic: the three recorded I_xy, I_xz, I_yz at every block end
    equal the direct sums over the engine's collisions (the kinetic integral between them and
    r_a Delta p_b at contact); the collisions' terms are symmetric (central impulses)."""
    sim = revcol.Simulation.random(n=150, dim=3, phi=0.35, mode="specular", seed=4)
    sim.run(collisions=2000)
    sim.observe(block_time=0.01)
    direct = _direct_sums(sim, 1500)
    o = sim.observation()
    _check_helfand(o, direct["steps"])
    assert np.all(np.abs(o.helfand[-1]) > 0)


@pytest.mark.parametrize("kwargs, error, word", [
    ({"speed_bins": -1}, ValueError, "speed_bins"),
    ({"speed_bins": 2.5}, TypeError, "speed_bins"),
    ({"slabs": "4"}, TypeError, "slabs"),
    ({"block_time": -1.0}, ValueError, "block_time"),
    ({"block_time": "x"}, TypeError, "block_time"),
    ({"min_blocks": 1}, ValueError, "min_blocks"),
    ({"slabs": 2, "slab_axis": 2}, ValueError, "slab_axis"),
    ({"pair_bins": 10, "pair_rmax": 1.0}, ValueError, "pair distances"),
    ({"pair_bins": 10}, ValueError, "pair_rmax"),
    ({"speed_max": float("nan")}, ValueError, "speed_max"),
])
def test_bad_input_is_named_and_changes_nothing(kwargs, error, word):
    sim = gas()
    sim.observe()
    sim.run(collisions=500)
    before = sim.observation().to_dict()
    with pytest.raises(error, match=word):
        sim.observe(**kwargs)
    assert sim.observing and sim.observation().to_dict() == before


def test_radial_distribution_numpy_fallback():
    rng = np.random.default_rng(1)
    r, g = radial_distribution(rng.random((20, 400, 2)) * 10.0, [10.0, 10.0], bins=25, r_max=5.0, use_freud=False)
    assert np.allclose(g[5:], 1.0, atol=0.06)  # ideal gas: g = 1
    sim = revcol.Simulation.random(n=400, dim=2, phi=0.5, seed=2, mode="specular")
    sim.run(collisions=4000)
    frames = []
    for _ in range(5):
        sim.run(collisions=400)
        frames.append(sim.positions)
    r, g = radial_distribution(frames, sim.box, bins=50, r_max=3.0, use_freud=False)
    assert np.all(g[r < 0.97] == 0.0)  # hard disks never overlap
    assert g[(r > 1.0) & (r < 1.06)].max() > 2.0  # the contact peak
    with pytest.raises(ValueError, match="diameter"):  # a walled axis: the centres' region needs D
        radial_distribution(frames, sim.box, periodic=[True, False])
    with pytest.raises(ValueError, match="r_max"):
        radial_distribution(frames, sim.box, r_max=100.0)


def test_snapshot_resumes_the_observation_bit_for_bit(tmp_path):
    """observe, run, snapshot (dict, file, pickle), run: the resumed runs' results equal the
    uninterrupted run's exactly; a snapshot without the observer keys (an older one) loads
    with no observation; a spoiled observer entry is a named error."""
    import pickle

    sim = revcol.Simulation.random(n=120, dim=2, phi=0.4, seed=5, boundary="wall")
    sim.run(collisions=2000)
    sim.observe(speed_bins=20, slabs=4, block_time=0.01)
    sim.run(collisions=3000)
    snap = sim.snapshot()
    assert len(snap["observer"]) > 0 and len(snap["observer_counts"]) > 0
    sim.save(tmp_path / "c.npz")
    copy = pickle.loads(pickle.dumps(sim))
    sim.run(collisions=4000)
    want = sim.observation().to_dict()
    for resumed in (revcol.Simulation.from_snapshot(snap), revcol.Simulation.load(tmp_path / "c.npz"), copy):
        assert resumed.observing
        resumed.run(collisions=4000)
        assert resumed.observation().to_dict() == want
    old = {k: v for k, v in snap.items() if k not in ("observer", "observer_counts")}
    plain = revcol.Simulation.from_snapshot(old)
    assert not plain.observing and plain.observation() is None
    bad = dict(snap)
    bad["observer"] = np.asarray(snap["observer"])[:-1]
    with pytest.raises(ValueError, match="observer"):
        revcol.Simulation.from_snapshot(bad)


def test_velocity_autocorrelation_at_block_ends():
    """vacf[k] = (1/N) sum_i v_i(t_start) . v_i(t_k) at each block end t_k (msd_time): a run
    that stops on a block end gives the same number from the velocities it stops with; it
    starts near d T and decays; a snapshot keeps it, and one written without it (older)
    resumes the other observables with no VACF."""
    sim = revcol.Simulation.random(n=200, dim=2, phi=0.3, seed=8, mode="specular")
    sim.run(collisions=2000)
    v0, t0, bt = sim.velocities, sim.time, 0.05
    sim.observe(block_time=bt)
    te = t0
    for _ in range(7):  # the 7th block end as the observer sums it
        te += bt
    sim.run(time=te)
    o = sim.observation()
    assert len(o.vacf) == len(o.msd) == len(o.msd_time) == 7
    direct = float(np.sum(v0 * sim.velocities)) / sim.n
    assert o.vacf[-1] == pytest.approx(direct, rel=1e-12, abs=1e-12)
    assert 0 < o.vacf[0] <= 2 * o.temperature.value * 1.0001
    sim.run(time=t0 + 300 * bt)  # many collision times: the correlation is gone
    o = sim.observation()
    assert abs(o.vacf[-1]) < 0.2 * o.vacf[0]
    # lattice engine: the same observable
    lat = revcol.Simulation.random(n=200, dim=2, phi=0.3, seed=8, engine="lattice")
    lat.observe(block_time=bt)
    lat.run(collisions=5000)
    assert len(lat.observation().vacf) == len(lat.observation().msd) > 0
    # snapshots: kept; an older observer entry (without start velocities and VACF) resumes without it
    snap = sim.snapshot()
    assert np.array_equal(revcol.Simulation.from_snapshot(snap).observation().vacf, o.vacf)
    # the Helfand moment follows: its values and running sums (1 each in 2D), then its record
    helf = 2 + len(o.helfand)
    assert np.array_equal(revcol.Simulation.from_snapshot(snap).observation().helfand, o.helfand)
    old = dict(snap)
    old["observer"] = np.asarray(snap["observer"])[: -(sim.n * sim.dim + len(o.vacf) + helf)]
    resumed = revcol.Simulation.from_snapshot(old)
    assert resumed.observing and len(resumed.observation().vacf) == 0 and len(resumed.observation().helfand) == 0
    assert np.array_equal(resumed.observation().msd, o.msd)
    no_helfand = dict(snap)  # written with the VACF, before the Helfand moment
    no_helfand["observer"] = np.asarray(snap["observer"])[:-helf]
    resumed = revcol.Simulation.from_snapshot(no_helfand)
    assert np.array_equal(resumed.observation().vacf, o.vacf) and resumed.observation().helfand.shape == (0, 1)
    resumed.run(collisions=500)
    assert len(resumed.observation().helfand) == 0 and len(resumed.observation().vacf) > len(o.vacf)


def _batched_rdf(points, box, batches, **kw):
    """g(r) of each batch of frames: the mean and its standard error over the batches."""
    gs = []
    for part in np.array_split(points, batches):
        r, g = radial_distribution(part, box, **kw)
        gs.append(g)
    gs = np.asarray(gs)
    return r, gs.mean(0), gs.std(0, ddof=1) / np.sqrt(batches)


@pytest.mark.parametrize("d", [2, 3])
def test_radial_distribution_walled_box_ideal_gas(d):
    """Uniform points in a walled box: g(r) = 1 within its error at every r up to r_max,
    with each reference point's shell cut by the walls; the periodic normalization (the
    whole shell) fails the same test near r_max (its ideal count is too large there)."""
    rng = np.random.default_rng(7 + d)
    D = 0.5
    L = np.array([8.0, 9.0, 10.0][:d])
    n, frames, batches = (300, 48, 12) if d == 2 else (250, 48, 12)
    pts = D / 2 + rng.random((frames, n, d)) * (L - D)  # centres in [D/2, L - D/2]
    r_max = 0.5 * float((L - D).min())
    kw = dict(bins=20, r_max=r_max, periodic=[False] * d, diameter=D)
    r, g, err = _batched_rdf(pts, L, batches, **kw)
    assert np.all(err > 0)
    assert np.all(np.abs(g - 1.0) < 4.0 * err), (g - 1.0) / err
    # the same pairs normalized by the whole shell (no walls): g falls well below 1 near r_max
    edges = np.linspace(0.0, r_max, 21)
    shell = np.diff(np.pi * edges ** 2 if d == 2 else 4.0 / 3.0 * np.pi * edges ** 3)
    gp = []
    for part in np.array_split(pts, batches):
        c = np.zeros(20)
        for f in part:
            dr = np.sqrt(((f[:, None, :] - f[None, :, :]) ** 2).sum(-1))
            c += np.histogram(dr[dr > 0], bins=edges)[0]
        gp.append(c / (len(part) * n * (n - 1) / np.prod(L - D) * shell))
    gp = np.asarray(gp)
    gpm, gpe = gp.mean(0), gp.std(0, ddof=1) / np.sqrt(batches)
    assert (1.0 - gpm[-1]) > 10.0 * gpe[-1]  # the periodic normalization misses by > 10 SE


def test_radial_distribution_walled_box_arguments():
    pts = np.random.default_rng(3).random((2, 50, 2)) * 4.0
    with pytest.raises(ValueError, match="diameter"):
        radial_distribution(pts, [4.0, 4.0], periodic=[False, True])
    with pytest.raises(ValueError, match="r_max"):
        radial_distribution(pts, [4.0, 4.0], periodic=[False, True], diameter=1.0, r_max=1.6)
    with pytest.raises(ValueError, match="freud"):
        radial_distribution(pts, [4.0, 4.0], periodic=[False, False], diameter=0.0, use_freud=True)
    r, g = radial_distribution(pts, [4.0, 4.0], periodic=[False, True], diameter=1.0, bins=5)
    assert r[-1] < 1.5 and g.shape == (5,)  # r_max defaults to (L - D) / 2 on the walled axis


def observed_scene(tmp_path, **observe):
    doc = {"system": {"dimension": 2, "particles": 200, "packing_fraction": 0.3, "boundaries": "periodic"},
           "collisions": {"engine": "float"}, "rng": {"generator": "philox", "seed": 4},
           "run": {"collisions": 400}, "observe": observe}
    return doc


def test_scene_observe_in_report_and_json(tmp_path, capsys):
    doc = observed_scene(tmp_path, speed_bins=20, slabs=3)
    scene = scene_from_dict(doc, "obs.toml", tmp_path)
    assert scene.observe == {"speed_bins": 20, "slabs": 3}
    r = run_scene(scene, json_path=tmp_path / "r.json", progress=False)
    assert r["passed"] and r["observe"]["particle_collisions"] == 800
    saved = json.loads((tmp_path / "r.json").read_text())
    assert saved["observe"]["compressibility"][0] > 1.0 and len(saved["observe"]["speed"]["value"]) == 20
    # an empty table observes the scalars
    doc["observe"] = {}
    assert scene_from_dict(doc, "obs.toml", tmp_path).observe == {}
    path = tmp_path / "obs.toml"
    path.write_text('[system]\ndimension = 2\nparticles = 100\npacking_fraction = 0.3\n'
                    '[collisions]\nengine = "float"\n[run]\ncollisions = 200\n[observe]\nspeed_bins = 10\n')
    assert cli_main(["run", str(path), "--no-progress"]) == 0
    assert "compressibility" in capsys.readouterr().out
    # a run shorter than two blocks has no errors, and says so
    sim = gas()
    sim.observe(block_time=1e6)
    sim.run(collisions=100)
    o = sim.observation()
    assert o.blocks == 0 and o.compressibility.error == 0.0
    assert "no errors: fewer than 2 complete blocks" in "\n".join(o.lines())


@pytest.mark.parametrize("observe, engine, word", [
    ({"slab_axis": 2}, "float", "slab_axis"),
    ({"pair_bins": 10}, "float", "pair_rmax"),
    ({"pair_bins": 10, "pair_rmax": 2.0}, "float", "pair_bins"),
    ({"speed_bins": -1}, "float", "speed_bins"),
    ({"speed_bins": 1.5}, "float", "speed_bins"),
    ({"colour": 1}, "float", "colour"),
])
def test_scene_observe_errors(tmp_path, observe, engine, word):
    doc = observed_scene(tmp_path, **observe)
    doc["collisions"]["engine"] = engine
    with pytest.raises(SceneError, match=word):
        scene_from_dict(doc, "obs.toml", tmp_path)


@pytest.mark.parametrize("engine", ["float", "lattice"])
def test_scene_observe_runs_on_either_engine(tmp_path, engine):
    doc = observed_scene(tmp_path, speed_bins=10)
    doc["collisions"]["engine"] = engine
    scene = scene_from_dict(doc, "obs.toml", tmp_path)
    report = run_scene(scene, progress=False)
    assert report["passed"] and report["observe"]["pair_collisions"] + report["observe"]["group_collisions"] == 400
    assert report["observe"]["compressibility"][0] > 1.0


def test_observe_table_only_for_gas(tmp_path):
    doc = {"scene": {"kind": "reversal", "case": "pair2d"}, "observe": {}}
    with pytest.raises(SceneError, match="observe"):
        scene_from_dict(doc, "rev.toml", tmp_path)


def test_observation_takes_a_result_it_does_not_know():
    """A result the C++ observer adds (the recipe in ARCHITECTURE.md) reaches Python with no
    Python change: an estimate as an Estimate, an array as numpy, both in to_dict."""
    sim = revcol.Simulation.random(n=100, dim=2, phi=0.3, seed=2)
    sim.observe()
    sim.run(collisions=2000)
    raw = dict(sim._e.observation())
    raw["new_estimate"] = {"value": 1.5, "error": 0.25}
    raw["new_series"] = np.array([1.0, 2.0])
    o = Observation(raw)
    assert o.new_estimate == Estimate(1.5, 0.25) and np.array_equal(o.new_series, [1.0, 2.0])
    d = o.to_dict()
    assert d["new_estimate"] == [1.5, 0.25] and d["new_series"] == [1.0, 2.0] and d["vacf"] == o.vacf.tolist()


def test_helfand_viscosity_and_self_diffusion_on_known_walks():
    """helfand_viscosity on synthetic windows: I a random walk with <dI^2> = 2 V T eta dt per
    component recovers eta within 4 of its standard errors (batches of windows), and the
    errors are about the spread of independent repeats; self_diffusion the same for an MSD
    2 d D t. Mismatched block spacings and too short lags are named errors."""
    from types import SimpleNamespace
    from revcol.observe import helfand_viscosity, self_diffusion

    rng = np.random.default_rng(5)
    V, T, eta, h, D = 50.0, 1.3, 0.7, 0.1, 0.2

    def window(points=200):
        steps = rng.normal(0.0, np.sqrt(2 * V * T * eta * h), size=(points, 3))
        t = h * np.arange(1, points + 1)
        msd = 6 * D * t + rng.normal(0.0, 0.05, size=points)
        return SimpleNamespace(msd_time=t, helfand=np.cumsum(steps, axis=0), msd=msd, dim=3,
                               temperature=Estimate(T, 0.0))

    runs = [helfand_viscosity([window() for _ in range(24)], V, 1.0, 3.0, batches=8) for _ in range(12)]
    vals, errs = np.array([r.value for r in runs]), np.array([r.error for r in runs])
    assert np.all(np.abs(vals - eta) < 4 * errs)
    assert 0.5 < np.mean(errs) / np.std(vals, ddof=1) < 2.0
    one = helfand_viscosity(window(4000), V, 1.0, 3.0, temperature=T)  # one record, cut into pieces
    assert abs(one.value - eta) < 4 * one.error
    d = self_diffusion([window() for _ in range(10)])
    assert abs(d.value - D) < 4 * d.error and d.error < 0.01
    bad = window()
    bad.msd_time = bad.msd_time * 2
    with pytest.raises(ValueError, match="spacings"):
        helfand_viscosity([window(), bad], V, 1.0, 3.0)
    with pytest.raises(ValueError, match="lags"):
        helfand_viscosity([window()], V, 1.01, 1.05)


@pytest.mark.parametrize("periodic", [[True, True], [False, True], [False, False]])
def test_numpy_g_of_r_counts_every_pair_as_the_brute_force_does(periodic):
    # the numpy path counts each unordered pair once, within r_max, in row blocks (issue 58:
    # 2.5x faster); its counts must equal every ordered pair's, taken all at once
    from revcol.observe import _pair_counts
    rng = np.random.default_rng(5)
    L = np.array([9.0, 7.0])
    walls = ~np.asarray(periodic)
    edges = np.linspace(0.0, 3.4, 41)
    for f in rng.random((3, 150, 2)) * L:
        dr = f[:, None, :] - f[None, :, :]
        dr -= np.where(walls, 0.0, 1.0) * L * np.round(dr / L)
        d = np.sqrt((dr * dr).sum(-1))[~np.eye(len(f), dtype=bool)]
        assert np.array_equal(_pair_counts(f, L, edges, walls), np.histogram(d, bins=edges)[0])
