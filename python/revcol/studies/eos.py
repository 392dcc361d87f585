"""The hard-sphere fluid's reference values the studies compare a run against: equations of
state (Liu's, Henderson's, Carnahan-Starling's, Tonks'), the contact value and Enskog's
collision rate they imply, the Maxwell-Boltzmann and the exact finite-N speed densities, and the
1/N extrapolation of Z to infinite size.

Both the equilibrium study (:mod:`revcol.studies.equilibrium`) and event-chain Monte Carlo
(:mod:`revcol.studies.ecmc`) use them; neither imports the other for them.

    >>> round(reference_z(2, 0.5), 4), round(reference_z(1, 0.5), 4)
    (4.1052, 2.0)
"""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np

__all__ = ["henderson", "carnahan_starling", "liu_disks", "liu_spheres", "reference_z", "classic_z",
           "contact_value", "enskog_rate", "maxwell_speed_density", "microcanonical_speed_density", "extrapolate"]



def henderson(phi: float) -> float:
    """Henderson's equation of state of hard disks (Mol. Phys. 30, 971 (1975)):
    Z = (1 + phi^2 / 8) / (1 - phi)^2."""
    return (1.0 + phi * phi / 8.0) / (1.0 - phi) ** 2


def carnahan_starling(phi: float) -> float:
    """Carnahan and Starling's equation of state of hard spheres (J. Chem. Phys. 51, 635
    (1969)): Z = (1 + phi + phi^2 - phi^3) / (1 - phi)^3."""
    return (1.0 + phi + phi**2 - phi**3) / (1.0 - phi) ** 3


def liu_disks(phi: float) -> float:
    """Liu's equation of state of the stable hard-disk fluid (H. Liu, "Global equation of state
    and phase transitions of the hard disc systems", arXiv:2010.10624 (2020), Eq. 1):
    Z = (1 + phi^2/8 + phi^3/18 - 4 phi^4/21) / (1 - phi)^2 (a Henderson-type form refitted
    to modern simulation data; fluid only, phi up to about 0.7)."""
    return (1.0 + phi**2 / 8.0 + phi**3 / 18.0 - 4.0 * phi**4 / 21.0) / (1.0 - phi) ** 2


def liu_spheres(phi: float) -> float:
    """Liu's correction to Carnahan-Starling for the hard-sphere fluid (H. Liu, Mol. Phys. 119,
    e1886364 (2021)): Z = (1 + phi + phi^2 - 8 phi^3/13 - phi^4 + phi^5/2) / (1 - phi)^3."""
    return (1.0 + phi + phi**2 - 8.0 * phi**3 / 13.0 - phi**4 + phi**5 / 2.0) / (1.0 - phi) ** 3


def reference_z(d: int, phi: float) -> float:
    """The reference equation of state of the fluid: Liu's for disks (2D) and spheres (3D),
    both within about 0.05% of modern simulation data where Henderson's (2D) drifts to +1% at
    0.6 and Carnahan-Starling's (3D) is 0.2-0.3% low at 0.3-0.45. In 1D, Tonks' exact
    1 / (1 - phi)."""
    if d == 1:
        return 1.0 / (1.0 - phi)
    return liu_disks(phi) if d == 2 else liu_spheres(phi)


def classic_z(d: int, phi: float) -> float:
    """Henderson (2D) or Carnahan-Starling (3D), the textbook forms, for comparison."""
    return henderson(phi) if d == 2 else carnahan_starling(phi)


def contact_value(d: int, phi: float, z: float) -> float:
    """g(sigma) from Z: Z - 1 = 2^(d-1) phi g(sigma) (the virial theorem for hard spheres)."""
    return (z - 1.0) / (2 ** (d - 1) * phi)


def enskog_rate(d: int, phi: float, temperature: float, g_contact: float, diameter: float = 1.0) -> float:
    """Collisions per particle per unit time, Enskog: n sigma^(d-1) S g(sigma) sqrt(T / pi)
    with S = 2 pi (2D) or ... : 2 n sigma g sqrt(pi T) in 2D, 4 n sigma^2 g sqrt(pi T) in 3D
    (unit mass)."""
    vol = math.pi / 4 * diameter**2 if d == 2 else math.pi / 6 * diameter**3
    n = phi / vol
    pref = 2.0 * n * diameter if d == 2 else 4.0 * n * diameter**2
    return pref * g_contact * math.sqrt(math.pi * temperature)


def maxwell_speed_density(d: int, s: np.ndarray, temperature: float) -> np.ndarray:
    """The Maxwell-Boltzmann density of the speed in d dimensions (unit mass)."""
    s = np.asarray(s, dtype=float)
    if d == 2:
        return s / temperature * np.exp(-s * s / (2 * temperature))
    return np.sqrt(2 / math.pi) * s * s / temperature**1.5 * np.exp(-s * s / (2 * temperature))


def microcanonical_speed_density(d: int, n: int, s: np.ndarray, temperature: float) -> np.ndarray:
    """The exact speed density of one of n particles with total momentum 0 and kinetic energy
    E = n d T / 2 (a periodic box): velocities uniform on the sphere of the d (n - 1)
    dimensional subspace, whose one-particle marginal is proportional to
    s^(d-1) (1 - n s^2 / (2 (n - 1) E))^((d (n - 1) - d - 2) / 2). Tends to Maxwell-Boltzmann as n grows."""
    s = np.asarray(s, dtype=float)
    energy = n * d * temperature / 2.0
    a = n / (2.0 * (n - 1) * energy)
    p = (d * (n - 1) - d - 2) / 2.0
    grid = np.linspace(0.0, 1.0 / math.sqrt(a), 20001)
    f = lambda x: np.where(a * x * x < 1.0, x ** (d - 1) * np.clip(1.0 - a * x * x, 0.0, None) ** p, 0.0)
    norm = np.trapezoid(f(grid), grid)
    return f(s) / norm


def extrapolate(ns: Sequence[float], zs: Sequence[float], errors: Sequence[float]) -> tuple[float, float, float]:
    """Z(N) = Z_inf + a / N through runs at two or more sizes, weighted least squares (weights
    1 / error^2): (Z_inf, its standard error, a). With two sizes the line goes through both."""
    x = 1.0 / np.asarray(ns, dtype=float)
    z, e = np.asarray(zs, dtype=float), np.asarray(errors, dtype=float)
    if len(x) < 2 or len(set(x.tolist())) < 2:
        raise ValueError("extrapolate needs runs at two different sizes at least")
    w = 1.0 / e ** 2
    a_mat = np.array([[w.sum(), (w * x).sum()], [(w * x).sum(), (w * x * x).sum()]])
    cov = np.linalg.inv(a_mat)
    zi, slope = cov @ np.array([(w * z).sum(), (w * x * z).sum()])
    return float(zi), float(math.sqrt(cov[0, 0])), float(slope)
