"""``solve_scene_camera``: the camera's rotation and focal length in every frame from static scene tracks.

1. frames with at least :data:`MIN_POINTS_PER_FRAME` points are usable; the longest stretch of
   usable frames linked by shared points is solved (a point seen in two of them links them);
2. a chained start (:mod:`.chain`) at the hint or the assumed focal length, then the rotation-only
   bundle adjustment (:mod:`.bundle`) with the focal length nearly free (a hint is a 5 % prior);
3. is the focal length determined (:mod:`.checks`)?  If not, the adjustment again with it held
   at the hint or the assumed value, and the reason reported;
4. points whose track is mostly outside the robust threshold are left out (a slipping tracker);
5. parallax: a translating camera is reported, not absorbed;
6. frames outside the solved stretch get interpolated cameras (not ``solved``); everything is
   turned so that frame 0's rotation is the identity, the convention of the whole project
   (:mod:`core.camera`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from ..camera import DEFAULT_FOCAL_MM, mm_per_pixel
from ..lens.prior import META_FOCAL_ASSUMED
from ..tracks import Tracks
from . import checks
from .bundle import Observations, adjust
from .chain import chained_start

MIN_POINTS = 4
MIN_POINTS_PER_FRAME = 3
#: A point is left out when fewer than this share of its observations are inliers.
MIN_INLIER_SHARE = 0.7
#: The scene camera is used only when it covers at least this share of the frames.
MIN_SOLVED_SHARE = 0.5
HINT_LOG_SIGMA = 0.05
#: Above this standard deviation of log f the adjusted focal length is dropped for the hint or the
#: assumed one; below it, even when not "determined" (:mod:`.checks`), the data's estimate is kept.
HOLD_LOG_SIGMA = 0.2
FREE_LOG_SIGMA = 1.0
#: Iterations of the adjustment.  A small turn leaves the focal length in a long flat valley that
#: Gauss-Newton crosses slowly: a tripod run panning 5 degrees at 22 mm, started at the assumed 50 mm,
#: was still at 41.5 mm after 30 iterations (camera 2.4 degrees off, unflagged) and reached 22.2 mm
#: (0.10 degrees) after 115.  Converged solves stop on their own long before this.
ADJUST_MAX_ITER = 200


@dataclass
class SceneCamera:
    """The camera from the background tracks, frame-0 axes (``R_0 = I``), and what its checks say."""

    rotvec_deg: np.ndarray          # (F, 3)
    focal_mm: np.ndarray            # (F,)
    solved: np.ndarray              # (F,) bool: frame in the adjusted stretch (else interpolated)
    directions: np.ndarray          # (S, 3) unit, frame-0 camera axes (NaN: not seen in the solved stretch)
    names: tuple
    used_points: np.ndarray         # (S,) bool: kept (seen in the solved stretch, not a slipping track)
    focal_determined: bool
    focal_reason: str
    log_focal_sigma: float          # from the background alone (what decides "determined")
    turn_deg: float
    residual_px: float
    noise_px: float
    parallax_px: float
    translating: bool
    warnings: list = field(default_factory=list)
    #: The lens prior's standard deviation of log f (the hint's, or the free range's around the assumed lens).
    log_focal_prior_sigma: float = FREE_LOG_SIGMA

    @property
    def log_focal_sigma_with_prior(self) -> float:
        """Standard deviation of log f from the background and the lens prior together: how far the lens,
        and so the camera's angles, may still be off (an undetermined lens is held near the prior's centre)."""
        data, prior = float(self.log_focal_sigma), float(self.log_focal_prior_sigma)
        if not data > 0.0:                      # NaN: the background says nothing; 0: it fixes the lens
            return prior if np.isnan(data) else 0.0
        return float(1.0 / np.sqrt(1.0 / data ** 2 + 1.0 / prior ** 2))

    @property
    def usable(self) -> bool:
        """Whether the joint solve should take this camera (enough frames, no translation)."""
        return bool(self.solved.mean() >= MIN_SOLVED_SHARE and not self.translating and self.used_points.sum() >= 2)

    def summary(self) -> dict:
        """Plain numbers for RESULT.json's diagnostics."""
        return {"points": len(self.names), "points_used": int(self.used_points.sum()),
                "frames_solved": float(self.solved.mean()), "turn_deg": self.turn_deg,
                "focal_determined": self.focal_determined, "focal_reason": self.focal_reason,
                "log_focal_sigma": self.log_focal_sigma,
                "log_focal_sigma_with_prior": self.log_focal_sigma_with_prior, "residual_px": self.residual_px,
                "noise_px": self.noise_px, "parallax_px": self.parallax_px, "translating": self.translating,
                "used": self.usable,
                "left_out": [n for n, u, d in zip(self.names, self.used_points, self.directions, strict=True)
                             if not u and np.isfinite(d).all()],
                "unseen": [n for n, d in zip(self.names, self.directions, strict=True) if not np.isfinite(d).all()]}


def _stretch(usable: np.ndarray, sets: list[set]) -> np.ndarray:
    """Frames of the longest run of usable frames where each shares 2+ points with the previous usable one."""
    idx = np.flatnonzero(usable)
    best, run = [], []
    for i in idx:
        if run and len(sets[i] & sets[run[-1]]) < 2:
            best = run if len(run) > len(best) else best
            run = []
        run.append(i)
    best = run if len(run) > len(best) else best
    return np.array(best, dtype=int)


def _determinacy(res) -> tuple[float, float, bool, str]:
    """(turn degrees, sigma of log f, determined, reason) of an adjustment (:mod:`.checks`)."""
    turn = checks.turn_deg(res.state.R)
    sigma_g = float(np.sqrt(max(res.cov_g_ref, 0.0)))
    return (turn, sigma_g, *checks.focal_determinacy(turn, sigma_g))


def focal_arguments(tracks: Tracks, focal_mm: float | None) -> dict:
    """:func:`solve_scene_camera`'s focal arguments for a method handed ``focal_mm`` with ``tracks``: a hint the
    background may move 5 %, or, where the estimate marked it assumed (:data:`core.lens.prior.META_FOCAL_ASSUMED`:
    a phone's main camera, not a stated lens), only the start of the background's own estimate."""
    if focal_mm is not None and tracks.meta.get(META_FOCAL_ASSUMED):
        return {"focal_hint_mm": None, "assumed_focal_mm": float(focal_mm)}
    return {"focal_hint_mm": focal_mm}


def solve_scene_camera(tracks: Tracks, *, focal_hint_mm: float | None = None,
                       assumed_focal_mm: float = DEFAULT_FOCAL_MM) -> SceneCamera | None:
    """The scene camera of ``tracks.static`` (module docstring); None when there are too few points."""
    st = tracks.static
    if st is None or st.n_points < MIN_POINTS:
        return None
    n = tracks.n_frames
    k = mm_per_pixel(tracks.image_size)
    centre = np.array(tracks.image_size) / 2.0
    present = st.present
    usable = present.sum(axis=1) >= MIN_POINTS_PER_FRAME
    sets = [set(np.flatnonzero(present[i])) for i in range(n)]
    frames = _stretch(usable, sets)
    if frames.size < 3:
        return None
    seen = np.flatnonzero(present[frames].any(axis=0))        # points seen in the stretch, re-indexed
    fi, si = np.nonzero(present[frames][:, seen])
    uv = st.xy[frames][:, seen][fi, si] - centre
    obs = Observations(fi, si, uv, frames.size, seen.size, frames)
    bounds = np.searchsorted(fi, np.arange(frames.size + 1))      # fi is sorted: each frame's observations
    uv_by_frame = [dict(zip(si[a:b].tolist(), uv[a:b], strict=True)) for a, b in zip(bounds[:-1], bounds[1:],
                                                                                      strict=True)]
    ref = 0
    guess_mm = focal_hint_mm if focal_hint_mm is not None else assumed_focal_mm
    g_prior = (np.log(guess_mm / k), HINT_LOG_SIGMA if focal_hint_mm is not None else FREE_LOG_SIGMA)
    start = chained_start(obs, uv_by_frame, guess_mm / k, ref)
    res = adjust(start, obs, ref=ref, g_prior=g_prior, max_iter=ADJUST_MAX_ITER)
    turn, sigma_g, determined, reason = _determinacy(res)
    # parallax over every point (before any is left out: a moving camera makes most of them look slipping)
    noise, parallax = checks.noise_and_parallax(res.residuals, fi, si, np.ones(len(fi), dtype=bool))
    moving = checks.translating(noise, parallax)
    warnings = []
    # slipping tracks: points mostly outside the robust threshold are left out, and the camera adjusted again
    share = np.bincount(si, weights=res.inlier.astype(float), minlength=seen.size) / np.maximum(
        np.bincount(si, minlength=seen.size), 1)
    used = share >= MIN_INLIER_SHARE
    if not used.all() and used.sum() >= MIN_POINTS and not moving:
        bad = [st.names[seen[s]] for s in np.flatnonzero(~used)]
        warnings.append(f"background: track(s) {', '.join(bad)} do not move with the others "
                        "(slipping, or on something that moves); left out")
        keep = used[si]
        obs = Observations(fi[keep], si[keep], uv[keep], frames.size, seen.size, frames)
        res = adjust(res.state, obs, ref=ref, g_prior=g_prior, max_iter=ADJUST_MAX_ITER)
        fi, si, uv = obs.frame, obs.point, obs.uv
        turn, sigma_g, determined, reason = _determinacy(res)
    if not determined and not (sigma_g <= HOLD_LOG_SIGMA):
        # the background says next to nothing about the lens: hold the hint or the assumed value, so the
        # angles are the ones that lens gives (a looser estimate is kept: its error is smaller than a guess's)
        res = adjust(res.state, obs, ref=ref, g_prior=(np.log(guess_mm / k), 1e-4))
    if moving:
        warnings.append(f"camera: the background tracks show {parallax:.1f} px of parallax (noise {noise:.1f} px): "
                        "the camera moves, not only turns (a walking operator?); they were not used for the camera")
    # every frame: the adjusted stretch, and interpolated (or held) cameras outside it
    rot = Rotation.from_matrix(res.state.R)
    if frames.size >= 2:
        inside = np.clip(np.arange(n), frames[0], frames[-1])
        R_all = Slerp(frames, rot)(inside).as_matrix()
    else:
        R_all = np.repeat(rot.as_matrix(), n, axis=0)
    g_all = np.interp(np.arange(n), frames, res.state.g)
    R0 = R_all[0].copy()
    R_all = R_all @ R0.T                               # frame 0 becomes the identity
    d = np.full((st.n_points, 3), np.nan)
    d[seen] = res.state.d @ R0.T
    used_all = np.zeros(st.n_points, dtype=bool)
    used_all[seen] = used
    solved = np.zeros(n, dtype=bool)
    solved[frames] = True
    return SceneCamera(
        rotvec_deg=np.degrees(Rotation.from_matrix(R_all).as_rotvec()), focal_mm=np.exp(g_all) * k,
        solved=solved, directions=d, names=st.names, used_points=used_all, focal_determined=bool(determined),
        focal_reason=reason, log_focal_sigma=sigma_g, turn_deg=turn,
        residual_px=float(np.sqrt(np.mean(np.sum(res.residuals[res.inlier] ** 2, axis=1)) / 2.0)),
        noise_px=noise, parallax_px=parallax, translating=moving, warnings=warnings, log_focal_prior_sigma=g_prior[1])
