"""Observables of a run on either engine: pressure, temperature, collision rate, free time and
path, mean squared displacement, speed and pair-distance distributions, with block errors.

They are accumulated in C++ while the engine runs (``revcol/engine/observe.hpp`` has the
definitions), on request only, by one observer for both engines: the float engine, and the
lattice engine (``engine="lattice"``), whose exact integer state is converted to float units
at each velocity change (an observed lattice run still reverses bit for bit)::

    >>> import revcol
    >>> sim = revcol.Simulation.random(n=400, dim=2, phi=0.4, seed=3, mode="specular")
    >>> _ = sim.run(collisions=4000)            # equilibrate first
    >>> sim.observe(speed_bins=40)
    >>> _ = sim.run(collisions=40000)
    >>> o = sim.observation()
    >>> o.temperature.value > 0 and o.compressibility.error > 0
    True

Every average is over time, not over events: a segment of free flight weighs by its
duration. Errors are block averages (blocks of equal simulated time, ``o.blocks`` of them).
The observation is forward only: ``run_back`` ends it (its results stay readable).
:func:`radial_distribution` computes g(r) from frames (freud when installed, numpy otherwise).
"""
from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from typing import Any, Optional, Sequence

import numpy as np

from .progress import Bar

__all__ = ["Observing", "Estimate", "Profile", "Observation", "radial_distribution", "contact_value",
           "compressibility_from_contact", "report_lines", "OBSERVE_FIELDS", "helfand_increments", "helfand_viscosity",
           "self_diffusion"]

#: the arguments of ``Simulation.observe`` (and the fields of a scene's ``[observe]`` table)
OBSERVE_FIELDS = ("block_time", "min_blocks", "slab_axis", "slabs", "speed_bins", "speed_max", "pair_bins",
                  "pair_rmax")


class Observing:
    """The observation methods of both engines' simulations (``self._e`` is the binding's
    engine: ``Engine``, ``LatticeEngine`` or ``LatticeEngine3D``, which share the observer)."""

    _e: Any

    def observe(self, *, block_time: float = 0.0, min_blocks: int = 16, slabs: int = 0, slab_axis: int = 0,
                speed_bins: int = 0, speed_max: float = 0.0, pair_bins: int = 0, pair_rmax: float = 0.0) -> None:
        """Starts observing the forward run from now (replacing any earlier observation):
        pressure (collision virial and walls), temperature, collision rate, mean free time and
        path, mean squared displacement, all time-averaged with block errors; optionally
        ``slabs`` along ``slab_axis`` (density and temperature), a time-weighted speed histogram
        (``speed_bins`` over [0, ``speed_max``], default 5 v_rms) and, for 2-64 particles in a
        closed box, pair distances (``pair_bins`` over [0, ``pair_rmax``]). ``block_time``: the
        first blocks' length (0: D / v_rms; blocks merge as the run grows); errors use blocks
        merged down to [``min_blocks``, 2 ``min_blocks``). Observation is forward only:
        ``run_back`` ends it. A bad argument raises TypeError / ValueError naming it and
        changes nothing. Off (the default) it costs nothing."""
        self._e.observe(block_time, min_blocks, slab_axis, slabs, speed_bins, speed_max, pair_bins, pair_rmax)

    def observation(self) -> Optional["Observation"]:
        """The running or last observation's results (:class:`Observation`), or None if
        ``observe`` was never called. Up to the end of the last run call."""
        raw = self._e.observation()
        return None if raw is None else Observation(raw)

    @property
    def observing(self) -> bool:
        """Whether an observation is running (``run_back`` and ``stop_observing`` end it)."""
        return bool(self._e.observing)

    def stop_observing(self) -> None:
        """Ends the observation at the clock; ``observation()`` still reads it."""
        self._e.stop_observing()


@dataclass(frozen=True)
class Estimate:
    """A time average (from the whole observed time) and its standard error (block averages)."""

    value: float
    error: float

    def sigmas(self, reference: float) -> float:
        """(value - reference) / error: how many standard errors from ``reference``."""
        return (self.value - reference) / self.error if self.error > 0 else math.inf

    def __format__(self, spec: str) -> str:
        spec = spec or ".5g"
        return f"{self.value:{spec}} +- {self.error:.2g}"


@dataclass(frozen=True)
class Profile:
    """A histogram of time averages: ``edges`` (bins + 1), ``value`` and ``error`` per bin."""

    edges: np.ndarray
    value: np.ndarray
    error: np.ndarray

    @property
    def centres(self) -> np.ndarray:
        """The bins' midpoints."""
        return 0.5 * (self.edges[1:] + self.edges[:-1])


_SCALARS = ("temperature", "pressure_virial", "compressibility", "collision_rate", "mean_free_time",
            "mean_free_path", "virial_balance")
_PROFILES = ("slab_density", "slab_temperature", "speed", "pair_distance", "slab_velocity")
_COUNTS = ("dim", "n", "t_start", "t_end", "blocks", "block_time", "pair_collisions", "group_collisions",
           "particle_collisions", "wall_reflections")
_SPECIES = ("species_temperature", "species_pressure")  # a mixture's estimates per species
_KNOWN = set(_SCALARS) | set(_PROFILES) | set(_COUNTS) | set(_SPECIES) | {"pressure_wall"}


class Observation:
    """The results of ``Simulation.observe`` so far (``Simulation.observation()``).

    Scalars (:class:`Estimate`): ``temperature`` (K2 / (d N tau)), ``pressure_virial``
    ((K2 + W) / (d V tau), the pressure of a periodic box), ``compressibility`` (Z = 1 + W / K2),
    ``collision_rate`` (per particle), ``mean_free_time``, ``mean_free_path``,
    ``pressure_wall`` (a list per axis: the force per area on the faces, walled axes),
    ``virial_balance`` ((K2 + W + W_wall) / K2, near 0 in a closed box). Profiles
    (:class:`Profile` or None): ``slab_density``, ``slab_temperature``, ``speed`` (probability
    density of the speed), ``pair_distance`` (of a pair's distance). ``msd_time``, ``msd``: the
    mean squared displacement (unwrapped) at each block end; ``vacf``: the velocity
    autocorrelation (1/N) sum_i v_i(t_start) . v_i(t) at the same times; ``helfand``: the
    Helfand moment of the shear stress at the same times, an array (block ends, d (d - 1) / 2)
    of I_ab, a < b ((0, 1); (0, 1), (0, 2), (1, 2)), the integral of sum_i v_ia v_ib plus
    sum r_a Delta p_b over collisions (:func:`helfand_viscosity`). Both are empty for an
    observation resumed from a snapshot written before they existed. A mixture (the lattice
    engine with ``diameters``; all empty for one size), per species in ascending diameter:
    ``species_diameter``, ``species_count``, ``species_temperature`` and ``species_pressure``
    (lists of :class:`Estimate`: K2_s / (d N_s tau) and the partial pressure (K2_s + W_s) /
    (d V tau), W_s half of each pair's virial to each member's species; their sum is
    ``pressure_virial``), ``species_msd`` (block ends, S) at ``msd_time``. A sheared gas (the
    lattice engine with ``shear_rate``; docs/shear.md): ``shear_rate``, ``shear_stress``
    (:class:`Estimate` of P_yx, the x momentum carried across planes of constant y, kinetic plus
    collisional, from the peculiar velocities u = v - rate (y - L_1 / 2) e_0: the peculiar energy
    changes by -rate V P_yx dt), ``viscosity`` (-P_yx / rate) and, with slabs along axis 1,
    ``slab_velocity`` (the mean flow velocity per slab); the temperature, the speeds and the
    kinetic sums are then the peculiar ones (``helfand`` keeps r_x Delta p_y, its equilibrium
    formula does not apply to a driven gas). Without shear ``shear_rate`` is 0 and the other three
    None. Any other entry the C++
    observer reports appears as an attribute of its own name. Counts: ``pair_collisions``,
    ``group_collisions``, ``particle_collisions``, ``wall_reflections``; ``t_start``, ``t_end``,
    ``blocks``, ``block_time``.
    """

    dim: int
    n: int
    t_start: float
    t_end: float
    blocks: int
    block_time: float
    pair_collisions: int
    group_collisions: int
    particle_collisions: int
    wall_reflections: int
    temperature: Estimate
    pressure_virial: Estimate
    compressibility: Estimate
    collision_rate: Estimate
    mean_free_time: Estimate
    mean_free_path: Estimate
    virial_balance: Estimate
    slab_density: Optional[Profile]
    slab_temperature: Optional[Profile]
    speed: Optional[Profile]
    pair_distance: Optional[Profile]
    slab_velocity: Optional[Profile]
    shear_rate: float = 0.0
    shear_stress: Optional[Estimate] = None
    viscosity: Optional[Estimate] = None

    def __init__(self, raw: dict[str, Any]):
        self.raw = raw
        for key in _COUNTS:
            setattr(self, key, raw[key])
        for key in _SCALARS:
            setattr(self, key, Estimate(float(raw[key]["value"]), float(raw[key]["error"])))
        self.pressure_wall = [Estimate(float(e["value"]), float(e["error"])) for e in raw["pressure_wall"]]
        for key in _SPECIES:
            setattr(self, key, [Estimate(float(e["value"]), float(e["error"])) for e in raw.get(key, [])])
        for key in _PROFILES:
            p = raw.get(key)  # (slab_velocity: absent from observations saved before it)
            setattr(self, key, None if p is None else Profile(np.asarray(p["edges"]), np.asarray(p["value"]),
                                                              np.asarray(p["error"])))
        # every other entry as it comes (an observable added in C++ needs no change here):
        # {"value", "error"} an Estimate, sequences numpy arrays (msd_time, msd, vacf, ...)
        self._extra = [key for key in raw if key not in _KNOWN]
        for key in self._extra:
            val = raw[key]
            if isinstance(val, dict) and set(val) == {"value", "error"}:
                setattr(self, key, Estimate(float(val["value"]), float(val["error"])))
            elif isinstance(val, (list, tuple, np.ndarray)):
                setattr(self, key, np.asarray(val))
            else:
                setattr(self, key, val)

    @property
    def duration(self) -> float:
        """The observed simulated time."""
        return self.t_end - self.t_start

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able values: scalars as [value, error], profiles as lists."""
        out: dict[str, Any] = {k: getattr(self, k) for k in _COUNTS}
        for key in _SCALARS:
            e = getattr(self, key)
            out[key] = [e.value, e.error]
        out["pressure_wall"] = [[e.value, e.error] for e in self.pressure_wall]
        for key in _SPECIES:
            out[key] = [[e.value, e.error] for e in getattr(self, key)]
        for key in _PROFILES:
            p = getattr(self, key)
            out[key] = None if p is None else {"edges": p.edges.tolist(), "value": p.value.tolist(),
                                               "error": p.error.tolist()}
        for key in self._extra:  # as they came: estimates as [value, error], arrays as lists
            val = getattr(self, key)
            out[key] = ([val.value, val.error] if isinstance(val, Estimate)
                        else val.tolist() if isinstance(val, np.ndarray) else val)
        return out

    def lines(self) -> list[str]:
        """The scalars as report lines."""
        return report_lines(self.to_dict())

    def __repr__(self) -> str:
        return (f"Observation(t={self.t_start:.6g}..{self.t_end:.6g}, T={self.temperature}, "
                f"Z={self.compressibility}, blocks={self.blocks})")


def report_lines(d: dict[str, Any]) -> list[str]:
    """Report lines of an observation's ``to_dict()`` (``revcol run`` prints them)."""
    errors = (f"errors from {d['blocks']} blocks of {d['block_time']:.3g}" if d["blocks"] >= 2 else
              "no errors: fewer than 2 complete blocks (run longer)")
    rows = [f"  observed         t = {d['t_start']:.6g} .. {d['t_end']:.6g}, {d['particle_collisions']:,} "
            f"particle collisions, {errors}"]
    closed = any(v != 0.0 for v, _ in d["pressure_wall"]) and all(v != 0.0 for v, _ in d["pressure_wall"])
    for key in _SCALARS:
        if key == "virial_balance" and not closed:  # defined for a closed box only
            continue
        v, e = d[key]
        rows.append(f"  {key:<16} {v:.5g}" + (f" +- {e:.2g}" if d["blocks"] >= 2 else ""))
    for k, (v, e) in enumerate(d["pressure_wall"]):
        if v != 0.0:
            rows.append(f"  pressure_wall[{k}] {v:.5g}" + (f" +- {e:.2g}" if d["blocks"] >= 2 else ""))
    for key in ("shear_stress", "viscosity"):  # a sheared gas's
        if key in d:
            v, e = d[key]
            rows.append(f"  {key:<16} {v:.5g}" + (f" +- {e:.2g}" if d["blocks"] >= 2 else "")
                        + (f" at shear rate {d['shear_rate']:.5g}" if key == "viscosity" else ""))
    if d["msd"]:
        rows.append(f"  msd              {d['msd'][-1]:.5g} at t = {d['msd_time'][-1]:.5g} after the start"
                    + (" (unwrapped through the sheared images: the flow's advection included)" if "shear_rate" in d else ""))
    pm = "+-" if d["blocks"] >= 2 else "~"
    masses = list(d.get("species_mass") or [])
    for u, diam in enumerate(d.get("species_diameter") or []):
        (t, te), (p, pe) = d["species_temperature"][u], d["species_pressure"][u]
        msd = f", msd {d['species_msd'][-1][u]:.5g}" if len(d.get("species_msd") or []) else ""
        m = f" m={masses[u]:.4g}" if any(q != 1.0 for q in masses) else ""
        rows.append(f"  species d={diam:.4g}{m} ({d['species_count'][u]}): T {t:.5g} {pm} {te:.2g}, partial pressure "
                    f"{p:.5g} {pm} {pe:.2g}{msd}")
    return rows


def radial_distribution(frames, box: Sequence[float], bins: int = 100, r_max: Optional[float] = None,
                        periodic: Optional[Sequence[bool]] = None, use_freud: Optional[bool] = None,
                        diameter: Optional[float] = None, progress: Optional[bool] = None):
    """g(r) averaged over frames (an array (F, n, d) or one frame (n, d)).

    Periodic box (``periodic`` None or all True): freud (``freud.density.RDF``) when installed
    and ``use_freud`` is not False, otherwise numpy (minimum image, pair distances by rows,
    normalized by the ideal gas's shell counts at the same density). Both normalize by the
    other particles' density (n - 1) / V (freud's ``normalization_mode="finite_size"``), so
    they agree up to the pairs that float32 positions in freud move across a bin edge
    (``test_observe``). ``r_max`` at most L / 2 (default: 0.5 min L).

    Walled axes (``periodic[k]`` False; numpy only, freud's normalization is periodic): the
    centres lie in [D/2, L - D/2] on those axes (``diameter`` D is then required; 0 for
    points anywhere in [0, L]), no minimum image there, and each reference particle's ideal
    count in a shell is (n - 1) / V' times the part of the shell inside that region (V' its
    volume), exactly: the full shell less the caps beyond the walls within r, plus the parts
    beyond two (and three) walls at once (closed forms; in 3D those are one-dimensional
    integrals done by 24-point Gauss-Legendre, relative error below 1e-8). So an ideal gas in a
    walled box has g = 1 at every r, not the periodic formula's dip near r_max. ``r_max`` at
    most half the region's shortest side (each axis cuts a shell at one wall at most).
    ``progress``: a bar over the frames (None: on a terminal, for 50 frames or more).
    Returns (r centres, g)."""
    x = np.asarray(frames, dtype=float)
    if x.ndim == 2:
        x = x[None]
    if x.ndim != 3 or x.shape[2] not in (2, 3):
        raise ValueError(f"frames must have shape (F, n, d) with d = 2 or 3, got {x.shape}")
    d = x.shape[2]
    L = np.asarray(box, dtype=float)
    if L.shape != (d,):
        raise ValueError(f"box needs {d} lengths, got {L.shape}")
    walls = np.zeros(d, dtype=bool) if periodic is None else ~np.asarray(periodic, dtype=bool)
    if walls.shape != (d,):
        raise ValueError(f"periodic needs {d} flags, got {walls.shape}")
    if isinstance(bins, bool) or not isinstance(bins, int) or bins < 1:
        raise TypeError(f"bins must be a positive integer, got {bins!r}")
    if walls.any():
        if diameter is None or not 0.0 <= float(diameter) < float(L[walls].min()):
            raise ValueError("a walled box needs the particles' diameter (0 <= diameter < L on walled axes): "
                             f"their centres lie in [D/2, L - D/2] there; got {diameter!r}")
        if use_freud:
            raise ValueError("freud's g(r) is for a periodic box; a walled box uses numpy (use_freud=None or False)")
        half = float(diameter) / 2.0
        x = x - np.where(walls, half, 0.0)  # the centres' region [0, L'] on walled axes
        L = L - np.where(walls, 2.0 * half, 0.0)
    limit = 0.5 * float(L.min())
    r_max = limit if r_max is None else float(r_max)
    if not 0 < r_max <= limit + 1e-12:
        raise ValueError(f"r_max must be in (0, {'L' if not walls.any() else 'L - D'}/2 = {limit:g}], got {r_max}")
    if progress is None:
        progress = sys.stdout.isatty() and x.shape[0] >= 50
    bar = Bar(progress, float(x.shape[0]), "g(r)", "frame")
    try:
        return _rdf(x, L, bins, r_max, walls, use_freud, bar)
    finally:
        bar.close()


def _rdf(x: np.ndarray, L: np.ndarray, bins: int, r_max: float, walls: np.ndarray, use_freud, bar):
    d = x.shape[2]
    if walls.any():
        return _rdf_numpy(x, L, bins, r_max, walls, bar)
    freud = None
    if use_freud is not False:
        try:
            import freud  # type: ignore
        except ImportError:
            if use_freud:
                raise
    if freud is not None:
        fbox = freud.box.Box.from_box(list(L) + ([0.0] if d == 2 else []))
        rdf = freud.density.RDF(bins=bins, r_max=r_max, normalization_mode="finite_size")
        for k, f in enumerate(x):
            pts = np.zeros((f.shape[0], 3))
            pts[:, :d] = f - 0.5 * L
            rdf.compute((fbox, fbox.wrap(pts)), reset=False)
            bar.to(k + 1)
        return np.asarray(rdf.bin_centers), np.asarray(rdf.rdf)
    return _rdf_numpy(x, L, bins, r_max, walls, bar)


def contact_value(r, g, diameter: float = 1.0, width: float = 0.2, order: int = 2) -> float:
    """g(D+), the radial distribution at contact: a least-squares polynomial of ``order`` in
    r - D through the bins whose centres lie in (D, D + ``width``], evaluated at r = D."""
    r, g = np.asarray(r, dtype=float), np.asarray(g, dtype=float)
    sel = (r > diameter) & (r <= diameter + width)
    if np.count_nonzero(sel) < order + 2:
        raise ValueError(f"contact_value needs at least {order + 2} bins in (D, D + width]; "
                         f"got {np.count_nonzero(sel)} (finer bins or a larger width)")
    return float(np.polyval(np.polyfit(r[sel] - diameter, g[sel], order), 0.0))


def compressibility_from_contact(g_contact: float, packing_fraction: float, dim: int) -> float:
    """Z = P / (n kT) of hard spheres from the contact value: 1 + 2^(d-1) phi g(D+) (the
    virial theorem: 1D 1 + phi g, 2D 1 + 2 phi g, 3D 1 + 4 phi g)."""
    if dim not in (1, 2, 3):
        raise ValueError(f"dim must be 1, 2 or 3, got {dim}")
    return 1.0 + 2.0 ** (dim - 1) * float(packing_fraction) * float(g_contact)


def _pair_counts(f: np.ndarray, L: np.ndarray, edges: np.ndarray, walls: np.ndarray) -> np.ndarray:
    """Ordered pairs (i != j) of one frame per distance bin (minimum image on periodic axes).
    Each unordered pair once (rows lo..hi against lo..n, above the diagonal), the distances
    within the last edge only through the histogram: the counts of every ordered pair, in 0.4 of
    the time (issue 58: 624 frames of 1000 walled disks had taken 90 s)."""
    n = f.shape[0]
    r_max = float(edges[-1])
    counts = np.zeros(len(edges) - 1, dtype=np.int64)
    rows = max(1, 2_000_000 // max(n, 1))
    wrap = np.where(walls, 0.0, 1.0)
    for lo in range(0, n, rows):
        hi = min(n, lo + rows)
        dr = f[lo:hi, None, :] - f[None, lo:, :]
        if not walls.all():
            dr -= wrap * L * np.round(dr / L)
        r2 = np.einsum("ijk,ijk->ij", dr, dr)
        keep = r2 <= r_max * r_max
        keep[:, :hi - lo] &= np.triu(np.ones((hi - lo, hi - lo), dtype=bool), 1)  # j > i
        counts += np.histogram(np.sqrt(r2[keep]), bins=edges)[0]
    return 2 * counts


def _rdf_numpy(x: np.ndarray, L: np.ndarray, bins: int, r_max: float, walls: np.ndarray, bar=None):
    F, n, d = x.shape
    edges = np.linspace(0.0, r_max, bins + 1)
    counts = np.zeros(bins, dtype=np.int64)
    inside = np.zeros(bins + 1)  # sum over reference particles of the ball volume inside the region
    for k, f in enumerate(x):
        counts += _pair_counts(f, L, edges, walls)
        inside += _ball_inside(f, L, walls, edges).sum(axis=0) if walls.any() else n * _ball(edges, d)
        if bar is not None:
            bar.to(k + 1)
    rho = (n - 1) / float(np.prod(L))  # the other particles' density: g -> 1 at large r for any n
    ideal = rho * np.diff(inside)  # ordered pairs: each pair counted from both ends
    return 0.5 * (edges[1:] + edges[:-1]), counts / ideal


def _ball(r, d: int):
    """The volume of the d-ball of radius r (d = 2, 3)."""
    r = np.asarray(r, dtype=float)
    return math.pi * r ** 2 if d == 2 else 4.0 / 3.0 * math.pi * r ** 3


def _corner2(p, q, rho):
    """The area of {u1 > p, u2 > q, |u| < rho} (p, q >= 0): the integral over u1 in [p, m],
    m = sqrt(rho^2 - q^2), of sqrt(rho^2 - u1^2) - q; 0 when p^2 + q^2 >= rho^2."""
    p, q, rho = np.broadcast_arrays(np.asarray(p, float), np.asarray(q, float), np.asarray(rho, float))
    r2 = rho * rho
    live = p * p + q * q < r2
    m = np.sqrt(np.maximum(r2 - q * q, 0.0))
    safe = np.where(live, rho, 1.0)

    def prim(u):  # an antiderivative of sqrt(rho^2 - u^2)
        return 0.5 * (u * np.sqrt(np.maximum(r2 - u * u, 0.0)) + r2 * np.arcsin(np.clip(u / safe, -1.0, 1.0)))

    return np.where(live, prim(m) - prim(p) - q * (m - p), 0.0)


_GL_X, _GL_W = np.polynomial.legendre.leggauss(24)


def _beyond_two_3d(p, q, r, s=None):
    """The volume of {u1 > p, u2 > q, |u| < r} in 3D (and u3 > s when s is given): the
    integral over u3 of _corner2 at radius sqrt(r^2 - u3^2), over |u3| < zm (u3 in [s, zm]),
    zm = sqrt(r^2 - p^2 - q^2); u3 = zm sin(theta) smooths the ends for Gauss-Legendre."""
    p, q, r = np.broadcast_arrays(np.asarray(p, float), np.asarray(q, float), np.asarray(r, float))
    zm = np.sqrt(np.maximum(r * r - p * p - q * q, 0.0))
    lo = -0.5 * math.pi * np.ones_like(zm) if s is None else np.arcsin(
        np.clip(np.asarray(s, float) / np.where(zm > 0, zm, 1.0), -1.0, 1.0))
    lo = np.where(zm > 0, lo, 0.5 * math.pi)
    hi = 0.5 * math.pi
    th = lo[..., None] + (hi - lo)[..., None] * 0.5 * (_GL_X + 1.0)
    z = zm[..., None] * np.sin(th)
    rho = np.sqrt(np.maximum(r[..., None] ** 2 - z * z, 0.0))
    f = _corner2(p[..., None], q[..., None], rho) * zm[..., None] * np.cos(th)
    return (f * _GL_W).sum(-1) * 0.5 * (hi - lo)


def _ball_inside(f: np.ndarray, L: np.ndarray, walls: np.ndarray, r: np.ndarray) -> np.ndarray:
    """(n, len(r)): the volume of each particle's ball of radius r inside the region [0, L]
    on walled axes (r <= L / 2: one wall per axis at most), by inclusion and exclusion of
    the parts beyond the nearest wall of each walled axis."""
    n, d = f.shape
    h = np.where(walls, np.minimum(f, L - f), np.inf)  # distance to the nearest wall (inf: periodic)
    rr = np.broadcast_to(r, (n, len(r)))
    out = np.broadcast_to(_ball(r, d), (n, len(r))).copy()
    hk = [np.clip(h[:, k, None], 0.0, None) for k in range(d)]
    for k in range(d):  # one wall: a segment (2D) or a cap (3D)
        c = np.minimum(hk[k], rr)
        if d == 2:
            out -= np.where(hk[k] < rr, rr * rr * np.arccos(np.clip(c / np.where(rr > 0, rr, 1.0), -1.0, 1.0))
                            - c * np.sqrt(np.maximum(rr * rr - c * c, 0.0)), 0.0)
        else:
            out -= np.where(hk[k] < rr, math.pi * (rr - c) ** 2 * (2.0 * rr + c) / 3.0, 0.0)
    for k in range(d):  # two walls at once (added back)
        for j in range(k + 1, d):
            near = (hk[k] < rr) & (hk[j] < rr)
            if not near.any():
                continue
            pk, pj = np.where(near, hk[k], rr), np.where(near, hk[j], rr)
            twice = _corner2(pk, pj, rr) if d == 2 else _beyond_two_3d(pk, pj, rr)
            out += np.where(near, twice, 0.0)
    if d == 3:  # three walls at once (taken away again)
        near = (hk[0] < rr) & (hk[1] < rr) & (hk[2] < rr)
        if near.any():
            p0, p1, p2 = (np.where(near, hk[k], rr) for k in range(3))
            out -= np.where(near, _beyond_two_3d(p0, p1, rr, s=p2), 0.0)
    return out


# ------------------------------------------------------------------ transport from block ends
def _as_list(observations) -> list:
    """One observation (anything with ``msd_time``) or a sequence of them, as a list."""
    return [observations] if hasattr(observations, "msd_time") else list(observations)


def _records(observations, key: str) -> tuple[float, list[np.ndarray]]:
    """(h, rows): each observation's record ``key`` (msd or helfand) at the block ends on its
    coarsest spacing h (blocks merge as a run grows, so early ends are finer; every end lies
    on the later grids), with the start (t = 0, value 0) prepended; one h for all."""
    obs = _as_list(observations)
    if not obs:
        raise ValueError("no observations")
    hs, rows = [], []
    for o in obs:
        t, y = np.asarray(o.msd_time, dtype=float), np.asarray(getattr(o, key), dtype=float)
        y = y.reshape(len(y), -1)
        if len(t) < 3 or len(y) != len(t):
            raise ValueError(f"an observation has {len(y)} {key} points at {len(t)} block ends; "
                             "need 3 or more of each (run longer, or a snapshot from before it existed)")
        h = t[-1] - t[-2]
        on = np.abs(t / h - np.round(t / h)) < 1e-6
        hs.append(h)
        rows.append(np.vstack([np.zeros((1, y.shape[1])), y[on]]))
    if max(hs) > min(hs) * (1 + 1e-6):
        raise ValueError(f"the observations' block spacings differ ({min(hs):.6g} .. {max(hs):.6g}): "
                         "observe every window with the same block_time and length")
    return float(hs[0]), rows


def _msi(rows: list[np.ndarray], kmax: int) -> tuple[np.ndarray, np.ndarray]:
    """Sums of squared increments per lag 1..kmax and component over every origin, and counts."""
    c = rows[0].shape[1]
    sq, num = np.zeros((kmax, c)), np.zeros(kmax)
    for y in rows:
        for k in range(1, min(kmax, len(y) - 1) + 1):
            d = y[k:] - y[:-k]
            sq[k - 1] += (d * d).sum(axis=0)
            num[k - 1] += len(d)
    return sq, num


def helfand_increments(observations, lag_max: float) -> tuple[np.ndarray, np.ndarray]:
    """The mean-square increment <(I_ab(t + tau) - I_ab(t))^2> of the Helfand moment over all
    time origins at block ends (of one observation, or pooled over several windows of equal
    block time): (lags tau up to ``lag_max``, an array (lags, components))."""
    h, rows = _records(observations, "helfand")
    kmax = int(np.floor(lag_max / h + 1e-9))
    if kmax < 1:
        raise ValueError(f"lag_max = {lag_max} is shorter than the block spacing {h:.6g}")
    sq, num = _msi(rows, kmax)
    ok = num > 0
    return h * np.arange(1, kmax + 1)[ok], sq[ok] / num[ok, None]


def helfand_viscosity(observations, volume: float, lag_min: float, lag_max: float,
                      temperature: Optional[float] = None, batches: int = 8) -> Estimate:
    """Shear viscosity by the Einstein-Helfand method, from the Helfand moments an observation
    records at its block ends (``Observation.helfand``; unit masses, k_B = 1):

        eta = lim_{tau -> inf} <(I_ab(t + tau) - I_ab(t))^2> / (2 V k T tau),

    I_ab(t) = int_0^t sum_i v_ia v_ib dt' + sum_{collisions up to t} r_a Delta p_b (an
    extensive moment, hence 1/V). The mean-square increment is averaged over every time origin
    at a block end and, per component, fitted by a straight line (least squares, with an
    intercept: the stress correlation's decay leaves an offset) over the lags in [``lag_min``,
    ``lag_max``], which must lie where it is linear (the stress autocorrelation decayed: a few
    time units in sqrt(m D^2 / kT) for hard spheres up to packing 0.45, longer nearer
    freezing); eta_ab = slope / (2 V T), and the value is the mean over the components a < b.

    ``observations``: one observation, or several windows of one run or of several runs (each
    started by ``observe(block_time=...)`` with the same block time; increments are taken
    within a window only). Blocks merge as a run grows (the spacing doubles); only the ends on
    the coarsest spacing are used, so observe in windows of fewer than 256 blocks to keep the
    spacing. ``temperature``: default the observations' mean. ``volume``: the box's.

    Error: the windows in ``batches`` contiguous groups (one observation: its record cut into
    ``batches`` pieces), eta of each group from its own increments (mean over components), and
    the standard error of the group values (s / sqrt(groups)); nan with fewer than 2 groups.
    Periodic boxes only: walls exchange momentum with the gas and their impulses do not enter
    I (the observer records the moment in a closed box too, but this formula does not apply)."""
    obs = _as_list(observations)
    if temperature is None:
        temperature = float(np.mean([o.temperature.value for o in obs]))
    if not 0.0 < lag_min < lag_max:
        raise ValueError(f"need 0 < lag_min < lag_max, got {lag_min}, {lag_max}")
    h, rows = _records(obs, "helfand")
    kmax = int(np.floor(lag_max / h + 1e-9))
    lags = h * np.arange(1, kmax + 1)
    fit = lags >= lag_min - 1e-9 * h
    if np.count_nonzero(fit) < 2:
        raise ValueError(f"fewer than 2 lags in [{lag_min}, {lag_max}] at a block spacing of {h:.6g}")
    scale = 2.0 * float(volume) * float(temperature)

    def eta(group: list[np.ndarray]) -> float:
        sq, num = _msi(group, kmax)
        use = fit & (num > 0)
        if np.count_nonzero(use) < 2:
            raise ValueError("a window is shorter than lag_max: longer windows, or fewer batches")
        m = sq[use] / num[use, None]
        return float(np.mean(np.polyfit(lags[use], m, 1)[0])) / scale

    if len(rows) == 1 and batches > 1:  # one record: cut it into pieces (increments within a piece)
        cuts = np.array_split(np.arange(len(rows[0])), batches)
        groups = [[rows[0][c[0]:c[-1] + 2]] for c in cuts if len(c)]
    else:
        groups = [[rows[u] for u in idx] for idx in np.array_split(np.arange(len(rows)), min(batches, len(rows)))]
    vals = np.array([eta(g) for g in groups])
    err = float(vals.std(ddof=1) / np.sqrt(len(vals))) if len(vals) > 1 else math.nan
    return Estimate(eta(rows), err)


def self_diffusion(observations, start: float = 0.5, batches: Optional[int] = None) -> Estimate:
    """Self-diffusion D from the mean squared displacement an observation records at its block
    ends from its own start (one origin, averaged over the particles): D = slope / (2 d) of a
    least-squares line through the points from ``start`` x its length to its end. Several
    observations (windows of one run, each started by ``observe``, or several runs): the mean
    of their D, and its standard error from ``batches`` contiguous groups of them (default one
    per observation): s / sqrt(groups) of the group means (nan for one group)."""
    obs = _as_list(observations)
    vals = []
    for o in obs:
        t, m = np.asarray(o.msd_time, dtype=float), np.asarray(o.msd, dtype=float)
        sel = t >= start * t[-1]
        if np.count_nonzero(sel) < 2:
            raise ValueError("fewer than 2 MSD points in the fitted part: run longer")
        vals.append(np.polyfit(t[sel], m[sel], 1)[0] / (2.0 * o.dim))
    v = np.asarray(vals)
    g = np.array([q.mean() for q in np.array_split(v, min(batches or len(v), len(v)))])
    return Estimate(float(v.mean()), float(g.std(ddof=1) / np.sqrt(len(g))) if len(g) > 1 else math.nan)
