"""COCO-17 keypoints, in either of the two COCO shapes.

* **Results** (what detectors write): a list of
  ``{"image_id", "category_id", "keypoints": [51 numbers], "score"}``.  It has
  no image size (pass ``image_size``).  Integer image ids are frame numbers:
  frames run from the smallest id to the largest, ids without a detection
  become empty frames.  String ids are sorted naturally, one frame each.
* **Full annotations**: ``{"images": [{"id", "file_name", "width", "height"}],
  "annotations": [...]}``.  Every image is a frame, ordered by ``file_name``
  (natural order; by ``id`` when names are absent); all images must have the
  same size, which becomes the image size.

Several people on one image: the entry with the highest ``score`` wins (the
largest summed keypoint confidence when there is no score).  Only the person
category counts (``category_id`` of the category named "person", else 1);
crowd annotations are skipped.  The third keypoint value is a confidence, except in
entries without ``score`` whose third values are all 0, 1 or 2: there it is
COCO's visibility flag (2 visible -> confidence 1, 1 occluded but labelled ->
0.5, 0 -> missing).
"""

from __future__ import annotations

import numpy as np

from ...errors import InputError
from ...tracks import Tracks
from ..file_io import read_json_file
from ._canonical import canonical_tracks, choose_fps, choose_image_size
from ._io import finite_float, frame_positions, natural_key
from .keypoint_sets import COCO_17, COCO_17_NAMES

LABEL = "COCO keypoints JSON"


def _keypoints(entry: dict, source: str, where: str, visibility_flags: bool) -> np.ndarray:
    kp = entry.get("keypoints")
    if not isinstance(kp, list) or len(kp) != 51:
        got = len(kp) if isinstance(kp, list) else type(kp).__name__
        raise InputError(f"{source}: {where}: \"keypoints\" must hold 51 numbers (17 x [x, y, v]), got {got}")
    values = []
    for i, v in enumerate(kp):
        f = finite_float(v)
        if f is None:
            raise InputError(f"{source}: {where}, keypoint {COCO_17_NAMES[i // 3]}: {v!r} is not a finite number")
        values.append(f)
    arr = np.array(values).reshape(17, 3)
    if (arr[:, 2] < 0).any():
        raise InputError(f"{source}: {where}: negative keypoint confidence")
    if visibility_flags and np.isin(arr[:, 2], (0.0, 1.0, 2.0)).all():
        arr[:, 2] = np.select([arr[:, 2] >= 2, arr[:, 2] >= 1], [1.0, 0.5], 0.0)
    return arr


def _person_category(doc: dict) -> int:
    categories = doc.get("categories")
    for cat in categories if isinstance(categories, list) else []:
        if isinstance(cat, dict) and cat.get("name") == "person" and isinstance(cat.get("id"), int):
            return cat["id"]
    return 1


def _select(entries: list[dict], source: str, person_cat: int, key_name: str) -> dict:
    """image id -> best keypoint array among the person entries for that image."""
    best: dict = {}
    for n, entry in enumerate(entries):
        where = f"{key_name} {n}"
        if not isinstance(entry, dict):
            raise InputError(f"{source}: {where} is not an object")
        image_id = entry.get("image_id")
        if isinstance(image_id, bool) or not isinstance(image_id, (int, str)):
            raise InputError(f"{source}: {where}: \"image_id\" must be an integer or a string, got {image_id!r}")
        cat = entry.get("category_id", person_cat)
        if cat != person_cat or entry.get("iscrowd"):
            continue
        has_score = "score" in entry
        arr = _keypoints(entry, source, f"{where} (image {image_id})", visibility_flags=not has_score)
        score = finite_float(entry["score"]) if has_score else float(arr[:, 2].sum())
        if score is None:
            raise InputError(f"{source}: {where}: \"score\" must be a finite number, got {entry['score']!r}")
        if image_id not in best or score > best[image_id][0]:
            best[image_id] = (score, arr)
    return {k: v[1] for k, v in best.items()}


def _image_size_of(images: list, source: str) -> tuple[float, float] | None:
    sizes = {}
    for img in images:
        w, h = finite_float(img.get("width")), finite_float(img.get("height"))
        if w is None or h is None or w <= 0 or h <= 0:
            if "width" in img or "height" in img:
                raise InputError(f"{source}: image {img.get('id')!r}: width/height must be positive numbers")
            continue
        sizes.setdefault((w, h), img)
    if len(sizes) > 1:
        (a, ia), (b, ib) = list(sizes.items())[:2]
        raise InputError(f"{source}: mixed image sizes: image {ia.get('file_name', ia.get('id'))!r} is "
                         f"{a[0]:g}x{a[1]:g} but {ib.get('file_name', ib.get('id'))!r} is {b[0]:g}x{b[1]:g}")
    return next(iter(sizes)) if sizes else None


def read_coco(source: str, *, fps: float | None = None, image_size=None) -> Tracks:
    doc = read_json_file(source)
    if isinstance(doc, list):
        shape = "results"
        chosen = _select(doc, source, 1, "entry")
        if not chosen:
            raise InputError(f"{source}: no person keypoints in this COCO results file")
        ids = list(chosen)
        if all(isinstance(i, int) for i in ids):
            rows, first, n = frame_positions(ids, source, "image ids")
            order = dict(zip(ids, rows, strict=True))
        elif all(isinstance(i, str) for i in ids):
            order = {i: r for r, i in enumerate(sorted(ids, key=natural_key))}
            n, first = len(ids), None
        else:
            raise InputError(f"{source}: image ids mix numbers and strings; cannot order the frames")
        file_size = None
    elif isinstance(doc, dict) and isinstance(doc.get("images"), list) and isinstance(doc.get("annotations"), list):
        shape = "annotations"
        images = doc["images"]
        if not images:
            raise InputError(f"{source}: \"images\" is empty; no frames")
        for n_img, img in enumerate(images):
            if not isinstance(img, dict) or isinstance(img.get("id"), bool) or not isinstance(img.get("id"),
                                                                                            (int, str)):
                raise InputError(f"{source}: images entry {n_img} needs an integer or string \"id\"")
        ids = [img["id"] for img in images]
        if len(set(ids)) != len(ids):
            raise InputError(f"{source}: image id listed twice in \"images\"")
        if all(isinstance(img.get("file_name"), str) for img in images):
            images = sorted(images, key=lambda img: natural_key(img["file_name"]))
        else:
            images = sorted(images, key=lambda img: (isinstance(img["id"], str), natural_key(str(img["id"]))))
        order = {img["id"]: r for r, img in enumerate(images)}
        n, first = len(images), None
        file_size = _image_size_of(images, source)
        chosen = _select(doc["annotations"], source, _person_category(doc), "annotation")
        unknown = [i for i in chosen if i not in order]
        if unknown:
            raise InputError(f"{source}: annotation for image id {unknown[0]!r}, which is not in \"images\"")
    else:
        raise InputError(f"{source}: not COCO keypoints (expected a results list or {{\"images\", \"annotations\"}})")
    fps = choose_fps(fps, None, LABEL, source)
    image_size = choose_image_size(image_size, file_size, LABEL, source)
    xy = np.full((n, 17, 2), np.nan)
    conf = np.zeros((n, 17))
    for image_id, arr in chosen.items():
        xy[order[image_id]] = arr[:, :2]
        conf[order[image_id]] = arr[:, 2]
    meta = {"format": "coco", "coco_shape": shape}
    if first is not None:
        meta["first_frame"] = first
    return canonical_tracks(xy, conf, list(COCO_17), fps=fps, image_size=image_size, source=source, meta=meta)
