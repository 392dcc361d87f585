"""revcol.studies.statesave: the paper's state saving vs reverse computation study, at small N and N_c
(seconds in all; the big runs are benchmarks whose results are committed)."""
import json
import math
import os
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest

import revcol
from revcol.studies import statesave as ss
from revcol.cli.main import main as cli_main

N, NC = 200, 400  # about 4 collisions per particle


@pytest.mark.parametrize("lazy", [False, True])
@pytest.mark.parametrize("mode", ["exact", "paper"])
@pytest.mark.parametrize("rng", ["clcg4", "philox"])
def test_rc_restores_within_1e9(lazy, mode, rng):
    r = ss.run(N, NC, variant="rc", lazy=lazy, mode=mode, rng=rng)
    assert r["restored"] and r["error"] == ""
    assert r["max_rel_error"] <= 1e-9
    assert r["rng_restored"] and r["clock_restored"]
    assert r["bytes_saved"] == r["log_bytes"]  # RC keeps only its (rare) logs


@pytest.mark.parametrize("lazy,variant", [(False, "ss1"), (False, "ss2"), (True, "ss1"), (True, "ss2"),
                                          (True, "ssp")])
def test_state_saving_restores_exactly(lazy, variant):
    r = ss.run(N, NC, variant=variant, lazy=lazy, capture=True)
    assert r["restored"] and r["bit_exact"] and r["max_rel_error"] == 0.0
    assert np.array_equal(r["end"], r["start"])
    assert r["bytes_saved"] == r["projected_bytes"] == r["record_bytes"] * NC


def test_fixed_draw_count_and_generator_back_at_start():
    for lazy in (False, True):
        for v in ss.variants(lazy):
            r = ss.run(N, NC, variant=v, lazy=lazy, mode="paper")
            assert r["draws"] == 3 * NC
            assert r["rng_restored"]
            if v == "rc":
                assert r["draws_undone"] == 3 * NC


@pytest.mark.parametrize("mode", ["exact", "paper"])
def test_lazy_equals_eager_to_rounding(mode):
    e = ss.run(N, NC, mode=mode, capture=True)
    z = ss.run(N, NC, mode=mode, lazy=True, capture=True)
    assert e["turn_ticks"] == z["turn_ticks"] > 0
    np.testing.assert_allclose(z["turn"][:, :2], e["turn"][:, :2], rtol=0, atol=1e-12)
    np.testing.assert_allclose(z["turn"][:, 2:], e["turn"][:, 2:], rtol=0, atol=1e-9)
    assert np.abs(e["turn"][:, 2:] - e["start"][:, 2:]).max() > 0.1  # the velocities did change


def test_deterministic():
    a = ss.run(N, NC, capture=True)
    b = ss.run(N, NC, capture=True)
    assert np.array_equal(a["turn"], b["turn"]) and a["max_rel_error"] == b["max_rel_error"]
    assert not np.array_equal(ss.run(N, NC, seed=1, capture=True)["turn"], a["turn"])


def test_skipped_projection_reported():
    r = ss.run(10**6, 1000, variant="ss1")  # 32 GB: not attempted, returns at once
    assert r["skipped"] and r["projected_bytes"] == 32_000_024_000 and r["bytes_saved"] == 0
    assert ss.projected_bytes(10**6, 1000, variant="ss1") == 32_000_024_000
    assert ss.projected_bytes(10**6, 1000, variant="rc") == 0
    rep = ss.study([300], 100, budget_gib=1e-4, inline=True, repeats=1, progress=False)
    rows = {r["variant"]: r for r in rep["runs"]}
    assert rows["ss1"]["skipped"] and rows["ss1"]["status"].startswith("skipped: needs ")
    assert rows["ss1"]["projected_bytes"] == (32 * 300 + 24) * 100
    assert not rows["rc"]["skipped"] and rows["rc"]["restored"]
    q = {x["vs"]: x for x in rep["ratios"]}
    assert q["ss1"]["time"] is None and q["ss1"]["note"]
    assert rep["passed"]


@pytest.mark.parametrize("kwargs,needle", [
    (dict(particles=1), "particles"),
    (dict(particles=2**26 + 1), "particles"),
    (dict(particles=2.5), "particles"),
    (dict(collisions=0), "collisions"),
    (dict(variant="ssp"), "lazy"),
    (dict(variant="ss3"), "variant"),
    (dict(mode="fast"), "mode"),
    (dict(rng="mt"), "rng"),
    (dict(seed=-1), "seed"),
    (dict(law="cosine"), "law"),
    (dict(budget_gib=-1), "budget_gib"),
    (dict(budget_gib=float("nan")), "budget_gib"),
    (dict(mean_dt=0.0), "mean_dt"),
    (dict(grazing_tol=0.0), "grazing_tol"),
])
def test_bad_arguments_raise_value_error(kwargs, needle):
    args = dict(particles=50, collisions=10)
    args.update(kwargs)
    with pytest.raises(ValueError, match=needle):
        ss.run(args.pop("particles"), args.pop("collisions"), **args)


def test_bad_study_arguments():
    with pytest.raises(ValueError, match="n must"):
        ss.study([], 10, inline=True)
    with pytest.raises(ValueError, match="n must"):
        ss.study([1], 10, inline=True)
    with pytest.raises(ValueError, match="variants"):
        ss.study([50], 10, variants=["ssp"], inline=True)
    with pytest.raises(ValueError, match="modes"):
        ss.study([50], 10, modes=["fast"], inline=True)
    with pytest.raises(ValueError, match="repeats"):
        ss.study([50], 10, repeats=0, inline=True)
    with pytest.raises(ValueError, match="binary"):
        ss.study([50], 10, binary="/nonexistent/revcol-bench")


def test_study_writes_json_csv_and_plot(tmp_path):
    rep = ss.study([100, 300], 100, lazy=True, modes=["exact", "paper"], repeats=2, inline=True,
                   progress=False)
    assert rep["passed"] and rep["transport"] == "lazy" and rep["runner"] == "inline"
    assert {r["variant"] for r in rep["runs"]} == {"ss1", "ss2", "ssp", "rc"}
    assert len(rep["runs"]) == 2 * 2 * 4
    for r in rep["runs"]:
        assert math.isclose(r["total_ms"], r["forward_ms"] + r["rollback_ms"])
        assert len(r["forward_ms_all"]) == 2
    assert len(rep["ratios"]) == 2 * 2 * 3
    ss.write_json(rep, tmp_path / "s.json")
    ss.write_csv(rep, tmp_path / "s.csv")
    back = json.loads((tmp_path / "s.json").read_text())
    assert back["runs"] == rep["runs"]
    lines = (tmp_path / "s.csv").read_text().splitlines()
    assert len(lines) == 1 + len(rep["runs"]) and lines[0].startswith("mode,transport,variant")
    assert "RC/SS-pair" in ss.format_table(rep)
    pytest.importorskip("matplotlib")
    ss.plot(rep, tmp_path / "s.png")
    assert (tmp_path / "s.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_study_interleaves_variants_round_by_round(monkeypatch):
    import revcol.studies.statesave.driver as sst
    order = []
    real = sst._run_inline

    def spy(kw, repeats):
        order.append((kw["particles"], kw["variant"]))
        return real(kw, repeats)

    monkeypatch.setattr(sst, "_run_inline", spy)
    rep = ss.study([100, 200], 50, variants=["ss1", "rc"], repeats=3, inline=True, progress=False)
    # A B, B A, A B for each N in turn: a change of load hits every variant alike
    assert order == [(100, "ss1"), (100, "rc"), (100, "rc"), (100, "ss1"), (100, "ss1"), (100, "rc"),
                     (200, "ss1"), (200, "rc"), (200, "rc"), (200, "ss1"), (200, "ss1"), (200, "rc")]
    for r in rep["runs"]:
        assert len(r["total_ms_all"]) == 3 and len(r["load_1m_all"]) == 3
        assert r["total_ms_min"] <= r["total_ms"] <= r["total_ms_max"]
    assert rep["load_1m_start"] >= 0 and rep["load_1m_end"] >= 0
    for q in rep["ratios"]:
        rc = next(r for r in rep["runs"] if r["particles"] == q["particles"] and r["variant"] == "rc")
        s1 = next(r for r in rep["runs"] if r["particles"] == q["particles"] and r["variant"] == "ss1")
        paired = sorted(a / b for a, b in zip(rc["total_ms_all"], s1["total_ms_all"]))
        assert (q["time_paired_min"], q["time_paired_median"], q["time_paired_max"]) == \
            (paired[0], paired[1], paired[2])


def test_study_stop_keeps_the_runs_done():
    calls = []

    def stop():
        calls.append(1)
        return len(calls) > 5  # 4 runs of N=100 (2 variants x 2 rounds), then one of N=200

    rep = ss.study([100, 200], 50, variants=["ss1", "rc"], repeats=2, inline=True, progress=False, stop=stop)
    assert rep["interrupted"] and rep["not_run"] == 1
    assert [(r["particles"], r["variant"], len(r["total_ms_all"])) for r in rep["runs"]] == \
        [(100, "ss1", 2), (100, "rc", 2), (200, "ss1", 1)]


def test_study_cpu_argument():
    with pytest.raises(ValueError, match="cpu"):
        ss.study([50], 10, cpu=-1, binary=_bench_binary() or "/bin/true")
    with pytest.raises(ValueError, match="cpu"):
        ss.study([50], 10, cpu=0, inline=True)


def test_plot_marks_zero_bytes_and_writes_pdf(tmp_path):
    pytest.importorskip("matplotlib")
    rep = ss.study([100], 50, modes=["paper"], repeats=2, inline=True, progress=False)
    assert next(r for r in rep["runs"] if r["variant"] == "rc")["bytes_saved"] == 0
    ss.plot(rep, tmp_path / "s.pdf")
    assert (tmp_path / "s.pdf").read_bytes()[:5] == b"%PDF-"


def _bench_binary():
    for c in (os.environ.get("REVCOL_BENCH"), str(Path(sys.executable).parent / "revcol-bench")):
        if c and Path(c).is_file():
            return c
    return None


def test_study_in_fresh_processes():
    exe = _bench_binary()
    if exe is None:
        pytest.skip("revcol-bench not found (set REVCOL_BENCH or install the package)")
    cpu = 0 if shutil.which("taskset") else None
    rep = ss.study([200], 200, modes=["exact"], repeats=2, binary=exe, progress=False, cpu=cpu)
    assert rep["runner"] == "process" and rep["passed"] and rep["cpu"] == cpu
    rows = {r["variant"]: r for r in rep["runs"]}
    assert rows["ss1"]["bytes_saved"] == (32 * 200 + 24) * 200
    assert rows["ss1"]["peak_rss_bytes"] > rows["ss1"]["bytes_saved"]
    assert rows["rc"]["max_rel_error"] <= 1e-9
    # a fresh process per run: RC's peak is far below SS1's
    assert rows["rc"]["peak_rss_bytes"] < rows["ss1"]["peak_rss_bytes"]


def test_cli(tmp_path, capsys):
    out = tmp_path / "r.json"
    code = cli_main(["bench", "statesave", "--n", "100", "200", "--collisions", "1e2", "--inline",
                     "--repeats", "1", "--no-progress", "--json", str(out)])
    assert code == 0
    text = capsys.readouterr().out
    assert "RC/SS1" in text and "PASSED" in text
    rep = json.loads(out.read_text())
    assert rep["particles"] == [100, 200] and rep["collisions"] == 100
    assert rep["command"].startswith("revcol bench statesave")
    assert out.with_suffix(".csv").exists()
    assert cli_main(["bench", "statesave", "--n", "100", "--inline", "--variants", "ssp",
                     "--no-progress"]) == 2
    with pytest.raises(SystemExit):
        cli_main(["bench", "statesave", "--n", "0"])


def test_exported():
    # revcol.statesave is the library's side (one run in this process); the study re-exports it
    assert revcol.statesave is sys.modules["revcol.statesave"] and "statesave" in revcol.__all__
    assert ss.run is revcol.statesave.run and ss.variants is revcol.statesave.variants


def test_markdown_tables_of_a_saved_report(tmp_path, capsys):
    rep = ss.study([100, 200], 50, modes=["exact", "paper"], variants=["ss2", "rc"], repeats=3, inline=True,
                   progress=False)
    from revcol.studies.statesave.output import markdown
    text = markdown(rep, "s.json")
    lines = text.splitlines()
    # a table of 4 runs per mode, and one ratio row per (mode, N) with the paired median [range]
    assert sum(ln.startswith("| 100 |") or ln.startswith("| 200 |") for ln in lines) == 8
    ratio_rows = [ln for ln in lines if ln.startswith("| exact |") or ln.startswith("| paper |")]
    assert len(ratio_rows) == 4
    q = next(q for q in rep["ratios"] if q["mode"] == "exact" and q["particles"] == 100)
    assert f"{q['time_paired_median']:.3f} [{q['time_paired_min']:.3f}, {q['time_paired_max']:.3f}]" in ratio_rows[0]
    ss.write_json(rep, tmp_path / "s.json")
    assert cli_main(["bench", "statesave", "--markdown-from", str(tmp_path / "s.json")]) == 0
    assert capsys.readouterr().out.strip() == markdown(json.loads((tmp_path / "s.json").read_text()), "s.json")
    assert cli_main(["bench", "statesave", "--markdown-from", str(tmp_path / "missing.json")]) == 2
