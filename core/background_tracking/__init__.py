"""Background features found and followed on the footage, so the camera comes from the scene.

From the person alone a handheld camera's turn is a measured limit (docs/robustness.md); with 8-16
static scene points the camera is right to about 0.1 degrees (``core.scene_camera``). An animator
should not have to place those points by hand. Blender's tracker (``blender.background_tracking``)
finds corners on the frames and follows them; this package, pure numpy, decides where they may be and
which are kept: never on or near the person (whose joints the tracks give), spread over the picture,
topped up as the camera turns them out of view, and cut where the person walks over them.
"""

from .plan import (
    DEFAULT_BACKGROUND,
    BackgroundReport,
    BackgroundSettings,
    clean_background,
    detection_frames,
    inside_boxes,
    off_the_scene_motion,
    person_boxes,
    pick_seeds,
    static_tracks,
)
from .verdict import judge_background

__all__ = ["DEFAULT_BACKGROUND", "BackgroundReport", "BackgroundSettings", "clean_background", "detection_frames",
           "inside_boxes", "judge_background", "off_the_scene_motion", "person_boxes", "pick_seeds", "static_tracks"]
