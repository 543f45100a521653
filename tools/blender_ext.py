"""Run Blender's own extension tool (build / validate) from the ``bpy`` module of this Python.

Without a ``blender`` binary, ``blender --command extension ...`` is not available, but the same
code ships inside the PyPI ``bpy`` wheel as ``bpy/<X.Y>/scripts/addons_core/bl_pkg/cli/blender_ext.py``.
This wrapper finds it (without importing bpy) and runs it, passing Blender's list of valid tags
to ``build`` and ``validate`` as ``blender --command extension`` does, so tags are checked too.

    python tools/blender_ext.py validate .
    python tools/blender_ext.py build --split-platforms --source-dir . --output-dir dist
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path


def bpy_scripts_dir() -> Path:
    """The ``scripts`` directory of the bpy module installed for this interpreter."""
    spec = importlib.util.find_spec("bpy")
    if spec is None or not spec.submodule_search_locations:
        raise SystemExit("error: the bpy module is not installed for " + sys.executable)
    package_dir = Path(next(iter(spec.submodule_search_locations)))
    candidates = sorted(package_dir.glob("[0-9]*.[0-9]*/scripts"))
    if len(candidates) != 1:
        raise SystemExit(f"error: expected one bpy/<X.Y>/scripts in {package_dir}, found {candidates}")
    return candidates[0]


def builder_path() -> Path:
    path = bpy_scripts_dir() / "addons_core" / "bl_pkg" / "cli" / "blender_ext.py"
    if not path.is_file():
        raise SystemExit(f"error: Blender's extension builder not found at {path}")
    return path


def valid_tags_path() -> Path:
    return bpy_scripts_dir() / "modules" / "_bpy_internal" / "extensions" / "tags.py"


def command(args: list[str]) -> list[str]:
    """The full command line for Blender's builder, with Blender's tag list added where it applies."""
    args = list(args)
    if args and args[0] in ("build", "validate") and not any(a.startswith("--valid-tags") for a in args):
        tags = valid_tags_path()
        if tags.is_file():
            args[1:1] = ["--valid-tags", str(tags)]
    return [sys.executable, str(builder_path()), *args]


def main(argv: list[str]) -> int:
    return subprocess.call(command(argv))


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
