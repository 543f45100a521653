"""Download the wheels that ``blender_manifest.toml`` bundles into ``wheels/`` (git-ignored).

The manifest names exact wheel files (one per platform, cp311).  Each missing file is fetched
from PyPI with ``pip download --no-deps --only-binary=:all:`` for its own platform and Python
3.11, so this works from any host.  A download that yields a different file name (PyPI serving
another build) is an error rather than a silent substitution: the manifest must name what ships.

    python tools/fetch_wheels.py                      # all platforms
    python tools/fetch_wheels.py --platform linux-x64 # only what the Linux package needs
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MANIFEST = ROOT / "blender_manifest.toml"

# wheel platform tag -> Blender platform name, as in Blender's builder.
_BLENDER_PLATFORM = (
    (re.compile(r"^(many)?linux.*_x86_64$"), "linux-x64"),
    (re.compile(r"^win_amd64$"), "windows-x64"),
    (re.compile(r"^macosx_.*_arm64$"), "macos-arm64"),
    (re.compile(r"^macosx_.*_x86_64$"), "macos-x64"),
)


def wheel_platform_tag(filename: str) -> str:
    """The first platform tag of a wheel file name (``a.b`` compressed tag sets: the first one)."""
    return filename[: -len(".whl")].split("-")[-1].split(".")[0]


def blender_platform(filename: str) -> str:
    tag = wheel_platform_tag(filename)
    for pattern, name in _BLENDER_PLATFORM:
        if pattern.match(tag):
            return name
    raise SystemExit(f"error: cannot tell the Blender platform of wheel {filename}")


def manifest_wheels(manifest: Path = MANIFEST) -> list[Path]:
    with open(manifest, "rb") as fh:
        data = tomllib.load(fh)
    return [(manifest.parent / entry).resolve() for entry in data.get("wheels", [])]


def manifest_platforms(manifest: Path = MANIFEST) -> list[str]:
    with open(manifest, "rb") as fh:
        return list(tomllib.load(fh).get("platforms", []))


def download(wheel: Path) -> None:
    """Fetch one wheel named in the manifest into its place."""
    name, version = wheel.name.split("-")[:2]
    wheel.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [
            sys.executable, "-m", "pip", "download", "--quiet", "--disable-pip-version-check",
            "--no-deps", "--only-binary=:all:", "--python-version", "3.11", "--implementation", "cp",
            "--platform", wheel_platform_tag(wheel.name), "--dest", tmp, f"{name}=={version}",
        ]
        print("downloading", wheel.name, flush=True)
        subprocess.run(cmd, check=True)
        got = Path(tmp) / wheel.name
        if not got.is_file():
            found = ", ".join(p.name for p in Path(tmp).iterdir())
            raise SystemExit(f"error: PyPI served {found} instead of {wheel.name}; update blender_manifest.toml")
        shutil.move(str(got), wheel)


def fetch(platforms: set[str] | None = None) -> list[Path]:
    """Make sure the manifest's wheels (for ``platforms``, default all) exist; return their paths."""
    wanted = [w for w in manifest_wheels() if platforms is None or blender_platform(w.name) in platforms]
    for wheel in wanted:
        if not wheel.is_file():
            download(wheel)
    return wanted


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--platform", action="append", help="Blender platform, e.g. linux-x64 (repeatable)")
    args = parser.parse_args(argv)
    for wheel in fetch(set(args.platform) if args.platform else None):
        print(f"{wheel.relative_to(ROOT)}  {wheel.stat().st_size} bytes  ({blender_platform(wheel.name)})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
