"""Import 2D joint tracks from any format the core reads (File > Import and the sidebar)."""

from __future__ import annotations

import os

import bpy
from bpy_extras.io_utils import ImportHelper

from ..properties import FORMAT_ITEMS
from . import common, summary


def _formats() -> dict:
    from ..core.io.formats import FORMATS

    return FORMATS


def _filter_glob() -> str:
    patterns = {"*.json"}
    for info in _formats().values():
        for ext in getattr(info, "extensions", ()) or ():
            ext = str(ext)
            patterns.add(ext if ext.startswith("*") else "*" + (ext if ext.startswith(".") else "." + ext))
    return ";".join(sorted(patterns))


def describe_tracks(tracks) -> str:
    """The one-line summary reported after an import."""
    return (f"{tracks.n_frames} frames at {tracks.fps:g} fps, "
            f"{int(tracks.present.any(axis=0).sum())}/17 joints present, "
            f"{100.0 * tracks.missing_fraction():.1f}% missing")


def store_new_tracks(scene, tracks, *, first_frame: int | None = None, keep_views: bool = False) -> None:
    """Put freshly read tracks on the scene: data, summary, frame rate and range, render size.

    An earlier estimate and truth belong to other tracks, so they are forgotten (stored data
    and summary; the builders then ask for a new estimate).  Objects already built stay.  Further
    views belong to other footage too, unless ``keep_views`` (the same footage's tracks, refined).
    """
    from ..blender import scene_data

    scene_data.store_tracks(scene, tracks)
    if not keep_views:
        scene_data.store_views(scene, [])
        summary.set_views_summary(scene.monoskel, [], None)
    if hasattr(scene_data, "clear"):
        scene_data.clear(scene, "estimate")
        scene_data.clear(scene, "truth")
    settings = scene.monoskel
    settings.tracks_first_frame = scene.frame_start if first_frame is None else int(first_frame)
    summary.set_tracks_summary(settings, tracks)
    summary.clear_estimate_summary(settings)
    summary.clear_truth_summary(settings)
    common.set_scene_timing(scene, tracks.fps, tracks.n_frames, first_frame)
    scene.render.resolution_x = int(round(tracks.image_size[0]))
    scene.render.resolution_y = int(round(tracks.image_size[1]))
    scene.render.resolution_percentage = 100


def read_with_fallbacks(scene, path, fmt, fps, size, min_confidence):
    """``read_any``, filling in the scene's frame rate / render size only when the file lacks them.

    Values given to ``read_any`` replace the file's, so the scene's are offered only after the
    reader said it needs them (:class:`MissingSettingError` names the setting).
    Returns (tracks, notes saying which values came from the scene).
    """
    from ..core.errors import MissingSettingError
    from ..core.io.formats import read_any

    notes = []
    for _ in range(3):
        try:
            return read_any(path, format=fmt, fps=fps, image_size=size, min_confidence=min_confidence), notes
        except MissingSettingError as exc:
            if fps is None and exc.setting == "fps":
                fps = scene.render.fps / scene.render.fps_base
                notes.append(f"fps {fps:g} from the scene")
            elif size is None and exc.setting == "image_size":
                size = (scene.render.resolution_x, scene.render.resolution_y)
                notes.append(f"image size {size[0]}x{size[1]} from the render resolution")
            else:
                raise
    return read_any(path, format=fmt, fps=fps, image_size=size, min_confidence=min_confidence), notes


class TracksFileImport(ImportHelper):
    """The file browser and reading options shared by every operator that reads a tracks file (a mixin:
    Blender cannot register a subclass of a registered operator)."""

    filter_glob: bpy.props.StringProperty(default=_filter_glob(), options={"HIDDEN"})
    directory: bpy.props.StringProperty(subtype="DIR_PATH", options={"HIDDEN", "SKIP_SAVE"})
    format: bpy.props.EnumProperty(name="Format", items=FORMAT_ITEMS, default="auto")
    fps: bpy.props.FloatProperty(
        name="FPS", description="Frame rate for files that do not store one (0: the scene's frame rate)",
        default=0.0, min=0.0, max=1000.0,
    )
    width: bpy.props.IntProperty(
        name="Width", description="Image width for files that do not store it (0: the render resolution)",
        default=0, min=0, max=100000,
    )
    height: bpy.props.IntProperty(
        name="Height", description="Image height for files that do not store it (0: the render resolution)",
        default=0, min=0, max=100000,
    )
    min_confidence: bpy.props.FloatProperty(
        name="Min Confidence", description="Detections below this confidence count as missing",
        default=0.0, min=0.0, max=1.0, subtype="FACTOR",
    )

    def invoke(self, context, event):
        settings = context.scene.monoskel
        self.format = settings.import_format
        self.fps = settings.import_fps
        self.width = settings.import_width
        self.height = settings.import_height
        self.min_confidence = settings.min_confidence
        return ImportHelper.invoke(self, context, event)

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.prop(self, "format")
        info = _formats().get(self.format)
        if info is not None and getattr(info, "is_folder", False):
            layout.label(text="Select the folder of per-frame files", icon="FILE_FOLDER")
        layout.prop(self, "fps")
        col = layout.column(align=True)
        col.prop(self, "width")
        col.prop(self, "height")
        layout.prop(self, "min_confidence")

    def _path(self) -> str:
        """The file, or the folder for per-frame formats (OpenPose) and when no file is picked."""
        path = bpy.path.abspath(self.filepath) if self.filepath else ""
        directory = bpy.path.abspath(self.directory) if self.directory else ""
        info = _formats().get(self.format)
        if path and os.path.isdir(path):
            return path.rstrip(os.sep) or path
        if info is not None and getattr(info, "is_folder", False):
            folder = directory or os.path.dirname(path)
            return folder.rstrip(os.sep) or folder
        if not path or path.endswith(os.sep):
            folder = path or directory
            return folder.rstrip(os.sep) or folder
        return path

    def read(self, scene, path):
        """(tracks, notes) of ``path`` with this operator's options."""
        fps = self.fps if self.fps > 0 else None
        size = (self.width, self.height) if self.width > 0 and self.height > 0 else None
        return read_with_fallbacks(scene, path, None if self.format == "auto" else self.format, fps, size,
                                   self.min_confidence)


class MONOSKEL_OT_import_tracks(TracksFileImport, bpy.types.Operator):
    """Read 2D joint tracks (native JSON, OpenPose, COCO, MediaPipe, DeepLabCut, CSV) onto the scene"""

    bl_idname = "monoskel.import_tracks"
    bl_label = "Import Tracks"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return common.poll_requirements(cls, context, ("idle",))

    def execute(self, context):
        scene = context.scene
        settings = scene.monoskel
        path = self._path()
        if not path:
            return common.fail(self, "No file selected")
        try:
            tracks, notes = self.read(scene, path)
            store_new_tracks(scene, tracks)
        except Exception as exc:  # noqa: BLE001 - any failure is one report line, never a traceback
            return common.fail(self, exc)
        settings.import_format = self.format
        settings.import_fps = self.fps
        settings.import_width = self.width
        settings.import_height = self.height
        settings.min_confidence = self.min_confidence
        note = f" ({'; '.join(notes)})" if notes else ""
        self.report({"INFO"}, f"Imported {os.path.basename(path.rstrip(os.sep))}: {describe_tracks(tracks)}{note}")
        return {"FINISHED"}


def menu_func_import(self, context):
    self.layout.operator(MONOSKEL_OT_import_tracks.bl_idname, text="MonoSkel Joint Tracks")


classes = (MONOSKEL_OT_import_tracks,)
