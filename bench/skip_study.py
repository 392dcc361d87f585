"""What a pair-only scene does not pay for (issue "skip what a scene doesn't need").

    python3 bench/skip_study.py [--bin build-dev/revcol-bench] [--rounds 5] [--collisions 200000]

Runs revcol-bench's skip/* benchmarks (bench/skip_bench.cpp), each in a fresh process and
alternating the two gas variants round by round (the machine is shared: side by side, not
one after the other), and writes bench/results/skip.json with the medians:

- skip/gas2d-pairs: the default scene's gas (2D, N = 1000, area fraction 0.3, walls, exact
  mode, flux law): start-up (make_simulation) and ns per collision forward and back, and how
  many paper-mode GSL tables the process built (0 expected);
- skip/gas2d-forced-groups: the same gas with the 3-particle group search run at every
  collision (what the engine would pay without the gate that runs it only when a group is
  possible);
- skip/paper-tables: the one-time build of the three tables a scene with paper-mode triples
  needs (calotte areas H4 and H3, the ellipse-arc inverse), each in a fresh process.
"""
from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import statistics
import subprocess
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
RESULTS = os.path.join(HERE, "results")


def bench(binary: str, name: str, collisions: int) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "r.json")
        subprocess.run([binary, "--bench", name, "--collisions", str(collisions), "--repeats", "1", "--json", out],
                       check=True, capture_output=True)
        with open(out) as f:
            return {r["metric"]: r["median"] for r in json.load(f)["results"] if r["bench"] == name}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bin", default=os.path.join(HERE, "..", "build-dev", "revcol-bench"))
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--collisions", type=int, default=200000)
    ap.add_argument("--out", default=os.path.join(RESULTS, "skip.json"))
    a = ap.parse_args()
    names = ["skip/gas2d-pairs", "skip/gas2d-forced-groups", "skip/paper-tables"]
    runs: dict[str, list[dict]] = {n: [] for n in names}
    for _ in range(a.rounds):
        for n in names:
            runs[n].append(bench(a.bin, n, a.collisions))
    medians = {n: {m: statistics.median(r[m] for r in rs) for m in rs[0]} for n, rs in runs.items()}
    pairs, forced = medians["skip/gas2d-pairs"], medians["skip/gas2d-forced-groups"]
    tables = medians["skip/paper-tables"]
    summary = {
        "pair_scene_startup_ms": pairs["startup_ms"],
        "pair_scene_tables_built": pairs["paper_tables_built"],
        "paper_tables_build_ms": tables["build_ms_calotte_h4"] + tables["build_ms_calotte_h3"]
        + tables["build_ms_ellipse_table"],
        "forward_ns_pairs": pairs["forward_ns_per_collision"],
        "forward_ns_forced_groups": forced["forward_ns_per_collision"],
        "forced_over_pairs_forward": forced["forward_ns_per_collision"] / pairs["forward_ns_per_collision"],
        "reverse_ns_pairs": pairs["reverse_ns_per_collision"],
        "reverse_ns_forced_groups": forced["reverse_ns_per_collision"],
        "forced_over_pairs_reverse": forced["reverse_ns_per_collision"] / pairs["reverse_ns_per_collision"],
    }
    doc = {"command": "python3 bench/skip_study.py " + " ".join(
        f"--{k} {v}" for k, v in (("rounds", a.rounds), ("collisions", a.collisions))),
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "machine": f"{platform.machine()} {os.cpu_count()} cores, {platform.platform()}",
        "summary": summary, "medians": medians, "runs": runs}
    os.makedirs(os.path.dirname(a.out), exist_ok=True)
    with open(a.out, "w") as f:
        json.dump(doc, f, indent=1)
    for k, v in summary.items():
        print(f"{k:28s} {v:.4g}")


if __name__ == "__main__":
    main()
