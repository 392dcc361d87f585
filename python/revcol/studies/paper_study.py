"""The measurements of docs/paper-findings.md from the command line (JSON on stdout).

    python -m revcol.studies.paper_study failure-rate CASE [--collisions 1e6] [--pre chain|uniform]
                                 [--printed-reverse] [--cos-tol 1e-8] [--arc simpson|elliptic|table]
                                 [--angle parametric|polar] [--seed 0]
    python -m revcol.studies.paper_study bias CASE [--samples 1e6] [--states 3] [--reference rejection|exact|exact-vs-rejection]
    python -m revcol.studies.paper_study uniformity [--samples 1e8] [--angle parametric|polar]

CASE is one of pair3d, triple1d, triple2d-c1 .. triple2d-c4. The functions are
:func:`revcol.paper.failure_rate`, :func:`revcol.paper.bias` and :func:`revcol.paper.uniformity`.
(A module of its own: ``python -m revcol.paper`` would run a second copy of a module that
``import revcol`` has already loaded.)
"""
from __future__ import annotations

import argparse
import json
import sys
from typing import Sequence

from ..paper import PAPER_CASES, bias, failure_rate, uniformity

__all__ = ["main"]


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m revcol.studies.paper_study failure-rate|bias CASE [options] | uniformity``: prints JSON."""
    p = argparse.ArgumentParser(prog="python -m revcol.studies.paper_study", description=__doc__.split("\n")[0])
    sub = p.add_subparsers(dest="command", required=True)
    f = sub.add_parser("failure-rate", help="forward + reverse per collision; count the failures")
    f.add_argument("case", choices=PAPER_CASES)
    f.add_argument("--collisions", type=float, default=1e6)
    f.add_argument("--seed", type=int, default=0)
    f.add_argument("--pre", choices=("chain", "uniform"), default="chain")
    f.add_argument("--printed-reverse", action="store_true")
    f.add_argument("--cos-tol", type=float, default=1e-8)
    f.add_argument("--arc", choices=("simpson", "elliptic", "table"), default="simpson")
    f.add_argument("--angle", choices=("parametric", "polar"), default="parametric")
    b = sub.add_parser("bias", help="KS distance of the paper-mode post law from the uniform law")
    b.add_argument("case", choices=PAPER_CASES)
    b.add_argument("--samples", type=float, default=1e6)
    b.add_argument("--states", type=int, default=3)
    b.add_argument("--seed", type=int, default=0)
    b.add_argument("--arc", choices=("simpson", "elliptic", "table"), default="table")
    b.add_argument("--angle", choices=("parametric", "polar"), default="parametric")
    b.add_argument("--reference", choices=("rejection", "exact", "exact-vs-rejection"), default="rejection")
    u = sub.add_parser("uniformity", help="triple1d: one-sample KS of the post angle over S1 (large samples)")
    u.add_argument("--samples", type=float, default=1e8)
    u.add_argument("--states", type=int, default=3)
    u.add_argument("--seed", type=int, default=0)
    u.add_argument("--arc", choices=("simpson", "elliptic", "table"), default="table")
    u.add_argument("--angle", choices=("parametric", "polar"), default="parametric")
    args = p.parse_args(argv)
    try:
        if args.command == "failure-rate":
            r = failure_rate(args.case, collisions=int(args.collisions), seed=args.seed, pre=args.pre,
                             printed_reverse=args.printed_reverse, cos_tol=args.cos_tol, arc=args.arc,
                             angle=args.angle)
        elif args.command == "uniformity":
            r = uniformity(samples=int(args.samples), states=args.states, seed=args.seed, arc=args.arc,
                           angle=args.angle)
        else:
            opts = {"arc": args.arc, "angle": args.angle} if args.case == "triple1d" else {}
            r = bias(args.case, samples=int(args.samples), states=args.states, seed=args.seed,
                     reference=args.reference, **opts)
    except ValueError as e:
        print(f"python -m revcol.studies.paper_study: error: {e}", file=sys.stderr)
        return 2
    print(json.dumps(r))
    return 0


if __name__ == "__main__":
    sys.exit(main())
