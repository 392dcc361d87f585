"""Scene files: a simulation described in TOML, read with the standard library.

A scene has five tables; every field is optional except where said, and every field is
checked: an unknown table or field, a wrong type or a value out of range raises
:class:`SceneError` (a ``ValueError``) whose one-line message names the file, the field and
what is allowed.

.. code-block:: toml

    [system]
    dimension = 2                 # 1, 2 or 3 (required)
    particles = 1000              # N >= 1 (required unless initial_state gives it)
    diameter = 1.0                # sigma > 0
    packing_fraction = 0.3        # sets a cubic box; or give box = [Lx, Ly]
    boundaries = "walls"          # "walls" | "periodic", or one per axis
    start = "random"              # "random" (sequential addition) | "lattice" (dense cases)
    kinetic_energy = 1000.0       # total; default N d / 2 (unit temperature)
    initial_state = "start.npz"   # arrays positions (N, d), velocities (N, d); relative to the file

    [collisions]
    mode = "exact"                # "exact" | "paper"
    law = "flux"                  # exact mode: "flux" | "uniform"
    bits = 40                     # K, bits per chart coordinate, 8..52

    [rng]
    generator = "clcg4"           # "clcg4" | "philox"
    streams = "per-particle"      # "per-particle" | "single"
    seed = 0                      # >= 0

    [run]
    collisions = 20000            # N_c forward, then as many back; or
    time = 10.0                   # an end time instead
    checkpoint_interval = 0       # collisions between checkpoints, 0 = none

    [output]
    json = "report.json"          # paths relative to the scene file
    plot = "figures"
    trajectory = "run.xyz"        # extended XYZ (OVITO) or .gsd
    trajectory_every = 100        # collisions between frames
"""
from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

__all__ = ["Scene", "SceneError", "load_scene", "scene_from_dict", "DEFAULT_SCENE"]


class SceneError(ValueError):
    """A scene file that cannot be run; the message is one line naming the problem."""


@dataclass(frozen=True)
class Scene:
    """A validated scene. Lengths are in units of the diameter's unit; mass 1."""

    dimension: int
    particles: int
    diameter: float = 1.0
    box: tuple[float, ...] = ()
    packing_fraction: float | None = None
    boundaries: tuple[str, ...] = ()
    start: str = "random"
    kinetic_energy: float | None = None
    initial_state: Path | None = None
    mode: str = "exact"
    law: str = "flux"
    bits: int = 40
    generator: str = "clcg4"
    streams: str = "per-particle"
    seed: int = 0
    collisions: int | None = None
    time: float | None = None
    checkpoint_interval: int = 0
    json: Path | None = None
    plot: Path | None = None
    trajectory: Path | None = None
    trajectory_every: int = 100
    name: str = "scene"
    source: str = "<built-in>"
    extra: dict[str, Any] = field(default_factory=dict)

    def summary(self) -> str:
        """One line describing the scene, for reports."""
        box = " x ".join(f"{b:g}" for b in self.box)
        law = f"/{self.law}" if self.mode == "exact" else ""
        end = f"{self.collisions:,} collisions" if self.collisions is not None else f"t = {self.time:g}"
        return (f"{self.name}: {self.particles} particles in {self.dimension}D, sigma = {self.diameter:g}, "
                f"box {box} ({', '.join(self.boundaries)}), {self.mode}{law}, {self.generator} "
                f"{self.streams} seed {self.seed}, {end}")


# the schema: table -> field -> (type check name, allowed values or range)
_SCHEMA: dict[str, dict[str, tuple[str, Any]]] = {
    "scene": {"name": ("str", None), "description": ("str", None)},
    "system": {
        "dimension": ("int", (1, 3)),
        "particles": ("int", (1, None)),
        "diameter": ("float", (0.0, None)),
        "packing_fraction": ("float", (0.0, None)),
        "box": ("floats", (0.0, None)),
        "boundaries": ("strs", ("walls", "periodic")),
        "start": ("str", ("random", "lattice")),
        "kinetic_energy": ("float", (0.0, None)),
        "initial_state": ("str", None),
    },
    "collisions": {
        "mode": ("str", ("exact", "paper")),
        "law": ("str", ("flux", "uniform")),
        "bits": ("int", (8, 52)),
    },
    "rng": {
        "generator": ("str", ("clcg4", "philox")),
        "streams": ("str", ("per-particle", "single")),
        "seed": ("int", (0, None)),
    },
    "run": {
        "collisions": ("int", (1, None)),
        "time": ("float", (0.0, None)),
        "checkpoint_interval": ("int", (0, None)),
    },
    "output": {
        "json": ("str", None),
        "plot": ("str", None),
        "trajectory": ("str", None),
        "trajectory_every": ("int", (1, None)),
    },
}

# the largest packing fractions a start can reach (random sequential addition jams near
# 0.547 in 2D and 0.38 in 3D; the lattice start goes to close packing, minus a margin)
_MAX_FRACTION = {1: 0.95, 2: 0.85, 3: 0.70}

DEFAULT_SCENE: dict[str, Any] = {
    "scene": {"name": "default", "description": "2D hard-disk gas, N = 1000, area fraction 0.3, walls"},
    "system": {"dimension": 2, "particles": 1000, "diameter": 1.0, "packing_fraction": 0.3,
               "boundaries": "walls"},
    "collisions": {"mode": "exact", "law": "flux"},
    "rng": {"generator": "clcg4", "streams": "per-particle", "seed": 0},
    "run": {"collisions": 20000},
}


def _fail(source: str, where: str, msg: str) -> SceneError:
    return SceneError(f"{source}: {where}: {msg}")


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
    if kind == "float":
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise _fail(source, where, f"must be a finite number, got {value!r}")
        if not value > allowed[0]:
            raise _fail(source, where, f"must be > {allowed[0]:g}, got {value}")
        return float(value)
    if kind == "str":
        if not isinstance(value, str):
            raise _fail(source, where, f"must be a string, got {value!r}")
        if allowed is not None and value not in allowed:
            raise _fail(source, where, f"must be one of {', '.join(map(repr, allowed))}, got {value!r}")
        return value
    if kind == "floats":
        if not isinstance(value, list) or not value:
            raise _fail(source, where, f"must be a list of numbers, got {value!r}")
        return tuple(_check(source, table, key, v, "float", allowed) for v in value)
    if kind == "strs":
        items = [value] if isinstance(value, str) else value
        if not isinstance(items, list) or not items:
            raise _fail(source, where, f"must be a string or a list of strings, got {value!r}")
        return tuple(_check(source, table, key, v, "str", allowed) for v in items)
    raise AssertionError(kind)


def scene_from_dict(doc: dict[str, Any], source: str = "<dict>", base: Path | None = None) -> Scene:
    """Validates a parsed scene document (tables of fields) and returns the :class:`Scene`."""
    if not isinstance(doc, dict):
        raise SceneError(f"{source}: a scene is a TOML document of tables")
    values: dict[str, Any] = {}
    for table, fields in doc.items():
        if table not in _SCHEMA:
            raise _fail(source, f"[{table}]", f"unknown table; allowed: {', '.join(_SCHEMA)}")
        if not isinstance(fields, dict):
            raise _fail(source, f"[{table}]", "must be a table")
        for key, value in fields.items():
            if key not in _SCHEMA[table]:
                raise _fail(source, f"[{table}] {key}",
                            f"unknown field; allowed in [{table}]: {', '.join(_SCHEMA[table])}")
            kind, allowed = _SCHEMA[table][key]
            values[(table, key)] = _check(source, table, key, value, kind, allowed)

    def get(table: str, key: str, default: Any = None) -> Any:
        return values.get((table, key), default)

    base = base or Path.cwd()
    d = get("system", "dimension")
    if d is None:
        raise _fail(source, "[system] dimension", "is required (1, 2 or 3)")
    initial = get("system", "initial_state")
    initial_path = (base / initial) if initial is not None else None
    n = get("system", "particles")
    if initial_path is not None:
        n = _initial_count(source, initial_path, d, n)
    if n is None:
        raise _fail(source, "[system] particles", "is required (a positive integer) unless initial_state gives it")
    sigma = get("system", "diameter", 1.0)

    box = get("system", "box")
    phi = get("system", "packing_fraction")
    if box is not None and phi is not None:
        raise _fail(source, "[system] packing_fraction", "give either box or packing_fraction, not both")
    if box is None and phi is None:
        raise _fail(source, "[system] box", "give box = [lengths] or packing_fraction")
    if phi is not None:
        if phi > _MAX_FRACTION[d]:
            raise _fail(source, "[system] packing_fraction",
                        f"must be at most {_MAX_FRACTION[d]} in {d}D, got {phi}")
        unit = {1: sigma, 2: math.pi * sigma**2 / 4, 3: math.pi * sigma**3 / 6}[d]
        side = (n * unit / phi) ** (1.0 / d)
        box = (side,) * d
    if len(box) != d:
        raise _fail(source, "[system] box", f"needs {d} lengths for dimension {d}, got {len(box)}")
    for k, length in enumerate(box):
        if length <= sigma:
            raise _fail(source, "[system] box", f"axis {k} length {length:g} is not larger than the diameter {sigma:g}")

    bounds = get("system", "boundaries", ("walls",))
    if len(bounds) == 1:
        bounds = bounds * d
    if len(bounds) != d:
        raise _fail(source, "[system] boundaries", f"needs 1 or {d} entries, got {len(bounds)}")

    mode = get("collisions", "mode", "exact")
    law = get("collisions", "law", "flux")
    if mode == "paper" and ("collisions", "law") in values:
        raise _fail(source, "[collisions] law", "applies to mode = 'exact' only")
    if mode == "paper" and d != 2:
        raise _fail(source, "[collisions] mode",
                    f"'paper' runs gases in 2D only (its pair operator of Procedures 1-2), got dimension {d}")

    nc, t_end = get("run", "collisions"), get("run", "time")
    if nc is not None and t_end is not None:
        raise _fail(source, "[run] time", "give either collisions or time, not both")
    if nc is None and t_end is None:
        nc = 10 * n

    def out(key: str) -> Path | None:
        p = get("output", key)
        return (base / p) if p is not None else None

    known = {k for k in values}
    return Scene(
        dimension=d, particles=n, diameter=sigma, box=tuple(box), packing_fraction=phi,
        boundaries=tuple(bounds), start=get("system", "start", "random"),
        kinetic_energy=get("system", "kinetic_energy"), initial_state=initial_path,
        mode=mode, law=law, bits=get("collisions", "bits", 40),
        generator=get("rng", "generator", "clcg4"), streams=get("rng", "streams", "per-particle"),
        seed=get("rng", "seed", 0), collisions=nc, time=t_end,
        checkpoint_interval=get("run", "checkpoint_interval", 0),
        json=out("json"), plot=out("plot"), trajectory=out("trajectory"),
        trajectory_every=get("output", "trajectory_every", 100),
        name=get("scene", "name", Path(source).stem if source.endswith(".toml") else "scene"),
        source=source, extra={"fields": sorted(f"{a}.{b}" for a, b in known)},
    )


def _initial_count(source: str, path: Path, d: int, n: int | None) -> int:
    import numpy as np

    where = "[system] initial_state"
    if not path.is_file():
        raise _fail(source, where, f"file not found: {path}")
    try:
        with np.load(path) as z:
            x, v = z["positions"], z["velocities"]
    except Exception as e:  # noqa: BLE001 - any unreadable file is the same user error
        raise _fail(source, where, f"cannot read arrays 'positions' and 'velocities' from {path}: {e}") from None
    if x.ndim != 2 or x.shape[1] != d or v.shape != x.shape:
        raise _fail(source, where, f"positions and velocities must both have shape (N, {d}), got {x.shape} and {v.shape}")
    if n is not None and n != x.shape[0]:
        raise _fail(source, "[system] particles", f"is {n} but initial_state holds {x.shape[0]} particles")
    return int(x.shape[0])


def load_scene(path: str | Path | None = None) -> Scene:
    """Reads and validates a scene file; ``None`` gives the built-in default scene."""
    if path is None:
        return scene_from_dict(DEFAULT_SCENE, "<default scene>")
    p = Path(path)
    if not p.is_file():
        raise SceneError(f"{p}: no such scene file")
    try:
        doc = tomllib.loads(p.read_text())
    except tomllib.TOMLDecodeError as e:
        raise SceneError(f"{p}: not valid TOML: {e}") from None
    return scene_from_dict(doc, str(p), p.parent)
