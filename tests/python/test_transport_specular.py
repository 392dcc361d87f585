"""revcol.studies.transport_specular at CI size (seconds): both engines' specular gases, 3D
periodic, N = 400 at packing 0.3, two seeds, 3 windows of 40 time units each. The full study
(N = 1000, four packing fractions) is bench/results/transport_specular.json (docs/physics.md)."""
import json
import math

import pytest

from revcol.studies import transport_specular as ts
from revcol.studies.literature import enskog_D, enskog_eta


@pytest.fixture(scope="module")
def result():
    return ts.study(400, [0.3], [1, 2], duration=120.0, block=0.16, equilibrate=30.0, lag_min=2.0, lag_max=6.0,
                    progress=lambda s: None)


def test_both_engines_measure_d_and_eta_near_enskog(result):
    rows = {r["engine"]: r for r in result["rows"]}
    assert set(rows) == {"lattice", "float"}
    for r in rows.values():
        assert r["windows"] == 6 and r["collisions"] > 3e5
        assert r["temperature"] == pytest.approx(1.0, abs=1e-6)
        assert r["D_error"] > 0 and r["eta_error"] > 0
        # the specular gas diffuses faster than Enskog's D at 0.3 (correlated collisions) and its
        # viscosity is of Enskog's size; the CI run's errors are ~5% (D) and ~20% (eta)
        assert 1.0 < r["D_over_enskog"] < 1.5
        assert 0.5 < r["eta_over_enskog"] < 1.7
        assert r["D_enskog"] == pytest.approx(enskog_D(0.3, 3, r["temperature"]))
        assert r["eta_enskog"] == pytest.approx(enskog_eta(0.3, 3, r["temperature"]))
        assert r["D_yeh_hummer"] > r["D"]  # the correction adds
        assert len(r["D_seeds"]) == len(r["eta_seeds"]) == 2
    # the two engines' statics agree closely (Z to ~1%), and their transport within its errors
    assert rows["lattice"]["compressibility"] == pytest.approx(rows["float"]["compressibility"], rel=0.02)
    (c,) = result["comparison"]
    assert abs(c["D_sigmas"]) < 4 and abs(c["eta_sigmas"]) < 4
    json.dumps(result)


def test_the_command_writes_its_json(tmp_path, monkeypatch):
    out = tmp_path / "t.json"
    ts.main(["--n", "300", "--phi", "0.25", "--seeds", "1", "--time", "40", "--block", "0.16", "--equilibrate", "10",
             "--lag-min", "1", "--lag-max", "3", "--out", str(out)])
    data = json.loads(out.read_text())
    assert data["command"].startswith("python -m revcol.studies.transport_specular")
    assert {"commit", "loadavg_start", "loadavg_end", "wall_s", "rows", "comparison"} <= set(data)
    assert len(data["rows"]) == 2 and "partial" not in data
    assert all(math.isfinite(r["eta"]) for r in data["rows"])
