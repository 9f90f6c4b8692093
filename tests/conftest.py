"""Shared paths for the tests."""

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
CMU_WALK = ROOT / "bench" / "data" / "cmu_131_01_walk.bvh"


@pytest.fixture(scope="session")
def cmu_walk() -> Path:
    return CMU_WALK
