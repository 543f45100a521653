""":func:`check_estimate`: the self-checks and their flags (see the package docstring)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..camera import mm_per_pixel, pixels_to_film
from ..nanstats import nanmean, nanmedian, second_difference_sigma
from ..result import Estimate
from ..skeleton import CLASSES, JOINTS, MIRROR, N_JOINTS, SEGMENTS, proportions, segment_lengths
from ..synthetic.procedural import adult_class_lengths
from ..track_cleaning.people import longest_one_person_stretch, person_switches
from ..tracks import Tracks
from .reprojection import camera_points, reprojection_residuals


@dataclass(frozen=True)
class SelfCheckSettings:
    #: Input: share of joint points rejected, and of frames with a left/right exchange, worth a flag.
    rejected_share: float = 0.03
    swapped_share: float = 0.15
    #: Fit: the median residual may be this many times the tracks' own noise (and at least ``fit_floor_px``).
    fit_ratio: float = 3.0
    fit_floor_px: float = 3.0
    #: Fit: a frame fits poorly when its median residual is over this many times the clip's median
    #: (and over ``fit_floor_px``); a flag when more than ``poor_share`` of the frames do.
    poor_frame_ratio: float = 4.0
    poor_share: float = 0.05
    #: Camera: with the focal length assumed, a turn beyond this (degrees) is scaled by the unknown lens.
    assumed_focal_turn_deg: float = 6.0
    #: Bones: the tracks need a segment this much longer than found in more than ``bone_share`` of frames.
    bone_excess: float = 1.2
    bone_share: float = 0.25
    #: Camera: below this share of frames in still spells, the camera track is integrated from the
    #: planted feet over most of the clip (a handheld camera) and drifts.
    still_share: float = 0.5
    #: Camera from the background with an undetermined focal length: flagged when the turn times the focal
    #: length's relative uncertainty exceeds this many degrees.
    scene_focal_angle_deg: float = 1.0
    #: Input: below this share of joint points present, the estimate rests on too little.
    present_share: float = 0.8
    #: Input: a joint whose median confidence over the clip is below this was mostly a detector's guess
    #: (BlazePose reports 0.05-0.3 for joints out of the picture or hidden; detectors' seen joints 0.6-1).
    unsure_confidence: float = 0.3
    #: Input: a joint missing (or rejected) in more than this share of the frames, its left/right twin too,
    #: leaves its bone class to the rest (BlazePose lost a small walker's wrists in 37-55 % of the frames on
    #: real footage; one side hidden in a side view is normal, and the other side measures the class).
    #: Only frames where fewer than two of the joint's skeleton neighbours are present count: between two
    #: present neighbours a missing joint is held by its bone lengths (a thorax under its neck and shoulders).
    sparse_joint: float = 0.3
    #: Proportions: a class whose share is outside these multiples of an adult's is implausible.
    proportion_ratio: tuple[float, float] = (0.25, 3.0)
    #: Pose: a frame is marked when the learnt pose prior (:mod:`core.motion_prior`) finds one of its limb
    #: bones (clearly out of the picture's plane) likelier by more than this many nats with its depth sign
    #: flipped: a limb most likely mirrored in depth.  Chosen on the tune half's true motions seen from random
    #: sides (``python bench/prior_uses_bench.py ../shared/data/bvh/*.bvh --part selfcheck --draws 4``): at 5
    #: nats 2.1 % of their frames are marked and 36.6 % of those frames with one limb bone mirrored (10 nats:
    #: 0.0 % and 18.4 %; 15 nats: 0.0 % and 8.8 %); the report half 1.2 % and 26.8 %.
    #: A flag when more than ``implausible_share`` of the frames are marked.
    mirrored_gain: float = 5.0
    implausible_share: float = 0.2


DEFAULT_SELF_CHECK = SelfCheckSettings()


def _noise_px(tracks: Tracks) -> float:
    """2D noise of the tracks: robust spread of second differences of every joint (px)."""
    if tracks.n_frames < 3:
        return 0.0
    d2 = tracks.xy[2:] - 2 * tracks.xy[1:-1] + tracks.xy[:-2]
    v = d2[np.isfinite(d2)]
    # motion adds little to second differences at video rates
    return second_difference_sigma(v) if v.size else 0.0


def check_estimate(est: Estimate, tracks: Tracks, cleaning: dict | None = None,
                   settings: SelfCheckSettings = DEFAULT_SELF_CHECK, raw: Tracks | None = None) -> dict:
    """Run the checks; returns ``{"flags": [{"code", "message"}], "metrics": {...}, "worst_frames": [...]}``
    and fills ``est.frames[i].reprojection_px`` from the tracks where the estimate has 3D joints.
    ``tracks`` are the ones solved (cleaned); ``raw``, the input before cleaning (default: the same)."""
    flags: list[dict] = []
    metrics: dict = {}

    def flag(code: str, message: str) -> None:
        flags.append({"code": code, "message": message})

    if cleaning:
        metrics["rejected_share"] = cleaning["rejected_share"]
        metrics["swapped_share"] = cleaning["swapped_share"]
        if cleaning["rejected_share"] > settings.rejected_share:
            flag("input_outliers", f"input: {100 * cleaning['rejected_share']:.1f} % of the joint points were "
                 "rejected as detector outliers or far off the image; check the tracks")
        if cleaning["swapped_share"] > settings.swapped_share:
            flag("input_swaps", f"input: left and right were exchanged in {100 * cleaning['swapped_share']:.0f} % "
                 "of the frames and undone; check the limbs' sides in the result")

    noise = _noise_px(tracks)
    metrics["noise_px"] = noise
    worst: list[int] = []
    if all(f.joints_3d is not None for f in est.frames) and len(est.frames) == tracks.n_frames:
        cam, focal = camera_points(est)
        res = reprojection_residuals(tracks, cam, focal)
        per_frame = nanmedian(res, axis=1)
        per_joint = nanmedian(res, axis=0)
        for i, v in enumerate(nanmean(res, axis=1)):
            est.frames[i].reprojection_px = float(v) if np.isfinite(v) else None
        fin = per_frame[np.isfinite(per_frame)]
        if fin.size:
            med = float(np.median(fin))
            metrics["residual_median_px"] = med
            metrics["residual_per_joint_px"] = {JOINTS[j]: float(v) for j, v in enumerate(per_joint)
                                                if np.isfinite(v)}
            limit = max(settings.fit_floor_px, settings.fit_ratio * noise)
            if med > limit:
                flag("fit", f"fit: the solved figure misses the tracks by {med:.1f} px (median; the tracks' "
                     f"noise is {noise:.1f} px): the 3D motion and camera do not explain the footage")
            poor = per_frame > max(settings.fit_floor_px, settings.poor_frame_ratio * med)
            share = float(np.mean(poor[np.isfinite(per_frame)]))
            metrics["poor_frame_share"] = share
            order = np.argsort(-np.where(np.isfinite(per_frame), per_frame, -1.0))
            worst = [int(i) for i in order[:10] if np.isfinite(per_frame[i])]
            if share > settings.poor_share:
                flag("fit_frames", f"fit: {100 * share:.0f} % of the frames fit poorly (worst frame {worst[0]}, "
                     f"{per_frame[worst[0]]:.1f} px)")
        bone = _bone_consistency(est, tracks, settings, noise, cam, focal)
        if bone is not None:
            metrics["bone_excess_share"] = bone[1]
            if bone[1] > settings.bone_share:
                flag("bones", f"bones: the tracks need the {bone[0]} longer than found in {100 * bone[1]:.0f} % "
                     "of the frames: the proportions or the depth of that limb are doubtful")

    rv = np.array([f.rotvec_deg for f in est.frames], dtype=float)
    turn = float(np.max(np.linalg.norm(rv, axis=1))) if len(rv) else 0.0
    metrics["camera_turn_deg"] = turn
    determined = bool(est.diagnostics.get("focal_determined"))
    scene = est.diagnostics.get("scene_camera") or {}
    if scene.get("used"):
        # the focal length comes from the background (and the lens prior where the background says little):
        # its uncertainty scales the camera's angles
        sigma = float(scene["log_focal_sigma_with_prior"])
        spread = float(scene.get("turn_deg", 0.0)) * (math.exp(sigma) - 1.0)
        metrics["focal_angle_uncertainty_deg"] = spread
        if not determined and spread > settings.scene_focal_angle_deg:
            flag("camera_focal", f"lens: the background tracks leave the focal length uncertain "
                 f"({scene.get('focal_reason')}), so the camera's angles may be off by {spread:.1f} degrees: "
                 "give the focal length if known")
    elif not determined and turn > settings.assumed_focal_turn_deg:
        flag("camera_focal", f"lens: the camera turned up to {turn:.0f} degrees while the focal length was assumed "
             f"({est.focal_mm:.0f} mm), and its angles scale with the real lens: give the focal length if known")
    for w in est.diagnostics.get("warnings", []):
        # the methods' own specific doubts: a camera track with no still spell to anchor it, a floor
        # that does not fit the planted feet
        for prefix, code in (("camera:", "camera_track"), ("floor:", "floor")):
            if w.startswith(prefix) and code not in {f["code"] for f in flags}:
                flags.append({"code": code, "message": w, "from_method": True})
    spells = est.diagnostics.get("spells") or []
    if spells:
        still = sum(int(sp["end"]) - int(sp["start"]) + 1 for sp in spells if sp.get("kind") == "still")
        share = still / max(len(est.frames), 1)
        metrics["still_share"] = share
        if share < settings.still_share and "camera_track" not in {f["code"] for f in flags}:
            flag("camera_moving", f"camera: it stood still in only {100 * share:.0f} % of the clip, so its track "
                 "is chained from the planted feet over most of it and may drift - check it against the footage")
    switches = person_switches((raw if raw is not None else tracks).xy)
    metrics["person_switches"] = switches.tolist()
    if switches.size:
        a, b = longest_one_person_stretch(switches, np.ones(tracks.n_frames, dtype=bool))
        listed = ", ".join(str(int(f)) for f in switches[:5]) + (" ..." if switches.size > 5 else "")
        flag("input_people", f"input: the tracks jump to another person at frame {listed}: one estimate is one "
             f"body, so these proportions mix people; estimate the tracks' frames {a}-{b - 1} (the longest stretch "
             f"of one person) on their own (--frames {a}-{b - 1}; in Blender, Trim Tracks to Scene Range), or "
             "correct the tracks")
    present = float(tracks.present.mean()) if tracks.n_frames else 0.0
    metrics["present_share"] = present
    if present < settings.present_share:
        flag("input_missing", f"input: {100 * (1 - present):.0f} % of the joint points are missing (out of "
             "the picture, occluded or rejected): the estimate rests on the rest")
    unsure = _unsure_joints(tracks, settings.unsure_confidence)
    metrics["unsure_joints"] = {name: round(value, 3) for name, value in unsure}
    if unsure:
        listed = ", ".join(f"{name} {value:.2f}" for name, value in unsure)
        flag("input_unsure", f"input: the detector was unsure of {listed} (median confidence over the clip): "
             "those joints were mostly out of the picture or hidden, so the bones they end are its guesses")
    if tracks.n_frames:
        gone = _loose_share(tracks.present)
        both = np.minimum(gone, gone[list(MIRROR)])
        sparse = [(JOINTS[j], float(gone[j])) for j in np.argsort(-gone) if both[j] > settings.sparse_joint]
        metrics["sparse_joints"] = {name: round(share, 3) for name, share in sparse}
        if sparse:
            listed = ", ".join(f"{name} {100 * share:.0f} %" for name, share in sparse)
            flag("input_sparse", f"input: some joints are missing in much of the clip ({listed} of the frames): the "
                 "bones they end are measured on the rest, and their 3D there is the solve's guess")
    frames: list[int] = []
    if all(f.joints_3d is not None for f in est.frames) and est.frames:
        frames, worst_frame = _mirrored_limb_frames(camera_points(est)[0], settings)
        share = len(frames) / len(est.frames)
        metrics["mirrored_limb_share"] = share
        if share > settings.implausible_share:
            flag("pose", f"pose: in {100 * share:.0f} % of the frames a limb is likelier mirrored in depth than as "
                 f"solved (by the pose prior; clearest at frame {worst_frame}): check those frames against the footage")
    odd = _implausible_proportions(est, settings)
    if odd:
        flag("proportions", f"proportions: the {odd[0]} is {odd[1]:.1f} times an adult's share of the body: "
             "implausible, most likely a failed solve")
    return {"flags": flags, "metrics": metrics, "worst_frames": worst, "implausible_frames": frames}


def _loose_share(present: np.ndarray) -> np.ndarray:
    """(17,) share of the frames where each joint is missing and fewer than two of its neighbours in the
    skeleton tree (parent, children) are present, so nothing but the solve's guess places it."""
    neighbours = np.zeros((N_JOINTS, N_JOINTS))
    for p, c in SEGMENTS:
        neighbours[p, c] = neighbours[c, p] = 1.0
    held = (present.astype(float) @ neighbours) >= 2.0
    return np.mean(~present & ~held, axis=0)


def _unsure_joints(tracks: Tracks, limit: float) -> list[tuple[str, float]]:
    """(joint, median confidence) of the joints whose median confidence where present is below ``limit``."""
    out = []
    for j, name in enumerate(JOINTS):
        c = tracks.conf[:, j]
        c = c[c > 0]
        median = float(np.median(c)) if c.size else limit
        if median < limit:
            out.append((name, median))
    return out


def adult_share_ratios(est: Estimate) -> tuple[np.ndarray, np.ndarray]:
    """(the built-in average adult's share of each bone class (10,), the estimate's share over it (10,))."""
    adult = proportions(adult_class_lengths())
    return adult, est.proportions_vector() / adult


def _implausible_proportions(est: Estimate, settings: SelfCheckSettings):
    """(class, ratio) of the class furthest outside the plausible multiples of an adult's share, or None."""
    lo, hi = settings.proportion_ratio
    worst = None
    for c, r in zip(CLASSES, adult_share_ratios(est)[1]):
        r = float(r)
        off = max(r / hi, lo / max(r, 1e-9))
        if off > 1.0 and (worst is None or off > worst[2]):
            worst = (c.replace("_", " "), r, off)
    return None if worst is None else worst[:2]


def _bone_consistency(est: Estimate, tracks: Tracks, settings: SelfCheckSettings, noise_px: float,
                      cam: np.ndarray, focal: np.ndarray):
    """(segment name, share of frames) where the image length of a segment needs it longer than found."""
    length = np.median(segment_lengths(cam), axis=0)          # a rotation keeps every length
    film = pixels_to_film(tracks.xy, tracks.image_size)
    # two standard deviations of the noise on a segment's two ends do not make a bone longer
    slack = 2.0 * np.sqrt(2.0) * noise_px * mm_per_pixel(tracks.image_size)
    worst_name, worst_share = None, 0.0
    for s, (p, c) in enumerate(SEGMENTS):
        z = 0.5 * (cam[:, p, 2] + cam[:, c, 2])
        d2 = np.maximum(np.linalg.norm(film[:, c] - film[:, p], axis=-1) - slack, 0.0)
        with np.errstate(all="ignore"):
            need = d2 * z / focal                     # the shortest 3D bone that projects this long at depth z
            ratio = need / length[s]
        ok = np.isfinite(ratio)
        if ok.sum() < 10:
            continue
        share = float(np.mean(ratio[ok] > settings.bone_excess))
        if share > worst_share:
            worst_name, worst_share = f"{JOINTS[p]}-{JOINTS[c]} segment", share
    return None if worst_name is None else (worst_name, worst_share)


def _mirrored_limb_frames(cam: np.ndarray, settings: SelfCheckSettings) -> tuple[list[int], int]:
    """(frames where a limb bone clearly out of the picture's plane is likelier, by the pose prior, with its
    depth sign flipped by more than ``mirrored_gain`` nats, the frame where it is clearest) for each frame's
    joints in its camera's axes ``cam`` (F, 17, 3)."""
    from ..motion_prior import load_default
    from ..motion_prior.evaluation import LIMB_BONES
    from ..motion_prior.features import bone_vectors

    limbs = list(LIMB_BONES)
    gains = load_default().flip_gains(cam)[:, limbs]
    bones = bone_vectors(cam)[:, limbs]
    with np.errstate(all="ignore"):
        clear = np.abs(bones[..., 2]) / np.linalg.norm(bones, axis=-1) > 0.5
    best = np.max(np.where(clear & np.isfinite(gains), gains, -np.inf), axis=1)
    return [int(i) for i in np.flatnonzero(best > settings.mirrored_gain)], int(np.argmax(best))
