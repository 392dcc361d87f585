"""revcol.studies.eos_zinf_compare on the committed results: every engine Z(inf) has its chains'
Z(inf), and the table is what docs/physics.md quotes (within 3 combined errors everywhere)."""
from pathlib import Path

from revcol.studies import eos_zinf_compare as mod

ROOT = Path(__file__).resolve().parents[2]


def test_committed_results(capsys):
    r = ROOT / "bench" / "results"
    assert mod.main([str(r / "equilibrium_finite_size.json"), str(r / "eos_replicas_2d_phi0.6_fit.json"),
                     str(r / "ecmc_compare.json")]) == 0
    out = capsys.readouterr().out
    assert "| 2 | 0.60 | flux | replicas, N = 1000, 4000, 16000 |" in out
    import json
    rows = mod.rows(*(json.load(open(r / f)) for f in ("equilibrium_finite_size.json",
                                                       "eos_replicas_2d_phi0.6_fit.json", "ecmc_compare.json")))
    assert len(rows) == 14 and all(abs(x["sigmas"]) < 3 for x in rows)
