"""Keep only the tracks inside the scene's frame range: estimate one stretch of the clip.

When the tracks jump to another person (the estimate's ``input:`` warning names the longest stretch
of one person) or only part of a clip matters, set the timeline's Start and End to that stretch and
trim: the tracks outside it are dropped (undo brings them back), they keep their place on the
timeline, and the next Estimate covers the stretch alone.
"""

from __future__ import annotations

import bpy

from . import common
from .import_tracks import describe_tracks, store_new_tracks


def scene_stretch(scene) -> tuple[int, int]:
    """The tracks' frames (0-based) that the scene's frame range covers, clipped to the tracks."""
    first = int(scene.monoskel.tracks_first_frame)
    n = int(scene.monoskel.tracks_frames)
    return max(0, scene.frame_start - first), min(n - 1, scene.frame_end - first)


class MONOSKEL_OT_trim_tracks(bpy.types.Operator):
    """Keep only the tracks inside the scene's frame range (Start to End), e.g. one person's stretch that a
    warning names; the estimate is then made again for that stretch"""

    bl_idname = "monoskel.trim_tracks"
    bl_label = "Trim Tracks to Scene Range"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return common.poll_requirements(cls, context, ("idle", "tracks"))

    def execute(self, context):
        from ..blender import scene_data

        scene = context.scene
        settings = scene.monoskel
        try:
            if settings.views_count:
                raise ValueError("Trim works on one camera's tracks: clear the further views first")
            tracks = scene_data.load_tracks(scene)
            a, b = scene_stretch(scene)
            if b - a + 1 < 2:
                raise ValueError(f"The scene's frame range {scene.frame_start}-{scene.frame_end} holds fewer than "
                                 f"2 of the tracks' frames (scene frames {settings.tracks_first_frame}-"
                                 f"{settings.tracks_first_frame + tracks.n_frames - 1})")
            if a == 0 and b == tracks.n_frames - 1:
                self.report({"INFO"}, "The scene's frame range already holds all the tracks: nothing trimmed")
                return {"CANCELLED"}
            first = settings.tracks_first_frame + a
            kept = tracks.frames_between(a, b)
            store_new_tracks(scene, kept, first_frame=first)
        except Exception as exc:  # noqa: BLE001 - any failure is one report line, never a traceback
            return common.fail(self, exc)
        self.report({"INFO"}, f"Kept scene frames {first}-{first + b - a}: {describe_tracks(kept)}; estimate again")
        return {"FINISHED"}


classes = (MONOSKEL_OT_trim_tracks,)
