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
from dataclasses import dataclass
from typing import Any, Optional, Sequence

import numpy as np

from ._rdf import _pair_counts, compressibility_from_contact, contact_value, radial_distribution  # noqa: F401

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
