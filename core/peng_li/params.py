"""Every parameter of Peng & Li (2006) in one place, named after the paper's wording.

The paper states most of its assumptions in seconds ("the camera is still for at
least 1 second", "a stance foot stays still for more than 1 second", "each camera
motion lasts over 0.5 second"); they are kept in seconds here and turned into
frames with the clip's frame rate ``p`` by the steps that use them.  Thresholds the
paper leaves unspecified ("below a given threshold") get a documented default.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class PaperParams:
    # --- 3.1 2D data rectification -------------------------------------------------------
    #: Smoothing filter on each joint trajectory: "savgol" (Savitzky-Golay, keeps peaks),
    #: "gaussian" or "none".  The paper only says "a smoothing filter".
    smoothing: str = "savgol"
    #: Savitzky-Golay window in frames at 30 fps (scaled with fps, made odd) and its polynomial order.
    savgol_window_30fps: int = 11
    savgol_order: int = 2
    #: Gaussian sigma in seconds (used when ``smoothing == "gaussian"``).
    gaussian_sigma_s: float = 0.05
    #: Gaps of missing joints up to this many seconds are interpolated before filtering;
    #: longer gaps stay missing (NaN) and the frames are skipped where needed.
    max_gap_s: float = 0.5

    # --- 3.2 sequence segmentation ----------------------------------------------------------
    #: Window over which each foot's movement is accumulated, in seconds (the paper: p/2 frames).
    still_window_s: float = 0.5
    #: "Below a given threshold": accumulated foot movement per frame of the window, in pixels
    #: of a 720-pixel-wide image (36 mm film: 0.05 mm per pixel), for noise-free data ...
    still_threshold_px_per_frame: float = 0.7
    #: ... plus this many times the 2D noise level measured from the data (robust spread of the raw
    #: tracks around the smoothed ones), since smoothed noise still adds apparent foot movement.
    still_threshold_per_noise: float = 0.2
    #: Moving runs shorter than this (seconds) are treated as still (the paper assumes motions
    #: last over 0.5 s; 0.4 s allows for the slow eased ends that fall into still windows).
    min_motion_s: float = 0.4
    #: Detected motions are widened by this much (seconds) on each side: a still window that reaches
    #: into the slow, eased start or end of a motion still passes the threshold.
    motion_extend_s: float = 0.17
    #: Frames of a still spell next to a moving spell that are included in the camera estimate, so
    #: slow starts and stops of the camera are undone too.
    motion_margin_frames: int = 3
    #: Below this share of frames in still spells the estimate carries a warning: the paper needs a
    #: still camera between moves, and finding (almost) none means either a camera that never stops
    #: or a motion with no foot still for p/2 frames (running, skipping), where the camera track is
    #: the stance foot integrated over the whole clip and drifts (measured: the built-in run, 0 %
    #: still found, 11.8 degrees median rotation error; jogging 13.9, side-skip 7.9).  Not the paper.
    warn_still_fraction: float = 0.1

    # --- 3.3 stance foot and camera motion ---------------------------------------------------
    #: "The stance foot would not lift off within p frames after it first touches the ground":
    #: minimum stance duration in seconds (runs at the spell ends may be shorter).  The paper's 1 s
    #: does not hold for walking (a foot is planted ~0.5-0.7 s per step), so the default is 0.3 s;
    #: :data:`PAPER_LITERAL` keeps 1 s.
    min_stance_s: float = 0.3
    #: Camera motion models tried for every moving spell ("directional rotating", "zooming").
    motion_models: tuple[str, ...] = ("rotate", "zoom")
    #: "If both motion-smoothnesses are large, both camera motions are possible": a model is chosen
    #: on smoothness alone only when its cost is below this fraction of the other's; otherwise both are
    #: undone and the one leaving less "enlargement/shrinking" of the figure wins.
    model_cost_ratio: float = 0.2
    #: Still frames on each side of a spell included when judging enlargement/shrinking, seconds.
    size_context_s: float = 0.5
    #: Longest spell (frames) for which the brute-force enumeration of swap cases is allowed.
    brute_force_max_frames: int = 200

    # --- 4.1 virtual scale -----------------------------------------------------------------
    #: Stance runs shorter than this (seconds) do not give a calf depth of their own.
    min_stance_run_for_depth_s: float = 0.2
    #: Before the first / after the last stance swap, continue the depth trend of the nearest two
    #: swaps (True) or hold the depth (False; the paper only says "interpolated linearly").
    extrapolate_scale: bool = True

    # --- 4.2 virtual length ----------------------------------------------------------------
    #: Which statistic of the normalised per-frame lower bounds gives the length.  1.0 is the
    #: paper's maximum; a value below 1 (e.g. 0.98) takes that quantile instead, which resists the
    #: upward bias that noise gives a maximum.  (A robustification, not the paper.)
    bound_quantile: float = 1.0
    #: Frames whose virtual scale is more than this factor off the clip median are not used.
    max_scale_ratio: float = 4.0

    # --- beyond the paper --------------------------------------------------------------------
    #: Take the planted ankle's own creep, measured in the still spells, out of the feet before a
    #: rotating camera is tracked (:mod:`core.peng_li.foot_drift`).  Off in the paper's setting.
    stance_drift_correction: bool = False
    #: Weight of the body cue in a moving spell's stance choice (0: the paper's smoothness alone).  The
    #: cue is each ankle's squared image speed relative to the pelvis (:func:`.pipeline.body_stance_cue`):
    #: a pan or tilt moves the whole figure alike, so it cancels, while a swinging foot outruns the
    #: pelvis.  The paper's smoothness alone cannot tell a foot swinging during a pan from the pan itself
    #: (both are smooth), and takes the swinging foot on about a fifth of the moving frames.  Measured
    #: on the 15 clips x seeds 0-2 at 1 px (900 frames max; share of the moving spells' clear-stance
    #: frames with the right stance, median of the clips' median rotation errors of the spell tracks):
    #: 0 80.3 %, 1.70 degrees;  0.03 82.4 %, 1.21;  0.1 85.2 %, 1.05;  0.3 86.8 %, 0.75;  1 84.6 %, 1.10;
    #: 10 80.5 %, 2.03.  The reference joint hardly matters (hips, torso mean, knees: 86.4-87.1 %).
    stance_body_weight: float = 0.0

    def window_frames(self, seconds: float, fps: float, minimum: int = 1) -> int:
        return max(minimum, int(round(seconds * fps)))


#: The default settings (the paper's method; two assumptions relaxed, see min_stance_s, extrapolate_scale).
PAPER = PaperParams()
#: The paper read literally: stance >= 1 s, virtual distance held outside the swaps.
PAPER_LITERAL = PaperParams(min_stance_s=1.0, extrapolate_scale=False)
#: The robustified variant: a high quantile instead of the maximum of the lower bounds.
ROBUST = PaperParams(bound_quantile=0.98)
#: The paper's method with the planted ankle's creep corrected.
DRIFT_CORRECTED = PaperParams(stance_drift_correction=True)
#: The joint method's start: the creep corrected, and the body cue in the moving spells' stance.
JOINT_START = PaperParams(stance_drift_correction=True, stance_body_weight=0.3)
