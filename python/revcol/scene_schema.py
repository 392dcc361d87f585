"""The scene file's schema: its tables and fields, each with its type and allowed values; the
fields each kind of scene uses; the old spellings still read; the built-in default scene.
:mod:`revcol.scene` reads a scene against them (and re-exports the public names).
"""
from __future__ import annotations

from typing import Any

from . import _core

__all__ = ["KINDS", "ENGINES", "LIMITS", "DEFAULT_SCENE", "SCHEMA", "USES", "DEPRECATED"]

#: the kinds of scene
KINDS = ("gas", "reversal", "statesave")

#: the engines a gas scene can run on (``[collisions] engine``)
ENGINES = ("float", "lattice")


#: the engine's limits and names (revcol/engine/limits.hpp), the one source of truth
LIMITS: dict[str, Any] = _core.engine_limits()

# old spellings still read: (table, field) -> {old: new}, with a DeprecationWarning
DEPRECATED: dict[tuple[str, str], dict[str, str]] = {
    ("system", "boundaries"): {"walls": "wall"},
    ("rng", "streams"): {"per-particle": "per_particle"},
}

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
        "start": ("str", ("auto", "random", "lattice")),
        "kinetic_energy": ("float", (0.0, None)),
        "initial_state": ("str", None),
    },
    "collisions": {
        "engine": ("str", ENGINES),
        "mode": ("str", ("exact", "paper")),
        "law": ("str", ("flux", "uniform")),
        "bits": ("int", tuple(LIMITS["bits"])),
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
