"""BlazePose's two stages in numpy: find the person, then read 33 landmarks in a region.

The networks themselves run elsewhere (:mod:`.runtime`); this module holds
everything around them, written from MediaPipe's published graph settings
for ``pose_detection`` and ``pose_landmark_full``:

* detector: 224 x 224 letterboxed frame in [-1, 1]; 2254 SSD anchors (strides
  8, 16, 32, 32, 32; two per cell and layer; unit size); per anchor a box and
  four keypoints as offsets in input pixels, a logit score; scores over 0.5
  kept, weighted non-maximum suppression at IoU 0.3, people best first.
  Keypoints 0 and 1 align the body (mid-hip, and a point on its enclosing
  circle) and give the landmark region (:func:`.roi.region_from_alignment`).
* landmarks: 256 x 256 crop of that region in [0, 1]; 39 rows of (x, y, z,
  visibility, presence) in crop pixels, 33 body landmarks then two alignment
  points for the next frame's region; a pose-presence score; a 64 x 64 heatmap
  that refines each landmark within a 7 x 7 window when it is confident; and
  39 "world" landmarks (x, y, z) in metres from the centre between the hips,
  in the crop's axes, which MediaPipe turns by the region's rotation into the
  picture's axes (its ``WorldLandmarkProjectionCalculator``): x right, y down,
  z away from the camera (smaller is nearer).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .roi import Region, crop, region_from_alignment, tiles, whole_frame

DETECTOR_SIZE = 224
LANDMARK_SIZE = 256
N_LANDMARKS = 33
#: a detection and a region's pose score must reach these (MediaPipe's defaults)
MIN_DETECTION_SCORE = 0.5
MIN_PRESENCE = 0.5
NMS_IOU = 0.3
HEATMAP_KERNEL = 7
MIN_HEATMAP_CONFIDENCE = 0.5


def _sigmoid(x):
    return 1.0 / (1.0 + np.exp(-np.clip(x, -100.0, 100.0)))


def ssd_anchors() -> np.ndarray:
    """(2254, 2) anchor centres in the detector's normalised input (the anchors are unit-sized)."""
    strides = (8, 16, 32, 32, 32)
    centres = []
    layer = 0
    while layer < len(strides):
        per_cell = 0
        last = layer
        while last < len(strides) and strides[last] == strides[layer]:
            per_cell += 2  # aspect ratio 1, plus the interpolated scale
            last += 1
        cells = math.ceil(DETECTOR_SIZE / strides[layer])
        ys, xs = np.meshgrid((np.arange(cells) + 0.5) / cells, (np.arange(cells) + 0.5) / cells, indexing="ij")
        grid = np.stack([xs.ravel(), ys.ravel()], axis=-1)
        centres.append(np.repeat(grid, per_cell, axis=0))
        layer = last
    return np.concatenate(centres)


ANCHORS = ssd_anchors()


@dataclass
class Detection:
    """One person found by the detector, in image pixels."""

    score: float
    box: np.ndarray        # (4,) x_min, y_min, x_max, y_max
    keypoints: np.ndarray  # (4, 2)

    def region(self) -> Region:
        return region_from_alignment(self.keypoints[0], self.keypoints[1])


def detector_input(image: np.ndarray, region: Region | None = None) -> tuple[np.ndarray, Region]:
    """The detector's (1, 224, 224, 3) float32 input and the region it shows (default: the whole frame)."""
    h, w = image.shape[:2]
    frame = whole_frame(w, h) if region is None else region
    tensor = crop(image, frame, DETECTOR_SIZE, replicate=False) * (2.0 / 255.0) - 1.0
    return tensor[None], frame


def find_people(image: np.ndarray, detect) -> tuple[list[Detection], int]:
    """People in ``image``, best first, and how many detector runs that took.

    ``detect`` runs the detector network on one input.  The whole frame first; when it shows nobody,
    the frame's :func:`.roi.tiles`, their people merged (a person seen by two tiles is kept once, the
    better-scored sighting).  Far, small people are found that way (docs/pose_detection.md).
    """
    h, w = image.shape[:2]
    found = decode_detections(*detect(detector_input(image)[0]), whole_frame(w, h))
    if found:
        return found, 1
    regions = tiles(w, h)
    for region in regions:
        found += decode_detections(*detect(detector_input(image, region)[0]), region)
    found.sort(key=lambda d: -d.score)
    kept: list[Detection] = []
    for d in found:
        if not kept or _iou(d.box, np.array([k.box for k in kept])).max() <= NMS_IOU:
            kept.append(d)
    return kept, 1 + len(regions)


def decode_detections(raw_boxes: np.ndarray, raw_scores: np.ndarray, frame: Region) -> list[Detection]:
    """People in the detector's output, best first, in image pixels (weighted NMS)."""
    raw = np.asarray(raw_boxes, dtype=np.float64).reshape(-1, 12)
    scores = _sigmoid(np.asarray(raw_scores, dtype=np.float64).reshape(-1))
    keep = np.flatnonzero(scores >= MIN_DETECTION_SCORE)
    if keep.size == 0:
        return []
    raw, scores, anchors = raw[keep], scores[keep], ANCHORS[keep]
    centre = raw[:, 0:2] / DETECTOR_SIZE + anchors
    half = raw[:, 2:4] / DETECTOR_SIZE / 2.0
    boxes = np.concatenate([centre - half, centre + half], axis=1)
    kps = raw[:, 4:12].reshape(-1, 4, 2) / DETECTOR_SIZE + anchors[:, None, :]
    found = []
    order = list(np.argsort(-scores))
    while order:
        top = order[0]
        rest = np.array(order)
        iou = _iou(boxes[top], boxes[rest])
        group = rest[iou > NMS_IOU]
        weights = scores[group][:, None]
        box = (boxes[group] * weights).sum(0) / weights.sum()
        kp = (kps[group] * weights[:, :, None]).sum(0) / weights.sum()
        corners = frame.to_image(box.reshape(2, 2)).ravel()
        found.append(Detection(float(scores[top]), corners, frame.to_image(kp)))
        merged = set(group.tolist())
        order = [i for i in order if i not in merged]
    return found


def _iou(box: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    lo = np.maximum(box[:2], boxes[:, :2])
    hi = np.minimum(box[2:], boxes[:, 2:])
    inter = np.prod(np.clip(hi - lo, 0.0, None), axis=1)
    area = np.prod(box[2:] - box[:2])
    areas = np.prod(boxes[:, 2:] - boxes[:, :2], axis=1)
    return inter / np.maximum(area + areas - inter, 1e-12)


def landmark_input(image: np.ndarray, region: Region) -> np.ndarray:
    """The landmark network's (1, 256, 256, 3) float32 input for ``region``."""
    return (crop(image, region, LANDMARK_SIZE, replicate=True) * (1.0 / 255.0))[None]


@dataclass
class Landmarks:
    """One region's answer: 33 landmarks in image pixels, their visibility, the pose score, and the two
    alignment points (px) that place the next frame's region."""

    xy: np.ndarray          # (33, 2) px
    visibility: np.ndarray  # (33,)
    score: float
    alignment: np.ndarray   # (2, 2) px: the body's centre, a point on its enclosing circle
    world: np.ndarray | None = None   # (33, 3) m from the hips' centre, picture axes (x right, y down, z away)


def decode_landmarks(raw: np.ndarray, flag: np.ndarray, heatmap: np.ndarray | None, region: Region,
                     world: np.ndarray | None = None) -> Landmarks:
    """Image-pixel landmarks from the landmark network's outputs for ``region`` (and its world landmarks,
    when ``world`` holds the network's 39 x 3 metric output, turned into the picture's axes)."""
    rows = np.asarray(raw, dtype=np.float64).reshape(-1, 5)
    uv = rows[:, :2] / LANDMARK_SIZE
    if heatmap is not None:
        uv = refine_with_heatmap(uv, np.asarray(heatmap).reshape(heatmap.shape[-3:]))
    xy = region.to_image(uv)
    score = float(np.asarray(flag).reshape(-1)[0])
    return Landmarks(xy=xy[:N_LANDMARKS], visibility=_sigmoid(rows[:N_LANDMARKS, 3]), score=score,
                     alignment=xy[N_LANDMARKS:N_LANDMARKS + 2],
                     world=None if world is None else world_in_picture_axes(world, region))


def world_in_picture_axes(world: np.ndarray, region: Region) -> np.ndarray:
    """(33, 3) metres: the network's world landmarks (crop axes) turned by the region's rotation about the
    viewing axis, so x and y follow the picture's right and down whatever way the crop was turned."""
    pts = np.asarray(world, dtype=np.float64).reshape(-1, 3)[:N_LANDMARKS]
    c, s = math.cos(region.rotation), math.sin(region.rotation)
    x, y = pts[:, 0], pts[:, 1]
    return np.stack([c * x - s * y, s * x + c * y, pts[:, 2]], axis=-1)


def refine_with_heatmap(uv: np.ndarray, heatmap: np.ndarray) -> np.ndarray:
    """Each landmark moved to the confidence-weighted centre of its heatmap window, when confident."""
    hm_h, hm_w, channels = heatmap.shape
    out = uv.copy()
    half = (HEATMAP_KERNEL - 1) // 2
    for k in range(min(channels, uv.shape[0])):
        col, row = int(uv[k, 0] * hm_w), int(uv[k, 1] * hm_h)
        if not (0 <= col < hm_w and 0 <= row < hm_h):
            continue
        r0, r1 = max(0, row - half), min(hm_h, row + half + 1)
        c0, c1 = max(0, col - half), min(hm_w, col + half + 1)
        conf = _sigmoid(heatmap[r0:r1, c0:c1, k].astype(np.float64))
        total = conf.sum()
        if conf.max() >= MIN_HEATMAP_CONFIDENCE and total > 0:
            rr, cc = np.mgrid[r0:r1, c0:c1]
            out[k, 0] = (cc * conf).sum() / hm_w / total
            out[k, 1] = (rr * conf).sum() / hm_h / total
    return out
