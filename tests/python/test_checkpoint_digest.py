"""Checkpoint integrity (issue 59): every checkpoint of both engines carries ``digest_sha256``, the
SHA-256 of the canonical bytes of its other entries (``revcol._io.content_digest``), written by
``save`` and checked by ``load``. A changed byte anywhere (a position, the lattice's bits-back
words, a log entry, a scalar, the stamp) is refused with "checkpoint corrupted: digest mismatch"
naming the file, before any state is built; a malformed digest entry is refused; a file without
one (written before digests) loads unchecked. Every writer (``save``, ``revcol simulate``'s and
``revcol run``'s checkpoints) goes through ``revcol._io.write_checkpoint``."""
import hashlib
import os
import warnings

import numpy as np
import pytest

from revcol import Simulation
from revcol._io import DIGEST_KEY, content_digest, digested
from revcol.cli.main import main as cli_main
from revcol.lattice import LatticeSimulation, LatticeSimulation3D, restart_from_legacy
from revcol.studies.scenes import run_scene

MISMATCH = r"^checkpoint corrupted: digest mismatch in '[^']*{name}'"
MALFORMED = r"^checkpoint corrupted: malformed digest entry 'digest_sha256' in '[^']*{name}'"

# the entries each case flips a byte of: positions, the generators' state (the lattice's
# bits-back words X; the float engine's stream counters), a log, and scalars
FLIPS = {
    "float": {"position": "x", "bits": "rng", "log": ("log_cells", "wall_keys", "pre_vals", "trace"),
              "scalar": ("time", "net_collisions")},
    "lattice": {"position": "x", "bits": "bits", "log": ("log_particle", "log_count", "group_drawer",
                                                          "group_members", "group_v"),
                "scalar": ("clock", "collisions")},
}


def _has_log(sim) -> bool:
    s = sim.snapshot()
    return any(np.asarray(s[k]).size for k in FLIPS["lattice"]["log"])


def _make(case: str):
    """A small gas a few hundred collisions in; the lattice ones run on (a few thousand, well
    under a second) until their rare log or group log holds an entry, the float cradle has one
    entry in its exact-pre log."""
    if case == "float2":
        sim = Simulation.random(60, 2, 0.3, seed=1, boundary="wall")
        sim.run(collisions=300)
    elif case == "float3":
        sim = Simulation.random(60, 3, 0.3, seed=2)
        sim.run(collisions=300)
    elif case == "float2-cradle":
        x = np.array([[5.0, 15.0], [10.0, 15.0], [11.0, 15.0], [12.0, 15.0]])
        v = np.array([[1.0, 0.0], [0.0, 0.0], [0.0, 0.0], [0.0, 0.0]])
        sim = Simulation(x, v, [30.0, 30.0], boundary="wall")
        sim.run(time=6.0)
        assert sim.diagnostics()["exact_pre_entries"] == 1
    else:
        sim = (LatticeSimulation.random(60, phi=0.6, seed=4, tick_bits=16) if case == "lattice2" else
               LatticeSimulation3D.random(200, phi=0.4, seed=4, tick_bits=16))
        sim.run(collisions=300)
        for _ in range(60):
            if _has_log(sim):
                break
            sim.run(collisions=500)
        assert _has_log(sim)
    return sim


CASES = ("float2", "float3", "float2-cradle", "lattice2", "lattice3")


@pytest.fixture(scope="module", params=CASES)
def saved(request, tmp_path_factory):
    """(case, the simulation, its saved file, the file's arrays)."""
    sim = _make(request.param)
    path = tmp_path_factory.mktemp(request.param) / "a.npz"
    sim.save(path)
    with np.load(path) as z:
        data = {k: z[k] for k in z.files}
    return request.param, sim, path, data


def _same(a: dict, b: dict) -> bool:
    """Two snapshots equal entry by entry, values and dtypes (nested dicts too)."""
    if a.keys() != b.keys():
        return False
    for k in a:
        if isinstance(a[k], dict):
            if not _same(a[k], b[k]):
                return False
        else:
            x, y = np.asarray(a[k]), np.asarray(b[k])
            if x.dtype != y.dtype or x.shape != y.shape or x.tobytes() != y.tobytes():
                return False
    return True


def _flip(a: np.ndarray, at: int = 0) -> np.ndarray:
    """``a`` with the lowest bit of its byte ``at`` flipped (byte 0: the least significant byte
    of the first element, on a little-endian machine the smallest change the type holds)."""
    b = np.array(a, copy=True)
    raw = b.reshape(-1).view(np.uint8)  # a view of b's bytes
    raw[at] ^= 1
    return b


def _load(cls, path):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no stamp warning either: the file is this build's
        return cls.load(path)


# --- the round trip ------------------------------------------------------------------------


def test_save_and_load_are_bit_for_bit_and_the_digest_is_canonical(saved, tmp_path):
    case, sim, path, data = saved
    assert DIGEST_KEY in data and data[DIGEST_KEY].dtype.kind == "U" and data[DIGEST_KEY].ndim == 0
    assert str(data[DIGEST_KEY]) == content_digest(data)
    back = _load(type(sim), path)
    assert type(back) is type(sim) and _same(back.snapshot(), sim.snapshot())
    # the loaded state saved again: the same entries, so the same digest
    back.save(tmp_path / "again.npz")
    with np.load(tmp_path / "again.npz") as z:
        assert str(z[DIGEST_KEY]) == str(data[DIGEST_KEY])
    # and it runs on as the saved one does (bit for bit)
    twin = type(sim).from_snapshot(sim.snapshot())
    for s in (back, twin):
        s.run(collisions=200)
    assert _same(back.snapshot(), twin.snapshot())


# --- a changed byte ------------------------------------------------------------------------


def _entries(case: str, data: dict):
    """(what, entry) pairs to flip a byte of, for this case."""
    f = FLIPS["float" if case.startswith("float") else "lattice"]
    log = next(k for k in f["log"] if k in data and data[k].size)
    out = [("position", f["position"]), ("bits", f["bits"]), ("log", log)]
    out += [("scalar", k) for k in f["scalar"]]
    out += [("stamp", "revcol_engine")]
    return out


def test_a_flipped_byte_in_any_entry_is_refused_by_the_digest(saved, tmp_path):
    case, sim, path, data = saved
    before = sim.snapshot()
    cls = type(sim)
    entries = _entries(case, data)
    assert {w for w, _ in entries} >= {"position", "bits", "log", "scalar"}
    for what, key in entries:
        a = data[key]
        for at in sorted({0, a.nbytes // 2, a.nbytes - 1}):
            bad = dict(data)
            bad[key] = _flip(a, at)  # the digest kept as saved
            q = tmp_path / f"{what}-{key}-{at}.npz"
            np.savez(q, **bad)
            loaded = None
            with pytest.raises(ValueError, match=MISMATCH.format(name=q.name)):
                loaded = cls.load(q)
            assert loaded is None  # nothing was built
            # the simulation that wrote the file is as it was
            assert _same(sim.snapshot(), before), (what, key)


def test_a_changed_position_that_every_other_check_accepts_is_refused(tmp_path):
    """The digest's reason: the last bit of a float position is a state the consistency checks
    cannot tell from the saved one (the same file without a digest loads, a different state)."""
    sim = _make("float2")
    sim.save(tmp_path / "a.npz")
    with np.load(tmp_path / "a.npz") as z:
        data = {k: z[k] for k in z.files}
    data["x"] = _flip(data["x"])
    np.savez(tmp_path / "b.npz", **data)
    with pytest.raises(ValueError, match=MISMATCH.format(name="b.npz")):
        Simulation.load(tmp_path / "b.npz")
    del data[DIGEST_KEY]
    np.savez(tmp_path / "c.npz", **data)
    changed = Simulation.load(tmp_path / "c.npz")
    assert not np.array_equal(changed.positions, sim.positions)


def test_an_entry_added_removed_or_renamed_is_refused(saved, tmp_path):
    case, sim, path, data = saved
    key = "x"
    changes = {
        "added": {**data, "extra": np.zeros(3)},
        "removed": {k: v for k, v in data.items() if k != "seed"},
        "renamed": {**{k: v for k, v in data.items() if k != key}, key + "_": data[key]},
        "reshaped": {**data, key: data[key].reshape(-1)} if data[key].ndim > 1 else
                    {**data, key: data[key].reshape(-1, 1)},
        "retyped": {**data, "seed": data["seed"].astype(np.uint64)},
    }
    for what, d in changes.items():
        q = tmp_path / f"{what}.npz"
        np.savez(q, **d)
        with pytest.raises(ValueError, match=MISMATCH.format(name=q.name)):
            type(sim).load(q)


# --- files without a digest, and malformed ones -----------------------------------------


def test_a_file_without_a_digest_loads_unchecked(saved, tmp_path):
    case, sim, path, data = saved
    old = {k: v for k, v in data.items() if k != DIGEST_KEY}
    np.savez(tmp_path / "old.npz", **old)
    back = _load(type(sim), tmp_path / "old.npz")
    assert _same(back.snapshot(), sim.snapshot())


@pytest.mark.parametrize("bad", ["", "0" * 63, "0" * 65, "g" * 64, "UPPER", "bytes", "list", "int", "empty"])
def test_a_malformed_digest_is_refused(saved, tmp_path, bad):
    case, sim, path, data = saved
    good = str(data[DIGEST_KEY])
    value = {"UPPER": np.asarray(good.upper()), "bytes": np.frombuffer(bytes.fromhex(good), dtype=np.uint8),
             "list": np.asarray([good]), "int": np.asarray(7), "empty": np.zeros(0)}.get(bad, np.asarray(bad))
    np.savez(tmp_path / "m.npz", **{**data, DIGEST_KEY: value})
    with pytest.raises(ValueError, match=MALFORMED.format(name="m.npz")):
        type(sim).load(tmp_path / "m.npz")


def test_restart_from_legacy_reads_through_the_digest_check(tmp_path):
    sim = _make("lattice2")
    sim.save(tmp_path / "a.npz")
    with np.load(tmp_path / "a.npz") as z:
        data = {k: z[k] for k in z.files}
    np.savez(tmp_path / "b.npz", **{**data, "clock": _flip(data["clock"])})
    with pytest.raises(ValueError, match=MISMATCH.format(name="b.npz")):
        restart_from_legacy(tmp_path / "b.npz")


# --- the definition ---------------------------------------------------------------------


def _reference_digest(arrays: dict) -> str:
    """The digest as docs/robustness.md defines it, written out again."""
    h = hashlib.sha256(b"revcol checkpoint digest v1\n")
    le = lambda k: k.to_bytes(8, "little")  # noqa: E731
    for key in sorted(arrays):
        if key == DIGEST_KEY:
            continue
        a = np.asarray(arrays[key])
        name, dt = key.encode(), a.dtype.str.encode()
        data = a.tobytes(order="C")
        h.update(le(len(name)) + name + le(len(dt)) + dt + le(a.ndim) + b"".join(le(e) for e in a.shape)
                 + le(len(data)) + data)
    return h.hexdigest()


def test_the_digest_is_the_documented_one(saved):
    case, sim, path, data = saved
    assert str(data[DIGEST_KEY]) == _reference_digest(data) == content_digest(data)


def test_the_digest_sees_dtype_shape_and_names_but_not_memory_order():
    a = np.arange(6, dtype=np.int64).reshape(2, 3)
    base = content_digest({"a": a, "b": np.asarray(1.5)})
    assert content_digest({"a": np.asfortranarray(a), "b": np.asarray(1.5)}) == base
    assert content_digest({"b": np.asarray(1.5), "a": a}) == base  # key order
    assert content_digest({"a": a, "b": np.asarray(1.5), DIGEST_KEY: np.asarray("f" * 64)}) == base
    for other in ({"a": a.reshape(3, 2), "b": np.asarray(1.5)}, {"a": a.astype(np.uint64), "b": np.asarray(1.5)},
                  {"a": a, "c": np.asarray(1.5)}, {"a": a, "b": np.asarray([1.5])},
                  {"a": a.reshape(-1)[:5], "b": np.asarray(1.5)}):
        assert content_digest(other) != base
    # bytes moved from one entry's end to the next's start: the lengths tell them apart
    assert content_digest({"a": np.frombuffer(b"xy", np.uint8), "b": np.frombuffer(b"z", np.uint8)}) != \
        content_digest({"a": np.frombuffer(b"x", np.uint8), "b": np.frombuffer(b"yz", np.uint8)})
    with pytest.raises(TypeError, match="'o' holds Python objects"):
        content_digest({"o": np.asarray([{}], dtype=object)})
    d = digested({"a": a, DIGEST_KEY: np.asarray("0" * 64)})
    assert str(d[DIGEST_KEY]) == content_digest({"a": a})


# --- every writer ------------------------------------------------------------------------


def _valid(path) -> bool:
    with np.load(path) as z:
        data = {k: z[k] for k in z.files}
    return DIGEST_KEY in data and str(data[DIGEST_KEY]) == content_digest(data)


SCENE = "[system]\ndimension = 2\nparticles = 64\npacking_fraction = 0.3\n[collisions]\nengine = \"{engine}\"\n" \
        "[rng]\nseed = 3\n[run]\ncollisions = 400\n"


@pytest.mark.parametrize("engine", ["float", "lattice"])
def test_revcol_simulate_writes_digests_and_refuses_a_corrupted_resume(tmp_path, capsys, engine):
    s = tmp_path / "s.toml"
    s.write_text(SCENE.format(engine=engine))
    assert cli_main(["simulate", str(s), "--checkpoint", str(tmp_path / "ck"), "--checkpoint-every", "200",
                     "--no-progress"]) == 0
    files = sorted((tmp_path / "ck").iterdir())
    assert [f.name for f in files] == ["checkpoint-000000000200.npz", "checkpoint-000000000400.npz"]
    assert all(_valid(f) for f in files)
    with np.load(files[-1]) as z:
        data = {k: z[k] for k in z.files}
    data["v"] = _flip(data["v"], 8)
    np.savez(files[-1], **data)
    capsys.readouterr()
    rc = cli_main(["simulate", str(s), "--resume", str(files[-1]), "--collisions", "100",
                   "--checkpoint", str(tmp_path / "ck2"), "--checkpoint-every", "50",
                   "--json", str(tmp_path / "r.json"), "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2 and "checkpoint corrupted: digest mismatch in" in err and files[-1].name in err
    assert not (tmp_path / "ck2").exists() and not (tmp_path / "r.json").exists()  # nothing ran


@pytest.mark.parametrize("engine", ["float", "lattice"])
def test_revcol_run_checkpoints_carry_digests(tmp_path, monkeypatch, engine):
    s = tmp_path / "s.toml"
    s.write_text(SCENE.format(engine=engine) + "checkpoint_interval = 200\n[output]\ncheckpoints = \"ck\"\n")
    monkeypatch.chdir(tmp_path)
    r = run_scene(str(s), progress=False)
    assert len(r["checkpoints"]) == 2 and all(_valid(os.path.join(tmp_path, c)) for c in r["checkpoints"])


@pytest.mark.parametrize("entry", ["streams", "particle_collisions"])
def test_a_digest_less_inconsistent_lattice_state_is_named_by_the_reverse_and_left_unchanged(entry):
    # behind the digest (a state built in memory, or a file from before digests): a stream
    # counter one draw short, or two particles' counts swapped (they still add up), is met by
    # the reverse, which names it as an inconsistent state, not as a bug of the engine, and
    # leaves the state as it was (the engine restores what run_back began with)
    from revcol.lattice import LatticeSimulation
    sim = LatticeSimulation.random(n=200, phi=0.5, seed=9, boundary="wall")
    sim.run(collisions=3000)
    snap = sim.snapshot()
    bad = dict(snap)
    pc = np.asarray(snap["particle_collisions"]).copy()
    if entry == "streams":
        st = np.asarray(snap["streams"]).copy()
        p = int(np.argmax(st))
        st[p] -= np.uint64(1)
        bad["streams"] = st
    else:
        p, q = int(np.argmax(pc)), int(np.argmin(pc))
        pc[p], pc[q] = pc[q], pc[p]
        bad["particle_collisions"] = pc
    try:
        tampered = LatticeSimulation.from_snapshot(bad)
    except ValueError:
        return  # refused at load: harmless
    before = tampered.snapshot()
    with pytest.raises(RuntimeError, match="inconsistent state"):
        tampered.run_back()
    after = tampered.snapshot()
    assert all(np.array_equal(np.asarray(before[k]), np.asarray(after[k])) for k in ("x", "v", "streams", "bits",
                                                                                     "particle_collisions", "clock"))
