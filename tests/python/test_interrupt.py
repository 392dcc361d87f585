"""Ctrl-C reaches every run (issue 17): a SIGINT during run or run_back, on either engine, stops
the run at a valid point within a fraction of a second and raises KeyboardInterrupt; the
simulation goes on from there (the lattice engine still returns to its start bit for bit). Under the CLI's handler
(revcol.progress.Interrupt), which counts presses instead of raising, the first one stops the
run too, collisions or not, and the report is written (issue 59)."""
import json
import os
import signal
import subprocess
import sys
import time

import pytest

from conftest import interrupt_child as _interrupt

CHILD = r"""
import sys, numpy as np, revcol
engine, direction = sys.argv[1], sys.argv[2]
workers = {"lattice-parallel": {"workers": 2}}.get(engine, {})  # (the parallel lattice engine, two threads)
engine = engine.split("-")[0]
s = revcol.Simulation.random(2000, 2, 0.3, seed=1, engine=engine, boundary="wall", **workers)
x0, v0 = s.positions.copy(), s.velocities.copy()
if direction == "back":  # a run_back of seconds, so that the SIGINT 0.3 s in surely lands inside it
    s.run(collisions=2000000)
print("ready", flush=True)
try:
    if direction == "fwd":
        s.run(collisions=10**12)  # hours: only Ctrl-C ends it
    else:
        s.run_back()
    print("finished", flush=True)
except KeyboardInterrupt:
    print("interrupted", flush=True)
    s.run(collisions=100)
    s.run_back()
    if engine == "lattice":
        assert np.array_equal(s.positions, x0) and np.array_equal(s.velocities, v0)
    print("usable", flush=True)
"""


@pytest.mark.parametrize("direction", ["fwd", "back"])
@pytest.mark.parametrize("engine", ["float", "lattice"])
def test_ctrl_c_stops_a_run_at_a_valid_point(engine, direction, tmp_path):
    rc, text = _interrupt(tmp_path, CHILD, [engine, direction])
    assert rc == 0 and "interrupted" in text and "usable" in text, text


def test_ctrl_c_stops_a_parallel_lattice_run_at_a_whole_tick(tmp_path):
    # the worker threads stop at the next GVT; the state is the run's at a whole tick, from which
    # the simulation goes on and comes back to its start bit for bit
    rc, text = _interrupt(tmp_path, CHILD, ["lattice-parallel", "fwd"])
    assert rc == 0 and "interrupted" in text and "usable" in text, text


STUDY = r"""
import sys, revcol
from revcol import _core
what, path = sys.argv[1], sys.argv[2]
print("ready", flush=True)
try:
    if what == "verify":
        _core.verify(case="pair2d", collisions=10**12)
    elif what == "paper_study":
        _core.paper_study(case="pair3d", collisions=10**12)
    elif what == "statesave":
        _core.statesave_run(particles=1000, collisions=2**32, variant="rc", transport="lazy")
    else:
        s = _core.WordStream(case="pair2d")
        try:
            s.write(path, 10**12)
        except KeyboardInterrupt:
            import os
            # the file holds exactly the words the stream moved past
            assert os.path.getsize(path) == 4 * s.emitted, (os.path.getsize(path), s.emitted)
            assert s.emitted > 0
            print("consistent", flush=True)
            raise
    print("finished", flush=True)
except KeyboardInterrupt:
    print("interrupted", flush=True)
"""


@pytest.mark.parametrize("what", ["verify", "paper_study", "statesave", "wordstream"])
def test_ctrl_c_stops_a_study(what, tmp_path):
    """The studies' C++ loops poll for Ctrl-C too (revcol/interrupt.hpp): before, each of these
    ran for hours with the GIL released and could only be killed."""
    rc, text = _interrupt(tmp_path, STUDY, [what, str(tmp_path / "w.bin")], ready_s=60, after_s=0.5, wait_s=30)
    assert rc == 0 and "interrupted" in text, text
    if what == "wordstream":
        assert "consistent" in text, text


CLI = r"""
import sys
from revcol.cli.main import main
from revcol.progress import Interrupt

enter = Interrupt.__enter__


def enter_and_say_ready(self):  # "ready" once the run's Ctrl-C handler is in place, never before
    out = enter(self)
    print("ready", flush=True)
    return out


Interrupt.__enter__ = enter_and_say_ready
sys.exit(main(sys.argv[1:]))
"""


@pytest.mark.parametrize("command", ["simulate", "run"])
@pytest.mark.parametrize("engine", ["float", "lattice"])
def test_the_first_ctrl_c_stops_a_run_without_collisions(engine, command, tmp_path):
    """Issue 59: one particle in a periodic box never collides, so the run never reached the
    progress callback that reads the counted press; the first two Ctrl-C did nothing and the
    third ended it with a traceback and no report. One SIGINT now stops it at the engine's
    next poll, with the report written and the exit status of an interrupted run."""
    scene = tmp_path / "one.toml"
    scene.write_text(f'[system]\ndimension = 2\nparticles = 1\npacking_fraction = 0.01\nboundaries = "periodic"\n'
                     f'[collisions]\nengine = "{engine}"\n[run]\ntime = 1e9\n')
    report = tmp_path / "r.json"
    # `revcol run` then goes back from where it stopped, as long again as it went forward
    rc, text = _interrupt(tmp_path, CLI, [command, str(scene), "--json", str(report), "--no-progress"],
                          after_s=0.5, wait_s=10)
    assert rc == 130 and "Traceback" not in text and "interrupted" in text, text
    r = json.loads(report.read_text())
    if command == "simulate":
        assert r["interrupted"] and r["collisions"] == 0 and 0 < r["time_end"] < 1e9, r
    else:
        assert r["interrupted"] == "forward" and r["collisions_forward"] == 0 and r["passed"], r
