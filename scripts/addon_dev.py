"""The working tree imported as the extension package, ``twist_mocap``, the way Blender
imports an installed extension (the repository root is the package). For the demo, the
example builder and the tests; Blender itself never needs it."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def load_addon():
    """The package (imported once; its ``register()`` is the caller's)."""
    if "twist_mocap" not in sys.modules:
        spec = importlib.util.spec_from_file_location(
            "twist_mocap", ROOT / "__init__.py", submodule_search_locations=[str(ROOT)])
        module = importlib.util.module_from_spec(spec)
        sys.modules["twist_mocap"] = module
        spec.loader.exec_module(module)
    return sys.modules["twist_mocap"]
