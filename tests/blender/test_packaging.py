"""The extension as a user gets it: Blender's validator, the Linux zip, an install through Blender's API.

Everything runs Blender's own extension code from the ``bpy`` under test (see tools/blender_ext.py).
The install happens in a subprocess because ``BLENDER_USER_RESOURCES`` must be set before ``bpy`` is
imported; it points at a temporary directory, so the user's real Blender configuration is never touched.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import textwrap
import tomllib
import zipfile
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
TOOLS = REPO / "tools"
MANIFEST = REPO / "blender_manifest.toml"
LINUX = "linux-x64"
# Never in a package a user installs.
DEV_ONLY = ("tests/", "tools/", ".ci/", ".venvs/", ".git/", "docs/", "bench/", "out/", "dist/", "Makefile",
            "pyproject.toml")


def _tool(*args: str, cwd: Path = REPO) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, *args], cwd=cwd, capture_output=True, text=True, timeout=600)


def _blender_ext(*args: str) -> subprocess.CompletedProcess:
    return _tool(str(TOOLS / "blender_ext.py"), *args)


def _manifest() -> dict:
    with open(MANIFEST, "rb") as fh:
        return tomllib.load(fh)


def test_manifest_passes_blenders_validator():
    result = _blender_ext("validate", str(REPO))
    assert result.returncode == 0, result.stdout + result.stderr


def test_manifest_fields_blender_requires():
    manifest = _manifest()
    assert manifest["schema_version"] == "1.0.0"
    assert manifest["id"] == "monoskel"
    assert re.fullmatch(r"\d+\.\d+\.\d+", manifest["version"])
    assert manifest["blender_version_min"] == "4.2.0"
    assert len(manifest["tagline"]) <= 64 and manifest["tagline"][-1].isalnum()
    platforms = set(manifest["platforms"])
    assert platforms == {"linux-x64", "windows-x64", "macos-arm64", "macos-x64"}
    # one cp311 scipy wheel per platform; the detector's LiteRT wherever it is built for cp311
    sys.path.insert(0, str(TOOLS))
    try:
        import fetch_wheels
    finally:
        sys.path.remove(str(TOOLS))
    wheels = manifest["wheels"]
    assert all(re.search(r"-cp311-cp311-", w) for w in wheels)
    scipy = [w for w in wheels if Path(w).name.startswith("scipy-")]
    assert sorted(fetch_wheels.blender_platform(Path(w).name) for w in scipy) == sorted(platforms)
    litert = [w for w in wheels if Path(w).name.startswith("ai_edge_litert-")]
    assert sorted(fetch_wheels.blender_platform(Path(w).name) for w in litert) == ["linux-x64", "macos-arm64"]
    assert len(scipy) + len(litert) == len(wheels)


@pytest.mark.parametrize(
    "field, bad_value",
    [("tagline", '"Ends with a full stop."'), ("tags", '["Animation", "No Such Tag"]'), ("version", '"0.1"')],
)
def test_validator_rejects_a_broken_manifest(tmp_path, field, bad_value):
    """The validator we rely on must actually catch mistakes (otherwise the test above proves nothing)."""
    text = re.sub(rf"(?m)^{field} = .*$", f"{field} = {bad_value}", MANIFEST.read_text())
    (tmp_path / "blender_manifest.toml").write_text(text)
    shutil.copy(REPO / "__init__.py", tmp_path / "__init__.py")
    result = _blender_ext("validate", str(tmp_path))
    assert result.returncode != 0, f"validator accepted {field} = {bad_value}: {result.stdout}"


def _linux_only_manifest(text: str, linux_wheels: list[str]) -> str:
    """The real manifest restricted to Linux (so the test downloads one wheel, not four)."""
    text = re.sub(r"(?m)^platforms = \[.*\]$", f'platforms = ["{LINUX}"]', text)
    wheels = ",\n".join(f'  "{w}"' for w in linux_wheels)
    text, count = re.subn(r"(?ms)^wheels = \[.*?\]$", f"wheels = [\n{wheels},\n]", text)
    assert count == 1
    return text


@pytest.fixture(scope="module")
def linux_zip(tmp_path_factory) -> Path:
    """Build the Linux package from a copy of the working tree with Blender's builder."""
    fetched = _tool(str(TOOLS / "fetch_wheels.py"), "--platform", LINUX)
    assert fetched.returncode == 0, fetched.stdout + fetched.stderr
    manifest = _manifest()
    sys.path.insert(0, str(TOOLS))
    try:
        import fetch_wheels
    finally:
        sys.path.remove(str(TOOLS))
    linux_wheels = [w for w in manifest["wheels"] if fetch_wheels.blender_platform(Path(w).name) == LINUX]
    assert linux_wheels

    source = tmp_path_factory.mktemp("source")
    shutil.copytree(
        REPO, source, dirs_exist_ok=True,
        ignore=shutil.ignore_patterns(".git", ".venvs", "wheels", "dist", "out", "build", "__pycache__",
                                      ".pytest_cache", ".ruff_cache", ".hypothesis", "*.blend", "*.blend1"),
    )
    (source / "wheels").mkdir()
    for wheel in linux_wheels:
        shutil.copy(REPO / wheel, source / wheel)
    restricted = _linux_only_manifest(MANIFEST.read_text(), linux_wheels)
    parsed = tomllib.loads(restricted)
    assert {k: v for k, v in parsed.items() if k not in ("platforms", "wheels")} == {
        k: v for k, v in manifest.items() if k not in ("platforms", "wheels")
    }
    (source / "blender_manifest.toml").write_text(restricted)

    out = tmp_path_factory.mktemp("dist")
    built = _blender_ext("build", "--split-platforms", "--source-dir", str(source), "--output-dir", str(out))
    assert built.returncode == 0, built.stdout + built.stderr
    zips = sorted(out.glob("*.zip"))
    assert [z.name for z in zips] == [f"monoskel-{manifest['version']}-linux_x64.zip"]
    return zips[0]


def test_linux_zip_holds_the_extension_and_its_wheels_only(linux_zip):
    with zipfile.ZipFile(linux_zip) as archive:
        names = archive.namelist()
    assert "blender_manifest.toml" in names and "__init__.py" in names
    assert any(n.startswith("core/") for n in names)
    wheels = sorted(n for n in names if n.endswith(".whl"))
    assert len(wheels) == 2 and all("manylinux" in w for w in wheels)
    assert "ai_edge_litert" in wheels[0] and "scipy" in wheels[1]
    # the pose detector's models and their licence travel with the extension
    assert {"models/blazepose/pose_detection.tflite", "models/blazepose/pose_landmark_full.tflite",
            "models/blazepose/LICENSE-mediapipe.txt"} <= set(names)
    # the learnt pose prior and pose lifter (core.motion_prior) are data, not code: they must ship too
    learnt = {"core/motion_prior/data/pose_prior.npz", "core/motion_prior/data/pose_lifter.npz",
              "core/motion_prior/data/pose_lifter_video.npz"}
    assert learnt <= set(names)
    with zipfile.ZipFile(linux_zip) as archive:                     # together within the 5 MB they may add
        assert sum(archive.getinfo(n).compress_size for n in learnt) < 5_000_000
    assert not [n for n in names if n.startswith(DEV_ONLY) or "__pycache__" in n or n.endswith(".pyc")]
    validated = _blender_ext("validate", str(linux_zip))
    assert validated.returncode == 0, validated.stdout + validated.stderr


# Runs in a fresh interpreter with BLENDER_USER_RESOURCES set.  The test environment has its own scipy
# (for the core tests); real Blender has none, so it is hidden here: the add-on must get scipy from the
# wheel it ships.  Prints one JSON line with what it found.
_INSTALL_SCRIPT = textwrap.dedent(
    """
    import importlib, importlib.machinery, importlib.util, json, os, pkgutil, sys

    zip_path = sys.argv[1]
    own_scipy = importlib.util.find_spec("scipy")
    hidden_dir = os.path.realpath(os.path.dirname(os.path.dirname(own_scipy.origin))) if own_scipy else None

    own_litert = importlib.util.find_spec("ai_edge_litert")
    hidden_dirs = {hidden_dir, os.path.realpath(os.path.dirname(os.path.dirname(own_litert.origin)))
                   if own_litert else None}

    class HideTestEnvironmentScipy:
        @staticmethod
        def find_spec(name, path=None, target=None):
            if name not in ("scipy", "ai_edge_litert"):
                return None
            search = [p for p in sys.path if os.path.realpath(p or ".") not in hidden_dirs]
            spec = importlib.machinery.PathFinder.find_spec(name, search)
            if spec is None:
                raise ModuleNotFoundError(f"No module named {name!r} (test environment's copy hidden)", name=name)
            return spec

    sys.meta_path.insert(0, HideTestEnvironmentScipy)
    facts = {}
    try:
        import scipy  # noqa: F401
        facts["scipy_before_install"] = scipy.__file__
        del sys.modules["scipy"]
    except ModuleNotFoundError:
        facts["scipy_before_install"] = None

    import bpy

    facts["blender"] = bpy.app.version_string
    bpy.ops.wm.read_factory_settings(use_empty=True)
    facts["repos"] = [repo.module for repo in bpy.context.preferences.extensions.repos]
    facts["install"] = sorted(
        bpy.ops.extensions.package_install_files(filepath=zip_path, repo="user_default", enable_on_install=True)
    )
    module_name = "bl_ext.user_default.monoskel"
    facts["enabled"] = module_name in {addon.module for addon in bpy.context.preferences.addons}
    addon = sys.modules[module_name]
    facts["addon_file"] = addon.__file__
    facts["operators"] = {cls.bl_idname: cls.is_registered for cls in addon.operators.classes}
    facts["ui_classes"] = {cls.__name__: cls.is_registered for cls in addon.ui.classes}
    facts["ops_monoskel"] = sorted(dir(bpy.ops.monoskel))
    panel = getattr(bpy.types, "MONOSKEL_PT_main", None)
    facts["panel"] = None if panel is None else [panel.bl_space_type, panel.bl_region_type, panel.bl_category]
    facts["scene_property"] = hasattr(bpy.context.scene, "monoskel")

    importlib.invalidate_caches()
    import numpy
    import scipy
    import scipy.linalg

    facts["scipy_file"] = scipy.__file__
    facts["scipy_version"] = scipy.__version__
    facts["scipy_solve"] = scipy.linalg.solve(numpy.array([[2.0, 0.0], [0.0, 4.0]]), numpy.array([2.0, 2.0])).tolist()
    facts["site_dir"] = os.path.join(bpy.utils.user_resource("EXTENSIONS"), ".local", "lib",
                                     f"python{sys.version_info[0]}.{sys.version_info[1]}", "site-packages")
    detection = importlib.import_module(module_name + ".core.pose_detection.runtime")
    facts["detector"] = list(detection.available())
    import ai_edge_litert
    facts["litert_file"] = ai_edge_litert.__file__
    core_failures = {}
    for info in pkgutil.walk_packages(addon.core.__path__, module_name + ".core."):
        if not info.name.endswith("__main__"):
            try:
                importlib.import_module(info.name)
            except Exception as ex:
                core_failures[info.name] = repr(ex)
    facts["core_import_failures"] = core_failures

    bpy.ops.preferences.addon_disable(module=module_name)
    facts["panel_after_disable"] = hasattr(bpy.types, "MONOSKEL_PT_main")
    facts["scene_property_after_disable"] = hasattr(bpy.types.Scene, "monoskel")
    print("FACTS " + json.dumps(facts))
    """
)


@pytest.fixture(scope="module")
def installed(linux_zip, tmp_path_factory) -> dict:
    """Install the Linux zip into a throw-away user repository and report what Blender registered."""
    work = tmp_path_factory.mktemp("install")
    user = work / "user_resources"
    user.mkdir()
    script = work / "install_and_probe.py"
    script.write_text(_INSTALL_SCRIPT)
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "BLENDER_USER_CONFIG",
                                                           "BLENDER_USER_SCRIPTS", "BLENDER_USER_EXTENSIONS")}
    env["BLENDER_USER_RESOURCES"] = str(user)
    result = subprocess.run([sys.executable, str(script), str(linux_zip)], cwd=work, env=env,
                            capture_output=True, text=True, timeout=600)
    lines = [line for line in result.stdout.splitlines() if line.startswith("FACTS ")]
    assert result.returncode == 0 and lines, f"install subprocess failed:\n{result.stdout}\n{result.stderr}"
    facts = json.loads(lines[-1][len("FACTS "):])
    facts["user_resources"] = str(user)
    return facts


def test_install_from_zip_through_blenders_extension_api(installed):
    import bpy

    assert installed["blender"] == bpy.app.version_string  # the same Blender as the rest of this run
    assert installed["install"] == ["FINISHED"]
    assert installed["enabled"]
    assert Path(installed["addon_file"]).resolve().is_relative_to(Path(installed["user_resources"]).resolve())


def test_installed_addon_registers_its_sidebar_and_operators(installed, blender):
    assert installed["panel"] == ["VIEW_3D", "UI", "MonoSkel"]
    assert installed["scene_property"]
    assert installed["ui_classes"] and all(installed["ui_classes"].values())
    # the installed zip registers the same operators as the working tree, and all of them
    expected = sorted(cls.bl_idname for cls in blender.operators.classes)
    assert sorted(installed["operators"]) == expected
    assert all(installed["operators"].values()), installed["operators"]
    monoskel_ops = sorted(f"monoskel.{name}" for name in installed["ops_monoskel"])
    assert monoskel_ops == sorted(i for i in expected if i.startswith("monoskel."))


def test_scipy_comes_from_the_bundled_wheel(installed):
    assert installed["scipy_before_install"] is None, "the test environment's scipy was not hidden"
    site_dir = Path(installed["site_dir"]).resolve()
    assert site_dir.is_relative_to(Path(installed["user_resources"]).resolve())
    assert Path(installed["scipy_file"]).resolve().is_relative_to(site_dir)
    assert installed["scipy_version"] == "1.13.1"
    assert installed["scipy_solve"] == [1.0, 0.5]


def test_the_pose_detector_runs_from_the_bundled_wheel_and_models(installed):
    assert installed["detector"] == [True, ""]
    assert Path(installed["litert_file"]).resolve().is_relative_to(Path(installed["site_dir"]).resolve())


def test_installed_core_imports_completely(installed):
    assert installed["core_import_failures"] == {}


def test_disabling_the_installed_addon_unregisters_it(installed):
    assert not installed["panel_after_disable"]
    assert not installed["scene_property_after_disable"]
