"""The extension as a user gets it: built into a zip by Blender's own tool, installed with
Blender's own installer into an isolated user folder, enabled in a fresh Blender process, with
scipy and OpenCV loaded from the extension's bundled wheels."""

import dataclasses
import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from core.settings import TrackerSettings

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    dist = tmp_path_factory.mktemp("dist")
    subprocess.run([sys.executable, str(ROOT / "scripts" / "build_extension.py"), "--out",
                    str(dist)], check=True, capture_output=True, text=True)
    zips = sorted(dist.glob("twist_mocap-*-linux_x64.zip"))
    assert len(zips) == 1, list(dist.iterdir())
    user = tmp_path_factory.mktemp("blender_user")
    env = dict(os.environ, BLENDER_USER_RESOURCES=str(user))
    install = f"""
        import bpy
        result = bpy.ops.extensions.package_install_files(
            filepath={str(zips[0])!r}, repo="user_default", enable_on_install=True)
        assert result == {{"FINISHED"}}, result
    """
    proc = subprocess.run([sys.executable, "-c", textwrap.dedent(install)], env=env,
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return env, user


def _in_blender(env, code: str) -> dict:
    """Run code in a fresh process with the extension enabled; it sets ``out`` to report."""
    script = textwrap.dedent("""
        import json, bpy, addon_utils
        addon_utils.enable("bl_ext.user_default.twist_mocap", default_set=True,
                           handle_error=None)
        out = {}
    """) + textwrap.dedent(code) + "\nprint('RESULT' + json.dumps(out))\n"
    proc = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True,
                          text=True)
    assert proc.returncode == 0, proc.stderr[-2000:]
    line = next(x for x in proc.stdout.splitlines() if x.startswith("RESULT"))
    return json.loads(line[len("RESULT"):])


def test_bundled_wheels_load_from_the_extension(installed):
    env, user = installed
    out = _in_blender(env, """
        import scipy, cv2, numpy
        out = {"scipy": scipy.__file__, "cv2": cv2.__file__, "numpy": numpy.__version__,
               "versions": [scipy.__version__, cv2.__version__]}
    """)
    site = str(user / "extensions" / ".local" / "lib")
    assert out["scipy"].startswith(site) and out["cv2"].startswith(site), out
    assert out["versions"] == ["1.17.1", "4.11.0"]
    assert out["numpy"].startswith("1.26")  # Blender's own numpy, never bundled


def test_scene_settings_mirror_the_core_tracker_settings(installed):
    env, _ = installed
    out = _in_blender(env, """
        import dataclasses, importlib
        pkg = "bl_ext.user_default.twist_mocap"
        props = importlib.import_module(pkg + ".twist_addon.properties")
        settings = importlib.import_module(pkg + ".core.settings")
        scene = bpy.context.scene
        pg = scene.twist.tracker
        rna = pg.bl_rna.properties
        out["defaults"] = {f.name: getattr(pg, f.name)
                           for f in dataclasses.fields(settings.TrackerSettings)}
        out["tooltips"] = {f.name: rna[f.name].description
                           for f in dataclasses.fields(settings.TrackerSettings)}
        pg.levels, pg.key_weight, pg.stop_on_divergence = 2, 0.25, False
        s = props.settings_from_properties(pg)
        out["changed"] = [s.levels, s.key_weight, s.stop_on_divergence]
        out["mode"] = scene.twist.mode
    """)
    expect = {f.name: f.default for f in dataclasses.fields(TrackerSettings)}
    assert out["defaults"].keys() == expect.keys()
    for k, v in expect.items():
        assert out["defaults"][k] == pytest.approx(v), k
    assert all(len(t) > 15 for t in out["tooltips"].values()), out["tooltips"]
    assert out["changed"] == [2, 0.25, False]
    assert out["mode"] == "CALIBRATED"


def test_track_runs_through_the_installed_extension(installed, tmp_path):
    sys.path.insert(0, str(ROOT / "bench"))
    from walk_footage import render

    render(tmp_path, 560, 568, 4, ["lateral"])  # three frames, one view
    env, _ = installed
    out = _in_blender(env, f"""
        import sys
        sys.path.insert(0, {str(ROOT / "bench")!r})
        from pathlib import Path
        from walk_footage import tracking_scene
        scene, arm = tracking_scene(bpy, Path({str(tmp_path)!r}), ["lateral"], 3)
        out["result"] = sorted(bpy.ops.twist.track())
        ad = arm.animation_data
        bag = ad.action.layers[0].strips[0].channelbag(ad.action_slot)
        out["keys"] = sorted({{(int(k.co[0]), k.type) for fc in bag.fcurves
                              for k in fc.keyframe_points}})
        out["tracked"] = scene.twist.result.frames_tracked
    """)
    assert out["result"] == ["FINISHED"]
    # the first frame keeps the user's pose as a key, the two after it are tracked
    assert out["keys"] == [[1, "GENERATED"], [2, "GENERATED"], [3, "GENERATED"]]
    assert out["tracked"] == 2


def test_the_manifest_asks_for_the_blender_the_add_on_is_tested_with():
    """The add-on uses Blender 5's animation API (action slots and channelbags) and is tested
    with the bpy module only: its manifest must not promise an older Blender."""
    import tomllib

    import bpy

    manifest = tomllib.loads((ROOT / "blender_manifest.toml").read_text())
    wanted = tuple(int(x) for x in manifest["blender_version_min"].split("."))
    assert wanted <= tuple(bpy.app.version)
    assert wanted[:2] == tuple(bpy.app.version)[:2]
