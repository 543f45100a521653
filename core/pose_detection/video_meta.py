"""The display rotation a phone writes into an MP4 / MOV file, read from its track header.

Phones store the sensor's landscape frames and flag the video as "show turned
90 degrees" (the ``tkhd`` box's matrix).  Blender 4.5 and newer apply the flag
when they open the movie; Blender 4.2 shows and decodes the stored frames, so
a portrait video is sideways there, and the estimator would see a camera
rolled a quarter turn.  This reads the flag (pure Python, a few box headers)
so that the front ends can say so.
"""

from __future__ import annotations

import math
import struct


def boxes(data: bytes, start: int, end: int):
    """(type, payload start, payload end) of the MP4 / MOV boxes in ``data[start:end]``."""
    pos = start
    while pos + 8 <= end:
        size, kind = struct.unpack(">I4s", data[pos:pos + 8])
        header = 8
        if size == 1:
            if pos + 16 > end:
                return
            size = struct.unpack(">Q", data[pos + 8:pos + 16])[0]
            header = 16
        elif size == 0:
            size = end - pos
        if size < header or pos + size > end:
            return
        yield kind, pos + header, pos + size
        pos += size


def _tkhd_rotation(payload: bytes) -> tuple[int, float, float] | None:
    """(rotation degrees, width, height) of one track header; None when it cannot be read."""
    if len(payload) < 4:
        return None
    version = payload[0]
    offset = 4 + (32 if version == 1 else 20) + 8 + 2 + 2 + 2 + 2  # times, id, reserved, layer ... volume
    if len(payload) < offset + 36 + 8:
        return None
    a, b, _u, c, d, _v, _x, _y, _w = struct.unpack(">9i", payload[offset:offset + 36])
    width, height = (v / 65536.0 for v in struct.unpack(">II", payload[offset + 36:offset + 44]))
    angle = math.degrees(math.atan2(b / 65536.0, a / 65536.0))
    return int(round(angle / 90.0)) % 4 * 90, width, height


def file_ends(path: str, limit: int) -> tuple[bytes, bytes, int] | None:
    """A movie file's first ``limit`` bytes, its last ``limit`` bytes when it is longer (else ``b""``) and
    where those start; None when it cannot be read.

    The ``moov`` box that holds a movie's headers sits at the start or at the end of the file, so the
    readers of its metadata look at both ends and never read a whole long file.
    """
    try:
        with open(path, "rb") as fh:
            fh.seek(0, 2)
            size = fh.tell()
            fh.seek(0)
            head = fh.read(min(size, limit))
            if size <= limit:
                return head, b"", 0
            fh.seek(size - limit)
            return head, fh.read(), size - limit
    except OSError:
        return None


def display_rotation(path: str, limit: int = 64 * 1024 * 1024) -> int:
    """Degrees (0, 90, 180 or 270) the first video track of an MP4 / MOV is turned by its header's matrix
    (the angle of the matrix's first column; players turn the picture by it, or by its opposite).

    0 for anything that is not such a file or has no flag; reads at most ``limit`` bytes (the
    ``moov`` box sits at the start or the end of the file, so both ends are looked at).
    """
    ends = file_ends(path, limit)
    if ends is None:
        return 0
    head, tail, tail_start = ends
    for data in (head, tail):
        if not data:
            continue
        found = _search(data, tail_start if data is tail else 0)
        if found is not None:
            return found
    return 0


def _search(data: bytes, base: int) -> int | None:
    # find 'moov' among the top-level boxes within this chunk (a tail chunk may start mid-box)
    positions = [0] if base == 0 else [i - 4 for i in range(len(data)) if data.startswith(b"moov", i)][:8]
    for pos in positions:
        if pos < 0:
            continue
        for kind, start, end in boxes(data, pos, len(data)):
            if kind == b"moov":
                return _moov_rotation(data, start, end)
            if base != 0:
                break
    return None


def _moov_rotation(data: bytes, start: int, end: int) -> int | None:
    for kind, t0, t1 in boxes(data, start, end):
        if kind != b"trak":
            continue
        for sub, s0, s1 in boxes(data, t0, t1):
            if sub == b"tkhd":
                found = _tkhd_rotation(data[s0:s1])
                if found is not None and found[1] > 0 and found[2] > 0:  # a video track has a size
                    return found[0]
    return None
