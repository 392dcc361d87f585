"""The crafted-checkpoint suite (issue 17): every entry of a saved checkpoint, on both engines,
truncated, made of strings, NaN, huge (2^62 or 1e300), a pickled object, or missing. Each
damaged file must either be refused with a ValueError/TypeError whose message names the entry,
or be one of the loads listed in LEGAL below (with the reason it is legal), and then run and run
back without any other exception. Each damaged file is re-digested (``revcol._io.digested``, what
``save`` does), so that the consistency checks behind the digest are what is tested here; a
damaged file that keeps the old digest is refused by the digest first
(tests/python/test_checkpoint_digest.py)."""
import os
import warnings

import numpy as np
import pytest

from revcol import Simulation
from revcol._io import DIGEST_KEY, digested

DAMAGES = ("truncated", "strings", "nan", "huge", "pickle", "missing")

# (engine, entry, damage) that load, and why that is right
LEGAL = {
    # counters, stamps and counts: any value of their type is a state a long run can reach
    **{("float", k, "huge"): "a count or stamp" for k in
       ("counters", "ev_stamp", "stamp", "ncoll", "net_collisions", "netc", "log_pushed", "pre_pushed", "rng")},
    ("float", "second", "huge"): "a second collision far in the future is 'none soon'",
    ("float", "cell", "huge"): "cells are recomputed from the list centres (kept for older readers)",
    ("float", "momentum0", "huge"): "walls on every axis: momentum is not conserved, so not checked",
    **{("float", k, "missing"): "written before the entry existed: a default" for k in
       ("centre", "generator", "streams", "trace")},
    ("lattice", "bits", "huge"): "the bits-back integers: any integers are a state",
    ("lattice", "streams", "huge"): "Philox counters: any value",
    ("lattice", "momentum0", "huge"): "not conserved (walls, group bounces), so not checked",
    ("lattice", "units.L", "huge"): "2^62 is a box length the lattice's range holds (validate(u))",
    ("lattice", "units.length_unit", "huge"): "a float scale of 1e300 is finite",
    ("lattice", "units.tick", "huge"): "a float scale of 1e300 is finite",
    ("lattice", "quantization.max_position_error", "huge"): "a reported error, finite",
    ("lattice", "quantization.max_velocity_error", "huge"): "a reported error, finite",
    **{("lattice", k, "missing"): "written before the entry existed: a default" for k in
       ("engine", "mode", "units.tick_bits", "units.cell_bits", "units.boundary",
        "quantization.max_position_error", "quantization.max_velocity_error", "search", "units.gravity",
        "units.shear")},
}


def _damaged(a: np.ndarray, damage: str):
    """The damaged value, or None when the damage would leave the entry as it is."""
    if damage == "missing":
        return "DEL"
    if damage == "pickle":
        return np.asarray([{"x": 1}], dtype=object)
    if damage == "strings":
        return np.asarray(["x"] * max(1, a.size)).reshape(a.shape) if a.size else np.asarray("x")
    if a.size == 0:
        return None  # an empty array damaged is the same empty array
    if damage == "truncated":
        return a[:-1] if a.ndim else None
    if damage == "nan":
        return np.full(a.shape, np.nan) if a.dtype.kind in "fiu" else None
    if a.dtype.kind in "iu":
        return np.full(a.shape, 2**62, dtype=np.int64)
    return np.full(a.shape, 1e300) if a.dtype.kind == "f" else None


def _cases(engine, tmp):
    s = Simulation.random(60, 2, 0.3, seed=1, engine=engine, boundary="wall")
    s.run(collisions=80)
    path = os.path.join(tmp, f"{engine}.npz")
    s.save(path)
    with np.load(path) as z:
        data = {k: z[k] for k in z.files}
    for key in sorted(data):
        if key.startswith("revcol_") or key == DIGEST_KEY:  # the digest's own damage: test_checkpoint_digest.py
            continue
        for damage in DAMAGES:
            bad = _damaged(data[key], damage)
            if bad is None:
                continue
            yield type(s), data, key, damage, bad


@pytest.mark.parametrize("engine", ["float", "lattice"])
def test_every_damaged_entry_is_refused_by_name_or_legal(engine, tmp_path):
    refused = loaded = 0
    problems = []
    for cls, data, key, damage, bad in _cases(engine, str(tmp_path)):
        d = dict(data)
        if isinstance(bad, str):
            del d[key]
        else:
            d[key] = bad
        q = tmp_path / "b.npz"
        if damage == "pickle":  # refused on reading the entry, before the digest (objects have no digest)
            np.savez(q, **d, allow_pickle=True)
        else:  # a digest that matches the damage: the entry's own check must refuse it
            np.savez(q, **digested(d))
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                sim = cls.load(q)
        except (ValueError, TypeError) as e:
            refused += 1
            leaf = key.split(".")[-1]
            if leaf not in str(e) and damage != "pickle":
                problems.append(f"{key}/{damage}: message does not name it: {e}")
            continue
        loaded += 1
        if (engine, key, damage) not in LEGAL:
            problems.append(f"{key}/{damage}: loaded")
            continue
        try:  # a legal load must also run and run back (or refuse with a named error)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                sim.run(collisions=50)
                sim.run_back(collisions=50)
        except (ValueError, OverflowError):
            pass
    assert not problems, "\n".join(problems)
    assert refused > 50 and loaded == sum(1 for k in LEGAL if k[0] == engine), (refused, loaded)


def test_a_forged_wall_partner_is_named_for_what_it_is():
    # issue 59: both forgeries said "wall event on an axis without walls"
    import revcol
    s = revcol.Simulation.random(50, dim=2, phi=0.3, boundary=["wall", "periodic"], seed=1)
    s.run(collisions=100)
    d = s.snapshot()
    kind, partner = np.array(d["ev_kind"]), np.array(d["ev_partner"])
    kind[0], partner[0] = 0, 2  # a wall event on axis 1, which is periodic
    d["ev_kind"], d["ev_partner"] = kind, partner
    with pytest.raises(ValueError, match="a wall event on axis 1, which has no walls"):
        revcol.Simulation.from_snapshot(d)
    partner[0] = 7
    d["ev_partner"] = partner
    with pytest.raises(ValueError, match=r"must be 2 axis \+ \(upper wall\), in \[0, 4\), got 7"):
        revcol.Simulation.from_snapshot(d)
