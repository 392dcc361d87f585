"""The paper's reversal illustration through revcol.verify and the CLI."""
import json
import pathlib
import subprocess
import sys

import pytest

import revcol


@pytest.mark.parametrize("rng", ["clcg4", "philox"])
@pytest.mark.parametrize("mode,law", [("exact", "flux"), ("exact", "uniform"), ("paper", "flux")])
def test_pair2d_million_collisions(mode, law, rng):
    """The issue's bar: 1e6 collisions, exact mode bit exact, paper mode within 1e-9."""
    r = revcol.verify("pair2d", collisions=1_000_000, mode=mode, law=law, rng=rng, seed=3)
    assert r["passed"], r
    assert r["rng_restored"]
    assert r["random_numbers_drawn"] == r["random_numbers_undone"] == 1_000_000
    assert r["max_rel_error"] <= 1e-9
    if mode == "exact":
        assert r["bit_exact"]
        assert r["log_bytes"] == 0
        assert r["max_rel_error"] < 2.0 ** -38  # only the first quantization remains


def test_pair1d_is_exact():
    r = revcol.verify("pair1d", collisions=100_000)
    assert r["passed"] and r["bit_exact"] and r["max_rel_error"] == 0.0


def test_printed_reverse_fails_verification():
    r = revcol.verify("pair2d", collisions=1000, mode="paper", printed_reverse=True)
    assert not r["passed"] and r["max_rel_error"] > 1e-3


def test_bad_configuration():
    with pytest.raises(ValueError, match="unknown case"):
        revcol.verify("pair4d")
    with pytest.raises(ValueError, match="rng"):
        revcol.verify("pair2d", rng="mt19937", collisions=10)
    with pytest.raises(ValueError, match="collisions"):
        revcol.verify("pair2d", collisions=0)
    with pytest.raises(ValueError, match="not approaching"):
        revcol.verify("pair2d", collisions=10, velocities=[1.0, 1.0, 0.0, 0.0])


def test_cli_json_keys():
    out = subprocess.run([sys.executable, "-m", "revcol", "verify", "pair2d", "--collisions", "10000",
                          "--mode", "paper", "--rng", "philox", "--seed", "5", "--json"],
                         capture_output=True, text=True, check=True)
    r = json.loads(out.stdout)
    for key in ("passed", "bit_exact", "max_rel_error", "collisions", "forward_per_s",
                "reverse_per_s", "log_bytes", "random_numbers_drawn"):
        assert key in r
    assert r["passed"] and r["collisions"] == 10000 and r["seed"] == 5


def test_cli_reports_failure_and_bad_arguments():
    bad = subprocess.run([sys.executable, "-m", "revcol", "verify", "pair2d", "--collisions", "100",
                          "--mode", "paper", "--printed-reverse"], capture_output=True, text=True)
    assert bad.returncode == 1 and "FAILED" in bad.stdout
    usage = subprocess.run([sys.executable, "-m", "revcol", "verify", "pair2d", "--collisions", "-3"],
                           capture_output=True, text=True)
    assert usage.returncode == 2 and "positive integer" in usage.stderr


# Known answers: every case, both modes, both laws (exact mode), both generators, the
# printed reverse (paper mode), 2000 collisions at seed 3, as verify reported them before
# its three reversal loops became one (cpp/include/revcol/studies/verify.hpp, reversal_chain). The
# timings are left out; every other field must be the same, bit for bit. The last four lines,
# case pair3d-fast (Pair3DExact, issue 21), were recorded when that case was added.
_KNOWN = [json.loads(line) for line in
          (pathlib.Path(__file__).with_name("verify_known_answers.jsonl")).read_text().splitlines()]
_TIMINGS = {"forward_per_s", "reverse_per_s", "forward_s", "reverse_s"}


@pytest.mark.parametrize("known", _KNOWN, ids=lambda k: f"{k['case']}-{k['mode']}-{k['law']}-{k['rng']}-{k['printed_reverse']}")
def test_known_answers(known):
    args = dict(collisions=2000, mode=known["mode"], law=known["law"], rng=known["rng"], seed=known["seed"],
                printed_reverse=known["printed_reverse"])
    if "throws" in known:
        with pytest.raises(ValueError) as e:
            revcol.verify(known["case"], **args)
        assert str(e.value) == known["throws"]
        return
    r = revcol.verify(known["case"], **args)
    assert {k: v for k, v in r.items() if k not in _TIMINGS} == known
