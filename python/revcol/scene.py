"""Scene files: a simulation described in TOML, read with the standard library.

A scene is one of three kinds (``[scene] kind``):

- ``"gas"`` (the default): N hard spheres in a box, run forward N_c collisions (or to an
  end time) with the event-driven engine, then back to the start (``revcol run``); the
  float engine (``revcol.Simulation``, 1-3D, exact within a horizon) unless ``[collisions]
  engine = "lattice"`` (``revcol.lattice.LatticeSimulation``, 2D, or ``LatticeSimulation3D``,
  3D: integer state, exact for any number of collisions; exact mode, flux or uniform law,
  Philox per-particle streams, or specular mode, deterministic specular dynamics with no draws);
- ``"reversal"``: the paper's reversal illustration for a named case (2 or 3 particles,
  momentum and energy held, velocities only: no positions are built), ``revcol verify``'s
  machinery;
- ``"statesave"``: the paper's performance study (§6), state saving against reverse
  computation, ``revcol bench statesave``'s machinery.

Every field is optional except where said, and every field is checked: an unknown table or
field, a field the scene's kind does not use, a wrong type or a value out of range raises
:class:`SceneError` (a ``ValueError``) whose one-line message names the file, the field and
what is allowed. An explicit initial state is checked in full (inside the box, no two
particles overlapping) by building the engine from it once.

The limits a scene is checked against (the largest packing fraction, the particle volume,
periodic axes of at least 3 diameters, the dimensions paper mode runs in, the bits and the
seed range) are the engine's own, read from C++ (``revcol._core.engine_limits``, header
``revcol/engine/limits.hpp``), and so are the names: the engine's vocabulary ``"wall"`` and
``"per_particle"``. The older spellings ``"walls"``, ``"per-particle"`` and ``start =
"lattice"`` (now ``"crystal"``) are still read, with a :class:`DeprecationWarning` naming the
file and the replacement.

.. code-block:: toml

    [scene]
    name = "spheres"              # default: the file's stem
    description = "..."
    kind = "gas"                  # "gas" | "reversal" | "statesave"
    case = "pair2d"               # reversal only (required there): revcol verify's case

    [system]                      # gas only
    dimension = 2                 # 1, 2 or 3 (required)
    particles = 1000              # N >= 1 (required unless initial_state gives it)
    diameter = 1.0                # sigma > 0
    packing_fraction = 0.3        # sets a cubic box; or give box = [Lx, Ly]
    boundaries = "wall"           # "wall" | "periodic" | "bounce" (float engine), or one per axis ("walls": deprecated)
    start = "auto"                # "auto" | "random" (sequential addition) | "crystal" (jittered:
                                  # square in 2D, fcc in 3D; "lattice": deprecated) | "relax" (overlaps
                                  # relaxed away: dense, amorphous); auto: random up to the engine's
                                  # rsa_fraction, else crystal; a mixture as its largest, else relaxed
    kinetic_energy = 1000.0       # total; default N d / 2 (unit temperature)
    initial_state = "start.npz"   # arrays positions (N, d), velocities (N, d); relative to the file
    gravity = [0.0, -1.0]         # a uniform field, one component per axis, along one walled axis (default none)
    shear_rate = 0.1              # Lees-Edwards shear, 1/time, lattice only: flow axis 0, gradient 1 (default none)

    [collisions]
    engine = "float"              # gas only: "float" | "lattice" (2D and 3D, exact or specular mode,
                                  # Philox per_particle; its default generator is then "philox")
    mode = "exact"                # "exact" | "paper" (gas: 1D and 2D, the float engine's limit) |
                                  # "specular" (gas only, either engine: deterministic specular
                                  # dynamics, no draws; on the lattice reversed bit for bit)
    law = "flux"                  # exact mode only: "flux" | "uniform"
    bits = 40                     # K, bits per chart coordinate, 8..52 (not statesave, not lattice)
    tick_bits = 20                # engine = "lattice" only: 16..26 (default automatic), a particle of
                                  # rms speed moves 2^-tick_bits diameters per tick
    cell_bits = 16                # engine = "lattice" only: 12..20, 2^cell_bits direction cells per turn
    search = "auto"               # engine = "lattice" only: "auto" | "cells" | a neighbour-list shell in
                                  # diameters, 0.02..2 (the speed only: the run is the same bit for bit)
    workers = 1                   # engine = "lattice" only: 1..64 threads of the parallel engine, one
                                  # slab each (the speed only: the run is the same bit for bit)

    [rng]
    generator = "clcg4"           # "clcg4" | "philox"
    streams = "per_particle"      # gas only: "per_particle" | "single" ("per-particle": deprecated)
    seed = 0                      # 0 .. 2^32 - 1

    [run]
    collisions = 1000             # N_c forward, then as many back; or (gas only)
    time = 10.0                   # an end time instead
    checkpoint_interval = 0       # gas: collisions between .npz checkpoints, 0 = none

    [statesave]                   # statesave only
    particles = [1000, 10000]     # N per run, each >= 2
    variants = ["ss1", "ss2", "rc"]   # default: all the transport supports
    lazy = false                  # lazy transport (adds variant "ssp")
    repeats = 3
    budget_gib = 8.0              # skip state saving that would save more
    runner = "auto"               # "process" (fresh revcol-bench per run) | "inline" | "auto"

    [output]                      # paths relative to the scene file (a scene found by name: below)
    json = "report.json"
    plot = "figures"              # a directory of PNGs (gas, statesave)
    trajectory = "run.xyz"        # gas: extended XYZ (OVITO) or .gsd
    trajectory_every = 100        # gas: collisions between frames
    checkpoints = "checkpoints"   # gas: where checkpoint_interval writes (default ./NAME-checkpoints)
    max_output = "10G"            # gas: refuse a run whose outputs are estimated to need more (K, M, G, T:
                                  # powers of 1024; 0 or "none": no limit; default 10G; --max-output)

    [observe]                     # gas, either engine: observables of the forward run (revcol.observe);
                                  # the table alone observes the scalars; its values go in the report
    speed_bins = 50               # time-weighted speed histogram over [0, speed_max] (default 5 v_rms)
    slabs = 10                    # density and temperature in slabs along slab_axis (default 0)
    block_time = 1.0              # the first blocks' length (default D / v_rms); min_blocks = 16
    pair_bins = 100               # pair distances over [0, pair_rmax] (2-64 particles, walls on every axis)

    [[species]]                   # gas, either engine, random start: a mixture, one
    name = "A"                    # table per species (no [system] diameter then); diameter > 0; count,
    diameter = 1.0                # or fraction of [system] particles (the fractions add up to 1);
    mass = 1.0                    # default 1 (unequal masses: engine = "float" only)
    fraction = 0.5

**Scenes by name.** The example scenes ship with the package (``revcol/scenes``, the repository's
``scenes/``): ``load_scene("spheres-3d")`` (``revcol run spheres-3d``) reads the scene of that
name when no file of that name exists (:func:`scene_names` lists them). Its initial-state files
are read beside it; its ``[output]`` paths resolve as if it were ``./scenes/NAME.toml``, the
repository's layout, so the examples' ``../out/X`` lands in ``./out/X`` under the current
directory and nothing is written into the installed package.
"""
from __future__ import annotations

import dataclasses
import difflib
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from . import _core
from ._toml import read_toml, shipped_dirs
from .engine import Simulation
from . import lattice as _lattice  # noqa: F401 (registers engine="lattice": Simulation builds its classes)
from .scene_schema import (DEFAULT_PER_PARTICLE, DEFAULT_SCENE, DEPRECATED, ENGINE_MODES,  # noqa: F401 (__all__)
                           ENGINES, KINDS, LATTICE_DEFAULT_COLLISIONS, LATTICE_FIELDS, LIMITS, SCHEMA, USES,
                           SceneError, _check, _check_lattice, _check_mode, _fail, _modernize, check_shear_engine,
                           check_shear_observe, field_summary, observes_frames, scene_field, with_lattice_options)
from ._species import check_masses, parse_species, sized_options, species_volume
from .statesave import variants as statesave_variants
from .verify import verify_cases

__all__ = ["Scene", "SceneError", "load_scene", "scene_from_dict", "engine_options", "lattice_options", "with_engine",
           "with_mode", "with_lattice_options", "DEFAULT_SCENE", "KINDS", "ENGINES", "ENGINE_MODES"]

@dataclass(frozen=True)
class Scene:
    """A validated scene. Lengths are in units of the diameter's unit; mass 1.

    ``dimension``, ``particles``, ``box`` and ``boundaries`` describe a gas; they are 0 / empty
    for the other kinds. ``collisions`` is N_c (None when a gas runs to ``time``).
    """

    dimension: int = 0
    particles: int = 0
    kind: str = "gas"
    case: str | None = None
    diameter: float = 1.0
    box: tuple[float, ...] = ()
    packing_fraction: float | None = None
    boundaries: tuple[str, ...] = ()
    start: str = "auto"
    kinetic_energy: float | None = None
    initial_state: Path | None = None
    engine: str = "float"
    mode: str = "exact"
    law: str = "flux"
    bits: int = 40
    tick_bits: int | None = None  # the lattice engine's options (None: automatic)
    cell_bits: int = 16
    search: str | float = "auto"
    workers: int = 1
    generator: str = "clcg4"
    streams: str = "per_particle"
    seed: int = 0
    collisions: int | None = None
    time: float | None = None
    checkpoint_interval: int = 0
    statesave_particles: tuple[int, ...] = ()
    variants: tuple[str, ...] = ()
    lazy: bool = False
    repeats: int = 3
    budget_gib: float = 8.0
    runner: str = "auto"
    json: Path | None = None
    plot: Path | None = None
    trajectory: Path | None = None
    trajectory_every: int = 100
    checkpoints: Path | None = None
    max_output: int | None = None  # [output] max_output in bytes, 0: no limit (None: revcol._outputs' default)
    observe: dict[str, Any] | None = None  # [observe]: Simulation.observe's arguments (None: no table)
    species: tuple = ()  # [[species]] (revcol._species.Species): a mixture; () one diameter
    gravity: tuple[float, ...] | None = None  # [system] gravity: a uniform field (None: none)
    shear_rate: float | None = None  # [system] shear_rate: Lees-Edwards shear, lattice only (None: none)
    name: str = "scene"
    description: str = ""
    source: str = "<built-in>"
    extra: dict[str, Any] = field(default_factory=dict)

    def summary(self, length: str | None = None) -> str:
        """One line describing the scene, for reports; ``length`` replaces the scene's own run
        length (``"20,000 collisions"``: revcol simulate runs its own)."""
        law = f"/{self.law}" if self.mode == "exact" else ""
        if self.kind == "reversal":
            return (f"{self.name}: the paper's reversal illustration, case {self.case}, {self.mode}{law}, "
                    f"{self.generator} seed {self.seed}, {self.collisions:,} collisions forward and back")
        if self.kind == "statesave":
            ns = ", ".join(f"{n:,}" for n in self.statesave_particles)
            return (f"{self.name}: state saving vs reverse computation (the paper's §6), N = {ns}, "
                    f"{self.collisions:,} collisions, {'lazy' if self.lazy else 'eager'} transport, "
                    f"{self.mode}{law}, {self.generator} seed {self.seed}")
        box = " x ".join(f"{b:g}" for b in self.box)
        end = length or (f"{self.collisions:,} collisions" if self.collisions is not None else f"t = {self.time:g}")
        engine = "lattice engine, " if self.engine == "lattice" else ""
        sizes = (", ".join(f"{s.count} {s.name} (d = {s.diameter:g})" for s in self.species) if self.species
                 else f"sigma = {self.diameter:g}")
        field = field_summary(self.gravity, self.shear_rate)
        return (f"{self.name}: {self.particles} particles in {self.dimension}D, {sizes}, "
                f"box {box} ({', '.join(self.boundaries)}){field}, {engine}{self.mode}{law}, {self.generator} "
                f"{self.streams} seed {self.seed}, {end}")

    def to_dict(self) -> dict[str, Any]:
        """The scene's fields as plain JSON-able values (paths as strings)."""
        out = {}
        for f in dataclasses.fields(self):
            if f.name == "extra":
                continue
            v = getattr(self, f.name)
            out[f.name] = str(v) if isinstance(v, Path) else (list(v) if isinstance(v, tuple) else v)
        return out


def scene_from_dict(doc: dict[str, Any], source: str = "<dict>", base: Path | None = None,
                    output_base: Path | None = None) -> Scene:
    """Validates a parsed scene document (tables of fields) and returns the :class:`Scene`.

    Relative paths (initial state, outputs) are taken relative to ``base`` (default: the
    current directory); the ``[output]`` paths relative to ``output_base`` when given.
    """
    if not isinstance(doc, dict):
        raise SceneError(f"{source}: a scene is a TOML document of tables")
    values: dict[tuple[str, str], Any] = {}
    for table, fields in doc.items():
        if table == "species":  # an array of tables ([[species]]): _gas reads it (revcol._species)
            continue
        if table not in SCHEMA:
            raise _fail(source, f"[{table}]", f"unknown table; allowed: {', '.join(SCHEMA)}")
        if not isinstance(fields, dict):
            raise _fail(source, f"[{table}]", "must be a table")
        for key, value in fields.items():
            if key not in SCHEMA[table]:
                raise _fail(source, f"[{table}] {key}",
                            f"unknown field; allowed in [{table}]: {', '.join(SCHEMA[table])}")
            kind, allowed = SCHEMA[table][key]
            value = _modernize(source, table, key, value)
            values[(table, key)] = _check(source, table, key, value, kind, allowed)

    # fields the kind does not use are errors, not silently ignored
    kind = values.get(("scene", "kind"), "gas")
    uses = USES[kind]
    if "species" in doc and kind != "gas":
        raise _fail(source, "[[species]]", f"does not apply to kind = {kind!r} (used by: 'gas')")
    if "observe" in doc and "observe" not in uses:
        raise _fail(source, "[observe]", f"does not apply to kind = {kind!r} (used by: 'gas')")
    for table, key in values:
        used = uses.get(table)
        if used is None or (used != "*" and key not in used):
            whose = [k for k in KINDS if USES[k].get(table) == "*" or key in USES[k].get(table, ())]
            raise _fail(source, f"[{table}] {key}",
                        f"does not apply to kind = {kind!r} (used by: {', '.join(map(repr, whose))})")

    def get(table: str, key: str, default: Any = None) -> Any:
        return values.get((table, key), default)

    base = base or Path.cwd()
    name = get("scene", "name", Path(source).stem if source.endswith(".toml") else "scene")
    if not name or name in (".", "..") or any(c in name for c in "/\\\0"):
        # it names output files (NAME-checkpoints): a path would put them elsewhere
        raise _fail(source, "[scene] name", f"must be a plain name (no '/', '\\', '..'), got {name!r}")
    common = dict(kind=kind, name=name, description=get("scene", "description", ""), source=source,
                  generator=get("rng", "generator", "clcg4"), seed=get("rng", "seed", 0),
                  extra={"fields": sorted(f"{a}.{b}" for a, b in values), "tables": sorted(doc)})

    def out(key: str, default: str | None = None) -> Path | None:
        p = get("output", key, default)
        return Path(os.path.normpath((output_base or base) / p)) if p is not None else None

    mode = get("collisions", "mode", "exact")
    law = get("collisions", "law", "flux")
    if mode != "exact" and ("collisions", "law") in values:
        raise _fail(source, "[collisions] law", "applies to mode = 'exact' only")
    if kind != "gas":  # specular mode runs gases only
        _check_mode(source, "[collisions] mode", kind, "float", 0, mode)

    if kind == "reversal":
        return _reversal(source, get, common, mode, law, out)
    if kind == "statesave":
        return _statesave(source, get, common, mode, law, out)
    return _gas(source, get, values, base, common, mode, law, out, doc.get("species"))


def _gas(source, get, values, base, common, mode, law, out, species_doc=None) -> Scene:
    """A gas scene from its checked fields (``values``; ``get`` reads one with a default)."""
    name = common["name"]
    d = get("system", "dimension")
    if d is None:
        raise _fail(source, "[system] dimension", "is required (1, 2 or 3)")
    initial = get("system", "initial_state")
    initial_path = Path(os.path.normpath(base / initial)) if initial is not None else None
    n = get("system", "particles")
    arrays = None
    if initial_path is not None:
        for key in ("start", "kinetic_energy"):
            if ("system", key) in values:
                raise _fail(source, f"[system] {key}", "applies to random starts only, not with initial_state")
        arrays = read_initial(source, initial_path, d)
        if n is not None and n != arrays[0].shape[0]:
            raise _fail(source, "[system] particles", f"is {n} but initial_state holds {arrays[0].shape[0]} particles")
        n = int(arrays[0].shape[0])
    species = parse_species(source, species_doc, n) if species_doc else ()
    n = sum(sp.count for sp in species) if species else n
    if n is None:
        raise _fail(source, "[system] particles", "is required (a positive integer) unless initial_state gives it")
    top_n = LIMITS["max_particles"][d]
    if n > top_n and get("collisions", "engine", "float") == "float":
        raise _fail(source, "[system] particles", f"must be at most {top_n:,} in {d}D for the float engine "
                    f"(a neighbour-list entry packs an id and its image in 32 bits), got {n:,}")
    sigma = get("system", "diameter", 1.0)
    if species:
        if ("system", "diameter") in values:
            raise _fail(source, "[system] diameter", "give [system] diameter (one size) or [[species]] diameters, not both")
        if arrays is not None:
            raise _fail(source, "[[species]]", "takes a random start (each species' count in id order), not "
                        "[system] initial_state")
        check_masses(source, species, get("collisions", "engine", "float"))
        sigma = max(sp.diameter for sp in species)

    box = get("system", "box")
    phi = get("system", "packing_fraction")
    if box is not None and phi is not None:
        raise _fail(source, "[system] packing_fraction", "give either box or packing_fraction, not both")
    if box is None and phi is None:
        raise _fail(source, "[system] box", "give box = [lengths] or packing_fraction")
    if phi is not None:  # a mixture, or a relaxed start, may go past the crystal's limit
        relaxed = bool(species) or get("system", "start", "auto") == "relax"
        top = LIMITS["max_relax_fraction" if relaxed else "max_fraction"][d]
        if phi > top:
            raise _fail(source, "[system] packing_fraction", f"must be at most {top} in {d}D"
                        f"{' for a relaxed start' if relaxed else ''}, got {phi}")
        vol = species_volume(species, d) if species else n * _core.engine_particle_volume(d, sigma)
        side = (vol / phi) ** (1.0 / d)
        box = (side,) * d
    if len(box) != d:
        raise _fail(source, "[system] box", f"needs {d} lengths for dimension {d}, got {len(box)}")
    for k, length in enumerate(box):
        if length <= sigma:
            raise _fail(source, "[system] box", f"axis {k} length {length:g} is not larger than the diameter {sigma:g}")

    bounds = get("system", "boundaries", ("wall",))
    if len(bounds) == 1:
        bounds = bounds * d
    if len(bounds) != d:
        raise _fail(source, "[system] boundaries", f"needs 1 or {d} entries, got {len(bounds)}")
    for k, (b, length) in enumerate(zip(bounds, box)):
        # the neighbour lists need a periodic axis of at least 3 diameters (docs/engine.md)
        cells = LIMITS["min_periodic_cells"]
        if b == "periodic" and length < cells * sigma:
            raise _fail(source, "[system] box", f"periodic axis {k} length {length:g} is under {cells} diameters "
                        f"({cells * sigma:g}); make it larger or use walls")

    start = get("system", "start", "auto")

    engine = get("collisions", "engine", "float")
    if engine == "lattice":
        _check_lattice(source, d, mode, get("rng", "generator", "philox"), get("rng", "streams", "per_particle"),
                       ("collisions", "bits") in values)
        common = {**common, "generator": get("rng", "generator", "philox")}
    for key in LATTICE_FIELDS:  # the lattice's own options: an error on the float engine, not ignored
        if engine != "lattice" and ("collisions", key) in values:
            raise _fail(source, f"[collisions] {key}", "applies to engine = 'lattice' only (the float engine has no "
                        "ticks, direction cells, list shells or parallel engine)")

    _check_mode(source, "[collisions] mode", "gas", engine, d, mode)

    nc, t_end = get("run", "collisions"), get("run", "time")
    if nc is not None and t_end is not None:
        raise _fail(source, "[run] time", "give either collisions or time, not both")
    if nc is None and t_end is None:
        nc = LATTICE_DEFAULT_COLLISIONS if engine == "lattice" else max(1, DEFAULT_PER_PARTICLE * n // 2)
    if nc is not None and n == 1:
        raise _fail(source, "[run] collisions", "a single particle never collides; give [run] time instead")
    checkpoint_interval = get("run", "checkpoint_interval", 0)
    checkpoints = out("checkpoints")
    if checkpoints is not None and checkpoint_interval == 0:
        raise _fail(source, "[output] checkpoints", "needs [run] checkpoint_interval > 0")
    if checkpoint_interval > 0 and checkpoints is None:
        checkpoints = out("checkpoints", f"{name}-checkpoints")
    trajectory = out("trajectory")
    if trajectory is not None and trajectory.suffix.lower() not in (".xyz", ".gsd"):
        raise _fail(source, "[output] trajectory", f"must end in .xyz (extended XYZ) or .gsd, got {trajectory.name!r}")

    observe = _observe(source, values, d, n, bounds, engine) if "observe" in common["extra"]["tables"] else None
    gravity, shear = scene_field(source, get, d, bounds, engine, box, sigma)
    check_shear_observe(source, shear, observe)

    scene = Scene(
        dimension=d, particles=n, diameter=sigma, box=tuple(box), packing_fraction=phi,
        boundaries=tuple(bounds), start=start, engine=engine,
        kinetic_energy=get("system", "kinetic_energy"), initial_state=initial_path,
        mode=mode, law=law, bits=get("collisions", "bits", 40), tick_bits=get("collisions", "tick_bits"),
        cell_bits=get("collisions", "cell_bits", 16), search=get("collisions", "search", "auto"),
        workers=get("collisions", "workers", 1),
        streams=get("rng", "streams", "per_particle"), collisions=nc, time=t_end,
        checkpoint_interval=checkpoint_interval, checkpoints=checkpoints,
        json=out("json"), plot=out("plot"), trajectory=trajectory,
        trajectory_every=get("output", "trajectory_every", 100), max_output=get("output", "max_output"),
        observe=observe, species=species, gravity=gravity, shear_rate=shear, **common)
    if arrays is not None:
        _check_initial(source, scene, *arrays)
    return scene


def _observe(source: str, values: dict, d: int, n: int, bounds, engine: str) -> dict[str, Any]:
    """The [observe] table as Simulation.observe's arguments, checked against the system."""
    obs = {key: v for (table, key), v in values.items() if table == "observe"}
    if obs.get("slab_axis", 0) >= d:
        raise _fail(source, "[observe] slab_axis", f"must be an axis of the {d}D box (0..{d - 1}), got {obs['slab_axis']}")
    if obs.get("pair_bins", 0) > 0:
        if "pair_rmax" not in obs:
            raise _fail(source, "[observe] pair_rmax", "is required with pair_bins > 0")
        if not 2 <= n <= 64 or "periodic" in bounds:
            raise _fail(source, "[observe] pair_bins", "pair distances need 2 to 64 particles and walls on every axis")
    return obs


def with_engine(scene: Scene, engine: str) -> Scene:
    """``scene`` on another engine (``revcol run --engine``), checked as a scene file saying
    ``[collisions] engine = ...`` would be: a scene that names no generator gets the engine's
    default one (Philox on the lattice); a lattice scene moved to the float engine keeps its
    Philox streams, gets the float engine's default chart bits, 40, and drops the lattice's own
    options (tick_bits, cell_bits, search, workers); a sheared scene runs on the lattice only."""
    if engine not in ENGINES:
        raise SceneError(f"{scene.source}: --engine must be one of {', '.join(map(repr, ENGINES))}, got {engine!r}")
    if scene.kind != "gas":
        raise SceneError(f"{scene.source}: --engine applies to 'gas' scenes, not {scene.kind!r}")
    check_shear_engine(scene.source, scene.shear_rate, engine, " (--engine)")
    fields = scene.extra.get("fields", ())
    out = dataclasses.replace(scene, engine=engine)
    if engine == "float":
        out = dataclasses.replace(out, tick_bits=None, cell_bits=16, search="auto", workers=1)
    if engine == "lattice":
        check_masses(scene.source, scene.species, engine, " (--engine lattice)")
        if "rng.generator" not in fields:  # the lattice's default generator, as in a scene file
            out = dataclasses.replace(out, generator="philox")
        try:
            _check_lattice(scene.source, scene.dimension, scene.mode, out.generator, scene.streams,
                           "collisions.bits" in fields)
        except SceneError as e:
            raise SceneError(f"{e} (--engine lattice)") from None
    if scene.initial_state is not None:
        _check_initial(scene.source, out, *read_initial(scene.source, scene.initial_state, scene.dimension))
    return out


def with_mode(scene: Scene, mode: str, engine: str | None = None) -> Scene:
    """``scene`` in another collision mode (``revcol run`` and ``revcol simulate``'s ``--mode``), on
    ``engine`` when given (``--engine``: the pair is checked together, as :func:`with_engine`),
    checked as a scene file saying ``[collisions] mode = ...`` would be, but for a law: a scene
    that names the default (flux) runs in any mode, another law (uniform) in exact mode only."""
    src, allowed = scene.source, SCHEMA["collisions"]["mode"][1]
    if scene.kind != "gas":
        raise SceneError(f"{src}: --mode applies to 'gas' scenes, not {scene.kind!r}")
    if mode not in allowed:
        raise SceneError(f"{src}: --mode must be one of {', '.join(map(repr, allowed))}, got {mode!r}")
    if mode != "exact" and scene.law != "flux":
        raise SceneError(f"{src}: --mode {mode}: the scene's [collisions] law = {scene.law!r} applies to "
                         "mode = 'exact' only")
    engine = engine or scene.engine
    if engine in ENGINE_MODES:  # else with_engine names the engine
        _check_mode(src, "--mode", "gas", engine, scene.dimension, mode)
    return with_engine(dataclasses.replace(scene, mode=mode), engine)


def _reversal(source, get, common, mode, law, out) -> Scene:
    case = get("scene", "case")
    if case is None:
        raise _fail(source, "[scene] case", f"is required for kind = 'reversal'; one of {', '.join(verify_cases(mode))}")
    if case not in verify_cases(mode):
        raise _fail(source, "[scene] case", f"must be one of {', '.join(verify_cases(mode))} "
                    f"for mode = {mode!r}, got {case!r}")
    return Scene(case=case, mode=mode, law=law, bits=get("collisions", "bits", 40),
                 collisions=get("run", "collisions", 1_000_000), json=out("json"), **common)


def _statesave(source, get, common, mode, law, out) -> Scene:
    lazy = get("statesave", "lazy", False)
    have = statesave_variants(lazy)
    vs = get("statesave", "variants", have)
    for v in vs:
        if v not in have:
            need = " (ssp needs lazy = true)" if v == "ssp" else ""
            raise _fail(source, "[statesave] variants", f"must be among {', '.join(map(repr, have))}, got {v!r}{need}")
    return Scene(mode=mode, law=law, collisions=get("run", "collisions", 1000),
                 statesave_particles=get("statesave", "particles", (1000, 10000, 100000, 1000000)),
                 variants=tuple(v for v in have if v in vs), lazy=lazy, repeats=get("statesave", "repeats", 3),
                 budget_gib=get("statesave", "budget_gib", 8.0), runner=get("statesave", "runner", "auto"),
                 json=out("json"), plot=out("plot"), **common)


def read_initial(source: str, path: Path, d: int):
    """The (positions, velocities) arrays of an initial-state file, each (N, d); SceneError
    naming ``[system] initial_state`` when the file is missing, unreadable or misshapen."""
    where = "[system] initial_state"
    if not path.is_file():
        raise _fail(source, where, f"file not found: {path}")
    try:
        with np.load(path, allow_pickle=False) as z:
            x, v = np.asarray(z["positions"], dtype=float), np.asarray(z["velocities"], dtype=float)
    except Exception as e:  # noqa: BLE001 - any unreadable file is the same user error
        raise _fail(source, where, f"cannot read arrays 'positions' and 'velocities' from {path}: {e}") from None
    if d == 1:  # allow flat (N,) arrays in 1D
        x, v = x.reshape(-1, 1) if x.ndim == 1 else x, v.reshape(-1, 1) if v.ndim == 1 else v
    if x.ndim != 2 or x.shape[1] != d or v.shape != x.shape or x.shape[0] == 0:
        raise _fail(source, where, f"positions and velocities must both have shape (N, {d}) with N >= 1, "
                    f"got {x.shape} and {v.shape}")
    return x, v


def _check_initial(source: str, scene: Scene, x, v) -> None:
    """Builds the engine once from the explicit state: its validation (finite values, inside
    the box, no overlap, non-zero kinetic energy; on the lattice also the quantization: a box or
    speed range it cannot hold, an overlap after rounding) is the one the run will meet."""
    try:  # (engine="lattice": the lattice class of the positions' dimension, Simulation.__new__)
        opts = lattice_options(scene) if scene.engine == "lattice" else engine_options(scene)
        Simulation(x, v, scene.box, engine=scene.engine, **opts)
    except ValueError as e:
        raise _fail(source, "[system] initial_state", f"{scene.initial_state.name}: {e}") from None


_read_initial = read_initial  # its name before it was public


def engine_options(scene: Scene) -> dict[str, Any]:
    """The keyword arguments of :class:`revcol.Simulation` that a gas scene sets."""
    return sized_options(scene.species, dict(boundary=list(scene.boundaries), diameter=scene.diameter, mode=scene.mode,
                         law=scene.law, seed=scene.seed, bits=scene.bits, generator=scene.generator,
                         streams=scene.streams, gravity=scene.gravity), masses=True)


def lattice_options(scene: Scene) -> dict[str, Any]:
    """The keyword arguments of :class:`revcol.lattice.LatticeSimulation` that a gas scene sets."""
    opts = dict(boundary=list(scene.boundaries), diameter=scene.diameter, mode=scene.mode, law=scene.law,
                seed=scene.seed, tick_bits=scene.tick_bits, cell_bits=scene.cell_bits, search=scene.search,
                workers=scene.workers, gravity=scene.gravity, shear_rate=scene.shear_rate)
    return sized_options(scene.species, opts)


def scene_dirs() -> list[Path]:
    """Where scenes are found by name: the package's ``scenes`` (installed from a wheel), else
    the ``scenes/`` of the source checkout the package is imported from (a development build)."""
    return shipped_dirs("scenes", "default.toml")


def scene_names() -> list[str]:
    """The names of the scenes shipped with revcol (``revcol run NAME``)."""
    return sorted({p.stem for d in scene_dirs() for p in d.glob("*.toml")})


def find_scene(name: str) -> Path | None:
    """The shipped scene file called ``name`` (``"spheres-3d"`` or ``"spheres-3d.toml"``), or None."""
    stem = name[:-5] if name.endswith(".toml") else name
    if not stem or any(c in stem for c in "/\\\0") or stem in (".", ".."):
        return None
    for d in scene_dirs():
        if (d / f"{stem}.toml").is_file():
            return d / f"{stem}.toml"
    return None


def load_scene(path: str | Path | None = None) -> Scene:
    """Reads and validates a scene file, or a shipped scene by name (or as ``scenes/NAME.toml``)
    when no such file exists; ``None`` gives the built-in default scene. Its relative input paths are read beside the
    file, its relative ``[output]`` paths under the current directory."""
    if path is None:
        return scene_from_dict(DEFAULT_SCENE, "<default scene>")
    p = Path(path)
    if not p.is_file():
        # a name, or scenes/NAME.toml as the docs write it: the shipped scene, in a clone or not
        name = p.name if p.parent == Path("scenes") else str(path)
        found = None if p.exists() else find_scene(name)
        if found is None:
            close = difflib.get_close_matches(p.stem, scene_names(), n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise SceneError(f"{p}: no such scene file, nor a scene name (shipped: "
                             f"{', '.join(scene_names()) or 'none found'}){hint}")
        p = found
    doc = read_toml(p, SceneError, "scene")
    try:
        # inputs (an initial state) beside the scene file; outputs under the current directory,
        # wherever the scene lives (a clone, the installed package)
        return scene_from_dict(doc, str(p), p.parent, Path.cwd())
    except RecursionError:
        raise SceneError(f"{p}: not a usable scene: its arrays or tables are nested too deeply") from None
