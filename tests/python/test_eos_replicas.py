"""revcol.studies.eos_replicas, reduced: its summary by hand, and one small end-to-end study (two
seeds, two laws, a few hundred disks) through the same child processes as the full runs whose
JSON docs/physics.md quotes."""
import json
import math
import os
import sys

import pytest

from revcol.studies import eos_replicas as er


def test_summary_by_hand():
    runs = [{"law": "specular", "seed": s, "z": z, "z_block_error": e, "z_ref": 2.0}
            for s, (z, e) in enumerate([(2.0, 0.1), (2.2, 0.1), (2.4, 0.1)])]
    runs += [{"law": "flux", "seed": s, "z": z, "z_block_error": 0.05, "z_ref": 2.0}
             for s, z in enumerate([2.1, 2.1])]
    out = er.summarize(runs)
    sp = out["specular"]
    assert sp["runs"] == 3 and sp["mean"] == pytest.approx(2.2)
    assert sp["sd"] == pytest.approx(0.2) and sp["error_from_spread"] == pytest.approx(0.2 / math.sqrt(3))
    assert sp["scatter_ratio"] == pytest.approx(2.0)  # a spread twice what the blocks claimed
    assert sp["sigmas_from_liu"] == pytest.approx(0.2 / (0.2 / math.sqrt(3)))
    fl = out["flux"]
    assert fl["sd"] == 0.0 and fl["error_from_spread"] == 0.0 and fl["sigmas_from_liu"] is None
    d = out["specular - flux"]
    assert d["difference"] == pytest.approx(0.1) and d["error"] == pytest.approx(0.2 / math.sqrt(3))


def test_a_small_study_end_to_end(tmp_path):
    out = tmp_path / "rep.json"
    assert er.main(["--dim", "2", "--phi", "0.5", "--n", "200", "--per-particle", "100", "--seeds", "2",
                    "--json", str(out)]) == 0
    res = json.loads(out.read_text())
    assert [(r["law"], r["seed"]) for r in res["runs"]] == [("specular", 1), ("flux", 1), ("specular", 2), ("flux", 2)]
    for r in res["runs"]:  # pair collisions: 100 particle collisions per particle
        assert r["collisions"] == 200 * 100 // 2 and 3.0 < r["z"] < 5.5 and r["z_block_error"] > 0
    for law in ("specular", "flux"):
        s = res["summary"][law]
        assert s["runs"] == 2 and s["z_ref_liu"] == pytest.approx(4.10515873, rel=1e-8)
        assert s["rms_block_error"] > 0 and s["scatter_ratio"] >= 0
    assert "finished_utc" in res and not os.path.exists(str(out) + ".tmp")


def test_bad_arguments_are_named(tmp_path, capsys):
    with pytest.raises(SystemExit):
        er.main(["--dim", "2", "--phi", "0.5", "--n", "200", "--seeds", "1", "--json", str(tmp_path / "x.json")])
    assert "--seeds" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        er.main(["--dim", "2", "--phi", "1.5", "--n", "200", "--json", str(tmp_path / "x.json")])
    assert "--phi" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        er.main(["--json", str(tmp_path / "x.json")])  # neither a study nor --fit
    assert "--dim" in capsys.readouterr().err
    assert not (tmp_path / "x.json").exists()


def test_fit_in_one_over_n(tmp_path):
    """Three sizes on an exact line Z = 6.45 + 6 / N: the fit returns it, per law and pooled;
    an intercept 2 errors from Liu's value is 2 sigmas."""
    files = []
    for n in (1000, 4000, 16000):
        z = 6.45 + 6.0 / n
        summary = {law: {"mean": z + dz, "error_from_spread": 0.001, "z_ref_liu": 6.448} for law, dz in
                   (("specular", 0.0), ("flux", 0.0))}
        p = tmp_path / f"s{n}.json"
        p.write_text(json.dumps({"n": n, "summary": summary}))
        files.append(str(p))
    out_path = tmp_path / "fit.json"
    assert er.main(["--fit", *files, "--json", str(out_path)]) == 0
    res = json.loads(out_path.read_text())
    assert res["sizes"] == [1000, 4000, 16000]
    for key in ("specular", "flux", "pooled"):
        f = res["fits"][key]
        assert f["z_inf"] == pytest.approx(6.45, abs=1e-12) and f["a"] == pytest.approx(6.0, rel=1e-9)
        assert f["chi2"] == pytest.approx(0.0, abs=1e-12)
        assert f["sigmas_from_liu"] == pytest.approx(0.002 / f["z_inf_error"])
    assert res["fits"]["pooled"]["dof"] == 4 and res["fits"]["flux"]["dof"] == 1
    assert res["fits"]["pooled"]["z_inf_error"] < res["fits"]["flux"]["z_inf_error"]
