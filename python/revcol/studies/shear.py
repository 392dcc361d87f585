"""Shear viscosity from Lees-Edwards shear on the lattice engine (non-equilibrium MD, exact).

A gas of N spheres (unit diameter and mass) in a periodic cube, sheared by Lees-Edwards
boundaries at rate gamma (flow along x, gradient along y; `LatticeSimulation3D(shear_rate=)`),
started on the steady profile v_x = gamma (y - <y>) at kT = 1. No thermostat: the boundary's
work heats the gas, and that work is the measurement. Energy has no other source (hard spheres,
no field), so over an interval the change of the total kinetic energy is the work
-gamma V P_xy dt, and eta = dE / dt / (gamma^2 V) exactly, the total stress (kinetic plus
collisional) read from exact integer energies. Hard spheres have no energy scale: a gas at kT
behaves as one at kT = 1 with time scaled by sqrt(kT), so each interval gives the reduced
eta* = eta / sqrt(m kT) sigma^2 at the reduced rate gamma* = gamma sqrt(m / kT) sigma, kT the
interval's peculiar temperature (velocities less the imposed profile). As the gas heats, gamma*
falls: each run sweeps a range of reduced rates, reported.

The kinetic part of the stress, P_xy^kin = sum u_x v_y / V, u the peculiar velocity (v less the
profile of slope gamma through the centre of mass, as for kT), is read from
the frames; the collisional part is the total less it. The same eta from the stress itself
(a second route, independent of the energy): the observer, started afresh at each frame,
integrates the kinetic stress exactly between events and adds each collision's r_x Delta p_y
(the pairs across the gradient faces through the moving images, docs/shear.md "Observables");
each interval's -P_xy / gamma at its own observed temperature is eta_stress. The velocity profile (mean v_x in bins
along y, over the frames) is fitted by a line whose slope is compared with gamma (Lees-Edwards
has no walls, so no slip). At the end every run goes back to its start, bit for bit.

Zero-rate extrapolation: eta* against gamma*^2 (the analytic low-rate form; the mode-coupling
gamma*^(1/2) form is reported beside it as the extrapolation's systematic), weighted by the
errors (the seeds' spread). The reference is the project's own equilibrium Einstein-Helfand
eta of the same specular gas at the same N (bench/results/transport_specular.json,
docs/physics.md "Transport in the specular gas") and Enskog's eta_E; published NEMD tables were
not reachable from this environment (studies/literature.py).

    python -m revcol.studies.shear --n 1000 --phi 0.3 0.4 --rates 0.05 0.1 0.2 --seeds 4 \\
        --modes specular exact --json bench/results/shear_viscosity.json [--figure F]
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time

import numpy as np

__all__ = ["measure", "extrapolate", "figure", "main"]


def _peculiar(x: np.ndarray, v: np.ndarray, rate: float) -> np.ndarray:
    """v less the streaming profile of slope ``rate`` through the centre of mass."""
    u = v - v.mean(axis=0)
    u[:, 0] -= rate * (x[:, 1] - x[:, 1].mean())
    return u


def measure(n: int, phi: float, rate: float, mode: str = "specular", seed: int = 1, warm: float = 20.0,
            per_frame: float = 4.0, frames: int = 60, bins: int = 10, back: bool = True) -> dict:
    """One sheared run: ``warm`` collisions per particle, then ``frames`` frames of ``per_frame``
    collisions per particle. Returns the per-interval reduced eta*, gamma* and kT, the kinetic
    stress, the profile, and whether the run went back to its start bit for bit."""
    from revcol.lattice import LatticeSimulation3D
    sim = LatticeSimulation3D.random(n, phi=phi, shear_rate=rate, mode=mode, seed=seed)
    start = sim.snapshot()
    g = sim.shear_rate  # the rate run (quantized)
    box = sim.box
    vol = float(np.prod(box))
    ly = float(box[1])
    sim.run(collisions=int(warm * n))
    t, e, kt, pkin, eta_st = [], [], [], [], []
    prof = np.zeros(bins)
    for f in range(frames + 1):
        if f:
            sim.observe()  # (afresh: this interval's stress and temperature)
            sim.run(collisions=int(per_frame * n))
            o = sim.observation()
            eta_st.append(o.viscosity.value / math.sqrt(o.temperature.value))  # reduced at its own kT
        x, v = sim.positions, sim.velocities
        u = _peculiar(x, v, g)
        t.append(sim.time)
        e.append(0.5 * float(np.sum(v * v)))
        kt.append(float(np.sum(u * u)) / (3.0 * n))
        pkin.append(float(np.sum(u[:, 0] * v[:, 1])) / vol)
        idx = np.minimum((x[:, 1] / ly * bins).astype(int), bins - 1)
        prof += np.bincount(idx, weights=v[:, 0], minlength=bins) / np.maximum(np.bincount(idx, minlength=bins), 1)
    t, e, kt, pkin = map(np.asarray, (t, e, kt, pkin))
    tk = 0.5 * (kt[1:] + kt[:-1])
    eta = np.diff(e) / (np.diff(t) * g * g * vol) / np.sqrt(tk)  # reduced, per interval
    gam = g / np.sqrt(tk)
    pk = 0.5 * (pkin[1:] + pkin[:-1])
    eta_kin = -pk / (g * np.sqrt(tk))
    prof /= frames + 1
    centres = (np.arange(bins) + 0.5) / bins * ly
    slope = float(np.polyfit(centres, prof, 1)[0])
    out = {"n": n, "phi": phi, "rate": g, "mode": mode, "seed": seed, "shear_error": sim.quantization.get("shear_error", 0.0),
           "collisions": sim.collisions, "time": float(t[-1]), "kT_first": float(kt[0]), "kT_last": float(kt[-1]),
           "eta": float(np.mean(eta)), "eta_stress": float(np.mean(eta_st)), "eta_kinetic": float(np.mean(eta_kin)), "gamma_star": float(np.mean(gam)),
           "gamma_star_range": [float(gam.min()), float(gam.max())], "profile_slope_over_rate": slope / g,
           "profile": (prof / (g * ly)).tolist(), "log_entries": int(sim.diagnostics()["log_entries"])}
    if back:
        sim.run_back()
        end = sim.snapshot()
        out["back_bit_for_bit"] = all(np.array_equal(np.asarray(start[k]), np.asarray(end[k]))
                                      for k in ("x", "v", "streams", "bits", "clock", "collisions"))
    return out


def extrapolate(gam: np.ndarray, eta: np.ndarray, err: np.ndarray) -> dict:
    """Weighted least squares of eta* against gamma*^2 and against gamma*^(1/2): the intercepts
    (eta* at zero rate) with their errors."""
    out = {}
    if len(gam) < 2:  # one rate: no extrapolation
        return {k: {"eta0": float(eta[0]), "eta0_error": float(err[0]), "slope": 0.0} for k in ("quadratic", "sqrt")}
    for name, xv in (("quadratic", gam ** 2), ("sqrt", np.sqrt(gam))):
        w = 1.0 / np.maximum(err, 1e-12) ** 2
        a = np.vstack([np.ones_like(xv), xv]).T
        cov = np.linalg.inv(a.T @ (a * w[:, None]))
        coef = cov @ (a.T @ (w * eta))
        out[name] = {"eta0": float(coef[0]), "eta0_error": float(math.sqrt(cov[0, 0])), "slope": float(coef[1])}
    return out


def _reference(phi: float, path: str) -> dict:
    from revcol.studies.literature import enskog_eta
    ref = {"eta_enskog": enskog_eta(phi, 3)}
    try:
        with open(path) as f:
            rows = json.load(f)["rows"]
        for r in rows:
            if r["engine"] == "lattice" and abs(r["phi"] - phi) < 1e-9:
                ref.update(eta_helfand=r["eta"], eta_helfand_error=r["eta_error"], helfand_n=r["n"])
    except (OSError, KeyError, ValueError):
        pass
    return ref


def figure(data: dict, path: str) -> None:
    """eta* against gamma* per packing fraction and mode, with the zero-rate fits and the
    equilibrium reference; and the velocity profiles."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4))
    for s in data["summary"]:
        gs, es, ee = (np.asarray(s[k]) for k in ("gamma_star", "eta", "eta_error"))
        line = a.errorbar(gs, es, ee, fmt="o" if s["mode"] == "specular" else "s", label=f"phi {s['phi']} {s['mode']}")
        if "eta_stress" in s:  # the stress route, open markers beside it
            a.errorbar(np.asarray(gs) * 1.03, s["eta_stress"], s["eta_stress_error"], fmt="o" if s["mode"] == "specular" else "s",
                       mfc="none", color=line[0].get_color())
        q = s["fit"]["quadratic"]
        xs = np.linspace(0, gs.max(), 50)
        a.plot(xs, q["eta0"] + q["slope"] * xs ** 2, "-", lw=0.8)
        if "eta_helfand" in s["reference"]:
            a.errorbar([0.0], [s["reference"]["eta_helfand"]], [s["reference"]["eta_helfand_error"]], fmt="k*")
    a.set_xlabel("gamma* (reduced shear rate)")
    a.set_ylabel("eta* (reduced shear viscosity)")
    a.legend(fontsize=7)
    a.set_title("Lees-Edwards on the lattice engine (filled: energy, open: stress; stars: equilibrium Helfand)",
                fontsize=8)
    for r in data["runs"][:: max(1, len(data["runs"]) // 6)]:
        p = np.asarray(r["profile"])
        yb = (np.arange(p.size) + 0.5) / p.size
        b.plot(yb, p, "o-", ms=3, lw=0.6, label=f"phi {r['phi']} gamma {r['rate']:.2g} {r['mode']}")
    b.plot([0, 1], [-0.5, 0.5], "k--", lw=0.8, label="imposed: slope gamma")
    b.set_xlabel("y / L")
    b.set_ylabel("<v_x> / (gamma L)")
    b.legend(fontsize=6)
    fig.tight_layout()
    tmp = path + ".tmp.png"
    fig.savefig(tmp, dpi=120)
    os.replace(tmp, path)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--n", type=int, default=1000)
    p.add_argument("--phi", type=float, nargs="+", default=[0.3, 0.4])
    p.add_argument("--rates", type=float, nargs="+", default=[0.05, 0.1, 0.2])
    p.add_argument("--modes", nargs="+", default=["specular", "exact"])
    p.add_argument("--seeds", type=int, default=4)
    p.add_argument("--warm", type=float, default=20.0, help="collisions per particle before the frames")
    p.add_argument("--per-frame", type=float, default=4.0, help="collisions per particle per frame")
    p.add_argument("--frames", type=int, default=60, help="frames at rate 0.1 (x (0.1 / rate)^2, at most 4x)")
    p.add_argument("--reference", default="bench/results/transport_specular.json")
    p.add_argument("--json", default=None)
    p.add_argument("--figure", default=None)
    p.add_argument("--from", dest="from_", default=None, help="draw --figure from a JSON written before")
    a = p.parse_args(argv)
    if a.from_:
        with open(a.from_) as f:
            data = json.load(f)
        figure(data, a.figure)
        return 0
    t0 = time.time()
    runs, summary = [], []
    for phi in a.phi:
        ref = _reference(phi, a.reference)
        for mode in a.modes:
            gs, es, ee, ks, ss, se = [], [], [], [], [], []
            for rate in a.rates:
                # the boundary heats the gas as gamma^2: a run's length scales as 1 / gamma^2 (at most 4x
                # the frames), so every rate heats it alike and the errors (~ 1 / (gamma sqrt(time))) match
                fr = max(10, round(a.frames * min(4.0, (0.1 / rate) ** 2)))
                rs = [measure(a.n, phi, rate, mode, s, a.warm, a.per_frame, fr) for s in range(1, a.seeds + 1)]
                runs += rs
                eta = np.array([r["eta"] for r in rs])
                gs.append(float(np.mean([r["gamma_star"] for r in rs])))
                es.append(float(eta.mean()))
                ee.append(float(eta.std(ddof=1) / math.sqrt(len(rs))) if len(rs) > 1 else float("nan"))
                ks.append(float(np.mean([r["eta_kinetic"] for r in rs])))
                st = np.array([r["eta_stress"] for r in rs])
                ss.append(float(st.mean()))
                se.append(float(st.std(ddof=1) / math.sqrt(len(rs))) if len(rs) > 1 else float("nan"))
                print(f"phi {phi} {mode} rate {rate}: gamma* {gs[-1]:.4f} eta* {es[-1]:.4f} +- {ee[-1]:.4f} "
                      f"(stress {ss[-1]:.4f} +- {se[-1]:.4f}, kinetic {ks[-1]:.4f}) slope/rate {np.mean([r['profile_slope_over_rate'] for r in rs]):.4f} "
                      f"back {all(r['back_bit_for_bit'] for r in rs)}", flush=True)
            fit = extrapolate(np.array(gs), np.array(es), np.array(ee))
            s = {"phi": phi, "mode": mode, "gamma_star": gs, "eta": es, "eta_error": ee, "eta_stress": ss,
                 "eta_stress_error": se, "eta_kinetic": ks, "fit": fit,
                 "fit_stress": extrapolate(np.array(gs), np.array(ss), np.array(se)), "reference": ref}
            if "eta_helfand" in ref:
                q = fit["quadratic"]
                s["eta0_minus_helfand_sd"] = (q["eta0"] - ref["eta_helfand"]) / math.hypot(q["eta0_error"], ref["eta_helfand_error"])
            summary.append(s)
            print(f"phi {phi} {mode}: eta0* {fit['quadratic']['eta0']:.4f} +- {fit['quadratic']['eta0_error']:.4f} "
                  f"(sqrt fit {fit['sqrt']['eta0']:.4f}; stress {s['fit_stress']['quadratic']['eta0']:.4f} +- "
                  f"{s['fit_stress']['quadratic']['eta0_error']:.4f}); reference {ref}", flush=True)
    data = {"command": "python -m revcol.studies.shear " + " ".join(sys.argv[1:] if argv is None else argv),
            "loadavg": os.getloadavg(), "wall_s": time.time() - t0, "n": a.n, "warm": a.warm, "per_frame": a.per_frame,
            "frames": a.frames, "seeds": a.seeds, "summary": summary, "runs": runs}
    if a.json:
        tmp = a.json + ".tmp"
        with open(tmp, "w") as f:
            json.dump(data, f, indent=1)
        os.replace(tmp, a.json)
    if a.figure:
        figure(data, a.figure)
    return 0 if all(r.get("back_bit_for_bit", True) for r in runs) else 1


if __name__ == "__main__":
    sys.exit(main())
