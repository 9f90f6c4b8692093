"""Build the installable extension: fetch the wheels the manifest names, then run Blender's
own extension builder (shipped inside the bpy module) to write one zip per platform.

    python scripts/build_extension.py [--out dist]

Wheels are downloaded into wheels/ (never committed) and reused when present.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
# pip matches platform tags exactly: every tag a wheel of ours is published under
PLATFORM_TAGS = {
    "manylinux": ["manylinux_2_28_x86_64", "manylinux2014_x86_64", "manylinux_2_17_x86_64"],
    "win_amd64": ["win_amd64"],
    "arm64": ["macosx_14_0_arm64", "macosx_13_0_arm64", "macosx_11_0_arm64"],
    "x86_64": ["macosx_14_0_x86_64", "macosx_13_0_x86_64", "macosx_10_15_x86_64"],
}


def fetch_wheels(manifest: dict) -> None:
    """Download every wheel the manifest lists that wheels/ does not hold yet."""
    for rel in manifest["wheels"]:
        path = ROOT / rel
        if path.is_file():
            continue
        name, version = re.match(r"([^-]+)-([^-]+)-", path.name).groups()
        key = next(k for k in PLATFORM_TAGS if k in path.name.split("-")[-1])
        cmd = [sys.executable, "-m", "pip", "download", "--no-deps", "--only-binary=:all:",
               "--python-version", "3.11", "-d", str(path.parent), "--quiet",
               f"{name.replace('_', '-')}=={version}"]
        for tag in PLATFORM_TAGS[key]:
            cmd += ["--platform", tag]
        subprocess.run(cmd, check=True)
        if not path.is_file():
            raise SystemExit(f"pip did not produce {path.name}; the manifest's wheel list and "
                             "PyPI disagree")


def blender_ext() -> Path:
    import bpy  # noqa: F401  (the module ships Blender's scripts)

    here = Path(sys.modules["bpy"].__file__)
    for base in here.parents:  # .../bpy/<version>/scripts/modules/bpy/__init__.py
        tool = base / "addons_core" / "bl_pkg" / "cli" / "blender_ext.py"
        if tool.is_file():
            return tool
    raise SystemExit(f"Blender's extension builder was not found above {here}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=ROOT / "dist")
    a = ap.parse_args(argv)
    manifest = tomllib.loads((ROOT / "blender_manifest.toml").read_text())
    fetch_wheels(manifest)
    a.out.mkdir(parents=True, exist_ok=True)
    subprocess.run([sys.executable, str(blender_ext()), "build", "--source-dir", str(ROOT),
                    "--output-dir", str(a.out), "--split-platforms"], check=True)
    for z in sorted(a.out.glob(f"{manifest['id']}-{manifest['version']}-*.zip")):
        print(f"{z} ({z.stat().st_size / 1e6:.0f} MB)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
