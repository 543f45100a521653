"""``pose_from_image``: one frame's 2D joints and the segment lengths -> a 3D pose, and its JSON.

The scale: the user's (a number, ``"min"`` or ``"trunk"``), else, with closure or coplanarity
constraints, the one in ``[s_min, SCALE_SEARCH_MAX x s_min]`` whose best sign pattern meets them
best (Taylor 2.1), else the trunk's (:func:`.family.scale_trunk`: pelvis to neck in the image over its
length).  Taylor's own default, the minimum ``s_min`` ("one or more of the segments are typically
quite close to perpendicular to the viewing direction"), is the largest ratio of image to true length
over all segments, so noise pushes it up: on the tune half's frames (true lengths and signs,
orthographic) ``s_min`` is 14 % above the true scale at 1 px (3.7 % at 0 px) and gives 101 mm per
joint, the trunk's 0.3 % below and 54 mm (the true scale: 50 mm).  The signs: chosen (:mod:`.signs`)
with the user's held.  The pose: scaled orthographic, or perspective when a focal length is given;
under perspective it is then polished (:mod:`.refine`: all joints fitted to all image points at once,
bones and scale held, the bones the user did not hold leaning towards the pose lifter's directions;
``refine=False`` keeps Taylor's construction, the baseline).

``skeleton-pose`` JSON::

    {"format": "skeleton-pose", "version": 1, "projection": "orthographic" | "perspective",
     "focal_mm": f, "image_size": [w, h], "joints": [17 names], "joints_3d": 17 x [x, y, z] | null
     (metres, camera axes: x right, y down, z forward), "signs": {segment: "+" | "-"},
     "scale": s, "scale_min": s_min, "scale_range": [s_min, null], "ambiguous": [segments],
     "shortfall_m": {segment: metres} (segments too short for their image at this scale),
     "lengths_m": {class: metres}, "source": "..."}

Segments are named by class and side: ``thigh.L``, ``forearm.R``, ``lower_spine``, ``head``.
"""

from __future__ import annotations

import dataclasses
import os
from dataclasses import dataclass

import numpy as np

from ..camera import DEFAULT_FOCAL_MM, mm_per_pixel
from ..errors import InputError
from ..io.file_io import check_header, read_json_file, write_json_atomic
from ..skeleton import CLASSES, JOINTS, N_JOINTS, SEGMENT_CLASS, SEGMENTS, segment_lengths_from_classes
from .family import depth_sign, orthographic_pose, perspective_pose, scale_min, scale_trunk
from .refine import refine_pose
from .signs import Constraints, choose_signs, lifter_cue

FORMAT_NAME = "skeleton-pose"
FORMAT_VERSION = 1
#: Constraints search the scale up to this multiple of the minimum.
SCALE_SEARCH_MAX = 3.0
SCALE_SEARCH_STEPS = 25


def segment_names() -> list[str]:
    """``thigh.L`` style names of the 16 segments, in :data:`core.skeleton.SEGMENTS` order."""
    names = []
    for k, (_, c) in enumerate(SEGMENTS):
        cls = CLASSES[SEGMENT_CLASS[k]]
        side = JOINTS[c][:2]
        names.append(f"{cls}.{side[0].upper()}" if side in ("l_", "r_") else cls)
    return names


SEGMENT_NAMES = segment_names()


def parse_signs(text: str | None) -> dict:
    """``"thigh.L=+,forearm.R=-"`` -> {segment index: +1 / -1}."""
    out: dict = {}
    for part in (p.strip() for p in (text or "").split(",") if p.strip()):
        name, sep, value = part.partition("=")
        name = name.strip()
        if not sep or value.strip() not in ("+", "-") or name not in SEGMENT_NAMES:
            raise InputError(f"signs: {part!r} must be SEGMENT=+ or SEGMENT=- with a segment from {SEGMENT_NAMES}")
        out[SEGMENT_NAMES.index(name)] = 1 if value.strip() == "+" else -1
    return out


def _joint(name: str, what: str) -> int:
    if name not in JOINTS:
        raise InputError(f"{what}: unknown joint {name!r}; expected one of {list(JOINTS)}")
    return JOINTS.index(name)


def parse_constraints(closures=(), coplanar=()) -> Constraints:
    """``["l_wrist=r_wrist"]`` and ``["l_wrist,r_wrist,l_elbow,r_elbow"]`` -> :class:`Constraints`."""
    c = Constraints()
    for text in closures:
        a, sep, b = text.partition("=")
        if not sep:
            raise InputError(f"closure {text!r} must be JOINT=JOINT")
        c.closures.append((_joint(a.strip(), "closure"), _joint(b.strip(), "closure")))
    for text in coplanar:
        names = [t.strip() for t in text.split(",") if t.strip()]
        if len(names) != 4:
            raise InputError(f"coplanar {text!r} must name four joints")
        c.coplanar.append(tuple(_joint(n, "coplanar") for n in names))
    return c


@dataclass
class SinglePose:
    joints: np.ndarray          # (17, 3) metres, camera axes; NaN where missing
    signs: np.ndarray           # (16,) +-1
    scale: float                # pixels per metre
    scale_min: float
    ambiguous: list             # segment indices
    shortfall: np.ndarray       # (16,) metres
    projection: str
    focal_mm: float
    class_lengths: np.ndarray
    flip_cost: np.ndarray


def pose_from_image(xy_px: np.ndarray, image_size, class_lengths: np.ndarray, *, focal_mm: float | None = None,
                    perspective: bool = False, scale: float | str | None = None, signs: dict | None = None,
                    constraints: Constraints | None = None, refine: bool = True) -> SinglePose:
    """The pose of one frame (module docstring).  ``xy_px`` (17, 2) pixels, NaN where missing;
    ``class_lengths`` (10,) metres; ``perspective`` without ``focal_mm`` assumes 50 mm."""
    xy = np.asarray(xy_px, dtype=float)
    if xy.shape != (N_JOINTS, 2):
        raise InputError(f"one frame's joints must be shaped (17, 2), got {xy.shape}")
    seg_len = segment_lengths_from_classes(np.asarray(class_lengths, dtype=float))
    if not (np.all(np.isfinite(seg_len)) and np.all(seg_len > 0)):
        raise InputError("every segment length must be a positive number")
    seen = [k for k, (p, c) in enumerate(SEGMENTS) if np.isfinite(xy[p]).all() and np.isfinite(xy[c]).all()]
    if len(seen) < 2:
        raise InputError(f"only {len(seen)} segment(s) have both joints visible; at least 2 are needed")
    if not np.isfinite(xy[0]).all():
        raise InputError("the pelvis is not visible; it is the root of the figure")
    centre = np.array(image_size, dtype=float) / 2.0
    uv = xy - centre
    s_min = scale_min(uv, seg_len)
    if not (np.isfinite(s_min) and s_min > 0):
        raise InputError("the joints coincide in the image: no scale fits the lengths")
    constraints = constraints or Constraints()
    f_mm = float(focal_mm) if focal_mm is not None else DEFAULT_FOCAL_MM
    f_px = f_mm / mm_per_pixel(image_size)
    cue = lifter_cue(uv, f_px)
    trunk = scale_trunk(uv, seg_len)
    if scale == "min" or (scale is None and not constraints.any and not np.isfinite(trunk)):
        s = s_min
    elif scale == "trunk" or (scale is None and not constraints.any):
        if not np.isfinite(trunk) or trunk <= 0:
            raise InputError("the trunk (pelvis to neck) is not visible: give a scale, or 'min'")
        s = trunk
    elif scale is not None:
        if isinstance(scale, str) or not (np.isfinite(scale) and scale > 0):
            raise InputError(f"scale must be a positive number of pixels per metre, 'min' or 'trunk', got {scale!r}")
        s = float(scale)
    else:
        grid = s_min * np.exp(np.linspace(0.0, np.log(SCALE_SEARCH_MAX), SCALE_SEARCH_STEPS))
        costs = [choose_signs(uv, seg_len, g, signs, constraints, cue=cue).cost for g in grid]
        s = float(grid[int(np.argmin(costs))])
    choice = choose_signs(uv, seg_len, s, signs, constraints, cue=cue)
    use_persp = perspective or focal_mm is not None
    if use_persp:
        joints, short = perspective_pose(uv, seg_len, s, choice.signs, f_px)
        if refine:
            # the lifter leans the bones whose signs were chosen; the ones the user held are fitted as given
            held = signs or {}
            lean = np.array([k not in held for k in range(len(SEGMENTS))])
            joints = refine_pose(joints, uv, seg_len, f_px,
                                 cue=None if cue is None else np.where(lean[:, None], cue, np.nan))
            chosen = np.array(choice.signs, copy=True)
            for k, (p, c) in enumerate(SEGMENTS):       # the polish may take a chosen bone through the plane
                if lean[k] and np.isfinite(joints[[p, c]]).all():
                    chosen[k] = depth_sign(joints[p], joints[c])
            choice = dataclasses.replace(choice, signs=chosen)
    else:
        joints, short = orthographic_pose(uv, seg_len, s, choice.signs, f_px)
    return SinglePose(joints, choice.signs, s, s_min, choice.ambiguous, short,
                      "perspective" if use_persp else "orthographic", f_mm, np.asarray(class_lengths, dtype=float),
                      choice.flip_cost)


def pose_to_dict(pose: SinglePose, image_size, source: str = "") -> dict:
    return {
        "format": FORMAT_NAME, "version": FORMAT_VERSION, "projection": pose.projection,
        "focal_mm": pose.focal_mm, "image_size": [float(v) for v in image_size], "joints": list(JOINTS),
        "joints_3d": [None if not np.isfinite(p).all() else [round(float(v), 6) for v in p] for p in pose.joints],
        "signs": {SEGMENT_NAMES[k]: "+" if v > 0 else "-" for k, v in enumerate(pose.signs)},
        "scale": pose.scale, "scale_min": pose.scale_min, "scale_range": [pose.scale_min, None],
        "ambiguous": [SEGMENT_NAMES[k] for k in pose.ambiguous],
        "shortfall_m": {SEGMENT_NAMES[k]: round(float(v), 6) for k, v in enumerate(pose.shortfall) if v > 1e-6},
        "lengths_m": {c: float(v) for c, v in zip(CLASSES, pose.class_lengths, strict=True)},
        "source": source,
    }


def write_pose_json(pose: SinglePose, image_size, path: str | os.PathLike, source: str = "") -> None:
    write_json_atomic(pose_to_dict(pose, image_size, source), path, what="pose file", indent=1)


def read_pose_json(path: str | os.PathLike) -> dict:
    """A ``skeleton-pose`` file as its document, checked: joints (17, 3) as an array (NaN for null)."""
    doc = read_json_file(path)
    where = f"{os.fspath(path)}: "
    check_header(doc, FORMAT_NAME, FORMAT_VERSION, where)
    pts = doc.get("joints_3d")
    if not isinstance(pts, list) or len(pts) != N_JOINTS:
        raise InputError(f"{where}\"joints_3d\" must list 17 joints")
    arr = np.full((N_JOINTS, 3), np.nan)
    for j, p in enumerate(pts):
        if p is None:
            continue
        if not (isinstance(p, list) and len(p) == 3 and all(isinstance(v, (int, float)) for v in p)):
            raise InputError(f"{where}joint {JOINTS[j]}: expected [x, y, z] or null")
        arr[j] = p
    doc["joints_3d"] = arr
    return doc
