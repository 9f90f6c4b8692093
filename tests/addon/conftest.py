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
    """The extension's package, imported as Blender imports it: the repository root is the
    package (named ``twist_mocap`` here, whatever the clone's folder is called)."""
    import importlib
    import importlib.util

    if "twist_mocap" not in sys.modules:
        spec = importlib.util.spec_from_file_location(
            "twist_mocap", ROOT / "__init__.py", submodule_search_locations=[str(ROOT)])
        module = importlib.util.module_from_spec(spec)
        sys.modules["twist_mocap"] = module
        spec.loader.exec_module(module)
    importlib.import_module("twist_mocap.twist_addon.bridge")
    return sys.modules["twist_mocap"]


@pytest.fixture(scope="session")
def registered(addon):
    """The add-on's classes registered once (they survive factory resets)."""
    addon.twist_addon.register()
    yield addon
    addon.twist_addon.unregister()
