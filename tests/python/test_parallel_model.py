"""bench/parallel_model.py, the parallel lattice engine's performance model: it must recover the
unit costs of runs made by its own cost law, and read the committed runs into predictions."""
import importlib.util
import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "bench" / "parallel_model.py"


def _module():
    spec = importlib.util.spec_from_file_location("parallel_model", SCRIPT)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _synthetic(name: str, n: int, costs: tuple) -> list[dict]:
    """A revcol-bench parallel case whose run times follow the model's cost law exactly."""
    ce, cu, cm, cb = costs
    coll = 10**6
    m = {"collisions": coll, "n": n, "phi": 0.5, "band_over_L": 0.01, "seconds_seq": 0.9 * ce * 1.5 * coll}
    for k in (1, 2, 4, 8):
        for w in (1, 2):
            if w > k:
                continue
            v = f"K{k}_w{w}"
            e = 1.5 * (1 + 0.02 * k) + (0.3 * k if w == 2 else 0.05 * k)
            u = 0.0 if k == 1 else (0.25 * k * w + 0.01 * k * k)
            msg = 0.0 if k == 1 else 0.02 * k + 0.001 * k * k * w
            b = 1.0 if w == 1 else 1.0 + 0.05 * k ** 0.5
            g = 40.0 * w * k + 10 * k * k
            s = 50e-9 * e
            t = (ce * e + cu * u + cm * msg) * b / w + (cb * g / coll if w > 1 else 0.0) + s
            m.update({f"seconds_{v}": t * coll, f"events_per_collision_{v}": e, f"undone_per_collision_{v}": u,
                      f"messages_per_collision_{v}": msg, f"gvts_{v}": g, f"gvt_s_per_collision_{v}": s,
                      f"worker_imbalance_{v}": b, f"speedup_{v}": m["seconds_seq"] / (t * coll),
                      f"speedup_{v}_min": 0.0, f"speedup_{v}_max": 0.0})
    return [{"bench": name, "metric": k, "median": v} for k, v in m.items()]


def test_the_fit_recovers_the_costs_of_its_own_law(tmp_path):
    costs = (2e-6, 1e-6, 5e-6, 4e-4)
    runs = tmp_path / "runs.json"
    runs.write_text(json.dumps({"results": _synthetic("parallel/d2/n100000/phi0.5", 100000, costs)
                                + _synthetic("parallel/d2/n1000000/phi0.5", 1000000, costs)}))
    out = tmp_path / "model.json"
    subprocess.run([sys.executable, str(SCRIPT), "--runs", str(runs), "--json", str(out), "--cores", "2", "64"],
                   capture_output=True, text=True, check=True)
    doc = json.loads(out.read_text())
    for case in doc["cases"]:
        got = (case["c_event_s"], case["c_undone_s"], case["c_message_s"], case["c_gvt_barrier_s"])
        assert got == pytest.approx(costs, rel=1e-6)
        assert all(v["ratio_left_out"] == pytest.approx(1.0, rel=1e-6) for v in case["validation_leave_one_out"])
    assert {(p["n"], p["cores"], p["decomposition"]) for p in doc["predictions"]} == {
        (n, p, c) for n in (1e6, 1e7, 1e8) for p in (2, 64) for c in ("slabs", "blocks")}


def test_redundancy_follows_the_bands():
    mod = _module()
    cm = {"d": 2, "n": 1e6, "band_over_L": 0.0025, "events_per_collision_K1": 1.5, "undone_per_redundant": 10.0,
          "undone_per_redundant_worst": 20.0, "messages_per_redundant": 1.4, "messages_per_redundant_worst": 1.4,
          "imbalance_K2": 1.0, "c_event_s": 1e-6, "c_undone_s": 0.0, "c_message_s": 0.0, "c_gvt_barrier_s": 0.0,
          "gvts_per_busiest_event": 0.0, "gvt_step_s_per_event": 0.0, "seq_s_per_collision": 1.5e-6}
    slabs = mod.predict(cm, 1e6, 64, False, False)
    assert slabs["rho"] == pytest.approx(1 + 2 * 64 * 0.0025)
    blocks = mod.predict(cm, 1e6, 64, True, False)
    assert blocks["rho"] == pytest.approx((1 + 2 * 0.0025 * 8) ** 2)
    assert mod.predict(cm, 1e8, 64, False, False)["rho"] == pytest.approx(1 + 2 * 64 * 0.00025)  # W / L as N^(-1/2)
    assert mod.predict({**cm, "band_over_L": 0.5}, 1e6, 4, False, False)["rho"] == 4  # at most K: every LP holds all
    assert mod.predict(cm, 1e6, 64, False, True)["speedup"] < slabs["speedup"]  # the pessimistic factors cost more


def test_the_committed_runs_give_the_committed_model(tmp_path):
    out = tmp_path / "model.json"
    subprocess.run([sys.executable, str(SCRIPT), "--runs", str(ROOT / "bench/results/lattice_parallel_scaling.json"),
                    "--json", str(out)], capture_output=True, text=True, check=True)
    got, want = json.loads(out.read_text()), json.loads((ROOT / "bench/results/lattice_parallel_model.json").read_text())
    assert len(got["predictions"]) == len(want["predictions"]) == 2 * 3 * 2 * 6
    for a, b in zip(got["predictions"], want["predictions"]):
        assert a["speedup"] == pytest.approx(b["speedup"], rel=1e-9) and a["decomposition"] == b["decomposition"]


def test_the_undone_slope_is_fitted_per_dimension():
    mod = _module()

    def case(d, n, undone_per_collision):  # undone per collision at K = 2 = u_red * e1 * 4 * beta
        return {"d": d, "n": n, "events_per_collision_K1": 1.0, "band_over_L": 0.25,
                "undone_per_redundant": undone_per_collision}

    two = [case(2, 1e4, 1.0), case(2, 1e6, 0.01)]           # N^-1
    three = [case(3, 1e5, 1.0), case(3, 1e6, 10 ** -0.5)]   # N^-0.5
    assert mod.undone_slope(two + three, 2) == pytest.approx(-1.0)
    assert mod.undone_slope(two + three, 3) == pytest.approx(-0.5)
    assert mod.undone_slope(two + three[:1], 3) == pytest.approx(-1.0)  # one 3D size: the 2D slope
    assert mod.undone_slope(three[:1], 3) == pytest.approx(-1.0 / 3)    # nothing to fit: the bands'
