"""The paper's randomness experiment (§5.2): post-collision chart coordinates as 32-bit words,
run through a Diehard-class battery (``dieharder``), with controls that must fail and pass.

A chain of collisions (the paper's Reversal Illustration run forward: invariants held, the
post velocities negated to make the next collision) maps each post state x to its chart
coordinates u = F(x) in [0,1)^(d_n), F the measure-preserving chart of the law (each
coordinate is the CDF value of one one-dimensional law), and writes floor(u 2^32) as raw
uint32 words, the format ``dieharder -g 201 -f FILE`` reads. Under the operator's law the
words are uniform; through the other law's CDF, or from a biased operator, they are not.
Paper mode is read through the exact uniform law's chart: the paper's stated law (uniform
on the permitted set, uniform in its angles on a round circle for pair2d and triple1d).
The cases gas2d and gas3d are the float engine's pair collisions in a periodic gas (exact
mode): the direction of each post relative velocity about its contact normal, read through
the law's CDF (revcol/studies/randomness.hpp).

The battery runs the paper's tests by dieharder number (``PAPER_TESTS``), one process per
test and each from the start of the file, without dieharder's ``rate`` output field (its
timing run reads, and rewinds, the file before the test). On a short file (the paper's
3 x 10^6 words) psamples is lowered until the test does not rewind; on a long file
(>= 2.4 x 10^8 words) every test runs with dieharder's defaults without rewinding. A WEAK
result (p < 0.005 or p > 0.995) is rerun on a fresh file from another seed; dieharder
calls p < 1e-6 (or > 1 - 1e-6) FAILED. All p-values of a run then get one Kolmogorov-Smirnov
test against the uniform law.

Command line (``python -m revcol.studies.randomness``, also ``revcol study randomness``)::

    python -m revcol.studies.randomness battery --case pair2d --mode exact --law flux --rng philox --words 3000000
    python -m revcol.studies.randomness battery --case gas2d --particles 1000 --fraction 0.2 --words 3000000
    python -m revcol.studies.randomness controls --words 3000000
    python -m revcol.studies.randomness matrix --words 3000000 --json bench/results/randomness_3e6.json
    python -m revcol.studies.randomness coverage --out docs/figures/randomness
    python -m revcol.studies.randomness table bench/results/randomness_paper_cases_3e6.json [--detail]

    >>> import revcol.studies.randomness as R
    >>> w = R.stream("pair2d", mode="exact", law="flux", rng="philox").words(4)
    >>> w.dtype.name, len(w)
    ('uint32', 4)
"""
from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from typing import Any, Optional, Sequence

import numpy as np

from .._io import atomic_open
from .coverage import coverage
from .words import GAS_FRACTION, GAS_PARTICLES, GAS_WARMUP, stream, stream_cases, write_words

__all__ = ["PAPER_TESTS", "CI_TESTS", "stream", "stream_cases", "write_words", "has_dieharder",
           "run_test", "battery", "controls", "ks_uniform", "coverage", "table", "marginals", "main"]

#: the paper's Diehard tests as dieharder numbers: runs, craps, 3D spheres, minimum distance,
#: parking lot, squeeze, birthdays, and the 32x32 and 6x8 binary rank tests. (The paper's
#: SUMS test is dieharder -d 14, which dieharder marks "Do Not Use": a known bug.)
PAPER_TESTS = {15: "runs", 16: "craps", 12: "3d spheres", 11: "minimum distance (2d circle)",
               10: "parking lot", 13: "squeeze", 0: "birthdays", 2: "rank 32x32", 3: "rank 6x8"}
#: the reduced battery of the CI test
CI_TESTS = (15, 12, 10)

_FIELDS = ["-D", "test_name", "-D", "ntuple", "-D", "tsamples", "-D", "psamples", "-D", "pvalues",
           "-D", "assessment"]


def has_dieharder() -> bool:
    """Whether the dieharder binary is on PATH."""
    return shutil.which("dieharder") is not None


_LINE = re.compile(r"^\s*(\S+)\|\s*(\d+)\|\s*(\d+)\|\s*(\d+)\|\s*([0-9.eE+-]+)\|\s*(\w+)\s*$")
_REWOUND = re.compile(r"rewound (\d+) times")


def parse(output: str) -> dict:
    """dieharder's table (the fields of ``_FIELDS``) as a dict: rows of (name, ntuple,
    tsamples, psamples, p, assessment) and the number of times the file was rewound."""
    rows = []
    for line in output.splitlines():
        m = _LINE.match(line)
        if m:
            rows.append({"name": m.group(1), "ntuple": int(m.group(2)), "tsamples": int(m.group(3)),
                         "psamples": int(m.group(4)), "p": float(m.group(5)), "assessment": m.group(6)})
    m = _REWOUND.search(output)
    return {"rows": rows, "rewound": int(m.group(1)) if m else 0}


#: below this many psamples dieharder's final KS of the psample p-values is wrong (2 or 3
#: psamples of /dev/urandom give p = 1.00000000, FAILED): such a test runs instead once
#: (-p 1) on each of that many disjoint segments of the file, every p-value reported, as the
#: paper's Diehard ran its tests once or twice
MIN_PSAMPLES = 10


def _dieharder(path: str, test: int, psamples: Optional[int], nice: bool) -> tuple[dict, list[str]]:
    cmd = (["nice", "-n", "10"] if nice else []) + ["dieharder", "-g", "201", "-f", path, "-d", str(test)]
    cmd += _FIELDS + (["-p", str(psamples)] if psamples else [])
    done = subprocess.run(cmd, capture_output=True, text=True, check=True)
    out = done.stdout + done.stderr  # the rewind notice is on stderr
    r = parse(out)
    if not r["rows"]:
        raise RuntimeError(f"dieharder -d {test} printed no result:\n{out}")
    return r, cmd[3:] if nice else cmd


def run_test(path: str, test: int, *, psamples: Optional[int] = None, fit: bool = True,
             nice: bool = True) -> dict:
    """One dieharder test on a raw file. With ``fit``, a run that rewinds the file is redone
    with fewer psamples (scaled down by the rewinds, 10% margin) until it does not; when
    that leaves fewer than MIN_PSAMPLES, the test runs with -p 1 on that many segments."""
    while True:
        r, cmd = _dieharder(path, test, psamples, nice)
        used = r["rows"][0]["psamples"]
        if not fit or r["rewound"] == 0 or used == 1:
            break
        psamples = max(1, int(used * 0.9 / (r["rewound"] + 1)))
    if fit and 1 < used < MIN_PSAMPLES:
        words = np.memmap(path, dtype="<u4", mode="r")
        size = len(words) // used
        rows, rewound = [], 0
        for k in range(used):
            seg = f"{path}.seg{k}"
            np.asarray(words[k * size:(k + 1) * size]).tofile(seg)
            try:
                rk, cmd = _dieharder(seg, test, 1, nice)
            finally:
                os.remove(seg)
            rows += rk["rows"]
            rewound += rk["rewound"]
        del words
        r = {"rows": rows, "rewound": rewound, "segments": used}
        cmd[cmd.index(seg)] = f"SEGMENT_OF_{size}_WORDS"
        used = 1
    r.update(test=test, name=PAPER_TESTS.get(test, r["rows"][0]["name"]), psamples=used,
             command=" ".join(cmd))
    return r


def ks_uniform(p: Sequence[float]) -> float:
    """Kolmogorov-Smirnov p-value of a sample against the uniform law on [0, 1]."""
    from scipy import stats  # optional (the test extra) and slow to import

    return float(stats.kstest(np.asarray(p, float), "uniform").pvalue) if len(p) else float("nan")


def _verdict(rows: Sequence[dict]) -> str:
    a = {r["assessment"] for r in rows}
    return "FAILED" if "FAILED" in a else "WEAK" if "WEAK" in a else "PASSED"


def battery(config: dict, words: int, tests: Sequence[int] = tuple(PAPER_TESTS), *,
            workdir: Optional[str] = None, rerun_seed: int = 1000, fit: bool = True,
            keep: bool = False) -> dict:
    """Writes ``words`` words of ``stream(**config)`` and runs each test; a WEAK test is rerun
    on a fresh file (seed + rerun_seed), and its final verdict is the rerun's. Returns the
    per-test results, the KS p-value of all first-run p-values and the overall verdict
    (FAILED if any test's final verdict is FAILED or WEAK)."""
    workdir = workdir or tempfile.gettempdir()
    tag = "-".join(str(config.get(k, "")) for k in ("case", "mode", "law", "rng", "seed"))
    path = os.path.join(workdir, f"revcol-words-{tag}-{os.getpid()}.bin")
    info = write_words(path, words, **config)
    t0 = time.perf_counter()
    results, rerun_path = [], None
    try:
        for t in tests:
            r = run_test(path, t, fit=fit)
            r["verdict"] = _verdict(r["rows"])
            if r["verdict"] == "WEAK":
                if rerun_path is None:
                    rerun_path = path + ".rerun"
                    cfg = dict(config, seed=int(config.get("seed", 0)) + rerun_seed)
                    info["rerun"] = write_words(rerun_path, words, **cfg)
                r2 = run_test(rerun_path, t, psamples=None if fit else r["psamples"], fit=fit)
                r["rerun"] = {"rows": r2["rows"], "rewound": r2["rewound"], "seed_offset": rerun_seed,
                              "command": r2["command"]}
                r["verdict"] = "WEAK then " + _verdict(r2["rows"])
            results.append(r)
    finally:
        for p in (path, rerun_path):
            if p and os.path.exists(p) and not keep:
                os.remove(p)
    pvals = [row["p"] for r in results for row in r["rows"]]
    final = [r["verdict"].split()[-1] for r in results]
    overall = "FAILED" if "FAILED" in final else "WEAK" if "WEAK" in final else "PASSED"
    return {"config": dict(config), "words": int(words), "stream": info, "tests": results,
            "pvalues": pvals, "ks_p": ks_uniform(pvals), "verdict": overall,
            "battery_s": round(time.perf_counter() - t0, 2)}


def controls(words: int, tests: Sequence[int] = tuple(PAPER_TESTS), **kw: Any) -> list[dict]:
    """The battery's controls: raw CLCG4 and Philox (must pass), raw RANDU and the exact pair2d
    chain driven by RANDU and by philox-repeat100 (the bad ones)."""
    out = []
    for case, rng in (("raw", "clcg4"), ("raw", "philox"), ("raw", "randu"), ("pair2d", "randu"),
                      ("raw", "philox-repeat100"), ("pair2d", "philox-repeat100")):
        out.append(battery({"case": case, "mode": "exact", "law": "flux", "rng": rng, "seed": 1}, words,
                           tests, **kw))
    return out


def _run_info(argv: Sequence[str], t0: float) -> dict:
    def sh(cmd: list[str]) -> str:
        try:
            return subprocess.run(cmd, capture_output=True, text=True, check=True).stdout.strip()
        except (OSError, subprocess.CalledProcessError):
            return ""

    return {"command": "python -m revcol.studies.randomness " + " ".join(argv),
            "commit": sh(["git", "rev-parse", "--short", "HEAD"]), "uptime": sh(["uptime"]),
            "wall_s": round(time.perf_counter() - t0, 1),
            "dieharder": " ".join(re.findall(r"dieharder version \S+", sh(["dieharder", "-l"]))[:1])}


def _summary(b: dict) -> str:
    c = b["config"]
    tests = " ".join(f"{r['test']}:{r['verdict']}" for r in b["tests"])
    return (f"{c['case']:12s} {c['mode']:5s} {c['law']:7s} {c['rng']:16s} {b['verdict']:6s} "
            f"KS p={b['ks_p']:.3f}  restarts={b['stream']['restarts']}  {tests}")


def table(runs: Sequence[dict], detail: bool = False) -> str:
    """Markdown: one row per battery (verdict, KS of its p-values, extremes, WEAK tests and
    their reruns); with ``detail``, one row per test and p-value column per battery."""
    if detail:
        head = ["test"] + [f"{r['config']['case']} {r['config']['mode']} {r['config']['law']} "
                           f"{r['config']['rng']}" for r in runs]
        lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        for i, t in enumerate(runs[0]["tests"]):
            cells = [f"{t['name']} (-d {t['test']})"]
            for r in runs:
                rt = r["tests"][i]
                ps = ", ".join(f"{row['p']:.4f}" for row in rt["rows"])
                if "rerun" in rt:
                    ps += " (WEAK; rerun: " + ", ".join(f"{row['p']:.4f}" for row in rt["rerun"]["rows"]) + ")"
                cells.append(ps)
            lines.append("| " + " | ".join(cells) + " |")
        return "\n".join(lines)
    lines = ["| case | mode | law | rng | words | restarts | n p | min p | max p | KS p | WEAK (rerun) | verdict |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in runs:
        c = r["config"]
        weak = "; ".join(f"-d {t['test']}: {t['verdict']}" for t in r["tests"] if "rerun" in t) or "-"
        p = r["pvalues"]
        lost = (f"{r['stream'].get('skipped', 0)} groups" if c["case"].startswith("gas")
                else r["stream"]["restarts"])
        lines.append(f"| {c['case']} | {c['mode']} | {c['law']} | {c['rng']} | {r['words']:.2g} | "
                     f"{lost} | {len(p)} | {min(p):.2g} | {max(p):.4f} | {r['ks_p']:.3f} | "
                     f"{weak} | **{r['verdict']}** |")
    return "\n".join(lines)


def marginals(config: dict, words: int = 3_000_000) -> dict:
    """One-sample KS of each chart coordinate of the first ``words`` words of a stream against
    the uniform law: D, sqrt(n) D and p per coordinate. A battery failure with a large D is
    the law's (the operator's or the chart's), not the generator's."""
    from scipy import stats  # optional (the test extra) and slow to import

    s = stream(**config)
    w = s.words(int(words) - int(words) % s.width).reshape(-1, s.width)
    out = []
    for k in range(s.width):
        r = stats.kstest((w[:, k] + 0.5) / 2.0**32, "uniform")
        out.append({"D": float(r.statistic), "K": float(r.statistic * np.sqrt(len(w))), "p": float(r.pvalue)})
    return {"config": dict(config), "words": int(w.size), "restarts": int(s.restarts), "coordinates": out}


def _tests(spec: str) -> list[int]:
    return list(PAPER_TESTS) if spec == "paper" else [int(t) for t in spec.split(",")]


def _matrix_configs(cases: Sequence[str], modes: Sequence[str], laws: Sequence[str],
                    rngs: Sequence[str], gas: Optional[dict] = None) -> list[dict]:
    out = []
    for mode in modes:
        known = stream_cases(mode)
        for case in cases:
            if case not in known:
                continue
            for law in (laws if mode == "exact" else ["uniform"]):
                for rng in rngs:
                    out.append(_gas_options({"case": case, "mode": mode, "law": law, "rng": rng, "seed": 1}, gas))
    return out


def _gas_options(cfg: dict, gas: Optional[dict]) -> dict:
    """cfg with the gas options (particles, fraction, warmup) when its case is a gas."""
    if not cfg["case"].startswith("gas"):
        return cfg
    g = {"particles": GAS_PARTICLES, "fraction": GAS_FRACTION, "warmup": GAS_WARMUP}
    g.update({k: v for k, v in (gas or {}).items() if v is not None})
    return dict(cfg, particles=int(g["particles"]), fraction=float(g["fraction"]), warmup=float(g["warmup"]))


def main(argv: Optional[Sequence[str]] = None, prog: str = "python -m revcol.studies.randomness") -> int:
    """The command line (see the module docstring)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    ap = argparse.ArgumentParser(prog=prog, description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("--words", type=float, default=3e6)
    common.add_argument("--tests", default="paper", help="'paper' or dieharder numbers, e.g. 15,12")
    common.add_argument("--json", help="write the results here")
    common.add_argument("--workdir", help="where the word files go (default: the temp dir)")
    common.add_argument("--defaults", action="store_true",
                        help="dieharder's default psamples (a long file); otherwise fit them to the file")
    gas_args = argparse.ArgumentParser(add_help=False)
    gas_args.add_argument("--particles", type=int, help=f"gas cases: N (default {GAS_PARTICLES})")
    gas_args.add_argument("--fraction", type=float, help=f"gas cases: packing fraction (default {GAS_FRACTION})")
    gas_args.add_argument("--warmup", type=float,
                          help=f"gas cases: collisions per particle before the first word (default {GAS_WARMUP})")
    b = sub.add_parser("battery", parents=[common, gas_args], help="one case")
    b.add_argument("--case", default="pair2d")
    b.add_argument("--mode", default="exact")
    b.add_argument("--law", default="flux")
    b.add_argument("--rng", default="philox")
    b.add_argument("--seed", type=int, default=1)
    sub.add_parser("controls", parents=[common], help="the good and bad controls")
    m = sub.add_parser("matrix", parents=[common, gas_args], help="case x mode x law x rng")
    m.add_argument("--cases", default="pair2d,triple1d")
    m.add_argument("--modes", default="exact,paper")
    m.add_argument("--laws", default="flux,uniform")
    m.add_argument("--rngs", default="clcg4,philox")
    w = sub.add_parser("words", parents=[gas_args], help="write a raw word file (for dieharder by hand)")
    w.add_argument("path")
    w.add_argument("--words", type=float, default=3e6)
    for k, v in (("--case", "pair2d"), ("--mode", "exact"), ("--law", "flux"), ("--rng", "philox")):
        w.add_argument(k, default=v)
    w.add_argument("--seed", type=int, default=1)
    tb = sub.add_parser("table", help="markdown tables of result files")
    tb.add_argument("files", nargs="+")
    tb.add_argument("--detail", action="store_true", help="one row per test, p-values per battery")
    tb.add_argument("--only", help="batteries to show, e.g. pair2d:exact:flux:clcg4,triple1d:paper:uniform:clcg4")
    mg = sub.add_parser("marginals", help="per-coordinate KS of the words of each battery in result files")
    mg.add_argument("files", nargs="+")
    mg.add_argument("--words", type=float, default=3e6)
    mg.add_argument("--json", help="write the results here")
    c = sub.add_parser("coverage", help="the coverage figures")
    c.add_argument("--out", default="docs/figures/randomness")
    c.add_argument("--samples", type=int, default=20000)
    a = ap.parse_args(argv)
    t0 = time.perf_counter()
    if a.cmd == "coverage":
        for p in coverage(a.out, samples=a.samples):
            print(p)
        return 0
    if a.cmd == "table":
        runs = [r for f in a.files for r in json.load(open(f))["runs"]]
        if a.only:
            key = [tuple(k.split(":")) for k in a.only.split(",")]
            runs = [r for k in key for r in runs
                    if tuple(r["config"][x] for x in ("case", "mode", "law", "rng")) == k]
        print(table(runs, a.detail))
        return 0
    if a.cmd == "marginals":
        import scipy.stats  # noqa: F401 (the studies extra): missing, it is refused before any work
        res = []
        for f in a.files:
            for r in json.load(open(f))["runs"]:
                keys = ("case", "mode", "law", "rng", "seed", "particles", "fraction", "warmup")
                res.append(marginals({k: r["config"][k] for k in keys if k in r["config"]}, int(a.words)))
                c = res[-1]["config"]
                ks = ", ".join(f"D={x['D']:.2g} p={x['p']:.2g}" for x in res[-1]["coordinates"])
                print(f"| {c['case']} | {c['mode']} | {c['law']} | {c['rng']} | {ks} |", flush=True)
        if a.json:
            with atomic_open(a.json) as f:
                json.dump(dict(_run_info(argv, t0), runs=res), f, indent=1)
                f.write("\n")
        return 0
    gas = {k: getattr(a, k, None) for k in ("particles", "fraction", "warmup")}
    if a.cmd == "words":
        cfg = _gas_options({"case": a.case, "mode": a.mode, "law": a.law, "rng": a.rng, "seed": a.seed}, gas)
        print(json.dumps(dict(write_words(a.path, int(a.words), **cfg), config=cfg)))
        return 0
    import scipy.stats  # noqa: F401,F811 (the studies extra): missing, it is refused before any battery runs
    if not has_dieharder():
        print("dieharder is not installed (apt-get install dieharder; scripts/setup.sh does it)",
              file=sys.stderr)
        return 2
    kw = {"workdir": a.workdir, "fit": not a.defaults}
    tests = _tests(a.tests)
    commit = _run_info([], t0)["commit"]  # the code that runs (HEAD may move during a long run)

    def save(runs: list[dict], complete: bool) -> None:
        if a.json:  # after every battery of a matrix, so that a stopped run keeps what it did
            with atomic_open(a.json) as f:
                json.dump(dict(_run_info(argv, t0), commit=commit, complete=complete, runs=runs), f, indent=1)
                f.write("\n")

    if a.cmd == "battery":
        cfg = _gas_options({"case": a.case, "mode": a.mode, "law": a.law, "rng": a.rng, "seed": a.seed}, gas)
        runs = [battery(cfg, int(a.words), tests, **kw)]
    elif a.cmd == "controls":
        runs = controls(int(a.words), tests, **kw)
    else:
        runs = []
        for cfg in _matrix_configs(a.cases.split(","), a.modes.split(","), a.laws.split(","),
                                   a.rngs.split(","), gas):
            runs.append(battery(cfg, int(a.words), tests, **kw))
            print(_summary(runs[-1]), flush=True)
            save(runs, False)
    if a.cmd != "matrix":
        for r in runs:
            print(_summary(r))
    save(runs, True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
