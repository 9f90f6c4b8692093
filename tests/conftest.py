"""Shared paths for the tests."""

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared"
CMU_WALK = SHARED / "data" / "mocap" / "cmu_131_01_walk.bvh"


@pytest.fixture(scope="session")
def cmu_walk() -> Path:
    if not CMU_WALK.is_file():
        pytest.fail(f"{CMU_WALK} is missing: the tests need ../shared beside the repository")
    return CMU_WALK
