"""Property-based run over both engines' checkpoints (issue 59): save, tamper, load, then run,
run back, save/load and snapshot at random, on the float engine (2D/3D) and the lattice engine
(2D/3D), every boundary kind and mode.

Each example is a pure function of (seed, index): ``numpy.random.default_rng([seed, index])``
draws the engine, dimension, boundary per axis, mode and law, N (2..200, log-uniform), the
packing fraction and seed, the collisions run before the save, one tamper of the saved file and
one to six operations after the load. ``--replay INDEX`` runs one example in this process and
prints what it did: the reproducer of any failure the run reports.

Tampers (``TAMPERS``): ``none``; ``redigest_same`` (entries read and written again with
:func:`revcol._io.digested`, unchanged); ``flip_keep_digest`` (one bit of one entry flipped, the
old digest kept: must be refused as a digest mismatch); ``flip_file_byte`` (one byte of the
file flipped: refused, or loads the same state when the byte is outside the data, e.g. a zip
timestamp); ``truncate_file`` (the file cut short: refused); and, re-digested so that the
engine's own checks are what stands, ``flip_redigest`` (one bit of one entry), ``dtype`` (an
entry cast to another dtype), ``shape`` (an array entry cut, extended or reshaped), ``drop_entry``
(one entry removed; one time in five without re-digesting: refused), ``add_entry`` (an unknown
entry), ``scalar`` (a 0-d entry set to 0, -1, +-1 off, doubled, 2^63 - 1, NaN, inf or a string)
and ``swap_particles`` (two particles' rows swapped in one per-particle entry, or in all of them).

Properties, each example:

1. no crash: examples run in batches in child processes; a child killed by a signal is a
   crash, charged to the example after the last one it reported (the run goes on after it);
2. no hang: an example has ``CASE_SECONDS`` (SIGALRM; the engines poll signals, so it stops a
   run), and a child that reports nothing for ``WATCHDOG_SECONDS`` is killed and counted a hang;
3. every exception is a named ValueError/TypeError/RuntimeError/OverflowError (not a
   SystemError, KeyError, MemoryError, ...) with a message that is not pybind11's generic one
   nor a bare C++ one (``std::``, ``bad_alloc``, ``basic_string``, ``vector::``);
4. after an exception from an operation the simulation's ``snapshot()`` is bit-identical;
5. no silent divergence: an untampered (or identical) checkpoint loaded and driven through the
   same operations as the original simulation gives the same snapshot bit for bit after every
   one; ``from_snapshot(snapshot())`` and a save/load round trip give the same snapshot; on the
   lattice engine a run forward then ``run_back`` of as many collisions comes back to the state
   it started from bit for bit, from any checkpoint that loaded, tampered or not (or raises a
   named error, state unchanged). On the float engine a round trip of at most N/2 collisions
   (back to the start's clock) from an untampered checkpoint that comes back 0.1 or more off
   (velocities over the rms speed, positions over the diameter) must be reported by
   ``run_back``'s ``diverged`` (docs/robustness.md promises no silent failure there); errors
   between 1e-9 and 0.1 (a drifted trajectory, which no memoryless check sees; dilute gases
   reach it in fewer collisions than docs/engine.md's 4 to 10 per particle) are counted;
6. a file that must be refused (``flip_keep_digest``, ``truncate_file``, ``drop_entry`` without a
   new digest) is refused, and a flipped byte of the file (``flip_file_byte``) never loads a
   different state (``missed_refusal`` otherwise);
7. a state the engine reaches is one it accepts: ``save`` succeeds, and ``from_snapshot(snapshot())``
   and ``load`` of its own ``save`` succeed (``invalid_state`` otherwise); the one exception is a
   float state with overlapping particles after a ``run_back`` that reported a divergence, which
   both refuse by name.

    python -m revcol.studies.fuzz_checkpoints --examples 100000 --seed 59 --json bench/results/checkpoint_property_run.json
    python -m revcol.studies.fuzz_checkpoints --replay 1234 --seed 59     # one example, verbosely
"""
from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import signal
import subprocess
import sys
import tempfile
import time
import traceback
import warnings
from collections import Counter
from pathlib import Path
from typing import Callable, Optional

import numpy as np

from .fuzz_tamper import tamper

__all__ = ["TAMPERS", "run_example", "run", "main"]

TAMPERS = ("none", "redigest_same", "flip_keep_digest", "flip_file_byte", "truncate_file", "flip_redigest", "dtype",
           "shape", "drop_entry", "add_entry", "scalar", "swap_particles")
#: tampers whose file must be refused by ``load``
MUST_REFUSE = ("flip_keep_digest", "truncate_file")
CASE_SECONDS = 20
WATCHDOG_SECONDS = 120
#: test hook: a child aborts (SIGABRT) at this example index, so that the crash accounting is tested
ABORT_AT_ENV = "REVCOL_FUZZ_CHECKPOINTS_ABORT_AT"
NAMED = (ValueError, TypeError, RuntimeError, OverflowError)
GENERIC = ("incompatible function arguments", "Unable to cast", "incompatible constructor arguments", "std::",
           "bad_alloc", "basic_string", "vector::", "_M_range_check")
#: float round trips: within 1e-9 is "back"; an error of 0.1 or more is another trajectory, which
#: run_back must report (docs/robustness.md: no silent failure there). Between the two is the
#: drifted trajectory a memoryless check cannot see (ibid.): counted, not a failure
FLOAT_ROUND_TRIP = 1e-9
FLOAT_SILENT = 0.1
FAILURE_KINDS = ("crash", "hang", "unnamed_error", "state_change", "divergence", "missed_refusal", "invalid_state")


class Failure(Exception):
    """A property violated: ``kind`` is one of FAILURE_KINDS."""

    def __init__(self, kind: str, what: str):
        super().__init__(f"{kind}: {what}")
        self.kind = kind


class Hang(BaseException):
    """The per-example alarm (a BaseException, so that no ``except Exception`` in the package eats it)."""


@contextlib.contextmanager
def _alarm(seconds: int):
    def ring(signum, frame):
        raise Hang(f"example ran past {seconds} s")

    old = signal.signal(signal.SIGALRM, ring)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


# --- comparing states --------------------------------------------------------------------------


def _diff(a, b, where: str = "") -> Optional[str]:
    """The first place two snapshots differ (bit for bit; NaN equal to NaN), or None."""
    if isinstance(a, dict) or isinstance(b, dict):
        if not (isinstance(a, dict) and isinstance(b, dict)):
            return f"{where}: dict against {type(b).__name__}"
        if a.keys() != b.keys():
            return f"{where}: keys {sorted(set(a) ^ set(b))}"
        for k in a:
            d = _diff(a[k], b[k], f"{where}.{k}")
            if d:
                return d
        return None
    x, y = np.asarray(a), np.asarray(b)
    if x.dtype != y.dtype or x.shape != y.shape:
        return f"{where}: {x.dtype}{x.shape} against {y.dtype}{y.shape}"
    if x.dtype.hasobject:
        return None if a == b else f"{where}: {a!r:.60} against {b!r:.60}"
    if x.tobytes() != y.tobytes():
        return f"{where}: values differ"
    return None


def _check_error(e: BaseException, doing: str) -> None:
    """Property 3: a named exception with a message of its own."""
    if isinstance(e, (Hang, Failure)):
        raise e
    msg = str(e)
    if not isinstance(e, NAMED) or isinstance(e, RecursionError):
        raise Failure("unnamed_error", f"{doing}: {type(e).__name__}: {msg[:300]}")
    if not msg.strip() or any(g in msg for g in GENERIC):
        raise Failure("unnamed_error", f"{doing}: generic message {type(e).__name__}: {msg[:300]}")


def _attempt(fn: Callable, sim, doing: str, log: list):
    """fn(); on an exception checks properties 3 and 4 (sim's snapshot unchanged). Returns
    (ok, result)."""
    before = sim.snapshot() if sim is not None else None
    try:
        return True, fn()
    except Exception as e:  # noqa: BLE001 -- every exception is judged here
        _check_error(e, doing)
        log.append(f"{doing}: {type(e).__name__}: {str(e)[:160]}")
        if sim is not None:
            d = _diff(before, sim.snapshot(), "snapshot")
            if d:
                raise Failure("state_change", f"{doing} raised {type(e).__name__} ({str(e)[:160]}) and changed {d}")
        return False, None


# --- the example -------------------------------------------------------------------------------


def _draw_system(rng: np.random.Generator) -> dict:
    engine = str(rng.choice(["float", "lattice"]))
    dim = int(rng.choice([2, 3]))
    kinds = ["periodic", "wall", "bounce"]
    boundary = str(rng.choice(kinds)) if rng.random() < 0.6 else [str(rng.choice(kinds)) for _ in range(dim)]
    modes = ["exact", "specular"] + (["paper"] if engine == "float" and dim == 2 else [])
    mode = str(rng.choice(modes))
    law = str(rng.choice(["flux", "uniform"])) if mode == "exact" else "flux"
    n = int(round(math.exp(rng.uniform(math.log(2), math.log(200)))))
    phi = float(rng.uniform(0.02, 0.4 if dim == 2 else 0.3))
    return {"engine": engine, "dim": dim, "boundary": boundary, "mode": mode, "law": law, "n": n, "phi": phi,
            "seed": int(rng.integers(1, 2**31))}


def _build(rng: np.random.Generator, log: list):
    """A gas of the drawn kind; a start the engine refuses by name (too small a periodic box, no
    room) is drawn again, then with a lower packing fraction and more particles."""
    import revcol

    sys_ = _draw_system(rng)
    for attempt in range(8):
        try:
            sim = revcol.Simulation.random(sys_["n"], sys_["dim"], sys_["phi"], boundary=sys_["boundary"],
                                           seed=sys_["seed"], engine=sys_["engine"], mode=sys_["mode"], law=sys_["law"])
            sys_["build_attempts"] = attempt + 1
            return sim, sys_
        except Exception as e:  # noqa: BLE001
            _check_error(e, f"Simulation.random({sys_})")
            log.append(f"start refused: {str(e)[:120]}")
            sys_["phi"] = max(0.01, sys_["phi"] / 2)
            sys_["n"] = min(200, max(sys_["n"], 8) * 2)
    raise Failure("unnamed_error", f"no start built in 8 attempts: {sys_}")


def run_example(seed: int, index: int, folder: Path, verbose: bool = False) -> dict:
    """One example (module docstring); returns its record. Raises Failure (a property violated)
    or Hang."""
    rng = np.random.default_rng([seed, index])
    log: list = []
    rec: dict = {"index": index}
    try:
        return _example(rng, index, folder, rec, log)
    finally:
        if verbose:
            print(json.dumps(rec, indent=1, default=str))
            print("\n".join(log))


def _example(rng, index: int, folder: Path, rec: dict, log: list) -> dict:
    sim, sys_ = _build(rng, log)
    rec.update({"system": sys_, "tamper": None, "load": None, "ops": [], "errors": 0, "round_trips": Counter()})
    n = sim.n
    lattice = sys_["engine"] == "lattice"
    before = int(rng.integers(0, min(3 * n, 400) + 1))
    ok, _ = _attempt(lambda: _run(sim, before), sim, f"run({before}) before the save", log)
    if ok and rng.random() < 0.25 and sim.collisions > 0:
        back = int(rng.integers(0, sim.collisions + 1))
        _attempt(lambda: _run_back(sim, back), sim, f"run_back({back}) before the save", log)
    path = folder / f"ex{index}.npz"
    sim.save(path)
    saved = sim.snapshot()
    kind = str(rng.choice(TAMPERS))
    rec["tamper"] = {"kind": kind, **tamper(path, kind, rng, n)}
    cls = type(sim)
    ok, loaded = _attempt(lambda: cls.load(path), None, f"load after {kind}", log)
    must_refuse = kind in MUST_REFUSE or (kind == "drop_entry" and not rec["tamper"].get("redigest", True))
    if not ok:
        rec["load"] = "refused"
        if kind == "flip_keep_digest" and not any("digest mismatch" in m for m in log[-1:]):
            raise Failure("missed_refusal", f"flip_keep_digest refused, but not as a digest mismatch: {log[-1]}")
    else:
        same = _diff(saved, loaded.snapshot(), "snapshot") is None
        rec["load"] = "identical" if same else "changed"
        if (must_refuse or kind == "flip_file_byte") and not same:
            raise Failure("missed_refusal", f"{kind} {rec['tamper']} loaded a different state")
        if kind in ("none", "redigest_same") and not same:
            raise Failure("divergence", f"{kind}: the loaded state differs: {_diff(saved, loaded.snapshot(), 'snapshot')}")
    if ok:
        reference = sim if rec["load"] == "identical" else None
        _operations(rng, loaded, reference, lattice, folder, index, rec, log)
    rec["errors"] = len(log)
    return rec


#: a forward run stops after its collisions or this much time (kT = 1, unit diameter: about as
#: many mean flights), whichever comes first: a gas that never collides (two particles between
#: bounce-back walls) runs for ever on a count alone, which is a long run, not a hang
RUN_TIME = 100.0


def _run(sim, k: int):
    return sim.run(collisions=k, time=sim.time + RUN_TIME)


def _run_back(sim, k: int):
    if sim.engine == "lattice":
        return sim.run_back(collisions=k)
    return sim.run_back(collisions=k, on_divergence="ignore")


def _reported_overlap(sim) -> bool:
    """Whether the float engine reported a divergence (its first reason: "particles overlap", or
    one found earlier, such as the collision sequence) and its particles overlap: a run_back that
    left the forward trajectory, into a state it then neither saves nor restores, by name."""
    return (sim.engine != "lattice" and sim.diagnostics().get("divergence") is not None
            and "overlap" in sim._e.fault())


def _operations(rng, sim, reference, lattice: bool, folder: Path, index: int, rec: dict, log: list) -> None:
    """Random operations on the loaded ``sim``; ``reference`` (the original, when the file loaded
    unchanged) gets the same runs and must stay bit-identical (property 5)."""
    n = sim.n
    for step in range(int(rng.integers(1, 7))):
        op = str(rng.choice(["run", "run_back", "round_trip", "save_load", "snapshot", "bad_call"]))
        rec["ops"].append(op)
        if op == "run":
            k = int(rng.integers(0, min(2 * n, 300) + 1))
            ok, _ = _attempt(lambda: _run(sim, k), sim, f"run({k})", log)
            if reference is not None:
                ok_r, _ = _attempt(lambda: _run(reference, k), reference, f"reference run({k})", log)
                _same_course(sim, reference, ok, ok_r, op)
        elif op == "run_back":
            # sometimes more than were run: refused or bounded (a tampered count may be near 2^63:
            # the bound is capped for numpy, the same draw as uncapped below 2^40)
            k = int(rng.integers(0, min(max(1, sim.collisions), 2**40) + 3))
            ok, _ = _attempt(lambda: _run_back(sim, k), sim, f"run_back({k})", log)
            if reference is not None:
                ok_r, _ = _attempt(lambda: _run_back(reference, k), reference, f"reference run_back({k})", log)
                _same_course(sim, reference, ok, ok_r, op)
        elif op == "round_trip":
            k = int(rng.integers(1, max(2, n // 2) + 1))
            ok = _round_trip(sim, k, lattice, reference is not None, log, rec["round_trips"])
            if reference is not None:  # the original does the same round trip, bit for bit
                ok_r = _round_trip(reference, k, lattice, True, log, Counter())
                _same_course(sim, reference, ok, ok_r, op)
        elif op == "save_load":
            p = folder / f"ex{index}-{step}.npz"
            ok, _ = _attempt(lambda: sim.save(p), sim, "save", log)
            if not ok and not _reported_overlap(sim):
                raise Failure("invalid_state", f"save refused a state the engine reached: {log[-1]}")
            if ok:
                ok2, back = _attempt(lambda: type(sim).load(p), None, "load of a save", log)
                if not ok2:
                    raise Failure("invalid_state", f"a checkpoint this simulation saved does not load: {log[-1]}")
                d = _diff(sim.snapshot(), back.snapshot(), "snapshot")
                if d:
                    raise Failure("divergence", f"save/load round trip changed {d}")
                sim = back
                p.unlink()
        elif op == "snapshot":
            snap = sim.snapshot()
            ok, back = _attempt(lambda: type(sim).from_snapshot(snap), None, "from_snapshot(snapshot())", log)
            if not ok and not _reported_overlap(sim):
                raise Failure("invalid_state", f"from_snapshot(snapshot()) refused: {log[-1]}")
            d = _diff(snap, back.snapshot(), "snapshot") if ok else None
            if d:
                raise Failure("divergence", f"from_snapshot(snapshot()) changed {d}")
        else:  # an invalid call: must be refused by name, state unchanged
            bad = int(rng.integers(0, 6))
            calls = [lambda: sim.run(collisions=-1), lambda: sim.run(time=float("nan")),
                     lambda: sim.run_back(collisions=sim.collisions + 5 + 10**6) if lattice else sim.run_back(collisions=-3),
                     lambda: sim.run(collisions=1.5), lambda: sim.run(), lambda: sim.run_back(time=float("inf"))]
            _attempt(calls[bad], sim, f"bad call {bad}", log)


def _same_course(sim, reference, ok: bool, ok_r: bool, op: str) -> None:
    if ok != ok_r:
        raise Failure("divergence", f"{op}: the loaded simulation {'succeeded' if ok else 'failed'}, the original "
                                    f"{'succeeded' if ok_r else 'failed'}")
    d = _diff(reference.snapshot(), sim.snapshot(), "snapshot")
    if d:
        raise Failure("divergence", f"{op}: the loaded simulation left the original's course: {d}")


def _round_trip(sim, k: int, lattice: bool, untampered: bool, log: list, tally: dict) -> bool:
    """Forward k collisions, back as many: the lattice comes back bit for bit; the float engine
    within FLOAT_ROUND_TRIP (an untampered state, k <= N/2) or says it diverged. False if a
    step raised (a named error, state unchanged: checked by _attempt)."""
    n = sim.n
    start = sim.snapshot()
    x_start, v_start = sim.positions, sim.velocities  # the snapshot's x are at each particle's own time
    ok, r = _attempt(lambda: _run(sim, k), sim, f"round trip: run({k})", log)
    if not ok:
        return False
    did, t0 = int(r["collisions"]), float(start["time"]) if "time" in start else None
    # back to the start's clock (a count of collisions would stop at the first one's time)
    if lattice:
        back = lambda: sim.run_back(time=int(start["clock"]) * sim.units["tick"])  # noqa: E731
    else:
        back = lambda: sim.run_back(time=t0, on_divergence="ignore")  # noqa: E731
    ok, rb = _attempt(back, sim, f"round trip: run_back to the start ({did} collisions)", log)
    if not ok:
        tally["refused"] += 1
        return False
    if lattice:
        d = _diff(start, sim.snapshot(), "snapshot")
        if d:
            raise Failure("divergence", f"lattice run({k}) then run_back({did}) did not come back: {d}")
        tally["lattice_bit_for_bit"] += 1
        return True
    if not untampered:
        tally["float_unchecked_tampered"] += 1
        return True
    if rb.get("diverged"):
        tally["float_reported_diverged"] += 1
        return True
    v0, v1 = np.asarray(v_start, dtype=float), np.asarray(sim.velocities, dtype=float)
    rms = math.sqrt(float(np.mean(v0 * v0))) if v0.size else 1.0
    dv = float(np.max(np.abs(v1 - v0))) / (rms or 1.0) if v0.size else 0.0
    box = np.asarray(start["box"], dtype=float)
    dx = np.abs(np.asarray(sim.positions, dtype=float).reshape(n, -1) - np.asarray(x_start, dtype=float).reshape(n, -1))
    dx = np.minimum(dx, np.abs(box - dx))  # a periodic image
    err = max(dv, float(np.max(dx)) / float(start["diameter"]) if dx.size else 0.0)
    if err >= FLOAT_SILENT:
        raise Failure("divergence", f"float run({k}) then run_back to the start came back {err:.3g} off, not reported")
    if err > FLOAT_ROUND_TRIP:
        tally["float_1e-9_to_0.1_unreported"] += 1
        tally["float_largest_error_unreported"] = max(tally.get("float_largest_error_unreported", 0.0), err)
    else:
        tally["float_within_1e-9"] += 1
    return True


# --- batches in child processes ---------------------------------------------------------------


def _child(seed: int, start: int, stop: int, out: str) -> int:
    """Runs examples [start, stop), one JSON line each to ``out`` (flushed), in this process."""
    warnings.simplefilter("ignore")
    with tempfile.TemporaryDirectory(prefix="revcol-fuzzck-") as tmp, open(out, "a") as f:
        folder = Path(tmp)
        abort_at = os.environ.get(ABORT_AT_ENV)
        for i in range(start, stop):
            if abort_at is not None and int(abort_at) == i:
                os.abort()
            t0 = time.perf_counter()
            try:
                with _alarm(CASE_SECONDS):
                    rec = run_example(seed, i, folder)
                rec["failure"] = None
            except Failure as e:
                rec = {"index": i, "failure": e.kind, "what": str(e)}
            except Hang as e:
                rec = {"index": i, "failure": "hang", "what": str(e)}
            except Exception as e:  # noqa: BLE001 -- an error outside any attempt: the harness's own
                rec = {"index": i, "failure": "unnamed_error",
                       "what": f"{type(e).__name__}: {str(e)[:300]}", "trace": traceback.format_exc()[-1500:]}
            rec["seconds"] = round(time.perf_counter() - t0, 4)
            for p in folder.iterdir():
                p.unlink()
            f.write(json.dumps(rec, default=str) + "\n")
            f.flush()
    return 0


def _package_path() -> str:
    import revcol

    return str(Path(revcol.__file__).resolve().parents[1])


def run(examples: int, seed: int, batch: int = 500, start: int = 0, progress: bool = False,
        partial: Optional[Callable[[dict], None]] = None) -> dict:
    """Runs examples [start, start + examples) in child processes of ``batch`` examples; a
    child that dies by a signal is a crash of the example after its last record, and the batch
    goes on from the one after. Returns the summary (counts per tamper, outcome and failure)."""
    t0 = time.time()
    load_start = os.getloadavg()
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([_package_path(), os.environ.get("PYTHONPATH", "")]))
    records: list = []
    with tempfile.TemporaryDirectory(prefix="revcol-fuzzck-run-") as tmp:
        nxt, end = start, start + examples
        while nxt < end:
            stop = min(end, nxt + batch)
            out = os.path.join(tmp, f"b{nxt}.jsonl")
            open(out, "w").close()
            p = subprocess.Popen([sys.executable, "-m", "revcol.studies.fuzz_checkpoints", "--child", str(seed), str(nxt),
                                  str(stop), out], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
            last_size, last_change, hung = 0, time.time(), False
            while p.poll() is None:
                time.sleep(0.2)
                size = os.path.getsize(out)
                if size != last_size:
                    last_size, last_change = size, time.time()
                elif time.time() - last_change > WATCHDOG_SECONDS:
                    p.kill()  # the child this run started
                    hung = True
            err = p.stderr.read().decode(errors="replace") if p.stderr else ""
            p.wait()
            done = [json.loads(line) for line in open(out) if line.strip()]
            records.extend(done)
            nxt = done[-1]["index"] + 1 if done else nxt
            if p.returncode != 0 and nxt < stop:
                kind = "hang" if hung else "crash"
                records.append({"index": nxt, "failure": kind, "what": f"child exit {p.returncode}"
                                + (f" (signal {-p.returncode})" if p.returncode < 0 else "") + f"; stderr: {err[-800:]}"})
                nxt += 1
            if partial is not None:
                partial(summarize(records, seed, start, examples, time.time() - t0, load_start))
            if progress:
                fails = sum(1 for r in records if r.get("failure"))
                print(f"{nxt - start}/{examples} examples, {fails} failures, {time.time() - t0:.0f} s", flush=True)
    return summarize(records, seed, start, examples, time.time() - t0, load_start)


def summarize(records: list, seed: int, start: int, examples: int, seconds: float, load_start) -> dict:
    failures = [r for r in records if r.get("failure")]
    per_tamper: dict = {}
    for r in records:
        if r.get("failure") or not r.get("tamper"):
            continue
        per_tamper.setdefault(r["tamper"]["kind"], Counter())[r["load"]] += 1
    systems: Counter = Counter()
    for r in records:
        s = r.get("system")
        if s:
            b = s["boundary"] if isinstance(s["boundary"], str) else "mixed"
            systems[f"{s['engine']} {s['dim']}D {s['mode']} {b}"] += 1
    ops = Counter(op for r in records for op in r.get("ops", ()))
    trips: dict = Counter()
    for r in records:
        got = dict(r.get("round_trips") or {})
        big = got.pop("float_largest_error_unreported", 0.0)
        trips["float_largest_error_unreported"] = max(trips.get("float_largest_error_unreported", 0.0), big)
        trips.update(got)
    counts = {k: sum(1 for r in failures if r["failure"] == k) for k in FAILURE_KINDS}
    secs = [r["seconds"] for r in records if "seconds" in r]
    return {
        "examples": len(records), "seed": seed, "first_index": start, "asked": examples,
        "failures": counts, "all_passed": not failures,
        "loads_per_tamper": {k: dict(sorted(v.items())) for k, v in sorted(per_tamper.items())},
        "outcomes": dict(Counter(r["load"] for r in records if not r.get("failure"))),
        "operations": dict(sorted(ops.items())), "operation_errors": sum(r.get("errors", 0) for r in records),
        "round_trips": dict(sorted(trips.items())),
        "systems": dict(sorted(systems.items())),
        "seconds": round(seconds, 1), "example_seconds_max": max(secs) if secs else None,
        "load_average_start": list(load_start), "load_average_end": list(os.getloadavg()),
        "failure_records": failures[:200],
    }


def main(argv=None) -> int:
    if argv is None:
        argv = sys.argv[1:]
    if argv[:1] == ["--child"]:
        return _child(int(argv[1]), int(argv[2]), int(argv[3]), argv[4])
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--examples", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=59)
    ap.add_argument("--start", type=int, default=0, help="first example index")
    ap.add_argument("--batch", type=int, default=500, help="examples per child process")
    ap.add_argument("--json", help="write the summary here (atomically)")
    ap.add_argument("--replay", type=int, help="run example INDEX in this process and print it")
    args = ap.parse_args(argv)
    if args.replay is not None:
        with tempfile.TemporaryDirectory() as tmp:
            with _alarm(CASE_SECONDS):
                run_example(args.seed, args.replay, Path(tmp), verbose=True)
        print("passed")
        return 0
    command = ("python -m revcol.studies.fuzz_checkpoints " + " ".join(argv)).strip()
    try:
        commit = subprocess.run(["git", "-C", str(Path(__file__).resolve().parent), "rev-parse", "--short", "HEAD"],
                                capture_output=True, text=True).stdout.strip() or None
    except OSError:
        commit = None

    def write(summary: dict, final: bool) -> None:
        summary.update(command=command, commit=commit, finished=final)
        if args.json:
            from revcol._io import write_json

            write_json(summary, args.json)

    summary = run(args.examples, args.seed, args.batch, args.start, progress=True,
                  partial=lambda s: write(s, False))  # a partial summary after every batch
    write(summary, True)
    brief = {k: summary[k] for k in ("examples", "failures", "outcomes", "seconds")}
    print(json.dumps(brief))
    return 0 if summary["all_passed"] else 1


if __name__ == "__main__":
    sys.exit(main())
