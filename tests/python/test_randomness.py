"""revcol.randomness: the word stream (uniform under the right law, not under the wrong
one; the engine's collisions in a gas too), dieharder's output parser, the command line,
Ctrl-C during a word file (no partial file is left), and a reduced battery in which the good
streams pass and the bad control fails (skipped only when the dieharder binary is absent;
CI's setup installs it)."""
import os
import signal
import threading

import numpy as np
import pytest
from scipy import stats

import revcol.studies.randomness as R


def ks_p(words):
    return stats.kstest((np.asarray(words, float) + 0.5) / 2.0**32, "uniform").pvalue


@pytest.mark.parametrize("case,width", [("pair2d", 1), ("pair3d", 2), ("triple2d-c1", 3)])
@pytest.mark.parametrize("law", ["flux", "uniform"])
def test_words_uniform_under_the_law_and_not_under_the_other(case, width, law):
    s = R.stream(case, mode="exact", law=law, rng="philox", seed=5)
    assert s.width == width
    w = s.words(60000).reshape(-1, width)
    for k in range(width):
        assert ks_p(w[:, k]) > 1e-3
    other = "uniform" if law == "flux" else "flux"
    wrong = R.stream(case, mode="exact", law=law, rng="philox", seed=5, cdf_law=other).words(60000)
    assert min(ks_p(wrong.reshape(-1, width)[:, k]) for k in range(width)) < 1e-6


@pytest.mark.parametrize("case,width", [("gas2d", 1), ("gas3d", 2)])
@pytest.mark.parametrize("law", ["flux", "uniform"])
def test_gas_words_uniform_under_the_law_and_not_under_the_other(case, width, law):
    s = R.stream(case, law=law, rng="philox", seed=5, particles=300)
    assert s.width == width
    w = s.words(60000).reshape(-1, width)
    assert s.collisions == 60000 // width
    for k in range(width):
        assert ks_p(w[:, k]) > 1e-3
    other = "uniform" if law == "flux" else "flux"
    wrong = R.stream(case, law=law, rng="philox", seed=5, particles=300, cdf_law=other).words(60000)
    assert min(ks_p(wrong.reshape(-1, width)[:, k]) for k in range(width)) < 1e-6


def test_gas_options_reach_the_engine():
    a = R.stream("gas2d", seed=1, particles=200).words(500)
    assert not np.array_equal(a, R.stream("gas2d", seed=1, particles=201).words(500))
    assert not np.array_equal(a, R.stream("gas2d", seed=1, particles=200, fraction=0.3).words(500))
    assert not np.array_equal(a, R.stream("gas2d", seed=1, particles=200, warmup=6).words(500))
    assert np.array_equal(a, R.stream("gas2d", seed=1, particles=200).words(500))
    for kw in ({"rng": "randu"}, {"mode": "paper"}, {"particles": 1}, {"fraction": 0.99}, {"warmup": -1},
               {"seed": 2**32}):
        with pytest.raises(ValueError):
            R.stream("gas2d", **dict({"particles": 100}, **kw))


def test_ctrl_c_during_write_words_leaves_no_file(tmp_path):
    path = str(tmp_path / "w.bin")
    # Python's own handler, even when this process inherited SIGINT ignored (a background job)
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            R.write_words(path, 10**12, case="pair2d", seed=1)  # hours: only Ctrl-C ends it
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, before)
    assert os.listdir(tmp_path) == []  # neither the file nor its .part


def test_stream_is_deterministic_and_resumable():
    a = R.stream("triple2d-c3", seed=2).words(1000)
    s = R.stream("triple2d-c3", seed=2)
    b = np.concatenate([s.words(1), s.words(499), s.words(500)])
    assert np.array_equal(a, b)
    assert s.emitted == 1000 and s.collisions == 334
    assert not np.array_equal(a, R.stream("triple2d-c3", seed=3).words(1000))


def test_paper_mode_streams_read_through_the_uniform_chart():
    assert R.stream_cases("paper")[:2] == ["raw", "pair2d"]
    s = R.stream("pair2d", mode="paper", rng="clcg4")
    assert ks_p(s.words(50000)) > 1e-3
    assert s.restarts == 0
    for case in R.stream_cases("paper")[2:]:
        assert len(R.stream(case, mode="paper").words(30)) == 30


def test_bad_arguments_raise_value_error(tmp_path):
    for kw in ({"case": "nope"}, {"case": "pair1d"}, {"case": "pair2d", "rng": "mt"},
               {"case": "pair2d", "mode": "specular"}, {"case": "pair2d", "seed": -1},
               {"case": "pair2d", "law": "maxwell"}):
        with pytest.raises(ValueError):
            R.stream(**kw)
    with pytest.raises(ValueError):
        R.stream("pair2d").write(str(tmp_path / "no" / "such" / "dir.bin"), 5)


def test_words_file_and_cli(tmp_path):
    path = tmp_path / "w.bin"
    assert R.main(["words", str(path), "--words", "1000", "--case", "triple1d", "--seed", "4"]) == 0
    raw = np.fromfile(path, dtype="<u4")
    assert np.array_equal(raw, R.stream("triple1d", seed=4).words(1000))
    assert R.main(["words", str(path), "--words", "1000", "--case", "gas3d", "--seed", "4", "--particles", "150"]) == 0
    assert np.array_equal(np.fromfile(path, dtype="<u4"), R.stream("gas3d", seed=4, particles=150).words(1000))


SAMPLE = """# The file file_input_raw was rewound 3 times
        diehard_runs|   0|    100000|      29|0.37764425|  PASSED
        diehard_runs|   0|    100000|      29|0.00300000|   WEAK
 diehard_3dsphere|   3|      4000|     100|0.00000000|  FAILED
"""


def test_parser_reads_rows_and_rewinds():
    r = R.parse(SAMPLE)
    assert r["rewound"] == 3
    assert [x["assessment"] for x in r["rows"]] == ["PASSED", "WEAK", "FAILED"]
    assert r["rows"][0]["psamples"] == 29 and r["rows"][2]["ntuple"] == 3
    assert r["rows"][1]["p"] == pytest.approx(0.003)
    assert R.parse("nothing here") == {"rows": [], "rewound": 0}


@pytest.mark.skipif(not R.has_dieharder(), reason="dieharder binary absent (scripts/setup.sh installs it)")
def test_reduced_battery_good_passes_bad_fails(tmp_path):
    good = R.battery({"case": "pair2d", "mode": "exact", "law": "flux", "rng": "philox", "seed": 1},
                     1_000_000, R.CI_TESTS, workdir=str(tmp_path))
    assert good["verdict"] == "PASSED", good
    assert all(t["rewound"] == 0 for t in good["tests"])
    assert good["ks_p"] > 1e-3
    bad = R.battery({"case": "raw", "mode": "exact", "law": "flux", "rng": "randu", "seed": 1},
                    1_000_000, (12,), workdir=str(tmp_path))
    assert bad["verdict"] == "FAILED", bad
    assert not os.listdir(tmp_path)  # the word files are removed


@pytest.mark.skipif(not R.has_dieharder(), reason="dieharder binary absent (scripts/setup.sh installs it)")
def test_reduced_battery_gas_passes(tmp_path):
    cfg = {"case": "gas2d", "mode": "exact", "law": "flux", "rng": "philox", "seed": 1, "particles": 500}
    good = R.battery(cfg, 1_000_000, R.CI_TESTS, workdir=str(tmp_path))
    assert good["verdict"] == "PASSED", good
    assert good["stream"]["collisions"] == 1_000_000
    assert not os.listdir(tmp_path)


def test_revcol_study_randomness_forwards(tmp_path):
    import revcol.cli.main as cli

    path = tmp_path / "w.bin"
    assert cli.main(["study", "randomness", "words", str(path), "--words", "100", "--case", "pair3d"]) == 0
    assert path.stat().st_size == 400


def test_coverage_figures_are_written_small(tmp_path):
    paths = R.coverage(str(tmp_path), samples=2000)
    assert len(paths) == 8
    for p in paths:
        assert os.path.getsize(p) < 150_000, p
