"""``revcol run``: a scene forward and back (:func:`revcol.studies.scenes.run_scene`), the text
report on standard output (:mod:`revcol.cli.report`) and the exit status."""
from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import warnings

from .._io import jsonable
from ..observe import report_lines
from ..scene import Scene, SceneError, load_scene, with_engine, with_lattice_options, with_mode
from ..studies.scenes import run_scene
from .report import format_report

__all__ = ["run_command"]


def _warn_line(message, category, *rest) -> None:
    print(f"revcol run: warning: {message}", file=sys.stderr)


def run_command(args: argparse.Namespace) -> int:
    """``revcol run``: exit 0 passed, 1 failed, 2 bad scene/option, 130 interrupted."""
    if args.seeds is not None and not args.horizon:
        print("revcol run: error: --seeds applies to --horizon only", file=sys.stderr)
        return 2
    to_stdout = args.json == "-"
    try:
        with warnings.catch_warnings():  # a scene's deprecated spellings: one line each on stderr
            warnings.simplefilter("always", DeprecationWarning)
            warnings.showwarning = _warn_line
            scene, engine = args.scene, args.engine
            lattice = dict(tick_bits=args.tick_bits, cell_bits=args.cell_bits, search=args.search, workers=args.workers)
            if args.mode is not None or any(v is not None for v in lattice.values()):
                # on the engine the scene runs on (--engine too), in the mode it runs (--mode too)
                scene = load_scene(scene)
                if args.mode is not None:
                    scene = with_mode(scene, args.mode, engine)
                elif engine:
                    scene = with_engine(scene, engine)
                scene, engine = with_lattice_options(scene, **lattice), None
            if to_stdout:  # the scene's own [output] json is replaced by standard output
                scene = dataclasses.replace(scene if isinstance(scene, Scene) else load_scene(scene), json=None)
            report = run_scene(scene, json_path=None if to_stdout else args.json, plot=args.plot,
                               trajectory=args.trajectory,
                               horizon_seeds=(args.seeds or 1) if args.horizon else None,
                               max_collisions=args.max_collisions, collisions=args.collisions, seed=args.seed,
                               engine=engine, progress=False if args.no_progress else None,
                               plot_format=args.plot_format, max_output=args.max_output)
    except SceneError as e:
        print(f"revcol run: error: {e}", file=sys.stderr)
        return 2
    except OSError as e:  # an output that cannot be written (permissions, a file where a directory goes)
        print(f"revcol run: error: {e}", file=sys.stderr)
        return 2
    except MemoryError:
        print("revcol run: error: not enough memory for this scene (fewer particles, or a larger machine)",
              file=sys.stderr)
        return 2
    text = sys.stderr if to_stdout else sys.stdout
    print(format_report(report), file=text)
    if report.get("observe"):
        print("\n".join(report_lines(report["observe"])), file=text)
    if to_stdout:
        print(json.dumps(jsonable(report), indent=1))
    if report.get("interrupted"):
        return 130
    if report["kind"] == "horizon":  # a measurement; on the lattice, a check that fails exits 1
        return 0 if report.get("passed", True) else 1
    return 0 if report["passed"] else 1
