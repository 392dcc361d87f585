"""Several revcol builds and the peer FSmallenburg/EDMD, interleaved on one equilibrated fluid:
how much a change moved revcol's ratio to the peer, measured in one run (issue 21).

    python bench/peers/fs_edmd_builds.py --n 10976 --phi 0.45 --rounds 3 --cpu 1 \\
        --build old=/tmp/old_pkg --build new=build-dev/pkg [--json bench/results/peer_builds.json]

A build is a folder holding an importable ``revcol`` package (``scripts/dev_build.sh`` stages
one in DIR/pkg); ``NAME=`` (empty) is the ``revcol`` the running Python imports without any
PYTHONPATH. Each round runs the peer, then every build, in alternating order, each a fresh
process pinned to ``--cpu``; the state, the peer's build and the revcol child are
``fs_edmd.py``'s (the same warm-up, the same 2e5 untimed and 1e6 timed collisions).
The ratios are the medians' ratios to the peer's median. Cross-session tables (fs_edmd.py) are
not comparable: the same binary's rate moves by 20% between sessions on a shared host.
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import fs_edmd  # noqa: E402


def _env(path: str) -> dict:
    """The environment of a child that imports the build at ``path`` ('' : the installed one)."""
    env = dict(os.environ)
    env.pop("PYTHONPATH", None)
    if path:
        env["PYTHONPATH"] = os.path.abspath(path)
    return env


def main(argv: list | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--src", default=fs_edmd.DEFAULT_SRC, help="the peer's checkout")
    ap.add_argument("--n", type=int, default=10976)
    ap.add_argument("--phi", type=float, default=0.45)
    ap.add_argument("--build", action="append", required=True, help="NAME=PATH of a staged revcol package")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--collisions", default="1e6")
    ap.add_argument("--warmup-peer", default="2e5")
    ap.add_argument("--cpu", type=int, default=1)
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    builds = []
    for b in args.build:
        name, sep, path = b.partition("=")
        if not sep or not name:
            ap.error(f"--build takes NAME=PATH, got {b!r}")
        if path and not os.path.isdir(os.path.join(path, "revcol")):
            ap.error(f"--build {b!r}: no revcol package in {path}")
        builds.append((name, path))
    c, wpeer = int(float(args.collisions)), int(float(args.warmup_peer))
    try:
        exe = fs_edmd.build_peer(args.src, os.path.join(os.path.dirname(os.path.abspath(args.src)), "build-fs-single"),
                                 wpeer, c)
    except fs_edmd.PeerMissing as e:
        print(str(e))
        return 0
    st = fs_edmd.equilibrated_state(args.n, args.phi, 50.0)
    if not st["fluid"]:
        raise RuntimeError(f"not a fluid after {st['warmup_per_particle']:.0f} collisions per particle")
    runs = {"peer": []}
    runs.update({name: {"forward": [], "reverse": []} for name, _ in builds})
    loads = []
    with tempfile.TemporaryDirectory() as tmp:
        sph, npz = os.path.join(tmp, "init.sph"), os.path.join(tmp, "state.npz")
        fs_edmd.write_sph(sph, st["x"], st["box"])
        np.savez(npz, x=st["x"], v=st["v"], box=st["box"])
        order = ["peer"] + [name for name, _ in builds]
        paths = dict(builds)
        for r in range(args.rounds):
            for who in (order if r % 2 == 0 else order[::-1]):
                loads.append(os.getloadavg()[0])
                if who == "peer":
                    runs["peer"].append(fs_edmd.run_peer(exe, sph, args.cpu))
                else:
                    d = fs_edmd.run_revcol(npz, wpeer, c, args.cpu, env=_env(paths[who]))
                    runs[who]["forward"].append(d["forward"])
                    runs[who]["reverse"].append(d["reverse"])
    peer = statistics.median(runs["peer"])
    out = {"command": " ".join([os.path.basename(sys.executable)] + sys.argv), "n": args.n, "phi": args.phi,
           "peer_commit": fs_edmd.peer_commit(args.src), "rounds": args.rounds, "cpu": args.cpu,
           "s_bragg_after": st["s_bragg_after"], "warmup_per_particle": st["warmup_per_particle"],
           "date_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), "load_before_runs": loads,
           "peer_per_s": fs_edmd._summary(runs["peer"]), "builds": {}}
    print(f"N = {args.n}, phi = {args.phi}: peer {peer / 1e3:.0f}k/s (load {min(loads):.2f}-{max(loads):.2f})")
    for name, path in builds:
        f, b = runs[name]["forward"], runs[name]["reverse"]
        out["builds"][name] = {"path": path or "(installed)", "forward_per_s": fs_edmd._summary(f),
                               "reverse_per_s": fs_edmd._summary(b), "ratio_forward": statistics.median(f) / peer,
                               "ratio_reverse": statistics.median(b) / peer}
        print(f"  {name:12s} forward {statistics.median(f) / 1e3:.0f}k ({min(f) / 1e3:.0f}-{max(f) / 1e3:.0f}) "
              f"ratio {statistics.median(f) / peer:.2f}; reverse {statistics.median(b) / 1e3:.0f}k "
              f"({min(b) / 1e3:.0f}-{max(b) / 1e3:.0f}) ratio {statistics.median(b) / peer:.2f}")
    if args.json:
        fs_edmd._write_json(args.json, out)
        print("wrote", args.json)
    return 0


if __name__ == "__main__":
    sys.exit(main())
