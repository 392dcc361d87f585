"""The long run of the fuzz suite (issue 17): every test of tests/python/test_fuzz.py with
REVCOL_FUZZ_EXAMPLES examples each, one pytest process per test, hypothesis's own statistics
parsed for the number of cases it really ran; the result is written atomically as JSON.

    .venv/bin/python tests/long/fuzz_long.py --examples 15000 --out bench/results/fuzz_long.json
"""
from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
TESTS = ["test_fuzz_named_operators", "test_fuzz_pair2d", "test_fuzz_generators", "test_fuzz_simulation_construction",
         "test_fuzz_run_and_run_back", "test_fuzz_damaged_snapshots", "test_fuzz_scene_files"]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--examples", type=int, default=15000, help="examples per test")
    ap.add_argument("--out", default=str(ROOT / "bench/results/fuzz_long.json"))
    ap.add_argument("--tests", nargs="*", default=TESTS)
    args = ap.parse_args()
    rows, total = [], 0
    for name in args.tests:
        t0 = time.time()
        env = dict(os.environ, REVCOL_FUZZ_EXAMPLES=str(args.examples))
        p = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "--hypothesis-show-statistics",
                            str(ROOT / "tests/python/test_fuzz.py"), "-k", name], env=env, capture_output=True, text=True)
        out = p.stdout + p.stderr
        passing = sum(int(x) for x in re.findall(r"(\d+) passing", out))
        failing = sum(int(x) for x in re.findall(r"(\d+) failing", out))
        invalid = sum(int(x) for x in re.findall(r"(\d+) invalid", out))
        row = {"test": name, "returncode": p.returncode, "passing_examples": passing, "failing_examples": failing,
               "invalid_examples": invalid, "seconds": round(time.time() - t0, 1),
               "tail": out.strip().splitlines()[-1] if out.strip() else ""}
        if p.returncode != 0:
            row["output"] = out[-4000:]
        rows.append(row)
        total += passing + failing
        print(json.dumps(row), flush=True)
    doc = {"what": "issue 17's fuzz suite, long run: every generated call succeeds or raises a named "
                   "ValueError/TypeError, state unchanged after errors, no crash, no hang (20 s per case)",
           "command": f"{sys.executable} tests/long/fuzz_long.py --examples {args.examples}",
           "commit": subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                                    text=True).stdout.strip(),
           "load_at_end": os.getloadavg(), "cases": total, "all_passed": all(r["returncode"] == 0 for r in rows),
           "tests": rows}
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=out.parent, suffix=".tmp")
    with os.fdopen(fd, "w") as f:
        json.dump(doc, f, indent=1)
    os.replace(tmp, out)
    print(f"{total} cases, all passed: {doc['all_passed']}")
    return 0 if doc["all_passed"] else 1


if __name__ == "__main__":
    sys.exit(main())
