"""Reports of ``revcol run`` as text: a gas round trip, a reversal scene, a state-saving study
and the horizon table (:func:`format_report`, :func:`format_horizon`); the JSON report is
:func:`revcol._io.write_json`'s.
"""
from __future__ import annotations

import math
from pathlib import Path

from ..roundtrip import BAR, ERROR_DEFINITIONS, divergence_text
from ..scene_schema import field_text, shear_text
from ..studies.statesave.output import format_table

__all__ = ["format_report", "format_horizon", "verify_lines", "field_line", "shear_line"]


def _si(x: float | None, unit: str = "") -> str:
    return "n/a" if x is None else f"{x:.3g}{unit}"


def _duration(s: float) -> str:
    return f"{s * 1e3:.3g} ms" if s < 1 else f"{s:.3g} s"


def _mib(b: int | None) -> str:
    return "n/a" if b is None else f"{b / 2**20:.1f} MiB (this process)"


def format_report(r: dict) -> str:
    """The report as text (any kind)."""
    scene = r["scene"]
    head = f"revcol run {scene['name']}  ({scene['source']})"
    if r["kind"] == "horizon":
        return format_horizon(r)
    if r["kind"] == "reversal":
        lines = [head, f"  scene               {r['summary']}"] + verify_lines(r)
        if r["interrupted"]:
            lines.append("  interrupted         (Ctrl-C) after the reversal, which is one call: it ran to the end")
    elif r["kind"] == "statesave":
        lines = [head, f"  scene   {r['summary']}", f"  runner  {r['runner']}: {r['rss_note']}", format_table(r)]
        if r["interrupted"]:
            lines.append(f"  interrupted (Ctrl-C): the table covers the runs done; {r.get('not_run', 0)} not run")
    else:
        body = _lattice_lines(r) if r.get("engine") == "lattice" else _float_lines(r)
        lines = [head, f"  scene            {r['summary']}"] + body + _gas_tail(r)
    if r.get("written"):
        lines.append("  written          " + " ".join(r["written"]))
    return "\n".join(lines)


def field_line(r: dict) -> list[str]:
    """The uniform field's line (none without one): the field run, on the lattice (a report with
    ``quantization``) its relative rounding; the energy drifts then include its potential. Then
    the shear's (:func:`shear_line`)."""
    g = r.get("gravity")
    if not g:
        return shear_line(r)
    axis = next(k for k, c in enumerate(g) if c)
    err = (r.get("quantization") or {}).get("gravity_error")
    rounding = "" if err is None else f", quantized once to an even integer per tick^2 (within {err:.2g} relative)"
    return [f"  field            gravity {field_text(g)} along axis {axis}{rounding}; "
            "the energy includes its potential"] + shear_line(r)


def shear_line(r: dict) -> list[str]:
    """Lees-Edwards shear's line (none without): the rate run and, on the lattice (``shear_per_tick``),
    its integer and relative rounding; the energy then grows (viscous heating: not a drift)."""
    rate = r.get("shear_rate")
    if not rate:
        return []
    per, err = r.get("shear_per_tick"), (r.get("quantization") or {}).get("shear_error")
    lattice = "" if per is None else f" (lattice: {per:,} units per tick, within {err or 0.0:.2g} relative)"
    return [f"  shear            rate {shear_text(rate)}{lattice}, flow axis 0, gradient axis 1 (Lees-Edwards); "
            "the energy grows by viscous heating"]


def _float_lines(r: dict) -> list[str]:
    """A float-engine gas round trip: rates, errors against the bar, drifts, log, memory."""
    drift_p = ("n/a (walls on every axis)" if r["momentum_drift_turn"] is None else
               f"{r['momentum_drift_turn']:+.2g} at the turn, {_si(r['momentum_drift_end'])} after reversal "
               "(periodic axes)")
    lines = [
        *field_line(r),
        f"  forward          {r['collisions_forward']:,} collisions ({r['per_particle']:.3g} per particle) to "
        f"t = {r['time_turn']:.6g} in {_duration(r['forward_s'])}: {_si(r['forward_per_s'])} collisions/s",
        f"  reverse          {r['collisions_back']:,} collisions back to t = {r['time_end']:.6g} in "
        f"{_duration(r['reverse_s'])}: {_si(r['reverse_per_s'])} collisions/s",
        f"  positions error  {r['error_x']:.3g}   {ERROR_DEFINITIONS['error_x']}",
        f"  velocity error   {r['error_v']:.3g}   {ERROR_DEFINITIONS['error_v']}",
        f"  bar              {BAR:g} (both)",
        f"  energy drift     {r['energy_drift_turn']:+.2g} at the turn, {r['energy_drift_end']:+.2g} after "
        "reversal   ((E - E0) / E0)",
        f"  momentum drift   {drift_p}",
        f"  log bytes        {r['log_bytes_turn']} at the turn, {r['log_bytes_end']} after reversal",
        f"  peak RSS         {_mib(r['peak_rss_bytes'])}",
    ]
    if r["reverse_failures"]:
        lines.append(f"  reverse failures {r['reverse_failures']} (the reversed run left the forward one)")
    if r.get("divergence"):
        lines.append(f"  diverged         {divergence_text(r)}")
    return lines


def _err(e: float, unit: str) -> str:
    return f"{e:.2g} {unit}" if e > 0 else "0 (the float values lie on the lattice)"


def _n(count: int, one: str, many: str | None = None) -> str:
    return f"{count:,} {one if count == 1 else (many or one + 's')}"


_PARTS = {"positions": "positions", "velocities": "velocities", "rng_counters": "RNG counters",
          "bits_back": "bits-back integers", "clock": "clock", "collision_count": "collision counts",
          "rare_log": "rare log"}


def _search(search) -> str:
    """The lattice's neighbour search as the report says it."""
    if search is None or search == "cells":
        return "cells (the cell grid)" if search else "n/a"
    return f"neighbour lists, shell {search:.3g} diameters"


def _per(x: dict) -> str:
    """' (k per particle)' when the report knows the particle count (one X per particle)."""
    n = x.get("particles")
    return f" ({x['start'] / n:.4g} per particle)" if n else ""


def parallel_line(p: dict | None, back: bool = False) -> list[str]:
    """The parallel engine's line of a lattice report (none for a sequential run); ``back``: the run back's."""
    if p is None:
        return []
    events, par = max(int(p["events"]), 1), int(p["parallel_collisions"])
    if back:
        return [f"  parallel back    {par:,} collisions taken back in parallel, {int(p['sequential_collisions']):,} "
                f"sequential (tail); {int(p['events']):,} events processed (efficiency {par / events:.3g}), "
                f"{int(p['rollbacks']):,} rollbacks undoing {int(p['undone']):,}, {int(p['messages']):,} messages; "
                f"journals at most {int(p['journal_peak_bytes']):,} bytes ({float(p['journal_bytes_per_entry']):.0f} per entry)"]
    return [f"  parallel         {p['lps']} logical processes on {p['workers']} worker thread(s), rollback by "
            f"{p['rollback']}{', lazy cancellation' if p['lazy'] else ''}: {par:,} collisions committed in parallel, "
            f"{int(p['sequential_collisions']):,} sequential (probe and tail); {int(p['events']):,} events processed "
            f"(efficiency {par / events:.3g}), {int(p['rollbacks']):,} rollbacks undoing {int(p['undone']):,}, "
            f"{int(p['messages']):,} messages, {int(p['anti_messages']):,} anti-messages; journals at most "
            f"{int(p['journal_peak_bytes']):,} bytes ({float(p['journal_bytes_per_entry']):.0f} per entry)"]


def _lattice_lines(r: dict) -> list[str]:
    """A lattice-engine round trip: what came back bit for bit, X's size, the rare log,
    redraws (specular mode: refusals) and backscatters, multi-body ticks, drifts, rates and memory."""
    u, q, x, n = r["units"], r["quantization"], r["bits_back"], max(r["collisions_forward"], 1)
    ok = r["restored"]
    same = ", ".join(f"{_PARTS[k]} {'yes' if v else 'NO'}" for k, v in ok.items())
    redraws = ", ".join(f"{k} {c}" for k, c in r["redraws"].items())
    mom = r["momentum_drift_turn"]
    drift_p = ("n/a (walls on every axis)" if mom is None else
               f"({', '.join(f'{p:+.0f}' for p in mom['lattice_units'])}) lattice units at the turn "
               f"({mom['relative']:.2g} of sqrt(2 E0 N)), "
               f"({', '.join(f'{p:+.0f}' for p in r['momentum_drift_end']['lattice_units'])}) after reversal")
    lines = [
        f"  engine           lattice: sigma = 2^{u['S']} lattice units per diameter, a tick = {u['tick']:.3g} time "
        f"units (a typical particle moves 2^-{u['tick_bits']} sigma per tick), 2^{u['cell_bits']} direction cells",
        f"  settings         mode {r.get('mode', 'exact')}, tick_bits {u['tick_bits']}, cell_bits {u['cell_bits']}, "
        f"search {_search(r.get('search'))}",
        *field_line(r),
        *parallel_line(r.get("parallel")),
        *parallel_line(r.get("parallel_back"), back=True),
        f"  start            quantized once: positions within {_err(q['max_position_error'], 'diameters')}, "
        f"velocities within {_err(q['max_velocity_error'], 'v_rms')}; exact from there on",
        f"  forward          {r['collisions_forward']:,} collisions ({r['per_particle']:,.4g} per particle) to "
        f"t = {r['time_turn']:.6g} (tick {r['clock_turn']:,}) in {_duration(r['forward_s'])}: "
        f"{_si(r['forward_per_s'])} collisions/s ({_si(r['forward_per_cpu_s'])} per CPU second)",
        f"  reverse          {r['collisions_back']:,} collisions back to t = {r['time_end']:.6g} (tick "
        f"{r['clock_end']:,}) in {_duration(r['reverse_s'])}: {_si(r['reverse_per_s'])} collisions/s "
        f"({_si(r['reverse_per_cpu_s'])} per CPU second)",
        f"  restored         {'bit for bit' if r['bit_for_bit'] else 'NOT bit for bit'}: {same}",
        f"  bits-back X      {x['start']:,} bits over all particles at the start{_per(x)}, {x['turn']:,} at the turn, "
        f"{x['end']:,} after reversal; max {x['max']:,} (sampled every {x['sampled_every']:,} collisions)",
        f"  rare log         {_n(r['log_entries_turn'], 'entry', 'entries')} ({r['log_bytes_turn']} bytes) at the "
        f"turn, {r['log_entries_per_collision']:.2g} per collision ({_n(r['group_resolves'], 'group collision')} "
        f"resolved, {_n(r['group_bounces'], 'group bounce')}); "
        f"{_n(r['log_entries_end'], 'entry', 'entries')} ({r['log_bytes_end']} bytes) after reversal",
        # specular mode draws nothing: its counters are the map's refusals, each resolved as a group
        (f"  refusals         {r['redraws_total']:,} ({r['redraws_total'] / n:.2g} per collision; no redraws in specular "
         f"mode, each went to the group rule): {redraws}" if r.get("mode") == "specular" else
         f"  redraws          {r['redraws_total']:,} ({r['redraws_total'] / n:.2g} per collision): {redraws}"),
        *([f"  backscatters     {r['backscatters']:,} ({r['backscatters'] / n:.2g} per collision): specular pairs "
           "turned back in place"] if r.get("mode") == "specular" else []),
        f"  multi-body       {_n(r['multi_body'], 'tick')} with three bodies ({r['multi_body'] / n:.2g} per "
        f"collision), {r['wall_body']} with a wall and a body ({r['wall_body'] / n:.2g} per collision)",
        f"  energy drift     {r['energy_drift_turn']:+.2g} at the turn, {r['energy_drift_end']:+.2g} after reversal   "
        "((E - E0) / E0, exact integers)",
        f"  momentum drift   {drift_p}",
        f"  memory           engine {r['engine_memory_bytes'] / 2**10:.0f} KiB; peak RSS {_mib(r['peak_rss_bytes'])}",
    ]
    if r["engine_error"]:
        lines.append(f"  engine error     {r['engine_error']}")
    return lines


def _gas_tail(r: dict) -> list[str]:
    """Outputs written, an interruption, and the result line of a gas round trip."""
    lines = []
    if r["checkpoints"]:
        lines.append(f"  checkpoints      {len(r['checkpoints'])} in {Path(r['checkpoints'][0]).parent}")
    if r["trajectory"]:
        lines.append(f"  trajectory       {r['trajectory_frames']} frames in {r['trajectory']}")
    if r["interrupted"]:
        lines.append(f"  interrupted      during the {r['interrupted']} run (Ctrl-C)"
                     + ("; the round trip is incomplete" if not r["round_trip_complete"] else
                        "; went back from where it stopped"))
    how = ": restored bit for bit" if r.get("engine") == "lattice" and r["passed"] else ""
    lines.append(f"  result           {'PASSED' if r['passed'] else 'FAILED'}{how}")
    return lines


def verify_lines(r: dict) -> list[str]:
    """``revcol verify``'s report lines (shared with the CLI's verify command)."""
    return [
        f"  collisions          {r['collisions']:,} forward, {r['collisions']:,} back",
        f"  forward             {r['forward_per_s']:.3g} collisions/s",
        f"  reverse             {r['reverse_per_s']:.3g} collisions/s",
        f"  max relative error  {r['max_rel_error']:.3g}  (bar: 1e-9)",
        f"  bit exact           {r['bit_exact']}",
        f"  rng restored        {r['rng_restored']}  ({r['random_numbers_drawn']:,} drawn)",
        f"  rare log            {r['log_bytes']} bytes at the turn",
        f"  result              {'PASSED' if r['passed'] else 'FAILED'}",
    ] + ([f"  stopped             {r['error']}"] if r.get("error") else [])


def format_horizon(r: dict) -> str:
    """The horizon table as text."""
    if r.get("engine") == "lattice":
        return _lattice_horizon(r)
    lines = [f"revcol run --horizon {r['scene']['name']}  ({r['scene']['source']})",
             f"  scene  {r['summary']}",
             f"  worst round-trip error over {r['seeds']} seed(s) from {r['seed_first']}; "
             f"bar {BAR:g}; stop at {r['o1']:g}",
             f"  {'N_c':>10}  {'per particle':>12}  {'error_x':>9}  {'error_v':>9}  {'median':>9}  fails"]
    def e(x: float) -> str:  # a seed that already reached O(1) counts as infinite
        return f"{x:>9.2e}" if math.isfinite(x) else f"{'O(1)':>9}"

    for row in r["rows"]:
        lines.append(f"  {row['collisions']:>10,}  {row['per_particle']:>12.3g}  {e(row['error_x'])}  "
                     f"{e(row['error_v'])}  {e(row['median'])}  {row['fails']}/{row['seeds']}")
    if r["horizon_reached"]:
        lines.append(f"  horizon: N_c = {r['horizon_collisions']:,} ({r['horizon_per_particle']:.3g} collisions "
                     f"per particle) is the largest grid point with every error <= {BAR:g}")
    else:
        lines.append(f"  horizon: not reached up to N_c = {r['rows'][-1]['collisions']:,} "
                     f"(--max-collisions {r['max_collisions']:,})")
    if r["interrupted"]:
        lines.append("  interrupted (Ctrl-C): the table covers what ran")
    if r.get("written"):
        lines.append("  written  " + " ".join(r["written"]))
    return "\n".join(lines)


def _lattice_horizon(r: dict) -> str:
    """``--horizon`` on a lattice scene: the bit-for-bit checks and why there is no horizon."""
    lines = [f"revcol run --horizon {r['scene']['name']}  ({r['scene']['source']})",
             f"  scene  {r['summary']}",
             f"  round trips of {r['seeds']} seed(s) from {r['seed_first']}, each compared exactly with its start",
             f"  {'N_c':>10}  {'per particle':>12}  bit for bit"]
    for row in r["rows"]:
        lines.append(f"  {row['collisions']:>10,}  {row['per_particle']:>12.4g}  {row['bit_for_bit']}/{row['seeds']}")
        lines += [f"      engine error: {e}" for e in row["errors"]]
    if r["passed"]:
        other = ("the float engine runs no shear" if r["scene"].get("shear_rate") else
                 "the float engine's horizon for this gas: --horizon --engine float")
        lines.append("  horizon: none. The lattice engine's state is integers and each collision an exact "
                     f"bijection, so the round trip is exact at every N_c (checked above bit for bit); {other}")
    else:
        lines.append("  FAILED: a lattice round trip did not come back bit for bit (above)")
    if r["interrupted"]:
        lines.append("  interrupted (Ctrl-C): the table covers what ran")
    if r.get("written"):
        lines.append("  written  " + " ".join(r["written"]))
    return "\n".join(lines)
