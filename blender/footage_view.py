"""The footage behind the built camera, and the solved lens on the clip's tracking camera.

Looking through the built camera should show the armature over the person it came from, as Blender's
own *Setup Tracking Scene* does: the camera's background image is the Movie Clip. And the clip's
tracking camera gets the solved focal length, so Blender's own tools (its camera solve, *Tracks from
Movie Clip*'s starting focal length) agree with the built camera.
"""

from __future__ import annotations

import numpy as np

from ..core.camera import film_size_mm
from .movie_clip import clip_size


def show_footage(camera_obj, clip) -> None:
    """Make ``clip`` the background image of ``camera_obj`` (replacing a clip it showed), shown behind."""
    data = camera_obj.data
    for old in [b for b in data.background_images if b.source == "MOVIE_CLIP"]:
        data.background_images.remove(old)
    image = data.background_images.new()
    image.source = "MOVIE_CLIP"
    image.clip = clip
    image.use_camera_clip = False
    image.alpha = 1.0
    image.display_depth = "BACK"
    image.frame_method = "FIT"
    data.show_background_images = True


def set_tracking_focal(clip, est) -> float:
    """Give ``clip``'s tracking camera the estimate's focal length (the median frame's, a zoom's middle)
    on a sensor as wide as the picture sits on 36 mm film; returns the focal length set (mm)."""
    focal = float(np.median([fr.focal_mm for fr in est.frames])) if est.frames else float(est.focal_mm)
    cam = clip.tracking.camera
    cam.units = "MILLIMETERS"
    cam.sensor_width = film_size_mm(clip_size(clip))[0]
    cam.focal_length = focal
    return focal
