"""Residual lines through the camera: what the viewport overlay draws lands, seen through the
built camera, on the tracks and on the solved joints' reprojection, coloured by the distance."""

from __future__ import annotations

import numpy as np
import pytest


def _build(noise_px=0.0, n_frames=12, moved=None):
    """A take built from the truth of a noise-free walk; ``moved`` (frame, joint, metres) displaces one
    solved joint so its reprojection leaves its track."""
    import bpy

    from monoskel.blender import scene_data
    from monoskel.blender.test_data import truth_as_estimate
    from monoskel.core.synthetic.motion import load_motion
    from monoskel.core.synthetic.synth import synthesize

    tracks, truth = synthesize(load_motion("builtin:walk", max_frames=n_frames), kinds=("pan", "zoom"), seed=4,
                               noise_px=noise_px)
    est = truth_as_estimate(truth)
    if moved is not None:
        frame, joint, dx = moved
        j = np.array(est.frames[frame].joints_3d)
        j[joint, 0] += dx
        est.frames[frame].joints_3d = j.tolist()
    scene = bpy.context.scene
    scene_data.store_tracks(scene, tracks)
    scene_data.store_estimate(scene, est)
    assert bpy.ops.monoskel.refresh() == {"FINISHED"}
    assert bpy.ops.monoskel.build_all() == {"FINISHED"}
    return scene, tracks, est


def _pixels(scene, camera, points):
    """Where world points appear in the rendered image, pixels (x right, y down)."""
    from bpy_extras.object_utils import world_to_camera_view
    from mathutils import Vector

    w, h = scene.render.resolution_x, scene.render.resolution_y
    out = []
    for p in points:
        co = world_to_camera_view(scene, camera, Vector(p))
        out.append((co.x * w, (1.0 - co.y) * h))
    return np.array(out)


@pytest.mark.parametrize("frame_index", [0, 7])
def test_lines_join_the_track_to_the_reprojection_through_the_camera(empty_scene, frame_index):
    from monoskel.blender import scene_data
    from monoskel.blender.review.overlay import residual_geometry
    from monoskel.core.review.residuals import reprojected_pixels

    scene, _, _ = _build(noise_px=1.5)
    tracks, est = scene_data.load_tracks(scene), scene_data.load_estimate(scene)     # as stored (rounded)
    frame = scene.monoskel.tracks_first_frame + frame_index
    scene.frame_set(frame)
    geo = residual_geometry(scene)
    cam = scene.monoskel.camera
    joints = geo["joints"]
    assert joints.size == int(tracks.present[frame_index].sum())
    np.testing.assert_allclose(_pixels(scene, cam, geo["track"]), tracks.xy[frame_index, joints], atol=0.02)
    reproj = reprojected_pixels(est, tracks.image_size)[frame_index, joints]
    np.testing.assert_allclose(_pixels(scene, cam, geo["reprojection"]), reproj, atol=0.02)
    np.testing.assert_allclose(geo["residual_px"], np.linalg.norm(tracks.xy[frame_index, joints] - reproj, axis=1),
                               atol=1e-9)


def test_colour_follows_the_residual(empty_scene):
    from monoskel.blender.review.overlay import residual_geometry
    from monoskel.core.review.residuals import BAD, GOOD
    from monoskel.core.skeleton import JOINT_INDEX

    wrist = JOINT_INDEX["l_wrist"]
    scene, _, _ = _build(moved=(5, wrist, 0.3))
    geo = residual_geometry(scene, frame=scene.monoskel.tracks_first_frame + 5)
    k = int(np.flatnonzero(geo["joints"] == wrist)[0])
    assert geo["residual_px"][k] > 20.0
    np.testing.assert_allclose(geo["colour"][k], BAD)
    others = np.delete(np.arange(len(geo["joints"])), k)
    assert np.all(geo["residual_px"][others] < 0.01)         # JSON rounding of the stored estimate
    np.testing.assert_allclose(geo["colour"][others], np.tile(GOOD, (others.size, 1)), atol=0.01)
    # outside the clip, or with no take, there is nothing to draw
    assert residual_geometry(scene, frame=scene.monoskel.tracks_first_frame + 500) is None


def test_the_overlay_stays_out_of_background_runs(empty_scene):
    """No draw handler without a window, and the draw callback itself never raises headless."""
    import bpy

    from monoskel.blender.review import overlay

    _build()
    assert bpy.app.background and overlay._handle is None
    assert overlay._draw() is None                   # gets as far as the gpu module, which refuses: no error
    assert any("background mode" in message for _, message in overlay._said)     # ... and says so once
    bpy.context.scene.monoskel.show_residuals = False
    assert overlay._draw() is None
