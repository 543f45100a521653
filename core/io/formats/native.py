"""The project's own ``skeleton-tracks`` JSON (implemented in core/tracks.py), as a format entry.

fps and image size are stored in the file; an argument, when given, replaces
the stored value (the rule for every format).  The file is read here with
the shared helpers (so that undecodable bytes and absurdly large numbers are
:class:`InputError` too) and validated by :func:`core.tracks.tracks_from_dict`,
exactly as :func:`core.tracks.read_tracks_json` does.
"""

from __future__ import annotations

from ...errors import InputError
from ...tracks import Tracks, tracks_from_dict
from ..file_io import read_json_file

LABEL = "MonoSkel tracks JSON"


def read_native(source: str, *, fps: float | None = None, image_size=None) -> Tracks:
    doc = read_json_file(source)
    try:
        tracks = tracks_from_dict(doc, source)
    except OverflowError:
        raise InputError(f"{source}: a number is too large to be a coordinate, fps or size") from None
    meta = dict(tracks.meta)
    meta.setdefault("format", "native")
    return tracks.replaced(fps=fps if fps is not None else tracks.fps,
                           image_size=image_size if image_size is not None else tracks.image_size, meta=meta)
