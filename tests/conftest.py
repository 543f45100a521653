"""Shared pytest fixtures: the real Blender (``bpy`` from PyPI) and the shared BVH clips.

Pure-core tests need none of this and never import ``bpy``.  Blender tests ask for
``blender`` (the add-on registered once per test run, from this working tree, as the
package ``monoskel``) or ``empty_scene`` (a clean scene for one test).  Inside Blender
tests use ``monoskel.core``, not the top-level ``core``: the two are separate module
objects, and Blender-side code compares classes from ``monoskel.core``.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[1]
SHARED_BVH_DIR = REPO_ROOT.parent / "shared" / "data" / "bvh"

# `import core` and `import extension_loader` must work whatever directory pytest runs from.
if str(REPO_ROOT) not in sys.path:
    sys.path.insert(0, str(REPO_ROOT))

try:  # hypothesis is a test dependency, but keep core tests runnable without it.
    from hypothesis import HealthCheck, settings
except ImportError:  # pragma: no cover
    pass
else:
    # The CI machine has 2 cores shared with other jobs: a per-example deadline would make
    # property tests fail on load, not on bugs.
    settings.register_profile(
        "monoskel", deadline=None, suppress_health_check=[HealthCheck.too_slow], print_blob=True
    )
    settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "monoskel"))


def pytest_report_header(config):
    """Show which Blender, numpy and scipy ran, so CI logs prove both Blender versions ran."""
    lines = []
    try:
        import bpy
    except ImportError:
        lines.append("blender: bpy not importable (Blender tests will fail)")
    else:
        lines.append(f"blender: {bpy.app.version_string} (bpy {'.'.join(map(str, bpy.app.version))})")
    for name in ("numpy", "scipy"):
        try:
            module = __import__(name)
        except ImportError:
            lines.append(f"{name}: not installed")
        else:
            lines.append(f"{name}: {module.__version__}")
    return lines


@pytest.fixture(scope="session")
def shared_bvh_dir() -> Path:
    """The real BVH clips in ``<repo>/../shared/data/bvh`` (never copied into the repo).

    Missing folder: a failure on CI (where the clips must be present), a skip elsewhere
    (e.g. a fresh clone on a developer machine).
    """
    if SHARED_BVH_DIR.is_dir():
        return SHARED_BVH_DIR
    message = f"shared BVH clips not found at {SHARED_BVH_DIR}"
    if os.environ.get("CI"):
        pytest.fail(message + " (required on CI)")
    pytest.skip(message)


@pytest.fixture(scope="session")
def blender():
    """Blender at factory settings with this working tree registered as the add-on ``monoskel``.

    Yields the ``monoskel`` package module.  Unregisters at the end of the test run, letting any
    exception from unregister fail the run (a leak there is a real bug).
    """
    import bpy

    import extension_loader

    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon = extension_loader.load_extension()
    addon.register()
    try:
        yield addon
    finally:
        addon.unregister()


@pytest.fixture
def empty_scene(blender):
    """A clean, empty scene for one test, with the add-on still registered.

    ``read_factory_settings(use_empty=True)`` drops every datablock (objects, actions, cameras,
    armatures, texts, movie clips, extra scenes) and resets ``scene.monoskel`` to its defaults.
    The add-on was registered by hand (not through the preferences), so the reset leaves its
    classes and ``Scene.monoskel`` in place; verified on bpy 5.0.1 and 4.2 LTS.
    """
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    assert hasattr(bpy.types.Scene, "monoskel"), "factory reset unregistered the add-on"
    return bpy.context.scene


_EXIT_STATUS: list[int] = []


def pytest_sessionfinish(session, exitstatus):
    _EXIT_STATUS.append(int(exitstatus))


@pytest.hookimpl(trylast=True)
def pytest_unconfigure(config):
    """Leave at once, with pytest's status, once Rigify has been loaded into the bpy module.

    With Rigify enabled and scipy.optimize (or scipy.signal) imported, the bpy 4.5 module hangs in its
    native teardown after Python has finished (measured: a three-line script with
    ``addon_utils.enable('rigify')`` and ``import scipy.optimize`` never exits on bpy 4.5.15; it exits on
    4.2 and 5.0).  The retargeting tests enable Rigify; everything pytest reports is done by now.
    """
    if "rigify" in sys.modules and _EXIT_STATUS:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(_EXIT_STATUS[-1])
