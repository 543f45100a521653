"""OpenPose output: a folder with one ``*_keypoints.json`` per frame.

Each file is ``{"people": [{"pose_keypoints_2d": [x, y, c, ...]}, ...]}``;
the layout (BODY_25 = 75 numbers, COCO-18 = 54) is recognised from the length
and must be the same in every file.  Frames are the files in natural order
(``..._2_keypoints`` before ``..._10_keypoints``); when files named
``*_keypoints.json`` are present, other JSON files are ignored.  OpenPose writes (0, 0, 0)
for an undetected keypoint; confidence 0 means missing.  OpenPose stores no
frame rate or image size: both come from the arguments.

Several people in a frame: the one with the largest summed keypoint
confidence is taken (per frame, so with several people in view the track can
jump between them), or ``person=k`` takes the k-th entry of ``people`` in
every frame (a frame with fewer people is empty).
"""

from __future__ import annotations

import os
import re

import numpy as np

from ...errors import InputError
from ...tracks import Tracks
from ..file_io import read_json_file
from ._canonical import canonical_tracks, choose_fps, choose_image_size
from ._io import finite_float, natural_key
from .keypoint_sets import OPENPOSE_BODY_25, OPENPOSE_COCO_18, used

LABEL = "OpenPose JSON folder"
LAYOUTS = {75: ("BODY_25", OPENPOSE_BODY_25), 54: ("COCO-18", OPENPOSE_COCO_18)}


def frame_files(folder: str) -> list[str]:
    """The per-frame JSON files of an OpenPose output folder, in frame order."""
    try:
        names = [n for n in os.listdir(folder) if n.lower().endswith(".json")
                 and os.path.isfile(os.path.join(folder, n))]
    except OSError as exc:
        raise InputError(f"{folder}: cannot list folder ({exc.strerror or exc})") from None
    if not names:
        raise InputError(f"{folder}: no .json files in this folder (expected OpenPose per-frame output)")
    keypoint_files = [n for n in names if n.lower().endswith("_keypoints.json")]
    names = keypoint_files or names  # OpenPose's own naming: other JSON beside it (settings ...) is not a frame
    patterns = sorted({re.sub(r"\d+", "#", n) for n in names})
    if len(patterns) > 1:
        raise InputError(f"{folder}: files of several sequences are mixed here "
                         f"({patterns[0]!r} and {patterns[1]!r}); keep one sequence per folder")
    return [os.path.join(folder, n) for n in sorted(names, key=natural_key)]


def _person_rows(doc, path: str) -> list[list]:
    if not isinstance(doc, dict) or not isinstance(doc.get("people"), list):
        raise InputError(f"{path}: not an OpenPose frame (no \"people\" list)")
    rows = []
    for k, person in enumerate(doc["people"]):
        kp = person.get("pose_keypoints_2d") if isinstance(person, dict) else None
        if not isinstance(kp, list):
            raise InputError(f"{path}: person {k} has no \"pose_keypoints_2d\" list")
        rows.append(kp)
    return rows


def _parse_person(kp: list, path: str, k: int) -> np.ndarray:
    values = np.empty(len(kp))
    for i, v in enumerate(kp):
        f = finite_float(v)
        if f is None:
            raise InputError(f"{path}: person {k}, keypoint {i // 3}: {v!r} is not a finite number")
        values[i] = f
    arr = values.reshape(-1, 3)
    if (arr[:, 2] < 0).any():
        raise InputError(f"{path}: person {k}, keypoint {int(np.argmax(arr[:, 2] < 0))}: negative confidence")
    return arr


def read_openpose(source: str, *, fps: float | None = None, image_size=None, person: int | None = None) -> Tracks:
    if os.path.isfile(source):
        raise InputError(f"{source}: this is one OpenPose frame; pass the folder that holds all frame files")
    if person is not None and (isinstance(person, bool) or not isinstance(person, int) or person < 0):
        raise InputError(f"{source}: person must be a non-negative index, got {person!r}")
    files = frame_files(source)
    fps = choose_fps(fps, None, LABEL, source)
    image_size = choose_image_size(image_size, None, LABEL, source)
    layout_name, first_file, frames = None, None, []
    for path in files:
        people = _person_rows(read_json_file(path), path)
        chosen = None
        best = -1.0
        for k, kp in enumerate(people):
            if len(kp) not in LAYOUTS:
                raise InputError(f"{path}: person {k} has {len(kp)} numbers in pose_keypoints_2d; expected 75 "
                                 "(BODY_25) or 54 (COCO-18)")
            name = LAYOUTS[len(kp)][0]
            if layout_name is None:
                layout_name, first_file = name, path
            elif name != layout_name:
                raise InputError(f"{path}: {name} keypoints, but {os.path.basename(first_file)} has "
                                 f"{layout_name}; all files must use one layout")
            arr = _parse_person(kp, path, k)
            score = float(arr[:, 2].sum())
            if (person is None and score > best) or person == k:
                chosen, best = arr, score
        frames.append(chosen)
    if layout_name is None:
        raise InputError(f"{source}: no person detected in any of the {len(files)} frame files")
    idx, names = used(LAYOUTS[75 if layout_name == "BODY_25" else 54][1])
    xy = np.full((len(frames), len(idx), 2), np.nan)
    conf = np.zeros((len(frames), len(idx)))
    for f, arr in enumerate(frames):
        if arr is not None:
            xy[f] = arr[idx, :2]
            conf[f] = arr[idx, 2]
    meta = {"format": "openpose", "layout": layout_name, "person": "most confident" if person is None else person,
            "files": [os.path.basename(p) for p in (files[0], files[-1])]}
    return canonical_tracks(xy, conf, names, fps=fps, image_size=image_size, source=source, meta=meta)
