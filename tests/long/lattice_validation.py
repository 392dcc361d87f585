"""The lattice engine proven at scale (issue 13 in 2D, issue 14 in 3D: `--dim 3`, the sphere gas of
LatticeSimulation3D, volume fractions instead of area fractions). Writes
bench/results/lattice_validation_*.json.

    PYTHONPATH=build-dev/pkg python3 tests/long/lattice_validation.py matrix [--collisions 1e7]
        [--n 1000 10000] [--phi 0.1 0.3 0.5 0.7] [--boundary wall periodic bounce] [--mode exact|specular] [--out matrix]
        [--sizes one|binary|gauss] [--gravity G] [--shear RATE]
    PYTHONPATH=build-dev/pkg python3 tests/long/lattice_validation.py equilibrium [--n 1000] [--phi 0.5]
    PYTHONPATH=build-dev/pkg python3 tests/long/lattice_validation.py failures [--phi 0.5 0.7] [--seeds 4] [--collisions 2e6] --out failures
    PYTHONPATH=build-dev/pkg python3 tests/long/lattice_validation.py gas --n 1000 --phi 0.3 --boundary wall --collisions 1e5
    PYTHONPATH=build-dev/pkg python3 tests/long/lattice_validation.py probe --n 1000 --phi 0.7 --boundary wall --collisions 3e6 --ticks 20 22 24 --cells 20 16 --out probe

matrix: every gas (N x area fraction x boundary; the flux law, or the deterministic specular map
with ``--mode specular``) in its own subprocess (``gas``), one
at a time. The child runs C collisions forward, taking a snapshot at C/2, then runs back to C/2
and compares with that snapshot bit for bit (the midpoint check), then back to 0 and compares
with the start: positions, velocities, stream counters (RNG), the bits-back integer X, clock,
collision count and the rare log, each reported on its own. Per gas: forward and reverse
collisions per second (wall and CPU; under a shared machine's load the wall figure is not a
finding), log entries per collision, redraws per collision by reason, multi-body and wall-body
ticks, X's bit length (start, end, min and max sampled along the forward run; the reverse
passes through the same states), energy drift (relative, relative / sqrt(C), and per collision in
units of 2^-40 of a pair's mean energy), momentum drift (lattice units per periodic axis, per
collision and / sqrt(C); a wall axis does not conserve momentum), the child's peak RSS (VmHWM)
at 10^5, 10^6, ... collisions and C, and the child's ru_maxrss from wait4. If the engine throws
on the way forward, the row records the error and the collisions done (``completed`` false), whether
running back from the failed state works, and checks bit for bit from the latest snapshot before
the failure (taken every C/100 collisions) back to an earlier one and to 0. Rows are written
after each gas (atomically: a temporary file renamed), with the commit of the build and the load
average before and after.

--sizes (matrix, gas): one diameter (default), a binary mixture of equal numbers with size ratio
1.4 (``binary``), or a polydisperse gas (``gauss``: diameters 1 + 0.1 z, z a standard normal
truncated at +-2, so the start's crystal of the largest holds area fraction 0.5 and volume
fraction 0.4), the packing fraction counting each particle's own size.

--gravity G (matrix, gas): a uniform field of G (float units, toward the lower wall for G < 0)
along the last axis, which then has walls (a periodic --boundary keeps the other axes periodic);
the row adds the field run, its quantization, the mean height at the start and the end and the
walls' momentum against the column's weight over the second half (docs/engine.md).

--shear RATE (matrix, gas): Lees-Edwards shear at that rate (float units; flow along x, gradient
along y, both periodic; in 3D a --boundary wall walls z only); the row adds the shear run, its
quantization and the boundary's work (the energy's rise: viscous heating; docs/shear.md).

probe: forward only, one gas per (N, area fraction, boundary) for each tick (--ticks) and cell
resolution (--cells): the rare log's entries, the group entries and the redraws by reason, the
energy drift. It is how the engine's automatic tick and 2^16 cells were chosen (docs/lattice.md
"Choosing the tick and the cells"). Writes lattice_validation_<out>.json.

failures: forward only, several seeds, up to --collisions: the first engine error and, rebuilt
from the snapshot before it, the bodies within 3 ticks' travel of the failing pair; and a census
of the group bounces in the rare log (the same members bouncing again and again is a trap). Writes
lattice_validation_<out>.json.

equilibrium: a dense periodic lattice gas from equal speeds (not Maxwellian) relaxed for
--relax collisions per particle, then speed samples pooled over snapshots --gap collisions per
particle apart, KS against the 2D Maxwell-Boltzmann (Rayleigh) law with the measured kT; and the
collision rate per particle per unit time (2 collisions / (N t): each collision involves two
particles) measured by batch means over --batches batches of --batch collisions per particle, on
--seeds independent gases, for the lattice engine (time = clock * tick) and the float engine
(revcol.Simulation, mode="exact", law="flux") started from the same float state (same N, phi,
energy). The error bar is the standard error of the per-seed means (independent gases); the
batch spread within seeds is reported beside it. Writes lattice_validation_equilibrium.json.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import re
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
RESULTS = os.path.normpath(os.path.join(HERE, "..", "..", "bench", "results"))
DIM = 2  # --dim: 2 (disks, LatticeSimulation) or 3 (spheres, LatticeSimulation3D)


def _sim_cls():
    """The lattice simulation class of the dimension asked for."""
    from revcol import lattice
    return lattice.LatticeSimulation3D if DIM == 3 else lattice.LatticeSimulation

# Snapshot entries that define the physical state, grouped as the issue names them.
STATE_PARTS = {
    "positions": ["x"],
    "velocities": ["v"],
    "rng_counters": ["streams"],
    "bits_back_X": ["bits", "bits_size"],
    "clock": ["clock", "origin"],
    "collision_count": ["collisions", "particle_collisions"],
    "rare_log": ["log_particle", "log_count", "log_redraws", "group_drawer", "group_draws", "group_size", "group_members",
                 "group_counts"],
}


def compare_states(a: dict, b: dict) -> dict:
    """Bit-for-bit equality of two ``LatticeSimulation.snapshot()`` dicts, per part, and overall."""
    out = {part: all(np.array_equal(np.asarray(a[k]), np.asarray(b[k])) for k in keys)
           for part, keys in STATE_PARTS.items()}
    out["all"] = all(out.values())
    return out


def _proc_status(pid: str = "self") -> dict:
    """VmHWM and VmRSS of a process in bytes (Linux /proc)."""
    out = {}
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith(("VmHWM:", "VmRSS:")):
                k, v = line.split(":")
                out[k] = int(v.split()[0]) * 1024
    return out


def _git_commit() -> str:
    try:
        head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=HERE, capture_output=True, text=True,
                              check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=HERE,
                               capture_output=True, text=True, check=True).stdout.strip()
        return head + ("-dirty" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def _build_info() -> dict:
    """The module the run imports, and any uncommitted change to the tracked code (the build may
    carry a local line, e.g. module.cpp's registration of the lattice binding)."""
    from revcol import _core
    path = _core.__file__
    try:
        # the code that builds and runs the module, not the results and docs beside it (a results
        # file rewritten during a run made this diff, and the child's peak RSS, grow to 100 MB)
        diff = subprocess.run(["git", "diff", "HEAD", "--", "cpp", "python", "CMakeLists.txt", "pyproject.toml", "tests/long"],
                              cwd=HERE, capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        diff = "unknown"
    return {"core": path, "core_mtime": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(os.path.getmtime(path))),
            "uncommitted_diff": diff}


def _write_atomic(path: str, obj) -> None:
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(obj, f, indent=1)
    os.replace(tmp, path)


def _init_for(phi: float) -> str:
    # random sequential addition jams near 0.55 in 2D and 0.38 in 3D: dense gases start from a
    # jittered crystal (square in 2D, FCC in 3D)
    return "crystal" if phi > (0.35 if DIM == 2 else 0.2) else "auto"


def _checkpoints(c: int) -> list:
    """Collision counts at which the forward run records RSS and X: 10^3, 10^4, ... below C,
    C/2 (the midpoint snapshot) and C."""
    pts = {c, c // 2}
    k = 1000
    while k < c:
        pts.add(k)
        k *= 10
    return sorted(p for p in pts if p > 0)


def _drift_figures(d: dict, d0_energy: float, c: int, n: int, wall: list) -> dict:
    de = float(d["energy_drift"])
    pair_energy = 2.0 * d0_energy / n  # mean energy of two particles, lattice units
    dp = [float(x) for x in d["momentum_drift"]]
    periodic = [k for k in range(len(wall)) if not wall[k]]
    return {
        "energy_drift_relative": de,
        "energy_drift_units": float(d["energy_drift_units"]),
        "energy_drift_over_sqrt_c": abs(de) / math.sqrt(c),
        # a random walk of one error e per collision on a pair's energy: |dE| = e E_pair sqrt(C)
        "energy_error_per_collision_in_2^-40_of_pair_energy":
            abs(float(d["energy_drift_units"])) / pair_energy / math.sqrt(c) / 2.0 ** -40,
        # the velocity resolution sets it: |v| ~ 2^vbits lattice units, a rounding of 1/2 unit
        "v_rms_bits": 0.5 * math.log2(d0_energy / n),
        "energy_error_per_collision_in_2^-vbits_of_pair_energy":
            abs(float(d["energy_drift_units"])) / pair_energy / math.sqrt(c) * math.sqrt(d0_energy / n),
        "momentum_drift_units": dp,
        "momentum_conserved_axes": periodic,
        "momentum_drift_per_collision": [abs(dp[k]) / c for k in periodic],
        "momentum_drift_over_sqrt_c": [abs(dp[k]) / math.sqrt(c) for k in periodic],
    }


def _forward(sim, c: int, samples: int) -> dict:
    """C collisions forward in chunks: X's bit length sampled after each, RSS and drift at the
    checkpoints, a snapshot at C/2 and after the latest chunk. An engine error stops the run
    where the engine left it (at its last completed collision) and is recorded."""
    marks = _checkpoints(c)
    step = max(1, c // samples)
    f = {"rss": [], "mid": None, "last": None, "prev": None, "wall": 0.0, "cpu": 0.0, "error": None, "samples": 0,
         "bmin": sim.diagnostics()["bits_length"], "bmax": sim.diagnostics()["bits_length"]}
    done = 0
    while done < c:
        nxt = min([m for m in marks if m > done] + [(done // step + 1) * step])
        t0, p0 = time.perf_counter(), time.process_time()
        try:
            sim.run(collisions=nxt - done)
        except RuntimeError as e:
            f["error"] = str(e)
        f["wall"] += time.perf_counter() - t0
        f["cpu"] += time.process_time() - p0
        if f["error"] is not None or sim.collisions != nxt:
            f["error"] = f["error"] or f"forward run stopped after {sim.collisions} of {c} collisions"
            break
        done = nxt
        d = sim.diagnostics()
        f["samples"] += 1
        f["bmin"], f["bmax"] = min(f["bmin"], d["bits_length"]), max(f["bmax"], d["bits_length"])
        if done in marks:
            st = _proc_status()
            f["rss"].append({"collisions": done, "vmhwm_bytes": st["VmHWM"], "vmrss_bytes": st["VmRSS"],
                             "engine_memory_bytes": d["memory_bytes"], "bits_length": d["bits_length"],
                             "log_entries": d["log_entries"], "energy_drift_relative": d["energy_drift"]})
        if done == c // 2:
            f["mid"] = (done, sim.snapshot())
            f["impulse_mid"] = (d["field_wall_impulse"], d["clock"])  # (a field's walls: the weight check)
        if done == c:
            f["impulse_end"] = (d["field_wall_impulse"], d["clock"])
        elif done < c:
            f["prev"], f["last"] = f["last"], (done, sim.snapshot())
    return f


def _weight_balance(f: dict, n: int, units: dict):
    """Over the second half of the forward run, the momentum the field's walls gave the gas (the
    wall pulled to less the other) over the column's weight N |g| t; None if the run stopped short."""
    if "impulse_mid" not in f or "impulse_end" not in f:
        return None
    (a0, b0), t0 = f["impulse_mid"]
    (a1, b1), t1 = f["impulse_end"]
    g = int(units["gravity"][-1])
    pulled, other = (a1 - a0, b1 - b0) if g < 0 else (b1 - b0, a1 - a0)
    weight = n * abs(g) * (t1 - t0)
    return {"wall_pulled_to": int(pulled), "other_wall": int(other), "weight": int(weight), "ticks": int(t1 - t0),
            "ratio": (pulled - other) / weight if weight else None}


def _after_failure(sim, f: dict):
    """The engine failed on the way forward: try running back from where it stopped (recorded),
    then resume from the latest snapshot, whose midpoint is the C/2 snapshot if taken, else the
    one before. Returns the simulation to run back from."""
    LatticeSimulation = _sim_cls()
    try:
        sim.run_back()
        f["run_back_from_failure"] = "ok"
    except (RuntimeError, ValueError) as e:
        f["run_back_from_failure"] = f"{type(e).__name__}: {e}"
    if f["last"] is None:
        return None
    if f["mid"] is None or f["mid"][0] >= f["last"][0]:
        f["mid"] = f.get("prev")
    return LatticeSimulation.from_snapshot(f["last"][1])


def sizes_of(sizes: str, n: int, seed: int):
    """The diameters of --sizes (None: one diameter)."""
    if sizes == "one":
        return None
    if sizes == "binary":
        d = np.ones(n)
        d[1::2] = 1.0 / 1.4
        return d
    rng = np.random.default_rng(seed)
    z = rng.standard_normal(4 * n)
    return 1.0 + 0.1 * z[np.abs(z) <= 2.0][:n]


def run_gas(n: int, phi: float, boundary: str, collisions: int, seed: int = 1, samples: int = 100,
            law: str = "flux", tick_bits: int = 0, cell_bits: int = 16, mode: str = "exact", sizes: str = "one",
            gravity: float = 0.0, shear: float = 0.0) -> dict:
    """One gas: C collisions forward (snapshot at C/2), back to C/2 (compared), back to 0
    (compared). Returns the row (see the module doc). If the engine fails on the way forward, the
    row says so (``completed`` false, ``forward_error``) and the checks run on the collisions done,
    the midpoint being the latest snapshot before the failure."""
    LatticeSimulation = _sim_cls()
    load0 = os.getloadavg()
    field = {}
    if gravity:  # along the last axis, walled
        field = {"gravity": [0.0] * (DIM - 1) + [gravity],
                 "boundary": [boundary] * (DIM - 1) + ["wall" if boundary == "periodic" else boundary]}
    if shear:  # Lees-Edwards: x and y periodic (3D: z as asked)
        field = {"boundary": ["periodic", "periodic"] + [boundary] * (DIM - 2)}
    # a mixture's "auto": as the largest on a crystal where that fits (the crystal's bits), else relaxed
    init = _init_for(phi) if sizes == "one" else "auto"
    sim = LatticeSimulation.random(n=n, phi=phi, boundary=field.get("boundary", boundary), seed=seed, init=init,
                                   law=law, tick_bits=tick_bits or None, cell_bits=cell_bits, mode=mode,
                                   diameters=sizes_of(sizes, n, seed), gravity=field.get("gravity"),
                                   shear_rate=shear or None)
    s0 = sim.snapshot()
    units = sim.units
    wall = [bool(w) for w in units["wall"]]
    e0 = float(np.sum(sim.lattice_velocities.astype(float) ** 2))
    if gravity:  # the energy kept is kinetic and potential (2 |g| times the height above the floor)
        g_l, z = int(units["gravity"][-1]), sim.lattice_positions[:, -1].astype(float)
        e0 += 2.0 * abs(g_l) * float(np.sum(z if g_l < 0 else units["L"][-1] - z))
    h0 = float(np.mean(sim.positions[:, -1]))
    bits0 = sim.diagnostics()["bits_length"]
    f = _forward(sim, int(collisions), samples)
    h_end = float(np.mean(sim.positions[:, -1]))
    c = sim.collisions  # collisions done (= collisions unless the engine failed)
    d_end = sim.diagnostics()
    if f["error"] is not None:
        sim = _after_failure(sim, f)
    t0, p0 = time.perf_counter(), time.process_time()
    mid, back, d_back, checked = {"all": None}, {"all": None}, {"bits_length": None}, None
    if sim is not None:
        checked = sim.collisions
        if f["mid"] is not None:
            sim.run_back(to_collision=f["mid"][0])
            mid = compare_states(sim.snapshot(), f["mid"][1])
        sim.run_back()
        back = compare_states(sim.snapshot(), s0)
        d_back = sim.diagnostics()
    wall_r, cpu_r = time.perf_counter() - t0, time.process_time() - p0
    log_held = d_end["log_entries"]  # every entry, group bounces included (they are keyed in the same log)
    cc = max(c, 1)
    row = {
        "dim": DIM, "n": n, "phi": phi, "boundary": boundary, "mode": mode, "law": law, "seed": seed, "sizes": sizes,
        "collisions_asked": int(collisions), "backscatters": d_end.get("backscatters"),
        "search": None if sim is None else sim.search,
        "collisions": c, "completed": f["error"] is None, "forward_error": f["error"],
        "run_back_from_failure": f.get("run_back_from_failure"), "collisions_checked_back": checked,
        "collisions_per_particle": 2.0 * c / n,
        "bit_for_bit": bool(back["all"] and mid["all"]), "roundtrip": back, "midpoint": mid,
        "midpoint_collision": None if f["mid"] is None else f["mid"][0],
        "forward_collisions_per_s_wall": c / f["wall"], "reverse_collisions_per_s_wall": (checked or 0) / wall_r,
        "forward_collisions_per_s_cpu": c / f["cpu"], "reverse_collisions_per_s_cpu": (checked or 0) / max(cpu_r, 1e-9),
        "forward_s_wall": f["wall"], "reverse_s_wall": wall_r, "forward_s_cpu": f["cpu"], "reverse_s_cpu": cpu_r,
        "log_entries": log_held, "log_entries_redraw_only": log_held - d_end["group_log_entries"],
        "log_entries_group": d_end["group_log_entries"], "log_entries_per_collision": log_held / cc,
        "log_bar_met": log_held / cc <= 1e-5,
        "redraws": dict(d_end["redraws"]),
        "redraws_per_collision": {k: v / cc for k, v in d_end["redraws"].items()},
        "redraws_total_per_collision": sum(d_end["redraws"].values()) / cc,
        "multi_body_ticks": d_end["multi_body"], "wall_body_ticks": d_end["wall_body"],
        "group_resolves": d_end["group_resolves"], "group_bounces": d_end["group_bounces"],
        "events_forward": d_end["events"], "wall_reflections_forward": d_end["walls"],
        "bits_X": {"start": bits0, "end": d_end["bits_length"], "min": f["bmin"], "max": f["bmax"],
                   "after_reverse": d_back["bits_length"], "samples": f["samples"]},
        "drift_after_c": _drift_figures(d_end, e0, cc, n, wall),
        "rss": f["rss"],
        "units": {k: (list(v) if isinstance(v, tuple) else v) for k, v in units.items()},
        "quantization": sim.quantization,
        "loadavg_start": list(load0), "loadavg_end": list(os.getloadavg()),
        "commit": _git_commit(),
    }
    if gravity:
        row["gravity"] = {"asked": gravity, "run": [float(g) for g in sim.gravity],
                          "lattice_units_per_tick2": int(units["gravity"][-1]), "boundary": field["boundary"],
                          "mean_height_start": h0, "mean_height_end": h_end, "weight_balance": _weight_balance(f, n, units)}
    if shear:
        row["shear"] = {"asked": shear, "run": sim.shear_rate, "lattice_units_per_tick": int(units["shear"]),
                        "boundary": field["boundary"], "energy_rise_relative": float(d_end["energy_drift"])}
    hwm = [r["vmhwm_bytes"] for r in f["rss"] if r["collisions"] >= 100000]
    row["vmhwm_growth_from_1e5_bytes"] = (hwm[-1] - hwm[0]) if hwm else None
    return row


def _child(args) -> int:
    row = run_gas(args.n, args.phi, args.boundary, int(float(args.collisions)), args.seed,
                  tick_bits=args.tick_bits, cell_bits=args.cell_bits, mode=args.mode, sizes=args.sizes,
                  gravity=args.gravity, shear=args.shear)
    print("ROW " + json.dumps(row), flush=True)
    return 0


def run_child(n: int, phi: float, boundary: str, collisions: int, seed: int = 1, tick_bits: int = 0,
              cell_bits: int = 16, mode: str = "exact", sizes: str = "one", gravity: float = 0.0,
              shear: float = 0.0) -> dict:
    """``run_gas`` in a fresh subprocess; adds the child's ru_maxrss (wait4) and exit status."""
    cmd = [sys.executable, os.path.abspath(__file__), "gas", "--n", str(n), "--phi", str(phi),
           "--boundary", boundary, "--collisions", str(int(collisions)), "--seed", str(seed),
           "--tick-bits", str(tick_bits), "--cell-bits", str(cell_bits), "--dim", str(DIM), "--mode", mode,
           "--sizes", sizes, "--gravity", repr(gravity), "--shear", repr(shear)]
    t0 = time.time()
    with tempfile.TemporaryFile(mode="w+") as ferr:
        p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=ferr, text=True)
        out = p.stdout.read()
        _, status, ru = os.wait4(p.pid, 0)
        ferr.seek(0)
        err = ferr.read()
    p.returncode = os.waitstatus_to_exitcode(status)
    rows = [json.loads(line[4:]) for line in out.splitlines() if line.startswith("ROW ")]
    row = rows[0] if rows else {"n": n, "phi": phi, "boundary": boundary, "collisions": int(collisions),
                                "error": err[-4000:], "bit_for_bit": False}
    row["child_ru_maxrss_bytes"] = ru.ru_maxrss * 1024
    row["child_exit"] = p.returncode
    row["child_wall_s"] = time.time() - t0
    row["command"] = " ".join(cmd)
    return row


def matrix(args) -> dict:
    c = int(float(args.collisions))
    path = os.path.join(RESULTS, f"lattice_validation_{args.out}.json")
    res = {"command": " ".join([os.path.basename(sys.executable)] + sys.argv), "commit": _git_commit(),
           "build": _build_info(), "dim": DIM, "collisions": c, "mode": args.mode, "law": "flux", "seed": args.seed,
           "tick_bits": args.tick_bits,
           "cell_bits": args.cell_bits, "started_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), "rows": []}
    for phi, n, b, sizes in ((phi, n, b, sizes) for phi in args.phi for n in args.n for b in args.boundary
                             for sizes in args.sizes):  # in the order given: a run cut short still covers both N
        row = run_child(n, phi, b, c, args.seed, args.tick_bits, args.cell_bits, args.mode, sizes, args.gravity, args.shear)
        res["rows"].append(row)
        res["updated_utc"] = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
        _write_atomic(path, res)
        print(json.dumps({k: row.get(k) for k in ("n", "phi", "boundary", "sizes", "collisions", "completed", "bit_for_bit",
                                                  "log_entries", "child_wall_s")}), flush=True)
    res["finished_utc"] = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
    _write_atomic(path, res)
    print("wrote", path)
    return res


# --- equilibrium ------------------------------------------------------------------------------

def equal_speed_start(n: int, phi: float, seed: int, boundary: str = "periodic"):
    """A float start (dimension DIM, every axis periodic or every axis walled) at packing fraction
    phi with every speed equal (kT = 1)."""
    from revcol import _core
    x, v, box = _core.engine_random_state(DIM, int(n), float(phi), [boundary], 1.0, int(seed), 0.0,
                                          _init_for(phi), True)
    return np.asarray(x), np.asarray(v), np.asarray(box, dtype=float).ravel()


def maxwell_cdf(s, kT: float, dim: int):
    """Maxwell-Boltzmann speed CDF, unit mass: 2D 1 - exp(-s^2 / 2kT); 3D erf(s / sqrt(2kT)) -
    sqrt(2 / pi) (s / sqrt(kT)) exp(-s^2 / 2kT)."""
    from scipy import special
    s = np.asarray(s, dtype=float)
    if dim == 2:
        return 1.0 - np.exp(-s ** 2 / (2.0 * kT))
    a = s / math.sqrt(kT)
    return special.erf(a / math.sqrt(2.0)) - math.sqrt(2.0 / math.pi) * a * np.exp(-a * a / 2.0)


def rayleigh_ks(speeds: np.ndarray, kT: float, dim: int = 2):
    """KS of speeds against Maxwell-Boltzmann in dimension dim (2D: the Rayleigh law)."""
    from scipy import stats
    r = stats.kstest(speeds, lambda s: maxwell_cdf(s, kT, dim))
    return float(r.statistic), float(r.pvalue)


def _rate_batches(run, clock, n: int, batch_collisions: int, batches: int) -> list:
    """Collision rates per particle per unit time, 2 dC / (N dt), over consecutive batches of
    about batch_collisions collisions each, run by time (the duration of the first batch, so
    every batch spans the same time)."""
    t0 = clock()
    got = run(collisions=batch_collisions)
    dt = clock() - t0
    rates = []
    for _ in range(batches):
        t0 = clock()
        got = run(time=t0 + dt)
        rates.append(2.0 * got / (n * (clock() - t0)))
    return rates


def equilibrium_gas(n: int, phi: float, seed: int, relax: float, gap: float, snapshots: int,
                    batch: float, batches: int, boundary: str = "periodic") -> dict:
    """One seed: lattice and float engines from the same equal-speed float state; relax, sample
    speeds (lattice) and measure collision rates by batches (both)."""
    import revcol
    LatticeSimulation = _sim_cls()
    x, v, box = equal_speed_start(n, phi, seed, boundary)
    lat = LatticeSimulation(x, v, box, boundary=boundary, seed=seed)
    flt = revcol.Simulation(x, v, box, boundary=boundary, mode="exact", law="flux", seed=seed)
    per = n // 2  # collisions per "collision per particle"
    s_start = np.linalg.norm(lat.velocities, axis=1)
    lat.run(collisions=int(relax * per))
    flt.run(collisions=int(relax * per))
    speeds = []
    for _ in range(snapshots):
        lat.run(collisions=int(gap * per))
        flt.run(collisions=int(gap * per))  # the same age at the batches: a walled gas is still relaxing
        speeds.append(np.linalg.norm(lat.velocities, axis=1))
    lat_run = lambda collisions=None, time=None: lat.run(collisions=collisions, time=time)["collisions"]
    flt_run = lambda collisions=None, time=None: int(flt.run(collisions=collisions, time=time)["collisions"])
    r_lat = _rate_batches(lat_run, lambda: lat.time, n, int(batch * per), batches)
    r_flt = _rate_batches(flt_run, lambda: flt.time, n, int(batch * per), batches)
    d = lat.diagnostics()
    return {"seed": seed, "speeds": np.concatenate(speeds), "start_speeds": s_start,
            "last_snapshot": speeds[-1], "rates_lattice": r_lat, "rates_float": r_flt,
            "lattice_energy_drift": d["energy_drift"], "lattice_log_entries": d["log_entries"],
            "lattice_collisions": lat.collisions,
            "tick": lat.units["tick"], "box": box.tolist()}


def _mean_se(vals) -> tuple:
    a = np.asarray(vals, dtype=float)
    return float(a.mean()), float(a.std(ddof=1) / math.sqrt(len(a))) if len(a) > 1 else float("nan")


def equilibrium_summary(gases: list, n: int) -> dict:
    speeds = np.concatenate([g["speeds"] for g in gases])
    kT = float(np.mean(speeds ** 2) / DIM)  # unit mass: <|v|^2> = dim kT
    ks, p = rayleigh_ks(speeds, kT, DIM)
    ks_last, p_last = rayleigh_ks(gases[0]["last_snapshot"], kT, DIM)
    ks_start, p_start = rayleigh_ks(gases[0]["start_speeds"], kT, DIM)
    lat_seed = [float(np.mean(g["rates_lattice"])) for g in gases]
    flt_seed = [float(np.mean(g["rates_float"])) for g in gases]
    ml, sl = _mean_se(lat_seed)
    mf, sf = _mean_se(flt_seed)
    within_l = [_mean_se(g["rates_lattice"])[1] for g in gases]
    within_f = [_mean_se(g["rates_float"])[1] for g in gases]
    diff = ml - mf
    se = math.hypot(sl, sf)
    return {
        "samples": int(speeds.size), "kT": kT, "ks_stat": ks, "ks_p": p, "ks_pass": p > 1e-3,
        "ks_p_last_snapshot": p_last, "ks_stat_last_snapshot": ks_last,
        "ks_p_equal_speed_start": p_start, "ks_stat_equal_speed_start": ks_start,
        "rate_lattice": ml, "rate_lattice_se": sl, "rate_float": mf, "rate_float_se": sf,
        "rate_lattice_per_seed": lat_seed, "rate_float_per_seed": flt_seed,
        "rate_batch_se_within_seed_lattice": within_l, "rate_batch_se_within_seed_float": within_f,
        "rate_difference": diff, "rate_difference_se": se,
        "rate_difference_sigmas": diff / se if se > 0 else float("inf"),
        "rate_relative_difference": diff / mf,
        "rates_agree_3sigma": abs(diff) <= 3.0 * se,
        "lattice_energy_drift_max": max(abs(g["lattice_energy_drift"]) for g in gases),
        "lattice_log_entries": sum(g["lattice_log_entries"] for g in gases),
        "lattice_collisions": sum(g["lattice_collisions"] for g in gases),
    }


def equilibrium(args) -> dict:
    t0 = time.time()
    gases = []
    for k in range(args.seeds):
        gases.append(equilibrium_gas(args.n, args.phi, args.seed + k, args.relax, args.gap, args.snapshots,
                                     args.batch, args.batches, args.eq_boundary))
        print(f"seed {args.seed + k}: lattice {np.mean(gases[-1]['rates_lattice']):.5f}, "
              f"float {np.mean(gases[-1]['rates_float']):.5f}", flush=True)
    summ = equilibrium_summary(gases, args.n)
    res = {"command": " ".join([os.path.basename(sys.executable)] + sys.argv), "commit": _git_commit(),
           "build": _build_info(), "dim": DIM, "n": args.n, "phi": args.phi, "boundary": args.eq_boundary,
           "start": "equal speeds (kT = 1), positions as engine_random_state", "seeds": args.seeds,
           "relax_per_particle": args.relax, "gap_per_particle": args.gap, "snapshots": args.snapshots,
           "batch_per_particle": args.batch, "batches": args.batches,
           "rate_definition": "2 * collisions / (N * time): collisions per particle per unit time; "
                              "lattice time = clock * tick",
           "error_bar": "standard error of the per-seed means over independent gases",
           "wall_s": time.time() - t0, "loadavg_end": list(os.getloadavg()), **summ}
    path = os.path.join(RESULTS, "lattice_validation_equilibrium.json" if DIM == 2 else f"lattice_validation_{args.out}.json")
    _write_atomic(path, res)
    print(json.dumps({k: v for k, v in res.items() if not isinstance(v, list)}, indent=1))
    print("wrote", path)
    return res


# --- failures -----------------------------------------------------------------------------------

_FAIL = re.compile(r"collision (\d+) of particles (\d+), (\d+) at tick (-?\d+)")


def _third_bodies(sim, i: int, j: int, a: int) -> list:
    """At the state just before the failed collision: every body other than i and j whose gap to
    i or j at ticks a-1, a, a+1 is below 3 ticks' travel of the pair (free flight from the clock;
    a wall reflection in between is not modelled), in units of the pair's largest travel per tick."""
    u = sim.units
    sig = int(u["sigma"])
    box = [int(v) for v in u["L"]]
    x = sim.lattice_positions.astype(object)
    v = sim.lattice_velocities.astype(object)
    d = len(box)
    step = max(math.isqrt(sum(int(v[p][k]) ** 2 for k in range(d))) for p in (i, j))

    def gap(p, q, t):
        r = [int(x[p][k] - x[q][k] + (v[p][k] - v[q][k]) * (t - sim.clock)) for k in range(d)]
        r = [rk if u["wall"][k] else (rk + box[k] // 2) % box[k] - box[k] // 2 for k, rk in enumerate(r)]
        return (math.isqrt(sum(rk * rk for rk in r)) - sig) / step

    out = []
    for q in range(sim.n):
        for p in (i, j):
            if q not in (i, j):
                g = [gap(p, q, t) for t in (a - 1, a, a + 1)]
                if min(g) < 3:
                    out.append({"body": q, "near": p, "gap_ticks_at_a-1_a_a+1": g})
    return out


def group_census(state: dict, top: int = 3, window: int = 100) -> dict:
    """The group collisions held in a state's rare log (resolves and bounces): how often the same
    members met as a group (the most frequent groups, with the first member's collision counts
    at the first and last of them), and the most group collisions of one particle within any
    ``window`` consecutive collisions of its own (the same members again and again is a trap).
    The rare log is keyed per particle (particle, its collision count), so that is the clock."""
    sizes = np.asarray(state["group_size"], dtype=np.int64)
    members = np.asarray(state["group_members"], dtype=np.int64)
    counts = np.asarray(state["group_counts"], dtype=np.int64)
    starts = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int64)
    by, per = {}, {}
    for s0, m in zip(starts.tolist(), sizes.tolist()):
        g = tuple(members[s0:s0 + m].tolist())
        by.setdefault(g, []).append(int(counts[s0]))
        for p, c in zip(g, counts[s0:s0 + m].tolist()):
            per.setdefault(p, []).append(c)
    common = sorted(by.items(), key=lambda kv: -len(kv[1]))[:top]
    most = 0
    for cs in per.values():
        c = np.sort(np.asarray(cs, dtype=np.int64))
        most = max(most, int(np.max(np.searchsorted(c, c + window) - np.arange(c.size))))
    kind = np.asarray(state.get("group_kind", np.zeros(sizes.size)), dtype=np.int64)
    return {"groups": int(sizes.size), "resolves": int(np.sum(kind == 1)), "bounces": int(np.sum(kind == 0)),
            "distinct_groups": len(by), f"most_groups_of_one_particle_in_{window}_of_its_collisions": most,
            "most_frequent": [{"members": list(g), "times": len(ks), "first": min(ks), "last": max(ks)}
                              for g, ks in common]}


def failure_scan(n: int, phi: float, boundary: str, seed: int, collisions: int, chunk: int = 100000) -> dict:
    """Forward only, up to `collisions`, in chunks with a snapshot before each: the first engine
    error (collision index, message) and, rebuilt from the snapshot just before it, the third
    bodies near the failing pair."""
    LatticeSimulation = _sim_cls()
    sim = LatticeSimulation.random(n=n, phi=phi, boundary=boundary, seed=seed, init=_init_for(phi))
    row = {"n": n, "phi": phi, "boundary": boundary, "seed": seed, "collisions_asked": collisions,
           "failed_at": None, "error": None}
    while sim.collisions < collisions:
        snap = sim.snapshot()
        try:
            sim.run(collisions=min(chunk, collisions - sim.collisions))
        except RuntimeError as e:
            row["error"] = str(e)
            break
    row["collisions"] = sim.collisions
    d = sim.diagnostics()
    row.update(log_entries=d["log_entries"], group_resolves=d["group_resolves"], group_bounces=d["group_bounces"],
               multi_body=d["multi_body"],
               redraws=dict(d["redraws"]), groups=group_census(sim.snapshot()))
    m = _FAIL.search(row["error"] or "")
    if m:
        k, i, j, a = (int(g) for g in m.groups())
        row["failed_at"] = k
        sim = LatticeSimulation.from_snapshot(snap)
        sim.run(collisions=k - 1 - sim.collisions)
        row["third_bodies"] = _third_bodies(sim, i, j, a)
    return row


def failures(args) -> dict:
    c = int(float(args.collisions))
    path = os.path.join(RESULTS, f"lattice_validation_{args.out}.json")
    res = {"command": " ".join([os.path.basename(sys.executable)] + sys.argv), "commit": _git_commit(),
           "build": _build_info(), "rows": []}
    for phi in args.phi:
        for b in args.boundary:
            for s in range(args.seed, args.seed + args.seeds):
                res["rows"].append(failure_scan(args.n[0], phi, b, s, c))
                _write_atomic(path, res)
                r = res["rows"][-1]
                print(json.dumps({k: r[k] for k in ("phi", "boundary", "seed", "collisions", "failed_at")}), flush=True)
    print("wrote", path)
    return res


def probe(args) -> dict:
    """Forward only: the rare log's entries and the redraws by reason for each tick T (--ticks,
    0: automatic) and cell resolution (--cells) on each gas: what chooses the defaults."""
    LatticeSimulation = _sim_cls()
    c = int(float(args.collisions))
    path = os.path.join(RESULTS, f"lattice_validation_{args.out}.json")
    res = {"command": " ".join([os.path.basename(sys.executable)] + sys.argv), "commit": _git_commit(),
           "build": _build_info(), "dim": DIM, "collisions": c, "seed": args.seed, "rows": []}
    for phi in args.phi:
        for n in args.n:
            for b in args.boundary:
                for t in args.ticks:
                    for cb in args.cells:
                        t0 = time.time()
                        sim = LatticeSimulation.random(n=n, phi=phi, boundary=b, seed=args.seed, init=_init_for(phi),
                                                       tick_bits=t or None, cell_bits=cb)
                        sim.run(collisions=c)
                        d = sim.diagnostics()
                        row = {"n": n, "phi": phi, "boundary": b, "S": sim.units["S"], "tick_bits": sim.units["tick_bits"],
                               "cell_bits": cb, "collisions": sim.collisions, "log_entries": d["log_entries"],
                               "log_entries_per_collision": d["log_entries"] / max(sim.collisions, 1),
                               "group_entries": d["group_log_entries"], "redraws": dict(d["redraws"]),
                               "energy_drift": d["energy_drift"], "wall_s": time.time() - t0,
                               "loadavg": list(os.getloadavg())}
                        res["rows"].append(row)
                        _write_atomic(path, res)
                        print(json.dumps({k: row[k] for k in ("n", "phi", "boundary", "tick_bits", "cell_bits",
                                                              "log_entries", "group_entries")}), flush=True)
    print("wrote", path)
    return res


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("what", choices=["matrix", "equilibrium", "gas", "failures", "probe"])
    ap.add_argument("--collisions", default="1e7")
    ap.add_argument("--n", type=int, nargs="+", default=None, help="matrix default 1000 10000; equilibrium 1000")
    ap.add_argument("--phi", type=float, nargs="+", default=None, help="matrix default 0.1 0.3 0.5 0.7; equilibrium 0.5")
    ap.add_argument("--boundary", nargs="+", default=["wall", "periodic"], choices=["wall", "periodic", "bounce"])
    ap.add_argument("--mode", default="exact", choices=["exact", "specular"],
                    help="matrix, gas: the lattice engine's mode (exact: the flux law; specular: the deterministic map)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--tick-bits", type=int, default=0,
                    help="matrix, gas: a typical particle moves 2^-T D per tick (0: automatic, the engine's default)")
    ap.add_argument("--cell-bits", type=int, default=16, help="matrix, gas: 2^B direction cells per turn in the pair operator")
    ap.add_argument("--ticks", type=int, nargs="+", default=[0], help="probe: tick_bits to try (0: automatic)")
    ap.add_argument("--cells", type=int, nargs="+", default=[16], help="probe: cell_bits to try")
    ap.add_argument("--out", default="matrix", help="matrix, probe, failures: writes lattice_validation_<out>.json")
    ap.add_argument("--seeds", type=int, default=4, help="equilibrium: independent gases")
    ap.add_argument("--eq-boundary", default="periodic", choices=["periodic", "wall"],
                    help="equilibrium: every axis periodic or every axis walled")
    ap.add_argument("--relax", type=float, default=50.0, help="equilibrium: collisions per particle")
    ap.add_argument("--gap", type=float, default=4.0, help="equilibrium: collisions per particle between snapshots")
    ap.add_argument("--snapshots", type=int, default=10)
    ap.add_argument("--batch", type=float, default=20.0, help="equilibrium: collisions per particle per batch")
    ap.add_argument("--batches", type=int, default=10)
    ap.add_argument("--dim", type=int, default=2, choices=[2, 3], help="2: disks (area fraction); 3: spheres (volume fraction)")
    ap.add_argument("--gravity", type=float, default=0.0,
                    help="matrix, gas: a uniform field along the last axis (walled), float units; 0: none")
    ap.add_argument("--shear", type=float, default=0.0,
                    help="matrix, gas: Lees-Edwards shear rate (float units; x flow, y gradient); 0: none")
    ap.add_argument("--sizes", nargs="+", default=["one"], choices=["one", "binary", "gauss"],
                    help="matrix, gas: a mixture (see the doc)")
    a = ap.parse_args(argv)
    global DIM
    DIM = a.dim
    if a.n is None:
        a.n = [1000] if a.what == "equilibrium" else [1000, 10000]
    if a.phi is None:
        a.phi = [0.5] if a.what == "equilibrium" else [0.1, 0.3, 0.5, 0.7]
    if a.what == "gas":
        a.n, a.phi, a.boundary, a.sizes = a.n[0], a.phi[0], a.boundary[0], a.sizes[0]
        return _child(a)
    os.makedirs(RESULTS, exist_ok=True)
    if a.what == "matrix":
        matrix(a)
    elif a.what == "failures":
        failures(a)
    elif a.what == "probe":
        probe(a)
    else:
        a.n, a.phi = a.n[0], a.phi[0]
        equilibrium(a)
    return 0


if __name__ == "__main__":
    sys.exit(main())
