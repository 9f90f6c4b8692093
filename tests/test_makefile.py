"""The Makefile's set-up as a newcomer meets it with the wrong Python."""

import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.skipif(shutil.which("make") is None, reason="needs make")
def test_a_python_other_than_3_11_is_named_before_anything_is_installed(tmp_path):
    fake = tmp_path / "python3.12"
    fake.write_text("#!/bin/sh\nexit 1\n")  # a Python that is not 3.11: its check fails
    fake.chmod(0o755)
    venv = tmp_path / "venv"
    proc = subprocess.run(["make", "-C", str(ROOT), "venv", f"PYTHON={fake}", f"VENV={venv}"],
                          capture_output=True, text=True)
    assert proc.returncode != 0
    assert "twist-mocap needs Python 3.11 (Blender 5.0's)" in proc.stderr
    assert "make PYTHON=python3.11 venv" in proc.stderr
    assert not venv.exists()  # nothing half-built to be reused
