"""Where background features may be seeded, which are kept, and what the run found.

Everything here is in the joint tracks' pixels and frames (frame 0 = the tracks' first frame) and in
seconds and picture-relative sizes, so a clip at 24 or 240 fps, 720 or 3840 px wide, gets the same plan.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..timebase.frames import nearest_marked
from ..tracks import StaticTracks, Tracks


@dataclass(frozen=True)
class BackgroundSettings:
    #: Background points wanted in view at once (the scene camera was measured with 8-16).
    want: int = 16
    #: Seconds between looks for new features: a handheld pan takes points out of the picture.
    every_s: float = 0.5
    #: The person's box (its joints' extent) is widened by this share of the figure's image height on
    #: every side; nothing is seeded in it, and a point that enters it is cut (the person passes over it,
    #: and the tracker may follow the person from there).
    person_margin: float = 0.15
    #: No seed nearer the picture's edge than this share of its width (it leaves at the first turn).
    edge_share: float = 0.02
    #: Seeds at least this share of the picture's width apart (spread points pin the rotation best).
    separation_share: float = 0.05
    #: Tracks shorter than this (seconds) are dropped: too brief to tie frames together.
    min_track_s: float = 0.3
    #: A feature whose step between two frames misses the step of the others (an affine motion fitted to
    #: all, the worst left out in turn) by more than this share of the picture's width is cut from there:
    #: the tracker jumped to a look-alike, or the point is on something that moves.
    jump_share: float = 0.004

    def __post_init__(self) -> None:
        if self.want < 1:
            raise InputError(f"background points wanted must be at least 1, got {self.want}")
        for name in ("every_s", "min_track_s"):
            if not getattr(self, name) > 0:
                raise InputError(f"{name} must be positive, got {getattr(self, name)!r}")
        for name in ("person_margin", "edge_share", "separation_share", "jump_share"):
            if not 0 <= getattr(self, name) < 0.5:
                raise InputError(f"{name} must be in [0, 0.5), got {getattr(self, name)!r}")


DEFAULT_BACKGROUND = BackgroundSettings()


@dataclass
class BackgroundReport:
    """What a background run found: features kept, cut where the person passed, dropped as too short."""

    kept: int = 0
    cut: int = 0
    jumped: int = 0
    dropped: int = 0
    live_median: float = 0.0
    frames_under_four: int = 0
    n_frames: int = 0
    #: Why the features are not used for the camera (:func:`.verdict.judge_background`); '' when they are.
    fallback: str = ""

    def summary(self) -> str:
        text = (f"{self.kept} background tracks, {self.live_median:.0f} in view on the median frame"
                f" ({self.cut} cut where the person passed, {self.jumped} where they left the scene's motion, "
                f"{self.dropped} too short dropped)")
        if self.frames_under_four:
            text += (f"; {self.frames_under_four} of {self.n_frames} frames see fewer than 4, where the camera "
                     "comes from the person")
        return text


def person_boxes(tracks: Tracks, margin: float = DEFAULT_BACKGROUND.person_margin) -> np.ndarray:
    """(F, 4) box ``x0, y0, x1, y1`` around the joints seen in each frame, widened by ``margin`` times the
    figure's median image height. A frame without joints takes the box of the nearest frame with some."""
    xy = np.asarray(tracks.xy, dtype=float)
    seen = np.isfinite(xy).all(axis=-1)
    frames = np.flatnonzero(seen.any(axis=1))
    if frames.size == 0:
        raise InputError("the tracks see no joint in any frame: there is no person to keep the background "
                         "features off")
    n = xy.shape[0]
    sub = xy[frames]
    box = np.stack([np.nanmin(sub[..., 0], axis=1), np.nanmin(sub[..., 1], axis=1),
                    np.nanmax(sub[..., 0], axis=1), np.nanmax(sub[..., 1], axis=1)], axis=1)
    height = float(np.median(box[:, 3] - box[:, 1]))
    pad = margin * max(height, 1.0)
    box = box[nearest_marked(frames, np.arange(n))]   # each frame its own box, or the nearest frame's
    return box + np.array([-pad, -pad, pad, pad])


def inside_boxes(xy: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """(F, K) whether each point ``xy`` (F, K, 2) lies in its frame's box (F, 4); False where NaN."""
    x, y = xy[..., 0], xy[..., 1]
    b = boxes[:, None, :]
    with np.errstate(invalid="ignore"):
        return (x >= b[..., 0]) & (x <= b[..., 2]) & (y >= b[..., 1]) & (y <= b[..., 3])


def detection_frames(n_frames: int, fps: float, every_s: float = DEFAULT_BACKGROUND.every_s) -> list[int]:
    """Frames at which to look for new features: every ``every_s`` seconds, never the last frame (nothing
    is left to follow them through)."""
    step = max(1, int(round(every_s * fps)))
    return list(range(0, max(n_frames - 1, 0), step))


def pick_seeds(candidates: np.ndarray, box: np.ndarray, live: np.ndarray, image_size, want: int,
               min_separation_px: float, edge_px: float) -> list[int]:
    """Indices of the ``candidates`` (m, 2) to follow, so that with the ``live`` points (l, 2) about ``want``
    are in view: outside the person's ``box`` (4,), off the picture's edge, each at least
    ``min_separation_px`` from the others, greedily the farthest from every point already held and from
    the person's box centre (a spread of points pins the rotation; the person's surroundings are the
    likeliest to be covered next)."""
    cand = np.asarray(candidates, dtype=float).reshape(-1, 2)
    anchors = [p for p in np.asarray(live, dtype=float).reshape(-1, 2) if np.isfinite(p).all()]
    need = want - len(anchors)
    if need <= 0 or cand.shape[0] == 0:
        return []
    width, height = (float(v) for v in image_size)
    x, y = cand[:, 0], cand[:, 1]
    on_person = inside_boxes(cand[None], np.asarray(box, dtype=float)[None])[0]
    with np.errstate(invalid="ignore"):
        ok = (np.isfinite(cand).all(axis=1) & ~on_person
              & (x >= edge_px) & (x <= width - edge_px) & (y >= edge_px) & (y <= height - edge_px))
    held = np.array(anchors + [[(box[0] + box[2]) / 2, (box[1] + box[3]) / 2]], dtype=float)
    score = np.min(np.linalg.norm(cand[:, None] - held[None], axis=-1), axis=1)
    # the box centre only steers the choice; the separation is kept from the held points and the seeds
    sep = np.full(cand.shape[0], np.inf)
    if anchors:
        sep = np.min(np.linalg.norm(cand[:, None] - np.array(anchors)[None], axis=-1), axis=1)
    chosen: list[int] = []
    while len(chosen) < need:
        allowed = ok & (sep >= min_separation_px)
        if not allowed.any():
            break
        k = int(np.argmax(np.where(allowed, score, -np.inf)))
        chosen.append(k)
        ok[k] = False
        d = np.linalg.norm(cand - cand[k], axis=1)
        score = np.minimum(score, d)
        sep = np.minimum(sep, d)
    return chosen


#: Most pairs of features tried per frame as the scene's motion (a spread sample beyond that).
MAX_PAIRS = 400


def off_the_scene_motion(xy: np.ndarray, limit_px: float) -> np.ndarray:
    """(F, K) True where a feature's step from the frame before leaves the others' motion.

    A turning, zooming camera moves the whole picture between two frames by nearly a similarity (shift,
    scale, a little roll). Each pair of features seen in both frames proposes one; the one most features
    follow to within the limit wins, and an affine map fitted to those features by least squares (a
    wide lens' keystone) judges every feature. The limit is ``limit_px`` plus a tenth of the median step,
    for what neither map models of a fast pan's perspective. The ones that miss are marked when they are
    a minority; with fewer than four features in both frames nothing is judged.
    """
    xy = np.asarray(xy, dtype=float)
    n, k = xy.shape[:2]
    off = np.zeros((n, k), dtype=bool)
    seen = np.isfinite(xy).all(axis=-1)
    rng = np.random.default_rng(0)
    for i in range(1, n):
        both = np.flatnonzero(seen[i - 1] & seen[i])
        m = both.size
        if m < 4:
            continue
        z0 = xy[i - 1, both] @ np.array([1.0, 1j])
        z1 = xy[i, both] @ np.array([1.0, 1j])
        limit = limit_px + 0.1 * float(np.median(np.abs(z1 - z0)))
        p, q = np.triu_indices(m, 1)
        if p.size > MAX_PAIRS:
            pick = rng.choice(p.size, MAX_PAIRS, replace=False)
            p, q = p[pick], q[pick]
        dz = z0[p] - z0[q]
        ok = np.abs(dz) > 1e-6
        a = np.where(ok, (z1[p] - z1[q]) / np.where(ok, dz, 1.0), 1.0)
        b = z1[p] - a * z0[p]
        miss = np.abs(a[:, None] * z0[None] + b[:, None] - z1[None])          # (pairs, m)
        votes = np.where(ok, (miss <= limit).sum(axis=1), -1)
        best = np.flatnonzero(votes == votes.max())
        h = best[np.argmin(np.minimum(miss[best], limit).sum(axis=1))]
        inl = miss[h] <= limit
        if inl.sum() >= 3:
            design = np.stack([z0.real, z0.imag, np.ones(m)], axis=1)
            coef, *_ = np.linalg.lstsq(design[inl], np.stack([z1.real, z1.imag], axis=1)[inl], rcond=None)
            inl = np.linalg.norm(design @ coef - np.stack([z1.real, z1.imag], axis=1), axis=1) <= limit
        if 2 * inl.sum() > m:
            off[i, both[~inl]] = True
    return off


def clean_background(xy: np.ndarray, boxes: np.ndarray, fps: float, settings: BackgroundSettings = DEFAULT_BACKGROUND,
                     image_width: float | None = None) -> tuple[np.ndarray, np.ndarray, BackgroundReport]:
    """(cleaned xy (F, K, 2), kept (K,) bool, report) of followed features ``xy`` (NaN where not followed).

    A feature is cut from the first frame it lies in the person's box on: the person covers it there,
    and a tracker that lost it may have moved onto the person. With ``image_width``, it is also cut from
    the first frame its step leaves the others' (:func:`off_the_scene_motion`). Features followed for
    fewer than ``min_track_s`` seconds (and 3 frames) are dropped.
    """
    xy = np.array(xy, dtype=float)
    n, k = xy.shape[:2]
    inside = inside_boxes(xy, boxes)
    cut = 0
    for j in np.flatnonzero(inside.any(axis=0)):
        first = int(np.argmax(inside[:, j]))
        xy[first:, j] = np.nan
        cut += 1
    jumped = 0
    off = off_the_scene_motion(xy, settings.jump_share * image_width) if image_width else np.zeros((n, k), bool)
    for j in np.flatnonzero(off.any(axis=0)):
        xy[int(np.argmax(off[:, j])):, j] = np.nan
        jumped += 1
    seen = np.isfinite(xy).all(axis=-1)
    shortest = max(3, int(math.ceil(settings.min_track_s * fps)))
    kept = seen.sum(axis=0) >= shortest
    live = seen[:, kept].sum(axis=1) if n else np.zeros(0)
    report = BackgroundReport(kept=int(kept.sum()), cut=cut, jumped=jumped, dropped=int(k - kept.sum()),
                              live_median=float(np.median(live)) if n else 0.0,
                              frames_under_four=int(np.sum(live < 4)), n_frames=n)
    xy[:, ~kept] = np.nan
    return xy, kept, report


def static_tracks(xy: np.ndarray, names) -> StaticTracks | None:
    """The kept features as :class:`core.tracks.StaticTracks` (confidence 1 where followed); None if none."""
    xy = np.asarray(xy, dtype=float)
    if xy.shape[1] == 0:
        return None
    conf = np.isfinite(xy).all(axis=-1).astype(float)
    return StaticTracks(list(names), xy, conf)
