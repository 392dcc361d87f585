"""Threads and pickling (issue 19): the engines' long runs release the GIL (another Python thread
keeps running, the progress callback still runs and may read the state, Ctrl-C still stops a
run: tests/python/test_interrupt.py), a second thread's call on a running engine raises instead
of racing, and both simulations pickle through their snapshots, resuming bit for bit."""
import copy
import pickle
import threading
import time

import numpy as np
import pytest

import revcol
from revcol.lattice import LatticeSimulation


def _float_sim():
    return revcol.Simulation.random(n=300, dim=2, phi=0.3, seed=3, boundary="wall")


def _lattice_sim():
    return LatticeSimulation.random(n=300, phi=0.3, seed=3, boundary="wall")


def _same(a, b):
    for key in ("positions", "velocities"):
        x, y = getattr(a, key), getattr(b, key)
        assert x.dtype == y.dtype and np.array_equal(x, y), key
    assert a.time == b.time


@pytest.mark.parametrize("make", [_float_sim, _lattice_sim], ids=["float", "lattice"])
def test_pickle_round_trip_resumes_bit_for_bit(make):
    a = make()
    a.run(collisions=2000)
    b = pickle.loads(pickle.dumps(a))
    assert type(b) is type(a)
    _same(a, b)
    c = copy.deepcopy(a)
    for s in (a, b, c):
        s.run(collisions=3000)
    _same(a, b)
    _same(a, c)
    for s in (a, b):  # beyond the float engine's horizon: both diverge, identically
        s.run_back(**({} if isinstance(a, LatticeSimulation) else {"on_divergence": "ignore"}))
    _same(a, b)
    if isinstance(a, LatticeSimulation):
        assert a.collisions == b.collisions == 0
        assert np.array_equal(a.snapshot()["x"], b.snapshot()["x"])


def _ticks_during(run) -> tuple[int, float]:
    """Ticks a second thread counts (sleeping 1 ms each) while ``run()`` runs here, and its seconds."""
    stop = threading.Event()
    ticks = [0]

    def ticker():
        while not stop.is_set():
            ticks[0] += 1
            time.sleep(0.001)

    t = threading.Thread(target=ticker)
    t.start()
    time.sleep(0.05)  # the ticker is going
    start_ticks = ticks[0]
    t0 = time.perf_counter()
    try:
        run()
    finally:
        seconds = time.perf_counter() - t0
        stop.set()
        t.join()
    return ticks[0] - start_ticks, seconds


@pytest.mark.parametrize("engine", ["float", "lattice"])
@pytest.mark.parametrize("direction", ["run", "run_back"])
def test_a_second_thread_runs_during_a_long_run(engine, direction):
    # with the GIL held for the whole run the ticker got one tick in 1.1 s; released, it ticks
    # about once per ms (sleep granularity and a shared CPU allowing): ask for a tenth of that
    s = revcol.Simulation.random(n=2000, dim=2, phi=0.3, seed=1, boundary="wall", engine=engine)
    collisions = 300_000
    if direction == "run":
        ticks, seconds = _ticks_during(lambda: s.run(collisions=collisions))
    else:
        s.run(collisions=collisions)
        # far beyond the float engine's horizon: its reversal diverges, and still runs to the start
        kw = {"on_divergence": "ignore"} if engine == "float" else {}
        ticks, seconds = _ticks_during(lambda: s.run_back(**kw))
    assert seconds > 0.05, "the run is too short to tell"
    assert ticks >= max(5, 0.1 * seconds * 1000), (ticks, seconds)


def test_the_callback_runs_with_the_gil_and_may_read_the_state():
    s = _float_sim()
    seen = []
    s.run(collisions=5000, callback=lambda k: seen.append((k, s.positions.shape)), every=1000)
    assert [k for k, _ in seen] == [1000, 2000, 3000, 4000, 5000]
    assert all(shape == (300, 2) for _, shape in seen)


def test_a_callback_cannot_start_a_nested_run():
    s = _float_sim()
    with pytest.raises(RuntimeError, match="inside this Simulation's own run"):
        s.run(collisions=2000, callback=lambda k: s.run(collisions=1), every=1000)


@pytest.mark.parametrize("engine", ["float", "lattice"])
def test_another_thread_cannot_touch_a_running_engine(engine):
    s = revcol.Simulation.random(n=2000, dim=2, phi=0.3, seed=1, boundary="wall", engine=engine)
    errors, done = [], threading.Event()

    def poke():
        while not done.is_set():
            try:
                s.positions
            except RuntimeError as e:
                errors.append(str(e))
                return
            time.sleep(0.0005)

    t = threading.Thread(target=poke)
    t.start()
    try:
        s.run(collisions=400_000)
    finally:
        done.set()
        t.join()
    assert errors and "running in another thread" in errors[0]
    # after the run, any thread may read it again
    out = []
    t = threading.Thread(target=lambda: out.append(s.positions.shape))
    t.start()
    t.join()
    assert out == [(2000, 2)]
