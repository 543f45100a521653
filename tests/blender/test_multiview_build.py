"""A multi-view estimate built in Blender (issue 29): the first view's camera as for one camera, every
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
    from monoskel.core.motion import load_motion
    from monoskel.core.multiview import estimate_multiview
    from monoskel.core.multiview.synth import film_views, ring_cameras

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
