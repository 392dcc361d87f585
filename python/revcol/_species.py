"""A scene's species table: ``[[species]]`` entries, each a name, a diameter (in the scene's
length unit), a mass (default 1; unequal masses on the float engine only) and a count or a
fraction of ``[system] particles`` (docs/mixtures.md). :mod:`revcol.scene` reads it with
:func:`parse_species`; the gas is built with :func:`species_diameters` and
:func:`species_masses`.

    >>> sp = parse_species("s.toml", [{"name": "A", "diameter": 1.0, "fraction": 0.5},
    ...                               {"name": "B", "diameter": 0.7, "fraction": 0.5}], 10)
    >>> [(s.name, s.count) for s in sp], species_diameters(sp)[4:6].tolist()
    ([('A', 5), ('B', 5)], [1.0, 0.7])
"""
from __future__ import annotations

import math
from typing import Any, NamedTuple, Optional, Sequence

import numpy as np

__all__ = ["Species", "parse_species", "species_diameters", "species_masses", "species_volume", "trajectory_kinds",
           "sized_options", "check_masses", "SPECIES_FIELDS"]

#: the fields of one ``[[species]]`` entry
SPECIES_FIELDS = ("name", "diameter", "mass", "count", "fraction")


class Species(NamedTuple):
    """One species of a scene: its name, diameter, number of particles and mass."""
    name: str
    diameter: float
    count: int
    mass: float = 1.0


def _fail(source: str, where: str, msg: str) -> ValueError:
    from .scene_schema import SceneError
    return SceneError(f"{source}: {where}: {msg}")


def parse_species(source: str, entries: Any, n: Optional[int]) -> tuple:
    """The checked species of ``[[species]]`` (a list of tables), their counts from ``count``
    (then ``n``, when given, must be their sum) or ``fraction`` of ``n`` (rounded, the last
    species taking what is left; the fractions must sum to 1). Raises SceneError naming the
    entry and field."""
    if not isinstance(entries, list) or not entries or not all(isinstance(e, dict) for e in entries):
        raise _fail(source, "[[species]]", "must be one or more tables ([[species]] entries)")
    names, diam, counts, fracs, masses = [], [], [], [], []
    for k, e in enumerate(entries):
        where = f"[[species]] {k + 1}"
        for key in e:
            if key not in SPECIES_FIELDS:
                raise _fail(source, f"{where} {key}", f"unknown field; allowed: {', '.join(SPECIES_FIELDS)}")
        name = e.get("name", f"S{k}")
        if not isinstance(name, str) or not name or name in names:
            raise _fail(source, f"{where} name", f"must be a unique non-empty string, got {name!r}")
        d = e.get("diameter")
        if isinstance(d, bool) or not isinstance(d, (int, float)) or not (math.isfinite(d) and d > 0):
            raise _fail(source, f"{where} diameter", f"is required, a number > 0, got {d!r}")
        m = e.get("mass", 1.0)
        if isinstance(m, bool) or not isinstance(m, (int, float)) or not (math.isfinite(m) and m > 0):
            raise _fail(source, f"{where} mass", f"must be a number > 0, got {m!r}")
        masses.append(float(m))
        if ("count" in e) == ("fraction" in e):
            raise _fail(source, where, "give count or fraction (one of them)")
        c, f = e.get("count"), e.get("fraction")
        if "count" in e and (isinstance(c, bool) or not isinstance(c, int) or c < 1):
            raise _fail(source, f"{where} count", f"must be an integer >= 1, got {c!r}")
        if "fraction" in e and (isinstance(f, bool) or not isinstance(f, (int, float)) or not 0 < f <= 1):
            raise _fail(source, f"{where} fraction", f"must be in (0, 1], got {f!r}")
        names.append(name)
        diam.append(float(d))
        counts.append(c)
        fracs.append(f)
    if all(c is not None for c in counts):
        if n is not None and n != sum(counts):
            raise _fail(source, "[system] particles", f"is {n} but the species' counts add up to {sum(counts)}")
    elif all(f is not None for f in fracs):
        if n is None:
            raise _fail(source, "[system] particles", "is required with species fractions")
        if abs(sum(fracs) - 1.0) > 1e-9:
            raise _fail(source, "[[species]] fraction", f"must add up to 1, got {sum(fracs):g}")
        counts = [int(round(f * n)) for f in fracs[:-1]]
        counts.append(n - sum(counts))
        if min(counts) < 1:
            raise _fail(source, "[[species]] fraction", f"leaves a species with no particle among {n}")
    else:
        raise _fail(source, "[[species]]", "give every species a count, or every species a fraction")
    return tuple(Species(a, b, c, m) for a, b, c, m in zip(names, diam, counts, masses))


def species_diameters(species: Sequence[Species]) -> np.ndarray:
    """One diameter per particle, the species in blocks (particle ids 0.. of the first, ...)."""
    return np.concatenate([np.full(s.count, s.diameter) for s in species])


def species_masses(species: Sequence[Species]) -> Optional[np.ndarray]:
    """One mass per particle (the species in blocks), or None when every mass is 1."""
    if all(s.mass == 1.0 for s in species):
        return None
    return np.concatenate([np.full(s.count, s.mass) for s in species])


def check_masses(source: str, species: Sequence[Species], engine: str, note: str = "") -> None:
    """Unequal masses run on the float engine only: a SceneError naming ``mass`` otherwise."""
    if engine == "lattice" and species_masses(species) is not None:
        raise _fail(source, "[[species]] mass", "unequal masses run on engine = 'float' only (the lattice engine's "
                    "exact map for them is not built: docs/mixtures.md)" + note)


def sized_options(species: Sequence[Species], opts: dict, masses: bool = False) -> dict:
    """An engine's keyword arguments ``opts`` for a mixture: one diameter per particle instead of
    ``diameter`` and, with ``masses`` (the float engine), one mass per particle when they differ."""
    if species:
        del opts["diameter"]
        opts["diameters"] = species_diameters(species)
        if masses and species_masses(species) is not None:
            opts["masses"] = species_masses(species)
    return opts


def species_volume(species: Sequence[Species], d: int) -> float:
    """The particles' own volume (area in 2D, length in 1D) summed over every species."""
    unit = {1: 1.0, 2: math.pi / 4.0, 3: math.pi / 6.0}[d]
    return sum(s.count * unit * s.diameter**d for s in species)


def trajectory_kinds(species: Sequence[Species], diameters) -> dict:
    """The trajectory writers' per-particle keywords for a mixture (each particle's diameter,
    the species' names and each particle's species, ids in blocks); {} for one size."""
    if not species:
        return {}
    return dict(diameters=diameters, types=[s.name for s in species],
                typeid=np.repeat(np.arange(len(species)), [s.count for s in species]))
