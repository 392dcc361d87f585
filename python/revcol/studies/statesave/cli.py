"""``revcol bench statesave``: its options (:func:`add_arguments`) and its run
(:func:`cli_main`: the study, the table, the files asked for; exit 0 when it passed).
"""
from __future__ import annotations

import argparse
import json
import shlex
import sys
from pathlib import Path
from typing import Sequence

from .output import format_table, markdown, plot, write_csv, write_json
from ...statesave import MODES
from .driver import study

__all__ = ["add_arguments", "cli_main"]


def _count(text: str) -> int:
    try:
        v = float(text) if any(ch in text.lower() for ch in "e.") else int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if v != int(v) or v < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return int(v)


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The options of ``revcol bench statesave``."""
    p.add_argument("--n", type=_count, nargs="+", default=[1000, 10000, 100000, 1000000],
                   help="particle counts N (default 1e3 1e4 1e5 1e6)")
    p.add_argument("--collisions", type=_count, default=1000, help="N_c (default 1000)")
    p.add_argument("--lazy", action="store_true", help="lazy transport (x0 = x - v t, O(1) per step)")
    p.add_argument("--mode", nargs="+", choices=MODES, default=["exact"], help="operator mode(s)")
    p.add_argument("--law", choices=("flux", "uniform"), default="flux", help="exact mode's law")
    p.add_argument("--variants", nargs="+", choices=("ss1", "ss2", "ssp", "rc"), default=None,
                   help="subset of variants (default: all the transport supports)")
    p.add_argument("--repeats", type=_count, default=3, help="runs per (mode, N, variant) (default 3)")
    p.add_argument("--budget-gib", type=float, default=8.0,
                   help="skip state saving that would save more (default 8 GiB)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--rng", choices=("clcg4", "philox"), default="clcg4")
    p.add_argument("--mean-dt", type=float, default=1e-5, help="mean inter-collision time")
    p.add_argument("--grazing-tol", type=float, default=1e-11, help="exact mode's pre log threshold")
    p.add_argument("--first-touch", action="store_true",
                   help="state saving faults its record pages in inside the forward time")
    p.add_argument("--binary", help="the revcol-bench to run (default: next to python, or on PATH)")
    p.add_argument("--inline", action="store_true", help="run in this process (peak RSS is then shared)")
    p.add_argument("--cpu", type=int, metavar="K", help="pin every run to core K (taskset); the variants "
                   "are interleaved round by round in any case")
    p.add_argument("--no-progress", action="store_true")
    p.add_argument("--json", metavar="FILE", help="write the report (and FILE's .csv next to it); - for standard output")
    p.add_argument("--csv", metavar="FILE", help="write the runs as CSV (default: next to --json)")
    p.add_argument("--plot", metavar="FILE", help="write the stacked bar plot (.png, .pdf or .svg)")
    p.add_argument("--markdown-from", metavar="JSON", help="print the markdown tables of a saved report (no run; "
                   "with --plot, redraw its figure)")


def cli_main(args: argparse.Namespace, argv: Sequence[str] | None = None) -> int:
    """Runs ``revcol bench statesave`` from parsed arguments; exit code 0 when it passed."""
    command = "revcol " + " ".join(shlex.quote(a) for a in (sys.argv[1:] if argv is None else argv))
    if args.markdown_from:
        try:
            saved = json.loads(Path(args.markdown_from).read_text())
        except (OSError, ValueError) as e:
            print(f"revcol bench statesave: error: --markdown-from: {e}", file=sys.stderr)
            return 2
        print(markdown(saved, Path(args.markdown_from).name))
        if args.plot:
            plot(saved, args.plot)
        return 0
    try:
        report = study(args.n, args.collisions, lazy=args.lazy, modes=args.mode, law=args.law,
                       variants=args.variants, repeats=args.repeats, budget_gib=args.budget_gib,
                       seed=args.seed, rng=args.rng, mean_dt=args.mean_dt, grazing_tol=args.grazing_tol,
                       prefault=not args.first_touch, binary=args.binary, inline=args.inline,
                       progress=False if args.no_progress else None, command=command, cpu=args.cpu)
    except (ValueError, FileNotFoundError) as e:
        print(f"revcol bench statesave: error: {e}", file=sys.stderr)
        return 2
    to_stdout = args.json == "-"  # `--json -`: the JSON alone on stdout, the table on stderr
    print(format_table(report), file=sys.stderr if to_stdout else sys.stdout)
    written = []
    if to_stdout:
        print(json.dumps(report, indent=1))
    elif args.json:
        write_json(report, args.json)
        written.append(args.json)
    csv_path = args.csv or (str(Path(args.json).with_suffix(".csv")) if args.json and not to_stdout else None)
    if csv_path:
        write_csv(report, csv_path)
        written.append(csv_path)
    if args.plot:
        plot(report, args.plot)
        written.append(args.plot)
    if written:
        print("written: " + " ".join(written), file=sys.stderr if to_stdout else sys.stdout)
    return 0 if report["passed"] else 1
