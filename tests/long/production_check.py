"""A production run checked from its own outputs (issue 19's "done when"): `revcol simulate`
of the default gas (N = 1000 disks, area fraction 0.3, flux law, float engine; periodic, so
that g(r) is a bulk property), GSD frames on a periodic trigger, and two checks that
another tool's reading of those frames agrees with what the engine measured during the run:

1. **Contact value against the virial pressure.** g(r) from the frames (freud when installed,
   numpy otherwise), its contact value g(D+) by a quadratic through the bins in (D, D + 0.2],
   and Z = 1 + 2 phi g(D+) against the observer's Z = 1 + W / K2 from the collision virial.
   The two are independent estimates of one number (the virial theorem for hard disks), each
   with a statistical error (the contact value's by blocks of frames, the observer's by blocks
   of time); the check is |difference| <= 3 combined standard errors.
2. **MSD across periodic boundaries from the image flags.** The frames' unwrapped positions
   (x + image L) give the mean squared displacement from the first frame; the observer
   integrates each particle's displacement without ever wrapping it. At every frame time the
   two must agree to the observer's own interpolation error (its MSD is sampled on a grid; a
   single wrong image flag of one particle moves the MSD by about 2 |x| L / N, far above it).

    python tests/long/production_check.py --collisions 1e7 --every 1e4 --json bench/results/production_check.json

The CI version (`tests/python/test_production.py`) runs `check(collisions=2e5, every=1e4)`.
"""
from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def scene_doc(particles: int, phi: float, seed: int, collisions: int) -> dict:
    """The default gas (scenes/default.toml) with periodic boundaries, on the float engine,
    observed."""
    return {"scene": {"name": "production-check"},
            "system": {"dimension": 2, "particles": particles, "diameter": 1.0, "packing_fraction": phi,
                       "boundaries": "periodic"},
            "collisions": {"engine": "float", "mode": "exact", "law": "flux"},
            "rng": {"generator": "philox", "streams": "per_particle", "seed": seed},
            "run": {"collisions": collisions}, "observe": {}}


def _blocks(values: np.ndarray, k: int) -> tuple[float, float]:
    """Mean and standard error of the mean of k block means of ``values`` (along axis 0)."""
    k = max(2, min(k, len(values)))
    parts = np.array_split(values, k)
    means = np.array([p.mean(axis=0) for p in parts])
    return float(means.mean()), float(means.std(ddof=1) / np.sqrt(k))


def _reference_images(scene, times, dense: int) -> np.ndarray:
    """The image flags at ``times`` of the same run followed densely: the Python API on the
    same scene (bit for bit the trajectory of ``simulate``: pauses change nothing), each
    particle's unwrapped position accumulated from minimum-image jumps every ``dense``
    collisions (a fraction of a collision per particle: no jump comes near L/2)."""
    from revcol.gas import build_simulation
    from revcol.roundtrip import geometry

    sim = build_simulation(scene)
    L, periodic = geometry(sim)
    Lp = np.where(periodic, L, np.inf)
    state = {"x": sim.positions.copy()}
    state["u"] = state["x"].copy()

    def follow(s) -> None:
        x = s.positions
        dx = x - state["x"]
        dx -= np.where(periodic, L * np.round(dx / Lp), 0.0)
        state["u"] += dx
        state["x"] = x.copy()
    sim.attach(follow, every=dense)
    out = []
    for t in times:
        if t > sim.time:
            sim.run(time=t)
        follow(sim)
        out.append(np.rint((state["u"] - sim.positions) / np.where(periodic, L, 1.0)).astype(np.int64))
    return np.array(out)


def _gr_contact(frames, box, first, blocks, bins, r_max):
    """g(r) over frames[first:] by blocks of frames; (r, mean g, contact value, its error)."""
    from revcol.observe import contact_value, radial_distribution

    idx = np.arange(first, len(frames))
    gs = []
    for c in np.array_split(idx, min(blocks, len(idx))):
        r, g = radial_distribution(frames[c], box, bins=bins, r_max=r_max)
        gs.append(g)
    gs = np.array(gs)
    contacts = np.array([contact_value(r, g) for g in gs])
    return r, gs.mean(axis=0), contact_value(r, gs.mean(axis=0)), float(contacts.std(ddof=1) / np.sqrt(len(gs)))


def check(collisions: int = 200_000, every: int = 10_000, particles: int = 1000, phi: float = 0.3,
          seed: int = 0, bins_width: float = 0.02, r_max: float = 3.0, skip: float = 0.1,
          blocks: int = 10, dense: int = 100, workdir: str | None = None) -> dict:
    """Runs the production run twice (frames on a time trigger, then on a collision trigger,
    about ``every`` collisions apart) and the checks; returns the report."""
    from revcol.observe import compressibility_from_contact
    from revcol.scene import scene_from_dict
    from revcol.cli.simulate import simulate
    from revcol.trajectory import read_gsd

    try:
        import freud  # noqa: F401
        rdf_backend = "freud"
    except ImportError:
        rdf_backend = "numpy"
    scene = scene_from_dict(scene_doc(particles, phi, seed, collisions), "production-check.toml", None)
    rate = 2.397  # collisions per particle per unit time at this state (the observer's, 10^7 collisions)
    every_time = 2.0 * every / (particles * rate)
    runs = {}
    with tempfile.TemporaryDirectory(dir=workdir) as tmp:
        for trigger in ("time", "collisions"):
            path = Path(tmp) / f"gas-{trigger}.gsd"
            t0 = time.perf_counter()
            kw = dict(every_time=every_time) if trigger == "time" else dict(every=every)
            rep = simulate(scene, collisions=collisions, trajectory=path, precise=True, progress=False, **kw)
            runs[trigger] = (rep, read_gsd(path), time.perf_counter() - t0, path.stat().st_size)
    rep, tr, sim_s, gsd_bytes = runs["time"]
    obs = rep["observe"]
    frames = tr["positions"]
    first = int(np.ceil(skip * len(frames)))
    bins = int(round(r_max / bins_width))
    r, g_mean, g_contact, g_err = _gr_contact(frames, tr["box"], first, blocks, bins, r_max)
    area_fraction = particles * np.pi / 4.0 / float(np.prod(tr["box"]))
    z_contact = compressibility_from_contact(g_contact, area_fraction, 2)
    z_contact_err = 2.0 * area_fraction * g_err
    z_virial, z_virial_err = (float(x) for x in obs["compressibility"])
    z_sigma = abs(z_contact - z_virial) / float(np.hypot(z_contact_err, z_virial_err))
    # the same on frames taken at collisions: one pair exactly at contact in each
    rep_c, tr_c = runs["collisions"][0], runs["collisions"][1]
    _, _, gc_contact, gc_err = _gr_contact(tr_c["positions"], tr_c["box"], int(np.ceil(skip * len(tr_c["positions"]))),
                                           blocks, bins, r_max)
    same_run = rep_c["time_end"] == rep["time_end"] and rep_c["net_collisions"] == rep["net_collisions"]

    # image flags: exactly those of the same run followed densely
    ref = _reference_images(scene, tr["time"], dense)
    flags_equal = bool(np.array_equal(ref, tr["image"]))
    # MSD from the image flags against the observer's (both from t = 0, the first frame),
    # to the observer's interpolation error (its MSD is sampled on a grid of block ends)
    un = tr["unwrapped"]
    msd_frames = ((un - un[0]) ** 2).sum(axis=2).mean(axis=1)
    mt, mv = np.asarray(obs["msd_time"], float), np.asarray(obs["msd"], float)
    inside = (tr["time"] > mt[0]) & (tr["time"] <= mt[-1])
    msd_obs = np.interp(tr["time"][inside], mt, mv)
    msd_rel = np.abs(msd_frames[inside] - msd_obs) / msd_obs
    out = {
        "collisions": int(rep["collisions"]), "collisions_per_particle": rep["collisions_per_particle"],
        "particles": particles, "area_fraction": area_fraction, "seed": seed, "every": every,
        "every_time": every_time, "frames": int(len(frames)), "frames_used_for_gr": int(len(frames) - first),
        "gsd_bytes": gsd_bytes, "simulate_s": sim_s, "rdf_backend": rdf_backend, "bin_width": bins_width,
        "g_contact": g_contact, "g_contact_error": g_err, "z_contact": z_contact, "z_contact_error": z_contact_err,
        "z_virial": z_virial, "z_virial_error": z_virial_err, "z_difference_sigmas": z_sigma,
        "z_henderson": (1 + area_fraction ** 2 / 8) / (1 - area_fraction) ** 2,
        "collision_trigger": {"frames": int(len(tr_c["positions"])), "g_contact": gc_contact,
                              "g_contact_error": gc_err,
                              "z_contact": compressibility_from_contact(gc_contact, area_fraction, 2),
                              "z_difference_sigmas": abs(compressibility_from_contact(gc_contact, area_fraction, 2)
                                                         - z_virial) / float(np.hypot(2 * area_fraction * gc_err,
                                                                                      z_virial_err)),
                              "same_run_as_time_trigger": bool(same_run)},
        "image_flags_equal_dense_reference": flags_equal, "dense_every": dense,
        "max_image": int(np.abs(tr["image"]).max()),
        "msd_final": float(msd_frames[-1]), "msd_frames_checked": int(inside.sum()),
        "msd_max_rel_difference_to_observer": float(msd_rel.max()) if len(msd_rel) else None,
        "energy_drift": rep["energy_drift"],
        "g_r": {"r": [float(x) for x in r[: int(1.5 / bins_width)]],
                "g": [float(x) for x in g_mean[: int(1.5 / bins_width)]]},
    }
    out["passed"] = bool(z_sigma <= 3.0 and flags_equal and out["max_image"] > 0 and same_run)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--collisions", type=float, default=1e7)
    ap.add_argument("--every", type=float, default=1e4)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--json", metavar="FILE")
    a = ap.parse_args(argv)
    load0 = os.getloadavg()
    r = check(collisions=int(a.collisions), every=int(a.every), seed=a.seed)
    try:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                                cwd=Path(__file__).parent).stdout.strip()
    except OSError:
        commit = None
    r.update({"command": "python tests/long/production_check.py " + " ".join(shlex.quote(x) for x in (argv or sys.argv[1:])),
              "commit": commit, "date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
              "load_1m_before": load0[0], "load_1m_after": os.getloadavg()[0]})
    summary = {k: r[k] for k in ("collisions", "frames", "g_contact", "g_contact_error", "z_contact", "z_virial",
                                 "z_virial_error", "z_difference_sigmas", "z_henderson", "collision_trigger",
                                 "image_flags_equal_dense_reference", "max_image", "msd_final",
                                 "msd_max_rel_difference_to_observer", "rdf_backend", "simulate_s", "passed")}
    # simulate_s is the wall time of this run on whatever the machine was doing: not a benchmark
    print(json.dumps(summary, indent=1))
    if a.json:
        from revcol._io import atomic_open

        with atomic_open(a.json, "w") as f:
            json.dump(r, f, indent=1)
    return 0 if r["passed"] else 1


if __name__ == "__main__":
    sys.exit(main())
