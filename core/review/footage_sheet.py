"""The review page's pictures: frames of the footage with the tracks and the solved skeleton drawn on them.

Plots say a frame fits poorly; a picture says why (a joint on the wrong leg, a skeleton that leans off
the person, the camera drifting off the scene). The frames shown are the worst by residual, the first
frame of every problem the estimate marks, the frames its warnings name, and an even spread over the
clip. Each is drawn at thumbnail size with numpy alone: the footage (decoded by Blender,
``blender/review/footage_frames.py``), a dot per tracked joint, the skeleton where the solved joints
land through the solved camera, and a line from each track to its joint coloured by the distance as
the viewport's residual lines are (:func:`.residuals.residual_colours`). PNG thumbnails are embedded
in the page, so it stays one file.
"""

from __future__ import annotations

import base64
import re
from dataclasses import dataclass
from html import escape

import numpy as np

from ..io.png_plot import encode_png
from ..result import Estimate
from ..skeleton import SEGMENTS
from .problems import poor_fit_limit_px, problem_starts, reprojection_series
from .residuals import DEFAULT_LIMIT_PX, reprojected_pixels, residual_colours, residual_lines

#: Thumbnails this many pixels wide (a 16:9 frame is 320 x 180: 30-120 kB as PNG).
THUMB_WIDTH = 320
#: At most this many pictures (the page stays within a few MB).
MAX_PICTURES = 12
TRACK_COLOUR = (40, 220, 255)
SKELETON_COLOUR = (255, 150, 30)
BACKGROUND_COLOUR = (120, 255, 120)


@dataclass(frozen=True)
class Picture:
    """One frame of the sheet: estimate frame ``index``, why it is shown, the PNG."""

    index: int
    reasons: tuple[str, ...]
    png: bytes


#: A warning naming many frames (a list of person switches) shows this many of them.
NAMED_PER_WARNING = 3
_NAMED = re.compile(r"\bframes? (\d+(?![\d.-])(?:, \d+(?![\d.-]))*)")


def named_frames(text: str) -> list[int]:
    """The estimate frames a warning names ("worst frame 12", "another person at frame 40, 95"); a range
    ("frames 0-120", a stretch to estimate) names none."""
    return [int(v) for m in _NAMED.finditer(text) for v in m.group(1).split(", ")]


def _warning_texts(est: Estimate) -> list[str]:
    diag = est.diagnostics or {}
    flags = [f.get("message", "") for f in (diag.get("self_check") or {}).get("flags", [])]
    return [str(w) for w in diag.get("warnings", [])] + [f for f in flags if f]


def pick_frames(est: Estimate, *, even: int = 4, worst: int = 3, limit: int = MAX_PICTURES) -> list[tuple[int, str]]:
    """(estimate frame, reason) to show, in frame order: the ``worst`` frames by mean residual, the first
    frame of each problem the estimate marks, the frames its warnings name, and ``even`` frames spread over
    the clip; at most ``limit``
    frames (the worst and the named ones first). A frame picked for several reasons carries them all."""
    n = len(est.frames)
    if n == 0:
        return []
    chosen: dict[int, list[str]] = {}

    def add(i: int, why: str) -> None:
        if i not in chosen and len(chosen) >= limit:
            return
        chosen.setdefault(int(i), []).append(why)

    rep = reprojection_series(est)
    finite = np.flatnonzero(np.isfinite(rep))
    for i in finite[np.argsort(-rep[finite], kind="stable")][:worst]:
        add(int(i), f"worst fit {rep[i]:.1f} px")
    for name, i in problem_starts(est):
        add(int(i), name)
    for text in _warning_texts(est):
        for i in named_frames(text)[:NAMED_PER_WARNING]:
            if 0 <= i < n:
                add(i, text.split(":")[0] + " warning")
    for i in np.unique(np.round(np.linspace(0, n - 1, min(even, n))).astype(int)):
        add(int(i), "spread")
    return [(i, "; ".join(chosen[i])) for i in sorted(chosen)]


def thumbnail(rgb: np.ndarray, width: int = THUMB_WIDTH) -> tuple[np.ndarray, float]:
    """(a ``width``-pixel-wide copy of ``rgb`` (H, W, 3) uint8, the scale from frame to thumbnail pixels);
    each thumbnail pixel is the mean of the frame pixels it covers."""
    h, w = rgb.shape[:2]
    scale = min(1.0, width / float(w))
    tw, th = max(1, int(round(w * scale))), max(1, int(round(h * scale)))
    rows = np.minimum((np.arange(th + 1) * h / th).astype(int), h)
    cols = np.minimum((np.arange(tw + 1) * w / tw).astype(int), w)
    sums = np.add.reduceat(np.add.reduceat(rgb.astype(np.float64), rows[:-1], axis=0), cols[:-1], axis=1)
    counts = np.diff(rows)[:, None, None] * np.diff(cols)[None, :, None]
    return np.clip(np.round(sums / counts), 0, 255).astype(np.uint8), tw / float(w)


def draw_line(img: np.ndarray, a, b, colour, thick: int = 1) -> None:
    """A straight line from ``a`` to ``b`` (x, y pixels) into ``img``, clipped at its edges."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if not (np.isfinite(a).all() and np.isfinite(b).all()):
        return
    steps = int(np.ceil(np.abs(b - a).max())) + 1
    t = np.linspace(0.0, 1.0, max(steps, 2))[:, None]
    pts = np.round(a + t * (b - a)).astype(int)
    h, w = img.shape[:2]
    for dx in range(thick):
        for dy in range(thick):
            x, y = pts[:, 0] + dx, pts[:, 1] + dy
            ok = (x >= 0) & (x < w) & (y >= 0) & (y < h)
            img[y[ok], x[ok]] = colour


def draw_dot(img: np.ndarray, p, colour, radius: int = 1) -> None:
    p = np.asarray(p, dtype=float)
    if not np.isfinite(p).all():
        return
    x0, y0 = int(round(p[0])), int(round(p[1]))
    h, w = img.shape[:2]
    img[max(y0 - radius, 0):max(min(y0 + radius + 1, h), 0), max(x0 - radius, 0):max(min(x0 + radius + 1, w), 0)] = \
        colour


def draw_frame(rgb: np.ndarray, track_xy: np.ndarray, present: np.ndarray, reprojected: np.ndarray, *,
               limit_px: float = DEFAULT_LIMIT_PX, static_xy: np.ndarray | None = None,
               width: int = THUMB_WIDTH) -> np.ndarray:
    """One annotated thumbnail: ``rgb`` (H, W, 3) the frame, ``track_xy`` / ``present`` (17, 2) / (17,) its
    joint tracks, ``reprojected`` (17, 2) the solved joints through the solved camera (NaN: not solved),
    ``static_xy`` (S, 2) the background features followed in it, all in the frame's pixels."""
    img, scale = thumbnail(rgb, width)
    img = (0.75 * img).astype(np.uint8)          # dimmed a little, so the drawing reads on a bright frame
    track, reproj, residual, drawn = residual_lines(track_xy[None], present[None], reprojected[None])
    track, reproj, residual, drawn = track[0] * scale, reproj[0] * scale, residual[0], drawn[0]
    if static_xy is not None:
        for p in np.asarray(static_xy, dtype=float).reshape(-1, 2) * scale:
            draw_dot(img, p, BACKGROUND_COLOUR, radius=1)
    for a, b in SEGMENTS:
        draw_line(img, reproj[a], reproj[b], SKELETON_COLOUR, thick=2)
    colours = np.round(255 * residual_colours(residual, limit_px)[:, :3]).astype(np.uint8)
    for j in np.flatnonzero(drawn):
        draw_line(img, track[j], reproj[j], colours[j])
    seen = np.asarray(present, dtype=bool) & np.isfinite(track).all(axis=-1)
    for j in np.flatnonzero(seen):
        draw_dot(img, track[j], TRACK_COLOUR, radius=1)
    return img


def footage_pictures(est: Estimate, tracks, frames_rgb: dict, picks: list[tuple[int, str]]) -> list[Picture]:
    """The :class:`Picture` of each pick whose frame ``frames_rgb`` (estimate frame -> (H, W, 3) uint8)
    holds; ``tracks`` are the estimate's joint tracks (their background features drawn too)."""
    reproj = reprojected_pixels(est, tracks.image_size)
    limit = poor_fit_limit_px(est) or DEFAULT_LIMIT_PX
    out = []
    for i, why in picks:
        rgb = frames_rgb.get(i)
        if rgb is None:
            continue
        static = None if tracks.static is None else tracks.static.xy[i][tracks.static.present[i]]
        img = draw_frame(rgb, tracks.xy[i], tracks.present[i], reproj[i], limit_px=limit, static_xy=static)
        out.append(Picture(i, tuple(why.split("; ")), encode_png(img, level=6)))
    return out


def pictures_html(pictures: list[Picture], first_frame: int = 0) -> str:
    """The page's *Footage* section: the pictures as inline PNGs with the frame and why it is shown."""
    if not pictures:
        return ""
    parts = ["<h2>Footage</h2><p style='font-size:small'>Dots: the joint tracks; orange: the solved skeleton "
             "through the solved camera; lines from each track to its joint coloured by the distance (green "
             "close, yellow at the poor-fit limit, red twice it); green dots: the background features.</p><div>"]
    for pic in pictures:
        data = base64.b64encode(pic.png).decode("ascii")
        caption = f"frame {pic.index + first_frame}: {', '.join(pic.reasons)}"
        parts.append("<figure style='display:inline-block;margin:4px;font-size:small'>"
                     f"<img alt='{escape(caption)}' src='data:image/png;base64,{data}'>"
                     f"<figcaption>{escape(caption)}</figcaption></figure>")
    parts.append("</div>")
    return "".join(parts)
