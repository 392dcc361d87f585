#!/usr/bin/env python3
"""Benchmark driver: runs revcol-bench, writes its JSON and CSV under bench/results/, and
prints a table. All benchmarks of one invocation run side by side in one process, so
their ratios are comparable even on a shared, noisy machine.

    python bench/run_bench.py                      # everything, 5 repeats, 1e6 collisions
    python bench/run_bench.py --bench pair2d --repeats 7 --collisions 2000000
"""
from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import platform
import shutil
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent


def find_binary(explicit: str | None) -> str:
    if explicit:
        return explicit
    for cand in (shutil.which("revcol-bench"), Path(sys.executable).parent / "revcol-bench"):
        if cand and Path(cand).exists():
            return str(cand)
    sys.exit("run_bench: revcol-bench not found (pip install . puts it next to python; or pass --binary)")


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--binary")
    p.add_argument("--bench", action="append", default=[], help="name or prefix (repeatable)")
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--collisions", type=int, default=1_000_000)
    p.add_argument("--out", default=str(HERE / "results"), help="folder for the JSON and CSV")
    p.add_argument("--tag", default="", help="suffix for the result file names")
    args = p.parse_args()

    binary = find_binary(args.binary)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    stem = "bench" + (f"-{args.tag}" if args.tag else "")
    json_path, csv_path = out / f"{stem}.json", out / f"{stem}.csv"
    cmd = [binary, "--repeats", str(args.repeats), "--collisions", str(args.collisions),
           "--json", str(json_path), "--csv", str(csv_path)]
    for b in args.bench:
        cmd += ["--bench", b]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)

    data = json.loads(json_path.read_text())
    data["machine"] = {"platform": platform.platform(), "processor": platform.processor(),
                       "cpus": os.cpu_count(), "python": platform.python_version()}
    data["command"] = " ".join([Path(sys.argv[0]).name] + sys.argv[1:])
    data["date"] = dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds")
    json_path.write_text(json.dumps(data, indent=1) + "\n")
    print(f"{'benchmark':30s} {'metric':16s} {'median':>14s}")
    for r in data["results"]:
        print(f"{r['bench']:30s} {r['metric']:16s} {r['median']:14.4g}")
    print(f"\nwritten: {json_path} {csv_path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
