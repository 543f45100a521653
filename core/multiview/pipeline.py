"""``estimate_multiview``: proportions and 3D motion from two or more synchronized views.

1. the views' tracks are cleaned like a single view's (:mod:`core.track_cleaning`: far-off points,
   left/right exchanges, gross outliers) and put on the first view's clock (:mod:`.sync`: the frame
   offsets found from the joints and the scene points both views track under one name, or given; an
   offset another one a movement's cycle away fits about as well is said in a warning);
2. cameras: given (a calibration file or Blender cameras), or calibrated from the person
   (:mod:`.calibrate`);
3. every joint of every frame triangulated (:mod:`.triangulate`; a view that disagrees with the
   others is dropped for that point);
4. constant bone lengths by construction: the ten class lengths are the clip's medians of the
   triangulated bones (left and right together), and each frame is rebuilt from the pelvis outward
   along its triangulated bone directions with those lengths; a joint one view saw is placed on that
   view's ray at its bone's length from its parent, the depth picked by the pose prior (:mod:`.one_view`);
   joints no view saw are filled in time from their neighbours;
5. the result is a ``skeleton-estimate`` seen through view 1 (so every front end builds it as it
   builds a single view's), with the floor from the planted feet and, in ``diagnostics``, every
   camera (``cameras``) and each view's reprojection error (``view_reprojection_px``).
"""

from __future__ import annotations

import numpy as np

from ..errors import Cancelled, InputError
from ..joint_solve.taylor import fill_missing
from ..nanstats import nanmean, nanmedian
from ..result import Estimate, FrameEstimate
from ..skeleton import (
    PARENTS,
    SEGMENTS,
    class_lengths_from_segments,
    proportions_dict,
    segment_lengths,
    segment_lengths_from_classes,
)
from ..track_cleaning import clean_tracks
from ..track_cleaning.residual import found_detector_errors
from ..tracks import Tracks
from .calibrate import calibrate_from_person
from .cameras import ViewCamera
from .one_view import USE_ONE_VIEW, fill_one_view
from .sync import aligned_pixels, ambiguity_warning, frame_offset
from .triangulate import reprojection_errors, triangulate


def rigid_skeleton(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(joints (F, 17, 3), class lengths (10,)): every frame rebuilt from the pelvis with the clip's
    median class lengths along its own bone directions."""
    lengths = np.nanmedian(class_lengths_from_segments(segment_lengths(points)), axis=0)
    length_to = dict(zip((c for _, c in SEGMENTS), segment_lengths_from_classes(lengths)))   # by child joint
    out = np.empty_like(points)
    out[:, 0] = points[:, 0]
    for j in range(1, points.shape[1]):                   # parents precede children
        p = PARENTS[j]
        d = points[:, j] - points[:, p]
        d /= np.maximum(np.linalg.norm(d, axis=-1, keepdims=True), 1e-9)
        out[:, j] = out[:, p] + length_to[j] * d
    return out, lengths


#: Views one estimate takes at most.
MAX_VIEWS = 8
#: A self-calibrated lens whose standard deviation (from the bundle adjustment) exceeds this share, in
#: percent, is said in a warning. Chosen on the tune half and the built-in walk (2-4 views, 1 px): every
#: lens 1-4.4 % off had 0.72-1.99, every lens within 0.6 % at most 0.42 (docs/multiview.md).
LENS_DOUBT_PCT = 0.6


def check_same_rate(views: list[Tracks]) -> None:
    """Raise :class:`InputError` unless all ``views`` have one frame rate (to a thousandth)."""
    fps = {round(t.fps, 3) for t in views}
    if len(fps) > 1:
        raise InputError(f"the views have different frame rates ({', '.join(f'{v:g}' for v in sorted(fps))} fps): "
                         "synchronized views share one frame rate; resample them to one rate first")


def estimate_multiview(views: list[Tracks], *, cameras: list[ViewCamera] | None = None, height_m: float = 1.75,
                       focal_px: list[float | None] | None = None, offsets: list[int] | None = None,
                       progress=None, should_cancel=None) -> Estimate:
    """Estimate from ``views`` (2-8 tracks of the same person at one frame rate), on the first view's frames.

    ``cameras``: known cameras in view order (then ``height_m`` only names the metric scale of the
    report, the cameras' own units rule); None: calibrated from the person, scaled to ``height_m``.
    ``offsets``: per view, the frame of that view that shows the first view's frame 0 (the first's is
    0); None: found from the joints (:mod:`.sync`, up to 2 s either way). ``should_cancel()`` returning
    True between stages raises :class:`core.errors.Cancelled`."""
    if not 2 <= len(views) <= MAX_VIEWS:
        raise InputError(f"multi-view estimation takes 2 to {MAX_VIEWS} views, got {len(views)}")
    if cameras is not None and len(cameras) != len(views):
        raise InputError(f"{len(cameras)} cameras for {len(views)} views")
    if not (height_m > 0):
        raise InputError(f"height must be positive, got {height_m!r} m")

    def tick(fraction, message):
        if should_cancel is not None and should_cancel():
            raise Cancelled("multi-view estimate cancelled")
        if progress is not None:
            progress(fraction, message)

    check_same_rate(views)
    if offsets is not None and (len(offsets) != len(views) or offsets[0] != 0):
        raise InputError(f"give one frame offset per view, the first 0 (got {list(offsets)})")
    n = views[0].n_frames
    tick(0.0, "cleaning each view's tracks")
    cleaned, reports = [], []
    for t in views:
        c, rep = clean_tracks(t)
        cleaned.append(c)
        reports.append(rep)
    sync = None
    sync_notes = []
    if offsets is None:
        tick(0.1, "synchronising the views")
        found = [frame_offset(cleaned[0], c) for c in cleaned[1:]]
        offsets = [0] + [d for d, _ in found]
        sync = [r for _, r in found]
        names = [c.source or f"view {k + 1}" for k, c in enumerate(cleaned)]
        sync_notes = [w for k, r in enumerate(sync, start=1)
                      if (w := ambiguity_warning(names[k], names[0], r, cleaned[0].fps)) is not None]
    pixels = np.stack([aligned_pixels(c, int(d), n) for c, d in zip(cleaned, offsets)])     # (V, F, 17, 2)
    calibration = None
    if cameras is None:
        tick(0.2, "cameras from the person")
        cameras, calibration = calibrate_from_person(pixels, [c.image_size for c in cleaned], height_m,
                                                     focal_px=focal_px, names=[c.source or f"view {k + 1}"
                                                                               for k, c in enumerate(cleaned)])
    tick(0.7, "triangulating")
    points, used = triangulate(pixels, cameras)
    seen = np.isfinite(points).all(axis=-1)
    if seen.mean() < 0.5:
        raise InputError(f"only {100 * seen.mean():.0f} % of the joints were seen by two views: the views do not "
                         "overlap enough (or the cameras do not match them)")
    if USE_ONE_VIEW:
        from ..motion_prior import load_default

        points, _ = fill_one_view(points, pixels, used, cameras, load_default())
    joints, lengths = rigid_skeleton(fill_missing(points))
    errors = reprojection_errors(joints, pixels, cameras)
    est = _to_estimate(views, cameras, joints, lengths, seen, errors, used, reports, calibration, height_m,
                       cleaned[0].fps)
    est.diagnostics["warnings"] = sync_notes + est.diagnostics["warnings"]
    est.diagnostics["frame_offsets"] = [int(d) for d in offsets]
    est.diagnostics["sync"] = sync if sync is not None else "given"
    return est


def _lens_doubts(cameras, calibration) -> list[str]:
    """Warnings for the self-calibrated lenses the person pinned only loosely (:data:`LENS_DOUBT_PCT`)."""
    sigma = calibration.get("focal_sigma_pct") if isinstance(calibration, dict) else None
    notes = []
    for cam, s in zip(cameras, sigma or []):
        if s is not None and s > LENS_DOUBT_PCT:
            notes.append(f"views: the lens of {cam.name} is only loosely pinned by the person (about +-{2 * s:.1f} %, "
                         "so are that camera's distance and the 3D scale): the person moves little in depth in "
                         "this take; calibrate on a longer take of the same cameras and reuse its cameras (Save / "
                         "Load View Cameras, or --cameras-out / --calibration)")
    return notes


def _two_detector_views(views, reports, calibration) -> list[str]:
    """A warning when two views were calibrated from a detector's tracks (the cleaning found gross
    errors in either): with no third view to outvote an exchanged limb the lenses came out 2.9-238 %
    off on all 5 tune-half clips (2-207 % on the 9 of the report half), the lens warning above
    catching 3 and 7 of them."""
    if len(views) != 2 or not isinstance(calibration, dict):
        return []
    if not any(found_detector_errors(r, v) for v, r in zip(views, reports)):
        return []
    return ["views: two cameras calibrated from a detector's tracks: with no third view to outvote its "
            "mistakes (a limb exchanged in one view) the lenses and camera places can be several percent "
            "off, at worst far more; give a calibration file (Load View Cameras / --calibration) or add a view"]


def _to_estimate(views, cameras, joints_world, lengths, seen, errors, used, reports, calibration, height_m,
                 fps) -> Estimate:
    from ..joint_solve.ground import world_from_cam0
    from ..joint_solve.stance import NONE, stance_from_3d

    cam0 = cameras[0]
    joints = cam0.to_camera(joints_world)                          # view 1's camera axes
    stance = stance_from_3d(joints, fps, height_m)
    world, notes = world_from_cam0(joints, stance, height_m, camera_known=True)
    per_frame = nanmean(np.where(used, errors, np.nan), axis=(0, 2))          # frames no view saw: NaN
    view_err = [float(nanmedian(np.where(used[k], errors[k], np.nan))) for k in range(len(cameras))]
    # the first view's cleaning decides what is listed per frame (its frames are the estimate's)
    rejected_names = reports[0].per_frame()[0]
    frames = []
    for i in range(joints.shape[0]):
        rejected = sorted(rejected_names[i])
        frames.append(FrameEstimate(
            stance=None if stance[i] == NONE else ("l" if stance[i] == 0 else "r"),
            camera_moving=False, rotvec_deg=(0.0, 0.0, 0.0), focal_mm=cam0.focal_mm(), scale=1.0,
            joints_3d=joints[i].tolist(),
            reprojection_px=None if not np.isfinite(per_frame[i]) else float(per_frame[i]),
            rejected=rejected or None))
    unseen = float(1.0 - seen.mean())
    if unseen > 0.1:
        notes.append(f"views: {100 * unseen:.0f} % of the joints were seen by fewer than two views and are "
                     "filled in from neighbouring frames")
    notes += _lens_doubts(cameras, calibration)
    notes += _two_detector_views(views, reports, calibration)
    finite = [e if np.isfinite(e) else -1.0 for e in view_err]
    worst = int(np.argmax(finite))
    if finite[worst] > 3 * float(np.median(finite)) + 2.0:
        notes.append(f"views: {cameras[worst].name} fits {view_err[worst]:.1f} px where the others fit "
                     f"{np.nanmedian(view_err):.1f}: its camera or its tracks are off")
    diagnostics = {
        "world_from_cam0": world.tolist(), "warnings": notes, "class_lengths_m": [float(v) for v in lengths],
        "cameras": [c.to_dict() for c in cameras], "view_reprojection_px": view_err,
        "views": [v.source for v in views], "seen_by_two_views": float(seen.mean()),
        "calibration": calibration if calibration is not None else "given",
        "image_size": [float(v) for v in views[0].image_size], "fps": float(fps),
    }
    return Estimate(method="multiview", proportions=proportions_dict(lengths), focal_mm=cam0.focal_mm(),
                    frames=frames, height_m=height_m, diagnostics=diagnostics)
