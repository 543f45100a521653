"""Joint tracks made with the Movie Clip Editor's tracker: create the 17 named tracks, convert them."""

from __future__ import annotations

import bpy

from ..blender.track_refinement.tracker import MOTION_MODELS
from . import common
from .import_tracks import describe_tracks, store_new_tracks


def find_clip(context, name: str = ""):
    """The named clip, else the clip open in this Movie Clip Editor, else the scene's active clip."""
    if name:
        return bpy.data.movieclips.get(name)
    clip = getattr(context, "edit_movieclip", None)
    if clip is None and getattr(context, "scene", None) is not None:
        clip = context.scene.active_clip
    return clip


def _poll_clip(cls, context, needs=()) -> bool:
    if not common.poll_requirements(cls, context, needs):
        return False
    if find_clip(context) is None:
        cls.poll_message_set(common.REASONS["clip"])
        return False
    return True


class MONOSKEL_OT_clip_add_joint_tracks(bpy.types.Operator):
    """Add 17 tracks named after the canonical joints on the current frame, to place and track"""

    bl_idname = "monoskel.clip_add_joint_tracks"
    bl_label = "Add Joint Tracks"
    bl_options = {"REGISTER", "UNDO"}

    clip: bpy.props.StringProperty(name="Clip", description="Movie clip (empty: the active clip)")

    @classmethod
    def poll(cls, context):
        return _poll_clip(cls, context)

    def execute(self, context):
        from ..blender import movie_clip

        clip = find_clip(context, self.clip)
        if clip is None:
            return common.fail(self, f"No movie clip named '{self.clip}'" if self.clip else common.REASONS["clip"])
        frame = movie_clip.scene_to_clip_frame(clip, context.scene.frame_current)
        try:
            created = movie_clip.create_joint_tracks(clip, frame)
        except Exception as exc:  # noqa: BLE001 - one report line, never a traceback
            return common.fail(self, exc)
        if not created:
            self.report({"WARNING"}, f"Clip '{clip.name}' already has all 17 joint tracks")
        else:
            self.report({"INFO"}, f"Added {len(created)} joint tracks on clip frame {frame}; "
                                  "place each on its joint and track")
        return {"FINISHED"}


class MONOSKEL_OT_clip_to_tracks(bpy.types.Operator):
    """Use the clip's joint-named tracking markers as the scene's 2D tracks"""

    bl_idname = "monoskel.clip_to_tracks"
    bl_label = "Tracks from Clip"
    bl_options = {"REGISTER", "UNDO"}

    clip: bpy.props.StringProperty(name="Clip", description="Movie clip (empty: the active clip)")
    use_clip_focal: bpy.props.BoolProperty(
        name="Use Clip Focal Length",
        description="Start from the tracking camera's focal length when it has been set",
        default=True,
    )

    @classmethod
    def poll(cls, context):
        return _poll_clip(cls, context, ("idle",))

    def execute(self, context):
        from ..blender import movie_clip

        scene = context.scene
        clip = find_clip(context, self.clip)
        if clip is None:
            return common.fail(self, f"No movie clip named '{self.clip}'" if self.clip else common.REASONS["clip"])
        try:
            from ..blender import scene_data

            tracks = movie_clip.tracks_from_clip(clip, fps=scene.render.fps / scene.render.fps_base)
            tracks = movie_clip.keep_detection(scene_data.load_tracks(scene), scene.monoskel.tracks_first_frame,
                                               clip, tracks)
            focal = movie_clip.clip_focal_mm(clip) if self.use_clip_focal else None
            store_new_tracks(scene, tracks, first_frame=int(clip.frame_start))
        except Exception as exc:  # noqa: BLE001 - one report line, never a traceback
            return common.fail(self, exc)
        settings = scene.monoskel
        note = ""
        if focal is not None:
            settings.estimate_focal = False
            settings.focal_mm = focal
            note = f", initial focal {focal:.1f} mm (36 mm equivalent)"
        if scene.active_clip is None:
            scene.active_clip = clip
        self.report({"INFO"}, f"Tracks from clip '{clip.name}': {describe_tracks(tracks)}{note}")
        return {"FINISHED"}


class MONOSKEL_OT_refine_tracks(bpy.types.Operator):
    """Re-find the scene's joint tracks on the clip's images with Blender's tracker, and keep the tracked
    motion where it agrees with the detector (less jitter, short gaps filled)"""

    bl_idname = "monoskel.refine_tracks"
    bl_label = "Refine Tracks on Footage"
    bl_options = {"REGISTER", "UNDO"}

    clip: bpy.props.StringProperty(name="Clip", description="Movie clip of the footage (empty: the active clip)")
    window: bpy.props.IntProperty(
        name="Tracking Window", default=5, min=1, max=120,
        description="Frames Blender's tracker follows a joint from each detector position it is seeded at",
    )
    motion_model: bpy.props.EnumProperty(
        name="Motion Model", default="Loc",
        items=[(m, m, f"Blender's '{m}' motion model for the joint patches") for m in
               MOTION_MODELS],
    )
    disagree: bpy.props.EnumProperty(
        name="Where They Disagree", default="DETECTOR",
        items=[("DETECTOR", "Keep Detector", "Keep the detector's position; the track cleaning judges it"),
               ("REFINED", "Use Tracked", "Take the tracked motion's position"),
               ("MISSING", "Make Missing", "Neither source is trusted: the joint is missing on that frame")],
    )

    @classmethod
    def poll(cls, context):
        return _poll_clip(cls, context, ("idle", "tracks"))

    def execute(self, context):
        from ..blender import scene_data
        from ..blender.movie_clip import scene_to_clip_frame
        from ..blender.track_refinement import refine_on_clip

        scene = context.scene
        settings = scene.monoskel
        clip = find_clip(context, self.clip)
        if clip is None:
            return common.fail(self, f"No movie clip named '{self.clip}'" if self.clip else common.REASONS["clip"])
        wm = context.window_manager
        try:
            tracks = scene_data.load_tracks(scene)
            if tracks is None:
                return common.fail(self, common.REASONS["tracks"])
            first = scene_to_clip_frame(clip, settings.tracks_first_frame)
            wm.progress_begin(0.0, 1.0)
            try:
                refined, report = refine_on_clip(context, clip, tracks, first_clip_frame=first, window=self.window,
                                                 motion_model=self.motion_model, disagree=self.disagree.lower(),
                                                 progress=lambda done, total: wm.progress_update(done / max(total, 1)))
            finally:
                wm.progress_end()
            store_new_tracks(scene, refined, first_frame=settings.tracks_first_frame, keep_views=True)
        except Exception as exc:  # noqa: BLE001 - one report line; the scene's tracks are unchanged
            return common.fail(self, exc)
        self.report({"INFO"}, f"{report.summary()} (clip '{clip.name}')")
        return {"FINISHED"}


class MONOSKEL_OT_track_background(bpy.types.Operator):
    """Find and follow static background features on the clip with Blender's tracker, off the person, so the
    camera's turn and zoom come from the scene (replaces the tracks of an earlier run)"""

    bl_idname = "monoskel.track_background"
    bl_label = "Track Background"
    bl_options = {"REGISTER", "UNDO"}

    clip: bpy.props.StringProperty(name="Clip", description="Movie clip of the footage (empty: the active clip)")
    want: bpy.props.IntProperty(
        name="Points in View", default=16, min=4, max=64,
        description="Background points kept in view at once; new ones are found as the camera turns others out",
    )
    every_s: bpy.props.FloatProperty(
        name="Look Every", default=0.5, min=0.05, max=10.0, unit="TIME_ABSOLUTE",
        description="Seconds between looks for new features",
    )
    person_margin: bpy.props.FloatProperty(
        name="Person Margin", default=0.15, min=0.0, max=0.45, subtype="FACTOR",
        description="Widen the person's box by this share of its height: nothing is tracked in it",
    )

    @classmethod
    def poll(cls, context):
        return _poll_clip(cls, context, ("idle", "tracks"))

    def execute(self, context):
        from ..blender import scene_data
        from ..blender.background_tracking import track_background
        from ..blender.movie_clip import scene_to_clip_frame
        from ..core.background_tracking import BackgroundSettings

        scene = context.scene
        settings = scene.monoskel
        clip = find_clip(context, self.clip)
        if clip is None:
            return common.fail(self, f"No movie clip named '{self.clip}'" if self.clip else common.REASONS["clip"])
        wm = context.window_manager
        try:
            tracks = scene_data.load_tracks(scene)
            if tracks is None:
                return common.fail(self, common.REASONS["tracks"])
            opts = BackgroundSettings(want=self.want, every_s=self.every_s, person_margin=self.person_margin)
            first = scene_to_clip_frame(clip, settings.tracks_first_frame)
            wm.progress_begin(0.0, 1.0)
            try:
                static, report = track_background(context, clip, tracks, first_clip_frame=first, settings=opts,
                                                  progress=lambda done, total: wm.progress_update(done / max(total, 1)))
            finally:
                wm.progress_end()
            if static is None:
                return common.fail(self, f"Clip '{clip.name}': {report.fallback} ({report.summary()})")
            store_new_tracks(scene, tracks.replaced(static=static), first_frame=settings.tracks_first_frame,
                             keep_views=True)
            settings.use_background = True
        except Exception as exc:  # noqa: BLE001 - one report line; the scene's tracks are unchanged
            return common.fail(self, exc)
        self.report({"WARNING"} if report.frames_under_four else {"INFO"}, f"{report.summary()} (clip '{clip.name}')")
        return {"FINISHED"}


classes = (MONOSKEL_OT_clip_add_joint_tracks, MONOSKEL_OT_clip_to_tracks, MONOSKEL_OT_refine_tracks,
           MONOSKEL_OT_track_background)
