"""batch.py as the user runs it: a subprocess with this Python (PyPI bpy), checked from the files it writes."""

import json
import subprocess
import sys
from pathlib import Path

import bpy
import pytest

ROOT = Path(__file__).resolve().parents[2]


def _run(*args, cwd=None):
    return subprocess.run([sys.executable, str(ROOT / "batch.py"), *map(str, args)], capture_output=True,
                          text=True, timeout=300, cwd=cwd)


def test_builtin_run_writes_a_blend_that_reopens_with_rig_camera_and_actions(blender, tmp_path):
    from monoskel.blender import compat, scene_data

    blend, result = tmp_path / "demo.blend", tmp_path / "demo_result.json"
    proc = _run("--builtin", "walk", "--frames", "24", "--method", "truth", "--output", blend, "--result", result,
                "--bvh", tmp_path / "demo.bvh")
    assert proc.returncode == 0, proc.stderr
    assert "hip" in proc.stdout and "focal" in proc.stdout  # the summary table
    assert "[monoskel] INFO" in proc.stderr                 # progress on stderr
    assert json.loads(result.read_text())["format"] == "skeleton-estimate"
    assert (tmp_path / "demo.bvh").is_file()
    page = (tmp_path / "demo.review.html").read_text(encoding="utf-8")      # the headless review
    assert "Camera angles" in page and "Focal length" in page and "Proportions against the average adult" in page
    assert "no per-frame reprojection errors" in page                   # the truth was not fitted to anything
    assert "demo.review.html" in proc.stdout
    bpy.ops.wm.open_mainfile(filepath=str(blend))
    try:
        arm = next(o for o in bpy.data.objects if o.type == 'ARMATURE')
        cam = next(o for o in bpy.data.objects if o.type == 'CAMERA')
        assert len(arm.data.bones) == 16
        assert ('pose.bones["spine_lower"].location', 0) in compat.fcurve_paths(arm)
        assert ("rotation_euler", 0) in compat.fcurve_paths(cam)
        assert ("lens", 0) in compat.fcurve_paths(cam.data)
        assert bpy.context.scene.frame_end - bpy.context.scene.frame_start + 1 == 24
        assert len(scene_data.load_estimate(bpy.context.scene).frames) == 24
        takes = bpy.context.scene.monoskel.takes
        assert len(takes) == 1 and takes[0].armature == arm and arm.name in takes[0].collection.objects
    finally:
        bpy.ops.wm.read_factory_settings(use_empty=True)


def test_tracks_file_with_an_existing_estimate(blender, tmp_path):
    from monoskel.core.result import write_estimate_json
    from monoskel.core.synthetic.motion import load_motion
    from monoskel.core.synthetic.synth import synthesize
    from monoskel.core.synthetic.truth import truth_as_estimate
    from monoskel.core.tracks import write_tracks_json

    tracks, truth = synthesize(load_motion("builtin:walk", max_frames=10), seed=4)
    write_tracks_json(tracks, tmp_path / "clip.json")
    write_estimate_json(truth_as_estimate(truth), tmp_path / "est.json")
    proc = _run("--", tmp_path / "clip.json", "--estimate", tmp_path / "est.json", "--output", tmp_path / "o.blend",
                "--no-report")
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "o.blend").is_file() and not (tmp_path / "o.review.html").exists()


@pytest.mark.parametrize("make_args, says", [
    (lambda d: [d / "missing.json", "--output", d / "o.blend"], "no such file"),
    (lambda d: [d / "bad.json", "--output", d / "o.blend"], "bad.json"),
    (lambda d: ["--builtin", "walk", "--output", d / "o.blend", "--method", "nonsense"], "nonsense"),
    (lambda d: ["--builtin", "walk", "--output", d / "missing_dir" / "o.blend"], "does not exist"),
    (lambda d: ["--builtin", "walk"], "--output"),
    (lambda d: ["--builtin", "walk", "--output", d / "o.blend", "--height-m", "x"], "height"),
])
def test_bad_input_exits_nonzero_with_one_line_and_writes_nothing(tmp_path, make_args, says):
    (tmp_path / "bad.json").write_text("{not json")
    before = set(tmp_path.rglob("*"))
    proc = _run(*make_args(tmp_path))
    assert proc.returncode != 0
    lines = [line for line in proc.stderr.splitlines() if line.strip() and not line.startswith("[monoskel]")]
    assert len(lines) == 1, proc.stderr
    assert says in lines[0]
    assert set(tmp_path.rglob("*")) == before


def test_help_describes_the_command(tmp_path):
    proc = _run("--help")
    assert proc.returncode == 0
    assert "--builtin" in proc.stdout and "--output" in proc.stdout


def test_static_points_and_the_background_switch(blender, tmp_path):
    """--static-points films background points too and the estimate uses them; --no-background does not;
    --static-points on a tracks file is refused before anything is written."""
    result = tmp_path / "r.json"
    proc = _run("--builtin", "walk", "--frames", "90", "--static-points", "10", "--output", tmp_path / "a.blend",
                "--result", result)
    assert proc.returncode == 0, proc.stderr
    assert "background tracks" in proc.stderr
    assert "scene_camera" in json.loads(result.read_text())["diagnostics"]
    proc = _run("--builtin", "walk", "--frames", "90", "--static-points", "10", "--no-background",
                "--output", tmp_path / "b.blend", "--result", result)
    assert proc.returncode == 0, proc.stderr
    assert "scene_camera" not in json.loads(result.read_text())["diagnostics"]
    (tmp_path / "t.json").write_text("{}")
    proc = _run(tmp_path / "t.json", "--static-points", "4", "--output", tmp_path / "c.blend")
    assert proc.returncode == 2 and "needs a .bvh or --builtin" in proc.stderr
    assert not (tmp_path / "c.blend").exists()


def test_target_rig_gets_the_motion_in_the_output(blender, tmp_path):
    from monoskel.blender import compat
    from tests.blender.rigs import mixamo_rig

    bpy.ops.wm.read_factory_settings(use_empty=True)
    rig_file = tmp_path / "character.blend"
    mixamo_rig(bpy.context.scene)
    bpy.ops.wm.save_as_mainfile(filepath=str(rig_file))
    bpy.ops.wm.read_factory_settings(use_empty=True)
    out = tmp_path / "shot.blend"
    proc = _run("--builtin", "walk", "--frames", "40", "--method", "truth", "--output", out,
                "--target-rig", f"{rig_file}:Character")
    assert proc.returncode == 0, proc.stderr
    assert "retargeted onto 'Character'" in proc.stderr
    bpy.ops.wm.open_mainfile(filepath=str(out))
    try:
        obj = bpy.data.objects["Character"]
        assert obj.animation_data.action.name == "Character|MonoSkel"
        frames, _ = compat.get_keys(obj, 'pose.bones["mixamorig:LeftForeArm"].rotation_quaternion', 0)
        assert len(frames) == 40
        assert obj.get("monoskel_bone_map")
    finally:
        bpy.ops.wm.read_factory_settings(use_empty=True)
    for spec, says in ((f"{rig_file}:Nobody", "no object 'Nobody'"), ("missing.blend:Character", "no such file"),
                       (str(rig_file), "FILE.blend:ARMATURE")):
        bad = tmp_path / "bad.blend"
        proc = _run("--builtin", "walk", "--frames", "20", "--method", "truth", "--output", bad, "--target-rig", spec)
        assert proc.returncode == 2 and says in proc.stderr, proc.stderr
        assert not bad.exists()


def test_several_views_make_one_estimate_and_a_camera_per_view(blender, tmp_path):
    from monoskel.core.multiview import write_calibration
    from monoskel.core.multiview.synth import film_views, ring_cameras
    from monoskel.core.synthetic.motion import load_motion
    from monoskel.core.tracks import write_tracks_json

    motion = load_motion("builtin:walk", max_frames=40)
    cams = ring_cameras(motion, 3, seed=2)
    paths = []
    for k, view in enumerate(film_views(motion, cams, noise_px=0.5, seed=2)):
        paths.append(tmp_path / f"view{k + 1}.json")
        write_tracks_json(view, paths[-1])
    write_calibration(cams, tmp_path / "cal.json")
    blend, result = tmp_path / "mv.blend", tmp_path / "mv.json"
    proc = _run(paths[0], "--views", paths[1], paths[2], "--calibration", tmp_path / "cal.json", "--output", blend,
                "--result", result, "--no-report")
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(result.read_text())
    assert doc["method"] == "multiview" and len(doc["diagnostics"]["cameras"]) == 3
    bpy.ops.wm.open_mainfile(filepath=str(blend))
    try:
        assert sum(o.type == 'CAMERA' for o in bpy.data.objects) == 3
        # every further view shows its own tracks through its camera, and the views stay on the scene
        for cam in (o for o in bpy.data.objects if o.get("monoskel_view")):
            assert any(c.name.endswith(" Tracks") for c in cam.children)
        from monoskel.blender import scene_data

        views, cameras = scene_data.load_views(bpy.context.scene)
        assert len(views) == 2 and len(cameras) == 3
    finally:
        bpy.ops.wm.read_factory_settings(use_empty=True)
    proc = _run("--builtin", "walk", "--views", paths[1], "--output", blend)
    assert proc.returncode == 2 and "tracks files" in proc.stderr


def test_a_frame_range_estimates_one_stretch_in_its_place_on_the_timeline(blender, tmp_path):
    from monoskel.core.synthetic.motion import load_motion
    from monoskel.core.synthetic.synth import synthesize
    from monoskel.core.tracks import write_tracks_json

    tracks, _ = synthesize(load_motion("builtin:walk", max_frames=60), seed=4)
    write_tracks_json(tracks, tmp_path / "clip.json")
    result = tmp_path / "r.json"
    proc = _run(tmp_path / "clip.json", "--frame-range", "10-39", "--output", tmp_path / "o.blend", "--result", result,
                "--no-report")
    assert proc.returncode == 0, proc.stderr
    assert "using frames 10-39" in proc.stderr
    assert len(json.loads(result.read_text())["frames"]) == 30
    bpy.ops.wm.open_mainfile(filepath=str(tmp_path / "o.blend"))
    try:
        scene = bpy.context.scene
        assert (scene.frame_start, scene.frame_end) == (11, 40)      # tracks frame 0 sits at scene frame 1
        assert scene.monoskel.tracks_first_frame == 11
    finally:
        bpy.ops.wm.read_factory_settings(use_empty=True)
    for bad, says in (("39-10", "first <= last"), ("10-", "--frame-range must look like"),
                      ("10-99", "not within 0-59")):
        proc = _run(tmp_path / "clip.json", "--frame-range", bad, "--output", tmp_path / "x.blend")
        assert proc.returncode != 0 and says in proc.stderr, (bad, proc.stderr)
        assert not (tmp_path / "x.blend").exists()
    proc = _run("--builtin", "walk", "--frame-range", "1-5", "--output", tmp_path / "x.blend")
    assert proc.returncode == 2 and "--frame-range takes a stretch" in proc.stderr
