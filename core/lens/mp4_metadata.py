"""The 35 mm-equivalent focal length an MP4 / MOV file records, and the phone that recorded it, read from its atoms.

Where cameras put it (each looked for, first found wins):

* QuickTime metadata, as iPhones write it: a ``meta`` atom (in ``moov``, in a track, or in ``udta``)
  whose ``keys`` atom lists ``com.apple.quicktime.camera.focal_length.35mm_equivalent`` and whose
  ``ilst`` atom holds its value in a ``data`` atom (an integer, a float, or UTF-8 text such as
  ``"26"`` or ``"26.00mm"``);
* an EXIF block (TIFF header, optionally after ``Exif\\0\\0``) inside ``udta``, as some cameras embed
  one: tag 0xA405 ``FocalLengthIn35mmFilm`` of its EXIF directory;
* XMP text (the ``XMP_`` atom in ``udta``, or the XMP ``uuid`` atom): ``exif:FocalLengthIn35mmFilm``.

Which phone recorded the file, when it says so (:func:`recording_phone`: Android's ``com.android.*``
keys, an iPhone's make and model), for a lens the file does not state (:mod:`.prior`).

Only metadata atoms are read (``moov`` at the file's start or end, within ``limit`` bytes); any
damage makes the reader give up quietly: it returns None, never raises, since a lens prior is a
help and its absence is normal.
"""

from __future__ import annotations

import re
import struct

from ..pose_detection.video_meta import boxes, file_ends

FOCAL_KEY = "com.apple.quicktime.camera.focal_length.35mm_equivalent"
#: the QuickTime metadata keys Android's camera writes begin with this
ANDROID_PREFIX = "com.android."
EXIF_TAG_FOCAL_35MM = 0xA405
EXIF_IFD_POINTER = 0x8769
XMP_UUID = bytes.fromhex("be7acfcb97a942e89c71999491e3afac")
#: containers walked for metadata (never ``mdat``: the pictures)
_CONTAINERS = {b"moov", b"trak", b"udta", b"mdia", b"minf"}
#: a 35 mm-equivalent focal length outside this range (mm) is not taken as one
PLAUSIBLE_MM = (5.0, 2000.0)


def focal_35mm_equivalent(path: str, limit: int = 64 * 1024 * 1024) -> tuple[float, str] | None:
    """(35 mm-equivalent focal length in mm, where in the file it was found), or None."""
    moov = _read_moov(path, limit)
    return None if moov is None else _focal_in(moov)


def lens_metadata(path: str, limit: int = 64 * 1024 * 1024) -> tuple[tuple[float, str] | None, str | None]:
    """(:func:`focal_35mm_equivalent`, and where it finds none :func:`recording_phone`) from one read of the
    file's ``moov``: a phone's video is large, and its ends are read once."""
    moov = _read_moov(path, limit)
    if moov is None:
        return None, None
    found = _focal_in(moov)
    return found, None if found is not None else _phone_in(moov)


def _focal_in(moov: bytes) -> tuple[float, str] | None:
    try:
        return _search(moov, 0, len(moov))
    except (struct.error, ValueError, IndexError, UnicodeDecodeError):
        return None


def _read_moov(path: str, limit: int) -> bytes | None:
    """The ``moov`` atom's bytes, from the file's first or last ``limit`` bytes."""
    ends = file_ends(path, limit)
    if ends is None:
        return None
    head, tail, _ = ends
    for kind, start, end in boxes(head, 0, len(head)):
        if kind == b"moov":
            return head[start:end]
    # a moov at the end of a long file: find its header in the tail (it may be preceded by part of mdat)
    at = tail.rfind(b"moov")
    while at >= 4:
        found = list(boxes(tail, at - 4, len(tail)))
        if found and found[0][0] == b"moov":
            return tail[found[0][1]:found[0][2]]
        at = tail.rfind(b"moov", 0, at)
    return None


def _search(data: bytes, start: int, end: int) -> tuple[float, str] | None:
    for kind, s0, s1 in boxes(data, start, end):
        found = None
        if kind == b"meta":
            found = _quicktime_meta(data, s0, s1)
        elif kind == b"XMP_":
            found = _xmp(data[s0:s1], "XMP_ atom")
        elif kind == b"uuid" and data[s0:s0 + 16] == XMP_UUID:
            found = _xmp(data[s0 + 16:s1], "XMP uuid atom")
        elif kind in _CONTAINERS:
            found = _search(data, s0, s1)
        if found is None and kind == b"udta":
            found = _exif(data[s0:s1])
        if found is not None:
            return found
    return None


def _quicktime_meta(data: bytes, start: int, end: int) -> tuple[float, str] | None:
    """The focal key's value in a ``meta`` atom."""
    payload = _quicktime_items(data, start, end).get(FOCAL_KEY)
    value = None if payload is None else _data_value(payload)
    return None if value is None else (value, f"QuickTime metadata key '{FOCAL_KEY}'")


def _quicktime_items(data: bytes, start: int, end: int) -> dict[str, bytes]:
    """Key name -> its first ``data`` atom's payload, of a ``meta`` atom's ``keys`` / ``ilst`` (QuickTime's
    ``meta`` has no version word, ISO's has four bytes); {} when it has none."""
    for offset in (0, 4):
        children = dict((k, (a, b)) for k, a, b in boxes(data, start + offset, end))
        if b"keys" in children and b"ilst" in children:
            keys = _keys(data, *children[b"keys"])
            out: dict[str, bytes] = {}
            for kind, s0, s1 in boxes(data, *children[b"ilst"]):
                index = struct.unpack(">I", kind)[0]
                if not 1 <= index <= len(keys) or keys[index - 1] in out:
                    continue
                for sub, d0, d1 in boxes(data, s0, s1):
                    if sub == b"data":
                        out[keys[index - 1]] = data[d0:d1]
                        break
            return out
    return {}


def recording_phone(path: str, limit: int = 64 * 1024 * 1024) -> str | None:
    """The phone an MP4 / MOV file says recorded it (its maker and model, as one name), or None.

    Android's camera writes ``com.android.*`` keys into the movie's QuickTime metadata (the system's
    version, and on recent phones ``com.android.manufacturer`` and ``com.android.model``); an iPhone
    writes ``com.apple.quicktime.make`` "Apple" and ``com.apple.quicktime.model`` "iPhone ...".  A file
    re-encoded by another program has usually lost them (then: None)."""
    moov = _read_moov(path, limit)
    return None if moov is None else _phone_in(moov)


def _phone_in(moov: bytes) -> str | None:
    try:
        items = _all_items(moov, 0, len(moov))
    except (struct.error, ValueError, IndexError):
        return None
    text = {k: _text(v) for k, v in items.items()}
    if any(k.startswith(ANDROID_PREFIX) for k in items):
        name = " ".join(v for v in (text.get(ANDROID_PREFIX + "manufacturer"), text.get(ANDROID_PREFIX + "model")) if v)
        return name or "an Android phone"
    model = text.get("com.apple.quicktime.model") or ""
    if text.get("com.apple.quicktime.make", "").strip().lower() == "apple" and model.lower().startswith("iphone"):
        return f"Apple {model}"
    return None


def _all_items(data: bytes, start: int, end: int) -> dict[str, bytes]:
    """Every QuickTime metadata key of the metadata atoms in ``data[start:end]`` (the first value of a key wins)."""
    out: dict[str, bytes] = {}
    for kind, s0, s1 in boxes(data, start, end):
        found = _quicktime_items(data, s0, s1) if kind == b"meta" else \
            _all_items(data, s0, s1) if kind in _CONTAINERS else {}
        for key, value in found.items():
            out.setdefault(key, value)
    return out


def _text(payload: bytes) -> str | None:
    """A ``data`` atom's UTF-8 text (well-known type 1), stripped; None for any other type."""
    if len(payload) < 8 or int.from_bytes(payload[1:4], "big") != 1:
        return None
    return payload[8:].decode("utf-8", "replace").strip("\0 ").strip() or None


def _keys(data: bytes, start: int, end: int) -> list[str]:
    """The key names of a ``keys`` atom, in order (index 1 first)."""
    count = struct.unpack(">I", data[start + 4:start + 8])[0]
    pos, out = start + 8, []
    for _ in range(min(count, 10_000)):
        if pos + 8 > end:
            break
        size = struct.unpack(">I", data[pos:pos + 4])[0]
        if size < 8 or pos + size > end:
            break
        out.append(data[pos + 8:pos + size].decode("utf-8", "replace"))
        pos += size
    return out


def _data_value(payload: bytes) -> float | None:
    """A ``data`` atom's number: well-known types 1 (UTF-8), 21/22 (big-endian int), 23/24 (float), 65-67 and
    75-77 (fixed-size ints)."""
    if len(payload) < 8:
        return None
    kind = int.from_bytes(payload[1:4], "big")
    value = payload[8:]
    number = None
    if kind == 1:
        match = re.match(r"\s*([0-9]+(?:\.[0-9]*)?)", value.decode("utf-8", "replace"))
        number = float(match.group(1)) if match else None
    elif kind in (21, 22) and 1 <= len(value) <= 8:
        number = float(int.from_bytes(value, "big", signed=kind == 21))
    elif kind in (65, 66, 67, 75, 76, 77) and len(value) in (1, 2, 4):
        number = float(int.from_bytes(value, "big", signed=kind < 70))
    elif kind == 23 and len(value) == 4:
        number = struct.unpack(">f", value)[0]
    elif kind == 24 and len(value) == 8:
        number = struct.unpack(">d", value)[0]
    return number if number is not None and PLAUSIBLE_MM[0] <= number <= PLAUSIBLE_MM[1] else None


def _exif(block: bytes) -> tuple[float, str] | None:
    """FocalLengthIn35mmFilm of the first EXIF (TIFF) block in ``block``."""
    for marker in (b"II*\x00", b"MM\x00*"):
        at = block.find(marker)
        if at < 0:
            continue
        tiff = block[at:]
        order = "<" if marker[:2] == b"II" else ">"
        ifd0 = _ifd(tiff, order, struct.unpack(order + "I", tiff[4:8])[0])
        pointer = ifd0.get(EXIF_IFD_POINTER)
        if pointer is None:
            continue
        value = _ifd(tiff, order, pointer).get(EXIF_TAG_FOCAL_35MM)
        if value is not None and PLAUSIBLE_MM[0] <= value <= PLAUSIBLE_MM[1]:
            return float(value), "EXIF FocalLengthIn35mmFilm in the file's user data"
    return None


def _ifd(tiff: bytes, order: str, offset: int) -> dict[int, int]:
    """Tag -> value of one TIFF directory's SHORT and LONG entries (the ones held in the entry itself)."""
    count = struct.unpack(order + "H", tiff[offset:offset + 2])[0]
    out = {}
    for k in range(min(count, 1000)):
        entry = tiff[offset + 2 + 12 * k:offset + 14 + 12 * k]
        if len(entry) < 12:
            break
        tag, kind, n = struct.unpack(order + "HHI", entry[:8])
        if kind == 3 and n >= 1:
            out[tag] = struct.unpack(order + "H", entry[8:10])[0]
        elif kind == 4 and n == 1:
            out[tag] = struct.unpack(order + "I", entry[8:12])[0]
    return out


def _xmp(text: bytes, where: str) -> tuple[float, str] | None:
    found = re.search(rb"exif:FocalLengthIn35mmFilm\s*(?:=\s*[\"']|>)\s*([0-9]+(?:\.[0-9]*)?)", text)
    if found is None:
        return None
    value = float(found.group(1))
    return (value, f"XMP exif:FocalLengthIn35mmFilm ({where})") if PLAUSIBLE_MM[0] <= value <= PLAUSIBLE_MM[1] \
        else None
