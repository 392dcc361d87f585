"""Dense random starts in walled boxes (issue 58): the spheres-3d geometry (1000 spheres, walls on
z) took volume fractions up to 0.7 and failed "do not fit" above 0.6. A crystal whose outer
layers lie on the walls is the last resort, and a start that still does not fit names the
densest packing fraction that does."""
from __future__ import annotations

import re

import numpy as np
import pytest

import revcol

SLAB = ["periodic", "periodic", "wall"]


@pytest.mark.parametrize("phi", [0.62, 0.65])
def test_a_dense_slab_start_fits_without_overlaps(phi):
    s = revcol.Simulation.random(1000, 3, phi, boundary=SLAB, seed=1)  # the engine checks every pair
    z = s.positions[:, 2]
    assert z.min() >= 0.5 and z.max() <= s.box[2] - 0.5
    s.run(collisions=2000)  # and it runs


def test_a_start_that_does_not_fit_names_the_densest_that_does():
    with pytest.raises(ValueError, match=r"fits up to a packing fraction of 0\.\d+") as e:
        revcol.Simulation.random(1000, 3, 0.69, boundary=SLAB, seed=1)
    densest = float(re.search(r"fits up to a packing fraction of (0\.\d+)", str(e.value)).group(1))
    assert 0.6 < densest < 0.69
    revcol.Simulation.random(1000, 3, densest, boundary=SLAB, seed=1)  # it does fit there


@pytest.mark.parametrize("args, boundary, digest", [
    ((1000, 3, 0.45), "wall", "64c15a872cce6772"),
    ((1000, 3, 0.55), SLAB, "22f4e07bbe8ca872"),
    ((400, 2, 0.7), "wall", "82bd66691e1a96b8"),
    ((400, 2, 0.6), ["periodic", "wall"], "42249e381d579cfa"),
])
def test_a_start_that_fitted_before_is_the_same(args, boundary, digest):
    # the tight crystal is tried only when the others fail: these starts (digests of their
    # positions from the build before it) keep every bit
    import hashlib
    x = revcol.Simulation.random(*args, boundary=boundary, seed=3).positions
    assert hashlib.sha256(np.ascontiguousarray(x).tobytes()).hexdigest()[:16] == digest
