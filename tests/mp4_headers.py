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


# ----------------------------------------------------------------------------- a lens in the file's metadata

def box(kind: bytes, payload: bytes) -> bytes:
    """One MP4 atom: 32-bit size, type, payload."""
    return struct.pack(">I4s", 8 + len(payload), kind) + payload


FOCAL_KEY = "com.apple.quicktime.camera.focal_length.35mm_equivalent"


def quicktime_focal_meta(value, kind: str = "int", *, iso: bool = False, extra_keys: int = 1) -> bytes:
    """A QuickTime ``meta`` atom (``hdlr``, ``keys``, ``ilst``) holding the 35 mm-equivalent focal length as
    iPhones write it, after ``extra_keys`` other keys; ``kind``: "int" (well-known type 21, 2 bytes),
    "uint8" (75), "float" (23), "double" (24) or "text" (1, e.g. "26.00mm").  ``iso``: with the version
    word an ISO ``meta`` has."""
    names = [f"com.apple.quicktime.other{k}" for k in range(extra_keys)] + [FOCAL_KEY]
    keys = struct.pack(">II", 0, len(names)) + b"".join(box(b"mdta", n.encode()) for n in names)
    type_code, fmt = {"int": (21, ">h"), "uint8": (75, ">B"), "float": (23, ">f"), "double": (24, ">d"),
                      "text": (1, None)}[kind]
    if fmt is None:
        data = f"{float(value):.2f}mm".encode()
    else:
        data = struct.pack(fmt, float(value) if fmt in (">f", ">d") else int(value))
    values = [(1, b"x")] * extra_keys + [(type_code, data)]
    items = b"".join(box(struct.pack(">I", k + 1), box(b"data", struct.pack(">II", code, 0) + payload))
                     for k, (code, payload) in enumerate(values))
    hdlr = box(b"hdlr", bytes(8) + b"mdta" + bytes(13))
    return box(b"meta", (bytes(4) if iso else b"") + hdlr + box(b"keys", keys) + box(b"ilst", items))


def quicktime_text_meta(items: dict[str, str]) -> bytes:
    """A QuickTime ``meta`` atom whose ``keys`` / ``ilst`` hold ``items`` as UTF-8 text (well-known type 1), as
    Android's recorder writes ``com.android.version``, ``com.android.manufacturer`` and ``com.android.model``."""
    names = list(items)
    keys = struct.pack(">II", 0, len(names)) + b"".join(box(b"mdta", n.encode()) for n in names)
    values = b"".join(box(struct.pack(">I", k + 1), box(b"data", struct.pack(">II", 1, 0) + items[n].encode()))
                      for k, n in enumerate(names))
    hdlr = box(b"hdlr", bytes(8) + b"mdta" + bytes(13))
    return box(b"meta", hdlr + box(b"keys", keys) + box(b"ilst", values))


def exif_udta(value: int, byte_order: str = "II") -> bytes:
    """A ``udta`` atom holding a vendor atom with an EXIF block whose EXIF directory has
    FocalLengthIn35mmFilm (0xA405, SHORT) = ``value``."""
    o = "<" if byte_order == "II" else ">"
    head = (b"II*\x00" if byte_order == "II" else b"MM\x00*") + struct.pack(o + "I", 8)
    ifd0 = struct.pack(o + "H", 1) + struct.pack(o + "HHII", 0x8769, 4, 1, 8 + 18) + struct.pack(o + "I", 0)
    exif = struct.pack(o + "H", 2) + struct.pack(o + "HHIHH", 0x920A, 3, 1, 4, 0) \
        + struct.pack(o + "HHIHH", 0xA405, 3, 1, int(value), 0) + struct.pack(o + "I", 0)
    return box(b"udta", box(b"VEND", b"Exif\x00\x00" + head + ifd0 + exif))


def xmp_udta(value: float) -> bytes:
    """A ``udta`` atom with an ``XMP_`` packet stating exif:FocalLengthIn35mmFilm."""
    text = ('<x:xmpmeta xmlns:x="adobe:ns:meta/"><rdf:RDF><rdf:Description '
            f'exif:FocalLengthIn35mmFilm="{value:g}"/></rdf:RDF></x:xmpmeta>')
    return box(b"udta", box(b"XMP_", text.encode()))


def add_to_moov(path, atom: bytes, *, into_track: bool = False) -> None:
    """Put ``atom`` at the end of the file's ``moov`` (or of its first ``trak``) in place, growing the sizes
    of the atoms around it.  The ``moov`` must follow the pictures (``mdat``), as encoders write it by
    default, so that no sample offset moves."""
    path = Path(path)
    data = bytearray(path.read_bytes())
    pos, moov, mdat = 0, None, None
    while pos + 8 <= len(data):
        size, kind = struct.unpack(">I4s", data[pos:pos + 8])
        if size == 1:
            size = struct.unpack(">Q", data[pos + 8:pos + 16])[0]
        size = size or len(data) - pos
        if kind == b"moov":
            moov = (pos, size)
        elif kind == b"mdat":
            mdat = pos
        pos += size
    assert moov is not None and mdat is not None and mdat < moov[0], "moov must follow mdat"
    parents = [moov[0]]
    end = moov[0] + moov[1]
    if into_track:
        at = data.find(b"trak", moov[0]) - 4
        assert at > moov[0]
        parents.append(at)
        end = at + struct.unpack(">I", data[at:at + 4])[0]
    data[end:end] = atom
    for p in parents:
        data[p:p + 4] = struct.pack(">I", struct.unpack(">I", data[p:p + 4])[0] + len(atom))
    path.write_bytes(bytes(data))


def fake_movie(path, *metadata: bytes, moov_last: bool = True, mdat_bytes: int = 5000) -> str:
    """A file of MP4 atoms with no pictures: ``ftyp``, ``mdat`` of zeros and a ``moov`` holding ``metadata``."""
    moov = box(b"moov", box(b"mvhd", bytes(100)) + box(b"trak", box(b"tkhd", bytes(84))) + b"".join(metadata))
    parts = [box(b"ftyp", b"isom\0\0\2\0isomiso2mp41"), box(b"mdat", bytes(mdat_bytes))]
    parts = parts + [moov] if moov_last else [parts[0], moov, parts[1]]
    Path(path).write_bytes(b"".join(parts))
    return str(path)
