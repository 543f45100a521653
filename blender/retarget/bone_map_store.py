"""A rig's bone map kept with the rig: a JSON custom property on the armature object, saved in the
.blend, and preset files (plain JSON ``{"format": "monoskel-bone-map", "map": {role: bone}}``) that
carry a map to another rig with the same names."""

from __future__ import annotations

import json

from ...core.errors import InputError
from ...core.io.file_io import read_json_file, write_json_atomic
from ...core.retarget.bone_map import ROLES

PROPERTY = "monoskel_bone_map"
PRESET_FORMAT = "monoskel-bone-map"


def load_stored(obj) -> dict[str, str] | None:
    text = obj.get(PROPERTY) if obj is not None else None
    if not text:
        return None
    try:
        doc = json.loads(text)
    except (TypeError, ValueError):
        return None
    return {r: str(b) for r, b in doc.items() if r in ROLES} if isinstance(doc, dict) else None


def stored_or_guessed(obj, *, fresh: bool = False) -> tuple[dict[str, str], bool]:
    """(bone map, whether it was stored with the rig): the rig's stored map, else (or with ``fresh``)
    one guessed from its bone names and chains."""
    from ...core.retarget import guess_bone_map
    from .rig_io import target_rig

    stored = None if fresh else load_stored(obj)
    return (stored, True) if stored is not None else (guess_bone_map(target_rig(obj)), False)


def store(obj, bone_map: dict[str, str]) -> None:
    obj[PROPERTY] = json.dumps({r: b for r, b in bone_map.items() if b}, sort_keys=True)


def write_preset(path: str, bone_map: dict[str, str]) -> None:
    write_json_atomic({"format": PRESET_FORMAT, "map": {r: b for r, b in bone_map.items() if b}}, path)


def read_preset(path: str) -> dict[str, str]:
    doc = read_json_file(path)
    if not isinstance(doc, dict) or doc.get("format") != PRESET_FORMAT or not isinstance(doc.get("map"), dict):
        raise InputError(f"{path}: not a MonoSkel bone-map preset")
    unknown = [r for r in doc["map"] if r not in ROLES]
    if unknown:
        raise InputError(f"{path}: unknown roles {', '.join(unknown)}")
    return {r: str(b) for r, b in doc["map"].items()}
