"""A hypothesis fuzz suite over the public API (issue 17): operators, generators, Simulation
construction, run / run_back, snapshots and checkpoints, scene files.

Every generated call must either succeed or raise ValueError / TypeError whose message names
the problem (never pybind11's "incompatible function arguments" or "Unable to cast"), and an
exception must leave the object it was called on bit-identical. A crash fails the run; a hang
is caught by a per-case alarm (the engines poll signals, so the alarm's exception stops a run).

CI runs a few hundred cases per test. The long run (issue 17's 10^5 cases) is the same file:

    REVCOL_FUZZ_EXAMPLES=17000 .venv/bin/python -m pytest -q -p no:cacheprovider tests/python/test_fuzz.py

(six tests x 17 000 examples); tests/long/fuzz_long.py runs it test by test, and
bench/results/fuzz_long.json records one.
"""
from __future__ import annotations

import math
import os
import signal
from contextlib import contextmanager

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis")  # installed by scripts/setup.sh; CI has it
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

import revcol  # noqa: E402
from revcol import Simulation  # noqa: E402

EXAMPLES = int(os.environ.get("REVCOL_FUZZ_EXAMPLES", "150"))
CASE_SECONDS = 20  # a case that runs longer is a hang
FUZZ = settings(max_examples=EXAMPLES, deadline=None, derandomize=EXAMPLES <= 1000,
                suppress_health_check=list(HealthCheck), database=None)
GENERIC = ("incompatible function arguments", "Unable to cast", "incompatible constructor arguments")


@contextmanager
def time_limit(seconds: int = CASE_SECONDS):
    def hang(signum, frame):
        raise TimeoutError(f"case ran past {seconds} s")

    old = signal.signal(signal.SIGALRM, hang)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


def clear_error(e: BaseException) -> None:
    """An expected error: ValueError/TypeError/OverflowError with a message of its own."""
    assert isinstance(e, (ValueError, TypeError, OverflowError)), f"{type(e).__name__}: {e}"
    msg = str(e)
    assert msg and not any(g in msg for g in GENERIC), f"generic message: {msg[:300]}"


def same(a, b, where="") -> None:
    """Bit-identical snapshots (nested dicts, arrays, scalars; NaN equal to NaN)."""
    assert type(a) is type(b) or (np.isscalar(a) and np.isscalar(b)), where
    if isinstance(a, dict):
        assert a.keys() == b.keys(), where
        for k in a:
            same(a[k], b[k], f"{where}.{k}")
    elif isinstance(a, np.ndarray):
        assert a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes(), where
    elif isinstance(a, float):
        assert a == b or (math.isnan(a) and math.isnan(b)), where
    else:
        assert a == b, where


def attempt(fn, *watched):
    """Calls fn(); on an exception checks it is clear and that every watched object's state()
    is unchanged. Returns fn's result or None."""
    before = [w() for w in watched]
    try:
        with time_limit():
            return fn()
    except (ValueError, TypeError, OverflowError) as e:
        clear_error(e)
        for w, b in zip(watched, before):
            same(b, w(), "state after an error")
        return None


# --- strategies ------------------------------------------------------------------------------

ints = st.one_of(st.integers(-3, 70), st.integers(-2**70, 2**70), st.sampled_from([2**31, 2**32, 2**63, 2**64]))
reals = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.floats(-10, 10),
                  st.sampled_from([0.0, -0.0, 1e-320, 1e-300, 1e-160, 1e160, 1e300, 5e-324]))
junk = st.one_of(st.none(), st.text(max_size=4), st.lists(st.integers(), max_size=3), st.booleans(),
                 st.just(object()), st.just(b"xx"), st.just(np.array([1, 2])))
int_arg = st.one_of(ints, ints, reals, junk)
real_arg = st.one_of(reals, reals, ints, junk)


def velocity_arrays(shape):
    scale = st.sampled_from([1.0, 1e-200, 1e-150, 1e-140, 1e130, 1e140, 1e200])
    return st.tuples(st.lists(st.floats(-3, 3), min_size=int(np.prod(shape)), max_size=int(np.prod(shape))),
                     scale).map(lambda t: np.array(t[0]).reshape(shape) * t[1])


# --- operators and generators ----------------------------------------------------------------

CASES = [c["name"] for c in revcol.named_cases()]


def gen_state(g):
    return {"counter": g.counter, "key": tuple(g.key)} if isinstance(g, revcol.Philox) else {"state": tuple(g.state)}


@FUZZ
@given(case=st.sampled_from(CASES), law=st.sampled_from(["flux", "uniform", "bogus"]), bits=int_arg,
       data=st.data(), use_rng=st.booleans(), counter=st.integers(0, 4), batch=st.integers(0, 3))
def test_fuzz_named_operators(case, law, bits, data, use_rng, counter, batch):
    c = next(x for x in revcol.named_cases() if x["name"] == case)
    op = attempt(lambda: revcol.Collision.named(case, law=law, bits=bits))
    if op is None:
        return
    shape = (c["n"], c["d"]) if batch == 0 else (batch, c["n"], c["d"])
    v = data.draw(velocity_arrays(shape))
    if data.draw(st.booleans()):
        v.flat[data.draw(st.integers(0, v.size - 1))] = data.draw(reals)
    g = revcol.Philox(counter=counter)
    kw = {"rng": g} if use_rng else {"g": data.draw(st.one_of(
        st.floats(-0.5, 1.5).map(lambda x: np.full(op.draws if batch == 0 else (batch, op.draws), x)), junk))}
    log = lambda: {"gen": gen_state(g), "log": op.log_size}  # noqa: E731
    post = attempt(lambda: op.forward(v, **kw), log)
    if post is not None:
        assert np.isfinite(post).all()
        back = attempt(lambda: op.reverse(post, **kw), log)
        if back is not None:
            assert np.isfinite(back).all()
    attempt(lambda: op.reverse(v, **kw), log)  # a pre state as a post: usually refused


@FUZZ
@given(mode=st.sampled_from(["exact", "paper", "specular", 3]), law=st.sampled_from(["flux", "uniform"]),
       bits=int_arg, data=st.data(), counter=st.integers(0, 3))
def test_fuzz_pair2d(mode, law, bits, data, counter):
    op = attempt(lambda: revcol.Pair2D(mode=mode, law=law, bits=bits))
    if op is None:
        return
    v = data.draw(velocity_arrays((2, 2)))
    n = data.draw(st.one_of(st.lists(st.floats(-2, 2), min_size=2, max_size=2).map(np.array), real_arg, junk))
    g = revcol.Philox(counter=counter)
    state = lambda: gen_state(g)  # noqa: E731
    post = attempt(lambda: op.forward(v, n, rng=g), state)
    if post is not None:
        attempt(lambda: op.reverse(post, n, rng=g), state)


@FUZZ
@given(kind=st.sampled_from(["philox", "clcg4"]), a=int_arg, b=int_arg, n=int_arg)
def test_fuzz_generators(kind, a, b, n):
    if kind == "philox":
        g = attempt(lambda: revcol.Philox(key=(a, b) if not isinstance(a, list) else a, counter=b))
    else:
        g = attempt(lambda: revcol.CLCG4(stream=a, substream=b))
    if g is None:
        return
    state = lambda: gen_state(g)  # noqa: E731
    if isinstance(n, int) and abs(n) > 10**5:
        n = 10**5 if n > 0 else -1  # the count is validated; the memory is not the point here
    attempt(lambda: g.next_many(n), state)
    attempt(lambda: g.prev_many(n), state)


# --- the engines -----------------------------------------------------------------------------


@FUZZ
@given(engine=st.sampled_from(["float", "lattice"]), n=st.one_of(st.integers(-2, 60), int_arg),
       dim=st.one_of(st.integers(0, 4), int_arg), phi=st.one_of(st.floats(-0.1, 0.9), real_arg),
       boundary=st.sampled_from(["periodic", "wall", "bounce", ["periodic", "wall"], "moebius", 3]),
       diameter=st.one_of(st.just(1.0), real_arg), seed=st.one_of(st.integers(0, 5), int_arg),
       energy=st.one_of(st.none(), real_arg), mode=st.sampled_from(["exact", "paper", "specular", "x"]))
def test_fuzz_simulation_construction(engine, n, dim, phi, boundary, diameter, seed, energy, mode):
    kw = {"mode": mode} if engine == "lattice" else {"energy": energy, "mode": mode}
    s = attempt(lambda: Simulation.random(n, dim, phi, boundary=boundary, diameter=diameter, seed=seed,
                                          engine=engine, **kw))
    if s is not None:
        attempt(lambda: s.run(collisions=20))


def _sim(engine: str, seed: int):
    return Simulation.random(40, 2, 0.4, boundary=["periodic", "wall"] if engine == "float" else "wall",
                             seed=seed, engine=engine)


@FUZZ
@given(engine=st.sampled_from(["float", "lattice"]), seed=st.integers(0, 3),
       calls=st.lists(st.tuples(st.sampled_from(["run", "run_back"]),
                                st.one_of(st.none(), st.integers(-5, 400), int_arg),
                                st.one_of(st.none(), st.floats(-5, 50), real_arg)), min_size=1, max_size=5))
def test_fuzz_run_and_run_back(engine, seed, calls):
    s = _sim(engine, seed)
    for name, collisions, t in calls:
        # the work a valid call asks for is bounded here (run(time=2^30) is a long run, not a hang)
        if isinstance(collisions, int) and not isinstance(collisions, bool) and collisions > 10**4:
            collisions = 10**4
        if isinstance(t, (int, float)) and not isinstance(t, bool) and math.isfinite(t) and abs(t) > 50:
            t = math.copysign(50.0, t)
        attempt(lambda: getattr(s, name)(collisions=collisions, time=t), s.snapshot)


@FUZZ
@given(engine=st.sampled_from(["float", "lattice"]), data=st.data())
def test_fuzz_damaged_snapshots(engine, data):
    s = _sim(engine, 1)
    s.run(collisions=60)
    snap = s.snapshot()
    keys = sorted(k for k in snap if not isinstance(snap[k], dict))
    bad = dict(snap)
    for _ in range(data.draw(st.integers(1, 3))):
        k = data.draw(st.sampled_from(keys))
        old = np.asarray(bad[k])
        choices = [junk, real_arg, int_arg,
                   st.just(old[: max(0, old.size - 1)] if old.ndim else old),                    # truncated
                   st.just(np.concatenate([old.ravel(), old.ravel()[:1]]) if old.size else old)]  # one extra
        if old.dtype.kind in "iuf":
            choices.append(st.just(old.astype(np.float64) if old.dtype.kind != "f" else old.astype(np.int64)))
            lo = 0 if old.dtype.kind == "u" else -2**40
            choices.append(st.integers(lo, 2**40).map(lambda x, o=old: np.full_like(o, x)))  # out-of-range values
        if old.dtype.kind == "f":
            choices.append(st.floats(allow_nan=True).map(lambda x, o=old: np.full_like(o, x)))
        bad[k] = data.draw(st.one_of(*choices))
    if data.draw(st.booleans()):
        bad.pop(data.draw(st.sampled_from(keys)), None)  # a missing field
    t = attempt(lambda: type(s).from_snapshot(bad))
    if t is not None:
        attempt(lambda: t.run(collisions=20), t.snapshot)


SCENE_KEYS = {
    "scene": ["kind", "name", "case"],
    "system": [ "particles", "dimension", "packing_fraction", "box", "boundaries", "diameter",
               "start", "kinetic_energy", "initial_state"],
    "collisions": ["engine", "mode", "law", "bits"],
    "rng": ["generator", "streams", "seed"],
    "run": ["collisions", "time", "checkpoint_interval"],
    "output": ["json", "plot", "trajectory", "trajectory_every", "checkpoints"],
}


@FUZZ
@given(data=st.data())
def test_fuzz_scene_files(data, tmp_path_factory):
    from revcol import scene as scene_mod
    folder = tmp_path_factory.mktemp("scene")
    lines = []
    for table, keys in SCENE_KEYS.items():
        lines.append(f"[{table}]")
        for k in data.draw(st.lists(st.sampled_from(keys), unique=True, max_size=4)):
            value = data.draw(st.one_of(
                st.integers(-3, 3000), st.floats(-1e3, 1e3, allow_nan=False), st.sampled_from(
                    ["1e-320", "1e300", "2147483648", '"gas"', '"../../x"', '"wall"', "[5, 5]", "[1e12, 1e12]",
                     '"lattice"', '"specular"', '"paper"', "true", "-1", "nan", "inf", '"/etc/x"', "[[[[1]]]]"])))
            lines.append(f"{k} = {value}")
    path = folder / "s.toml"
    path.write_text("\n".join(lines) + "\n")
    try:
        with time_limit():
            scene_mod.load_scene(path)
    except (ValueError, TypeError, OverflowError) as e:
        clear_error(e)
