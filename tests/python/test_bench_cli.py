"""The benchmark binary's command line: counts in float notation, bad values refused."""
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest


def _bench_binary():
    for c in (os.environ.get("REVCOL_BENCH"), str(Path(sys.executable).parent / "revcol-bench")):
        if c and Path(c).is_file():
            return c
    pytest.skip("revcol-bench not found (set REVCOL_BENCH or install the package)")


@pytest.mark.parametrize("value", ["1.2e7x", "1.5", "-3", "abc", "", "2e19"])
def test_bad_counts_are_refused_by_name(value):
    # std::stoull alone read "1.2e7" as 1: a lockstep check of 1.2e7 collisions compared one
    r = subprocess.run([_bench_binary(), "--bench", "lattice3d/lockstep/n1000/phi0.45", "--collisions", value],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 2
    assert "bad value" in r.stderr and "--collisions" in r.stderr


def test_float_notation_is_the_count():
    r = subprocess.run([_bench_binary(), "--bench", "lattice3d/lockstep/n1000/phi0.45", "--collisions", "2e3"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    got = {line.split()[1]: line.split()[2] for line in r.stdout.splitlines() if len(line.split()) == 3}
    assert got["first_difference"] == "-1" and int(float(got["collisions_compared"])) == 2000


def test_bench_json_and_module_name_their_instruction_set(tmp_path):
    # CMake's REVCOL_ISA (auto: x86-64-v3 where the machine runs it): a speed setting that the
    # benchmark's JSON records beside its figures, and the module reports
    import json
    import revcol
    out = tmp_path / "b.json"
    r = subprocess.run([_bench_binary(), "--bench", "floor/pair2d", "--collisions", "2000", "--repeats", "1",
                        "--json", str(out)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert json.loads(out.read_text())["isa"] in ("x86-64-v3", "baseline")
    assert revcol._core.isa in ("x86-64-v3", "baseline")


def test_floor_bench_reverses_and_reports_both_operators():
    # the floor is a real operator (it runs backwards to round-off) and both are timed; its
    # figures are benchmarks, never judged here
    r = subprocess.run([_bench_binary(), "--bench", "floor", "--collisions", "3000", "--repeats", "1"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    got = {}
    for line in r.stdout.splitlines():
        f = line.split()
        if len(f) == 3 and f[0].startswith("floor/"):
            got[(f[0], f[1])] = float(f[2])
    for case in ("floor/pair2d", "floor/pair3d"):
        for key in ("exact_forward_ns", "exact_reverse_ns", "floor_forward_ns", "floor_reverse_ns",
                    "ratio_forward", "ratio_reverse"):
            assert got[(case, key)] > 0.0, (case, key)
        assert got[(case, "floor_roundtrip_rel_err")] < 1e-9


def test_ab_compare_pairs_floor_cases(tmp_path):
    # bench/ab_compare.py on one build against itself: a floor case reports the operator's time
    # and its ratio to the floor per build, and the per-round paired ratios
    import json
    build = Path(_bench_binary()).parent
    out = tmp_path / "ab.json"
    script = Path(__file__).resolve().parents[2] / "bench" / "ab_compare.py"
    r = subprocess.run([sys.executable, str(script), "throughput", str(build), str(build), "--rounds", "2",
                        "--collisions", "2000", "--cpu", "-1", "--case", "floor/pair2d", "--json", str(out)],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    row = json.loads(out.read_text())["rows"][0]
    assert row["case"] == "floor/pair2d"
    for m in ("exact_forward_ns", "exact_reverse_ns", "ratio_forward", "ratio_reverse"):
        assert len(row[f"old_{m}"]["runs"]) == 2 and len(row[f"new_{m}"]["runs"]) == 2
        assert all(v > 0 for v in row[f"new_{m}"]["runs"])
        assert len(row[f"paired_new_over_old_{m}"]["ratios"]) == 2
    assert "forward_per_s" not in " ".join(row)


def test_op_ab_times_two_revisions_in_one_binary():
    # bench/op_ab/run.sh: HEAD's operator headers renamed beside the working tree's, both timed
    # in interleaved rounds; skipped outside a git checkout or without g++
    import shutil
    root = Path(__file__).resolve().parents[2]
    if not (root / ".git").exists() or shutil.which("g++") is None or shutil.which("git") is None:
        pytest.skip("bench/op_ab needs a git checkout and g++")
    r = subprocess.run(["bash", str(root / "bench" / "op_ab" / "run.sh"), "HEAD", "2"], capture_output=True,
                       text=True, timeout=600, env={**os.environ, "OP_AB_CPU": "0"})
    assert r.returncode == 0, r.stderr
    for op in ("pair2d", "pair3d"):
        line = next(x for x in r.stdout.splitlines() if x.startswith(op + " fwd"))
        assert "paired" in line and "| rev old" in line


def test_lattice_bench_storage_order_settings_keep_the_round_trip_exact(tmp_path):
    # lattice_study.py order: a random storage order (shuffle=1), re-sorted every neutral event per
    # particle (resort=1); the run back must still end on the starting bits
    out = tmp_path / "b.json"
    env = dict(os.environ, REVCOL_LATTICE="shuffle=1,resort=1")
    r = subprocess.run([_bench_binary(), "--bench", "lattice3d/periodic/n1000/phi0.3", "--collisions", "20000",
                        "--repeats", "1", "--json", str(out)], capture_output=True, text=True, timeout=300, env=env)
    assert r.returncode == 0, r.stderr
    m = {row["metric"]: row["median"] for row in json.loads(out.read_text())["results"]}
    assert m["bit_exact"] == 1.0
    assert m["resorts"] > 0
