"""Where a collision's time goes: revcol's float engine beside FSmallenburg/EDMD, part by part
(issue 21's profile table), and with ``--lattice`` the lattice engine's parts too (issue 57).
Writes bench/results/peer_profile.json (``--json``).

    python bench/peers/profile.py [--n 10976] [--phi 0.30 0.45] [--collisions 1e6] [--cpu 1]
        [--lattice] [--src bench/peers/src/EDMD] [--json bench/results/peer_profile.json]
    python bench/peers/profile.py --callgrind lattice3d/periodic/n10000/phi0.45 [CASE ...]
        [--bin build-dev/revcol-bench] [--counts 100000 200000] [--json FILE]

The codes run on the same equilibrated fluid as in ``fs_edmd.py`` (its state, its patched peer,
its revcol children: 2e5 untimed collisions, then 1e6 timed; revcol also runs them back), each a
fresh process pinned to ``--cpu`` under ``perf record -e cpu-clock``, ``--runs`` times each,
interleaved; the samples are summed over the runs and the time per collision is the runs'
median. Every sample in the
code's own binary (the peer's executable; revcol's ``_core`` module, not the Python around it)
is put in a part by the function it lies in, inlined functions included: addr2line names the
chain of inlined calls at the sample's address, and the innermost function that a part claims
decides (``part_of``). A part's time per collision is its share of those samples times the
time per collision the run measured itself (forward and reverse weighed by their run times;
the untimed warm-up runs the same code, so its samples only add to the count).

The parts (the issue's table):

- **prediction**: a particle's next event over its list (revcol ``predict`` and the pair tests
  inlined into it; FS ``findcollisions``, ``findcollision``, ``findneighborlistupdate``);
- **renewal**: the list renewal (revcol ``renew``, ``rebuild_list``, ``scan_cells``; FS
  ``makeneighborlist`` and its cell lists);
- **queue**: the event queue (revcol ``EventQueue``; FS ``addevent``, ``removeevent``,
  ``addnexteventlist``, ``step``);
- **operator + RNG**: the collision's new velocities (revcol's exact operator, its draws and
  ``apply_pair``; FS's specular ``collision`` body, which draws nothing);
- **bookkeeping**: the rest of the event loop and the collision's frame (revcol ``loop``,
  ``collide``; FS ``update``);
- **other**: any sample no part claims.

The lattice engine's parts (``LATTICE_RULES``; its run back must end on its starting bits):
**prediction: filter** (``predict``, ``scan``: the double-precision filter over the list),
**prediction: exact search** (``first_overlap`` and its guess), **acceptance scans**
(``post_reason``: third bodies at ticks a-1 and a), **group + redraws** (the group rule and the
rare log's lookups), **operator + bits-back** (the pair operator, its direction cells and
rotations, the bits-back integer, the draws), **renewal** (the neighbour lists and the
re-anchoring), **queue** (``EventQueue`` and ``schedule``), **bookkeeping** (the loop, the
collision's frame, ``apply``, walls), **other**.

``--callgrind CASE ...`` needs no peer and no perf: instructions per collision of revcol-bench's
cases (forward and back), part by part, which the host's load does not change. Each case runs
under callgrind at two collision counts; a function's own instructions (inlined helpers count
with the function they are inlined into) at the larger count less the smaller, over the
difference of the counts, go to the part of the function's name (the rules above: lattice
cases ``lattice...``, the float engine's otherwise). Needs valgrind.

Needs ``perf`` (Debian: linux-perf) and binutils. Line-level attribution needs debug
information, which changes no machine code: the peer is compiled here with its own flags plus
``-g``; for revcol pass ``--revcol-pkg`` a package staged from a build configured with
``-DCMAKE_CXX_FLAGS=-g`` (``scripts/dev_build.sh build-prof -DCMAKE_CXX_FLAGS=-g``). Without
it, a sample goes by its outermost function alone (the symbol perf names), and inlined
helpers count with their caller. Without the peer's source the script says where it goes and
measures nothing, as ``fs_edmd.py`` does.
"""
from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
from typing import Optional

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import fs_edmd  # noqa: E402

PARTS = ("prediction", "renewal", "queue", "operator + RNG", "bookkeeping", "other")
#: the lattice engine's parts (issue 57's table)
LATTICE_PARTS = ("prediction: filter", "prediction: exact search", "acceptance scans", "group + redraws",
                 "operator + bits-back", "renewal", "queue", "bookkeeping", "other")

#: revcol: (part, regular expression on a demangled function name), tried in this order
REVCOL_RULES = [
    ("queue", r"EventQueue<"),
    ("operator + RNG", r"Pair[23]DExact|ExactCollision|Philox|philox|::draw\b|apply_pair|FixedPoint|revcol::trig::"),
    ("renewal", r"rebuild_list|scan_cells|near_coded|list_insert|list_erase|list_recode|grow_lists|"
                r"NeighbourLists<\d>::renew\b|renew_event|move_centre|::unlink\b|::link\b|::place\b"),
    ("prediction", r"::predict\b|pair_time|pair_test2|renewal_time|plane_time|for_neighbour_pairs|prune_limit|"
                   r"Pair2::"),
    ("bookkeeping", r"::collide\b|::loop\b|finish_collision|trace_collision|trace_point|prefetch_collision|"
                    r"validate_collision|pair_shift|wall_event|touch_walls|EngineImpl<.*>::advance\b|repredict"),
]
#: the lattice engine: (part, regular expression), tried in this order on each function of the
#: chain, innermost first. Generic helpers (pos, diff, overlap, sync ...) match no rule, so the
#: part that calls them claims them.
LATTICE_RULES = [
    ("queue", r"EventQueue<[^>]*>::|BasicEngine<.*>::schedule\b"),  # (not the engine's template argument)
    ("group + redraws", r"group_collide|group_back|group_of|::Group\b|_Hashtable<revcol::lattice::LogKey|LogKey"),
    # the operators' files (pair2d, pair3d, cells, bitsback, specular), their helpers by name
    # (some in anonymous namespaces: addr2line names them bare or as "(anonymous namespace)::f")
    ("operator + bits-back", r"LatticePair[23]D::|BitsBack::|Shear3::|LatticeSpecular<|draw48|[Pp]hilox|"
                             r"(^|::)(dir_cell|face_of|flux_cum|flux_decode|half_cell|in_cell|in_coarse_cell|coarse_cell|"
                             r"normal_cell|lo_pre3?|lo_post3?|boundary(_x|_y|_component|_octant)?|initial_bits|"
                             r"angle_fx|atan2_guess|sincos_fx|octant_component|rot_coef|rotate|rotate_inv|isqrt_newton|"
                             r"div_word|div_step|az_cell|chart_of|from_normal|to_normal|in_polar_cell|polar_cell|"
                             r"make_column|row_of|make_frame|carry_phase|even_term|fix_ratio|pair_level(_back)?)(\(|<|$)"),
    ("acceptance scans", r"::post_reason\b"),
    ("prediction: exact search", r"(^|::)(first_overlap|first_overlap_d|guessed_tick|overlap_at)\b"),
    ("renewal", r"NeighbourListsN<|CellGridN<|::reanchor\b"),
    ("prediction: filter", r"BasicEngine<.*>::(scan|predict|region_ticks|Best::offer|coll_kind|wall_kind)\b|wall_ticks"),
    ("bookkeeping", r"BasicEngine<.*>::(loop|collide_forward|collide_drawn|collide_back|collide_specular|back_specular|"
                    r"apply|reflect|check_order|valid|journal|run|run_back|flip)\b"),
]
#: FS (C functions): (part, exact names)
FS_RULES = [
    ("queue", {"addevent", "addeventtotree", "removeevent", "addnexteventlist", "createevent", "step"}),
    ("renewal", {"makeneighborlist", "removefromcelllist", "addtocelllist", "celloffset"}),
    ("prediction", {"findcollisions", "findcollision", "findneighborlistupdate", "findallcollisions"}),
    ("operator + RNG", {"collision"}),
    ("bookkeeping", {"update", "backinbox", "main"}),
]


def part_of(chain: list, code: str) -> str:
    """The part a sample goes to: ``chain`` the functions at its address, innermost first (an
    inlined call, then its caller ...); the first one a rule of ``code`` ('revcol', 'lattice'
    or 'fs') claims decides, and 'other' when none does."""
    rules = LATTICE_RULES if code == "lattice" else REVCOL_RULES
    for name in chain:
        if code == "fs":
            base = name.split("(")[0].strip()
            for part, names in FS_RULES:
                if base in names:
                    return part
        else:
            for part, rx in rules:
                if re.search(rx, name):
                    return part
    return "other"


_SAMPLE = re.compile(r"^\s*[0-9a-f]+\s+(\S+)\s+\((.*)\)\s*$")


def samples(data: str, binary: str) -> tuple[dict, int]:
    """The samples of perf.data that lie in ``binary``: {(symbol, offset): count}, and the
    count of all samples."""
    out = subprocess.run(["perf", "script", "-i", data, "-F", "ip,sym,symoff,dso", "--no-demangle"],
                         capture_output=True, text=True, check=True).stdout
    return parse_samples(out, binary)


def parse_samples(out: str, binary: str) -> tuple[dict, int]:
    """``perf script -F ip,sym,symoff,dso --no-demangle`` output (one sample a line: address,
    symbol+0xoffset, (dso)) -> ({(symbol, offset): count} of the samples in ``binary``, the
    count of all samples). A sample without a symbol keeps perf's name for it, offset -1."""
    real = os.path.realpath(binary)
    hits: dict = {}
    total = 0
    for line in out.splitlines():
        m = _SAMPLE.match(line)
        if not m:
            continue
        total += 1
        if os.path.realpath(m.group(2)) != real:
            continue
        sym, _, off = m.group(1).rpartition("+0x")
        key = (sym, int(off, 16)) if sym else (m.group(1), -1)
        hits[key] = hits.get(key, 0) + 1
    return hits, total


def symbol_addresses(binary: str) -> dict:
    """{mangled symbol: address} of the binary's defined functions (nm)."""
    out = subprocess.run(["nm", "--defined-only", binary], capture_output=True, text=True, check=True).stdout
    addr = {}
    for line in out.splitlines():
        parts = line.split()
        if len(parts) == 3 and parts[1] in "tTwW":
            addr.setdefault(parts[2], int(parts[0], 16))
    return addr


def demangle(names: list) -> list:
    if not names:
        return []
    out = subprocess.run(["c++filt"], input="\n".join(names), capture_output=True, text=True, check=True).stdout
    return out.splitlines()


def inline_chains(binary: str, addresses: list) -> dict:
    """{address: [function, its caller, ...]} by addr2line (innermost first; empty when the
    binary has no debug information there)."""
    chains: dict = {}
    for k in range(0, len(addresses), 2000):
        batch = addresses[k:k + 2000]
        out = subprocess.run(["addr2line", "-e", binary, "-f", "-i", "-C", "-a"] + [hex(a) for a in batch],
                             capture_output=True, text=True, check=True).stdout.splitlines()
        cur = None
        u = 0
        while u < len(out):
            line = out[u]
            if line.startswith("0x"):
                cur = int(line, 16)
                chains[cur] = []
                u += 1
                continue
            if cur is not None and line != "??":
                chains[cur].append(line)
            u += 2  # a function name, then its file:line
    return chains


def attribute(data: str, binary: str, code: str) -> dict:
    """Samples in ``binary`` per part, and how many samples the run took in all."""
    hits, total = samples(data, binary)
    addr = symbol_addresses(binary)
    syms = sorted({s for s, _ in hits})
    plain = dict(zip(syms, demangle(syms)))
    where = {}
    for (sym, off) in hits:
        if sym in addr and off >= 0:
            where[(sym, off)] = addr[sym] + off
    chains = inline_chains(binary, sorted(set(where.values())))
    parts = {p: 0 for p in (LATTICE_PARTS if code == "lattice" else PARTS)}
    for key, c in hits.items():
        chain = list(chains.get(where.get(key, -1), []))
        chain.append(plain.get(key[0], key[0]))  # the symbol perf names: the outermost function
        parts[part_of(chain, code)] += c
    return {"parts": parts, "in_binary": sum(hits.values()), "all_samples": total}


def perf_record(cmd: list, data: str, cpu: int, cwd: Optional[str] = None, env: Optional[dict] = None) -> str:
    p = subprocess.run(fs_edmd._pin(["perf", "record", "-e", "cpu-clock", "-F", "4000", "-o", data, "--"] + cmd, cpu),
                       capture_output=True, text=True, cwd=cwd, env=env)
    if p.returncode != 0:
        raise RuntimeError(f"perf record failed ({p.returncode}):\n{p.stderr[-2000:]}")
    return p.stdout


def ns_per_part(parts: dict, ns_per_collision: float) -> dict:
    """Each part's ns per collision: its share of the binary's samples times the measured time."""
    n = sum(parts.values())
    return {p: (ns_per_collision * c / n if n else 0.0) for p, c in parts.items()}


_CORE_LINE = """
import revcol._core
print("REVCOL_CORE " + revcol._core.__file__)
"""
#: the timing children of fs_edmd.py, each also naming the _core module it imported
_CHILDREN = {"revcol": (fs_edmd._REVCOL_CHILD + _CORE_LINE, "REVCOL_SELF"),
             "lattice": (fs_edmd._LATTICE_CHILD + _CORE_LINE, "REVCOL_LATTICE")}


def _merge(acc: Optional[dict], a: dict) -> dict:
    """Sums the sample counts of two attributions."""
    if acc is None:
        return {"parts": dict(a["parts"]), "in_binary": a["in_binary"], "all_samples": a["all_samples"]}
    for p, c in a["parts"].items():
        acc["parts"][p] += c
    acc["in_binary"] += a["in_binary"]
    acc["all_samples"] += a["all_samples"]
    return acc


def profile_workload(n: int, phi: float, args, src: str, tmp: str) -> dict:
    """``--runs`` interleaved runs of each code (peer, revcol[, lattice]; then the reverse
    order; ...) on one state: samples summed over the runs, the time per collision the median
    of the runs'. A lattice run back that does not end on its starting bits is an error."""
    import numpy as np
    st = fs_edmd.equilibrated_state(n, phi, args.warmup, max_per_particle=args.max_warmup)
    npz = os.path.join(tmp, f"state_{n}_{phi}.npz")
    np.savez(npz, x=st["x"], v=st["v"], box=st["box"])
    run_dir = os.path.join(tmp, "peer_run")
    os.makedirs(run_dir, exist_ok=True)
    fs_edmd.write_sph(os.path.join(run_dir, "init.sph"), st["x"], st["box"])
    warm, coll = int(float(args.warmup_peer)), int(float(args.collisions))
    exe = fs_edmd.build_peer(src, os.path.join(tmp, "peer"), warm, coll, extra_flags=["-g"])
    env = dict(os.environ)
    if args.revcol_pkg:
        env["PYTHONPATH"] = os.path.abspath(args.revcol_pkg)
    codes = ("peer", "revcol", "lattice") if args.lattice else ("peer", "revcol")
    acc: dict = {c: None for c in codes}
    ns: dict = {c: [] for c in codes}
    fwd: dict = {c: [] for c in codes}
    rev: dict = {c: [] for c in codes}
    core, loads = "", []

    def run(code: str) -> None:
        nonlocal core
        data = os.path.join(tmp, code + ".data")
        if code == "peer":
            out = perf_record([exe], data, args.cpu, cwd=run_dir)
            line = next(l for l in out.splitlines() if l.startswith("REVCOL_PEER "))
            ns["peer"].append(1e9 * float(line.split()[2]) / int(line.split()[1]))
            acc["peer"] = _merge(acc["peer"], attribute(data, exe, "fs"))
            return
        script, tag = _CHILDREN[code]
        out = perf_record([sys.executable, "-c", script, npz, str(warm), str(coll)], data, args.cpu, env=env)
        me = json.loads(next(l for l in out.splitlines() if l.startswith(tag + " "))[len(tag) + 1:])
        if code == "lattice" and not me["bit_exact"]:
            raise RuntimeError(f"N = {n}, phi = {phi}: the lattice engine's run back did not end on its starting bits")
        core = next(l for l in out.splitlines() if l.startswith("REVCOL_CORE "))[len("REVCOL_CORE "):]
        fwd[code].append(me["forward"])
        rev[code].append(me["reverse"])
        # forward and reverse weighed by their run times: the mean time of a collision over both
        ns[code].append(1e9 * (1.0 / me["forward"] + 1.0 / me["reverse"]) / 2.0)
        acc[code] = _merge(acc[code], attribute(data, core, code))

    for r in range(args.runs):
        loads.append(os.getloadavg()[0])
        for code in (codes if r % 2 == 0 else codes[::-1]):
            run(code)
    out = {"n": n, "phi": phi, "s_bragg_after": st["s_bragg_after"], "fluid": st["fluid"], "load_before_runs": loads}
    for code in codes:
        med = statistics.median(ns[code])
        out[code] = {"ns_per_collision": med, "ns_per_collision_runs": ns[code], **acc[code],
                     "ns": ns_per_part(acc[code]["parts"], med)}
        if code != "peer":
            out[code].update({"forward_per_s_runs": fwd[code], "reverse_per_s_runs": rev[code], "core": core})
    if args.lattice:
        out["lattice"]["bit_exact"] = True
    return out


_ANNOTATE = re.compile(r"^\s*([\d,]+) \(\s*[\d.]+%\)\s+(\S*?):(.+?)(?: \[[^\]]*\])?\s*$")


def parse_annotate(out: str) -> dict:
    """``callgrind_annotate --inclusive=no`` output -> {function: its own instructions} (a name
    in several files or objects summed; the PROGRAM TOTALS line left out)."""
    own: dict = {}
    for line in out.splitlines():
        m = _ANNOTATE.match(line)
        if m:
            name = m.group(3).strip()
            own[name] = own.get(name, 0) + int(m.group(1).replace(",", ""))
    return own


def parts_of_counts(small: dict, large: dict, collisions: int, code: str) -> dict:
    """Instructions per collision by part: each function's own count at the larger run less the
    smaller, over the collisions between them, in the part of its name (setup cancels)."""
    parts = {p: 0.0 for p in (LATTICE_PARTS if code == "lattice" else PARTS)}
    for name in set(small) | set(large):
        parts[part_of([name], code)] += (large.get(name, 0) - small.get(name, 0)) / collisions
    return parts


def callgrind_case(binary: str, case: str, counts: list, tmp: str) -> dict:
    """One revcol-bench case under callgrind at the two counts: instructions per collision
    (forward and back), in all and by part."""
    own = []
    for c in counts:
        out = os.path.join(tmp, "callgrind.out")
        subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", binary, "--repeats", "1",
                        "--bench", case, "--collisions", str(c)], capture_output=True, text=True, check=True)
        ann = subprocess.run(["callgrind_annotate", "--inclusive=no", "--threshold=100", out],
                             capture_output=True, text=True, check=True).stdout
        own.append(parse_annotate(ann))
    code = "lattice" if case.startswith("lattice") else "revcol"
    parts = parts_of_counts(own[0], own[1], counts[1] - counts[0], code)
    return {"case": case, "counts": counts, "instructions_per_collision": sum(parts.values()), "parts": parts}


def main_callgrind(args) -> int:
    for tool in ("valgrind", "callgrind_annotate"):
        if shutil.which(tool) is None:
            print(f"profile.py --callgrind needs `{tool}` (Debian: valgrind); measured nothing")
            return 0
    if not 0 < args.counts[0] < args.counts[1]:
        raise SystemExit("profile.py: --counts takes two collision counts, the smaller first")
    res = {"command": " ".join(sys.argv), "binary": os.path.abspath(args.bin), "commit": fs_edmd.peer_commit(fs_edmd.ROOT),
           "cases": []}
    with tempfile.TemporaryDirectory() as tmp:
        for case in args.callgrind:
            r = callgrind_case(args.bin, case, args.counts, tmp)
            res["cases"].append(r)
            print(f"{case}: {r['instructions_per_collision']:.0f} instructions per collision (forward and back)")
            for p, v in r["parts"].items():
                print(f"  {p:26s} {v:8.0f}")
    fs_edmd._write_json(args.json, res)
    print(f"wrote {args.json}")
    return 0


def main(argv: Optional[list] = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--src", default=fs_edmd.DEFAULT_SRC, help="the peer's checkout (FSmallenburg/EDMD)")
    ap.add_argument("--n", type=int, nargs="+", default=[10976])
    ap.add_argument("--phi", type=float, nargs="+", default=[0.30, 0.45])
    ap.add_argument("--collisions", default="1e6", help="timed collisions per run")
    ap.add_argument("--warmup-peer", default="2e5", help="untimed collisions before the timing, in each run")
    ap.add_argument("--warmup", type=float, default=50.0, help="collisions per particle that equilibrate the state")
    ap.add_argument("--max-warmup", type=float, default=2000.0)
    ap.add_argument("--cpu", type=int, default=1, help="core each run is pinned to (-1: none)")
    ap.add_argument("--runs", type=int, default=3, help="interleaved runs of each code per workload")
    ap.add_argument("--lattice", action="store_true",
                    help="also profile revcol's lattice engine (3D, integer state) in the same rounds")
    ap.add_argument("--revcol-pkg", default="", help="a staged revcol package built with -g (default: the one imported)")
    ap.add_argument("--json", default=None, help="default: bench/results/peer_profile.json (--callgrind: lattice_instructions.json)")
    ap.add_argument("--callgrind", nargs="+", default=None, metavar="CASE",
                    help="instructions per collision of these revcol-bench cases by part (callgrind; no peer)")
    ap.add_argument("--bin", default="build-dev/revcol-bench", help="--callgrind: the revcol-bench binary")
    ap.add_argument("--counts", type=int, nargs=2, default=[100000, 200000], help="--callgrind: the two collision counts")
    args = ap.parse_args(argv)
    if args.callgrind:
        args.json = args.json or os.path.join(fs_edmd.RESULTS, "lattice_instructions.json")
        return main_callgrind(args)
    args.json = args.json or os.path.join(fs_edmd.RESULTS, "peer_profile.json")
    src = os.path.abspath(args.src)
    if not os.path.isfile(os.path.join(src, "Single", "mdSingle.c")):
        print(fs_edmd.where_to_put(src))
        return 0
    for tool in ("perf", "addr2line", "nm", "c++filt"):
        if shutil.which(tool) is None:
            print(f"profile.py needs `{tool}` (Debian: linux-perf for perf, binutils for the rest); measured nothing")
            return 0
    res = {"command": " ".join(sys.argv), "peer_commit": fs_edmd.peer_commit(src), "load_before": os.getloadavg()[0],
           "workloads": []}
    with tempfile.TemporaryDirectory() as tmp:
        for n in args.n:
            for phi in args.phi:
                w = profile_workload(n, phi, args, src, tmp)
                res["workloads"].append(w)
                pr, rv = w["peer"]["ns"], w["revcol"]["ns"]
                print(f"N = {n}, phi = {phi}: ns per collision, revcol / peer "
                      f"(total {w['revcol']['ns_per_collision']:.0f} / {w['peer']['ns_per_collision']:.0f})")
                for p in PARTS:
                    print(f"  {p:16s} {rv[p]:7.0f} {pr[p]:7.0f}")
                if args.lattice:
                    lt = w["lattice"]["ns"]
                    print(f"  lattice engine (total {w['lattice']['ns_per_collision']:.0f}, run back bit-exact):")
                    for p in LATTICE_PARTS:
                        print(f"    {p:26s} {lt[p]:7.0f}")
    res["load_after"] = os.getloadavg()[0]
    fs_edmd._write_json(args.json, res)
    print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
