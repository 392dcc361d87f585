"""How ``revcol sweep`` runs its points: the task a Dask worker runs (:func:`run_point`), and the
client side (:func:`execute`) that submits them, writes each result as it finishes and gathers.

A task returns its report to the client, and only the client writes: ``points/<hash>.json``
through :func:`revcol._io.atomic_open` as each future finishes. A task killed with its worker
(the worker process dies, its nanny starts a new one) has written nothing; the scheduler runs it
again from its start on a live worker (a task whose workers died 3 times,
``distributed.scheduler.allowed-failures``, is marked lost), and a task that raised is run again
up to ``retries`` times (``client.submit(retries=)``). Points are deterministic by seed, so a
rerun gives the same report. The workers need the same revcol build as the client, and a
scene's initial-state file must be readable at the same path on every worker.
"""
from __future__ import annotations

import datetime as dt
import json
import logging
import os
import signal
import socket
import sys
import threading
import time
import uuid
from pathlib import Path
from typing import Callable

from .._io import atomic_open, jsonable
from ..progress import Bar, Interrupt
from ..scene import SceneError, scene_from_dict
from .output import gather, point_path, read_point
from . import studies as sceneless
from .spec import SweepError

__all__ = ["run_point", "execute"]

#: Dask worker resource a task claims (bytes of memory); LocalCluster workers offer their memory limit
MEMORY = "MEMORY"


def run_point(task: dict) -> dict:
    """Runs one point (on a worker, or here) and returns ``{"report", "seconds", "host", "pid"}``;
    the report is the dict ``revcol run --json`` writes (JSON values only)."""
    # deferred, not a cycle: `import revcol` imports revcol.sweep, and the studies load only
    # when a point runs (on the worker)
    from ..studies.scenes import run_scene

    t0 = time.perf_counter()
    opts = task["options"]
    if task["study"] in ("randomness", "equilibrium"):
        r = sceneless.run(task["study"], opts)
    elif task["study"] == "horizon":
        scene = scene_from_dict(task["doc"], task["label"], Path(task["base"]))
        r = run_scene(scene, horizon_seeds=opts.get("seeds", 1), max_collisions=opts.get("max_collisions", 1_000_000),
                      engine=opts.get("engine"), progress=False)
    else:
        scene = scene_from_dict(task["doc"], task["label"], Path(task["base"]))
        r = run_scene(scene, engine=opts.get("engine"), progress=False)
    return {"report": jsonable(r), "seconds": time.perf_counter() - t0, "host": socket.gethostname(),
            "pid": os.getpid()}


def _write_point(out: Path, spec, p, result: dict) -> None:
    doc = {"sweep": spec.name, "study": spec.study, "index": p.index, "hash": p.hash, "point": p.params,
           "seconds": result["seconds"], "host": result["host"], "pid": result["pid"],
           "finished": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"), "report": result["report"]}
    with atomic_open(point_path(out, p.hash)) as f:
        json.dump(doc, f, indent=1, default=str)


class _State:
    """What one execution did: points run, failures, whether it was interrupted."""

    def __init__(self) -> None:
        self.ran, self.failed, self.interrupted, self.cluster = 0, [], False, {"kind": "none"}

    def fail(self, p, e: BaseException) -> None:
        self.failed.append({"index": p.index, "point": p.params, "hash": p.hash,
                            "error": f"{type(e).__name__}: {e}"})


def execute(spec, out: Path, *, workers, scheduler, scheduler_file, client, progress, stop_after,
            log: Callable[[str], None], on_result: Callable[[dict], None] | None = None,
            output_estimate: dict | None = None) -> dict:
    """Runs the points of ``spec`` not yet in ``out``, then gathers the table and the summary
    (``output_estimate``: the outputs' estimated bytes, for the summary)."""
    todo = [p for p in spec.points if read_point(out, p.hash) is None]
    reused = len(spec.points) - len(todo)
    load0, t0 = os.getloadavg(), time.perf_counter()
    log(f"revcol sweep {spec.name}: {len(spec.points)} points ({spec.study} of {spec.scene_name}); "
        f"{reused} already done in {out}, {len(todo)} to run")
    state = _State()
    bars: list[Bar] = []  # drawn from the first result on, below the cluster's lines

    def finished(p, result: dict) -> bool:
        _write_point(out, spec, p, result)
        state.ran += 1
        if not bars:
            bars.append(Bar(sys.stdout.isatty() if progress is None else progress, float(len(todo)), spec.name, "pt"))
        bars[0].to(state.ran + len(state.failed))
        if on_result is not None:
            on_result({"index": p.index, "hash": p.hash, "point": p.params})
        return stop_after is not None and state.ran >= stop_after

    try:
        if todo and workers == 0:
            _serial(spec, todo, state, finished)
        elif todo:
            _distributed(spec, todo, state, finished, workers=workers, scheduler=scheduler,
                         scheduler_file=scheduler_file, client=client, log=log)
    except KeyboardInterrupt:
        state.interrupted = True
    finally:
        for b in bars:
            b.close()
    return gather(spec, out, state, reused=reused, seconds=time.perf_counter() - t0, load=(load0, os.getloadavg()),
                  log=log, output_estimate=output_estimate)


def _serial(spec, todo, state: _State, finished) -> None:
    state.cluster = {"kind": "serial", "workers": 1}
    for p in todo:
        try:
            result = run_point(p.task(spec.base, spec.study))
        except (SceneError, ValueError, RuntimeError, MemoryError, OSError) as e:
            state.fail(p, e)
            continue
        if result["report"].get("interrupted"):  # Ctrl-C reached the run: not a finished point
            state.interrupted = True
            return
        if finished(p, result):
            return


def _connect(workers, scheduler, scheduler_file, log):
    """(client, things to close): a client of the named cluster, or of a new LocalCluster."""
    from distributed import Client, LocalCluster  # optional (the sweep extra): Dask only when a sweep runs on it

    if scheduler is not None or scheduler_file is not None:
        where = scheduler or f"the scheduler in {scheduler_file}"
        if scheduler_file is not None and not os.path.isfile(scheduler_file):  # Client would wait for it forever
            raise SweepError(f"{scheduler_file}: no such scheduler file (dask scheduler --scheduler-file writes it)")
        try:
            c = Client(address=scheduler, scheduler_file=scheduler_file, timeout="10s")
        except (OSError, TimeoutError, ValueError) as e:
            raise SweepError(f"cannot reach {where}: {e}") from None
        try:
            c.wait_for_workers(1, timeout=60)
        except (OSError, TimeoutError) as e:
            c.close()
            raise SweepError(f"{where} has no worker (none joined within 60 s): {e}") from None
        return c, [c], "existing"
    n = workers or os.cpu_count() or 1
    total = _total_memory()
    per = total // n if total else None
    # the workers start with SIGINT ignored (inherited through exec): a terminal's Ctrl-C reaches
    # the whole process group, and only this process is to act on it (it cancels, writes, closes)
    old = signal.signal(signal.SIGINT, signal.SIG_IGN) if threading.current_thread() is threading.main_thread() else None
    try:
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0",
                               memory_limit=per if per else "auto", resources={MEMORY: per} if per else None,
                               silence_logs=logging.ERROR,
                               worker_dashboard_address=":0")  # free ports: others on this machine may hold 8787
    finally:
        if old is not None:
            signal.signal(signal.SIGINT, old)
    c = Client(cluster)
    return c, [c, cluster], "local"


def _has_bokeh() -> bool:
    """Whether the dashboard's pages can be drawn here (they need bokeh)."""
    try:
        import bokeh  # noqa: F401
    except ImportError:
        return False
    return True


def _total_memory() -> int | None:
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError, AttributeError):
        return None


def _resources(spec, client, todo, log) -> bool:
    """Whether tasks claim MEMORY: yes when every worker offers it (a point needing more than the
    largest offer is an error: it would never run); no, with a note, when no worker does."""
    offers = [w.get("resources", {}).get(MEMORY) for w in client.scheduler_info()["workers"].values()]
    if not offers or any(o is None for o in offers):
        log("revcol sweep: the workers declare no MEMORY resource (dask worker --resources MEMORY=BYTES): "
            "tasks are not held back by memory")
        return False
    need = max(todo, key=lambda p: p.memory_bytes)
    if need.memory_bytes > max(offers):
        raise SweepError(f"{spec.source}: point {need.index} ({need.label()}) needs "
                         f"{need.memory_bytes / 2**30:.2f} GiB, the largest worker offers {max(offers) / 2**30:.2f} "
                         "GiB ([resources] memory_gib, or larger workers)")
    return True


def _completed(ac, stop: Interrupt):
    """The futures of ``ac`` as they finish, polled from this thread: a Ctrl-C (counted by ``stop``)
    raises KeyboardInterrupt here, between two of Dask's calls, never inside one (distributed's
    ``sync`` logs a NameError traceback when the interrupt lands before its future exists)."""
    while True:
        if stop.presses:
            raise KeyboardInterrupt
        batch = ac.next_batch(block=False)
        if batch:
            yield from batch
        elif ac.is_empty():
            return
        else:
            time.sleep(0.02)


def _distributed(spec, todo, state: _State, finished, **how) -> None:
    with Interrupt() as stop:  # SIGINT only counted while Dask's calls run; acted on between them
        _distributed_run(spec, todo, state, finished, stop, **how)


def _distributed_run(spec, todo, state: _State, finished, stop: Interrupt, *, workers, scheduler, scheduler_file,
                     client, log) -> None:
    from distributed import as_completed  # optional (the sweep extra): Dask only when a sweep runs on it

    owned = []
    try:
        if client is None:
            client, owned, kind = _connect(workers, scheduler, scheduler_file, log)
        else:
            kind = "client"
        info = client.scheduler_info()
        dash = info.get("services", {}).get("dashboard")
        state.cluster = {"kind": kind, "address": info.get("address"), "workers": len(info["workers"]),
                         "dashboard": client.dashboard_link if dash else None}
        log(f"revcol sweep: scheduler {info.get('address')}, {len(info['workers'])} workers; dashboard: "
            + (client.dashboard_link if dash else "none") + ("" if _has_bokeh() else
                                                                " (its pages need bokeh: pip install 'bokeh>=3.1')"))
        claim = _resources(spec, client, todo, log)
        tag = uuid.uuid4().hex[:8]  # fresh keys: a cancelled earlier run's tasks never answer for these
        futures = {}
        for p in todo:
            f = client.submit(run_point, p.task(spec.base, spec.study), key=f"revcol-sweep-{p.hash}-{tag}",
                              retries=spec.retries, resources={MEMORY: p.memory_bytes} if claim else None)
            futures[f] = p
        try:
            for f in _completed(as_completed(list(futures)), stop):
                p = futures.pop(f)
                try:
                    result = f.result()
                except Exception as e:  # noqa: BLE001 - the task's own error, after its retries
                    state.fail(p, e)
                    continue
                if finished(p, result):
                    break
        finally:
            if futures:
                client.cancel(list(futures))
    finally:
        for thing in owned:
            thing.close()
