"""Joints only one view sees: placed on that view's ray, at their bone's length from their parent.

Triangulation needs two views; a joint one view sees (the other views' line of sight blocked) still
lies on that view's viewing ray, and at its bone's length from its parent joint, so it is one of the
ray's two points at that distance (Taylor's two depth choices, :func:`core.joint_solve.taylor.child_candidates`).
Which one is the depth guess; the learnt pose prior (:mod:`core.motion_prior`) picks the likelier pose.
Joints no view sees are left to the time fill (:func:`core.joint_solve.taylor.fill_missing`).
"""

from __future__ import annotations

import numpy as np

from ..joint_solve.taylor import child_candidates, fill_missing
from ..skeleton import PARENTS, SEGMENTS, class_lengths_from_segments, segment_lengths, segment_lengths_from_classes
from .cameras import ViewCamera

#: Place one-view joints on their ray (False: leave them to the time fill).
USE_ONE_VIEW = True


def _world_rays(camera: ViewCamera, pixels: np.ndarray) -> np.ndarray:
    """Unit viewing directions (..., 3) in world axes of pixels (..., 2)."""
    d = np.concatenate([(pixels - camera.centre) / camera.focal_px, np.ones(pixels.shape[:-1] + (1,))], axis=-1)
    d = d @ camera.rotation                                          # R^T d for row vectors
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def fill_one_view(points: np.ndarray, pixels: np.ndarray, used: np.ndarray, cameras: list[ViewCamera],
                  prior=None) -> tuple[np.ndarray, int]:
    """(points (F, J, 3) with the joints one view saw placed, how many were placed).

    ``points`` and ``used`` (V, F, J) from :func:`.triangulate.triangulate` (NaN where fewer than two views),
    ``pixels`` (V, F, J, 2), ``prior`` a :class:`core.motion_prior.PosePrior` (None: the candidate nearer
    the time fill)."""
    seen = np.asarray(used, dtype=bool) & np.isfinite(pixels).all(axis=-1)   # (V, F, J)
    lengths = np.nanmedian(class_lengths_from_segments(segment_lengths(points)), axis=0)
    if not np.all(np.isfinite(lengths)):
        return points, 0
    bone = segment_lengths_from_classes(lengths)
    out = np.array(points, dtype=float, copy=True)
    guess = fill_missing(points)                                             # the time fill, for the rest of the pose
    placed = 0
    for s, (p, j) in enumerate(SEGMENTS):                                    # parents first
        one = ~np.isfinite(out[:, j]).all(axis=-1) & (seen[:, :, j].sum(axis=0) == 1) & np.isfinite(out[:, p]).all(-1)
        frames = np.flatnonzero(one)
        if frames.size == 0:
            continue
        view = np.argmax(seen[:, frames, j], axis=0)
        cands = np.empty((2, frames.size, 3))
        for k in np.unique(view):
            sel = view == k
            f = frames[sel]
            cam = cameras[k]
            ray = _world_rays(cam, pixels[k, f, j])
            near, far, _ = child_candidates(out[f, p] - cam.position, ray, bone[s])
            cands[0, sel], cands[1, sel] = near + cam.position, far + cam.position
        pose = np.where(np.isfinite(out[frames]), out[frames], guess[frames])
        trial = np.repeat(pose[None], 2, axis=0)
        trial[:, :, j] = cands
        for c in (c for c in range(len(PARENTS)) if PARENTS[c] == j):          # its children keep their place
            trial[:, :, c] = np.where(np.isfinite(out[frames, c]), out[frames, c], guess[frames, c] - guess[frames, j]
                                      + cands)
        if prior is not None:
            score = prior.log_likelihood(trial)                               # (2, n)
        else:
            score = np.full((2, frames.size), np.nan)
        near_fill = -np.linalg.norm(cands - guess[frames, j][None], axis=-1)
        score = np.where(np.isfinite(score).all(axis=0), score, near_fill)
        out[frames, j] = cands[np.argmax(score, axis=0), np.arange(frames.size)]
        placed += int(frames.size)
    return out, placed
