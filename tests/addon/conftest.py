"""The bpy module, reset to an empty factory scene for each test."""

import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def bpy_module():
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    return bpy


@pytest.fixture(scope="session")
def addon():
    """The extension's package, imported as Blender imports it (scripts/addon_dev.py)."""
    import importlib

    sys.path.insert(0, str(ROOT / "scripts"))
    from addon_dev import load_addon

    module = load_addon()
    importlib.import_module("twist_mocap.twist_addon.bridge")
    return module


@pytest.fixture(scope="session")
def registered(addon):
    """The add-on's classes registered once (they survive factory resets)."""
    addon.twist_addon.register()
    yield addon
    addon.twist_addon.unregister()
