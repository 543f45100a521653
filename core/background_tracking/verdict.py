"""Whether the background followed on the footage can carry the camera, or the person must alone.

Background tracking runs by default whenever footage is at hand, so it must know when the scene gives
too little: a plain wall or a blurred background (too few features), or a background that does not
move as one scene seen by a turning camera (a crowd walking past, a camera carried while walking).
Then the features would mislead the camera more than they help, and the run falls back to the person
alone with one warning that says which of these it was. The test of "moves as one scene" is the scene
camera itself (:func:`core.scene_camera.solve_scene_camera`): it fits a turning, zooming camera to every
feature, leaves out the ones that slip, and measures the parallax nothing but a moving camera explains.
"""

from __future__ import annotations

import numpy as np

from ..runs import runs
from ..scene_camera import solve_scene_camera
from ..tracks import StaticTracks, Tracks

#: Fewer than this many features in view leave a frame's camera to the person (Kabsch needs 3; 4 give a check).
MIN_IN_VIEW = 4
#: The background is dropped when fewer than :data:`MIN_IN_VIEW` are in view on at least this share of the
#: frames: the scene camera is used only when it solves half the frames (``scene_camera.MIN_SOLVED_SHARE``).
MAX_SHORT_SHARE = 0.5
#: The background is dropped when the scene camera keeps fewer than this share of the features (the rest
#: do not move with the others: they are on something that moves).
MIN_CONSISTENT_SHARE = 0.5
#: What every fallback warning starts and ends with, so a reader (and a test) finds it.
PREFIX = "background: "
FALLBACK = "; the camera comes from the person alone"


def _longest_run_s(mask: np.ndarray, fps: float) -> float:
    """Seconds of the longest run of True in ``mask``."""
    return max((b - a for a, b in runs(mask)), default=0) / max(float(fps), 1e-9)


def judge_background(tracks: Tracks, static: StaticTracks | None) -> str:
    """'' when ``static`` (the features followed for the joint ``tracks``) can give the camera; otherwise
    the one-line warning that says why not and that the camera comes from the person alone."""
    n = tracks.n_frames
    if static is None or static.n_points == 0:
        return (f"{PREFIX}no background feature could be followed on the footage (a plain or blurred "
                f"background?){FALLBACK}")
    in_view = static.present.sum(axis=1)
    short = in_view < MIN_IN_VIEW
    if n and short.mean() >= MAX_SHORT_SHARE:
        return (f"{PREFIX}fewer than {MIN_IN_VIEW} background features in view on {int(short.sum())} of {n} "
                f"frames (the longest stretch {_longest_run_s(short, tracks.fps):.1f} s; "
                f"{float(np.median(in_view)):.0f} on the median frame): too little texture in the scene"
                f"{FALLBACK}")
    scene = solve_scene_camera(tracks.replaced(static=static))
    if scene is None:
        return (f"{PREFIX}the {static.n_points} background features never share a stretch of frames that "
                f"ties the camera together{FALLBACK}")
    if scene.translating:
        return (f"{PREFIX}the background features show {scene.parallax_px:.1f} px of parallax (noise "
                f"{scene.noise_px:.1f} px): the camera moves, not only turns, or the background does (a crowd)"
                f"{FALLBACK}")
    seen = np.isfinite(scene.directions).all(axis=1)
    used = int(scene.used_points.sum())
    if used < MIN_CONSISTENT_SHARE * max(int(seen.sum()), 1):
        return (f"{PREFIX}only {used} of {int(seen.sum())} background features move as one scene seen by a "
                f"turning camera: the others are on something that moves (a crowd?){FALLBACK}")
    if not scene.usable:
        return (f"{PREFIX}the background features tie together only {100 * scene.solved.mean():.0f} % of the "
                f"frames{FALLBACK}")
    return ""
