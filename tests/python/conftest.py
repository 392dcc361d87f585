import os

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
