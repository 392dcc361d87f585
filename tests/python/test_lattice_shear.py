"""Lees-Edwards shear on the lattice engine from Python: the rate run and its rounding, the steady
start profile, forward and back bit for bit (also through a checkpoint), the observer's stress,
viscosity and velocity profile (resumed from a checkpoint to the same bits), the refusals by name,
and a reduced run of the viscosity study (python -m revcol.studies.shear)."""
import math

import numpy as np
import pytest

import revcol
from revcol.lattice import LatticeSimulation, LatticeSimulation3D


def _same(a: dict, b: dict) -> bool:
    return all(np.array_equal(np.asarray(a[k]), np.asarray(b[k])) for k in ("x", "v", "streams", "bits", "clock", "collisions"))


def test_rate_run_and_start_profile():
    s = LatticeSimulation.random(400, phi=0.4, shear_rate=0.2, seed=2)
    assert s.shear_rate == pytest.approx(0.2, rel=1e-9)
    assert 0 < s.quantization["shear_error"] < 1e-9
    assert s.units["shear"] == round(0.2 * s.box[1] * s.units["tick"] / s.units["length_unit"])
    # the steady profile v_x = rate (y - L/2): its least-squares slope within the thermal noise
    x, v = s.positions, s.velocities
    slope = np.polyfit(x[:, 1] - 0.5 * s.box[1], v[:, 0], 1)[0]
    assert slope == pytest.approx(0.2, abs=0.05)
    assert abs(v[:, 0].sum()) < 1e-6 * len(v)  # no momentum added
    plain = LatticeSimulation.random(400, phi=0.4, seed=2)
    assert plain.shear_rate == 0.0 and "shear_error" not in plain.quantization


@pytest.mark.parametrize("cls,n,phi,mode", [(LatticeSimulation, 400, 0.4, "exact"), (LatticeSimulation, 400, 0.5, "specular"),
                                            (LatticeSimulation3D, 900, 0.3, "exact"), (LatticeSimulation3D, 900, 0.3, "specular")])
def test_forward_and_back_bit_for_bit(cls, n, phi, mode, tmp_path):
    s = cls.random(n, phi=phi, shear_rate=0.3, mode=mode, seed=4)
    s0 = s.snapshot()
    s.run(collisions=3000)
    mid = s.snapshot()
    e_mid = s.diagnostics()["energy_drift"]
    assert e_mid > 0  # the boundary's work heats the gas
    path = tmp_path / "sheared.npz"
    s.save(path)
    s.run(collisions=3000)
    end = s.snapshot()
    r = cls.load(path)  # a checkpoint keeps the shear and resumes on the same bits
    assert r.shear_rate == s.shear_rate
    r.run(collisions=3000)
    assert _same(r.snapshot(), end)
    s.run_back(to_collision=3000)
    assert _same(s.snapshot(), mid)
    s.run_back()
    assert _same(s.snapshot(), s0)


@pytest.mark.parametrize("cls,n", [(LatticeSimulation, 400), (LatticeSimulation3D, 900)])
def test_observed_shear_stress_profile_and_checkpoint(cls, n, tmp_path):
    s = cls.random(n, phi=0.3, shear_rate=0.2, mode="specular", seed=6)
    s.run(collisions=2000)
    s.observe(slabs=6, slab_axis=1, speed_bins=20)
    s.run(collisions=4000)
    path = tmp_path / "observed.npz"
    s.save(path)  # with the running observation
    s.run(collisions=4000)
    r = cls.load(path)
    r.run(collisions=4000)
    a, b = s.observation(), r.observation()
    assert a.to_dict() == b.to_dict()  # resumed to the same bits
    assert a.shear_rate == pytest.approx(s.shear_rate) and a.viscosity.value > 0
    assert a.shear_stress.value == pytest.approx(-a.viscosity.value * a.shear_rate)
    assert np.polyfit(a.slab_velocity.centres, a.slab_velocity.value, 1)[0] == pytest.approx(0.2, rel=0.2)
    assert np.sum(a.speed.value) * (a.speed.edges[1] - a.speed.edges[0]) == pytest.approx(1.0, abs=1e-3)
    plain = cls.random(n, phi=0.3, seed=6)
    plain.observe()
    plain.run(collisions=2000)
    p = plain.observation()
    assert p.shear_rate == 0.0 and p.shear_stress is None and p.slab_velocity is None


def test_refusals_by_name():
    with pytest.raises(ValueError, match="lattice engine"):
        revcol.Simulation.random(100, dim=3, phi=0.3, shear_rate=0.1)  # the float engine's is not built
    with pytest.raises(ValueError, match="one worker"):
        LatticeSimulation.random(400, phi=0.4, shear_rate=0.2, workers=2)
    with pytest.raises(ValueError, match="periodic"):
        LatticeSimulation.random(400, phi=0.4, shear_rate=0.2, boundary=["periodic", "wall"])
    with pytest.raises(ValueError, match="at least 9 diameters"):
        LatticeSimulation.random(40, phi=0.4, shear_rate=0.2)
    with pytest.raises(ValueError, match="shear_rate"):
        LatticeSimulation.random(400, phi=0.4, shear_rate=math.inf)
    with pytest.raises(ValueError, match="bounce-back"):
        LatticeSimulation3D.random(900, phi=0.3, shear_rate=0.2, boundary=["periodic", "periodic", "bounce"])
    s = LatticeSimulation3D.random(900, phi=0.3, shear_rate=0.2, seed=3)
    before = s.snapshot()
    with pytest.raises(ValueError, match="neighbour lists"):
        s.search = 0.5
    with pytest.raises(ValueError, match="slab_axis 1"):
        s.observe(slabs=4)  # across the flow: the profile is along the gradient
    with pytest.raises(ValueError, match="sheared"):
        s.keep_journal(True)
    assert _same(s.snapshot(), before)


def test_viscosity_study_reduced():
    from revcol.studies import shear
    r = shear.measure(500, 0.3, 0.2, "specular", seed=1, warm=5, per_frame=2, frames=10)
    assert r["back_bit_for_bit"]
    # eta* of the specular gas at 0.3 is about 0.72 (docs/shear.md); a short run within 40%
    assert 0.4 < r["eta"] < 1.1
    assert 0.0 < r["eta_kinetic"] < r["eta"]
    assert r["eta_stress"] == pytest.approx(r["eta"], rel=0.25)  # the stress route: the same viscosity
    assert r["profile_slope_over_rate"] == pytest.approx(1.0, abs=0.15)
    fit = shear.extrapolate(np.array([0.05, 0.1, 0.2]), np.array([0.70, 0.72, 0.745]), np.array([0.02, 0.01, 0.01]))
    assert fit["quadratic"]["eta0"] == pytest.approx(0.71, abs=0.02)
