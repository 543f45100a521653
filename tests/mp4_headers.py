"""Test helper: turn an mp4's video track header a quarter, as a phone flags a portrait video.

Encoders no longer write the old ``rotate`` tag, so the tests rewrite the first track header's
matrix in place (a version-0 ``tkhd``: matrix 40 bytes into its payload).
"""

from __future__ import annotations

import struct
from pathlib import Path


def turn_quarter(path) -> None:
    path = Path(path)
    data = bytearray(path.read_bytes())
    at = data.find(b"tkhd")
    assert at > 0 and data[at + 4] == 0, "no version-0 track header"
    matrix = at + 4 + 40
    data[matrix:matrix + 36] = struct.pack(">9i", 0, 1 << 16, 0, -1 << 16, 0, 0, 0, 0, 1 << 30)
    path.write_bytes(bytes(data))
