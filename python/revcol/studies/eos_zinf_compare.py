"""The equation of state measured twice: the engine's Z(inf) against the event chains' Z(inf).

Both extrapolate Z(N) = Z(inf) + a / N through runs at several N, each in its own convention
(the engine's Z_md and the chains' Z_mc differ at finite N, not in the limit). The engine's
come from `python -m revcol.studies.equilibrium finite-size` (one run per size) and from
`python -m revcol.studies.eos_replicas --fit` (replicas at 2D 0.6); the chains' from `python -m revcol.studies.equilibrium
mc-compare`. Prints a markdown table: value, error, and the difference in combined errors.

    python -m revcol.studies.eos_zinf_compare bench/results/equilibrium_finite_size.json \\
        bench/results/eos_replicas_2d_phi0.6_fit.json bench/results/ecmc_compare.json
"""
from __future__ import annotations

import argparse
import json
import math
import sys


def rows(finite_size: dict, replicas_fit: dict, chains: dict) -> list[dict]:
    """One row per engine estimate of Z(inf) that has a chains' Z(inf) at the same (d, phi)."""
    mc = {(r["dim"], r["phi"]): r["z_inf"] for r in chains["infinite_size"]}
    out = []
    for r in finite_size["finite_size"]:
        if (r["dim"], r["phi"]) in mc:
            out.append({"dim": r["dim"], "phi": r["phi"], "law": r["law"], "z_inf": r["z_inf"],
                        "source": "dense, N = " + ", ".join(map(str, r["n"]))})
    files = replicas_fit.get("files", [])
    for law in ("flux", "specular"):
        f = replicas_fit["fits"].get(law)
        if f is not None and (2, 0.6) in mc and any("2d_phi0.6" in p for p in files):
            out.append({"dim": 2, "phi": 0.6, "law": law, "z_inf": [f["z_inf"], f["z_inf_error"]],
                        "source": "replicas, N = " + ", ".join(map(str, replicas_fit["sizes"]))})
    for r in out:
        m = mc[(r["dim"], r["phi"])]
        r["chains_z_inf"] = m
        r["sigmas"] = (r["z_inf"][0] - m[0]) / math.hypot(r["z_inf"][1], m[1])
    return sorted(out, key=lambda r: (r["dim"], r["phi"], r["law"], r["source"]))


def table(rs: list[dict]) -> str:
    lines = ["| d | phi | law | engine runs | engine Z(inf) | chains' Z(inf) | sd |", "|---|---|---|---|---|---|---|"]
    for r in rs:
        lines.append(f"| {r['dim']} | {r['phi']:.2f} | {r['law']} | {r['source']} | {r['z_inf'][0]:.5f} +- "
                     f"{r['z_inf'][1]:.5f} | {r['chains_z_inf'][0]:.5f} +- {r['chains_z_inf'][1]:.5f} | {r['sigmas']:+.1f} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("finite_size", help="JSON of python -m revcol.studies.equilibrium finite-size")
    ap.add_argument("replicas_fit", help="JSON of python -m revcol.studies.eos_replicas --fit")
    ap.add_argument("chains", help="JSON of python -m revcol.studies.equilibrium mc-compare")
    args = ap.parse_args(argv)
    load = lambda p: json.load(open(p))  # noqa: E731
    print(table(rows(load(args.finite_size), load(args.replicas_fit), load(args.chains))))
    return 0


if __name__ == "__main__":
    sys.exit(main())
