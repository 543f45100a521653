"""Build the per-platform extension zips into ``dist/`` with Blender's own builder.

Steps: download the manifest's wheels (tools/fetch_wheels.py), validate the source manifest,
``build --split-platforms``, then check every zip: Blender's validator accepts it, it holds exactly
its own platform's wheels, and no development file (tests, tools, CI, caches) slipped in.
Run with a Python that has ``bpy`` (``make package`` uses .venvs/bpy-5.0.1).
"""

from __future__ import annotations

import subprocess
import sys
import zipfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import blender_ext  # noqa: E402  (sibling tool modules; tools/ is not a package)
import fetch_wheels  # noqa: E402

ROOT = fetch_wheels.ROOT
DIST = ROOT / "dist"
DEV_ONLY = ("tests/", "tools/", ".ci/", ".venvs/", "docs/", "bench/", "out/", "dist/", "Makefile", "pyproject.toml")


def run(args: list[str]) -> None:
    subprocess.run(blender_ext.command(args), check=True, cwd=ROOT)


def check_zip(path: Path, wheels: list[Path]) -> None:
    """Fail loudly if a built package holds another platform's wheels or development files."""
    platform = path.stem.rsplit("-", 1)[-1].replace("_", "-")
    expected = {f"wheels/{w.name}" for w in wheels if fetch_wheels.blender_platform(w.name) == platform}
    with zipfile.ZipFile(path) as archive:
        names = archive.namelist()
    shipped = {n for n in names if n.startswith("wheels/")}
    if shipped != expected:
        raise SystemExit(f"error: {path.name} ships wheels {sorted(shipped)}, expected {sorted(expected)}")
    leaked = [n for n in names if n.startswith(DEV_ONLY) or "__pycache__" in n]
    if leaked:
        raise SystemExit(f"error: {path.name} contains development files: {leaked[:5]}")
    run(["validate", str(path)])


def main() -> int:
    wheels = fetch_wheels.fetch()
    run(["validate", str(ROOT)])
    DIST.mkdir(exist_ok=True)
    for old in DIST.glob("monoskel-*.zip"):
        old.unlink()
    run(["build", "--split-platforms", "--source-dir", str(ROOT), "--output-dir", str(DIST)])
    zips = sorted(DIST.glob("monoskel-*.zip"))
    platforms = fetch_wheels.manifest_platforms()
    if len(zips) != len(platforms):
        raise SystemExit(f"error: expected {len(platforms)} platform zips, built {[z.name for z in zips]}")
    for path in zips:
        check_zip(path, wheels)
    print("\nbuilt packages:")
    for path in zips:
        print(f"  {path.relative_to(ROOT)}  {path.stat().st_size / 1e6:.1f} MB ({path.stat().st_size} bytes)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
