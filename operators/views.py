"""Further synchronized views of the person: add their tracks, give their cameras, clear them.

With views on the scene, Estimate runs the multi-view estimate (``core.multiview``) from the scene's
tracks (the first view) and these; the build adds one still camera per view with its tracks shown
through it.
"""

from __future__ import annotations

import os

import bpy
from bpy_extras.io_utils import ExportHelper, ImportHelper

from . import common, summary
from .import_tracks import TracksFileImport


class MONOSKEL_OT_add_view(TracksFileImport, bpy.types.Operator):
    """Add the tracks of another synchronized camera filming the same person; Estimate then uses every view"""

    bl_idname = "monoskel.add_view"
    bl_label = "Add View Tracks"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return common.poll_requirements(cls, context, ("idle", "tracks"))

    def execute(self, context):
        from ..blender import scene_data
        from ..core.multiview.pipeline import MAX_VIEWS, check_same_rate

        scene = context.scene
        path = self._path()
        if not path:
            return common.fail(self, "No file selected")
        try:
            first = scene_data.load_tracks(scene)
            if first is None:
                return common.fail(self, common.REASONS["tracks"])
            views, cameras = scene_data.load_views(scene)
            if len(views) + 1 >= MAX_VIEWS:
                return common.fail(self, f"The scene has {len(views) + 1} views already (at most {MAX_VIEWS})")
            view, notes = self.read(scene, path)
            check_same_rate([first, view])
            scene_data.store_views(scene, views + [view], None)
        except Exception as exc:  # noqa: BLE001 - one report line; the scene's views are unchanged
            return common.fail(self, exc)
        summary.set_views_summary(scene.monoskel, views + [view], None)
        if cameras is not None:
            self.report({"WARNING"}, "The calibration was for fewer views and is dropped: "
                                     "the cameras will come from the person unless you load one for all views")
        note = f" ({'; '.join(notes)})" if notes else ""
        self.report({"INFO"}, f"View {len(views) + 2}: {os.path.basename(path.rstrip(os.sep))}, "
                              f"{view.n_frames} frames{note}; Estimate uses all {len(views) + 2} views")
        return {"FINISHED"}


class MONOSKEL_OT_load_view_cameras(bpy.types.Operator, ImportHelper):
    """Read the cameras of every view (a multiview-calibration JSON, first view first) instead of
    calibrating them from the person"""

    bl_idname = "monoskel.load_view_cameras"
    bl_label = "Load View Cameras"
    bl_options = {"REGISTER", "UNDO"}

    filename_ext = ".json"
    filter_glob: bpy.props.StringProperty(default="*.json", options={"HIDDEN"})

    @classmethod
    def poll(cls, context):
        return common.poll_requirements(cls, context, ("idle", "views"))

    def execute(self, context):
        from ..blender import scene_data
        from ..core.multiview import read_calibration

        scene = context.scene
        try:
            views, _ = scene_data.load_views(scene)
            cameras = read_calibration(bpy.path.abspath(self.filepath))
            if len(cameras) != len(views) + 1:
                return common.fail(self, f"{os.path.basename(self.filepath)} has {len(cameras)} cameras, the scene "
                                         f"{len(views) + 1} views")
            scene_data.store_views(scene, views, cameras)
        except Exception as exc:  # noqa: BLE001 - one report line
            return common.fail(self, exc)
        summary.set_views_summary(scene.monoskel, views, cameras)
        self.report({"INFO"}, f"Cameras of {len(cameras)} views from {os.path.basename(self.filepath)}")
        return {"FINISHED"}


class MONOSKEL_OT_save_view_cameras(bpy.types.Operator, ExportHelper):
    """Write the cameras of the last multi-view estimate as a calibration file, to load for other takes
    filmed by the same cameras (a short take pins the lenses less than a long one)"""

    bl_idname = "monoskel.save_view_cameras"
    bl_label = "Save View Cameras"
    bl_options = {"REGISTER"}

    filename_ext = ".json"
    filter_glob: bpy.props.StringProperty(default="*.json", options={"HIDDEN"})

    @classmethod
    def poll(cls, context):
        return common.poll_requirements(cls, context, ("idle", "views", "estimate"))

    def execute(self, context):
        from ..blender import scene_data
        from ..core.multiview import write_calibration
        from ..core.multiview.cameras import ViewCamera

        try:
            est = scene_data.load_estimate(context.scene)
            found = (est.diagnostics or {}).get("cameras") if est is not None else None
            if est is None or est.method != "multiview" or not found:
                return common.fail(self, "The estimate is not a multi-view one: Estimate with the views first")
            cameras = [ViewCamera.from_dict(c) for c in found]
            path = bpy.path.abspath(self.filepath)
            write_calibration(cameras, path)
        except Exception as exc:  # noqa: BLE001 - one report line; nothing in the scene changes
            return common.fail(self, exc)
        self.report({"INFO"}, f"Cameras of {len(cameras)} views written to {os.path.basename(path)}")
        return {"FINISHED"}


class MONOSKEL_OT_clear_views(bpy.types.Operator):
    """Forget the further views (and their cameras): Estimate uses the first view alone again"""

    bl_idname = "monoskel.clear_views"
    bl_label = "Clear Views"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return common.poll_requirements(cls, context, ("idle", "views"))

    def execute(self, context):
        from ..blender import scene_data

        scene_data.store_views(context.scene, [])
        summary.set_views_summary(context.scene.monoskel, [], None)
        self.report({"INFO"}, "Further views cleared: Estimate uses the scene's tracks alone")
        return {"FINISHED"}


classes = (MONOSKEL_OT_add_view, MONOSKEL_OT_load_view_cameras, MONOSKEL_OT_save_view_cameras,
           MONOSKEL_OT_clear_views)
