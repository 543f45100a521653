"""Per-frame measures of a 3D pose against the truth: the error after alignment and mirrored limbs.

A *mirrored limb* is a limb bone (upper arm, forearm, thigh, shank) pointing more than
:data:`MIRROR_DEG` away from the true bone once the frame is aligned to the truth by a similarity
(rotation, translation, scale; no reflection): the signature of a depth sign guessed wrong, which the
mean joint error hides among the rest.
"""

from __future__ import annotations

import numpy as np

from ..evaluation.metrics import similarity_align
from ..skeleton import LIMBS, SEGMENTS

MIRROR_DEG = 45.0
#: Segment indices of the 8 limb bones (the clavicles and hips excluded).
LIMB_BONES = tuple(k for k, (_, c) in enumerate(SEGMENTS) if any(c in js[1:] for js in LIMBS.values()))


def frame_errors(estimated: np.ndarray, truth: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(P-MPJPE per frame (F,) metres, mirrored limb per frame (F,) bool) for poses (F, 17, 3)."""
    est = np.asarray(estimated, dtype=float)
    act = np.asarray(truth, dtype=float)
    err = np.full(est.shape[0], np.nan)
    mirrored = np.zeros(est.shape[0], dtype=bool)
    limit = np.cos(np.radians(MIRROR_DEG))
    for f in range(est.shape[0]):
        al = similarity_align(est[f], act[f])
        err[f] = np.nanmean(np.linalg.norm(al - act[f], axis=-1))
        for k in LIMB_BONES:
            p, c = SEGMENTS[k]
            a, b = al[c] - al[p], act[f, c] - act[f, p]
            if np.isfinite(a).all():
                mirrored[f] |= bool(a @ b < limit * np.linalg.norm(a) * np.linalg.norm(b))
    return err, mirrored


def with_bones_mirrored(est, bones):
    """A copy of the estimate ``est`` (:class:`core.result.Estimate`) with the given bones (segment indices)
    mirrored in depth on every frame: each bone vector's depth negated in the frame's camera axes, with
    every joint below it carried along (Taylor's other choice for those bones), the pelvis kept.

    It is a depth sign guessed wrong on purpose: what the self-check must mark, made on a real estimate."""
    import copy

    from ..camera import rotation_matrix
    from .features import bone_vectors, joints_from_bones

    out = copy.deepcopy(est)
    bones = list(bones)
    for f in out.frames:
        R = rotation_matrix(np.array(f.rotvec_deg))
        cam = np.array(f.joints_3d) @ R.T
        b = bone_vectors(cam)
        b[bones, 2] *= -1.0
        f.joints_3d = (joints_from_bones(b, cam[0]) @ R).tolist()
    return out
