"""The scene file's schema: its tables and fields, each with its type and allowed values; the
fields each kind of scene uses; the old spellings still read; the built-in default scene; the
check of one field against them (:class:`SceneError` naming it); and the checks of the uniform field
and of Lees-Edwards shear against the system and the engine's options (``[system] gravity`` and
``shear_rate``: :func:`scene_field`).
:mod:`revcol.scene` reads a scene with them (and re-exports the public names).
"""
from __future__ import annotations

import dataclasses
import math
import warnings
from typing import Any, Iterable, Sequence

from . import _core
from ._args import size

__all__ = ["KINDS", "ENGINES", "ENGINE_MODES", "LIMITS", "DEFAULT_SCENE", "SCHEMA", "USES", "DEPRECATED",
           "LATTICE_FIELDS", "SceneError", "with_lattice_options", "check_gravity", "check_shear", "check_shear_engine",
           "check_field_options", "check_shear_observe", "scene_field", "observes_frames", "field_text", "shear_text", "field_summary",
           "SHEAR_CELLS"]

#: the kinds of scene
KINDS = ("gas", "reversal", "statesave")

#: the engines a gas scene can run on (``[collisions] engine``)
ENGINES = ("float", "lattice")

#: the collision modes (``[collisions] mode``) each engine runs gases in: the float engine's
#: exact, paper (1D and 2D) and specular operators; the lattice's exact operator and its
#: deterministic specular map (revcol.lattice.MODES). Reversal and statesave scenes: exact, paper.
ENGINE_MODES = {"float": ("exact", "paper", "specular"), "lattice": ("exact", "specular")}


#: the engine's limits and names (revcol/engine/limits.hpp), the one source of truth
LIMITS: dict[str, Any] = _core.engine_limits()

# old spellings still read: (table, field) -> {old: new}, with a DeprecationWarning
DEPRECATED: dict[tuple[str, str], dict[str, str]] = {
    ("system", "boundaries"): {"walls": "wall"},
    ("rng", "streams"): {"per-particle": "per_particle"},
    ("system", "start"): {"lattice": "crystal"},  # "lattice" names the engine only
}

#: the [collisions] fields of the lattice engine alone (LatticeSimulation's options)
LATTICE_FIELDS = ("tick_bits", "cell_bits", "search", "workers")

# the schema: table -> field -> (type check name, allowed values or range)
SCHEMA: dict[str, dict[str, tuple[str, Any]]] = {
    "scene": {"name": ("str", None), "description": ("str", None), "kind": ("str", KINDS),
              "case": ("str", None)},
    "system": {
        "dimension": ("int", tuple(LIMITS["dimensions"])),
        "particles": ("int", (1, (1 << 31) - 1)),
        "diameter": ("float", (0.0, None)),
        "packing_fraction": ("float", (0.0, None)),
        "box": ("floats", (0.0, None)),
        "boundaries": ("strs", tuple(LIMITS["boundaries"])),
        "start": ("str", ("auto", "random", "crystal", "relax")),
        "kinetic_energy": ("float", (0.0, None)),
        "initial_state": ("str", None),
        "gravity": ("vector", None),  # a uniform field, one component per axis (scene_field)
        "shear_rate": ("real", None),  # Lees-Edwards shear, 1 / time, on the lattice engine (scene_field)
    },
    "collisions": {
        "engine": ("str", ENGINES),
        "mode": ("str", ("exact", "paper", "specular")),
        "law": ("str", ("flux", "uniform")),
        "bits": ("int", tuple(LIMITS["bits"])),
        # the lattice engine's (revcol/lattice/units.hpp, engine_core.hpp set_list_shell)
        "tick_bits": ("int", (16, 26)),
        "cell_bits": ("int", (12, 20)),
        "search": ("search", (0.02, 2.0)),
        "workers": ("int", (1, 64)),  # the parallel engine's threads (timewarp.hpp): the speed only
    },
    "rng": {
        "generator": ("str", tuple(sorted(LIMITS["generators"]))),
        "streams": ("str", tuple(LIMITS["streams"])),
        "seed": ("int", (0, int(LIMITS["max_seed"]))),   # the engine's and the generators' keys are 32-bit
    },
    "run": {
        "collisions": ("int", (1, None)),
        "time": ("float", (0.0, None)),
        "checkpoint_interval": ("int", (0, None)),
    },
    "statesave": {
        "particles": ("ints", (2, 1 << 26)),
        "variants": ("strs", ("ss1", "ss2", "ssp", "rc")),
        "lazy": ("bool", None),
        "repeats": ("int", (1, 1000)),
        "budget_gib": ("float", (0.0, None)),
        "runner": ("str", ("auto", "process", "inline")),
    },
    "output": {
        "json": ("str", None),
        "plot": ("str", None),
        "trajectory": ("str", None),
        "trajectory_every": ("int", (1, None)),
        "checkpoints": ("str", None),
        "max_output": ("size", None),  # bytes, or "20G" (K, M, G, T: powers of 1024); 0 or "none": no limit
    },
    "observe": {
        "block_time": ("float", (0.0, None)),
        "min_blocks": ("int", (2, 64)),
        "slab_axis": ("int", (0, 2)),
        "slabs": ("int", (0, 1 << 20)),
        "speed_bins": ("int", (0, 1 << 20)),
        "speed_max": ("float", (0.0, None)),
        "pair_bins": ("int", (0, 1 << 20)),
        "pair_rmax": ("float", (0.0, None)),
    },
}

# what each kind uses; any other field is an error naming it ("*" = the whole table)
USES: dict[str, dict[str, Any]] = {
    "gas": {"scene": {"name", "description", "kind"}, "system": "*", "collisions": "*", "rng": "*",
            "run": "*", "output": "*", "observe": "*"},
    "reversal": {"scene": {"name", "description", "kind", "case"}, "collisions": {"mode", "law", "bits"},
                 "rng": {"generator", "seed"}, "run": {"collisions"}, "output": {"json"}},
    "statesave": {"scene": {"name", "description", "kind"}, "statesave": "*", "collisions": {"mode", "law"},
                  "rng": {"generator", "seed"}, "run": {"collisions"}, "output": {"json", "plot"}},
}

# N_c when a float-engine gas scene gives neither collisions nor time: 2 collisions per
# particle. A gas is chaotic and round-off grows by about an order of magnitude per collision
# per particle, so a round trip restores the start to 1e-9 only within a horizon of 4-10
# collisions per particle in 2D/3D (docs/engine.md); 2 per particle sits well inside it
# (docs/run.md). The lattice engine has no horizon: its default is a real length, 10^6.
DEFAULT_PER_PARTICLE = 2
LATTICE_DEFAULT_COLLISIONS = 1_000_000

DEFAULT_SCENE: dict[str, Any] = {
    "scene": {"name": "default",
              "description": "2D hard-disk gas on the lattice engine, N = 1000, area fraction 0.3, walls"},
    "system": {"dimension": 2, "particles": 1000, "diameter": 1.0, "packing_fraction": 0.3,
               "boundaries": "wall"},
    "collisions": {"engine": "lattice", "mode": "exact", "law": "flux"},
    "rng": {"generator": "philox", "streams": "per_particle", "seed": 0},
    # 10^6 collisions (2000 per particle, 2 N_c / N) forward and back, restored bit for bit;
    # about 3 s of CPU each way (docs/run.md). The float engine's horizon for this gas is
    # 3 collisions per particle (revcol run --horizon --engine float).
    "run": {"collisions": 1_000_000},
}


class SceneError(ValueError):
    """A scene file that cannot be run; the message is one line naming the problem."""



def _fail(source: str, where: str, msg: str) -> SceneError:
    return SceneError(f"{source}: {where}: {msg}")


def _check_mode(source: str, where: str, kind: str, engine: str, d: int, mode: str) -> None:
    """The collision modes a scene's kind, engine and dimension run: specular in gas scenes
    only, the lattice without paper mode, paper mode in the engine's dimensions (``where``
    names the field or option in the SceneError)."""
    if kind != "gas":
        if mode == "specular":
            raise _fail(source, where, f"'specular' runs gas scenes only, not kind = {kind!r} (exact or paper)")
        return
    if mode not in ENGINE_MODES[engine]:
        raise _fail(source, where, f"engine = {engine!r} runs {' and '.join(ENGINE_MODES[engine])} modes, got {mode!r}")
    paper_dims = tuple(LIMITS["paper_mode_dimensions"])
    if mode == "paper" and d not in paper_dims:
        raise _fail(source, where, f"'paper' runs gases in {' and '.join(f'{k}D' for k in paper_dims)} "
                    f"only (it has no invertible {d}D pair operator), got dimension {d}")


def _check_lattice(source: str, d: int, mode: str, generator: str, streams: str, bits_given: bool) -> None:
    """The combinations the lattice engine runs: 2D and 3D, exact mode (flux or uniform law) or
    specular mode, Philox per-particle streams, no chart bits; anything else is a SceneError
    naming the field."""
    why = "engine = 'lattice'"
    if d not in (2, 3):
        raise _fail(source, "[system] dimension", f"{why} runs 2D and 3D gases, got dimension {d}")
    _check_mode(source, "[collisions] mode", "gas", "lattice", d, mode)
    if generator != "philox":
        raise _fail(source, "[rng] generator", f"{why} draws from Philox per-particle streams, got {generator!r}")
    if streams != "per_particle":
        raise _fail(source, "[rng] streams", f"{why} draws from one Philox stream per particle, got {streams!r}")
    if bits_given:
        raise _fail(source, "[collisions] bits", f"does not apply to {why} (its collisions are exact integer "
                    "bijections, no K-bit chart)")


def _check(source: str, table: str, key: str, value: Any, kind: str, allowed: Any) -> Any:
    where = f"[{table}] {key}"
    if kind == "int":
        if isinstance(value, bool) or not isinstance(value, int):
            raise _fail(source, where, f"must be an integer, got {value!r}")
        lo, hi = allowed
        if value < lo or (hi is not None and value > hi):
            span = f"{lo}..{hi}" if hi is not None else f">= {lo}"
            raise _fail(source, where, f"must be {span}, got {value}")
        return value
    if kind in ("float", "real"):  # "real": of any sign
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise _fail(source, where, f"must be a finite number, got {value!r}")
        if kind == "float" and not value > allowed[0]:
            raise _fail(source, where, f"must be > {allowed[0]:g}, got {value}")
        return float(value)
    if kind == "bool":
        if not isinstance(value, bool):
            raise _fail(source, where, f"must be true or false, got {value!r}")
        return value
    if kind == "str":
        if not isinstance(value, str):
            raise _fail(source, where, f"must be a string, got {value!r}")
        if allowed is not None and value not in allowed:
            raise _fail(source, where, f"must be one of {', '.join(map(repr, allowed))}, got {value!r}")
        return value
    if kind == "size":  # the output limit: bytes or a string such as "20G" (revcol._outputs)
        try:
            return size(value, f"{where}:")
        except ValueError as e:
            raise SceneError(f"{source}: {e}") from None
    if kind == "search":  # "auto", "cells" or a neighbour-list shell in diameters
        if value in ("auto", "cells") or (not isinstance(value, (bool, str)) and isinstance(value, (int, float))
                                         and allowed[0] <= value <= allowed[1]):
            return value if isinstance(value, str) else float(value)
        raise _fail(source, where, f"must be 'auto', 'cells' or a shell in diameters, {allowed[0]:g}..{allowed[1]:g}, "
                    f"got {value!r}")
    if kind == "vector":  # components of any sign, one per axis (the length is the system's: check_gravity)
        if not isinstance(value, list) or not value:
            raise _fail(source, where, f"must be a list of numbers, one per axis, got {value!r}")
        for k, v in enumerate(value):
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise _fail(source, where, f"component {k} must be a finite number, got {v!r}")
        return tuple(float(v) for v in value)
    if kind in ("floats", "ints"):
        if not isinstance(value, list) or not value:
            raise _fail(source, where, f"must be a non-empty list of numbers, got {value!r}")
        return tuple(_check(source, table, key, v, kind[:-1], allowed) for v in value)
    if kind == "strs":
        items = [value] if isinstance(value, str) else value
        if not isinstance(items, list) or not items:
            raise _fail(source, where, f"must be a string or a list of strings, got {value!r}")
        return tuple(_check(source, table, key, v, "str", allowed) for v in items)
    raise AssertionError(kind)


def _modernize(source: str, table: str, key: str, value: Any) -> Any:
    """``value`` with deprecated spellings replaced, warning once per field (DeprecationWarning)."""
    old_new = DEPRECATED.get((table, key))
    if old_new is None:
        return value
    items = value if isinstance(value, list) else [value]
    old = sorted({v for v in items if isinstance(v, str) and v in old_new})
    if not old:
        return value
    said = ", ".join(f"{o!r} is deprecated, write {old_new[o]!r}" for o in old)
    warnings.warn(f"{source}: [{table}] {key}: {said}", DeprecationWarning, stacklevel=4)
    new = [old_new.get(v, v) if isinstance(v, str) else v for v in items]
    return new if isinstance(value, list) else new[0]


def with_lattice_options(scene, *, tick_bits: int | None = None, cell_bits: int | None = None,
                         search: str | float | None = None, workers: int | None = None):
    """``scene`` with the lattice engine's options that are not None replaced (``revcol run`` and
    ``revcol simulate``'s ``--tick-bits``, ``--cell-bits``, ``--search``, ``--workers``), each checked as its
    ``[collisions]`` field; a scene that does not run the lattice engine refuses them, one under shear
    (``shear_rate``) more than one worker and a neighbour-list shell, and one with a field (``[system]
    gravity``) along axis 0 more than one worker (check_field_options)."""
    given = {k: v for k, v in zip(LATTICE_FIELDS, (tick_bits, cell_bits, search, workers)) if v is not None}
    flags = {k: "--" + k.replace("_", "-") for k in given}
    if given and (scene.kind != "gas" or scene.engine != "lattice"):
        runs = "the float engine (add --engine lattice)" if scene.kind == "gas" else f"no gas (kind = {scene.kind!r})"
        raise SceneError(f"{scene.source}: {', '.join(flags.values())}: the lattice engine's options; this scene runs {runs}")
    for k, v in given.items():
        try:
            given[k] = _check(scene.source, "collisions", k, v, *SCHEMA["collisions"][k])
        except SceneError as e:
            raise SceneError(str(e).replace(f"[collisions] {k}", flags[k])) from None
    out = dataclasses.replace(scene, **given)
    check_field_options(scene.source, out.gravity, out.engine, workers=out.workers, search=out.search, names=flags,
                        shear=out.shear_rate)
    return out


# --- the uniform field: [system] gravity ---------------------------------------------------------
# an acceleration in the scene's units (diameters per time unit squared, unit mass), one component
# per axis, nonzero along one walled axis at most (docs/run.md "A uniform field"); checked against
# the system and against what runs no field yet before any engine is built, so that a scene is
# refused by name rather than by the engine mid-run

_GRAVITY = "[system] gravity"


def check_gravity(source: str, gravity: Sequence[float] | None, d: int,
                  bounds: Sequence[str]) -> tuple[float, ...] | None:
    """The field a scene runs (None: none; a zero field is none), checked against its ``d`` axes
    and their ``bounds``: one component per axis, nonzero on one axis at most, and that axis
    walled (a periodic axis has no floor). ``gravity`` has passed the schema (finite numbers)."""
    if gravity is None:
        return None
    if len(gravity) != d:
        raise _fail(source, _GRAVITY, f"needs {d} components for dimension {d} (one per axis), got {len(gravity)}")
    axes = [k for k, g in enumerate(gravity) if g != 0.0]
    if not axes:
        return None
    if len(axes) > 1:
        raise _fail(source, _GRAVITY, f"must be nonzero along one axis at most, got {list(gravity)}")
    if bounds[axes[0]] == "periodic":
        raise _fail(source, _GRAVITY, f"points along axis {axes[0]}, which is periodic: a field needs walls "
                    "('wall' or 'bounce') on its axis (a periodic axis has no floor)")
    return tuple(gravity)


# what runs no shear yet on the lattice engine, in the words of each refusal: where the gas is, what
# the parallel engine and the neighbour lists are not built for yet (both engines observe it: the
# observer follows moving images). A field runs on either search and on many workers (the slabs,
# along axis 0, across the field: check_field_options)
_UNBUILT = {
    "shear": ("under shear ([system] shear_rate)", "shear", "moving images"),
}


def check_field_options(source: str, gravity: Sequence[float] | None, engine: str, *, workers: int = 1,
                        search: str | float = "auto", names: dict | None = None,
                        shear: float | None = None) -> None:
    """Refuses, naming the option, what runs no shear (``shear``, a rate; None: none) yet on the
    lattice engine: more than one worker and neighbour lists (``search`` a shell; ``"auto"`` takes the
    cell grid there); and a field (``gravity``) along axis 0 on more than one worker (the parallel
    engine's slabs lie along axis 0 and must cut across the field). (A sheared gas's slabs lie along
    axis 1 only: check_shear_observe.) ``names`` renames an option where it came from the command line
    (``{"workers": "--workers"}``)."""
    names = names or {}
    if engine == "lattice" and gravity is not None and gravity[0] != 0.0 and workers > 1:
        raise _fail(source, names.get("workers", "[collisions] workers"), f"engine = 'lattice' runs a gas in a field "
                    f"along axis 0 on one worker (the parallel engine's slabs lie along axis 0 and cut across the field "
                    f"only: put the field on another axis), got {workers}")
    for kind, on in (("shear", shear is not None),):
        if not on:
            continue
        where, what, lists = _UNBUILT[kind]
        if engine != "lattice":
            continue
        if workers > 1:
            raise _fail(source, names.get("workers", "[collisions] workers"), f"engine = 'lattice' runs a gas "
                        f"{where} on one worker (the parallel engine is not built for {what} yet), got {workers}")
        if search not in ("auto", "cells"):
            raise _fail(source, names.get("search", "[collisions] search"), f"engine = 'lattice' searches a gas "
                        f"{where} with the cell grid only ('auto' or 'cells'; no neighbour lists for {lists} yet), "
                        f"got {search!r}")


# --- Lees-Edwards shear: [system] shear_rate ------------------------------------------------------
# a rate in 1 / time units, of either sign: the flow along axis 0, the gradient along axis 1, the
# images above the box moving shear_rate * L_1 faster (docs/run.md "Shear", docs/shear.md); checked,
# as the field, before any engine is built

_SHEAR = "[system] shear_rate"

#: the least box of a sheared gas, in the lattice engine's cells along axis 0 (the flow) and axis 1
#: (the gradient): a crossing pair's image is the nearest one only in such a box (geometry.cpp validate)
SHEAR_CELLS = (9, 5)
_SHEAR_CELL = 1.0 + 2.0 ** -7  # a cell's width in (largest) diameters: sigma + 2 vmax, vmax = sigma / 2^8


def check_shear_engine(source: str, shear_rate: float | None, engine: str, note: str = "") -> None:
    """Refuses shear (``shear_rate`` not None nor 0) on another engine than the lattice's, naming the key."""
    if shear_rate and engine != "lattice":
        raise _fail(source, _SHEAR, f"Lees-Edwards shear runs on the lattice engine only (engine = 'lattice'; the "
                    f"float engine's is not built yet), got engine = {engine!r}{note}")


def check_shear(source: str, shear_rate: float | None, engine: str, bounds: Sequence[str], box: Sequence[float],
                sigma: float, gravity: Sequence[float] | None = None) -> float | None:
    """The shear rate a scene runs (None: none; a zero rate is none), checked against its engine (the
    lattice's only), its axes' ``bounds`` (0 and 1 periodic), its ``box`` in (largest) diameters
    ``sigma`` (:data:`SHEAR_CELLS`) and a field (``gravity``, as given: none together with shear yet).
    ``shear_rate`` has passed the schema (a finite number)."""
    if not shear_rate:
        return None
    check_shear_engine(source, shear_rate, engine)
    if gravity is not None and any(gravity):
        raise _fail(source, _SHEAR, "is refused together with [system] gravity: shear and a field together are not "
                    "built yet")
    if len(bounds) < 2 or bounds[0] != "periodic" or bounds[1] != "periodic":
        raise _fail(source, _SHEAR, "needs axes 0 (the flow) and 1 (the gradient) periodic, got boundaries "
                    f"({', '.join(bounds)})")
    least = [c * _SHEAR_CELL * sigma for c in SHEAR_CELLS]
    if box[0] < least[0] or box[1] < least[1]:
        raise _fail(source, _SHEAR, f"needs a box of at least {least[0]:.6g} along axis 0 (the flow) and "
                    f"{least[1]:.6g} along axis 1 (the gradient), {SHEAR_CELLS[0]} and {SHEAR_CELLS[1]} of the "
                    f"lattice's cells of 1 + 2^-7 diameters; got {box[0]:.6g} x {box[1]:.6g}")
    return float(shear_rate)


def check_shear_observe(source: str, shear_rate: float | None, observe: dict | None) -> None:
    """Refuses an ``[observe]`` table whose slabs lie across another axis than 1 under shear (the
    observer's slabs there give the velocity profile along the gradient)."""
    if shear_rate and observe and observe.get("slabs", 0) > 0 and observe.get("slab_axis", 0) != 1:
        raise _fail(source, "[observe] slab_axis", "must be 1 (the gradient) under [system] shear_rate: a sheared "
                    f"gas's slabs give its velocity profile across the gradient, got {observe.get('slab_axis', 0)}")


def scene_field(source: str, get, d: int, bounds: Sequence[str], engine: str,
                box: Sequence[float] = (), sigma: float = 1.0) -> tuple[tuple[float, ...] | None, float | None]:
    """A gas scene's field and shear rate (None: none) from its checked fields (``get(table, key,
    default)``), its ``d`` axes' ``bounds``, its ``box``, its (largest) diameter ``sigma`` and its
    ``engine``: every check of both."""
    shear = check_shear(source, get("system", "shear_rate"), engine, bounds, box, sigma, get("system", "gravity"))
    gravity = check_gravity(source, get("system", "gravity"), d, bounds)
    check_field_options(source, gravity, engine, workers=get("collisions", "workers", 1),
                        search=get("collisions", "search", "auto"), shear=shear)
    return gravity, shear


def observes_frames(scene, trajectory) -> bool:
    """Whether a run of ``scene`` writing ``trajectory`` observes (unreported, in its checkpoints) for the
    image flags of a periodic box's frames: when its own ``[observe]`` does not already, nor shear
    forbids it (the flags are then inferred between frames)."""
    return (trajectory is not None and scene.observe is None and not scene.shear_rate
            and "periodic" in scene.boundaries)


def field_text(gravity: Iterable[float] | None) -> str:
    """A field as the reports write it, ``"(0, -1)"`` (6 significant digits), or ``"none"``."""
    return "none" if gravity is None else f"({', '.join(f'{float(c):.6g}' for c in gravity)})"


def shear_text(shear_rate: float | None) -> str:
    """A shear rate as the reports write it, ``"0.1"`` (6 significant digits), or ``"none"``."""
    return f"{float(shear_rate):.6g}" if shear_rate else "none"


def field_summary(gravity: Iterable[float] | None, shear_rate: float | None) -> str:
    """A scene summary's field and shear, ``", gravity (0, -1)"``, ``", shear rate 0.1"``; "" without."""
    return ((f", gravity {field_text(gravity)}" if gravity else "")
            + (f", shear rate {shear_text(shear_rate)}" if shear_rate else ""))
