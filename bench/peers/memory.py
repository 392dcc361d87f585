"""Memory per particle: revcol's lattice engine and float engine beside FSmallenburg/EDMD (issue
57). Writes bench/results/peer_memory.json.

    python bench/peers/memory.py [--n 97556 1000000] [--phi 0.30] [--per-particle 2] [--small 4000]
        [--src bench/peers/src/EDMD] [--json bench/results/peer_memory.json]

Each code runs in a fresh process on the same start (revcol's FCC crystal at the volume fraction,
periodic cube, seed 1) for ``--per-particle`` collisions per particle, so that its lists, queue
and logs are in use. A process's memory is its resident set at the end of the run (revcol: VmRSS
read by the child itself; the peer: the maximum resident set the kernel reports for it, which
for a program that allocates once at the start is the same), and the memory per particle is the
growth between ``--small`` particles and N, divided by the difference: the interpreter, numpy,
the C runtime and the binary cancel, and what is left is what the code holds per particle,
including the start's arrays it keeps (revcol's children hold the float64 start, 48 bytes per
particle, as the peer holds its own copy). revcol's children also report what the engine counts
itself (``memory_bytes``). Without the peer's source the script says where it goes and measures
nothing.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from typing import Optional

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import fs_edmd  # noqa: E402

_CHILD = """
import json, sys, numpy as np
def rss():
    with open("/proc/self/status") as f:
        return next(int(l.split()[1]) * 1024 for l in f if l.startswith("VmRSS:"))
d = np.load(sys.argv[1]); engine, per = sys.argv[2], float(sys.argv[3])
if engine == "lattice":
    from revcol.lattice import LatticeSimulation3D as S
else:
    from revcol import Simulation as S
x, v, box = d["x"], d["v"], d["box"]
sim = S(x, v, box, seed=1)
sim.run(collisions=int(per * len(x)))
print("REVCOL_MEMORY " + json.dumps({"rss": rss(), "engine_bytes": int(sim.diagnostics()["memory_bytes"])}))
"""


def child_memory(engine: str, npz: str, per: float) -> dict:
    """One revcol child (``engine``: 'lattice' or 'float'): its resident set at the end and the
    engine's own count, bytes."""
    p = subprocess.run([sys.executable, "-c", _CHILD, npz, engine, str(per)], capture_output=True, text=True)
    if p.returncode != 0:
        raise RuntimeError(f"the {engine} child failed ({p.returncode}):\n{p.stderr[-3000:]}")
    line = next(l for l in p.stdout.splitlines() if l.startswith("REVCOL_MEMORY "))
    return json.loads(line[len("REVCOL_MEMORY "):])


def peer_memory(src: str, tmp: str, n: int, x, box, per: float) -> int:
    """The peer's maximum resident set (bytes) over a run of ``per`` collisions per particle."""
    exe = fs_edmd.build_peer(src, os.path.join(tmp, f"peer_{n}"), 0, int(per * n))
    run_dir = os.path.join(tmp, f"run_{n}")
    os.makedirs(run_dir, exist_ok=True)
    fs_edmd.write_sph(os.path.join(run_dir, "init.sph"), x, box)
    proc = subprocess.Popen([exe], cwd=run_dir, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(proc.pid, 0)
    if status != 0:
        raise RuntimeError(f"the peer failed at N = {n} (status {status})")
    return int(usage.ru_maxrss) * 1024


def start(n: int, phi: float) -> dict:
    from revcol import Simulation
    sim = Simulation.random(n, 3, phi, seed=1, init="crystal")
    return {"x": fs_edmd.wrapped(sim.positions, sim.box), "v": sim.velocities, "box": sim.box}


def measure(args) -> dict:
    import numpy as np
    src = os.path.abspath(args.src)
    res = {"command": " ".join([os.path.basename(sys.executable)] + sys.argv), "peer_commit": fs_edmd.peer_commit(src),
           "revcol_commit": subprocess.run(["git", "-C", fs_edmd.ROOT, "rev-parse", "--short", "HEAD"],
                                           capture_output=True, text=True).stdout.strip(),
           "phi": args.phi, "collisions_per_particle": args.per_particle, "small_n": args.small,
           "started_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), "rows": []}
    with tempfile.TemporaryDirectory() as tmp:
        raw = {}
        for n in [args.small] + list(args.n):
            st = start(n, args.phi)
            npz = os.path.join(tmp, f"state_{n}.npz")
            np.savez(npz, **st)
            raw[n] = {"peer_rss": peer_memory(src, tmp, n, st["x"], st["box"], args.per_particle),
                      "lattice": child_memory("lattice", npz, args.per_particle),
                      "float": child_memory("float", npz, args.per_particle)}
            print(f"N = {n}: {json.dumps(raw[n])}", flush=True)
        s = raw[args.small]
        for n in args.n:
            r, dn = raw[n], n - args.small
            row = {"n": n, "peer_bytes_per_particle": (r["peer_rss"] - s["peer_rss"]) / dn,
                   "lattice_bytes_per_particle": (r["lattice"]["rss"] - s["lattice"]["rss"]) / dn,
                   "float_bytes_per_particle": (r["float"]["rss"] - s["float"]["rss"]) / dn,
                   "lattice_engine_bytes_per_particle": r["lattice"]["engine_bytes"] / n,
                   "float_engine_bytes_per_particle": r["float"]["engine_bytes"] / n, "raw": r}
            res["rows"].append(row)
        res["raw_small"] = s
    res["finished_utc"] = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
    return res


def main(argv: Optional[list] = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--src", default=fs_edmd.DEFAULT_SRC, help="the peer's checkout (FSmallenburg/EDMD)")
    ap.add_argument("--n", type=int, nargs="+", default=[97556, 1000000])
    ap.add_argument("--phi", type=float, default=0.30)
    ap.add_argument("--per-particle", type=float, default=2.0, help="collisions per particle before the reading")
    ap.add_argument("--small", type=int, default=4000, help="the small system whose memory is subtracted")
    ap.add_argument("--json", default=os.path.join(fs_edmd.RESULTS, "peer_memory.json"))
    args = ap.parse_args(argv)
    if not os.path.isfile(os.path.join(os.path.abspath(args.src), "Single", "mdSingle.c")):
        print(fs_edmd.where_to_put(os.path.abspath(args.src)))
        return 0
    res = measure(args)
    fs_edmd._write_json(args.json, res)
    for row in res["rows"]:
        print(f"N = {row['n']}: bytes per particle: peer {row['peer_bytes_per_particle']:.0f}, lattice "
              f"{row['lattice_bytes_per_particle']:.0f} (engine counts {row['lattice_engine_bytes_per_particle']:.0f}), "
              f"float {row['float_bytes_per_particle']:.0f} (engine counts {row['float_engine_bytes_per_particle']:.0f})")
    print("wrote", args.json)
    return 0


if __name__ == "__main__":
    sys.exit(main())
