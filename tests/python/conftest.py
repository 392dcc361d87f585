import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest


@pytest.fixture
def pre_states():
    """Ten fixed approaching pre-collision states (velocities (2,2), unit-free normal (2,)),
    from head-on to nearly grazing, with slow and fast centres of mass."""
    rng = np.random.default_rng(20131)
    states = []
    while len(states) < 10:
        v = rng.normal(size=(2, 2)) * rng.choice([0.1, 1.0, 10.0])
        n = rng.normal(size=2)
        w = v[0] - v[1]
        if w @ n > 0:
            n = -n
        states.append((v, n))
    # one nearly grazing state: approach speed 1e-9 of the relative speed
    states[-1] = (np.array([[-1e-9, 1.0], [0.0, 0.0]]), np.array([1.0, 0.0]))
    return states


def run_cli(folder, args, capsys):
    """``revcol ARGS --no-progress`` run in ``folder`` (a scene's [output] paths are taken under
    the current directory): the exit status and standard error's lines (the output-guard and
    output-size tests: ``from conftest import run_cli``)."""
    from revcol.cli.main import main
    cwd = os.getcwd()
    os.chdir(folder)
    try:
        rc = main([str(a) for a in args] + ["--no-progress"])
    finally:
        os.chdir(cwd)
    return rc, capsys.readouterr().err.strip().splitlines()


def interrupt_child(tmp_path, code, args, ready_s=120, after_s=0.3, wait_s=60):
    """Runs `code` in a child, sends SIGINT `after_s` after it prints "ready"; returns (rc, output)
    (the Ctrl-C tests: ``from conftest import interrupt_child``)."""
    script = tmp_path / "child.py"
    script.write_text(code)
    out = tmp_path / "out.txt"
    with open(out, "w") as f:
        # SIGINT at its default in the child, whatever this process inherited: a shell's
        # background job (`cmd &`) starts with SIGINT ignored, and a Python started that way
        # keeps ignoring it instead of raising KeyboardInterrupt
        child = subprocess.Popen([sys.executable, str(script), *args], stdout=f, stderr=subprocess.STDOUT,
                                 env=dict(os.environ), preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        deadline = time.monotonic() + ready_s
        while "ready" not in out.read_text():
            assert child.poll() is None, out.read_text()
            assert time.monotonic() < deadline, "child never got ready"
            time.sleep(0.05)
        time.sleep(after_s)
        child.send_signal(signal.SIGINT)
        rc = child.wait(timeout=wait_s)  # was: never (the loops did not look at signals)
    finally:
        if child.poll() is None:
            child.kill()
    return rc, out.read_text()
