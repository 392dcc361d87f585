"""Event-chain Monte Carlo (revcol.ecmc, issue 16): the binding, its errors, the conversion
between the two temperature conventions, the study's command line, and the CI version of the
comparison it exists for: the engine's flux law and specular gas against the equilibrium
pressure of the same N and box, which the uniform law must miss."""
import json
import math

import numpy as np
import pytest

from revcol.studies import ecmc
from revcol.studies import equilibrium as P

LIMIT = 3.5  # standard errors; seeded, so the same bits every time


def test_sampler_from_the_engine_start_keeps_spheres_apart_and_in_the_box():
    s = ecmc.start(2, 0.5, 200, seed=3)
    x, _v, box = __import__("revcol")._core.engine_random_state(2, 200, 0.5, ["periodic"], 1.0, 3, 0.0, "auto", False)
    assert np.array_equal(s.positions, x) and list(s.box) == list(box)
    assert s.dim == 2 and s.n == 200 and s.diameter == 1.0
    assert s.packing_fraction == pytest.approx(0.5, rel=1e-12)
    r = s.run(2000, 5.0)
    assert set(r) == {"chains", "displacement", "lift_dx", "lifts", "crossings", "z"}
    assert r["chains"] == 2000 and 2000 * 2.5 <= r["displacement"] <= 2000 * 7.5
    assert r["z"] == pytest.approx(1 + r["lift_dx"] / r["displacement"], rel=1e-15)
    assert s.totals["chains"] == 2000
    assert s.min_distance() >= 1 - 1e-9
    p = s.positions
    assert p.shape == (200, 2) and (p >= 0).all() and (p < np.asarray(s.box)).all()


def test_same_seed_same_bits():
    a, b = ecmc.start(3, 0.3, 100, seed=4), ecmc.start(3, 0.3, 100, seed=4)
    assert a.run(500, 3.0) == b.run(500, 3.0)
    assert np.array_equal(a.positions, b.positions)


def test_bad_input_names_the_problem_and_changes_nothing():
    with pytest.raises(ValueError, match=r"positions must be an \(n, 2\) array, got shape \(3\)"):
        ecmc.EventChain([4.0, 4.0], np.zeros(3))
    with pytest.raises(ValueError, match="overlap"):
        ecmc.EventChain([4.0, 4.0], [[0.5, 0.5], [1.0, 0.5]])
    with pytest.raises(ValueError, match="outside"):
        ecmc.EventChain([4.0, 4.0], [[0.5, 4.0]])
    with pytest.raises(ValueError, match="at least 3 diameters"):
        ecmc.EventChain([2.0, 4.0], [[0.5, 0.5]])
    with pytest.raises(TypeError, match="seed must be an integer"):
        ecmc.EventChain([4.0, 4.0], [[0.5, 0.5]], seed=1.5)
    with pytest.raises(ValueError, match="seed"):
        ecmc.EventChain([4.0, 4.0], [[0.5, 0.5]], seed=2 ** 32)
    s = ecmc.start(2, 0.3, 50, seed=1)
    before = s.positions.copy()
    for bad in (0.0, -1.0, math.inf, math.nan):
        with pytest.raises(ValueError, match="chain length"):
            s.run(10, bad)
    with pytest.raises(ValueError, match="chains"):
        s.run(-1, 1.0)
    assert np.array_equal(s.positions, before) and s.totals["chains"] == 0
    with pytest.raises(ValueError, match="blocks"):
        ecmc.sample(2, 0.3, n=50, blocks=1)


def test_mixture_sampler_from_python():
    # every other sphere of an engine start shrunk: the pair's own contact distance counts
    s0 = ecmc.start(2, 0.5, 200, seed=3)
    d = np.where(np.arange(200) % 2, 1 / 1.4, 1.0)
    s = ecmc.EventChain(list(s0.box), s0.positions, diameters=d, seed=3)
    assert s.diameter == 1.0 and np.array_equal(s.diameters, d) and s0.diameters is None
    assert s.packing_fraction == pytest.approx(0.5 * (1 + 1 / 1.4 ** 2) / 2, rel=1e-12)
    s.run(2000, 5.0)
    assert s.min_distance() >= 1.0 - 1e-9
    # equal diameters given one by one: the one-size chain, bit for bit
    a = ecmc.EventChain(list(s0.box), s0.positions, seed=4)
    b = ecmc.EventChain(list(s0.box), s0.positions, diameters=np.ones(200), seed=4)
    assert a.run(500, 4.0) == b.run(500, 4.0) and np.array_equal(a.positions, b.positions)
    box, x = [4.0, 4.0], [[0.5, 0.5], [1.3, 0.5]]
    with pytest.raises(ValueError, match="not both"):
        ecmc.EventChain(box, x, diameter=1.0, diameters=[1.0, 0.5])
    with pytest.raises(ValueError, match="one diameter per sphere"):
        ecmc.EventChain(box, x, diameters=[1.0])
    with pytest.raises(ValueError, match="overlap"):  # 0.8 apart, contact at 0.85
        ecmc.EventChain(box, x, diameters=[1.0, 0.7])
    with pytest.raises(ValueError, match="16 times smaller"):
        ecmc.EventChain(box, x, diameters=[1.0, 0.05])
    assert ecmc.EventChain(box, x, diameters=[0.8, 0.7]).min_distance() == pytest.approx(0.8 / 0.75)


def test_rods_give_tonks_in_the_engine_convention():
    # 1D: the chains' Z_mc is Tonks' finite-N value, and md_equivalent turns it into 1 / (1 - phi)
    r = ecmc.sample(1, 0.5, n=50, seed=1, per_particle=500, blocks=16, warmup=20)
    assert r["z_md"][1] < 0.005
    assert abs(r["z_md"][0] - 2.0) < 4 * r["z_md"][1]
    assert P.reference_z(1, 0.5) == 2.0


def test_temperature_conventions():
    # Tonks: Z_mc - 1 = (N - 1) D / (L - N D) and Z_md = L / (L - N D): md_equivalent maps one onto the other
    n, L = 10, 20.0
    assert ecmc.md_equivalent(1 + (n - 1) / (L - n), n) == pytest.approx(L / (L - n), rel=1e-14)
    assert ecmc.mc_equivalent(ecmc.md_equivalent(6.45, 1000), 1000) == pytest.approx(6.45, rel=1e-15)
    with pytest.raises(ValueError, match="n >= 2"):
        ecmc.md_equivalent(2.0, 1)


def test_engine_against_the_equilibrium_of_the_same_n():
    """The CI version of the study: 300 disks at 0.4, one start; the chains give the exact
    equilibrium Z of that N and box, the flux law and the specular gas must agree with it, and
    the uniform law must not (or the test could not fail)."""
    mc = ecmc.sample(2, 0.4, n=300, seed=2, per_particle=3000, blocks=16, warmup=100)
    assert mc["min_distance"] >= 1 - 1e-9
    assert mc["z_md"][1] < 0.003 * mc["z_md"][0]  # sharp enough to see a 5% drift many times over
    rows = ecmc.summarize([mc])
    for law in ("flux", "specular", "uniform"):
        r = P.dense(2, 0.4, law, n=300, per_particle=3000, seed=2, frames=2)
        (c,) = ecmc.compare(rows, [{"dim": 2, "phi": 0.4, "n": 300, "law": law, "z": r["z"], "source": "test"}])
        if law == "uniform":
            assert c["sigmas"] < -5.0, c
        else:
            assert abs(c["sigmas"]) < LIMIT, c


def test_study_command_line(tmp_path, capsys):
    mc_json, dense_json, cmp_json = tmp_path / "mc.json", tmp_path / "dense.json", tmp_path / "cmp.json"
    assert P.main(["mc", "--dim", "2", "--phi", "0.3", "--n", "60", "120", "--seeds", "3", "--per-particle", "200",
                   "--blocks", "4", "--warmup", "20", "--json", str(mc_json)]) == 0
    out = capsys.readouterr().out
    assert "| 2 | 0.30 | 60 | 3 |" in out and "| 2 | 0.30 | 120 | 3 |" in out
    doc = json.loads(mc_json.read_text())
    assert len(doc["mc"]) == 6 and len(doc["summary"]) == 2 and "commit" in doc
    assert P.main(["dense", "--dim", "2", "--phi", "0.3", "--n", "60", "--per-particle", "200", "--laws", "flux",
                   "--json", str(dense_json)]) == 0
    capsys.readouterr()
    assert P.main(["mc-compare", "--mc", str(mc_json), "--md", str(dense_json), "--json", str(cmp_json)]) == 0
    out = capsys.readouterr().out
    assert "| 2 | 0.30 | 60 | flux |" in out and "Z(inf) from the chains at N = [60, 120]" in out
    doc = json.loads(cmp_json.read_text())
    assert len(doc["compare"]) == 1 and len(doc["infinite_size"]) == 1
    assert P.main(["figures", str(dense_json), str(mc_json), "--out", str(tmp_path / "fig")]) == 0
    assert (tmp_path / "fig" / "z_vs_phi.png").stat().st_size > 1000
    with pytest.raises(SystemExit, match="holds no `mc` runs"):
        P.main(["mc-compare", "--mc", str(cmp_json)])
    with pytest.raises(ValueError, match="neither"):
        ecmc.md_estimates({"walls": []})
