"""Taylor's one-parameter family of poses for one image (Taylor 2000, section 2).

Under scaled orthography (``u = s X``, ``v = s Y``) a segment of length ``l`` whose image is ``d``
pixels long has relative depth ``dZ = +-sqrt(l^2 - d^2 / s^2)``: a pose for every scale ``s`` at
or above ``s_min = max d / l`` (equation 3), two depth choices per segment.  With a focal length
the same family is built under perspective: the root sits at depth ``f / s`` on its viewing ray and
each child on its ray at distance ``l`` from its parent (``core.joint_solve.taylor``), exact for a
real camera.  Positions are metres in camera axes (x right, y down, z forward); ``sign`` +1 puts the
child farther from the camera than its parent, -1 nearer; under perspective "farther" is along the
child's own line of sight (``(X_c - X_p) . X_c > 0``), which :func:`depth_sign` computes for a known pose.
"""

from __future__ import annotations

import numpy as np

from ..joint_solve.taylor import child_candidates
from ..skeleton import N_JOINTS, SEGMENTS


def depth_sign(parent: np.ndarray, child: np.ndarray) -> int:
    """+1 when ``child`` lies beyond ``parent`` along the child's line of sight (camera at the origin), else -1."""
    return 1 if float(np.dot(child - parent, child)) >= 0 else -1


def scale_min(uv: np.ndarray, seg_len: np.ndarray) -> float:
    """Taylor's lower bound on the scale (pixels per metre): no segment longer in the image than ``s l``.
    Segments with a missing end are skipped."""
    d = np.array([np.linalg.norm(uv[c] - uv[p]) for p, c in SEGMENTS])
    ok = np.isfinite(d) & (seg_len > 0)
    return float(np.max(d[ok] / seg_len[ok])) if ok.any() else float("nan")


#: The trunk's chain, pelvis to neck: an upright person seen by a roughly level camera holds it nearly
#: parallel to the image, so its image length over its true length is the scale (Taylor's own experiment
#: took the scale from the actor's height in the image the same way).
TRUNK = ("spine", "thorax", "neck")


def scale_trunk(uv: np.ndarray, seg_len: np.ndarray) -> float:
    """Scale (pixels per metre) from the trunk's image length, pelvis to neck; NaN when a trunk joint is missing."""
    from ..skeleton import JOINT_INDEX

    neck, pelvis = JOINT_INDEX["neck"], JOINT_INDEX["pelvis"]
    if not (np.isfinite(uv[neck]).all() and np.isfinite(uv[pelvis]).all()):
        return float("nan")
    length = sum(seg_len[JOINT_INDEX[j] - 1] for j in TRUNK)      # segment index = child joint index - 1
    return float(np.linalg.norm(uv[neck] - uv[pelvis]) / length)


def orthographic_pose(uv: np.ndarray, seg_len: np.ndarray, s: float, signs: np.ndarray,
                      focal_px: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(joints (17, 3) metres, shortfall (16,) metres) of the scaled-orthographic pose at scale ``s``.

    ``uv`` (17, 2) pixels from the principal point; the root is placed at depth ``focal_px / s``
    (``focal_px`` None: depth 0, relative depths only).  A segment too short for its image at this
    scale lies in the image plane and its shortfall is reported; missing joints (and their
    subtrees) are NaN.
    """
    out = np.full((N_JOINTS, 3), np.nan)
    short = np.zeros(len(SEGMENTS))
    z0 = 0.0 if focal_px is None else float(focal_px) / s
    if np.isfinite(uv[0]).all():
        out[0] = (uv[0, 0] / s, uv[0, 1] / s, z0)
    for k, (p, c) in enumerate(SEGMENTS):
        if not (np.isfinite(out[p]).all() and np.isfinite(uv[c]).all()):
            continue
        d2 = float(np.sum((uv[c] - uv[p]) ** 2)) / s ** 2
        dz2 = seg_len[k] ** 2 - d2
        short[k] = np.sqrt(max(-dz2, 0.0))
        out[c] = (uv[c, 0] / s, uv[c, 1] / s, out[p, 2] + signs[k] * np.sqrt(max(dz2, 0.0)))
    return out, short


def perspective_pose(uv: np.ndarray, seg_len: np.ndarray, s: float, signs: np.ndarray,
                     focal_px: float) -> tuple[np.ndarray, np.ndarray]:
    """The same under perspective with focal length ``focal_px``: the root at depth ``focal_px / s``."""
    rays = np.concatenate([uv, np.full((N_JOINTS, 1), float(focal_px))], axis=1)
    rays = rays / np.linalg.norm(rays, axis=1, keepdims=True)
    out = np.full((N_JOINTS, 3), np.nan)
    short = np.zeros(len(SEGMENTS))
    if np.isfinite(rays[0]).all():
        out[0] = rays[0] * (float(focal_px) / s / rays[0, 2])
    for k, (p, c) in enumerate(SEGMENTS):
        if not (np.isfinite(out[p]).all() and np.isfinite(rays[c]).all()):
            continue
        near, far, miss = child_candidates(out[p], rays[c], seg_len[k])
        out[c] = far if signs[k] > 0 else near
        short[k] = float(miss)
    return out, short
