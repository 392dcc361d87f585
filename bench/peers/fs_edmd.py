"""revcol's float engine beside the reference specular EDMD code, FSmallenburg/EDMD ("Single"),
on identical equilibrated hard-sphere fluids (issue 21). Writes bench/results/peer_fs_edmd.json.

    python bench/peers/fs_edmd.py [--n 10976 97556] [--phi 0.05 0.10 0.30 0.45]
        [--collisions 1e6] [--pairs 3] [--cpu 1] [--lattice] [--src bench/peers/src/EDMD]

The peer's source is never part of revcol (MIT licence, a separate project): put it at
``bench/peers/src/EDMD`` (git-ignored) or pass ``--src``:

    git clone https://github.com/FSmallenburg/EDMD bench/peers/src/EDMD
    git -C bench/peers/src/EDMD checkout 2d0c862        # the commit issue 21 measured

Without it the script says where the source goes and exits with status 0 having measured
nothing (CI has no network; ``tests/python/test_peers.py`` checks the parts that need no peer).

What it does, per workload (N, packing fraction; 3D, periodic, unit diameter, kT = 1):

1. **The state.** revcol's ``Simulation.random`` (FCC start at these densities), run for
   ``--warmup`` collisions per particle (default 50) with the flux law, and on in steps of that
   length (up to ``--max-warmup``) until it is a fluid: the static structure factor
   S(k) = |sum_j exp(i k . r_j)|^2 / N at the start
   lattice's Bragg vectors (the (111) and (200) families of its FCC cell) must be below 10 (a
   crystal remnant gives ~N; a fluid ~1, at most ~2.9 at the first peak: Hansen-Verlet).
   The positions go to the peer as its ``init.sph`` (``N``, box, then ``a x y z 0.5`` per
   line); the peer draws its own Gaussian velocities at kT = 1 (its ``randommovement``), revcol
   keeps the equilibrated ones: the same positions, the same temperature.
   (At 0.45 the superheated crystal takes hundreds of collisions per particle to melt.)
2. **The peer's build.** Its ``Single/`` sources are copied to a build folder (next to the
   source, git-ignored) and patched, as a peer benchmark must: the thermostat off
   (``usethermostat = 0``), no screen output inside the run (``writeinterval`` 1e30), and a
   timed main loop: ``--warmup-peer`` collisions untimed, then ``--collisions`` collisions timed
   with ``clock_gettime(CLOCK_MONOTONIC)``, printed as ``REVCOL_PEER <collisions> <seconds>``.
   Compiled with the peer's own flags (``-Ofast -funroll-loops -march=native``), as its author
   ships it.
3. **The runs**, each a fresh process pinned to ``--cpu`` (``taskset``), in interleaved pairs
   (peer, revcol; then revcol, peer; ...): revcol times ``run(collisions=C)`` forward and
   ``run_back(collisions=C)`` in-process (the loop is C++; Python only starts it) after its own
   untimed warm-up of the same length as the peer's. The 1-minute load is recorded before each run.
4. **The table**: per workload, median collisions per second of each (forward and reverse for
   revcol) with min..max over pairs, and the ratios revcol / peer of the medians.
5. **With ``--lattice``**, revcol's lattice engine (``LatticeSimulation3D``: integer state, the
   bits-back pair operator) runs in the same rounds as a third code (peer, float, lattice; then
   lattice, float, peer; ...), built from the same equilibrated positions and velocities
   (quantized once, the automatic tick, flux law, seed 1), with the same untimed warm-up and the
   same timed forward and reverse runs. Its run back must end on the bits it started from
   (``lattice_bit_exact``; the script stops otherwise), so the figure is of a real reversal.

The issue's bar is a ratio >= 1.0 forward and reverse at every workload; this script measures,
it does not decide. Run it on a quiet machine: a figure taken under load is not a finding.
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from typing import Optional

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
DEFAULT_SRC = os.path.join(HERE, "src", "EDMD")
RESULTS = os.path.join(ROOT, "bench", "results")
PEER_COMMIT = "2d0c862"

#: the patches applied to the peer's Single/mdSingle.c (old text, new text); each must match once
_TIMED_LOOP = """    long long warm = WARMUP_COLLISIONS, timed = TIMED_COLLISIONS;
    while (colcounter < (unsigned int)warm) step();
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    unsigned int c0 = colcounter;
    while (colcounter - c0 < (unsigned int)timed) step();
    clock_gettime(CLOCK_MONOTONIC, &t1);
    printf("REVCOL_PEER %u %.9f\\n", colcounter - c0, (t1.tv_sec - t0.tv_sec) + 1e-9 * (t1.tv_nsec - t0.tv_nsec));
"""
PATCHES = [
    ("const int usethermostat = 1;", "const int usethermostat = 0;"),
    ("double writeinterval = 1;", "double writeinterval = 1e30;"),
    ("double maxtime = 100;", "double maxtime = 1e30;"),
    ("    while (simtime <= maxtime)\n    {\n      step();\n    }\n", _TIMED_LOOP),
    ("#include <string.h>\n", "#include <string.h>\n#include <time.h>\n"),
]


class PeerMissing(RuntimeError):
    """The peer's source is not where the benchmark looks for it."""


def where_to_put(src: str) -> str:
    """The message for a missing peer: where its source goes and how to get it."""
    return (f"FSmallenburg/EDMD not found at {src} (its Single/mdSingle.c). The peer is not part of revcol; "
            f"get it with:\n  git clone https://github.com/FSmallenburg/EDMD {src}\n"
            f"  git -C {src} checkout {PEER_COMMIT}\nand run this again (or pass --src).")


def patch_source(text: str, warmup: int, collisions: int) -> str:
    """The peer's mdSingle.c with the benchmark's patches; ValueError naming the first patch
    whose text is not found exactly once (a different version of the peer)."""
    for old, new in PATCHES:
        if text.count(old) != 1:
            raise ValueError(f"peer source: expected one {old.strip().splitlines()[0]!r}, found {text.count(old)} "
                             f"(this script patches commit {PEER_COMMIT})")
        text = text.replace(old, new)
    return (text.replace("WARMUP_COLLISIONS", str(int(warmup)))
                .replace("TIMED_COLLISIONS", str(int(collisions))))


def build_peer(src: str, build: str, warmup: int, collisions: int, extra_flags: Optional[list] = None) -> str:
    """Copies Single/ to ``build``, patches it, compiles it with the peer's flags (and
    ``extra_flags``, e.g. ``-g`` for a profile); the binary."""
    single = os.path.join(src, "Single")
    if not os.path.isfile(os.path.join(single, "mdSingle.c")):
        raise PeerMissing(where_to_put(src))
    os.makedirs(build, exist_ok=True)
    for f in ("mdSingle.c", "mdSingle.h", "mt19937ar.c"):
        shutil.copy(os.path.join(single, f), os.path.join(build, f))
    path = os.path.join(build, "mdSingle.c")
    with open(path) as fh:
        text = fh.read()
    with open(path, "w") as fh:
        fh.write(patch_source(text, warmup, collisions))
    exe = os.path.join(build, f"md_{warmup}_{collisions}")
    subprocess.run(["gcc", "-Wall", "-Ofast", "-funroll-loops", "-march=native"] + list(extra_flags or []) +
                   ["mdSingle.c", "-o", os.path.basename(exe), "-lm"], cwd=build, check=True, capture_output=True)
    return exe


def write_sph(path: str, x: np.ndarray, box: np.ndarray, diameter: float = 1.0) -> None:
    """The peer's input format: N, the box, then ``a x y z radius`` per particle (atomically)."""
    from revcol._io import atomic_open
    with atomic_open(path) as fh:
        fh.write(f"{len(x)}\n{box[0]:.17g} {box[1]:.17g} {box[2]:.17g}\n")
        for p in x:
            fh.write(f"a {p[0]:.17g} {p[1]:.17g} {p[2]:.17g} {diameter / 2:.17g}\n")


def read_sph(path: str) -> tuple[np.ndarray, np.ndarray]:
    """Positions and box from an ``.sph`` file (the inverse of write_sph, for tests)."""
    with open(path) as fh:
        n = int(fh.readline())
        box = np.array([float(t) for t in fh.readline().split()])
        x = np.array([[float(t) for t in fh.readline().split()[1:4]] for _ in range(n)])
    return x, box


def fcc_bragg_vectors(n: int, box: np.ndarray) -> np.ndarray:
    """The (111) and (200) reciprocal vectors of the FCC cell revcol's start uses for n
    particles in this cubic box (4 m^3 = n sites, m cells per side)."""
    m = round((n / 4) ** (1 / 3))
    if 4 * m ** 3 != n:
        raise ValueError(f"N = {n} is not 4 m^3: not an FCC start (use N = 4 m^3, e.g. 10976 = 4 * 14^3)")
    g = 2 * np.pi * m / box[0]
    fam = [(sx, sy, sz) for sx in (1, -1) for sy in (1, -1) for sz in (1, -1)]
    fam += [(2, 0, 0), (0, 2, 0), (0, 0, 2)]
    return g * np.array(fam, dtype=float)


def wrapped(x: np.ndarray, box: np.ndarray) -> np.ndarray:
    """Positions folded into [0, box) on every axis (a rounding that lands on box goes to 0)."""
    y = x - np.floor(x / box) * box
    return np.where(y >= box, 0.0, y)


def structure_factor(x: np.ndarray, k: np.ndarray) -> np.ndarray:
    """S(k) = |sum_j exp(i k . r_j)|^2 / N for each row of k."""
    ph = x @ k.T
    return (np.cos(ph).sum(axis=0) ** 2 + np.sin(ph).sum(axis=0) ** 2) / len(x)


def equilibrated_state(n: int, phi: float, warmup_per_particle: float, seed: int = 1,
                       max_per_particle: float = 2000.0) -> dict:
    """revcol's random start, run for warm-up collisions per particle, then on in steps of the
    same length until the start lattice's Bragg peaks have melted (S(k) < 10 at every Bragg
    vector; a superheated FCC at 0.45 takes hundreds of collisions per particle) or
    max_per_particle is reached; positions, velocities, box, S(k) before and after, the
    collisions per particle it took."""
    from revcol import Simulation
    sim = Simulation.random(n, 3, phi, seed=seed, init="crystal")
    k = fcc_bragg_vectors(n, sim.box)
    s_before = float(structure_factor(sim.positions, k).max())
    t0 = time.time()
    step, done = int(warmup_per_particle * n / 2), 0
    while True:
        sim.run(collisions=step)
        done += step
        x = wrapped(sim.positions, sim.box)  # the engine wraps lazily (at list renewals)
        s_after = float(structure_factor(x, k).max())
        if s_after < 10.0 or 2.0 * done / n >= max_per_particle:
            break
    return {"x": x, "v": sim.velocities, "box": sim.box, "s_bragg_start": s_before,
            "s_bragg_after": s_after, "fluid": s_after < 10.0, "warmup_per_particle": 2.0 * done / n,
            "warmup_s": time.time() - t0}


def _pin(cmd: list, cpu: int) -> list:
    return (["taskset", "-c", str(cpu)] + cmd) if cpu >= 0 else cmd


def run_peer(exe: str, sph: str, cpu: int) -> float:
    """One peer process on init.sph: collisions per second of its timed loop."""
    with tempfile.TemporaryDirectory() as tmp:
        shutil.copy(sph, os.path.join(tmp, "init.sph"))
        p = subprocess.run(_pin([exe], cpu), cwd=tmp, capture_output=True, text=True)
        if p.returncode != 0:
            raise RuntimeError(f"the peer failed ({p.returncode}):\n{(p.stdout + p.stderr)[-3000:]}")
        out = p.stdout
    for line in out.splitlines():
        if line.startswith("REVCOL_PEER "):
            _, c, s = line.split()
            return int(c) / float(s)
    raise RuntimeError(f"the peer printed no REVCOL_PEER line:\n{out[-2000:]}")


_REVCOL_CHILD = """
import json, sys, time, numpy as np
from revcol import Simulation
d = np.load(sys.argv[1])
sim = Simulation(d["x"], d["v"], d["box"], seed=1)
w, c = int(sys.argv[2]), int(sys.argv[3])
sim.run(collisions=w)
t0 = time.perf_counter(); sim.run(collisions=c); t1 = time.perf_counter()
sim.run_back(collisions=c); t2 = time.perf_counter()
print("REVCOL_SELF " + json.dumps({"forward": c / (t1 - t0), "reverse": c / (t2 - t1)}))
"""


def _run_child(who: str, script: str, tag: str, state_npz: str, warmup: int, collisions: int, cpu: int,
               env: Optional[dict]) -> dict:
    """Runs a timing child (``python -c script state warmup collisions``) pinned to ``cpu`` and
    returns the JSON it prints after ``tag``; a failure or a missing line is a RuntimeError
    naming ``who``."""
    p = subprocess.run(_pin([sys.executable, "-c", script, state_npz, str(warmup), str(collisions)], cpu),
                       capture_output=True, text=True, env=env)
    if p.returncode != 0:
        raise RuntimeError(f"the {who} child failed ({p.returncode}):\n{p.stderr[-3000:]}")
    for line in p.stdout.splitlines():
        if line.startswith(tag + " "):
            return json.loads(line[len(tag) + 1:])
    raise RuntimeError(f"the {who} child printed no {tag} line:\n{p.stdout[-2000:]}")


def run_revcol(state_npz: str, warmup: int, collisions: int, cpu: int, env: Optional[dict] = None) -> dict:
    """One revcol process (the float engine, exact mode, flux law, Philox): forward and reverse
    collisions per second of the timed run after an untimed warm-up. ``env``: the child's
    environment (default: this process's), e.g. a PYTHONPATH naming another build."""
    return _run_child("revcol", _REVCOL_CHILD, "REVCOL_SELF", state_npz, warmup, collisions, cpu, env)


_LATTICE_CHILD = """
import json, sys, time, numpy as np
from revcol.lattice import LatticeSimulation3D
d = np.load(sys.argv[1])
sim = LatticeSimulation3D(d["x"], d["v"], d["box"], seed=1)
w, c = int(sys.argv[2]), int(sys.argv[3])
sim.run(collisions=w)
x0, v0 = sim.lattice_positions.copy(), sim.lattice_velocities.copy()
t0 = time.perf_counter(); sim.run(collisions=c); t1 = time.perf_counter()
sim.run_back(collisions=c); t2 = time.perf_counter()
exact = bool(np.array_equal(x0, sim.lattice_positions) and np.array_equal(v0, sim.lattice_velocities))
print("REVCOL_LATTICE " + json.dumps({"forward": c / (t1 - t0), "reverse": c / (t2 - t1), "bit_exact": exact}))
"""


def run_lattice(state_npz: str, warmup: int, collisions: int, cpu: int, env: Optional[dict] = None) -> dict:
    """One process of revcol's lattice engine (3D, periodic, flux, seed 1) on the state's
    positions and velocities: forward and reverse collisions per second of the timed run after
    an untimed warm-up, and whether the run back ended on the bits the timed run started from."""
    return _run_child("lattice", _LATTICE_CHILD, "REVCOL_LATTICE", state_npz, warmup, collisions, cpu, env)


def peer_commit(src: str) -> str:
    """The peer checkout's commit, or 'unknown (not a git checkout)'. Only a folder that is its
    own repository's top level counts: git asked inside an unpacked archive (no .git) placed in
    revcol's tree would answer with revcol's commit."""
    def git(*a: str) -> str:
        return subprocess.run(["git", "-C", src, *a], capture_output=True, text=True).stdout.strip()
    top = git("rev-parse", "--show-toplevel")
    if not top or os.path.realpath(top) != os.path.realpath(src):
        return "unknown (not a git checkout)"
    return git("rev-parse", "--short", "HEAD") or "unknown (not a git checkout)"


def _summary(vals: list) -> dict:
    return {"median": float(np.median(vals)), "min": float(min(vals)), "max": float(max(vals)), "runs": vals}


def measure(args, src: str) -> dict:
    c, wpeer = int(float(args.collisions)), int(float(args.warmup_peer))
    build = os.path.join(os.path.dirname(os.path.abspath(src)), "build-fs-single")
    exe = build_peer(src, build, wpeer, c)
    res = {"command": " ".join([os.path.basename(sys.executable)] + sys.argv), "peer": "FSmallenburg/EDMD Single",
           "peer_commit": peer_commit(src),
           "revcol_commit": subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True,
                                           text=True).stdout.strip(),
           "collisions_timed": c, "warmup_collisions": wpeer, "pairs": args.pairs, "cpu": args.cpu,
           "started_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), "workloads": []}
    with tempfile.TemporaryDirectory() as tmp:
        for n in args.n:
            for phi in args.phi:
                st = equilibrated_state(n, phi, args.warmup, max_per_particle=args.max_warmup)
                if not st["fluid"]:
                    raise RuntimeError(f"N = {n}, phi = {phi}: S(k) at the start's Bragg vectors is still "
                                       f"{st['s_bragg_after']:.3g} after {st['warmup_per_particle']:.0f} collisions per "
                                       "particle: not a fluid (raise --max-warmup)")
                sph, npz = os.path.join(tmp, "init.sph"), os.path.join(tmp, "state.npz")
                write_sph(sph, st["x"], st["box"])
                np.savez(npz, x=st["x"], v=st["v"], box=st["box"])
                peer, fwd, rev, loads, lfwd, lrev = [], [], [], [], [], []
                codes = ("peer", "revcol", "lattice") if args.lattice else ("peer", "revcol")
                for p in range(args.pairs):
                    for who in (codes if p % 2 == 0 else codes[::-1]):
                        loads.append(os.getloadavg()[0])
                        if who == "peer":
                            peer.append(run_peer(exe, sph, args.cpu))
                        elif who == "revcol":
                            r = run_revcol(npz, wpeer, c, args.cpu)
                            fwd.append(r["forward"])
                            rev.append(r["reverse"])
                        else:
                            r = run_lattice(npz, wpeer, c, args.cpu)
                            if not r["bit_exact"]:
                                raise RuntimeError(f"N = {n}, phi = {phi}: the lattice engine's run back did not "
                                                   "end on the bits it started from")
                            lfwd.append(r["forward"])
                            lrev.append(r["reverse"])
                row = {"n": n, "phi": phi, "s_bragg_start": st["s_bragg_start"], "s_bragg_after": st["s_bragg_after"],
                       "warmup_per_particle": st["warmup_per_particle"],
                       "peer_per_s": _summary(peer), "revcol_forward_per_s": _summary(fwd),
                       "revcol_reverse_per_s": _summary(rev),
                       "ratio_forward": float(np.median(fwd) / np.median(peer)),
                       "ratio_reverse": float(np.median(rev) / np.median(peer)),
                       "load_before_runs": loads}
                if args.lattice:
                    row.update({"lattice_forward_per_s": _summary(lfwd), "lattice_reverse_per_s": _summary(lrev),
                                "lattice_bit_exact": True,
                                "ratio_lattice_forward": float(np.median(lfwd) / np.median(peer)),
                                "ratio_lattice_reverse": float(np.median(lrev) / np.median(peer))})
                res["workloads"].append(row)
                _write_json(args.json, res)  # after every workload: a run cut short keeps what it measured
                print(json.dumps({k: row[k] for k in ("n", "phi", "ratio_forward", "ratio_reverse",
                                                      "ratio_lattice_forward", "ratio_lattice_reverse") if k in row}),
                      flush=True)
    res["finished_utc"] = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
    return res


def _write_json(path: str, res: dict) -> None:
    from revcol._io import atomic_open
    with atomic_open(path) as fh:
        json.dump(res, fh, indent=1)


def main(argv: Optional[list] = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--src", default=DEFAULT_SRC, help="the peer's checkout (FSmallenburg/EDMD)")
    ap.add_argument("--n", type=int, nargs="+", default=[10976, 97556])
    ap.add_argument("--phi", type=float, nargs="+", default=[0.05, 0.10, 0.30, 0.45])
    ap.add_argument("--collisions", default="1e6", help="timed collisions per run")
    ap.add_argument("--warmup-peer", default="2e5", help="untimed collisions before the timing, in each run")
    ap.add_argument("--warmup", type=float, default=50.0, help="collisions per particle that equilibrate the state")
    ap.add_argument("--max-warmup", type=float, default=2000.0,
                    help="collisions per particle at most, in steps of --warmup, until the start lattice has melted")
    ap.add_argument("--pairs", type=int, default=3, help="interleaved (peer, revcol) pairs per workload")
    ap.add_argument("--cpu", type=int, default=1, help="core each run is pinned to (-1: none)")
    ap.add_argument("--lattice", action="store_true",
                    help="also run revcol's lattice engine (3D, integer state) in the same rounds")
    ap.add_argument("--json", default=os.path.join(RESULTS, "peer_fs_edmd.json"))
    args = ap.parse_args(argv)
    try:
        res = measure(args, args.src)
    except PeerMissing as e:
        print(str(e))
        return 0
    _write_json(args.json, res)
    print("wrote", args.json)
    return 0


if __name__ == "__main__":
    sys.exit(main())
