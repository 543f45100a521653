"""A tiny PNG scatter plot (numpy + zlib only): the paper's Figure 8.

Blender's bundled Python has no matplotlib, and the plot is simple: frame id on
the horizontal axis, the virtual scale parameter on the vertical, actual values
as red dots and estimated ones as blue dots.  This module rasterises that into
an RGB array and encodes it as a PNG by hand.
"""

from __future__ import annotations

import os
import struct
import zlib

import numpy as np

from .file_io import write_atomic

RED = (220, 30, 30)
BLUE = (30, 60, 220)
BLACK = (0, 0, 0)
GREY = (200, 200, 200)


def encode_png(rgb: np.ndarray, level: int = 9) -> bytes:
    """PNG bytes of an (H, W, 3) uint8 image (``level``: zlib's, 1 fast, 9 small)."""
    img = np.ascontiguousarray(rgb, dtype=np.uint8)
    h, w, _ = img.shape
    raw = b"".join(b"\x00" + img[y].tobytes() for y in range(h))   # filter type 0 per row

    def chunk(tag: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)
    body = chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw, level)) + chunk(b"IEND", b"")
    return b"\x89PNG\r\n\x1a\n" + body


#: A 3x5 pixel font, just the characters the plot writes (tick values, axis names, legend): Blender's
#: Python has no font renderer we may rely on, and a plot without numbers cannot be read.
_GLYPHS = {
    "0": "111101101101111", "1": "010110010010111", "2": "111001111100111", "3": "111001111001111",
    "4": "101101111001001", "5": "111100111001111", "6": "111100111101111", "7": "111001001001001",
    "8": "111101111101111", "9": "111101111001111", ".": "000000000000010", "-": "000000111000000",
    " ": "000000000000000", "A": "010101111101101", "C": "011100100100011", "D": "110101101101110",
    "E": "111100110100111", "F": "111100110100100", "I": "111010010010111", "L": "100100100100111",
    "M": "101111111101101", "R": "110101110101101", "S": "011100010001110", "T": "111010010010010",
    "U": "101101101101111", "V": "101101101101010",
}
TEXT_SCALE = 2


def text_width(text: str, scale: int = TEXT_SCALE) -> int:
    return max(0, 4 * scale * len(text) - scale)


def draw_text(img: np.ndarray, x: int, y: int, text: str, colour=BLACK, scale: int = TEXT_SCALE) -> None:
    """Write ``text`` (upper case, digits, ``.-``) with its top-left corner at (x, y); clipped at the edges."""
    h, w, _ = img.shape
    for k, char in enumerate(text.upper()):
        bits = _GLYPHS.get(char, _GLYPHS[" "])
        for idx, bit in enumerate(bits):
            if bit == "1":
                r, c = divmod(idx, 3)
                top, left = y + r * scale, x + (4 * k + c) * scale
                img[max(top, 0):max(min(top + scale, h), 0), max(left, 0):max(min(left + scale, w), 0)] = colour


def _dots(img: np.ndarray, xs: np.ndarray, ys: np.ndarray, colour, radius: int = 1) -> None:
    h, w, _ = img.shape
    for dx in range(-radius, radius + 1):
        for dy in range(-radius, radius + 1):
            x = np.clip(xs + dx, 0, w - 1)
            y = np.clip(ys + dy, 0, h - 1)
            img[y, x] = colour


def scatter_image(series: list[tuple[np.ndarray, tuple[int, int, int]]], width: int = 900, height: int = 400,
                  margin: int = 50, labels: tuple[str, ...] = (), x_title: str = "", y_title: str = "") -> np.ndarray:
    """RGB image of y-series against their index (frame id), each in its colour, with labelled axes.

    ``labels`` name the series in a legend (top right), in the order given.
    """
    img = np.full((height, width, 3), 255, dtype=np.uint8)
    vals = np.concatenate([np.asarray(s, dtype=float) for s, _ in series])
    vals = vals[np.isfinite(vals)]
    lo, hi = (float(vals.min()), float(vals.max())) if vals.size else (0.0, 1.0)
    if hi - lo < 1e-9:
        lo, hi = lo - 0.5, hi + 0.5
    pad = 0.05 * (hi - lo)
    lo, hi = lo - pad, hi + pad
    n = max(len(s) for s, _ in series)
    x0, x1, y0, y1 = margin, width - margin // 2, height - margin, margin // 2

    def px(i):
        return np.round(x0 + (x1 - x0) * np.asarray(i, dtype=float) / max(1, n - 1)).astype(int)

    def py(v):
        return np.round(y0 - (y0 - y1) * (np.asarray(v, dtype=float) - lo) / (hi - lo)).astype(int)

    # Grid lines and labelled ticks, then the axes.
    digits = max(0, int(np.ceil(-np.log10((hi - lo) / 5))))
    for t in np.linspace(lo, hi, 6)[1:-1]:
        img[py(t), x0:x1] = GREY
        img[py(t), x0 - 5:x0] = BLACK
        label = f"{t:.{digits}f}"
        draw_text(img, x0 - 8 - text_width(label), int(py(t)) - 5, label)
    for t in np.linspace(0, n - 1, 6):
        img[y0:y0 + 5, px(t)] = BLACK
        label = str(int(round(t)))
        draw_text(img, int(px(t)) - text_width(label) // 2, y0 + 9, label)
    if x_title:
        draw_text(img, (x0 + x1 - text_width(x_title)) // 2, height - 14, x_title)
    if y_title:
        draw_text(img, 4, 4, y_title)
    right = x1
    for (_, colour), name in reversed(list(zip(series, labels))):
        left = right - text_width(name)
        draw_text(img, left, 4, name)
        img[5:13, left - 14:left - 6] = colour
        right = left - 30
    img[y1:y0 + 1, x0] = BLACK
    img[y0, x0:x1 + 1] = BLACK
    for s, colour in series:
        s = np.asarray(s, dtype=float)
        ok = np.isfinite(s)
        _dots(img, px(np.flatnonzero(ok)), py(s[ok]), colour)
    return img


def write_scale_plot(path: str | os.PathLike, actual: np.ndarray, estimated: np.ndarray) -> None:
    """Figure 8: actual (red) and estimated (blue) virtual scale per frame, as a PNG file."""
    img = scatter_image([(np.asarray(actual), RED), (np.asarray(estimated), BLUE)], labels=("actual", "estimated"),
                        x_title="frame", y_title="virtual scale")
    write_atomic(path, encode_png(img), what="plot")
