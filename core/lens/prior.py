"""A lens read from the footage, as the core's focal length, and how it reaches the estimate.

The core's focal lengths are millimetres of the 36 x 24 mm film the picture is fitted into
(:mod:`core.camera`).  Two kinds of source are turned into that:

* a **35 mm-equivalent** focal length (what phones write into their videos): by its standard
  definition the lens that gives a 36 x 24 mm frame the same *diagonal* angle of view, so the focal
  length in pixels is ``f_eq * diagonal_px / 43.27``.  For a 16:9 picture that is 0.955 ``f_eq`` in
  the core's millimetres, for 3:2 exactly ``f_eq``, for 4:3 1.04 ``f_eq`` (and a portrait picture
  the same in pixels).  Caveat: a phone may state the equivalent of its whole (4:3) sensor while the
  video is cut from it (16:9, and more for stabilisation), so the video's own focal length can be
  longer than this says;
* a **camera's focal length and sensor width** (a Blender Movie Clip's camera): the sensor width
  spans the picture's width.

A file that states no lens but names the phone that recorded it (:func:`.mp4_metadata.recording_phone`:
Android's own recorder writes no lens, only the phone's maker and model) gets a phone's main camera,
*assumed* (:data:`PHONE_VIDEO_EQUIVALENT_MM`), and says so: far closer to a phone's footage than the
estimator's 50 mm default, which makes a walker's depth and planted feet wrong (docs/pose_detection.md).

The lens travels with the tracks: :func:`lens_meta` gives the ``meta`` entries a detector run
writes (``lens_focal_mm``, ``lens_source``, and ``lens_assumed`` for a phone's assumed lens), which the
``skeleton-tracks`` file keeps, and
:func:`lens_prior` is what :func:`core.estimate.estimate` takes when the user gives no focal length.
Order: the user's focal length, then the Movie Clip's camera when it was set, then the file's
metadata, then a phone's main camera when the file names the phone, then none (the estimator's own
default).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..camera import mm_per_pixel

#: the diagonal of the 36 x 24 mm frame that "35 mm equivalent" refers to
FULL_FRAME_DIAGONAL_MM = math.hypot(36.0, 24.0)
META_FOCAL = "lens_focal_mm"
META_SOURCE = "lens_source"
META_ASSUMED = "lens_assumed"
#: Set by :func:`core.estimate.estimate` in the tracks it hands a method when the focal length handed with them
#: is an assumed one (:func:`phone_lens`), not one the footage or the user states: background tracks that show
#: the lens then overrule it (:func:`core.scene_camera.solve.focal_arguments`).
META_FOCAL_ASSUMED = "focal_assumed"
#: The 35 mm-equivalent focal length assumed for a phone's video whose file states none.  Phones film with
#: their main camera unless told otherwise; its lens is 23-26 mm equivalent across its whole 4:3 sensor
#: (the makers' figures for recent Pixel, Galaxy and iPhone models).  A 16:9 video cut across the sensor's
#: full width has a 9 % smaller diagonal, so a 9 % longer equivalent, and stabilisation crops a little more:
#: 25-31 mm for the video's picture.
PHONE_VIDEO_EQUIVALENT_MM = 28.0


def focal_from_35mm_equivalent(equivalent_mm: float, image_size) -> float:
    """The core's focal length (mm of the 36 mm film, :mod:`core.camera`) of a 35 mm-equivalent focal length."""
    w, h = (float(v) for v in image_size)
    focal_px = float(equivalent_mm) * math.hypot(w, h) / FULL_FRAME_DIAGONAL_MM
    return focal_px * mm_per_pixel((w, h))


def focal_from_sensor(focal_mm: float, sensor_width_mm: float, image_size) -> float:
    """The core's focal length of a lens ``focal_mm`` on a sensor ``sensor_width_mm`` wide (the picture's width)."""
    w, h = (float(v) for v in image_size)
    return float(focal_mm) / float(sensor_width_mm) * w * mm_per_pixel((w, h))


@dataclass(frozen=True)
class Lens:
    """A lens read from the footage: the core's focal length for its picture and where it came from
    (words for a report, e.g. "the file's metadata: 26 mm 35 mm-equivalent")."""

    focal_mm: float
    source: str
    #: True for a lens inferred rather than read (:func:`phone_lens`): the estimate warns that it assumed it
    assumed: bool = False

    def meta(self) -> dict:
        """The tracks' ``meta`` entries that carry it."""
        out = {META_FOCAL: round(float(self.focal_mm), 3), META_SOURCE: self.source}
        if self.assumed:
            out[META_ASSUMED] = True
        return out


def phone_lens(phone: str, image_size) -> Lens:
    """The lens assumed for a video of ``image_size`` that ``phone`` recorded without stating its lens."""
    return Lens(focal_from_35mm_equivalent(PHONE_VIDEO_EQUIVALENT_MM, image_size),
                f"a phone's main camera, assumed: {PHONE_VIDEO_EQUIVALENT_MM:g} mm 35 mm-equivalent (the file "
                f"names the phone, {phone}, but not its lens)", assumed=True)


def lens_from_file(path: str, image_size) -> Lens | None:
    """The lens an MP4 / MOV file records (:mod:`.mp4_metadata`), for frames of ``image_size``; else, when the
    file names the phone that recorded it, that phone's main camera (:func:`phone_lens`); else None."""
    from .mp4_metadata import lens_metadata

    found, phone = lens_metadata(path)
    if found is None:
        return None if phone is None else phone_lens(phone, image_size)
    equivalent, where = found
    return Lens(focal_from_35mm_equivalent(equivalent, image_size),
                f"the file's metadata: {equivalent:g} mm 35 mm-equivalent ({where})")


def lens_meta(lens: Lens | None) -> dict:
    return {} if lens is None else lens.meta()


def lens_prior(meta: dict) -> Lens | None:
    """The lens the tracks' ``meta`` carries (:meth:`Lens.meta`), or None when it carries none (or a bad one)."""
    focal = meta.get(META_FOCAL)
    if isinstance(focal, bool) or not isinstance(focal, (int, float)) or not (0 < focal < 1e4):
        return None
    source = meta.get(META_SOURCE)
    return Lens(float(focal), source if isinstance(source, str) and source else "the tracks' metadata",
                assumed=meta.get(META_ASSUMED) is True)


def describe(lens_diag: dict | None) -> str:
    """One line for a report from an estimate's ``diagnostics["lens"]``; "" when there is none."""
    if not isinstance(lens_diag, dict) or lens_diag.get("focal_mm") is None:
        return ""
    return f"lens {lens_diag['focal_mm']:.1f} mm (36 mm film) from {lens_diag.get('source', 'unknown')}"
