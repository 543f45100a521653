"""A multi-view estimate built in Blender: the first view's camera as for one camera, every
further view a still camera where it filmed from, and each of them sees the built figure where its own
tracks put it."""

from __future__ import annotations

import numpy as np


def test_every_view_gets_a_camera_that_sees_the_figure_on_its_tracks(empty_scene):
    import bpy
    from bpy_extras.object_utils import world_to_camera_view
    from mathutils import Vector

    from monoskel.blender import build
    from monoskel.blender.review import takes
    from monoskel.core.multiview import estimate_multiview
    from monoskel.core.multiview.synth import film_views, ring_cameras
    from monoskel.core.synthetic.motion import load_motion

    motion = load_motion("builtin:walk", max_frames=60)
    cams = ring_cameras(motion, 3, seed=5)
    views = film_views(motion, cams, noise_px=0.5, seed=5)
    est = estimate_multiview(views, cameras=cams)
    scene = bpy.context.scene
    built = takes.build_take(scene, est, views[0])
    first = built["camera"]
    extra = [o for o in bpy.data.objects if o.get("monoskel_view")]
    assert len(extra) == 2 and all(o.type == 'CAMERA' for o in extra)
    assert all(o.users_collection[0] == first.users_collection[0] for o in extra)     # in the take
    idx, world = build.world_joints(est, scene.monoskel.height_m)
    w, h = views[0].image_size
    for cam_obj, view in zip([first] + sorted(extra, key=lambda o: o.name), views):
        errs = []
        for i in (0, 30, 59):
            scene.frame_set(int(idx[i]) + scene.monoskel.tracks_first_frame)
            for j in range(17):
                if not view.present[idx[i], j]:
                    continue
                p = world_to_camera_view(scene, cam_obj, Vector(world[i, j].tolist()))
                errs.append(np.hypot(p.x * w - view.xy[idx[i], j, 0], (1 - p.y) * h - view.xy[idx[i], j, 1]))
        assert np.median(errs) < 3.0, (cam_obj.name, np.median(errs))


def _write_views(tmp_path, n_frames=60, offset=0):
    from monoskel.core.multiview import write_calibration
    from monoskel.core.multiview.synth import film_views, ring_cameras
    from monoskel.core.synthetic.motion import load_motion
    from monoskel.core.tracks import write_tracks_json

    motion = load_motion("builtin:walk", max_frames=n_frames)
    cams = ring_cameras(motion, 3, seed=5)
    views = film_views(motion, cams, noise_px=0.5, seed=5)
    paths = []
    for k, view in enumerate(views):
        if k == 2 and offset:             # the third camera started `offset` frames later
            view = view.replaced(xy=view.xy[offset:], conf=view.conf[offset:])
        path = tmp_path / f"view{k + 1}.json"
        write_tracks_json(view, path)
        paths.append(path)
    cal = tmp_path / "cameras.json"
    write_calibration(cams, cal)
    return views, cams, paths, cal


def test_sidebar_views_estimate_and_build_with_each_views_tracks(empty_scene, tmp_path):
    """The sidebar path: tracks, two further views, their cameras from a file, Estimate, Build All; each
    still camera shows its own view's tracks (the third view started 4 frames late) where they are."""
    import bpy
    from bpy_extras.object_utils import world_to_camera_view

    from monoskel.blender import scene_data
    from monoskel.ui import state

    views, cams, paths, cal = _write_views(tmp_path, offset=4)
    s = empty_scene.monoskel
    assert bpy.ops.monoskel.import_tracks(filepath=str(paths[0])) == {"FINISHED"}
    rows = state.section_rows("views", s)
    assert [r.enabled for r in rows if r.kind == "operator"] == [True, False, False, False]
    for p in paths[1:]:
        assert bpy.ops.monoskel.add_view(filepath=str(p)) == {"FINISHED"}
    assert s.views_count == 2 and not s.views_cameras_given
    assert bpy.ops.monoskel.load_view_cameras(filepath=str(cal)) == {"FINISHED"}
    assert s.views_cameras_given
    texts = [r.text for r in state.section_rows("views", s) if r.kind == "label"]
    assert "Views: 3 (the scene's tracks and 2 more)" in texts and "Cameras: given by the calibration file" in texts

    assert bpy.ops.monoskel.estimate() == {"FINISHED"}
    est = scene_data.load_estimate(empty_scene)
    assert est.method == "multiview" and est.diagnostics["calibration"] == "given"
    assert est.diagnostics["frame_offsets"] == [0, 0, -4]
    assert bpy.ops.monoskel.build_all() == {"FINISHED"}

    extra = sorted((o for o in bpy.data.objects if o.get("monoskel_view")), key=lambda o: o.name)
    assert len(extra) == 2
    w, h = views[0].image_size
    first = s.tracks_first_frame
    for cam_obj, view in zip(extra, views[1:]):
        overlay = [o for o in cam_obj.children_recursive if o.name.endswith(" Tracks") and o.type == 'EMPTY']
        assert len(overlay) == 1
        markers = {o.name.rsplit(".", 1)[-1]: o for o in overlay[0].children if "." in o.name}
        errs = []
        for i in (10, 40):
            empty_scene.frame_set(first + i)
            for name, j in (("head", 4), ("l_ankle", 7), ("r_wrist", 16)):
                if not view.present[i, j]:
                    continue
                p = world_to_camera_view(empty_scene, cam_obj, markers[name].matrix_world.translation)
                errs.append(np.hypot(p.x * w - view.xy[i, j, 0], (1 - p.y) * h - view.xy[i, j, 1]))
        assert errs and max(errs) < 0.5, (cam_obj.name, errs)


def test_views_are_checked_and_forgotten_with_their_footage(empty_scene, tmp_path):
    import bpy

    from monoskel.blender import scene_data
    from monoskel.core.tracks import read_tracks_json, write_tracks_json

    views, cams, paths, cal = _write_views(tmp_path, n_frames=30)
    s = empty_scene.monoskel
    assert bpy.ops.monoskel.import_tracks(filepath=str(paths[0])) == {"FINISHED"}
    slow = read_tracks_json(paths[1])
    slow.fps = 25.0
    write_tracks_json(slow, tmp_path / "slow.json")
    import pytest

    with pytest.raises(RuntimeError, match="share one frame rate"):
        bpy.ops.monoskel.add_view(filepath=str(tmp_path / "slow.json"))
    assert s.views_count == 0
    assert bpy.ops.monoskel.add_view(filepath=str(paths[1])) == {"FINISHED"}
    with pytest.raises(RuntimeError, match="3 cameras, the scene 2 views"):
        bpy.ops.monoskel.load_view_cameras(filepath=str(cal))
    assert not s.views_cameras_given
    # the summary comes back from the stored data (a file opened without the sidebar)
    s.views_count = 0
    from monoskel.operators import summary

    summary.refresh_from_scene(empty_scene)
    assert s.views_count == 1 and "view" in s.views_sources
    assert bpy.ops.monoskel.estimate() == {"FINISHED"}
    found = scene_data.load_estimate(empty_scene).diagnostics
    assert found["calibration"] != "given"                                               # from the person
    # the self-calibrated cameras saved, and loaded back as given cameras for the same views
    from monoskel.core.multiview import read_calibration

    assert bpy.ops.monoskel.save_view_cameras(filepath=str(tmp_path / "saved.json")) == {"FINISHED"}
    saved = read_calibration(tmp_path / "saved.json")
    assert [c.focal_px for c in saved] == [c["focal_px"] for c in found["cameras"]]
    assert bpy.ops.monoskel.load_view_cameras(filepath=str(tmp_path / "saved.json")) == {"FINISHED"}
    assert s.views_cameras_given
    # new footage: the old views go with the old tracks
    assert bpy.ops.monoskel.import_tracks(filepath=str(paths[2])) == {"FINISHED"}
    assert s.views_count == 0 and scene_data.load_views(empty_scene) == ([], None)
    assert bpy.ops.monoskel.estimate() == {"FINISHED"}
    assert scene_data.load_estimate(empty_scene).method != "multiview"
    assert bpy.ops.monoskel.clear_views.poll() is False
    assert bpy.ops.monoskel.save_view_cameras.poll() is False
