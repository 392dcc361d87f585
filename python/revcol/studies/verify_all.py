"""Runs `revcol.verify` on every named case (exact mode, both laws) and writes the reports to
--out (default verify_exact.json) and a table to stdout.

    python -m revcol.studies.verify_all --collisions 1000000 --out bench/results/verify_exact.json
    python -m revcol.studies.verify_all --bits-scan 32 36 40 44 48 --cases pair3d triple2d-c1 chain4-1d \
        --out bench/results/exact_bits.json

The second form is the precision/memory trade-off of K (bits per chart coordinate): the
quantization error falls like 2^-K while the rare log grows until every collision logs
(bench/results/exact_bits.json; --out defaults to exact_bits.json with --bits-scan).
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from ..collide import named_cases
from ..verify import verify


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--collisions", type=int, default=1_000_000)
    p.add_argument("--rng", default="clcg4", choices=("clcg4", "philox"))
    p.add_argument("--bits", type=int, default=40)
    p.add_argument("--out", default=None)
    p.add_argument("--bits-scan", type=int, nargs="+", metavar="K", help="run these K instead")
    p.add_argument("--cases", nargs="+", default=None, help="named cases (default: all)")
    args = p.parse_args()
    if args.out is None:
        args.out = "exact_bits.json" if args.bits_scan else "verify_exact.json"
    cases = args.cases or [c["name"] for c in named_cases()]
    if args.bits_scan:
        return _bits_scan(args, cases)
    rows = []
    print(f"{'case':14s} {'law':8s} {'passed':7s} {'bit_exact':9s} {'max_rel_err':>11s} "
          f"{'fwd/s':>9s} {'rev/s':>9s} {'log B':>8s} {'log B/coll':>10s}")
    for case in cases:
        for law in ("flux", "uniform"):
            r = verify(case, collisions=args.collisions, mode="exact", law=law,
                              rng=args.rng, bits=args.bits)
            rows.append({k: r[k] for k in r if k not in ("initial", "final", "reference")})
            print(f"{case:14s} {law:8s} {str(r['passed']):7s} {str(r['bit_exact']):9s} "
                  f"{r['max_rel_error']:11.2e} {r['forward_per_s']:9.3g} {r['reverse_per_s']:9.3g} "
                  f"{r['log_bytes']:8d} {r['log_bytes'] / r['collisions']:10.2e}", flush=True)
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps({"command": _command(), "results": rows}, indent=1) + "\n")
    return 0 if all(r["passed"] for r in rows) else 1


def _command() -> str:
    return " ".join(["python", "-m", "revcol.studies.verify_all"] + sys.argv[1:])


def _bits_scan(args, cases) -> int:
    rows = []
    print(f"{'case':14s} {'K':>3s} {'passed':7s} {'bit_exact':9s} {'max_rel_err':>11s} {'log B/coll':>10s} {'fwd/s':>9s}")
    for case in cases:
        for bits in args.bits_scan:
            r = verify(case, collisions=args.collisions, mode="exact", law="flux", rng=args.rng, bits=bits)
            rows.append({k: r[k] for k in r if k not in ("initial", "final", "reference")} | {"bits": bits})
            print(f"{case:14s} {bits:3d} {str(r['passed']):7s} {str(r['bit_exact']):9s} {r['max_rel_error']:11.2e} "
                  f"{r['log_bytes'] / r['collisions']:10.2e} {r['forward_per_s']:9.3g}", flush=True)
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps({"command": _command(), "results": rows}, indent=1) + "\n")
    return 0 if all(r["passed"] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
