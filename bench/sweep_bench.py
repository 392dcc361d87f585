"""The default scene's horizon over K seeds: ``revcol sweep`` on a LocalCluster against the serial
``revcol run --horizon --seeds K`` (issue 20). Both run as subprocesses of this script, one after
the other; the sweep's seeds combined must equal the serial report's rows exactly, and the
speed-up is the serial wall time over the sweep's (ideal: the number of workers). The machine's
load average is recorded before and after each, since the machine may be shared.

    PYTHONPATH=build-dev/pkg .venv/bin/python bench/sweep_bench.py --seeds 200 --workers 2 --repeats 2 \
        --json bench/results/sweep_default_horizon.json
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
STABLE = ("collisions", "per_particle", "bit_for_bit", "seeds", "errors")


def _timed(cmd: list[str]) -> dict:
    """Runs ``cmd``; its wall and CPU seconds (children's rusage) and the load around it."""
    load0, c0, t0 = os.getloadavg(), resource.getrusage(resource.RUSAGE_CHILDREN), time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True)
    wall, c1 = time.perf_counter() - t0, resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({p.returncode}):\n{p.stderr}")
    return {"command": " ".join(cmd), "wall_s": wall, "cpu_s": (c1.ru_utime - c0.ru_utime) + (c1.ru_stime - c0.ru_stime),
            "loadavg_before": list(load0), "loadavg_after": list(os.getloadavg()), "stderr_tail": p.stderr[-600:]}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=200)
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--repeats", type=int, default=1,
                    help="pairs of runs, in the order serial sweep, sweep serial, ... (a shared machine's load drifts)")
    ap.add_argument("--json", required=True)
    a = ap.parse_args(argv)
    pairs = [_pair(a, k % 2 == 1) for k in range(a.repeats)]
    speedups = sorted(p["speedup"] for p in pairs)
    result = {
        "what": f"the default scene's horizon over {a.seeds} seeds: revcol sweep on a LocalCluster of {a.workers} "
                "workers against the serial revcol run --horizon",
        "seeds": a.seeds, "workers": a.workers, "cpu_count": os.cpu_count(), "ideal_speedup": a.workers,
        "rows_equal": all(p["rows_equal"] for p in pairs), "speedups": [p["speedup"] for p in pairs],
        "speedup_median": speedups[len(speedups) // 2] if len(speedups) % 2 else
        0.5 * (speedups[len(speedups) // 2 - 1] + speedups[len(speedups) // 2]),
        # CPU seconds of the serial run over the sweep's (all its processes): the share of the sweep's
        # work that is the points themselves; on an idle machine the speed-up approaches workers x this
        "cpu_ratio": [p["serial"]["cpu_s"] / p["sweep"]["cpu_s"] for p in pairs],
        "pairs": pairs, "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
    }
    Path(a.json).parent.mkdir(parents=True, exist_ok=True)
    Path(a.json).write_text(json.dumps(result, indent=1) + "\n")
    for p in pairs:
        print(f"rows equal: {p['rows_equal']}; serial {p['serial']['wall_s']:.1f} s ({p['serial']['cpu_s']:.1f} s CPU), "
              f"sweep {p['sweep']['wall_s']:.1f} s ({p['sweep']['cpu_s']:.1f} s CPU), speed-up {p['speedup']:.2f} "
              f"(ideal {a.workers}); load {p['serial']['loadavg_before']} -> {p['sweep']['loadavg_after']}")
    return 0 if result["rows_equal"] else 1


def _pair(a, sweep_first: bool) -> dict:
    """One serial run and one sweep of the same seeds; their times and whether the rows agree."""
    py = [sys.executable, "-m", "revcol"]
    with tempfile.TemporaryDirectory() as tmp:
        sweep_file = Path(tmp) / "default-horizon.toml"
        text = (ROOT / "sweeps" / "default-horizon.toml").read_text()
        sweep_file.write_text(text.replace("count = 200", f"count = {a.seeds}"))
        runs = {}
        for what in (("sweep", "serial") if sweep_first else ("serial", "sweep")):
            if what == "serial":
                runs[what] = _timed(py + ["run", "--horizon", "--seeds", str(a.seeds), "--json", f"{tmp}/serial.json",
                                          "--no-progress"])
            else:
                runs[what] = _timed(py + ["sweep", str(sweep_file), "--workers", str(a.workers), "--out", f"{tmp}/out",
                                          "--no-progress"])
        ref = json.loads(Path(f"{tmp}/serial.json").read_text())
        summary = json.loads(Path(f"{tmp}/out/default-horizon.json").read_text())
        # the points' own run times (inside the workers): against the serial wall time they show
        # how much of each core the workers got on this (possibly shared) machine
        task_s = sum(json.loads(f.read_text())["seconds"] for f in Path(f"{tmp}/out/points").glob("*.json"))
    (combined,) = summary["combined"]
    equal = [{k: r[k] for k in STABLE} for r in combined["rows"]] == [{k: r[k] for k in STABLE} for r in ref["rows"]]
    return {"order": "sweep, serial" if sweep_first else "serial, sweep", "serial": runs["serial"],
            "sweep": runs["sweep"], "speedup": runs["serial"]["wall_s"] / runs["sweep"]["wall_s"], "rows_equal": equal,
            "serial_rows": ref["rows"], "sweep_rows": combined["rows"], "serial_passed": ref["passed"],
            "sweep_passed": combined["passed"], "sweep_points": summary["points"], "sweep_done": summary["done"],
            "sweep_failed": summary["failed"], "sweep_cluster": summary["cluster"],
            "sweep_seconds_in_process": summary["seconds"], "sweep_task_seconds_sum": task_s}


if __name__ == "__main__":
    sys.exit(main())
