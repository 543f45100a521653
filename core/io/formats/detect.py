"""Guess a file's format from its path and first bytes, for ``read_any(path)`` without ``format``.

The rules are in docs/formats.md ("Auto-detection"): a folder is OpenPose;
a JSON file is recognised by its top-level shape; a CSV file by its header.
Anything else is an :class:`InputError` that lists the format names.
"""

from __future__ import annotations

import os

from ...errors import InputError
from ..file_io import read_json_file
from ._io import csv_rows
from .mediapipe_csv import is_mediapipe_header


def _json_format(doc) -> str | None:
    if isinstance(doc, dict):
        if doc.get("format") == "skeleton-tracks" or "joints" in doc:  # "joints": a native file, even if damaged
            return "native"
        if "images" in doc and "annotations" in doc:
            return "coco"
        if "people" in doc:
            return "openpose"
        if isinstance(doc.get("frames"), list):
            return "mediapipe_json"
        return None
    if isinstance(doc, list):
        items = [d for d in doc if d is not None]
        if items and any(isinstance(d, dict) and ("keypoints" in d or "image_id" in d) for d in items):
            return "coco"
        if items and all(isinstance(d, (list, dict)) for d in items):
            return "mediapipe_json"
    return None


def _csv_format(header: list[str]) -> str | None:
    lowered = [c.lower() for c in header]
    if lowered and lowered[0] == "scorer":
        return "dlc"
    if {"frame", "joint", "x", "y"} <= set(lowered):
        return "generic_csv"
    if is_mediapipe_header(header):
        return "mediapipe_csv"
    return None


def detect_format(source: str, names: list[str]) -> str:
    """Name of the format of ``source`` (a key of ``FORMATS``, passed as ``names`` for the message)."""
    if os.path.isdir(source):
        return "openpose"
    if not os.path.exists(source):
        raise InputError(f"{source}: no such file or folder")
    ext = os.path.splitext(source)[1].lower()
    found = None
    if ext == ".json":
        found = _json_format(read_json_file(source))
        if found == "openpose":
            raise InputError(f"{source}: this is one OpenPose frame; pass the folder that holds all frame files")
    elif ext in (".csv", ".txt"):
        rows = [r for r in csv_rows(source, limit=20) if not r[1][0].startswith("#")]
        found = _csv_format(rows[0][1]) if rows else None
    if found is None:
        raise InputError(f"{source}: cannot tell the file format; pass format= one of {names}")
    return found
