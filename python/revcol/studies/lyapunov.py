"""The largest Lyapunov exponent of the specular gas on both engines, by renormalization.

Two copies of one gas a distance d0 apart (positions in diameters and velocities in sqrt(kT/m),
combined), the copy put back at d0 along its current difference every dt (Benettin et al.): the
mean growth rate is the largest exponent. On the lattice engine the copy is rebuilt from the
reference's snapshot with integer differences; on the float engine it is a new Simulation. The
lattice's specular map carries a deterministic error of order 2^-T of the relative velocity per
collision (its normal is the column's, within one tick's travel of the contact's), which the two
copies do not share: below d0 ~ 1e-5 diameters it grows the difference as much as the
instability does, so the exponent is measured against d0 (``lyapunov_scan``). Used by
:mod:`revcol.studies.echo` (``--d0``); docs/specular.md.
"""
from __future__ import annotations

import math
import time
from typing import Sequence

import numpy as np

from ..engine import Simulation
from ..lattice import LatticeSimulation, LatticeSimulation3D

__all__ = ["lattice_gas", "Metric", "benettin", "lyapunov_scan", "scan_summary", "LatticePair", "FloatPair"]


def lattice_gas(dim: int, n: int, phi: float, seed: int, mode: str = "specular", boundary: str = "periodic"):
    """A random lattice gas in ``mode`` (the float engine's random start, quantized once)."""
    cls = LatticeSimulation3D if dim == 3 else LatticeSimulation
    s = cls.random(n, phi=phi, seed=seed, boundary=boundary)
    snap = s.snapshot()
    snap["mode"] = mode
    return cls.from_snapshot(snap)


class Metric:
    """Distances between two states of one gas in diameters and sqrt(kT/m) (nearest image)."""

    def __init__(self, sim):
        u = sim.units
        self.L = np.asarray(u["L"], dtype=np.float64)
        self.periodic = ~np.asarray(u["wall"], dtype=bool)
        self.sigma = float(u["sigma"])
        self.vunit = float(u["length_unit"]) / float(u["tick"])  # float speed of one lattice unit per tick

    def lattice(self, xa, va, xb, vb) -> tuple:
        """(dx, dv) of two integer states."""
        d = (np.asarray(xa, dtype=np.int64) - np.asarray(xb, dtype=np.int64)).astype(np.float64)
        d = np.where(self.periodic, d - np.round(d / self.L) * self.L, d)
        dv = (np.asarray(va, dtype=np.int64) - np.asarray(vb, dtype=np.int64)).astype(np.float64)
        return float(np.sqrt((d * d).sum()) / self.sigma), float(np.sqrt((dv * dv).sum()) * self.vunit)


class LatticePair:
    """A reference lattice gas and a perturbed copy, for the Benettin renormalization."""

    def __init__(self, sim):
        self.ref, self.metric = sim, Metric(sim)
        self.L = np.asarray(sim.units["L"], dtype=np.int64)
        self.pert = None

    def diff(self) -> tuple:
        """(dx in diameters, dv in sqrt(kT/m)) and the integer differences (nearest image)."""
        xr, vr = self.ref.lattice_positions, self.ref.lattice_velocities
        xp, vp = self.pert.lattice_positions, self.pert.lattice_velocities
        d = xp - xr
        per = self.metric.periodic
        d[:, per] -= np.round(d[:, per] / self.L[per]).astype(np.int64) * self.L[per]
        return d, vp - vr

    def distance(self) -> float:
        d, dv = self.diff()
        return math.hypot(float(np.sqrt((d.astype(float) ** 2).sum())) / self.metric.sigma,
                          float(np.sqrt((dv.astype(float) ** 2).sum())) * self.metric.vunit)

    def place(self, dx, dv) -> bool:
        """The perturbed copy at the reference's state plus (dx, dv) (integers); False if refused
        (a pair of the reference within the perturbation of contact: try again later)."""
        snap = self.ref.snapshot()
        x = np.asarray(snap["x"], dtype=np.int64) + dx
        per = self.metric.periodic
        x[:, per] %= self.L[per]
        snap["x"], snap["v"] = x, np.asarray(snap["v"], dtype=np.int64) + dv
        try:
            self.pert = type(self.ref).from_snapshot(snap)
        except ValueError:
            return False
        return True

    def run(self, t: float) -> None:
        self.ref.run(time=t)
        self.pert.run(time=t)


class FloatPair:
    """A reference float specular gas and a perturbed copy (each new copy's clock starts at 0)."""

    def __init__(self, x, v, box, boundary):
        self.box, self.boundary = np.asarray(box, dtype=float), list(boundary)
        self.periodic = np.array([b == "periodic" for b in self.boundary])
        self.ref = Simulation(x, v, self.box, boundary=self.boundary, mode="specular")
        self.pert, self.offset = None, 0.0

    def diff(self) -> tuple:
        d = np.asarray(self.pert.positions) - np.asarray(self.ref.positions)
        d = np.where(self.periodic, d - np.round(d / self.box) * self.box, d)
        return d, np.asarray(self.pert.velocities) - np.asarray(self.ref.velocities)

    def distance(self) -> float:
        d, dv = self.diff()
        return math.hypot(float(np.sqrt((d * d).sum())), float(np.sqrt((dv * dv).sum())))

    def place(self, dx, dv) -> bool:
        x = np.asarray(self.ref.positions) + dx
        x = np.where(self.periodic, np.mod(x, self.box), x)
        try:
            self.pert = Simulation(x, np.asarray(self.ref.velocities) + dv, self.box, boundary=self.boundary,
                                   mode="specular")
        except ValueError:
            return False
        self.offset = self.ref.time
        return True

    def run(self, t: float) -> None:
        self.ref.run(time=t)
        self.pert.run(time=t - self.offset)


def benettin(pair, t_total: float, dt: float, d0: float = 1e-6, skip: float = 0.2, blocks: int = 10,
             integer: bool = False, jump: float = 5.0) -> dict:
    """The largest Lyapunov exponent by renormalization (Benettin et al.): the perturbed copy is
    put back at distance d0 from the reference along its current difference every dt, and lambda
    is the mean of ln(d / d0) / dt over the run after the first ``skip`` of it (the perturbation
    first turns into the most unstable direction); its error is the standard error of
    ``blocks`` block means. Distances combine positions (diameters) and velocities (sqrt(kT/m)).
    On the lattice (``integer``) d0 = 1e-6 is far above the resolution (2^-T diameters)."""
    rng = np.random.default_rng(12345)
    n, dim = pair.ref.n, pair.ref.dim
    t = pair.ref.time
    sigma = pair.metric.sigma if integer else 1.0
    for _ in range(20):  # a random direction; another if it moves a centre into a near-touching neighbour
        u = rng.normal(size=(n, dim))
        first = u / np.sqrt((u * u).sum()) * d0
        if integer:
            placed = pair.place(np.round(first * sigma).astype(np.int64), np.zeros((n, dim), dtype=np.int64))
        else:
            placed = pair.place(first, np.zeros((n, dim)))
        if placed:
            break
    else:
        raise RuntimeError(f"benettin: 20 first perturbations of size {d0} were refused")
    logs, steps, start, refused = [], int(round(t_total / dt)), pair.distance(), 0
    jumps = []  # (time, ln growth) of the steps beyond e^jump (see lambda_linear)
    for k in range(steps):
        t += dt
        pair.run(t)
        d = pair.distance()
        logs.append(math.log(d / start))
        if logs[-1] > jump:
            jumps.append((t, logs[-1]))
        dx, dv = pair.diff()
        f = d0 / d
        if integer:
            ok = pair.place(np.round(dx * f).astype(np.int64), np.round(dv * f).astype(np.int64))
        else:
            ok = pair.place(dx * f, dv * f)
        start = pair.distance() if ok else d  # refused: the copy runs on from where it is
        refused += 0 if ok else 1
    used = np.asarray(logs[int(skip * len(logs)):]) / dt
    means = [float(b.mean()) for b in np.array_split(used, blocks)]
    # linear steps only: a step that grew the perturbation by more than e^jump is a collision one
    # copy had and the other missed (a grazing one, or on the lattice one whose normal moved by
    # the map's error), not the instability's linear growth; lambda_linear leaves them out
    lin = used[used * dt <= jump]
    lmeans = [float(b.mean()) for b in np.array_split(lin, blocks)]
    return {"lambda": float(used.mean()), "error": float(np.std(means, ddof=1) / math.sqrt(blocks)),
            "lambda_linear": float(lin.mean()), "error_linear": float(np.std(lmeans, ddof=1) / math.sqrt(blocks)),
            "steps_left_out": int(len(used) - len(lin)),
            "renormalizations": steps, "refused": refused, "jumps": jumps[:50], "n_jumps": len(jumps), "dt": dt,
            "d0": d0, "time": t_total}


def lyapunov_scan(dim: int, phi: float, n: int, seed: int, d0s: Sequence[float], t_mft: float = 60.0,
                  dt_mft: float = 0.25, warm: float = 5.0) -> dict:
    """Benettin's lambda on the lattice specular gas and on the float specular gas from the same
    start, for each perturbation size d0: the lattice's map carries a deterministic error of
    order 2^-T of the relative velocity per collision (the column's normal is within one tick's
    travel of the contact's), so below some d0 that error, not the instability, grows the
    perturbation; above it both engines must give one lambda until d0 is large enough to change
    which collisions happen."""
    base = lattice_gas(dim, n, phi, seed)
    base.run(time=warm)
    c0, t0 = base.collisions, base.time
    probe = type(base).from_snapshot(base.snapshot())
    probe.run(collisions=20 * n)
    rate = 2.0 * (probe.collisions - c0) / (n * (probe.time - t0))
    snap = base.snapshot()
    rows = []
    for d0 in d0s:
        w0 = time.perf_counter()
        lat = benettin(LatticePair(type(base).from_snapshot(snap)), t_mft / rate, dt_mft / rate, d0=d0, integer=True)
        s2 = type(base).from_snapshot(snap)
        flt = benettin(FloatPair(np.asarray(s2.positions), np.asarray(s2.velocities), s2.box, s2.boundary),
                       t_mft / rate, dt_mft / rate, d0=d0)
        rows.append({"d0": d0, "lattice": lat, "float": flt, "seconds": time.perf_counter() - w0,
                     "sd": abs(lat["lambda"] - flt["lambda"]) / math.hypot(lat["error"], flt["error"]),
                     "sd_linear": abs(lat["lambda_linear"] - flt["lambda_linear"]) / math.hypot(lat["error_linear"],
                                                                                              flt["error_linear"])})
    return {"dim": dim, "phi": phi, "n": n, "seed": seed, "collision_rate": rate, "tick_bits": int(snap["units"]["tick_bits"]),
            "rows": rows}


def scan_summary(scans: list) -> dict:
    """Per (dim, phi) and d0: lambda of each engine, mean and standard error over seeds, and
    their difference in combined standard errors."""
    out = {}
    for key in sorted({(s["dim"], s["phi"]) for s in scans}):
        group = [s for s in scans if (s["dim"], s["phi"]) == key]
        rows = {}
        for k, d0 in enumerate(r["d0"] for r in group[0]["rows"]):
            row = {}
            for eng in ("lattice", "float"):
                for key_, err_key in (("lambda", "error"), ("lambda_linear", "error_linear")):
                    vals = [s["rows"][k][eng][key_] for s in group]
                    err = (float(np.std(vals, ddof=1) / math.sqrt(len(vals))) if len(vals) > 1
                           else group[0]["rows"][k][eng][err_key])
                    row.setdefault(eng, {})[key_] = float(np.mean(vals))
                    row[eng][err_key] = err
                row[eng]["steps_left_out"] = int(sum(s["rows"][k][eng]["steps_left_out"] for s in group))
            for key_, err_key, out_key in (("lambda", "error", "sd"), ("lambda_linear", "error_linear", "sd_linear")):
                row[out_key] = abs(row["lattice"][key_] - row["float"][key_]) / math.hypot(row["lattice"][err_key],
                                                                                           row["float"][err_key])
            rows[f"{d0:g}"] = row
        rate = float(np.mean([s["collision_rate"] for s in group]))
        out[f"{key[0]}D phi {key[1]}"] = {"seeds": len(group), "collision_rate": rate, "by_d0": rows}
    return out
