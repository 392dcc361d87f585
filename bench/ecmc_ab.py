"""Two builds of the event-chain sampler (revcol.studies.ecmc) interleaved, A B A B ..., pinned to one core.

Each measurement is a child process: the package directory of one build first on sys.path, a
random start (``ecmc.start``, seed 5), 2000 chains to warm up, then ``chains`` chains timed
by CPU time; it prints ns per lift and the chains' Z, which must be the same bits for both
builds when a change is meant to keep them.

    python3 bench/ecmc_ab.py OLD_PKG NEW_PKG --rounds 5 --cpu 0 --json bench/results/ecmc_cells_ab.json

(OLD_PKG, NEW_PKG: directories holding a ``revcol`` package with its ``_core`` module, as
scripts/dev_build.sh stages under build-dev/pkg.)
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

CASES = [(2, 0.6, 1000, 60000), (3, 0.45, 1000, 30000)]

CHILD = """
import sys, time, json
sys.path.insert(0, sys.argv[1])
try:
    from revcol.studies import ecmc
except ImportError:  # a build from before revcol.studies
    from revcol import ecmc
d, phi, n, chains = int(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5])
s = ecmc.start(d, phi, n, seed=5)
ell = ecmc.default_chain_length(d, phi)
s.run(2000, ell)
t = time.process_time(); r = s.run(chains, ell); dt = time.process_time() - t
print(json.dumps({"ns_per_lift": 1e9 * dt / r["lifts"], "z": r["z"], "lifts": r["lifts"]}))
"""


def one(pkg: str, case: tuple, cpu: int | None) -> dict:
    cmd = [sys.executable, "-c", CHILD, pkg] + [str(c) for c in case]
    if cpu is not None:
        cmd = ["taskset", "-c", str(cpu)] + cmd
    out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("a", help="package directory of build A")
    ap.add_argument("b", help="package directory of build B")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--cpu", type=int, help="pin every child to this core (taskset)")
    ap.add_argument("--scale", type=float, default=1.0, help="times the cases' chain counts (tests: 0.01)")
    ap.add_argument("--json")
    args = ap.parse_args(argv)
    runs = []
    for d, phi, n, chains in CASES:
        case = (d, phi, n, max(1, round(chains * args.scale)))
        for _ in range(args.rounds):
            for name, pkg in (("A", args.a), ("B", args.b)):
                r = one(pkg, case, args.cpu)
                r.update({"dim": case[0], "phi": case[1], "n": case[2], "chains": case[3], "build": name,
                          "load": os.getloadavg()[0]})
                runs.append(r)
                print(f"{case[0]}D phi {case[1]} {name}: {r['ns_per_lift']:.0f} ns/lift  Z {r['z']!r}  load {r['load']:.2f}")
    summary = {}
    for d, phi, _, _ in CASES:
        sel = [r for r in runs if (r["dim"], r["phi"]) == (d, phi)]
        a = [r["ns_per_lift"] for r in sel if r["build"] == "A"]
        b = [r["ns_per_lift"] for r in sel if r["build"] == "B"]
        ratio = [y / x for x, y in zip(a, b)]
        summary[f"{d}d_phi{phi}"] = {"A_median_ns": statistics.median(a), "A_range": [min(a), max(a)],
                                     "B_median_ns": statistics.median(b), "B_range": [min(b), max(b)],
                                     "paired_B_over_A_median": statistics.median(ratio),
                                     "paired_range": [min(ratio), max(ratio)],
                                     "same_z_bits": len({r["z"] for r in sel}) == 1}
        print(f"{d}D phi {phi}: B / A = {summary[f'{d}d_phi{phi}']['paired_B_over_A_median']:.3f} "
              f"[{min(ratio):.3f}, {max(ratio):.3f}], same Z bits: {summary[f'{d}d_phi{phi}']['same_z_bits']}")
    if args.json:
        sys.path.insert(0, args.b)
        from revcol._io import atomic_open
        with atomic_open(args.json) as fh:
            json.dump({"what": "event-chain sampler, two builds interleaved (bench/ecmc_ab.py)",
                       "command": "python3 bench/ecmc_ab.py " + " ".join(argv if argv is not None else sys.argv[1:]),
                       "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), "runs": runs,
                       "summary": summary}, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
