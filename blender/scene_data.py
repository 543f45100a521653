"""Keep the tracks, the estimate and the truth with the scene, inside the .blend.

Each is stored as the core's own JSON document in a hidden Text datablock (a
name starting with "." hides it from most lists), so it is saved with the
file, survives undo and can be read by any later Blender or tool.  The scene
remembers the name of its Text in a custom property, so several scenes in one
file each keep their own data and renaming a scene does not lose it.
"""

from __future__ import annotations

import json

import bpy

from ..core.result import Estimate, estimate_from_dict, estimate_to_dict
from ..core.tracks import Tracks, tracks_from_dict, tracks_to_dict

KINDS = ("tracks", "estimate", "truth", "single_image", "views")


def _prop(kind: str) -> str:
    return f"monoskel_{kind}_text"


def write_json_text(text, doc) -> None:
    """Replace ``text``'s contents with ``doc`` as JSON, one value per line.

    Blender's text blocks are slow with long lines: writing a 1.6 MB single-line document took 44 s
    (measured, Blender 5.0), the same with a line break after every value 0.02 s.
    """
    text.clear()
    text.from_string(json.dumps(doc, separators=(",", ":"), indent=0))


def read_json_text(text):
    """The JSON document in ``text`` (the non-standard NaN token reads as a float NaN)."""
    return json.loads(text.as_string(), parse_constant=lambda c: float("nan"))


def _store(scene, kind: str, doc: dict) -> None:
    text_name = scene.get(_prop(kind))
    text = bpy.data.texts.get(text_name) if text_name else None
    if text is None:
        text = bpy.data.texts.new(f".monoskel_{kind}.json")
        scene[_prop(kind)] = text.name
    write_json_text(text, doc)


def _load(scene, kind: str):
    text_name = scene.get(_prop(kind))
    text = bpy.data.texts.get(text_name) if text_name else None
    if text is None:
        return None
    return read_json_text(text)


def clear(scene, kind: str) -> None:
    """Forget one stored item (removes its Text datablock)."""
    text_name = scene.get(_prop(kind))
    text = bpy.data.texts.get(text_name) if text_name else None
    if text is not None:
        bpy.data.texts.remove(text)
    if _prop(kind) in scene:
        del scene[_prop(kind)]


def _json_safe(value):
    try:
        json.dumps(value)
    except (TypeError, ValueError):
        return None
    return value


def store_tracks(scene, tracks: Tracks) -> None:
    doc = tracks_to_dict(tracks)
    doc["source"] = tracks.source
    meta = _json_safe(tracks.meta)
    if meta:
        doc["meta"] = meta
    _store(scene, "tracks", doc)


def load_tracks(scene) -> Tracks | None:
    doc = _load(scene, "tracks")
    if doc is None:
        return None
    tracks = tracks_from_dict(doc)
    tracks.source = str(doc.get("source", ""))
    tracks.meta = dict(doc.get("meta") or {})
    return tracks


def store_estimate(scene, est: Estimate) -> None:
    _store(scene, "estimate", estimate_to_dict(est))


def load_estimate(scene) -> Estimate | None:
    doc = _load(scene, "estimate")
    return None if doc is None else estimate_from_dict(doc)


def store_truth(scene, truth) -> None:
    from ..core.synthetic.truth import truth_to_dict

    _store(scene, "truth", truth_to_dict(truth))


def load_truth(scene):
    doc = _load(scene, "truth")
    if doc is None:
        return None
    from ..core.synthetic.truth import truth_from_dict

    return truth_from_dict(doc)


def store_single_image(scene, doc: dict) -> None:
    """What the single-image pose was made from (:mod:`.single_image`): joints of one frame, lengths, focal."""
    xy = [None if not all(v == v for v in p) else p for p in doc["xy"]]     # NaN (missing) as null
    _store(scene, "single_image", {**doc, "xy": xy})


def load_single_image(scene) -> dict | None:
    return _load(scene, "single_image")


def store_views(scene, views: list[Tracks], cameras=None) -> None:
    """The further synchronized views of the person (their tracks, in order) and, when known, the
    cameras of all views including the first (:class:`core.multiview.ViewCamera`); no views: forgotten."""
    if not views:
        clear(scene, "views")
        return
    docs = []
    for view in views:
        doc = tracks_to_dict(view)
        doc["source"] = view.source
        docs.append(doc)
    _store(scene, "views", {"views": docs, "cameras": [c.to_dict() for c in cameras] if cameras else None})


def load_views(scene) -> tuple[list[Tracks], list | None]:
    """(further views' tracks, cameras of all views or None); ([], None) when there are none."""
    doc = _load(scene, "views")
    if not doc:
        return [], None
    from ..core.multiview.cameras import ViewCamera

    views = []
    for d in doc.get("views") or []:
        view = tracks_from_dict(d)
        view.source = str(d.get("source", ""))
        views.append(view)
    cams = doc.get("cameras")
    return views, ([ViewCamera.from_dict(c) for c in cams] if cams else None)
