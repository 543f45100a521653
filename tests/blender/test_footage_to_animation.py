"""From footage to animation without knowing the flags: the background followed by default (batch.py and
Animate from Clip), the fallback when the scene gives too little, the one button's chain with its cancel
and undo, the footage behind the built camera, the solved lens on the clip, and the review page's pictures.

The footage is small (12 frames): a real person (the public-domain astronaut photo) walking in front of a
textured scene the camera pans across (``person_footage.py``), or in front of a plain grey one.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.blender.person_footage import person_over_scene

ROOT = Path(__file__).resolve().parents[2]
N = 12


@pytest.fixture(scope="module")
def scene_clip(tmp_path_factory):
    return person_over_scene(tmp_path_factory.mktemp("scene"), N)


def _batch(*args):
    return subprocess.run([sys.executable, str(ROOT / "batch.py"), *map(str, args)], capture_output=True, text=True,
                          timeout=600)


def _pictures(html: str) -> list[bytes]:
    import base64

    return [base64.b64decode(b) for b in re.findall(r"src='data:image/png;base64,([^']+)'", html)]


def test_batch_video_follows_the_background_by_default_and_shows_the_footage(blender, tmp_path, scene_clip):
    import json

    import bpy

    from monoskel.blender.background_tracking import BG_PREFIX

    out, result = tmp_path / "shot.blend", tmp_path / "shot.json"
    proc = _batch("--video", scene_clip, "--output", out, "--result", result)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert re.search(r"background followed in [0-9.]+ s: \d+ background tracks", proc.stderr)
    scene_camera = json.loads(result.read_text())["diagnostics"]["scene_camera"]
    assert scene_camera["used"] and scene_camera["points"] >= 4, scene_camera
    est_focal = json.loads(result.read_text())["focal_mm"]
    # the review page beside the .blend: at least 4 frames of the footage, small
    html = (tmp_path / "shot.review.html").read_text()
    pictures = _pictures(html)
    assert len(pictures) >= 4 and all(p.startswith(b"\x89PNG") for p in pictures)
    assert len(html) < 3_000_000
    assert "frame 1:" in html and "worst fit" in html and "spread" in html
    bpy.ops.wm.open_mainfile(filepath=str(out))
    try:
        scene = bpy.context.scene
        clip = scene.active_clip
        assert sum(t.name.startswith(BG_PREFIX) for t in clip.tracking.tracks) == scene_camera["points"]
        camera = scene.monoskel.camera
        backgrounds = [b for b in camera.data.background_images if b.source == "MOVIE_CLIP"]
        assert camera.data.show_background_images and len(backgrounds) == 1 and backgrounds[0].clip == clip
        from monoskel.blender.movie_clip import clip_focal_mm

        assert clip_focal_mm(clip) == pytest.approx(est_focal, rel=0.05)
    finally:
        bpy.ops.wm.read_factory_settings(use_empty=True)

    # --no-background: nothing followed, the camera from the person alone
    result2 = tmp_path / "alone.json"
    proc = _batch("--video", scene_clip, "--output", tmp_path / "alone.blend", "--result", result2, "--no-report",
                  "--no-background")
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "background followed" not in proc.stderr
    assert not json.loads(result2.read_text())["diagnostics"].get("scene_camera")


def test_a_featureless_background_falls_back_to_the_person_with_one_warning(blender, tmp_path):
    """A tracks file beside plain grey footage: nothing to follow, one warning, the estimate still made."""
    import json

    from monoskel.core.io.png_plot import encode_png
    from monoskel.core.synthetic.motion import load_motion
    from monoskel.core.synthetic.synth import synthesize
    from monoskel.core.tracks import write_tracks_json

    tracks, _ = synthesize(load_motion("builtin:walk", max_frames=N), kinds=("pan",), noise_px=0.5, seed=1)
    write_tracks_json(tracks, tmp_path / "joints.json")
    w, h = (int(v) for v in tracks.image_size)
    for i in range(N):
        (tmp_path / f"grey_{i + 1:04d}.png").write_bytes(encode_png(np.full((h, w, 3), 128, np.uint8), level=1))
    result = tmp_path / "r.json"
    proc = _batch(tmp_path / "joints.json", "--footage", tmp_path / "grey_0001.png", "--output", tmp_path / "g.blend",
                  "--result", result, "--no-report")
    assert proc.returncode == 0, proc.stderr[-2000:]
    said = [line for line in proc.stderr.splitlines() if "WARNING: background: " in line]
    assert len(said) == 1 and "no background feature could be followed" in said[0], said
    assert said[0].endswith("the camera comes from the person alone")
    warnings = json.loads(result.read_text())["diagnostics"]["warnings"]
    assert warnings[0].startswith("background: no background feature")
    # asking for it by name changes nothing; asking for both is refused before anything is written
    proc = _batch(tmp_path / "joints.json", "--footage", tmp_path / "grey_0001.png", "--track-background",
                  "--no-background", "--output", tmp_path / "x.blend")
    assert proc.returncode == 2 and not (tmp_path / "x.blend").exists()


def _scene_state(scene):
    import bpy

    clip = scene.active_clip
    return {"objects": sorted(o.name for o in bpy.data.objects), "texts": sorted(t.name for t in bpy.data.texts),
            "actions": sorted(a.name for a in bpy.data.actions), "scenes": sorted(bpy.data.scenes.keys()),
            "tracks": sorted(t.name for t in clip.tracking.tracks), "has_tracks": scene.monoskel.has_tracks,
            "takes": len(scene.monoskel.takes), "frames": (scene.frame_start, scene.frame_end),
            "focal": clip.tracking.camera.focal_length, "camera": scene.camera}


def test_animate_from_clip_end_to_end_and_undo(empty_scene, scene_clip):
    import bpy

    from monoskel.blender import scene_data
    from monoskel.blender.background_tracking import BG_PREFIX
    from monoskel.core.skeleton import JOINTS
    from monoskel.ui import state

    clip = bpy.data.movieclips.load(str(scene_clip))
    empty_scene.active_clip = clip
    rows = state.input_rows(empty_scene.monoskel, has_clip=True)
    row = next(r for r in rows if r.op == "monoskel.animate_from_clip")
    assert row.enabled and rows.index(row) < 3            # the first thing the Input section offers
    bpy.ops.ed.undo_push(message="before")
    before = _scene_state(empty_scene)

    assert bpy.ops.monoskel.animate_from_clip() == {"FINISHED"}

    scene = bpy.context.scene
    settings = scene.monoskel
    tracks = scene_data.load_tracks(scene)
    assert tracks.n_frames == N and tracks.static is not None and tracks.static.n_points >= 4
    assert settings.has_estimate and settings.use_background and settings.armature is not None
    assert len(settings.takes) == 1 and scene.camera == settings.camera
    names = {t.name for t in clip.tracking.tracks}
    assert set(JOINTS) <= names and sum(n.startswith(BG_PREFIX) for n in names) == tracks.static.n_points
    assert not any(n.startswith("MonoSkel new") for n in names)
    assert [b.clip for b in settings.camera.data.background_images] == [clip]
    assert clip.tracking.camera.focal_length != before["focal"]
    lines = settings.animate_summary.split("\n")
    assert [line.split(":")[0] for line in lines[:4]] == ["pose", "background", "estimate", "build"], lines
    shown = [r.text for r in state.input_rows(settings, has_clip=True)]
    assert "Last run: Done" in shown and all(line in shown for line in lines)
    assert set(bpy.data.scenes.keys()) == set(before["scenes"])       # the decoding scene is gone
    # one undo step takes all of it back
    bpy.ops.ed.undo_push(message="after")
    bpy.ops.ed.undo()
    scene = bpy.context.scene
    assert _scene_state(scene) == {**before, "camera": None}
    assert scene_data.load_tracks(scene) is None

    # the sidebar's Follow Background unticked: the camera from the person alone
    scene.monoskel.animate_background = False
    assert bpy.ops.monoskel.animate_from_clip() == {"FINISHED"}
    scene = bpy.context.scene
    assert scene_data.load_tracks(scene).static is None and not scene.monoskel.use_background
    assert "background: not followed (switched off)" in scene.monoskel.animate_summary
    assert not any(t.name.startswith(BG_PREFIX) for t in scene.active_clip.tracking.tracks)


def test_cancel_or_failure_at_any_stage_leaves_the_scene_as_it_was(empty_scene, scene_clip):
    import bpy

    from monoskel.blender.animate import AnimateOptions, AnimateRun
    from monoskel.core.errors import Cancelled

    clip = bpy.data.movieclips.load(str(scene_clip))
    empty_scene.active_clip = clip
    clip.tracking.tracks.new(name="floor mark", frame=1)      # the animator's own track stays
    rig = bpy.data.objects.new("no bones", bpy.data.armatures.new("no bones"))
    empty_scene.collection.objects.link(rig)
    before = _scene_state(empty_scene)
    for stop_in in ("detect", "background", "estimate"):
        run = AnimateRun.start(clip, AnimateOptions(fps=25.0), chunk=4)
        with pytest.raises(Cancelled):
            while True:
                if run.stage == stop_in:
                    run.cancel()
                run.step(bpy.context)
                if run.waiting:
                    run.job.wait(0.05)
        run.abort(bpy.context)
        assert _scene_state(bpy.context.scene) == before, stop_in

    # a failure while the result goes into the scene (the retarget, after the tracks, the estimate and the
    # take are in) puts everything back
    from monoskel.blender.animate.chain import run_to_end
    from monoskel.operators import animate

    empty_scene.monoskel.retarget_target = rig               # a rig without bones: its retarget fails
    run = run_to_end(AnimateRun.start(clip, AnimateOptions(fps=25.0)), bpy.context)
    with pytest.raises(Exception, match="bone"):
        animate.commit(bpy.context, run)
    assert _scene_state(bpy.context.scene) == before
    assert not empty_scene.monoskel.has_estimate and empty_scene.monoskel.retarget_target == rig


def test_a_clip_without_a_person_or_that_cannot_be_read_is_one_line(empty_scene, tmp_path):
    import bpy

    first = person_over_scene(tmp_path / "nobody", 3, plain=True)
    from monoskel.core.io.png_plot import encode_png

    for i in range(3):                       # the grey scene without the person
        (tmp_path / "nobody" / f"shot_{i + 1:04d}.png").write_bytes(
            encode_png(np.full((54, 128, 3), 128, np.uint8), level=1))
    clip = bpy.data.movieclips.load(str(first))
    empty_scene.active_clip = clip
    before = _scene_state(empty_scene)
    with pytest.raises(RuntimeError, match="no person found in any of the 3 frames"):
        bpy.ops.monoskel.animate_from_clip()
    assert _scene_state(empty_scene) == before
    for i in range(3):                       # footage gone from the disk: Blender cannot decode it
        (tmp_path / "nobody" / f"shot_{i + 1:04d}.png").unlink()
    with pytest.raises(RuntimeError, match="is missing"):
        bpy.ops.monoskel.animate_from_clip()
    assert _scene_state(empty_scene) == before
