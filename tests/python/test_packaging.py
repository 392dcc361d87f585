"""Packaging (issue 19): the licence in the repository and in the package metadata.

The metadata is built with scikit-build-core's own PEP 517 hook
``prepare_metadata_for_build_wheel`` into a temporary directory; it reads pyproject.toml only
(no CMake run, nothing written into the source tree)."""
import email
import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _tracked_state() -> str:
    """git status of the source tree, ignored files included (what a build may leave behind)."""
    return subprocess.run(["git", "status", "--porcelain", "--ignored", "--untracked-files=all", "--", "."],
                          cwd=ROOT, capture_output=True, text=True, check=True).stdout


@pytest.fixture(scope="module")
def metadata(tmp_path_factory):
    from scikit_build_core.build import prepare_metadata_for_build_wheel

    out = tmp_path_factory.mktemp("meta")
    before = _tracked_state()
    cwd = os.getcwd()
    os.chdir(ROOT)  # a PEP 517 hook runs in the project directory
    try:
        name = prepare_metadata_for_build_wheel(str(out))
    finally:
        os.chdir(cwd)
    assert _tracked_state() == before, "preparing the metadata changed the source tree"
    return out / name


def test_licence_file_is_the_gpl3_text():
    text = (ROOT / "LICENSE").read_text()
    assert text.split()[:6] == ["GNU", "GENERAL", "PUBLIC", "LICENSE", "Version", "3,"]
    # the whole licence, not a stub: its last section and its closing paragraph are there
    assert "How to Apply These Terms to Your New Programs" in text
    assert text.rstrip().endswith("<https://www.gnu.org/licenses/why-not-lgpl.html>.")


def test_metadata_names_the_licence_and_carries_the_file(metadata):
    msg = email.message_from_string((metadata / "METADATA").read_text())
    assert msg["Metadata-Version"] in ("2.4", "2.5", "2.6")
    assert msg["License-Expression"] == "GPL-3.0-or-later"
    assert msg.get_all("License-File") == ["LICENSE"]
    assert (metadata / "licenses" / "LICENSE").read_bytes() == (ROOT / "LICENSE").read_bytes()
