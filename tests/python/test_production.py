"""A production run checked from its own outputs (issue 19): `revcol simulate` of the default
gas (periodic, float engine, observed) with GSD frames on a time trigger; g(r) from the
frames (freud when installed) gives a contact value whose pressure matches the collision
virial's, and the image flags are exactly those of the same run followed densely. The CI form of
`tests/long/production_check.py` (which runs 10^7 collisions)."""
from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("gsd")

_PATH = Path(__file__).resolve().parents[1] / "long" / "production_check.py"
_spec = importlib.util.spec_from_file_location("production_check", _PATH)
production_check = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(production_check)

from revcol.observe import compressibility_from_contact, contact_value, radial_distribution  # noqa: E402


def test_contact_value_and_image_flags_agree_with_the_observer(tmp_path):
    r = production_check.check(collisions=200_000, every=2_000, workdir=str(tmp_path))
    assert r["frames"] >= 100 and r["max_image"] >= 1
    # 1. Z from g(D+) of time-triggered frames within 3 combined standard errors of the
    #    collision virial's Z, with an error small enough that a 2.5% error in Z would show
    assert r["z_difference_sigmas"] <= 3.0, r
    assert r["z_contact_error"] < 0.03
    # 2. the image flags equal those of the same run followed every 100 collisions
    assert r["image_flags_equal_dense_reference"]
    #    and the MSD they give is the observer's (to its sampling grid's interpolation)
    assert r["msd_max_rel_difference_to_observer"] < 0.05
    # frames on a collision trigger are the same run (the pauses change nothing)
    assert r["collision_trigger"]["same_run_as_time_trigger"]
    assert r["passed"]


def test_contact_value_and_compressibility_helpers():
    r = np.linspace(0.51, 2.99, 125)
    g = np.where(r > 1.0, 1.5 + 0.8 * (r - 1.0) - 0.3 * (r - 1.0) ** 2, 0.0)
    assert math.isclose(contact_value(r, g, 1.0), 1.5, rel_tol=1e-12)
    with pytest.raises(ValueError, match="needs at least"):
        contact_value(r, g, 1.0, width=0.01)
    assert compressibility_from_contact(2.0, 0.3, 2) == pytest.approx(1 + 2 * 0.3 * 2.0)
    assert compressibility_from_contact(2.0, 0.3, 3) == pytest.approx(1 + 4 * 0.3 * 2.0)
    with pytest.raises(ValueError, match="dim"):
        compressibility_from_contact(2.0, 0.3, 4)


def test_freud_and_numpy_give_the_same_g_of_r():
    freud = pytest.importorskip("freud")  # noqa: F841
    rng = np.random.default_rng(4)
    L = np.array([12.0, 12.0])
    frames = rng.random((6, 300, 2)) * L
    rf, gf = radial_distribution(frames, L, bins=60, r_max=3.0, use_freud=True)
    rn, gn = radial_distribution(frames, L, bins=60, r_max=3.0, use_freud=False)
    assert np.allclose(rf, rn, atol=1e-6)
    # same normalization ((n - 1) / V); what differs is ordered pairs that freud's float32
    # positions move across a bin edge: whole numbers of pairs (2 per pair), a handful at most
    # (to within 0.05 of a pair: freud's float32 shell volumes and g differ by ~1e-6 relative)
    edges = np.linspace(0.0, 3.0, 61)
    ideal = 6 * 300 * 299 / L.prod() * np.pi * (edges[1:] ** 2 - edges[:-1] ** 2)
    moved = (gf - gn) * ideal
    assert np.allclose(moved, np.round(moved), atol=0.05)
    assert np.abs(moved).sum() <= 8
