"""Blender's feature detector and tracker run on a Movie Clip for background points.

At each look (:func:`core.background_tracking.detection_frames`) Blender's detector finds corners on the
frame; :func:`core.background_tracking.pick_seeds` keeps those off the person and spread out, up to the
number wanted with the points still followed; Blender's tracker follows the new ones forward until it
loses them. Then :func:`core.background_tracking.clean_background` cuts each where the person passes
over it and drops the brief ones, and :func:`core.background_tracking.judge_background` says whether
they can carry the camera at all (enough in view, moving as one scene); if not, none is kept. The kept
tracks stay on the clip, named ``MonoSkel bg NNN`` (so the animator sees them, and Blender's own camera
solve can use them); a new run replaces them. If the run fails, the clip is left as it was: the new
tracks carry a temporary name until the run has succeeded.
"""

from __future__ import annotations

import contextlib

import bpy
import numpy as np

from ...core.background_tracking import (
    DEFAULT_BACKGROUND,
    BackgroundSettings,
    clean_background,
    detection_frames,
    judge_background,
    person_boxes,
    pick_seeds,
    static_tracks,
)
from ...core.errors import InputError
from ..clip_editor import clip_editor, delete_tracks_named, kept_clip_state
from ..movie_clip import _marker_points, _tracks_collection, clip_size, marker_pixels

#: Names of the background tracks a run leaves on the clip (never a joint's name).
BG_PREFIX = "MonoSkel bg "
#: Names while a run is under way (not starting with :data:`BG_PREFIX`: the last run's stay until this succeeds).
NEW_PREFIX = "MonoSkel new bg "
#: Blender's corner detector threshold: low, because the picks (not the detector) choose the points.
CORNER_THRESHOLD = 0.05
#: Blender's motion model for a feature's patch. ``LocScale`` (a zoom scales the patch) measured no better
#: on cases 0-2 of ``bench/background_bench.py`` (rotation, median case 0.176 against 0.133 degrees; 3 of 6
#: cases better, 3 worse): a look every half second renews the patches before a zoom changes them much.
MOTION_MODEL = "Loc"
#: The tracked patch, as a share of the picture's width (odd pixel sizes, 11-41 px).
PATTERN_SHARE = 0.03


def _marker_at(track, clip_frame: int):
    marker = track.markers.find_frame(clip_frame, exact=True)
    return None if marker is None or marker.mute else marker


class BackgroundRun:
    """One Track Background run, a look at a time: :meth:`step` until :attr:`done`, then :meth:`finish`,
    then :meth:`adopt` (the clip keeps the kept features) or :meth:`discard` (the clip as it was).

    Stepped so that a modal caller (*Animate from Clip*) shows progress and takes Esc between looks; each
    step borrows the clip editor and puts the scene's frames and the clip's defaults back itself. Until
    :meth:`adopt`, the features carry a temporary name and the last run's stay on the clip."""

    def __init__(self, clip, tracks, *, first_clip_frame: int = 1, settings: BackgroundSettings = DEFAULT_BACKGROUND):
        step = int(tracks.meta.get("step", 1) or 1)
        if step != 1:
            raise InputError(f"the tracks were detected on one frame in {step} of the clip: Track Background "
                             "follows features frame by frame, so detect on every frame first")
        width, height = clip_size(clip)
        self.scale = width / tracks.image_size[0]
        if abs(height / tracks.image_size[1] - self.scale) > 0.01 * self.scale:
            raise InputError(f"clip '{clip.name}' is {width:g}x{height:g} px, the tracks "
                             f"{tracks.image_size[0]:g}x{tracks.image_size[1]:g}: not the same picture")
        self.first = int(first_clip_frame)
        self.last_clip = self.first + tracks.n_frames - 1
        if self.first < 1 or self.last_clip > clip.frame_duration:
            raise InputError(f"the tracks cover clip frames {self.first}-{self.last_clip}, clip '{clip.name}' has "
                             f"frames 1-{clip.frame_duration}: they are not tracks of this clip")
        self.clip_name, self.tracks, self.settings = clip.name, tracks, settings
        self.size = (width, height)
        self.boxes = person_boxes(tracks, settings.person_margin)
        self.looks = detection_frames(tracks.n_frames, tracks.fps, settings.every_s)
        self.pattern = int(np.clip(round(PATTERN_SHARE * width), 11, 41)) | 1
        self.next_look = 0
        self.made = 0
        self.final: dict[str, str] = {}      # temporary name -> the name it takes on adopt
        self._held = None                    # the clip while :meth:`on_clip` is held

    @property
    def done(self) -> bool:
        return self.next_look >= len(self.looks)

    @property
    def fraction(self) -> float:
        return self.next_look / max(len(self.looks), 1)

    def _clip(self):
        clip = bpy.data.movieclips.get(self.clip_name)
        if clip is None:
            raise InputError(f"clip '{self.clip_name}' was removed during Track Background")
        return clip

    @contextlib.contextmanager
    def on_clip(self, context):
        """The borrowed clip editor, with this run's tracking defaults, and the scene put back after. Each
        step enters it on its own; a caller that runs several steps at once holds it around them (entering
        it every look cost 40 % more time on a 120-frame shot: the editor and the frame are set up anew)."""
        if self._held is not None:
            yield self._held
            return
        clip = self._clip()
        with kept_clip_state(context.scene, clip), clip_editor(context, clip):
            opts = clip.tracking.settings
            opts.default_pattern_size = self.pattern
            opts.default_search_size = int(min(4 * self.pattern + 1, 201)) | 1
            opts.default_motion_model = MOTION_MODEL
            opts.default_pattern_match = "KEYFRAME"
            opts.default_frames_limit = 0
            self._held = clip
            try:
                yield clip
            finally:
                self._held = None

    def step(self, context) -> None:
        """Look for new features on the next look's frame and follow them forward."""
        if self.done:
            return
        look = self.looks[self.next_look]
        settings, tracks = self.settings, self.tracks
        image_w, image_h = tracks.image_size
        edge_px = settings.edge_share * image_w
        separation_px = settings.separation_share * image_w
        width, height = self.size
        scale = self.scale
        scene = context.scene
        with self.on_clip(context) as clip:
            collection = _tracks_collection(clip)
            if self.next_look == 0:
                delete_tracks_named(clip, NEW_PREFIX)
            clip_frame = self.first + look
            scene_frame = clip_frame + int(clip.frame_start) - 1
            scene.frame_start = min(scene.frame_start, scene_frame)
            scene.frame_end = self.last_clip + int(clip.frame_start) - 1
            scene.frame_set(scene_frame)
            context.space_data.clip_user.frame_current = scene_frame
            live = []
            for t in collection:
                if t.name.startswith(NEW_PREFIX):
                    marker = _marker_at(t, clip_frame)
                    if marker is not None:
                        live.append(marker_pixels(t, marker, width / scale, height / scale))
            for t in collection:
                t.select = False
            before = {t.as_pointer() for t in collection}
            bpy.ops.clip.detect_features(placement="FRAME", margin=int(edge_px * scale),
                                         threshold=CORNER_THRESHOLD, min_distance=int(separation_px * scale))
            found = [t for t in collection if t.as_pointer() not in before]
            cands = []
            for t in found:
                marker = t.markers.find_frame(clip_frame, exact=True)
                cands.append((np.nan, np.nan) if marker is None else
                             marker_pixels(t, marker, width / scale, height / scale))
            picked = set(pick_seeds(np.array(cands).reshape(-1, 2), self.boxes[look], np.array(live).reshape(-1, 2),
                                    (image_w, image_h), settings.want, separation_px, edge_px))
            names = []
            for i in sorted(picked):
                self.made += 1
                found[i].name = f"{NEW_PREFIX}{self.made:03d}"
                names.append(found[i].name)
            for i, t in enumerate(found):
                t.select = i not in picked
            if len(picked) < len(found):
                bpy.ops.clip.delete_track()
            if names:
                for t in collection:
                    t.select = t.name in names
                bpy.ops.clip.track_markers(backwards=False, sequence=True)
        self.next_look += 1

    def finish(self, context):
        """(:class:`core.tracks.StaticTracks` or None, :class:`BackgroundReport`): the followed features
        cleaned (:func:`core.background_tracking.clean_background`) and judged
        (:func:`core.background_tracking.judge_background`: ``report.fallback`` says why they are not used,
        and then None is returned and nothing is kept). The clip keeps them only after :meth:`adopt`."""
        tracks, first = self.tracks, self.first
        width, height = self.size
        with self.on_clip(context) as clip:
            ours = [t for t in _tracks_collection(clip) if t.name.startswith(NEW_PREFIX)]
            xy = np.full((tracks.n_frames, len(ours), 2), np.nan)
            for k, t in enumerate(ours):
                frames, pts = _marker_points(t, clip.frame_duration, width, height)
                i = frames - (first - 1)
                inside = (i >= 0) & (i < tracks.n_frames)
                xy[i[inside], k] = pts[inside] / self.scale
            cleaned, kept, report = clean_background(xy, self.boxes, tracks.fps, self.settings,
                                                     image_width=tracks.image_size[0])
            # the clip shows what is used: the brief ones deleted, the cut ones muted from the cut on
            keep_names = [t.name for k, t in enumerate(ours) if kept[k]]
            for t in _tracks_collection(clip):      # only ours are deleted (each step put the user's selection back)
                t.select = False
            for k, t in enumerate(ours):
                t.select = not kept[k]
                if kept[k]:
                    for i in np.flatnonzero(np.isfinite(xy[:, k, 0]) & ~np.isfinite(cleaned[:, k, 0])):
                        marker = t.markers.find_frame(int(i) + first, exact=True)
                        if marker is not None:
                            marker.mute = True
            if not kept.all():
                bpy.ops.clip.delete_track()
        self.final = {n: BG_PREFIX + n[len(NEW_PREFIX):] for n in keep_names}
        static = static_tracks(cleaned[:, kept], [self.final[n] for n in keep_names])
        report.fallback = judge_background(tracks, static)
        return (None if report.fallback else static), report

    def adopt(self, context) -> None:
        """The kept features replace the last run's ``MonoSkel bg`` tracks on the clip."""
        with self.on_clip(context) as clip:
            delete_tracks_named(clip, BG_PREFIX)
            by_name = {t.name: t for t in _tracks_collection(clip)}
            for old, name in self.final.items():
                by_name[old].name = name

    def discard(self, context) -> None:
        """Remove this run's features from the clip (which keeps the last run's)."""
        if bpy.data.movieclips.get(self.clip_name) is None:
            return
        with self.on_clip(context) as clip:
            delete_tracks_named(clip, NEW_PREFIX)


def track_background(context, clip, tracks, *, first_clip_frame: int = 1,
                     settings: BackgroundSettings = DEFAULT_BACKGROUND, progress=None):
    """Background features of ``clip`` for the joint ``tracks`` (whose frame 0 is clip frame
    ``first_clip_frame``): (:class:`core.tracks.StaticTracks` or None, :class:`BackgroundReport`); a whole
    :class:`BackgroundRun`. ``progress(done, total)`` is called after each look for features. When the
    features cannot carry the camera (``report.fallback`` says why) None is returned and the clip keeps
    what it had."""
    run = BackgroundRun(clip, tracks, first_clip_frame=first_clip_frame, settings=settings)
    try:
        with run.on_clip(context):
            while not run.done:
                run.step(context)
                if progress is not None:
                    progress(run.next_look, len(run.looks))
            static, report = run.finish(context)
            if static is None:
                run.discard(context)
            else:
                run.adopt(context)
    except BaseException:
        run.discard(context)
        raise
    return static, report
