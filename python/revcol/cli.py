"""The ``revcol`` command line.

    revcol verify pair2d --collisions 1000000 --mode exact --law flux --rng clcg4 --seed 0 --json
    revcol bench statesave --n 1000 10000 100000 1000000 --collisions 1000 [--lazy] --json out.json --plot out.png
"""
from __future__ import annotations

import argparse
import json
import sys

from . import statesave
from .verify import VERIFY_CASES, verify


def _positive_int(text: str) -> int:
    try:
        value = int(float(text)) if "e" in text.lower() else int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return value


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="revcol", description="Reversible elastic collisions.")
    sub = p.add_subparsers(dest="command", required=True)
    v = sub.add_parser("verify", help="run the paper's reversal illustration and check the round trip")
    v.add_argument("case", choices=VERIFY_CASES)
    v.add_argument("--collisions", type=_positive_int, default=1_000_000, help="N_c (default 1e6)")
    v.add_argument("--mode", choices=("exact", "paper"), default="exact")
    v.add_argument("--law", choices=("flux", "uniform"), default="flux", help="exact mode's law")
    v.add_argument("--rng", choices=("clcg4", "philox"), default="clcg4")
    v.add_argument("--seed", type=int, default=0)
    v.add_argument("--bits", type=int, default=40, help="K, bits per chart coordinate")
    v.add_argument("--printed-reverse", action="store_true",
                   help="paper mode: use the printed Procedure 2 (tests the post angle)")
    v.add_argument("--json", nargs="?", const="-", metavar="FILE",
                   help="write the report as JSON to FILE (or stdout when no FILE)")
    b = sub.add_parser("bench", help="benchmark studies")
    bsub = b.add_subparsers(dest="study", required=True)
    statesave.add_arguments(bsub.add_parser(
        "statesave", help="the paper's state saving vs reverse computation study (and lazy transport)"))
    return p


def _summary(r: dict) -> str:
    mode = r["mode"] + (f"/{r['law']}" if r["mode"] == "exact" and r["case"] != "pair1d" else "")
    return "\n".join([
        f"revcol verify {r['case']}  mode={mode}  rng={r['rng']}  seed={r['seed']}",
        f"  collisions          {r['collisions']:,} forward, {r['collisions']:,} back",
        f"  forward             {r['forward_per_s']:.3g} collisions/s",
        f"  reverse             {r['reverse_per_s']:.3g} collisions/s",
        f"  max relative error  {r['max_rel_error']:.3g}  (bar: 1e-9)",
        f"  bit exact           {r['bit_exact']}",
        f"  rng restored        {r['rng_restored']}  ({r['random_numbers_drawn']:,} drawn)",
        f"  rare log            {r['log_bytes']} bytes at the turn",
        f"  result              {'PASSED' if r['passed'] else 'FAILED'}",
    ] + ([f"  stopped             {r['error']}"] if r.get("error") else []))


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    if args.command == "verify":
        try:
            report = verify(args.case, collisions=args.collisions, mode=args.mode, law=args.law,
                            rng=args.rng, seed=args.seed, bits=args.bits,
                            printed_reverse=args.printed_reverse)
        except ValueError as e:
            print(f"revcol verify: error: {e}", file=sys.stderr)
            return 2
        if args.json == "-":
            print(json.dumps(report))
        else:
            print(_summary(report))
            if args.json:
                with open(args.json, "w") as f:
                    json.dump(report, f, indent=1)
        return 0 if report["passed"] else 1
    if args.command == "bench":
        return statesave.cli_main(args, argv)
    return 2


if __name__ == "__main__":
    sys.exit(main())
