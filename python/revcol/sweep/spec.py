"""``revcol sweep``: many runs of one study, spread over Dask distributed, gathered in one table.

A *sweep file* (TOML) names a study, the scene it runs, and the parameters to vary; each point
of the sweep is one task whose result is the run's JSON report (the dict ``revcol run --json``
writes). The tasks are independent and deterministic by seed: a point run twice, on any worker,
gives the same report (less its dates, timings and memory figures).

.. code-block:: toml

    [sweep]
    name = "default-horizon"     # default: the file's stem
    description = "..."
    study = "horizon"            # "run" (the scene's revcol run: a gas's round trip, a reversal,
                                 # a statesave study) | "horizon" (revcol run --horizon) | "statesave"
                                 # | "randomness" | "equilibrium" (these two run no scene)
    scene = "default"            # a scene name (revcol run NAME) or a path relative to this file;
                                 # default: "default" ("paper-statesave" for study = "statesave")
    combine = "grid"             # "grid": every combination of [vary]; "list": the k-th of each

    [vary]                       # each a list, or {start = S, count = K} (the integers S .. S+K-1)
    seed = {start = 0, count = 200}
    packing_fraction = [0.1, 0.3, 0.5]

    [options]                    # held for every point (any name [vary] takes)
    max_collisions = 100000

    [resources]
    memory_gib = 2.0             # per task (default: estimated from each point)
    retries = 2                  # reruns of a task that raised (default 2)

The names a point sets: scene fields ``seed``, ``particles`` (a statesave scene: its one N),
``packing_fraction``, ``box``, ``dimension``, ``diameter``, ``boundaries``, ``start``,
``kinetic_energy``, ``mode``, ``law``, ``bits``, ``generator``, ``streams``, ``collisions``,
``time``, ``variants``, ``lazy``, ``repeats``, ``budget_gib``, ``runner`` (or any
``"table.field"`` of a scene), and the study's options: ``engine`` (run, horizon),
``max_collisions`` and ``seeds`` (horizon, default 1 seed per point). The studies without a scene
take their own parameters (:data:`revcol.sceneless.SCENELESS`): ``randomness`` (``case``,
``mode``, ``law``, ``rng``, ``seed``, ``words``, ``tests``: one dieharder battery) and
``equilibrium`` (``dimension``, ``packing_fraction``, ``law``, ``particles``, ``per_particle``,
``seed``: one dense gas against the equation of state). Every point is validated
as a scene before anything runs; a bad sweep file raises :class:`SweepError` naming the file,
the field (or the point) and what is allowed.

**Outputs** (``out``, default ``./out/sweeps/NAME``): ``points/<hash>.json``, one per finished
point, written atomically as it finishes (``{"point", "hash", "report", ...}``; the hash is of the
point's scene document, study options and revcol build, so a changed scene never reuses an old
result); ``NAME.csv`` (one row per point: its parameters and the report's scalars; also
``NAME.parquet`` when pyarrow is installed); ``NAME.json`` (the summary: counts, failures, the
machine's load, and for the horizon study each group of seeds combined as ``revcol run
--horizon --seeds K`` reports it); and, for the float engine's horizon, figures (horizon against
the varied parameter; error against collisions per particle).

**Resumable**: a point whose file exists is not run again, so an interrupted sweep (Ctrl-C, a
lost client, ``stop_after``) run again does only what is left, and the table has one row per
point, never two. **Execution**: a Dask ``LocalCluster`` on this machine's cores (processes, one
thread each) unless ``scheduler`` (``tcp://HOST:PORT``) or ``scheduler_file`` names a running
cluster; ``workers=0`` runs the points in this process, one after another (docs/sweep.md).

    >>> s = sweep_from_dict({"sweep": {"study": "horizon"}, "vary": {"seed": {"start": 0, "count": 3}},
    ...                      "options": {"particles": 100}})
    >>> [p.params for p in s.points], [p.scene.seed for p in s.points]
    ([{'particles': 100, 'seed': 0}, {'particles': 100, 'seed': 1}, {'particles': 100, 'seed': 2}], [0, 1, 2])
"""
from __future__ import annotations

import copy
import dataclasses
import difflib
import hashlib
import itertools
import json
import math
import os
import tomllib
from pathlib import Path
from typing import Any

from .. import _core
from .._toml import read_toml, shipped_dirs
from .._version import __version__
from ..gas import BYTES_PER_PARTICLE
from ..scene import DEFAULT_SCENE, Scene, SceneError, find_scene, scene_from_dict, with_engine
from ..statesave import _kwargs
from . import studies as sceneless

__all__ = ["SweepError", "Sweep", "Point", "load_sweep", "sweep_from_dict", "sweep_names", "check_options", "STUDIES",
           "SCENE_PARAMS"]

#: the studies a sweep runs, and the options each takes besides the scene's fields
STUDIES: dict[str, tuple[str, ...]] = {"run": ("engine",), "horizon": ("engine", "max_collisions", "seeds"),
                                       "statesave": (), "randomness": (), "equilibrium": ()}

#: a point's scene parameters: name -> (table, field) of the scene document
SCENE_PARAMS: dict[str, tuple[str, str]] = {
    "seed": ("rng", "seed"), "generator": ("rng", "generator"), "streams": ("rng", "streams"),
    "particles": ("system", "particles"), "packing_fraction": ("system", "packing_fraction"),
    "box": ("system", "box"), "dimension": ("system", "dimension"), "diameter": ("system", "diameter"),
    "boundaries": ("system", "boundaries"), "start": ("system", "start"),
    "kinetic_energy": ("system", "kinetic_energy"), "mode": ("collisions", "mode"),
    "law": ("collisions", "law"), "bits": ("collisions", "bits"), "collisions": ("run", "collisions"),
    "time": ("run", "time"), "variants": ("statesave", "variants"), "lazy": ("statesave", "lazy"),
    "repeats": ("statesave", "repeats"), "budget_gib": ("statesave", "budget_gib"),
    "runner": ("statesave", "runner"),
}

# fields that exclude each other: setting one removes the other from the scene
_EXCLUSIVE = {("system", "packing_fraction"): ("system", "box"), ("system", "box"): ("system", "packing_fraction"),
              ("run", "collisions"): ("run", "time"), ("run", "time"): ("run", "collisions")}

_TABLES = {"sweep": ("name", "description", "study", "scene", "combine"), "vary": None, "options": None,
           "resources": ("memory_gib", "retries")}

#: bytes a point needs besides its particles: the interpreter, numpy and revcol
BASE_BYTES = 256 * 2**20


class SweepError(ValueError):
    """A sweep file (or arguments) that cannot be run; the message is one line naming the problem."""


@dataclasses.dataclass(frozen=True)
class Point:
    """One task of a sweep: its parameters, the scene it runs, the study's options, and its hash."""

    index: int
    params: dict[str, Any]
    doc: dict[str, Any]
    options: dict[str, Any]
    scene: Scene | None  # None for the studies without a scene (randomness, equilibrium)
    hash: str
    memory_bytes: int

    def label(self) -> str:
        """``seed=3, particles=100``: the point's parameters, for messages."""
        return ", ".join(f"{k}={v!r}" for k, v in self.params.items()) or "(no parameters)"

    def task(self, base: str, study: str) -> dict:
        """What a worker needs to run the point (plain values only)."""
        return {"doc": self.doc, "options": self.options, "base": base, "label": self.label(), "study": study}


@dataclasses.dataclass(frozen=True)
class Sweep:
    """A validated sweep: its study, scene and points."""

    name: str
    description: str
    study: str
    scene_name: str
    source: str
    base: str
    points: tuple[Point, ...]
    retries: int
    memory_given: bool
    varied: tuple[str, ...] = ()  # the [vary] names, in the file's order


def _fail(source: str, where: str, msg: str) -> SweepError:
    return SweepError(f"{source}: {where}: {msg}")


def _values(source: str, key: str, spec: Any) -> list:
    """A [vary] entry as a list of values: a non-empty list, or {start, count} (integers)."""
    where = f"[vary] {key}"
    if isinstance(spec, dict):
        if set(spec) != {"start", "count"}:
            raise _fail(source, where, f"a range is {{start = S, count = K}}, got keys {sorted(spec)}")
        s, c = spec["start"], spec["count"]
        if any(isinstance(x, bool) or not isinstance(x, int) for x in (s, c)) or c < 1:
            raise _fail(source, where, f"start and count must be integers, count >= 1, got {spec!r}")
        return list(range(s, s + c))
    if isinstance(spec, list) and spec:
        return spec
    raise _fail(source, where, f"must be a non-empty list or {{start = S, count = K}}, got {spec!r}")


def _scene_doc(source: str, name: str, base: Path) -> tuple[dict, Path, str]:
    """The scene's TOML document, the folder its relative paths start from, and its label."""
    p = base / name
    if not p.is_file():
        found = find_scene(name)
        if found is None:
            if name == "default":
                return copy.deepcopy(DEFAULT_SCENE), Path.cwd(), "default"
            raise _fail(source, "[sweep] scene", f"{name!r} is neither a file (relative to the sweep file) nor a "
                        "shipped scene name")
        p = found
    try:
        doc = tomllib.loads(p.read_text())
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as e:
        raise _fail(source, "[sweep] scene", f"{p}: not a readable scene ({' '.join(str(e).split())})") from None
    return doc, p.parent, str(p)


def _apply(doc: dict, key: str, value: Any, kind: str, options: dict, study: str, source: str) -> None:
    """Sets one parameter of a point: a study option, or a field of its scene document."""
    if key in STUDIES[study]:
        options[key] = value
        return
    if key in SCENE_PARAMS:
        table, field = SCENE_PARAMS[key]
        if key == "particles" and kind == "statesave":
            table, field, value = "statesave", "particles", [value]
    elif key.count(".") == 1:
        table, field = key.split(".")
    else:
        allowed = sorted(set(SCENE_PARAMS) | set(STUDIES[study]))
        raise _fail(source, f"parameter {key!r}", f"unknown for study {study!r}; allowed: {', '.join(allowed)} "
                    "or 'table.field' of a scene")
    if table == "output" or key == "run.checkpoint_interval":
        raise _fail(source, f"parameter {key!r}", "a sweep writes its own outputs; points write none")
    t = doc.setdefault(table, {})
    if not isinstance(t, dict):
        raise _fail(source, f"parameter {key!r}", f"the scene's [{table}] is not a table")
    t[field] = value
    other = _EXCLUSIVE.get((table, field))
    if other is not None:
        doc.get(other[0], {}).pop(other[1], None)


def _memory(scene: Scene, study: str, options: dict) -> int:
    """Bytes a point needs (an estimate with margin): the engine's state (twice for a horizon: a
    clone runs back), or for a statesave scene the largest state saving it will attempt."""
    if scene.kind == "gas":
        copies = 2 if study == "horizon" else 1
        return BASE_BYTES + copies * BYTES_PER_PARTICLE * scene.particles
    if scene.kind == "statesave":
        n = max(scene.statesave_particles)
        return BASE_BYTES + 64 * n + min(int(scene.budget_gib * 2**30), _statesave_projection(scene))
    return BASE_BYTES


def _statesave_projection(scene: Scene) -> int:
    """The most bytes any run of a statesave scene saves (the engine's projection)."""
    most = 0
    for n in scene.statesave_particles:
        for v in scene.variants or ("ss1", "ss2", "rc"):
            kw = _kwargs(n, scene.collisions, v, scene.lazy, scene.mode, scene.law, scene.generator, scene.seed,
                         1e-5, 1e-11, scene.budget_gib, True)
            proj = _core.statesave_projected_bytes(**kw)
            if not proj["over_budget"]:
                most = max(most, int(proj["projected_bytes"]))
    return most


def _hash(doc: dict, options: dict, study: str) -> str:
    """The point's name: a hash of what decides its result (scene, study, options, revcol build)."""
    text = json.dumps({"study": study, "scene": doc, "options": options, "revcol": __version__,
                       "build": _core.build}, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:20]


def _combinations(source: str, vary: dict, combine: str) -> list[dict]:
    names = list(vary)
    lists = [_values(source, k, vary[k]) for k in names]
    if combine == "grid":
        return [dict(zip(names, combo)) for combo in itertools.product(*lists)]
    lengths = {k: len(v) for k, v in zip(names, lists)}
    if len(set(lengths.values())) > 1:
        raise _fail(source, "[sweep] combine", f"'list' needs [vary] lists of one length, got {lengths}")
    return [dict(zip(names, combo)) for combo in zip(*lists)]


def sweep_from_dict(doc: dict, source: str = "<dict>", base: str | os.PathLike | None = None) -> Sweep:
    """Validates a parsed sweep document and builds its points (each checked as a scene).
    ``base``: the folder a scene path is relative to (default: the current directory)."""
    if not isinstance(doc, dict):
        raise SweepError(f"{source}: a sweep is a TOML document of tables")
    for table, fields in doc.items():
        if table not in _TABLES:
            raise _fail(source, f"[{table}]", f"unknown table; allowed: {', '.join(_TABLES)}")
        if not isinstance(fields, dict):
            raise _fail(source, f"[{table}]", "must be a table")
        if _TABLES[table] is not None:
            for k in fields:
                if k not in _TABLES[table]:
                    raise _fail(source, f"[{table}] {k}", f"unknown field; allowed: {', '.join(_TABLES[table])}")
    head = doc.get("sweep", {})
    for k in ("name", "description", "study", "scene", "combine"):
        if k in head and not isinstance(head[k], str):
            raise _fail(source, f"[sweep] {k}", f"must be a string, got {head[k]!r}")
    study = head.get("study", "run")
    if study not in STUDIES:
        raise _fail(source, "[sweep] study", f"must be one of {', '.join(map(repr, STUDIES))}, got {study!r}")
    combine = head.get("combine", "grid")
    if combine not in ("grid", "list"):
        raise _fail(source, "[sweep] combine", f"must be 'grid' or 'list', got {combine!r}")
    name = head.get("name", Path(source).stem if source.endswith(".toml") else "sweep")
    if not name or name in (".", "..") or any(c in name for c in "/\\\0"):
        raise _fail(source, "[sweep] name", f"must be a plain name (no '/', '\\', '..'), got {name!r}")
    res = doc.get("resources", {})
    mem = res.get("memory_gib")
    if mem is not None and (isinstance(mem, bool) or not isinstance(mem, (int, float)) or not 0 < mem < math.inf):
        raise _fail(source, "[resources] memory_gib", f"must be a positive number, got {mem!r}")
    retries = res.get("retries", 2)
    if isinstance(retries, bool) or not isinstance(retries, int) or not 0 <= retries <= 100:
        raise _fail(source, "[resources] retries", f"must be an integer 0..100, got {retries!r}")
    base = Path(base) if base is not None else Path.cwd()
    fixed, vary = doc.get("options", {}), doc.get("vary", {})
    both = sorted(set(fixed) & set(vary))
    if both:
        raise _fail(source, "[options]", f"{', '.join(both)} also in [vary]: give each parameter once")
    if study in ("randomness", "equilibrium"):
        if "scene" in head:
            raise _fail(source, "[sweep] scene", f"study {study!r} runs no scene (its parameters go in [vary] / "
                        "[options])")
        points = _sceneless_points(source, study, fixed, _combinations(source, vary, combine), mem)
        return Sweep(name=name, description=head.get("description", ""), study=study, scene_name="-", source=source,
                     base=str(base), points=tuple(points), retries=retries, memory_given=mem is not None,
                     varied=tuple(vary))
    scene_name = head.get("scene", "paper-statesave" if study == "statesave" else "default")
    scene_doc, scene_base, scene_label = _scene_doc(source, scene_name, base)
    # a point writes nothing of its own (no [output], no checkpoints: points running at once would
    # share those paths); the sweep writes its report
    scene_doc.pop("output", None)
    if isinstance(scene_doc.get("run"), dict):
        scene_doc["run"].pop("checkpoint_interval", None)
    kind = scene_doc.get("scene", {}).get("kind", "gas") if isinstance(scene_doc.get("scene"), dict) else "gas"
    if study == "statesave" and kind != "statesave":
        raise _fail(source, "[sweep] scene", f"study 'statesave' needs a statesave scene, {scene_label} is {kind!r}")
    if study == "horizon" and kind != "gas":
        raise _fail(source, "[sweep] scene", f"study 'horizon' needs a gas scene, {scene_label} is {kind!r}")
    points, seen = [], {}
    for k, params in enumerate(_combinations(source, vary, combine)):
        pdoc, options = copy.deepcopy(scene_doc), {}
        for key, value in list(fixed.items()) + list(params.items()):
            _apply(pdoc, key, value, kind, options, study, source)
        where = f"{source}: point {k} ({', '.join(f'{a}={b!r}' for a, b in params.items()) or 'no parameters'})"
        scene = _point_scene(pdoc, options, where, str(scene_base))
        h = _hash(pdoc, options, study)
        if h in seen:
            raise _fail(source, "[vary]", f"points {seen[h]} and {k} are the same run (a value listed twice?)")
        seen[h] = k
        need = int(mem * 2**30) if mem is not None else _memory(scene, study, options)
        points.append(Point(k, dict(list(fixed.items()) + list(params.items())), pdoc, options, scene, h, need))
    return Sweep(name=name, description=head.get("description", ""), study=study, scene_name=scene_label,
                 source=source, base=str(scene_base), points=tuple(points), retries=retries,
                 memory_given=mem is not None, varied=tuple(vary))


def _sceneless_points(source: str, study: str, fixed: dict, combos: list[dict], mem) -> list[Point]:
    """The points of a study without a scene: its defaults, then [options], then [vary]."""
    points, seen = [], {}
    for k, params in enumerate(combos):
        given = dict(list(fixed.items()) + list(params.items()))
        try:
            sceneless.check(study, given)
        except ValueError as e:
            raise _fail(source, f"point {k} ({', '.join(f'{a}={b!r}' for a, b in params.items()) or 'no parameters'})",
                        str(e)) from None
        full = dict(sceneless.defaults(study), **given)
        h = _hash({}, full, study)
        if h in seen:
            raise _fail(source, "[vary]", f"points {seen[h]} and {k} are the same run (a value listed twice?)")
        seen[h] = k
        need = int(mem * 2**30) if mem is not None else BASE_BYTES + sceneless.memory(study, full)
        points.append(Point(k, given, {}, full, None, h, need))
    return points


def check_options(scene: Scene, options: dict) -> None:
    """Raises ValueError naming the option when a study option is out of range."""
    for k in ("max_collisions", "seeds"):
        if k in options:
            v = options[k]
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise ValueError(f"{k} must be a positive integer, got {v!r}")
    if "engine" in options:
        with_engine(scene, options["engine"])  # SceneError naming the engine
    if scene.seed + options.get("seeds", 1) > 2**32:
        raise ValueError(f"seeds {scene.seed} .. {scene.seed + options['seeds'] - 1} pass 2^32 - 1")


def _point_scene(doc: dict, options: dict, where: str, base: str) -> Scene:
    """The point's scene, validated (a SweepError naming the point otherwise), its options checked."""
    try:
        scene = scene_from_dict(doc, where, Path(base))
        check_options(scene, options)
    except SceneError as e:
        raise SweepError(str(e)) from None
    except (TypeError, ValueError) as e:
        raise SweepError(f"{where}: {e}") from None
    return scene


def sweep_dirs() -> list[Path]:
    """Where sweeps are found by name: the package's ``sweeps`` (installed from a wheel), else
    the ``sweeps/`` of the source checkout the package is imported from."""
    return shipped_dirs("sweeps")


def sweep_names() -> list[str]:
    """The names of the sweeps shipped with revcol (``revcol sweep NAME``)."""
    return sorted({p.stem for d in sweep_dirs() for p in d.glob("*.toml")})


def load_sweep(path: str | os.PathLike) -> Sweep:
    """Reads and validates a sweep file, or a sweep shipped with revcol by name (or as
    ``sweeps/NAME.toml``) when no such file exists (:class:`SweepError` naming the problem)."""
    p = Path(path)
    # a name, or sweeps/NAME.toml as the docs write it: the shipped sweep, in a clone or not
    if not p.exists() and (p.parent == Path("sweeps") or (p.parent == Path(".") and "/" not in str(path))):
        stem = p.stem if p.suffix == ".toml" else p.name
        found = [d / f"{stem}.toml" for d in sweep_dirs() if (d / f"{stem}.toml").is_file()]
        if found:
            p = found[0]
        else:
            close = difflib.get_close_matches(stem, sweep_names(), n=1)
            raise SweepError(f"{p}: no such sweep file, nor a sweep name (shipped: "
                             f"{', '.join(sweep_names()) or 'none found'})"
                             + (f"; did you mean {close[0]!r}?" if close else ""))
    return sweep_from_dict(read_toml(p, SweepError, "sweep"), str(p), p.parent)
