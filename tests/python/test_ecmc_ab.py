"""bench/ecmc_ab.py: two builds of the event-chain sampler interleaved (here the installed one
twice, at 1% of the chains): it must see the same Z bits and write its JSON."""
import json
import os
import subprocess
import sys
from pathlib import Path

import revcol

SCRIPT = Path(__file__).resolve().parents[2] / "bench" / "ecmc_ab.py"


def test_two_builds_interleaved(tmp_path):
    pkg = os.path.dirname(os.path.dirname(revcol.__file__))
    out = tmp_path / "ab.json"
    r = subprocess.run([sys.executable, str(SCRIPT), pkg, pkg, "--rounds", "2", "--scale", "0.01", "--json", str(out)],
                       capture_output=True, text=True, check=True)
    assert "same Z bits: True" in r.stdout
    doc = json.loads(out.read_text())
    assert len(doc["runs"]) == 8 and set(doc["summary"]) == {"2d_phi0.6", "3d_phi0.45"}
    assert all(s["same_z_bits"] for s in doc["summary"].values())
