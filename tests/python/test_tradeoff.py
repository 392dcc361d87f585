"""revcol bench tradeoff (issue 18), reduced: the same code path as the full table (revcol-bench
in fresh processes, round robin, the law's distance, the table, JSON/CSV, plots) on a few
points with small counts. Checks the table's structure and relations that physics requires
and a defect would break; never a timing."""
import json
import math
import os
import sys
from pathlib import Path

import numpy as np
import pytest

import revcol
from revcol.studies import law_distance as ld, tradeoff
from revcol.cli.main import main as cli_main


def _bench_binary():
    for c in (os.environ.get("REVCOL_BENCH"), str(Path(sys.executable).parent / "revcol-bench")):
        if c and Path(c).is_file():
            return c
    return None


@pytest.fixture(scope="module")
def report():
    exe = _bench_binary()
    if exe is None:
        pytest.skip("revcol-bench not found (set REVCOL_BENCH or install the package)")
    pts = tradeoff.reduced_points()
    # K = 24, 40, 52 on the 2D pair, both generators, one paper case, the engine, two map tables
    return tradeoff.run(pts, repeats=3, collisions=3000, min_collisions=3000, samples=4000, binary=exe,
                        command="test")


def _rows(rep, knob):
    return [r for r in rep["points"] if r["knob"] == knob]


def test_structure(report):
    assert report["command"] == "test" and report["repeats"] == 3
    for key in ("git_commit", "date", "loadavg_before", "loadavg_after", "pinned", "points"):
        assert key in report
    assert len(report["loadavg_before"]) == 3
    assert len(report["points"]) == len(tradeoff.reduced_points())
    for r in report["points"]:
        for t in ("forward_us", "reverse_us"):
            s = r[t]
            assert len(s["values"]) == 3 and s["min"] <= s["median"] <= s["max"] and s["min"] > 0
        assert r["deterministic"], f"{r['curve']} {r['label']}: errors differ between repeats of one seed"
        assert r["collisions"] > 0
    assert sum(r["default"] for r in report["points"]) >= 2


def test_round_trip_error_falls_as_k_grows(report):
    """Exact mode returns the quantized start bit for bit: the round-trip error is the first
    quantization's, about 2^-K of the chart, so it falls by orders of magnitude from K = 24 to 52."""
    ks = {r["settings"]["bits"]: r for r in _rows(report, "bits")}
    assert sorted(ks) == [24, 40, 52]
    assert all(r["bit_exact"] for r in ks.values())
    e = [ks[k]["roundtrip_error"] for k in (24, 40, 52)]
    assert e[0] > e[1] > e[2] > 0
    assert e[0] < 2.0 ** -20 and e[1] < 2.0 ** -36  # within a few cells of 2^-K
    assert e[0] / e[1] > 2.0 ** 10


def test_generators_give_the_same_law(report):
    rows = {r["settings"]["rng"]: r for r in _rows(report, "rng")}
    assert set(rows) == {"clcg4", "philox"}
    for r in rows.values():
        assert r["law_D"] < r["law_D_noise"] * 1.5  # no bias beyond the noise
    assert abs(rows["clcg4"]["law_D"] - rows["philox"]["law_D"]) < 2 * rows["clcg4"]["law_D_noise"]


def test_paper_triple2d_is_far_from_the_uniform_law_and_fails(report):
    """The paper's C1 procedure does not sample the uniform law and does not always separate
    (docs/paper-findings.md): the measure must see both."""
    (r,) = [r for r in report["points"] if r["settings"].get("mode") == "paper"]
    assert r["law_D"] > 5 * r["law_D_noise"]
    assert r["invalid_post"] > 0.05 and r["failure_rate"] > 0.01
    assert not r["bit_exact"]


def test_drift_without_held_invariants_is_round_off(report):
    for r in _rows(report, "bits") + _rows(report, "rng"):
        assert 0 <= r["energy_drift"] < 1e-13 and 0 <= r["momentum_drift"] < 1e-13


def test_engine_round_trip_within_its_horizon(report):
    (r,) = _rows(report, "group_tol")
    assert r["kind"] == "engine" and r["roundtrip_error"] < 1e-6 and r["failure_rate"] == 0.0
    assert r["settings"]["seeds"] == 6


def test_default_is_on_or_near_the_pareto_front(report):
    """Along K, no setting is both clearly faster (by 30%) and more accurate than K = 40."""
    rows = _rows(report, "bits")
    (d,) = [r for r in rows if r["default"]]
    for r in rows:
        assert not (r["time_us"] < 0.7 * d["time_us"] and r["roundtrip_error"] < d["roundtrip_error"])
    front = tradeoff.pareto_front(rows, "roundtrip_error")
    assert front and all(r in rows for r in front)


def test_pareto_front_definition():
    rows = [{"time_us": 1.0, "e": 1.0}, {"time_us": 2.0, "e": 0.5}, {"time_us": 3.0, "e": 0.7},
            {"time_us": 0.5, "e": None}]
    assert [r["time_us"] for r in tradeoff.pareto_front(rows, "e")] == [1.0, 2.0]


def test_law_distance_sees_a_wrong_law():
    """law_D can fail: flux samples against the uniform law's reference are far apart."""
    op = revcol.Collision.named("triple2d-c3", law="flux")
    nc = next(c for c in revcol.named_cases() if c["name"] == "triple2d-c3")
    rng = np.random.default_rng(5)
    while True:
        v = rng.normal(size=(3, 2))
        if max(op.normal_speeds(v)) < 0:
            break
    pos = np.asarray(nc["positions"], float)
    contacts = [(i, j, (pos[i] - pos[j]) / np.linalg.norm(pos[i] - pos[j])) for (i, j) in nc["contacts"]]
    n = 20_000
    post = op.forward(np.broadcast_to(v, (n, 3, 2)), rng=revcol.CLCG4(stream=3))
    same = tradeoff.rejection_posts(v, contacts, "flux", n, np.random.default_rng(1))
    other = tradeoff.rejection_posts(v, contacts, "uniform", n, np.random.default_rng(2))
    u = np.random.default_rng(3).normal(size=6)
    d_same = ld._ks2(post.reshape(n, -1) @ u, same.reshape(n, -1) @ u)
    d_other = ld._ks2(post.reshape(n, -1) @ u, other.reshape(n, -1) @ u)
    crit = 1.95 * math.sqrt(2 / n)  # the two-sample KS distance's 0.1% level, one projection
    assert d_same < crit and d_other > 3 * crit, (d_same, d_other, crit)
    # the rejection samples keep momentum and energy and separate
    np.testing.assert_allclose(same.sum(axis=1), np.broadcast_to(v.sum(axis=0), (n, 2)), atol=1e-12)
    np.testing.assert_allclose((same ** 2).sum(axis=(1, 2)), (v ** 2).sum(), rtol=1e-12)


def test_paper_pair2d_meets_its_uniform_target():
    """The paper's Procedure 1 samples the post angle uniformly: the one paper case whose law
    is the uniform law (and the exact flux law is not it)."""
    paper = tradeoff.law_distance({**tradeoff._OP_DEFAULTS, "case": "pair2d", "mode": "paper"}, 20_000)
    assert paper["law_D"] < paper["law_D_noise"] and paper["invalid_post"] == 0.0
    exact = tradeoff.law_distance({**tradeoff._OP_DEFAULTS, "case": "pair2d"}, 20_000)  # flux vs flux
    assert exact["law_D"] < exact["law_D_noise"]


def test_outputs(report, tmp_path):
    tradeoff.write_json(report, tmp_path / "t.json")
    tradeoff.write_csv(report, tmp_path / "t.csv")
    back = json.loads((tmp_path / "t.json").read_text())
    assert back["points"][0]["label"] == report["points"][0]["label"]
    lines = (tmp_path / "t.csv").read_text().splitlines()
    assert len(lines) == 1 + len(report["points"]) and lines[0].startswith("knob,curve,label")
    table = tradeoff.format_table(report)
    assert table.count("\n") == len(report["points"]) + 1 and "**(default)**" in table
    pytest.importorskip("matplotlib")
    files = tradeoff.plot(report, tmp_path / "fig")
    assert len(files) == len(tradeoff.ERRORS) + 1
    assert all(f.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" for f in files)


def test_cli(tmp_path, capsys):
    exe = _bench_binary()
    if exe is None:
        pytest.skip("revcol-bench not found (set REVCOL_BENCH or install the package)")
    out = tmp_path / "r.json"
    code = cli_main(["bench", "tradeoff", "--reduced", "--repeats", "1", "--collisions", "500",
                     "--min-collisions", "500", "--samples", "500", "--binary", exe, "--no-progress",
                     "--json", str(out)])
    assert code == 0
    assert "| knob |" in capsys.readouterr().out
    rep = json.loads(out.read_text())
    assert rep["command"].startswith("revcol bench tradeoff") and out.with_suffix(".csv").exists()
    assert cli_main(["bench", "tradeoff", "--repeats", "0", "--binary", exe]) == 2
    # the table, CSV and plots again from the JSON, without a run
    again = tmp_path / "again.json"
    assert cli_main(["bench", "tradeoff", "--from-json", str(out), "--json", str(again)]) == 0
    assert json.loads(again.read_text())["points"] == rep["points"]


def test_map_errors_fall_with_the_table_cells(report):
    """Cubic Hermite tables: the error falls about as cells^-4 (16 times the cells: over 1e3
    times smaller), and the defaults are accurate to ~1e-12 or better."""
    for kind, default in (("arc", 4096), ("calotte", 2048)):
        rows = {r["settings"]["cells"]: r for r in report["points"] if r["kind"] == kind}
        assert sorted(rows) == sorted((256, default))
        assert rows[default]["default"] and not rows[256]["default"]
        assert rows[default]["map_error"] < 1e-12 < rows[256]["map_error"]
        assert rows[256]["map_error"] / rows[default]["map_error"] > 1e3
        assert rows[default]["deterministic"] and rows[default]["time_us"] > 0
