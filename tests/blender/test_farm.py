"""batch.py --folder as the user runs it (this Python, PyPI bpy): a folder of small shots, one broken, built in
parallel; run again; forced; and the same folder as an Open Job Description job run by ``openjd run``."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
FRAMES = 24


def _run(*args, cwd=None, timeout=300):
    return subprocess.run([sys.executable, str(ROOT / "batch.py"), *map(str, args)], capture_output=True, text=True,
                          timeout=timeout, cwd=cwd)


def _shots(folder: Path, good=("walk", "turn"), broken=True) -> Path:
    """Small tracks files filmed from the built-in walk (a different camera seed each); with ``broken``, a file
    that is not JSON and a 3-frame video of a grey wall (no person in it)."""
    from monoskel.core.synthetic.motion import load_motion
    from monoskel.core.synthetic.synth import synthesize
    from monoskel.core.tracks import write_tracks_json

    folder.mkdir()
    motion = load_motion("builtin:walk", max_frames=FRAMES)
    for seed, name in enumerate(good):
        tracks, _ = synthesize(motion, seed=seed)
        write_tracks_json(tracks, folder / f"{name}.json")
    if broken:
        (folder / "broken.json").write_text("{not json")
        from tests.blender.test_pose_detection_clip import _frames, _mp4, _png_sequence

        tmp = folder.parent / "grey_frames"
        frames = _png_sequence(tmp, _frames(3, person=False))
        shutil.move(_mp4(tmp / "wall.mp4", frames, 3), folder / "wall.mp4")
        shutil.rmtree(tmp)
    return folder


def _mtimes(out: Path, names) -> dict:
    return {n: (out / n / f"{n}.blend").stat().st_mtime_ns for n in names}


@pytest.fixture(scope="module")
def folder_run(blender, tmp_path_factory):
    """Two good shots, a broken file and a video without a person, built two at a time with a shared option."""
    base = tmp_path_factory.mktemp("farm")
    shots, out = _shots(base / "shots"), base / "out"
    proc = _run("--folder", shots, "--output-dir", out, "--workers", "2", "--height-m", "1.6")
    return shots, out, proc


def test_a_folder_builds_each_good_shot_and_reports_the_broken_one(folder_run):
    shots, out, proc = folder_run
    assert proc.returncode == 1, proc.stdout + proc.stderr          # a shot failed: non-zero, at the end
    for name in ("walk", "turn"):
        for suffix in (".blend", "_result.json", ".review.html", ".log", ".status.json"):
            assert (out / name / f"{name}{suffix}").is_file(), (name, suffix)
        result = json.loads((out / name / f"{name}_result.json").read_text())
        assert len(result["frames"]) == FRAMES and result["height_m"] == pytest.approx(1.6)   # the shared option
        assert f"] {name}: built in " in proc.stdout                # a progress line per finished shot
    failed = [ln for ln in proc.stdout.splitlines() if "broken" in ln and "FAILED" in ln]
    assert len(failed) == 1 and "broken.json" in failed[0] and "JSON" in failed[0], proc.stdout
    failed = [ln for ln in proc.stdout.splitlines() if "wall" in ln and "FAILED" in ln]
    assert len(failed) == 1 and "no person found in any of the 3 frames" in failed[0], proc.stdout
    assert not (out / "broken" / "broken.blend").exists() and not (out / "wall" / "wall.blend").exists()
    assert not any((out / n / ".tmp").exists() for n in ("walk", "turn", "broken", "wall"))   # temp removed
    page = (out / "index.html").read_text(encoding="utf-8")
    assert "4 shots: 2 built, 2 failed" in page and "no person found" in page
    assert "href='walk/walk.review.html'" in page and "href='turn/turn.review.html'" in page
    assert "broken" in page and "invalid JSON" in page
    status = json.loads((out / "walk" / "walk.status.json").read_text())
    assert status["status"] == "ok" and status["peak_rss_mb"] > 50     # measured by the kernel for that process


def test_a_second_run_skips_built_shots_and_force_or_other_options_build_them_again(folder_run):
    shots, out, _ = folder_run
    before = _mtimes(out, ("walk", "turn"))
    proc = _run("--folder", shots, "--output-dir", out, "--workers", "2", "--height-m", "1.6")
    assert proc.returncode == 1                                  # the failed shots are tried again and fail
    assert "2 to build, 2 up to date" in proc.stdout, proc.stdout
    assert _mtimes(out, ("walk", "turn")) == before
    assert "(up to date)" in (out / "index.html").read_text(encoding="utf-8")
    os.remove(shots / "broken.json")
    os.remove(shots / "wall.mp4")
    proc = _run("--folder", shots, "--output-dir", out, "--workers", "2", "--height-m", "1.6", "--force")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert proc.stdout.splitlines()[0].endswith(": 2 to build, 2 at a time"), proc.stdout
    forced = _mtimes(out, ("walk", "turn"))
    assert all(forced[n] > before[n] for n in before)
    proc = _run("--folder", shots, "--output-dir", out, "--shot", "walk", "--height-m", "1.7")   # other options
    assert proc.returncode == 0 and "1 to build" in proc.stdout, proc.stdout + proc.stderr
    assert _mtimes(out, ("walk",))["walk"] > forced["walk"]
    assert json.loads((out / "walk" / "walk_result.json").read_text())["height_m"] == pytest.approx(1.7)


def test_openjd_run_on_the_bundle_builds_the_shots(blender, tmp_path):
    openjd = shutil.which("openjd", path=os.path.dirname(sys.executable)) or shutil.which("openjd")
    if openjd is None:
        message = "openjd (PyPI openjd-cli, pinned in tools/requirements-common.txt) is not installed"
        if os.environ.get("CI"):
            pytest.fail(message)
        pytest.skip(message)
    shots, out, bundle = _shots(tmp_path / "shots", broken=False), tmp_path / "out", tmp_path / "bundle"
    proc = _run("--folder", shots, "--output-dir", out, "--openjd-bundle", bundle, "--no-report")
    assert proc.returncode == 0, proc.stderr
    assert not out.exists()                                          # written, not run
    template = (bundle / "template.yaml").read_text()
    assert "specificationVersion: jobtemplate-2023-09" in template and "- turn" in template
    assert (bundle / "parameter_values.yaml").is_file() and (bundle / "asset_references.yaml").is_file()
    run = subprocess.run([openjd, "run", str(bundle / "template.yaml")], capture_output=True, text=True,
                         timeout=300, cwd=tmp_path)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    for name in ("walk", "turn"):
        assert (out / name / f"{name}.blend").is_file() and (out / name / f"{name}_result.json").is_file()
        assert not (out / name / f"{name}.review.html").exists()     # the shared --no-report reached the task
    assert "2 shots: 2 built, 0 failed" in (out / "index.html").read_text(encoding="utf-8")   # the Index step


@pytest.mark.parametrize("args, says", [
    (["--output-dir", "o"], "go with --folder"),
    (["--folder", "{shots}"], "needs --output-dir"),
    (["--folder", "{shots}", "--output-dir", "o", "--output", "x.blend"], "--output names one shot's"),
    (["--folder", "{shots}", "--output-dir", "o", "--bvh", "x.bvh"], "--exports bvh,fbx"),
    (["--folder", "{shots}", "--output-dir", "o", "--workers", "0"], "--workers must be 1 or more"),
    (["--folder", "{missing}", "--output-dir", "o"], "no such folder"),
    (["--folder", "{shots}", "--output-dir", "o", "--shot", "nobody"], "no shot 'nobody'"),
    (["--folder", "{shots}", "--output-dir", "o", "--exports", "obj"], "--exports takes bvh, fbx"),
])
def test_bad_folder_arguments_exit_2_with_one_line_and_write_nothing(tmp_path, args, says):
    (tmp_path / "shots").mkdir()
    (tmp_path / "shots" / "a.json").write_text("{}")
    before = set(tmp_path.rglob("*"))
    proc = _run(*(a.format(shots=tmp_path / "shots", missing=tmp_path / "missing") for a in args), cwd=tmp_path)
    assert proc.returncode == 2
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and says in lines[0], proc.stderr
    assert set(tmp_path.rglob("*")) == before


def test_print_tasks_gives_one_command_per_shot_then_the_index(tmp_path):
    import shlex

    for name in ("b.json", "a.csv", "c.mp4"):
        (tmp_path / name).write_text("{}")
    proc = _run("--folder", tmp_path, "--output-dir", tmp_path / "out", "--print-tasks", "--height-m", "1.6")
    assert proc.returncode == 0, proc.stderr
    tasks = [shlex.split(line) for line in proc.stdout.splitlines()]
    assert [t[t.index("--shot") + 1] for t in tasks[:-1]] == ["a", "b", "c"]
    assert all(t[0] == sys.executable and t[1] == str(ROOT / "batch.py") and "--height-m=1.6" in t for t in tasks[:-1])
    assert tasks[-1][-1] == "--index-only" and not (tmp_path / "out").exists()
