"""Single-image posing in the scene: one frame's joints -> an armature posed at that frame and a camera
through which the pose lands on the joints (the core is :mod:`core.single_image`).

The objects are their own ("MonoSkel Pose" and its camera), keyed at the posed scene frame only, so
a video build on the scene is left alone and the scene's frame range does not change.  Posing again
replaces them in one transaction; :func:`repose` re-keys the armature after a sign flip or a new
scale.  What the pose was made from (the frame's joints, the lengths, the focal length) is kept on
the scene (:mod:`.scene_data`, key ``single_image``) so a re-pose needs nothing else.
"""

from __future__ import annotations

import numpy as np

from ..core.camera import DEFAULT_FOCAL_MM
from ..core.errors import InputError
from ..core.result import Estimate, FrameEstimate
from ..core.single_image import SEGMENT_NAMES, pose_from_image
from ..core.skeleton import class_lengths_for_height, proportions_dict
from ..core.synthetic.procedural import adult_class_lengths
from . import build as _build
from . import build_armature as _arm
from . import build_camera as _cam
from . import scene_data

NAME = "MonoSkel Pose"


def frame_inputs(scene, settings) -> dict:
    """What to pose: the scene's tracks at the current frame, the lengths (the estimate's proportions or the
    adult figure, at the subject height) and the focal length (the user's, the estimate's frame, or 50 mm)."""
    tracks = scene_data.load_tracks(scene)
    if tracks is None:
        raise InputError("no tracks on the scene: import tracks or take them from a movie clip first")
    i = int(scene.frame_current) - int(settings.tracks_first_frame)
    if not 0 <= i < tracks.n_frames:
        raise InputError(f"scene frame {scene.frame_current} has no tracks (they cover frames "
                         f"{settings.tracks_first_frame}-{settings.tracks_first_frame + tracks.n_frames - 1})")
    est = scene_data.load_estimate(scene)
    height = float(settings.height_m)
    lengths = adult_class_lengths(height) if est is None else class_lengths_for_height(est.proportions_vector(), height)
    if not settings.estimate_focal:
        focal = float(settings.focal_mm)
    elif est is not None and len(est.frames) == tracks.n_frames:
        focal = float(est.frames[i].focal_mm)
    else:
        focal = DEFAULT_FOCAL_MM
    return {"xy": tracks.xy[i].tolist(), "image_size": list(tracks.image_size), "lengths": lengths.tolist(),
            "focal_mm": focal, "frame": int(scene.frame_current), "height_m": height}


def _pose(doc: dict, *, signs=None, scale=None):
    xy = np.array([[np.nan, np.nan] if p is None else p for p in doc["xy"]], dtype=float)
    return pose_from_image(xy, tuple(doc["image_size"]), np.asarray(doc["lengths"], dtype=float),
                           focal_mm=float(doc["focal_mm"]), signs=signs, scale=scale)


def _estimate(doc: dict, pose) -> Estimate:
    """The pose as a one-frame estimate in its camera's axes (so the video builders place it)."""
    frame = FrameEstimate(stance=None, camera_moving=False, rotvec_deg=(0.0, 0.0, 0.0), focal_mm=pose.focal_mm,
                          scale=1.0, joints_3d=filled_joints(pose).tolist())
    return Estimate(method="single-image", proportions=proportions_dict(np.asarray(doc["lengths"])),
                    focal_mm=pose.focal_mm, frames=[frame], height_m=float(doc["height_m"]), diagnostics={})


def filled_joints(pose) -> np.ndarray:
    """The pose's joints with the unseen ones hanging straight down from their parents (a rig needs
    every bone somewhere; :func:`missing_joints` names them)."""
    from ..core.skeleton import SEGMENTS, segment_lengths_from_classes

    out = np.array(pose.joints, dtype=float)
    seg = segment_lengths_from_classes(pose.class_lengths)
    for k, (p, c) in enumerate(SEGMENTS):
        if not np.isfinite(out[c]).all():
            out[c] = out[p] + np.array([0.0, seg[k], 0.0])       # camera y is down
    return out


def missing_joints(pose) -> list[str]:
    from ..core.skeleton import JOINTS

    return [JOINTS[j] for j in range(len(JOINTS)) if not np.isfinite(pose.joints[j]).all()]


def _world(doc: dict, pose, est: Estimate | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(world_from_camera 4x4, world joints (17, 3)): the placement the first pose chose (kept in ``doc``, so a
    re-pose moves the figure, never the camera), else :mod:`.build`'s default for this pose (``est``: the
    pose as an estimate, when the caller has made it already)."""
    if doc.get("world_from_camera") is not None:
        m = np.asarray(doc["world_from_camera"], dtype=float)
    else:
        m = _build.world_from_cam0(est if est is not None else _estimate(doc, pose), float(doc["height_m"]))
    return m, filled_joints(pose) @ m[:3, :3].T + m[:3, 3]


def pose_scene(scene, settings) -> tuple:
    """Pose the current frame (automatic signs, the default scale) and build its armature and camera.
    Returns (pose, armature, camera).  The previous pose's objects are replaced only once the new ones
    are built, so a failure leaves them as they were."""
    doc = frame_inputs(scene, settings)
    pose = _pose(doc)
    est = _estimate(doc, pose)
    m, joints = _world(doc, pose, est)

    def run(created):
        arm = _arm.create_armature(scene, np.asarray(doc["lengths"]), NAME, created)
        _arm.key_pose(arm, joints[None], np.array([doc["frame"]]), created)
        cam = _cam.create_camera(scene, est, tuple(doc["image_size"]), _build._rotation_only(m), m[:3, 3],
                                 f"{NAME} Camera", doc["frame"], created)
        arm["monoskel_single_image"] = True
        return arm, cam

    arm, cam = _build._transaction(scene, run)
    _build.replace_built(settings.si_armature, arm)
    _build.replace_built(settings.si_camera, cam)
    doc["world_from_camera"] = m.tolist()
    scene_data.store_single_image(scene, doc)
    settings.si_armature, settings.si_camera = arm, cam
    _store(settings, doc, pose)
    return pose, arm, cam


def _store(settings, doc: dict, pose) -> None:
    """Show the pose in the sidebar."""
    settings.si_has_pose = True
    settings.si_frame = int(doc["frame"])
    settings.si_scale_min = float(pose.scale_min)
    settings.si_scale = float(pose.scale)
    settings.si_signs = [bool(v > 0) for v in pose.signs]
    settings.si_ambiguous = ", ".join(SEGMENT_NAMES[k] for k in pose.ambiguous)


def repose(scene, settings):
    """Re-key the pose armature from the sidebar's signs and scale (every sign held); None when there is
    nothing to re-pose."""
    if not settings.si_has_pose or settings.si_armature is None:
        return None
    doc = scene_data.load_single_image(scene)
    if doc is None:
        return None
    signs = {k: (1 if v else -1) for k, v in enumerate(settings.si_signs)}
    # the slider stays in the valid range: below the smallest scale a segment cannot reach its image
    pose = _pose(doc, signs=signs, scale=max(float(settings.si_scale), float(settings.si_scale_min)))
    _, joints = _world(doc, pose)
    _arm.key_pose(settings.si_armature, joints[None], np.array([int(doc["frame"])]), [])
    scene.frame_set(scene.frame_current)
    _store(settings, doc, pose)
    return pose
