"""The ``revcol`` command line.

    revcol run [SCENE.toml] [--json FILE] [--plot DIR] [--trajectory FILE.xyz|.gsd] [--collisions N] [--seed S]
               [--engine float|lattice] [--mode exact|paper|specular] [--max-output SIZE]
               [--tick-bits T] [--cell-bits C] [--search auto|cells|SHELL] [--workers K]
    revcol run [SCENE.toml] --horizon [--seeds K] [--max-collisions N] [--engine float] [--json FILE] [--plot DIR]
    revcol simulate [SCENE] [--collisions N | --time T] [--trajectory FILE --every K|--every-time T] [--checkpoint DIR
               --checkpoint-every K] [--resume CHECKPOINT] [--species Ar] [--json FILE]   (forward only)
               [--engine float|lattice] [--mode exact|paper|specular] [--max-output SIZE]
               [--tick-bits T] [--cell-bits C] [--search auto|cells|SHELL] [--workers K]   (lattice engine)
    revcol verify pair2d --collisions 1000000 --mode exact --law flux --rng clcg4 --seed 0 --json
    revcol bench statesave --n 1000 10000 100000 1000000 --collisions 1000 [--lazy] --json out.json --plot out.png
    revcol bench tradeoff [--reduced] [--repeats 3] --json bench/results/tradeoff.json --plot docs/figures/tradeoff
    revcol study randomness battery|controls|matrix|words|coverage ...   (= python -m revcol.studies.randomness ...)
    revcol study equilibrium small|dense|walls|mc|mc-compare|figures|table ...   (= python -m revcol.studies.equilibrium ...)
    revcol study stability [--full] [--json FILE] [--markdown]   (= python -m revcol.studies.stability ...)
    revcol sweep SWEEP.toml|NAME [--out DIR] [--workers K | --scheduler tcp://HOST:PORT | --scheduler-file F]
                 [--max-output SIZE]
    revcol --version

Manners (issue 19): a mistyped subcommand, choice or option gets a "did you mean" suggestion
(difflib; argparse's own ``suggest_on_error`` exists from Python 3.14 only) and the usage of the
subcommand it was given to; ``--json -`` writes the JSON report to standard output (the text
report then goes to standard error); a closed pipe (``revcol ... | head -1``) ends the command
quietly with status 141 (128 + SIGPIPE, as a Unix tool killed by SIGPIPE), no traceback; an
optional package that is missing (matplotlib, gsd, Dask, scipy) is one line naming the extra that
installs it (``pip install 'revcol[plot]'``, revcol._extras) and status 2.
"""
from __future__ import annotations

import argparse
import dataclasses
import difflib
import json
import os
import sys
import warnings

from .._extras import missing_extra
from .._io import atomic_open, jsonable
from .._version import __version__
from ..scene import SceneError, load_scene
from ..studies import equilibrium, randomness, stability, statesave, tradeoff
from ..sweep import SweepError, sweep
from ..verify import VERIFY_CASES, verify
from .report import verify_lines
from .run import run_command
from .simulate import format_simulate, simulate


def _positive_int(text: str) -> int:
    try:
        value = int(float(text)) if "e" in text.lower() else int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return value


def _seed(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer 0 .. 2^32 - 1, got {text!r}") from None
    if not 0 <= value < 2**32:
        raise argparse.ArgumentTypeError(f"expected an integer 0 .. 2^32 - 1, got {text!r}")
    return value


def _positive_real(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}") from None
    if not (value > 0 and value != float("inf")):
        raise argparse.ArgumentTypeError(f"expected a positive finite number, got {text!r}")
    return value


def _search(text: str):
    """``--search``: "auto", "cells" or a shell in diameters (its range is checked with the scene's)."""
    if text in ("auto", "cells"):
        return text
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected 'auto', 'cells' or a shell in diameters (0.02..2), got {text!r}") from None


def _lattice_flags(p: argparse.ArgumentParser) -> None:
    """The lattice engine's options, overriding the scene's [collisions] tick_bits, cell_bits, search."""
    g = p.add_argument_group("lattice engine", "override the scene's [collisions] fields; refused on the float engine")
    g.add_argument("--tick-bits", type=int, metavar="T", help="a particle of rms speed moves 2^-T diameters per "
                   "tick, 16..26 (default: automatic)")
    g.add_argument("--cell-bits", type=int, metavar="C", help="2^C direction cells per turn, 12..20 (default 16)")
    g.add_argument("--search", type=_search, metavar="S", help="neighbour search: 'auto' (lists in 3D, cells in 2D), "
                   "'cells', or lists with a shell of S diameters, 0.02..2; the run is the same bit for bit")
    g.add_argument("--workers", type=int, metavar="K", help="run forward on the parallel engine, K threads and "
                   "slabs, 1..64 (docs/parallel.md); the run is the same bit for bit")


#: the collision modes --mode takes (a scene's [collisions] mode; the engine's own are checked with the scene)
MODES = ("exact", "paper", "specular")


def _mode_flag(p: argparse.ArgumentParser) -> None:
    """``--mode``, overriding the scene's [collisions] mode (checked as the scene file would be)."""
    p.add_argument("--mode", choices=MODES, help="run a gas scene in this collision mode instead of its [collisions] "
                   "mode: exact, paper (float engine, 1D and 2D) or specular (deterministic specular dynamics, no "
                   "draws; on the lattice engine reversed bit for bit); a law the scene names needs exact")


def _max_output_flag(p: argparse.ArgumentParser) -> None:
    """``--max-output``, overriding the scene's [output] max_output (checked by the run: exit 2 naming it)."""
    p.add_argument("--max-output", metavar="SIZE", help="refuse to start when the outputs (trajectory, checkpoints, "
                   "report, figures) are estimated to need more than SIZE: bytes or K, M, G, T (powers of 1024), "
                   "e.g. 20G; 0 or none: no limit (default: the scene's [output] max_output, else 10G). A run "
                   "whose outputs would not fit in the free space is refused too")


def _did_you_mean(word: str, candidates) -> str:
    """`` (did you mean 'x'?)`` for the closest candidate to a mistyped ``word``, or ``""``."""
    close = difflib.get_close_matches(word, [str(c) for c in candidates], n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


class _Parser(argparse.ArgumentParser):
    """argparse with typo suggestions for choices (subcommands included) and unknown options;
    an unknown option is reported with the usage of the subcommand it was given to."""

    def _check_value(self, action, value):  # argparse's hook for choices (3.11-3.13; 3.14 has its own)
        try:
            super()._check_value(action, value)
        except argparse.ArgumentError as e:
            choices = action.choices if action.choices is not None else ()
            raise argparse.ArgumentError(action, e.message + _did_you_mean(str(value), choices)) from None

    def parse_args(self, args=None, namespace=None):
        ns, extras = self.parse_known_args(args, namespace)
        if extras:
            target = self._chosen(ns)
            options = [s for a in target._actions for s in a.option_strings]
            hints = "".join(_did_you_mean(w.split("=", 1)[0], options) for w in extras if w.startswith("-"))
            target.error(f"unrecognized arguments: {' '.join(extras)}{hints}")
        return ns

    def _chosen(self, ns: argparse.Namespace) -> "argparse.ArgumentParser":
        """The innermost subcommand's parser that ``ns`` went through."""
        for a in self._actions:
            if isinstance(a, argparse._SubParsersAction) and getattr(ns, a.dest, None) in a.choices:
                sub = a.choices[getattr(ns, a.dest)]
                return sub._chosen(ns) if isinstance(sub, _Parser) else sub
        return self


def _parser() -> argparse.ArgumentParser:
    p = _Parser(prog="revcol", description="Reversible elastic collisions.")
    p.add_argument("--version", action="version", version=f"revcol {__version__}")
    sub = p.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="run a scene forward and back to its start, and report the round trip",
                       description="Run a scene (TOML; default: the built-in 2D hard-disk gas on the lattice "
                       "engine, 10^6 collisions) forward and back to its start and report the round trip. Exit 0 "
                       "when it passes (lattice engine: every part of the state restored bit for bit; float "
                       "engine: both errors <= 1e-9), 1 when it fails, 2 on a bad scene or option, 130 when "
                       "interrupted.")
    r.add_argument("scene", nargs="?", help="scene file, or the name of a scene shipped with revcol "
                   "(e.g. spheres-3d; see scenes/ and docs/run.md)")
    r.add_argument("--json", metavar="FILE", help="write the report as JSON ('-': to standard output, and the "
                   "text report to standard error)")
    r.add_argument("--plot", metavar="DIR", help="write the figures into DIR (needs matplotlib)")
    r.add_argument("--plot-format", choices=("png", "pdf", "svg"), default="png",
                   help="the figures' file format (default png; pdf and svg are vector)")
    r.add_argument("--trajectory", metavar="FILE",
                   help="write frames forward and through the reversal: FILE.xyz (extended XYZ) or FILE.gsd")
    r.add_argument("--horizon", action="store_true",
                   help="measure the round-trip error against collisions per particle instead (a lattice "
                   "scene has no horizon: its round trip is checked bit for bit at a few N_c)")
    r.add_argument("--seeds", type=_positive_int, default=None, metavar="K",
                   help="--horizon: worst error over this many seeds, from the scene's (default 1)")
    r.add_argument("--max-collisions", type=_positive_int, default=1_000_000, metavar="N",
                   help="--horizon: the largest N_c tried (default 1e6)")
    r.add_argument("--collisions", type=_positive_int, metavar="N", help="N_c instead of the scene's [run] collisions/time")
    r.add_argument("--seed", type=_seed, metavar="S", help="seed instead of the scene's [rng] seed")
    r.add_argument("--engine", choices=("float", "lattice"),
                   help="run a gas scene on this engine instead of its [collisions] engine (with --horizon: "
                   "--engine float measures the float engine's horizon for a lattice scene's gas)")
    _mode_flag(r)
    _max_output_flag(r)
    r.add_argument("--no-progress", action="store_true", help="no progress bar (off anyway when not a terminal)")
    _lattice_flags(r)
    _simulate_parser(sub)
    _sweep_parser(sub)
    v = sub.add_parser("verify", help="run the paper's reversal illustration and check the round trip",
                       description="Run one of the paper's reversal illustrations (a pair, a triple, a chain "
                       "or a cradle, in 1D to 3D: N_c collisions of the same bodies, their velocities negated "
                       "after each) forward with the reversible operator, then back with the generator stepping "
                       "back, and compare with the start: passed when the generator is restored, the rare log "
                       "empty, the error within the paper's bar of 1e-9, and (exact mode) the start's quantized "
                       "velocities restored bit for bit. Exit 0 when it passes, 1 when it fails, 2 on a bad option.")
    v.add_argument("case", choices=VERIFY_CASES, help="the collision sequence (the paper's names)")
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
    # revcol bench tradeoff (issue 18): run time against error
    tradeoff.add_arguments(bsub.add_parser(
        "tradeoff", help="run time against error for every operator and accuracy knob, with Pareto plots"))
    st = sub.add_parser("study", help="studies (their arguments go to the study's module)")
    stsub = st.add_subparsers(dest="study", required=True)
    rnd = stsub.add_parser("randomness", add_help=False,
                           help="the paper's randomness (dieharder) and coverage experiments: python -m revcol.studies.randomness")
    rnd.add_argument("rest", nargs=argparse.REMAINDER)
    eq = stsub.add_parser("equilibrium", add_help=False,
                          help="does a collision law keep equilibrium (two particles exactly, dense gases against "
                          "the equations of state and against event-chain Monte Carlo of the same N): "
                          "python -m revcol.studies.equilibrium")
    eq.add_argument("rest", nargs=argparse.REMAINDER)
    stab = stsub.add_parser("stability", add_help=False,
                            help="the numerical stress suite, every class for every operator: python -m revcol.studies.stability")
    stab.add_argument("rest", nargs=argparse.REMAINDER)
    return p


def _summary(r: dict) -> str:
    mode = r["mode"] + (f"/{r['law']}" if r["mode"] == "exact" and r["case"] != "pair1d" else "")
    return "\n".join([f"revcol verify {r['case']}  mode={mode}  rng={r['rng']}  seed={r['seed']}"] + verify_lines(r))


def _simulate_parser(sub) -> None:
    s = sub.add_parser("simulate", help="run a gas scene forward only (any length), with frames, checkpoints and "
                       "observables", description="Run a gas scene forward only, for any number of collisions or "
                       "any time (revcol run is the forward-and-back job). Outputs are triggered every K "
                       "collisions (the net count since the scene's start). Exit 0 when it ran, 1 when the engine "
                       "stopped on an error, 2 on a bad scene or option, 130 when interrupted (Ctrl-C: outputs "
                       "written and closed).")
    s.add_argument("scene", nargs="?", help="scene file, or the name of a scene shipped with revcol (default: the "
                   "built-in 2D gas)")
    length = s.add_mutually_exclusive_group()
    length.add_argument("--collisions", type=_positive_int, metavar="N", help="run N collisions (default: the "
                        "scene's [run] collisions or time)")
    length.add_argument("--time", type=_positive_real, metavar="T", help="run for T units of time")
    s.add_argument("--trajectory", metavar="FILE", help="frames at the start, every K collisions and at the end: "
                   "FILE.xyz (extended XYZ) or FILE.gsd")
    s.add_argument("--every", type=_positive_int, metavar="K", help="collisions between frames (default: the "
                   "scene's [output] trajectory_every)")
    s.add_argument("--every-time", type=_positive_real, metavar="T", help="frames at every multiple of T in time "
                   "instead (independent of the collisions: what g(r) at contact needs)")
    s.add_argument("--checkpoint", metavar="DIR", help="write checkpoint-<collisions>.npz into DIR every K "
                   "collisions and at the end")
    s.add_argument("--checkpoint-every", type=_positive_int, metavar="K", help="collisions between checkpoints")
    s.add_argument("--resume", metavar="FILE", help="continue from a checkpoint of this scene (bit for bit)")
    s.add_argument("--seed", type=_seed, metavar="S", help="seed instead of the scene's [rng] seed")
    s.add_argument("--engine", choices=("float", "lattice"), help="run the scene on this engine instead")
    _mode_flag(s)
    _max_output_flag(s)
    s.add_argument("--species", default="Ar", metavar="X", help="the trajectory's chemical element symbol "
                   "(default Ar; ASE reads element symbols only)")
    s.add_argument("--json", metavar="FILE", help="write the report as JSON ('-': to standard output, and the "
                   "text report to standard error)")
    s.add_argument("--no-progress", action="store_true", help="no progress bar (off anyway when not a terminal)")
    _lattice_flags(s)


def _simulate(args: argparse.Namespace) -> int:
    """``revcol simulate``: exit 0 ran, 1 engine error, 2 bad scene/option, 130 interrupted."""
    to_stdout = args.json == "-"
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("always", DeprecationWarning)
            warnings.showwarning = lambda message, *rest: print(f"revcol simulate: warning: {message}",
                                                                 file=sys.stderr)
            scene = load_scene(args.scene)
            if to_stdout:
                scene = dataclasses.replace(scene, json=None)
            report = simulate(scene, collisions=args.collisions, time=args.time, trajectory=args.trajectory,
                              every=args.every, checkpoints=args.checkpoint, checkpoint_every=args.checkpoint_every,
                              resume=args.resume, seed=args.seed, engine=args.engine, species=args.species,
                              tick_bits=args.tick_bits, cell_bits=args.cell_bits, search=args.search,
                              workers=args.workers, mode=args.mode,
                              json_path=None if to_stdout else args.json, max_output=args.max_output,
                              progress=False if args.no_progress else None, every_time=args.every_time)
    except (SceneError, OSError) as e:
        print(f"revcol simulate: error: {e}", file=sys.stderr)
        return 2
    except MemoryError:
        print("revcol simulate: error: not enough memory for this scene", file=sys.stderr)
        return 2
    print(format_simulate(report), file=sys.stderr if to_stdout else sys.stdout)
    if to_stdout:
        print(json.dumps(jsonable(report), indent=1))
    if report["interrupted"]:
        return 130
    return 1 if report["engine_error"] else 0


# --- revcol sweep (issue 20): many runs of one study on Dask distributed ---------------------------

def _sweep_parser(sub) -> None:
    s = sub.add_parser("sweep", help="run a sweep file's points (a study over seeds, N, packing fraction, ...) on "
                       "Dask distributed", description="Run every point of a sweep file (TOML, docs/sweep.md) as a "
                       "Dask task: on a local cluster of this machine's cores by default, or on a running cluster "
                       "(--scheduler / --scheduler-file). Each point's report is written as it finishes "
                       "(OUT/points/HASH.json); a sweep run again does only the points not yet written. Exit 0 when "
                       "every point is done, 1 when some failed, 2 on a bad sweep file or option, 130 when "
                       "interrupted (run it again to resume).")
    s.add_argument("sweep_file", metavar="SWEEP.toml", help="the sweep file (e.g. sweeps/default-horizon.toml)")
    s.add_argument("--out", metavar="DIR", help="output folder (default ./out/sweeps/NAME, beside the scenes' ./out)")
    where = s.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, metavar="K", help="local cluster of K worker processes, one thread "
                       "each (default: the number of cores; 0: no Dask, one point after another here)")
    where.add_argument("--scheduler", metavar="tcp://HOST:PORT", help="run on this running Dask scheduler's workers")
    where.add_argument("--scheduler-file", metavar="FILE", help="run on the Dask cluster this scheduler file names")
    s.add_argument("--no-progress", action="store_true", help="no progress bar (off anyway when not a terminal)")
    s.add_argument("--max-output", metavar="SIZE", help="refuse to start when the sweep's outputs (a report per point "
                   "still to run, the table, the summary, the figures) are estimated to need more than SIZE: bytes "
                   "or K, M, G, T (powers of 1024), e.g. 20G; 0 or none: no limit (default 10G). A sweep whose "
                   "outputs would not fit in the free space is refused too")


def _sweep(args: argparse.Namespace) -> int:
    """``revcol sweep``: exit 0 all done, 1 some points failed, 2 bad sweep file/option, 130 interrupted."""
    if args.workers is not None and args.workers < 0:
        print(f"revcol sweep: error: --workers must be >= 0, got {args.workers}", file=sys.stderr)
        return 2
    try:
        summary = sweep(args.sweep_file, out=args.out, workers=args.workers, scheduler=args.scheduler,
                        scheduler_file=args.scheduler_file, progress=False if args.no_progress else None,
                        log=lambda line: print(line, file=sys.stderr), max_output=args.max_output)
    except (SweepError, OSError) as e:
        print(f"revcol sweep: error: {e}", file=sys.stderr)
        return 2
    for f in summary["failed"]:
        print(f"revcol sweep: point {f['index']} ({f['point']}) failed: {f['error']}", file=sys.stderr)
    print(f"{summary['name']}: {summary['done']}/{summary['points']} points done, {len(summary['failed'])} failed; "
          f"summary {summary['out']}/{summary['name']}.json")
    if summary["interrupted"]:
        return 130
    return 1 if summary["failed"] or summary["missing"] else 0


def main(argv: list[str] | None = None) -> int:
    """The ``revcol`` command; returns the exit status (141 when standard output was closed)."""
    try:
        try:
            return _main(argv)
        except ImportError as e:  # an optional package missing: one line naming its extra, exit 2
            message = missing_extra(e)
            if message is None:
                raise
            words = sys.argv[1:] if argv is None else list(argv)
            command = " ".join(words[:2] if words[:1] == ["study"] else words[:1])
            print(f"revcol{' ' + command if command else ''}: error: {message}", file=sys.stderr)
            return 2
        finally:  # a pipe closed early shows here, not at the interpreter's exit
            sys.stdout.flush()
    except BrokenPipeError:
        # the reader is gone (revcol ... | head -1): stop quietly, as a Unix tool does on
        # SIGPIPE; what is still buffered goes to /dev/null so that the exit flush is quiet too
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
        return 141


def _main(argv: list[str] | None) -> int:
    words = sys.argv[1:] if argv is None else list(argv)
    if words[:2] == ["study", "randomness"]:  # everything after it (-h included) is the study's
        return randomness.main(words[2:], prog="revcol study randomness")
    if words[:2] == ["study", "equilibrium"]:
        return equilibrium.main(words[2:], prog="revcol study equilibrium")
    if words[:2] == ["study", "stability"]:
        return stability.main(words[2:], prog="revcol study stability")
    args = _parser().parse_args(argv)
    if args.command == "run":
        return run_command(args)
    if args.command == "simulate":
        return _simulate(args)
    if args.command == "sweep":
        return _sweep(args)
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
                with atomic_open(args.json) as f:
                    json.dump(report, f, indent=1)
        return 0 if report["passed"] else 1
    if args.command == "bench" and args.study == "tradeoff":
        return tradeoff.cli_main(args, argv)
    if args.command == "bench":
        return statesave.cli_main(args, argv)
    return 2


if __name__ == "__main__":
    sys.exit(main())
