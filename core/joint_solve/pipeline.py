"""``estimate_joint``: the "joint" method, end to end.

Steps (each a module of this package):

1. film coordinates; a gap-filled copy of the tracks for initialisation only;
2. the paper's method (core.peng_li) for stance, camera track and proportions;
   if it fails, our own 2D stance guess (:mod:`.stance`), planted-foot camera
   (:mod:`.camera_init`) and average proportions;
3. focal length: the user's hint (a prior, 5 %), else 50 mm with
   ``focal_determined = False`` and a warning (:mod:`.calibration` explains
   why its self-calibration curve is not trusted yet);
4. per-frame 3D by perspective Taylor with depth signs chosen by DP
   (:mod:`.taylor`, :mod:`.signs_dp`), the trunk's and legs' signs with the learnt pose prior
   (:mod:`core.motion_prior`, :data:`USE_POSE_PRIOR`); the starting pelvis depth from
   time-smoothed tracks (:data:`DEPTH_SMOOTH_FRAMES`);
5. the joint least-squares solve (:mod:`.solver`) with the paper's camera as a
   soft prior (:data:`PAPER_CAMERA_SIGMA`) and the paper's lengths as a weak
   one (:data:`LENGTH_PRIOR_SIGMA_M`; looser for the spine and head, :data:`UPRIGHT_CLASSES`),
   windowed beyond :data:`SINGLE_MAX` frames; then the depth signs chosen again on the solved
   state and solved again, twice, each round kept if the cost falls (:func:`signs_again`);
6. stance for the solve: the paper's when it ran, for the first solve; the sign rounds then hold the
   stance decided on its motion (:data:`STANCE_FROM_FIRST_SOLVE`); without the paper's run, re-decided
   in 3D with a short second solve;
7. floor and up direction (:mod:`.ground`), every per-frame field of the Estimate; the stance
   reported is decided on the solved motion in world axes, the slow and low foot
   (:func:`.stance.stance_from_world`, measured better than the paper's); with a camera from background
   points, also the foot that stands still in the picture once that camera is undone.

Status (measured; bench/bench_joint.py, README "Joint solve (beyond the paper)"; how far the
objective itself gets from the truth, clip by clip: bench/ceiling.py, README "How close the
objective itself gets"): full 3D motion, camera and floor for every frame, with missing joints;
proportions better than the paper's on average over the shared clips; the camera as good as the
paper's run with the planted ankle's creep corrected (:mod:`core.peng_li.foot_drift`), better where
the paper finds no still camera (:data:`STILL_START_WHEN_NO_STILL_SPELL`); 3D pose far from
15 mm (the objective started at the truth with every input right ends at 27 mm). Why, in
short: a person 5-17 m away shows so little perspective that every limb can be mirrored in depth at
almost no cost, and the Taylor + DP start lands in such mirror minima (the sign rounds,
:func:`signs_again`, win part of it back); the camera is hardly observable where no foot is planted
for long, and a zoom looks like the person coming nearer.

What was measured on the way, the ideas tried and dropped included (limb and trunk flips, local
re-solves, camera starts, zoom tests), is in ``docs/joint_solve_findings.md``; each setting below
keeps its own record beside it.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..camera import mm_per_pixel, pixels_to_film, rotvec_deg
from ..errors import Cancelled, InputError
from ..lens.prior import META_FOCAL_ASSUMED
from ..motion_cleanup.contacts import detect_contacts
from ..result import Estimate, FrameEstimate
from ..scene_camera import focal_arguments, solve_scene_camera
from ..skeleton import CLASS_INDEX, FEET, N_CLASSES, class_lengths_for_height, proportions, proportions_dict
from ..tracks import Tracks
from . import solver as slv
from .calibration import Calibration, self_calibrate
from .camera_init import figure_log_zoom, rotations_from_stance
from .ground import world_from_cam0
from .signs_dp import resolve_signs
from .stance import (
    NONE,
    feet_apart_speed,
    hips_over_feet_speed,
    stance_codes,
    stance_from_2d,
    stance_from_3d,
    stance_from_world,
    step_period,
    stride_period,
    undone_ankle_speeds,
)
from .taylor import fill_missing, root_depth, unit_rays

#: Average adult proportions (10 classes, CLASSES order) used when nothing better is known.
DEFAULT_PROPORTIONS = proportions(np.array([0.095, 0.43, 0.42, 0.20, 0.24, 0.10, 0.20, 0.17, 0.29, 0.26]))

#: Log-focal prior sigma on the assumed (default) focal length when the data do not determine it.
UNDETERMINED_FOCAL_SIGMA = 0.02

#: Clips longer than SINGLE_MAX frames are solved in windows of WINDOW frames overlapping by OVERLAP:
#: the first window fixes the class lengths, later windows pin their first OVERLAP frames (camera and
#: joints) to the previous window's answer, so memory stays bounded (a band of 110 x 55 per frame).
SINGLE_MAX = 1200
WINDOW = 600
OVERLAP = 40
#: Levenberg-Marquardt iterations per solve.  Measured over 6 synthetic clips (300 frames, 1 px;
#: proportion mean / mean-of-max pp, MPJPE per frame, total seconds): 8 iterations 0.255 / 0.650,
#: 97.7 mm, 11.2 s;  12: 0.261 / 0.668, 97.9 mm, 13-22 s;  16: 0.264 / 0.679, 98.0 mm, 19.3 s.
#: With the second sign choice (below) the iterations are split between the two solves.
#: Fewer iterations, measured for the time they would save (each of the estimate's 13 takes about 0.2 s of its
#: 5 s at 900 frames): 4 here and 2 after the sign round (:data:`SIGN_PASS_ITER`) looked free on the tune half
#: of ``bench/motion_bench.py`` (5 clips x 3 draws, cleanup on; means over cases paper / still / detector /
#: background: mirrored frames 3.6 / 5.9 / 12.3 / 7.8 -> 3.9 / 6.1 / 12.1 / 7.6 %, per-frame error 53.1 / 51.2
#: / 69.9 / 50.6 -> 53.1 / 50.8 / 69.6 / 51.4 mm), on ``bench/robust_bench.py --half tune --draws 3 --broad 3
#: --no-fps`` (median rotation error 3.50 -> 3.50 degrees target, 4.69 -> 4.72 broad) and on the 15 clips of
#: ``python -m core evaluate`` (0.212 -> 0.213 pp, 48.3 -> 48.6 mm), but not on the report half (``--half
#: report --cleanup both``, medians): paper 44 -> 46 mm, planted excess 205 -> 213 mm/s; background -2 -> 38
#: mm/s, whole clip 82 -> 87 mm; detector 62 -> 63 mm.  So 5 and 3 stay.  Alone on the tune half: 6 iterations
#: 3.6 / 6.1 / 12.6 / 7.8 %, 53.0 / 51.3 / 70.4 / 50.5 mm; 4: 4.2 / 5.9 / 12.6 / 7.7 %, 53.3 / 51.1 / 70.5 /
#: 50.9 mm; 2 after the sign round: 3.6 / 6.0 / 11.8 / 7.6 %, 53.0 / 50.7 / 69.9 / 51.1 mm; 3 and 2: 4.3 / 6.0
#: / 12.6 / 7.9 %, 53.5 / 50.8 / 70.3 / 51.5 mm.  The solves have not converged when they stop (the 900-frame
#: bench walk's cost still falls 10-17 % in each one's last iteration), but the poses hardly move any more.
SOLVE_ITER = 5
#: Depth signs chosen a second time, on the solved state, then a second solve of SIGN_PASS_ITER
#: iterations from there; the lower final cost wins (:func:`signs_again`).  0 switches it off.
#: Measured on the 15 clips (14 shared + built-in walk, 900 frames max, pan/tilt/zoom, 1 px): proportion
#: mean / max / mean of clip maxima pp, per-frame MPJPE, and the time of the 900-frame bench walk:
#: no second choice, 8 iterations 0.221 / 1.18 / 0.667, 81.2 mm, 4.9 s;  8 + 8 iterations 0.217 / 1.02 /
#: 0.604, 74.0 mm, 10-14 s;  8 + 4: 0.215 / 1.18 / 0.622, 74.2 mm, 11 s;  5 + 5: 0.213 / 1.00 / 0.597,
#: 75.6 mm, 6.1 s;  8, then up to three rounds of 8: 0.227 / 1.00 / 0.613, 72.3 mm.  The time is the banded
#: factorisation (0.2 s per LM step at 900 frames then, 0.1 s in single precision since); the DP itself takes 0.6 s.
#: Two rounds since the still spells hold still (:data:`STILL_SPEED_SIGMA`); measured on the same 15 clips,
#: one round -> two (proportion mean / max / mean of clip maxima pp, per-frame MPJPE):  0 px 0.201 / 1.73 /
#: 0.593, 74.1 mm -> 0.203 / 1.73 / 0.588, 70.6 mm;  1 px 0.207 / 1.02 / 0.592, 72.4 mm -> 0.207 / 1.03 /
#: 0.555, 70.0 mm;  2 px 0.300 / 1.43 / 0.837, 86.1 mm -> 0.291 / 1.21 / 0.791, 83.7 mm.  The second round
#: with the lengths held (1 px): 0.207 / 1.02 / 0.592, 69.8 mm.  But 5 + 5 + 5 iterations took the 900-frame
#: bench from 6.75 to 9.78 s back to back (a slow host), over the 10 s target on a busier one, so the rounds
#: get 3 iterations each (1 px): 5 + 3 + 3 0.203 / 1.02 / 0.549, 71.7 mm;  4 + 3 + 3 0.208 / 1.00 / 0.569,
#: 71.2 mm;  5 + 5 + 5 0.207 / 1.03 / 0.555, 70.0 mm;  one round 5 + 5 0.207 / 1.02 / 0.592, 72.4 mm.
#: Re-measured with the time the single-precision factorisation freed (:data:`.solver.SINGLE_PRECISION_FACTOR`)
#: and the sign rounds on the first solve's stance (1 px): 5 + 5 + 5 iterations 0.210 / 1.03 / 0.575 pp,
#: 69.7 / 390 mm against 0.203 / 1.02 / 0.551, 70.1 / 392 mm; so 3 stay.  With the camera polish, 15 clips x
#: seeds 0-2 (1 px), 15 + 8 + 8 iterations paired against 5 + 3 + 3: proportions -0.004 +- 0.005 pp (clip
#: maxima -0.036 +- 0.025), per-frame MPJPE -3.3 +- 1.5 mm, whole clip -5.5 +- 2.3 mm, stance -0.5 +- 0.3
#: points, at twice the time; per clip it is no rule of length (neutral, 82 frames, 87 -> 66 mm, strutting,
#: 75 frames, 63 -> 67 mm), so more iterations for short clips are not used either.
#: Since the pose lifter guides the first choice, one round does as well as two for a quarter less time
#: (the 900-frame bench walk 10.8 -> about 8 s): tune half of ``bench/motion_bench.py`` (5 clips x 3 draws,
#: cleanup on), means over cases paper / still / detector / background, two rounds -> one: mirrored frames
#: 6.9 / 9.7 / 17.0 / 7.7 -> 7.0 / 10.0 / 16.5 / 7.8 %, per-frame error 56.4 / 56.2 / 73.9 / 50.5 -> 56.7 /
#: 56.4 / 74.4 / 51.1 mm; the 15 clips at 1 px (``python -m core evaluate``) 0.21 / 1.07 pp both, per-frame
#: error within 2 mm on every clip (5 lower, 5 higher, 5 the same).
SIGN_PASSES = 1
SIGN_PASS_ITER = 3
#: :func:`estimate_joint` hands the sign rounds the stance decided on the first solve's motion
#: (:func:`.stance.stance_from_world`, the slow and low foot) instead of the paper's, at no extra solve
#: (False: the paper's throughout).  Why it helps is not pinned down: on ``walk_normal``, the largest gain,
#: both stances are right on every one-foot frame, so only the frames with both feet down changed.
#: Measured on the 15 clips (900 frames max, pan/tilt/zoom), proportion mean / max / mean of clip maxima pp,
#: per-frame / whole-clip MPJPE, paper's stance -> this:  0 px 0.201 / 1.73 / 0.622, 75.1 / 394 mm -> 0.198 /
#: 1.73 / 0.596, 71.4 / 387 mm;  1 px 0.204 / 1.02 / 0.550, 71.7 / 397 -> 0.203 / 1.02 / 0.551, 70.1 / 392;
#: 2 px 0.304 / 1.23 / 0.856, 85.3 / 422 -> 0.295 / 1.22 / 0.803, 83.3 / 419.  Per clip it is a nudge to the
#: sign search, not a sure gain: per-frame error lower on 9-12 clips, ``walk_normal`` 67.8 -> 50.0 mm and
#: 131_01 93.7 -> 85.8 at 1 px, but 01_01's proportions 0.14 -> 0.17 pp and the kick 73.5 -> 75.4 mm.  The
#: median rotation error stays (0.634 -> 0.653 degrees at 0 px, 0.638 -> 0.640 at 1 px, 0.685 -> 0.681 at
#: 2 px); the stance reported drops a little (92.6 / 93.1 / 91.5 -> 91.8 / 92.8 / 90.9 %).  The same switch
#: after the sign rounds with 3 more iterations (1 px): 0.202 / 1.04 / 0.558 pp, 71.3 / 395 mm.  Windowed
#: solves (over :data:`SINGLE_MAX` frames) keep the paper's stance.
STANCE_FROM_FIRST_SOLVE = True
#: First-order continuity (metres per frame) of the second sign choice: looser than the first DP's
#: (:data:`.signs_dp.SIGMA_CONTINUITY_M`, 0.08), since the solved candidates are not noisy.  Measured on
#: the same 15 clips at 1 px (mean / max / mean of clip maxima pp, MPJPE): 0.04 0.219 / 1.23 / 0.637,
#: 78.7 mm;  0.08 0.213 / 1.00 / 0.597, 75.6 mm;  0.15 0.207 / 1.01 / 0.589, 72.5 mm;  0.3 0.213 / 1.03 /
#: 0.590, 72.6 mm;  0.6 0.212 / 1.23 / 0.602, 73.0 mm.  0.08 -> 0.15 at 0 px: 0.21 / 1.73, 76 mm ->
#: 0.200 / 1.73, 74.0 mm; at 2 px 0.31 / 1.66, 90 mm -> 0.299 / 1.43, 86.1 mm.  Its second-order sigma
#: (:data:`.signs_dp.SIGMA_ACCEL_M`, 0.05) stays: 0.02 gave 0.215 / 1.04, 77.0 mm; 0.1 0.221 / 1.22, 75.3 mm
#: (with continuity 0.08).  Two rounds instead of one (5 + 5 + 5 iterations, continuity 0.15): 0.212 / 1.03 /
#: 0.569 pp, 70.3 mm, against 0.207 / 1.01 / 0.589, 72.5 mm: better 3D, slightly worse proportions and a
#: third solve's time, so one round then.  Also measured with continuity 0.15: 6 + 4 iterations 0.208 / 1.21 /
#: 0.617 pp, 72.4 mm; the first DP's own continuity at 0.05 0.208 / 1.02 / 0.594, 74.0 mm and at 0.12
#: 0.211 / 1.03 / 0.583, 73.2 mm (0.08 kept).  An ensemble, each round trying 0.08, 0.15 and 0.3 and keeping
#: the cheapest (15 clips x seeds 0-2, 1 px, paired against this): proportions +0.002 +- 0.003 pp, per-frame
#: MPJPE +0.0 +- 0.7 mm, whole clip -2.2 +- 1.4 mm, for twice the time: the cost does not pick per clip.
SIGN_PASS_CONTINUITY_M = 0.15
#: Camera is "moving" above these per-frame rates.
MOVING_DEG_PER_FRAME = 0.02
MOVING_ZOOM_PER_FRAME = 0.0005
#: Soft prior on the paper's camera track (degrees, log focal).  Measured on the synthetic walk (300
#: frames, spells, 1 px): without it the solve's camera drifts (median 0.52 deg, zoom 4.2 %), because a
#: person 10-20 m away shows little perspective; with it about 0.3 deg and 0.2-0.4 %.
PAPER_CAMERA_SIGMA = (0.2, 0.01)
#: The same prior inside the paper's still spells (degrees, log focal): the rotation as loose as in the moves,
#: the focal length tight.  With :data:`STILL_SPEED_SIGMA` a still spell holds still but may shift as one
#: block, so the solve can correct where the paper left it.
STILL_CAMERA_SIGMA = (0.2, 0.0002)
#: Change between consecutive frames of a paper's still spell (degrees, log focal): a still camera must not
#: shiver for an animator looking through it.  The paper's own track does, near its spell boundaries (steps
#: up to 0.1 degree), so the earlier tight *absolute* prior (0.005 degree, 0.0002) copied that: on the
#: built-in walk (1 px) its still spells spanned 0.08-0.20 degrees; with this sigma 0.0006-0.004 degrees,
#: and the focal length 0.0001-0.04 mm.  Measured on the 15 clips at 1 px (proportion mean / max / mean of
#: clip maxima pp, per-frame MPJPE, median rotation error, median zoom error): tight absolute prior 0.207 /
#: 1.01 / 0.587, 72.5 mm, 0.642 degrees, 6.17 %;  this 0.207 / 1.02 / 0.592, 72.4 mm, 0.634 degrees, 6.22 %.
#: Variants (absolute sigma; speed sigma), none clearly better: (0.2, 0.01; 0.005, 0.0002) 0.203 / 1.02,
#: 71.8 mm, 0.610 degrees, 6.38 %;  (0.2, 0.0002; 0.005, 0.0002) 0.203 / 1.01, 72.0 mm, 0.619, 6.24 % (still
#: spells spanning up to 0.09 degree);  (0.5, 0.0002; same) 0.204 / 1.00, 72.2 mm, 0.612, 6.27 %;
#: (0.05, 0.003; same) 0.209 / 1.01, 72.6 mm, 0.639, 6.24 %.  The data hardly move a still spell: the
#: gain is a camera that holds still, not accuracy.
STILL_SPEED_SIGMA = (0.0005, 0.00002)
#: Where the paper's method finds a still camera in under 10 % of the frames (its own warning,
#: ``warn_still_fraction``), start the solve from a camera standing still, and centre the camera prior
#: on it, instead of the paper's track: that track is the stance foot integrated over the whole clip,
#: and a runner's feet are never planted long, so it drifts.  Measured before the camera polish
#: (:data:`CAMERA_PRIOR_POLISH_ITER`; with it seed 0's run is 3.6 degrees) (1 px, 900 frames max, seeds
#: 0-2): the built-in run's median rotation error 11.9 / 17.6 / 11.9 -> 3.5 / 5.5 / 7.5 degrees, per-frame
#: MPJPE 146 / 151 / 138 -> 128 / 129 / 96 mm, proportions 0.62 / 0.66 / 0.85 -> 0.77 / 0.77 / 0.40 pp;
#: jogging 13.9 / 11.5 / 15.2 -> 4.8 / 8.1 / 3.9 degrees, whole clip 1307 / 1631 / 1366 -> 947 / 737 /
#: 780 mm (with :data:`~core.peng_li.params.JOINT_START`'s body cue).  Dropping the prior instead of
#: centring it on the still camera gave the same but for the run's frame-0 focal length (18 % off on
#: seed 1 against 8 %).
STILL_START_WHEN_NO_STILL_SPELL = True
#: ... unless the person stands on the spot: ankles moving against each other in the picture slower than
#: this (:func:`.stance.feet_apart_speed`, the figure's spread per second).  Then no still spell means a
#: camera that never stops (a handheld operator), not feet that never stay put, and the paper's track,
#: which follows the planted feet, is right.  Chosen on the tune half of ``bench/motion_bench.py``: the
#: built-in standing figure reads 0.09-0.22, the tune half's walks and runs 1.1-7.7 (detector and paper
#: schedules), so the threshold sits between them.  On the standing figure with a handheld operator and a
#: detector's errors (3 draws) the still start left the camera's pan out (18.7 degrees of it in one draw)
#: and the person walked 2 m sideways in the world.
STANDING_FEET_SPEED = 0.5
#: ... nor when the person walks (:func:`walking`): a stride read from the ankles' picture
#: (:func:`.stance.stride_period`) of :data:`WALKING_STRIDE_S` or longer that repeats with a correlation of
#: :data:`WALKING_STRIDE_CORRELATION` or more, and no step under :data:`RUNNING_STEP_S`.  A walker's feet stand
#: still for half a second and more at every step, so when the paper finds no still spell the camera moved all
#: the time (an operator following the person), and the paper's track, chained from those planted feet, is the
#: start and the prior, as where it finds still spells.  A still start there leaves the operator's turn out: the
#: solve turns the camera only a little, and the planted feet slide with the rest.  A runner's feet stand for a
#: quarter of a second, the chained track drifts, and the still start stays.  Chosen on the tune half of
#: ``bench/motion_bench.py`` (3 draws, all scenarios); over the 18 cases with a detector's errors and a handheld
#: operator (means): planted excess 602 -> 485 mm/s (median case 163 -> 101), whole clip 798 -> 707 mm,
#: per-frame error 54.0 -> 53.5 mm, mirrored frames 7.4 % both.  The walks' cases that changed: planted excess
#: 1494 / 914 / -29 / -8 -> 325 / -28 / -29 / -11 mm/s, whole clip 1409 / 612 / 70 / 198 -> 269 / 127 / 57 / 192
#: mm.  Nothing else on the tune half changed: its walks under the paper's schedule and the still camera have
#: still spells, its runs and jogging stride in 0.70-0.80 s.  Using the chained track for every clip with no still
#: spell, runners included, took the planted excess on the paper's schedule from 182 to 273 mm/s and its whole
#: clip from 630 to 784 mm (the built-in run: 1,258-2,226 -> 1,258-3,980 mm).  The cost, on the tune half of
#: ``bench/robust_bench.py`` (15 target and 15 broad cases): one walker on a tripod whose noisy feet (2.8 px and
#: a detector's errors) hid the still spells from the paper, its camera 0.18 -> 3.43 degrees off (median frame),
#: flagged either way; the rest unchanged.  A run whose stride read doubled there (left and right exchanged every
#: other stride in the cleaned tracks) is why the step is read too.  None: every clip with no still spell starts
#: still.
WALKING_STRIDE_S: float | None = 0.9
WALKING_STRIDE_CORRELATION = 0.25
RUNNING_STEP_S = 0.45
#: For a person standing on the spot (:data:`STANDING_FEET_SPEED`, no background tracks) the start's zoom is
#: read from the figure's picture (:func:`.camera_init.figure_log_zoom`, smoothed over this many seconds)
#: instead of the paper's, and frames zooming faster than :data:`ZOOMING_PER_S` (log focal length per
#: second) count as a moving camera for its prior.  Why: a zoom about the picture's centre hardly moves a
#: planted foot near it, so the paper's method misses it and holds the focal length, and the solve, started
#: there, reads the zoom as the person walking towards or away from the camera (a handheld operator's
#: 1.1-1.4x: 0.5-1.2 m in depth, the planted feet sliding with it).  None: the paper's zoom.  Tune half of
#: ``bench/motion_bench.py``, the built-in standing figure (3 draws; whole clip mm, planted excess mm/s):
#: with a detector's errors 203 / 96 / 351 mm and 274 / 67 / 404 mm/s -> 64 / 87 / 65 mm and 231 / 45 / 209
#: mm/s; on the paper's schedule 230 / 279 / 52 mm, 178 / 114 / 1 mm/s -> 88 / 58 / 44 mm, 34 / 0 / 0 mm/s.
#: Smoothing 0.3 s: 69 / 89 / 68 mm, 237 / 48 / 214 mm/s; paper 89 / 57 / 50 mm, 35 / 0 / 3 mm/s; 0.6 s
#: worse again.  The zoom without marking its frames as moving (0.3 s): paper 105 / 67 / 52 mm, 111 / 3 / 3
#: mm/s.  Lengths in pixels instead of angles between rays (0.3 s) measured worse (77 / 88 / 66 mm with a
#: detector, paper 89 / 57 / 66): panned to the edge of a wide lens's picture the figure looks larger.  No
#: other tune clip stands (their feet move apart at 1.1 figure spreads a second or more), so nothing else
#: changes there.  With the standing test of :data:`STANDING_FEET_SPEED` alone, the report half reads false
#: zooms on a still camera (the martial-arts clip: whole clip 153 -> 508 mm, mirrored frames 1 -> 9 %) and
#: under the paper's schedule (01_01: 560 -> 1164 mm), people who come nearer without moving their feet
#: apart for long.  The three conditions below answer that, their thresholds from the tune half's standing
#: figure alone; because the report half prompted them, it is no clean hold-out for them
#: (docs/joint_solve_findings.md, "The still start").
ZOOM_FROM_FIGURE_SMOOTH_S: float | None = 0.15
ZOOMING_PER_S = 0.03
#: ... and only where the person really holds the feet and hips still: the feet-apart speed's 90th
#: percentile over frames below :data:`ZOOM_FEET_SPEED_P90` (a few quick steps or a kick leave the median
#: low) and the hips' speed over the feet (:func:`.stance.hips_over_feet_speed`) below
#: :data:`ZOOM_STILL_HIPS_SPEED` (a jump with the feet together or a lunge does not move the feet apart but
#: brings the person nearer), both in figure spreads per second.  Each is twice the standing figure's
#: largest reading on the tune half (0.77 and 0.14; the tune half's walks and runs read 2.4 and 0.41 or
#: more).
ZOOM_FEET_SPEED_P90 = 1.5
ZOOM_STILL_HIPS_SPEED = 0.28
#: ... and only where the paper's method saw the camera move at all (a still share below this): a camera
#: the planted feet show still for the whole clip is taken as still, and a figure that changes size under
#: it as the pose (the built-in standing figure on a still camera: whole clip 33 / 37 / 33 mm with the
#: figure's zoom, 32 / 34 / 29 without).
ZOOM_STILL_SHARE_BELOW = 0.95
#: ... or where the figure's picture changes size by more than this over the clip (the range of its log
#: zoom), whatever the paper saw: a zoom about the picture's centre with no pan or tilt leaves the planted
#: feet where they were, so the paper's method sees a still camera throughout.  Twice the largest range
#: on a still camera among the standing cases of the tune half and the development set of
#: :data:`STANDING_HIPS_ACCEL_MS2` (0.009-0.132, 3 draws each: a person jumping on the spot reads the most);
#: the built-in standing figure filmed with zooms alone reads 0.33-0.59 (4 takes, zooms of 1.4-1.8 times,
#: every one of them missed by the paper's method).
ZOOM_FIGURE_RANGE = 0.26
#: A person standing on the spot (:func:`standing_on_the_spot`) is solved with two more terms
#: (``solver.Problem.standing``): the hips' acceleration (pelvis and both hips) at this sigma, m/s^2, besides
#: every joint's (``solver.Sigmas.accel_ms2``), and each ankle held still as the stance foot is
#: (``solver.Sigmas.foot_m``, robust) on the frames where the first solve's motion has it planted
#: (:func:`_standing_feet`).  Why: with a detector's errors a standing person's legs jitter (the ankles
#: 0.2-0.5 m/s from frame to frame), the solve holds only one foot, and the foot lock cannot hold a straight
#: leg's ankle that the jittering hips pull away.  The sigma is what people standing on the spot do: in the
#: training mocap (the 131 clips at 30 fps, 35 spells of 1 s or more with both ankles slower than 0.1 m/s,
#: 2,247 frames) the hips accelerate 2.45 m/s^2 (root mean square; median 1.4, 90th percentile 3.8).  None:
#: neither term.
#:
#: Measured (``bench/motion_bench.py --scenario all --draws 3``): on the tune half it applies only to the
#: built-in standing figure; there, with a detector's errors, the planted excess 231 / 45 / 209 -> 3 / 69 /
#: 133 mm/s, the whole clip 64 / 87 / 65 -> 55 / 88 / 59 mm, the world acceleration error 14.5 / 11.7 / 13.0
#: -> 9.9 / 9.4 / 10.2 m/s^2; on the paper's schedule 34 / 0 / 0 -> 10 / 0 / 0 mm/s; per-frame error within
#: 1.5 mm.  Because that figure holds both feet still throughout, how the feet are held was chosen on a
#: development set of training clips that read as standing on the spot (CMU 13_11, 16_01, 16_02, 2_05,
#: 5_18: punches, a dance, people who step and jump on the spot; 2 draws, with the standing figure; means,
#: paper / still / detector / background): without the terms per-frame error 42.7 / 35.9 / 45.7 / 44.5 mm,
#: |planted excess| 36 / 27 / 130 / 54 mm/s; both ankles held on every frame 43.4 / 36.6 / 49.8 / 46.5 mm,
#: 35 / 28 / 38 / 41 mm/s (a real step is held back); held where the first solve finds them planted
#: 42.6 / 35.8 / 46.5 / 45.0 mm, 37 / 27 / 92 / 45 mm/s; the same on that motion smoothed over 0.1 s
#: (:data:`STANDING_FEET_SMOOTH_S`, taken) 43.3 / 36.0 / 47.2 / 45.1 mm, 35 / 27 / 71 / 48 mm/s; over 0.2 s
#: 43.2 / 36.0 / 50.0 / 45.1 mm, 35 / 28 / 53 / 41 mm/s; the hips' term alone 43.0 / 35.8 / 46.3 / 45.3 mm,
#: 38 / 27 / 102 / 56 mm/s.  (Training clips only choose between ways of holding the feet here: the lifter
#: has seen their poses, so their errors are not reported as accuracy.)
STANDING_HIPS_ACCEL_MS2: float | None = 2.5
#: The paper's camera prior (:func:`_camera_prior`) joins only for this many final iterations, with the lengths
#: then held; the solve and its sign rounds run with the camera free.  0: the prior throughout. Why: the prior
#: holds the paper's still spells exactly still, and held still there the camera cannot take up what the
#: figure's fit asks of it; the proportions and the 3D pay.  The prior is kept, though, for an animator: without
#: it a still spell drifts (rotation span inside the truth's still spells, 15 clips x seeds 0-1: median 0.48
#: degrees, focal 0.8 %, against 0.06 degrees and 0.04 % with it).  With the prior last: 0.08 degrees and 0.04 %
#: (0.09 and 0.03 % with 3 iterations).  Measured on the 15 clips x seeds 0, 1, 2 (900 frames max), paired
#: against the prior throughout, mean +- standard error:  1 px proportions -0.014 +- 0.004 pp (0.208 -> 0.195),
#: per-frame MPJPE -2.5 +- 1.4 mm, whole clip -8.5 +- 4.5 mm, rotation +0.023 +- 0.022 degrees, zoom focal
#: +0.09 +- 0.08 %;  0 px -0.004 +- 0.004 pp, -1.8 +- 1.2 mm, -10.7 +- 3.4 mm, +0.035 +- 0.017 degrees;  2 px
#: -0.007 +- 0.006 pp, +0.9 +- 1.4 mm, -1.5 +- 2.9 mm, +0.023 +- 0.028 degrees. 3 iterations: the same
#: proportions, 0.4 mm more per frame, and the polish has not converged: on the built-in walk's first still
#: spell (150 frames, 1 px) the camera spans 0.0048 degrees with the prior throughout, 0.015 after 3 iterations
#: (a slow creep, 0.0005 degrees a frame), 0.0055 after 5 and 0.0052 after 10.  The prior in the sign rounds too
#: (free in the first solve only): 0.213 pp.  No prior at all: 0.195 pp, the drifting still spells above.
CAMERA_PRIOR_POLISH_ITER = 5
#: Gaussian smoothing (frames) of the tracks used for the starting pelvis depth only.
DEPTH_SMOOTH_FRAMES = 10.0
#: Prior (metres) tying the class lengths to the paper's; None = free lengths.  Measured over 6
#: synthetic clips (walk, jogging, 131_03, kick, neutral, side-skip; 300 frames, pan/tilt/zoom, 1 px),
#: proportion error mean / mean-of-max / worst, pp:  paper 0.31 / 0.68 / 0.87;  free lengths
#: 0.48 / 1.14 / 1.34;  sigma 3 mm 0.40 / 0.88 / 1.07;  1 mm 0.34 / 0.75 / 1.01;  0.3 mm 0.31 / 0.71 / 0.88.
#: The free solve is worse because it starts in per-frame depth-mirror minima (see the module
#: docstring), so the paper's lengths are kept (within a fraction of a millimetre) and the joint
#: solve adds what the paper lacks: full 3D motion and one consistent camera over the clip.
#: The clips whose maximum error stays high carry the paper's error: its shank on ``milad`` is 0.96 pp short,
#: its clavicle on ``neutral`` 0.86 and on strutting 2.04 (1 px, seed 0), and the solve keeps them (-1.01,
#: -1.05, -0.84).  Started from the *true* lengths with this prior unchanged, the solve goes most of the
#: way back (milad's shank -0.85, neutral's clavicle -0.96): it is the solved poses, not the start's
#: lengths, that hold them short.  Only with the prior centred on the truth as well do they come right
#: (milad 0.40 -> 0.11 pp mean, neutral 0.24 -> 0.10, ``acrnn_martial_04`` 0.34 -> 0.10), and even then
#: strutting's clavicle overshoots (+0.83): the data hardly determine a clavicle.
LENGTH_PRIOR_SIGMA_M = 0.001
#: The same prior's sigma (metres) *above* the paper's lengths.  The paper's length is the largest
#: per-frame lower bound, so it falls short whenever a segment never faces the camera squarely (short
#: clips, clavicles seen end-on): a length may grow past it more easily than shrink.  Measured on all
#: 15 clips (14 shared + built-in walk, 900 frames max, 30 fps, pan/tilt/zoom), proportion error mean /
#: max / mean of clip maxima, pp, at 1 px: symmetric 1 mm 0.284 / 1.84 / 0.796; above 2 mm 0.270 / 1.58 /
#: 0.760; 3 mm 0.268 / 1.45 / 0.743; 5 mm 0.270 / 1.35 / 0.749; 10 mm 0.281 / 1.30 / 0.798.  With 3 mm at
#: 0 px 0.205 -> 0.200 (max 1.86 -> 1.71) and at 2 px 0.437 -> 0.422 (max 1.90 -> 1.72); 3D error unchanged.
#: Re-measured for the clavicle alone, whose paper length falls short most (it lies across the chest, so a
#: person filmed obliquely may never show it square): 10 mm above for the clavicle, the 15 clips, proportion
#: mean / max / mean of clip maxima pp and per-frame MPJPE, before -> after:  0 px 0.200 / 1.73 / 0.622,
#: 75.1 mm -> 0.196 / 1.70 / 0.608, 74.9 mm;  1 px 0.203 / 1.02 / 0.549, 71.7 mm -> 0.193 / 1.03 / 0.497,
#: 71.3 mm;  2 px 0.304 / 1.23 / 0.857, 85.3 mm -> 0.312 / 1.25 / 0.891, 85.5 mm.  Only two short clips move
#: (strutting, neutral; 75 and 82 frames), and not consistently: strutting's clavicle goes -0.91 -> +0.12 pp
#: at 1 px but -0.69 -> +1.14 at 2 px and stays at -1.70 at 0 px, so the data do not determine it and the
#: 1 px gain is the noise's luck; not used.  Nor 30 mm (1 px 0.191 / 1.04 / 0.491, strutting's 3D error
#: 62 -> 70 mm), the shank too (0.191 / 1.03 / 0.502, 72.4 mm), or every class at 5 mm below / 10 mm above
#: in a final 3-iteration solve after the sign rounds (0.199 / 1.05 / 0.491, 71.4 mm; the same iterations
#: with this prior 0.205 / 1.03 / 0.563, 71.8 mm; in the sign rounds themselves 0.210 / 1.18 / 0.554).
LENGTH_PRIOR_SIGMA_ABOVE_M = 0.003
#: Classes of the upright chain whose length prior is loose (:data:`UPRIGHT_LENGTH_PRIOR_SIGMA_M` both
#: ways): the lower and upper spine and the head.  An upright person filmed by a roughly level camera
#: holds them nearly parallel to the image all the time, so their image lengths pin their lengths and the
#: solve's fit over all frames averages the noise, whereas the paper's length is the *largest* per-frame
#: lower bound, which the noise pushes up (at 1 px the paper's lower spine is too long on every one of the
#: 15 clips, by 0.40 pp on average, and the joint method tied to it by 0.17 pp; the limbs turn in depth,
#: where a free length trades with the depth-mirror minima).
#: The neck stays tight: as short as the hip segment, its solved length is noise-dominated.  Measured on
#: all 15 clips (14 shared + built-in walk, 900 frames max, pan/tilt/zoom), proportion error mean / max /
#: mean of clip maxima pp and mean per-frame MPJPE, before -> after (spine and head at 10 mm):
#: 0 px 0.192 / 1.72 / 0.586, 78.2 mm -> 0.197 / 1.72 / 0.586, 78.2 mm;  1 px 0.229 / 1.26 / 0.665,
#: 81.4 mm -> 0.216 / 1.18 / 0.653, 81.0 mm;  2 px 0.333 / 1.33 / 0.884, 95.2 mm -> 0.305 / 1.31 / 0.902,
#: 95.3 mm.  Variants at 1 / 2 px: with the neck too 0.214 / 1.18 and 0.297 / 1.56 pp (neck worst 0.98 ->
#: 1.56 at 2 px), the same at 5 mm 0.214 / 1.18 and 0.296 / 1.45;  the spine alone 0.219 / 1.28 (1 px);
#: adding the shank 0.216 / 1.46 or the clavicle 0.215 / 1.57 (1 px);  every class at 10 mm 0.248 / 1.61,
#: every class at 3 mm below / 6 mm above 0.236 / 1.43 (1 px).  Also tried: taking the prior's lengths from
#: a second paper run on time-smoothed tracks (Savitzky-Golay, to lower the noise in its bounds; the camera
#: and stance still from the raw run): 11 frames / cubic 0.215 / 1.34, 7 / quadratic 0.241 / 1.78 (1 px).
UPRIGHT_CLASSES = ("lower_spine", "upper_spine", "head")
UPRIGHT_LENGTH_PRIOR_SIGMA_M = 0.01
#: The solve's sigmas when static scene points join it: the camera's roll is no longer tied to the floor (a
#: handheld camera rolls, and the points see it), and the points weigh as if tracked to 0.5 px.  Chosen on the
#: tune half of ``bench/scene_bench.py`` (5 clips x 2 draws; rotation median / p95 clip degrees, zoom ratio
#: median / worst %, frame-0 focal median %, proportions mean / max pp, 3D per frame / whole clip mm): the
#: defaults 0.156 / 0.226, 0.37 / 0.91, 0.10, 0.31 / 0.83, 77 / 165;  roll 5 degrees 0.126 / 0.237, 0.37 / 0.93,
#: 0.10, 0.31 / 0.82, 80 / 161;  this (and 0.5 px) 0.117 / 0.239, 0.39 / 0.69, 0.11, 0.31 / 0.82, 79 / 155;
#: 0.25 px 0.118 / 0.240, 0.44 / 1.01, 0.08, 0.31 / 0.82, 80 / 157;  roll 5 with the camera's speed and
#: acceleration priors off 0.137 / 0.248, 0.88 / 1.95, 0.31, 0.31 / 0.85, 82 / 151;  rotation acceleration
#: 0.2 degrees, speed off 0.123 / 0.243, 0.35 / 0.77, 0.12, 0.31 / 0.85, 80 / 169.  The background's camera
#: alone: 0.113 / 0.240.
SCENE_SIGMAS = slv.Sigmas(roll_deg=5.0, static_px=0.5)
#: The paper's camera is used (start and prior) only if its frame-0 focal length is within this
#: fraction of the solve's.
PAPER_FOCAL_MATCH = 0.02


class _Ticker:
    """Progress and cancel in one call; the reported fraction never goes back (a progress bar that
    jumps backwards looks broken, and rounding in the per-step spans could do that)."""

    def __init__(self, progress, should_cancel):
        self.progress, self.should_cancel = progress, should_cancel
        self.last = 0.0

    def __call__(self, fraction: float, message: str) -> None:
        if self.should_cancel is not None and self.should_cancel():
            raise Cancelled("cancelled")
        self.last = float(min(max(fraction, self.last), 1.0))
        if self.progress is not None:
            self.progress(self.last, message)


def _check_input(tracks: Tracks) -> None:
    if tracks.n_frames < 10:
        raise InputError(f"{tracks.source or 'tracks'}: need at least 10 frames for the joint method, "
                         f"got {tracks.n_frames}")
    present = tracks.present
    if not present.any():
        raise InputError(f"{tracks.source or 'tracks'}: all joints are missing")
    for side in ("l", "r"):
        if not present[:, FEET[side]].any():
            raise InputError(f"{tracks.source or 'tracks'}: the {'left' if side == 'l' else 'right'} ankle "
                             "is never visible")


#: The paper's lengths are the largest of each segment's per-frame lower bounds: a few frames a detector
#: got wrong that the cleaning missed (a left/right exchange of 13 frames on 131_01 made the shank 9 pp
#: long) make a bone that long, and the solve's length prior keeps it.  On a detector's tracks
#: (``tracks.meta["detector_errors"]``, set by :func:`core.estimate.estimate` where the cleaning found
#: gross errors) this quantile of the bounds is taken instead.  Chosen on the tune half (15 target and
#: 15 broad cases, with and without background tracks; mean of the cases' mean / max pp, paired against
#: the maximum): 0.98 and 0.95 left a background case 10-11 pp off; 0.9 target 0.466 -> 0.413 / 1.34 ->
#: 1.21 pp, with background 0.616 -> 0.327 / 2.15 -> 1.03 (worst case 11.4 -> 2.0), broad 0.614 -> 0.384
#: and 0.478 -> 0.402, per-frame 3D -2 to -7 mm, stance -1 to -2 points; 0.8 about the same, a little
#: worse.  Clean tracks keep the paper's maximum.
DETECTOR_BOUND_QUANTILE = 0.9


#: The learnt pose prior (:mod:`core.motion_prior`) joins every depth-sign choice (:mod:`.signs_dp`,
#: :data:`.signs_dp.PRIOR_WEIGHT`); False: the geometric rules alone.  Measured: ``docs/motion_prior.md``.
USE_POSE_PRIOR = True


def pose_prior():
    """The shipped pose prior when :data:`USE_POSE_PRIOR`, else None."""
    if not USE_POSE_PRIOR:
        return None
    from ..motion_prior import load_default

    return load_default()


#: The pose lifter (:mod:`core.motion_prior.lifter`) gives every depth-sign choice a per-frame cue
#: (:data:`.signs_dp.SIGMA_CUE`); False: none.  Measured: ``docs/motion_prior.md``.
USE_POSE_LIFTER = True


#: The lifter's directions also as a term of the least-squares solve (:class:`.solver.Problem` ``bone_cue``),
#: with this unit-vector sigma; None: only in the sign choice.  Why: started from the right depth signs,
#: the solve and its sign rounds still let bones drift through the picture's plane to their mirror side
#: (with the true directions as the DP's cue, 0 px, a still camera: 0 % mirrored frames out of the DP,
#: 23 % after the solve on the built-in run).  Chosen on the tune half (``bench/prior_joint_bench.py
#: --half tune --solve-cue S``; P-MPJPE per frame and frames with a mirrored limb, moving 1 px / still
#: 0 px) as the strongest cue that keeps the proportions' mean error within 0.05 pp of the solve without
#: it (``python -m core evaluate`` on the 15 clips, 900 frames, 1 px; mean / max pp): none 83.0 mm 27.5 % /
#: 55.0 mm 16.8 %, 0.18 / 0.92;  0.3 61.8 mm 21.6 % / 52.0 mm 15.0 %;  0.15 56.4 mm 14.6 % / 53.6 mm 11.6 %;
#: 0.1 53.8 mm 10.9 % / 54.6 mm 11.6 %, 0.20 / 0.86;  0.08 54.1 mm 8.7 % / 53.3 mm 7.9 %, 0.22 / 0.98;
#: 0.06 54.9 mm 5.6 % / 53.4 mm 6.4 %, 0.24 / 1.06;  0.04 56.8 mm 3.9 % / 54.4 mm 4.9 %.  A stronger cue
#: pulls every bone's slant towards the lifter's, which regression shrinks towards the picture's plane, and
#: the lengths follow.
SOLVE_CUE_SIGMA: float | None = 0.08


#: True: the solve's cue is dropped for a bone in the frames where either of its joints was not seen (filled
#: in time, so the lifter read a guess there).  False: every bone keeps it.  On the tune half of
#: ``bench/motion_bench.py`` (5 clips x 3 draws, cleanup on; detector / background, the only scenarios with
#: unseen joints), True -> False, with a lost joint filled on its parent (:func:`.taylor.fill_missing`):
#: mirrored frames (mean over cases) 11.3 / 6.9 -> 9.6 / 6.9 %, per-frame error (mean) 63.0 / 48.6 -> 58.8 /
#: 48.7 mm, planted excess (mean) 940 / 6 -> 652 / 5 mm/s.  With each joint's own place interpolated
#: instead: detector 12.8 -> 11.6 %, 67.2 -> 66.3 mm; keeping the cue only across gaps up to 3, 8 or 20
#: frames fell between (12.5, 12.7, 12.3 %).  The lifter's reading of a filled joint still holds the bone
#: on its side of the picture better than no term at all.
SOLVE_CUE_SEEN_ONLY = False


def solve_cue(xy_filled: np.ndarray, focal_mm, image_size, sl=slice(None),
              seen: np.ndarray | None = None, fps: float | None = None) -> dict | None:
    """The solve's ``bone_cue`` for frames ``sl``: the lifter's directions for the tracks' rays at the
    starting focal length ``focal_mm`` (scalar or per frame), or None (:data:`SOLVE_CUE_SIGMA`).
    ``seen`` (F, 17) bool: the joints the tracks observed (:data:`SOLVE_CUE_SEEN_ONLY`); ``fps`` the tracks'
    frame rate, for the video lifter (:func:`lifter_cue`)."""
    if SOLVE_CUE_SIGMA is None or not USE_POSE_LIFTER:
        return None
    n = xy_filled.shape[0]
    f = np.broadcast_to(np.asarray(focal_mm, dtype=float), (n,))
    dirs = lifter_cue(unit_rays(xy_filled, f[:, None], image_size), fps)
    if SOLVE_CUE_SEEN_ONLY and seen is not None:
        from ..skeleton import SEGMENTS

        both = np.stack([seen[:, p] & seen[:, c] for p, c in SEGMENTS], axis=1)
        dirs[~both] = np.nan
    return {"dirs": dirs[sl], "sigma": SOLVE_CUE_SIGMA}


#: The lifter's directions of consecutive frames averaged with a Gaussian of this many frames' sigma
#: (:func:`core.motion_prior.lifter.smoothed_over_frames`) before any use; 0: each frame's own.  Tune half
#: of ``bench/motion_bench.py`` (5 clips x 3 draws x 4 scenarios, cleanup on; means of mirrored frames /
#: per-frame error, paper / still / detector / background): 0 3.3 / 4.4 / 12.8 / 7.2 %, 51.8 / 50.0 / 68.1
#: / 49.7 mm;  1 frame 3.0 / 4.2 / 12.8 / 6.8 %, 50.9 / 50.0 / 67.2 / 49.1 mm;  2.5 frames 3.0 / 4.3 / 12.4
#: / 6.9 %, 51.2 / 50.9 / 66.6 / 49.6 mm.  The report half: ``docs/motion_prior.md``.
LIFTER_SMOOTH_FRAMES = 1.0


def lifter_cue(rays: np.ndarray, fps: float | None = None) -> np.ndarray | None:
    """(F, 16, 3) the shipped video lifter's bone directions for ``rays`` (F, 17, 3) of consecutive frames
    at ``fps``, smoothed over :data:`LIFTER_SMOOTH_FRAMES`, when :data:`USE_POSE_LIFTER`, else None.
    Without ``fps`` (or with a lifter that reads one picture) each frame is read alone."""
    if not USE_POSE_LIFTER:
        return None
    from ..motion_prior import load_default_lifter, load_video_lifter
    from ..motion_prior.lifter import smoothed_over_frames

    global _last_cue
    lifter = load_video_lifter() if fps else load_default_lifter()
    key = (LIFTER_SMOOTH_FRAMES, fps if lifter.temporal else None)
    last = _last_cue                      # one read: another thread may replace it meanwhile
    if (last is not None and last[0] is lifter and last[1] == key
            and last[2].shape == rays.shape and np.array_equal(last[2], rays, equal_nan=True)):
        return last[3].copy()
    dirs = smoothed_over_frames(lifter.bone_directions(rays, fps), LIFTER_SMOOTH_FRAMES)
    _last_cue = (lifter, key, np.array(rays, copy=True), dirs.copy())
    return dirs


#: The last :func:`lifter_cue` (its lifter, setting, rays and answer), or None: the first sign choice and
#: the solve's term read the same rays (the tracks' at the starting focal length), and the lifter is the
#: dearest part of the cue.  Replaced whole, never changed in place.
_last_cue: tuple | None = None


def initial_state(xy_filled: np.ndarray, stance: np.ndarray, focal_mm, lengths: np.ndarray,
                  image_size, rotvec: np.ndarray | None = None, fps: float | None = None) -> np.ndarray:
    """Packed unknowns from the planted-foot camera, Taylor depth and DP signs.

    ``focal_mm`` is a scalar or per-frame (F,); ``rotvec`` (F, 3) radians
    overrides the planted-foot rotations (tests, windows).
    """
    from ..camera import rotation_matrix

    n = xy_filled.shape[0]
    f = np.broadcast_to(np.asarray(focal_mm, dtype=float), (n,))
    w = rotations_from_stance(xy_filled, stance, f, image_size) if rotvec is None else rotvec
    R = rotation_matrix(np.degrees(w))
    # Taylor's depth is the largest per-frame ratio image length / length, so 1 px of noise on a
    # 10-20 px segment biases it 5-8 % too near (measured on 6 clips), which then inflates every
    # segment's depth offset; ratios from time-smoothed tracks lower that bias to 0-5 %
    smooth = xy_filled
    if DEPTH_SMOOTH_FRAMES:
        from scipy.ndimage import gaussian_filter1d

        smooth = gaussian_filter1d(xy_filled, DEPTH_SMOOTH_FRAMES, axis=0, mode="nearest")
    depth = root_depth(smooth, f, image_size, lengths)
    rays = unit_rays(xy_filled, f[:, None], image_size)
    _, joints_i = resolve_signs(rays, lengths, depth, R, prior=pose_prior(), cue=lifter_cue(rays, fps))
    joints_0 = np.einsum("fba,fjb->fja", R, joints_i)       # R^T X_i
    return slv.pack(joints_0, w, np.log(f), lengths, stance=stance)


def paper_initialisation(tracks: Tracks, focal_mm: float | None, height_m: float, scene=None,
                         on_the_spot: bool | None = None):
    """Stance, zoom ratios, rotations and proportions from the paper's method, or None if it fails.

    The paper's pipeline (core.peng_li) is the designated starting
    point: its stance DP and spell-wise camera tracking are robust and cheap.  It runs with the
    planted ankle's creep corrected (:mod:`core.peng_li.foot_drift`): the camera it hands over
    is then closer (median rotation error over the 15 clips 0.97 -> 0.65 degrees at 1 px).
    It also adds the body cue to the moving spells' stance (:data:`core.peng_li.params.JOINT_START`), and a
    clip with no still spell starts still (:data:`STILL_START_WHEN_NO_STILL_SPELL`) unless the person stands
    on the spot (:data:`STANDING_FEET_SPEED`; such a person's zoom is read from the figure's picture,
    :data:`ZOOM_FROM_FIGURE_SMOOTH_S`) or walks (:data:`WALKING_STRIDE_S`).  The first two, measured on
    the 15 clips x seeds 0, 1, 2 (45 runs, 900 frames max), paired differences of the joint's results, mean
    +- standard error:  at 1 px the mean rotation error -0.97 +- 0.35 degrees (median of the runs' medians
    1.68 -> 0.77), stance +2.1 +- 1.0 points (90.3 -> 92.4 %), whole-clip MPJPE -50 +- 28 mm (423 -> 373),
    per-frame +1.7 +- 1.3 mm, proportions +0.001 +- 0.005 pp (0.207 -> 0.208);  at 0 px -0.79 +- 0.25
    degrees, stance +2.5 +- 0.8, whole clip -51 +- 28 mm, per frame +1.0 +- 1.5 mm, proportions -0.012 +-
    0.011 pp;  at 2 px -1.08 +- 0.35 degrees, +2.2 +- 1.0 points, -58 +- 27 mm, -1.6 +- 1.2 mm, -0.002 +-
    0.008 pp.  (Seed 0 alone, the README's tables, is the kindest of the three: 1 px rotation median 0.64
    degrees there against 1.21 and 3.22 on seeds 1 and 2 before this change.)  The paper baseline keeps its
    own settings.
    Any failure (missing module, odd input) falls back to our own 2D guesses.  ``on_the_spot``: the caller's
    :func:`standing_on_the_spot` of these tracks (None: worked out here).

    Its still window (``still_window_s``, 0.5 s, the paper's p/2) decides which zooms the joint method
    finds.  Measured for this initialisation only (15 clips, 900 frames max, 1 px; proportion mean / max
    pp, per-frame / whole-clip MPJPE, median rotation error, median zoom focal error): 0.5 s 0.203 / 1.02,
    70.1 / 392 mm, 0.64 degrees, 6.25 %;  0.4 s 0.209 / 1.14, 71.0 / 382 mm, 0.69, 3.39 %;  0.3 s 0.216 /
    1.14, 71.8 / 362 mm, 0.46, 1.12 % (``131_03``'s zoom found, 10.4 -> 1.2 %, whole clip 706 -> 455 mm; but
    01_01's proportions 0.17 / 0.81 -> 0.31 / 1.14 pp and neutral's 3D error 58 -> 77 mm);  0.3 s with the
    still threshold at 0.5 px 0.213 / 1.34, 70.9 / 361 mm, 0.64, 4.00 %, at 1.0 px 0.207 / 1.03, 69.6 /
    411 mm, 0.83, 6.33 %.  Single clips swing with the setting (the dance's zooms are found only at 0.3 s
    and 0.5 px), so 0.5 s stays: the lead is a segmentation that does not hang on one window length.
    Not the simplest two-scale rule, though: the 0.3 s window applied only inside moving runs longer than
    1.6 s (or 1.2 s) gives 0.204 / 1.02 pp, 70.2 / 395 mm, 0.64 (0.76) degrees, 6.29 %, and misses
    ``131_03``'s zoom (10.5 %).  Why the shorter window everywhere finds it is not pinned down.
    """
    try:
        from ..peng_li.params import JOINT_START
        from ..peng_li.pipeline import estimate_paper

        params = JOINT_START
        if tracks.meta.get("detector_errors"):
            params = dataclasses.replace(JOINT_START, bound_quantile=DETECTOR_BOUND_QUANTILE)
        # with a usable scene camera the paper undoes it instead of tracking one; without, no second solve
        est = estimate_paper(tracks if scene is not None else tracks.replaced(static=None), focal_mm=focal_mm,
                             height_m=height_m, params=params, scene_camera=scene)
    except Cancelled:
        raise
    except Exception:  # noqa: BLE001 - the baseline is only an initialisation
        return None
    stance = stance_codes(fr.stance for fr in est.frames)
    focal = np.array([fr.focal_mm for fr in est.frames], dtype=float)
    rot = np.radians(np.array([fr.rotvec_deg for fr in est.frames], dtype=float))
    if not (np.all(np.isfinite(focal)) and np.all(focal > 0) and np.all(np.isfinite(rot))):
        return None
    props = est.proportions_vector()
    moving = np.array([bool(fr.camera_moving) for fr in est.frames])
    warnings = [str(w) for w in est.diagnostics.get("warnings", [])]
    still_share = float(np.mean(~moving))
    standing = scene is None and feet_apart_speed(tracks.xy, tracks.fps) < STANDING_FEET_SPEED
    log_zoom = None
    if on_the_spot is None:
        on_the_spot = standing_on_the_spot(tracks)
    if scene is None and ZOOM_FROM_FIGURE_SMOOTH_S is not None and on_the_spot:
        log_zoom = figure_log_zoom(tracks.xy, tracks.fps, ZOOM_FROM_FIGURE_SMOOTH_S, focal[0], tracks.image_size)
    if log_zoom is not None and (still_share < ZOOM_STILL_SHARE_BELOW or np.ptp(log_zoom) > ZOOM_FIGURE_RANGE):
        # a person who never steps does not come nearer: the figure's picture grows only with a zoom
        focal = focal[0] * np.exp(log_zoom)
        moving = moving | (np.abs(np.gradient(log_zoom)) * tracks.fps > ZOOMING_PER_S)
    if (scene is None and STILL_START_WHEN_NO_STILL_SPELL and still_share < JOINT_START.warn_still_fraction
            and not standing and not walking(tracks)):
        # no still spell: the paper's track is the stance foot integrated over the clip, and drifts
        # (:data:`STILL_START_WHEN_NO_STILL_SPELL`); start from, and lean on, a camera standing still
        rot = np.zeros_like(rot)
        focal = np.full_like(focal, focal[0])
        warnings = [w for w in warnings if not w.startswith("camera:")] + [
            f"camera: a still camera was found in only {still_share:.0%} of the frames (no foot stays still "
            "for half a second: running, skipping); the solve starts from a camera standing still and moves it "
            "only where the tracks demand - check it against the footage"]
    return {"stance": stance, "focal_ratio": focal / focal[0], "rotvec": rot, "focal0": float(focal[0]),
            "proportions": props if np.all(np.isfinite(props)) and np.all(props > 0) else None,
            "moving": moving,
            "spells": list(est.diagnostics.get("spells", [])),
            "warnings": warnings}


def _fill_stance(stance: np.ndarray) -> np.ndarray:
    """Stance with gaps (-1) filled from the nearest labelled frame (for the camera init only)."""
    out = stance.copy()
    idx = np.nonzero(out >= 0)[0]
    if idx.size == 0:
        return np.zeros_like(out)
    near = idx[np.clip(np.searchsorted(idx, np.arange(len(out))), 0, idx.size - 1)]
    out[out < 0] = out[near[out < 0]]
    return out


def _paper_camera_fits(paper, f0: float) -> bool:
    """Whether the paper's camera track (made with its own frame-0 focal length) can start and steer a
    solve at focal ``f0``: the same within :data:`PAPER_FOCAL_MATCH`."""
    return paper is not None and abs(paper["focal0"] / f0 - 1) < PAPER_FOCAL_MATCH


def _camera_prior(paper, f0: float, sl=slice(None)):
    """The paper's camera track as a soft prior, or None.

    Sigmas :data:`PAPER_CAMERA_SIGMA` where the paper says the camera moves, and
    :data:`STILL_CAMERA_SIGMA` in its still spells, which also hold still frame to frame
    (:data:`STILL_SPEED_SIGMA`): an animator looking through a camera that should stand still must
    not see it shiver.
    """
    if not _paper_camera_fits(paper, f0):
        return None
    moving = np.asarray(paper["moving"][sl], dtype=bool)
    return {"w": paper["rotvec"][sl], "g": np.log(f0 * paper["focal_ratio"][sl]),
            "sigma_deg": np.where(moving, PAPER_CAMERA_SIGMA[0], STILL_CAMERA_SIGMA[0]),
            "sigma_log": np.where(moving, PAPER_CAMERA_SIGMA[1], STILL_CAMERA_SIGMA[1]),
            "still": ~moving, "still_sigma_deg": STILL_SPEED_SIGMA[0], "still_sigma_log": STILL_SPEED_SIGMA[1]}


def _length_prior(paper, lengths):
    """The paper's class lengths as a soft prior, or None: sigma :data:`LENGTH_PRIOR_SIGMA_M` below them,
    :data:`LENGTH_PRIOR_SIGMA_ABOVE_M` above, :data:`UPRIGHT_LENGTH_PRIOR_SIGMA_M` both ways for
    :data:`UPRIGHT_CLASSES`."""
    if paper is None or paper["proportions"] is None or LENGTH_PRIOR_SIGMA_M is None:
        return None
    below = np.full(N_CLASSES, float(LENGTH_PRIOR_SIGMA_M))
    above = np.full(N_CLASSES, float(LENGTH_PRIOR_SIGMA_ABOVE_M))
    upright = [CLASS_INDEX[c] for c in UPRIGHT_CLASSES]
    below[upright] = above[upright] = UPRIGHT_LENGTH_PRIOR_SIGMA_M
    return (np.asarray(lengths, dtype=float).copy(), below, above)


def _lm_progress(tick, span, iters: int, label: str):
    """A :func:`.solver.solve` progress callback filling ``span`` of the bar, one step per LM iteration."""
    def progress(fraction, cost):
        tick(span[0] + (span[1] - span[0]) * fraction, f"{label}: iteration {round(fraction * iters)} of {iters}")
    return progress


def signs_from_solution(x: np.ndarray, n: int, keep: int = 0, fps: float | None = None) -> np.ndarray:
    """The packed state with every depth sign chosen again by the DP (:mod:`.signs_dp`), on the
    *solved* rays, pelvis depth, camera and lengths; the first ``keep`` frames stay as they are
    (a window's frames pinned to the previous window).

    Why a second choice helps: the first DP works on the raw tracks, where near the plane parallel to
    the image 1 px of noise throws a segment's two depth candidates about by several centimetres, so
    its sign changes land frames off and whole stretches come out mirrored.  The solve then cannot
    undo a wrong sign (a segment cannot turn through that plane without leaving its ray) and settles
    in a mirror minimum.  Its answer, though, is smooth in time and consistent with one camera and one
    set of lengths, so the candidates built from it are clean and the DP's continuity terms work.
    """
    joints, w, g, lengths = slv.unpack(x, n)
    up, offset = slv.unpack_ground(x, n)
    R = slv.rot_and_left_jacobian(w)[0]
    Y = np.einsum("fab,fjb->fja", R, joints)
    rays = Y / np.linalg.norm(Y, axis=-1, keepdims=True)
    _, Y_new = resolve_signs(rays, lengths, Y[:, 0, 2], R, continuity_m=SIGN_PASS_CONTINUITY_M, prior=pose_prior(),
                             cue=lifter_cue(rays, fps))
    joints_new = np.einsum("fba,fjb->fja", R, Y_new)
    joints_new[:keep] = joints[:keep]
    return slv.pack(joints_new, w, g, lengths, up, offset)


#: The pose prior's share in the sign rounds' arbiter (:func:`signs_again`): a round is kept when the
#: solve's cost plus this weight times the prior's negative log-likelihood of the solved poses falls
#: (0: the solve's cost alone).
PRIOR_ARBITER_WEIGHT = 0.0


def _prior_energy(x: np.ndarray, n: int, keep: int = 0) -> float:
    """:data:`PRIOR_ARBITER_WEIGHT` x the pose prior's negative log-likelihood summed over the frames
    after ``keep`` (0 without the prior)."""
    prior = pose_prior()
    if prior is None or PRIOR_ARBITER_WEIGHT <= 0:
        return 0.0
    ll = prior.log_likelihood(slv.unpack(x, n)[0][keep:])
    return float(-PRIOR_ARBITER_WEIGHT * np.sum(ll[np.isfinite(ll)]))


def signs_again(prob, x: np.ndarray, rep, *, keep: int = 0, tick=None, span=None):
    """:data:`SIGN_PASSES` rounds of :func:`signs_from_solution` and a solve of
    :data:`SIGN_PASS_ITER` iterations; a round is kept only if it ends at a lower cost.

    The objective is the arbiter: started from the true poses, the solve ends 21-24 % below the cost
    it reaches from our start (walks, 300 frames, 1 px), and with the true poses' depth signs forced
    onto our solution it ends within about 2 % of that, so a lower cost means fewer mirrored stretches.
    ``tick`` cancels; with ``span`` it also reports progress in that part of the bar.
    """
    n = prob.film.shape[0]
    energy = _prior_energy(x, n, keep)
    for k in range(SIGN_PASSES):
        progress = None
        if tick is not None and span is not None:
            lo = span[0] + (span[1] - span[0]) * k / SIGN_PASSES
            hi = span[0] + (span[1] - span[0]) * (k + 1) / SIGN_PASSES
            tick(lo, f"depth signs: chosen again, round {k + 1} of {SIGN_PASSES}")
            progress = _lm_progress(tick, (lo, hi), SIGN_PASS_ITER, f"joint solve after sign round {k + 1}")
        x2, rep2 = slv.solve(prob, signs_from_solution(x, n, keep, prob.fps), max_iter=SIGN_PASS_ITER,
                             should_cancel=None if tick is None else tick.should_cancel, progress=progress)
        energy2 = _prior_energy(x2, n, keep)
        if not rep2.cost + energy2 < rep.cost + energy:
            break
        x, rep, energy = x2, rep2, energy2
    return x, rep


def _polishes(cprior) -> bool:
    """Whether the camera prior ``cprior`` comes in as a final polish (:data:`CAMERA_PRIOR_POLISH_ITER`)."""
    return cprior is not None and CAMERA_PRIOR_POLISH_ITER > 0


def _solve_camera_prior(cprior):
    """The camera prior of the solves before the polish: none when ``cprior`` is kept for the polish."""
    return None if _polishes(cprior) else cprior


def _polish_with_camera_prior(prob, x: np.ndarray, rep, cprior, tick, span=None):
    """:data:`CAMERA_PRIOR_POLISH_ITER` iterations with the camera prior ``cprior`` and the solved lengths
    held; ``(x, rep, prob)`` as they were when there is nothing to do.  With ``span`` it reports progress
    in that part of the bar."""
    if not _polishes(cprior):
        return x, rep, prob
    n = prob.film.shape[0]
    prob = dataclasses.replace(prob, camera_prior=cprior, fixed_lengths=slv.unpack(x, n)[3].copy())
    progress = None
    if span is not None:
        tick(span[0], "camera: the paper's track as a prior")
        progress = _lm_progress(tick, span, CAMERA_PRIOR_POLISH_ITER, "camera polish")
    x, rep = slv.solve(prob, x, max_iter=CAMERA_PRIOR_POLISH_ITER, should_cancel=tick.should_cancel,
                       progress=progress)
    return x, rep, prob


def walking(tracks: Tracks) -> bool:
    """Whether the person walks: a stride of :data:`WALKING_STRIDE_S` or longer in the ankles' picture
    (:func:`.stance.stride_period`), repeating with a correlation of :data:`WALKING_STRIDE_CORRELATION` or more,
    and no step shorter than :data:`RUNNING_STEP_S` (:func:`.stance.step_period`: a run whose stride reads
    doubled, left and right exchanged every other stride in the tracks)."""
    if WALKING_STRIDE_S is None:
        return False
    stride, corr = stride_period(tracks.xy, tracks.fps)
    if not (stride >= WALKING_STRIDE_S and corr >= WALKING_STRIDE_CORRELATION):
        return False                    # no walk's stride: the step, read only to veto one, is not needed
    return not step_period(tracks.xy, tracks.fps)[0] < RUNNING_STEP_S


def standing_on_the_spot(tracks: Tracks) -> bool:
    """Whether the person never steps: the ankles move apart in the picture slower than
    :data:`STANDING_FEET_SPEED` (:func:`.stance.feet_apart_speed`), their 90th percentile over frames below
    :data:`ZOOM_FEET_SPEED_P90`, and the hips move over the feet slower than :data:`ZOOM_STILL_HIPS_SPEED`
    (:func:`.stance.hips_over_feet_speed`), all in the figure's spread per second."""
    return bool(feet_apart_speed(tracks.xy, tracks.fps) < STANDING_FEET_SPEED
                and feet_apart_speed(tracks.xy, tracks.fps, quantile=0.9) < ZOOM_FEET_SPEED_P90
                and hips_over_feet_speed(tracks.xy, tracks.fps) < ZOOM_STILL_HIPS_SPEED)


def _standing_term(on_the_spot: bool) -> dict | None:
    """The solve's term for a person standing on the spot (:func:`standing_on_the_spot`, read once per estimate;
    :data:`STANDING_HIPS_ACCEL_MS2`), else None.  Its
    feet are found on the first solve's motion (:func:`_standing_feet`; in a clip solved in windows,
    :data:`SINGLE_MAX`, on each window's)."""
    if STANDING_HIPS_ACCEL_MS2 is None or not on_the_spot:
        return None
    return {"accel_ms2": STANDING_HIPS_ACCEL_MS2, "feet": None}


#: The first solve's motion is smoothed over this many seconds (a Gaussian's sigma) before a standing
#: person's planted feet are found on it (:data:`STANDING_HIPS_ACCEL_MS2`); None: as solved.
STANDING_FEET_SMOOTH_S: float | None = 0.1


def _standing_feet(joints: np.ndarray, world: np.ndarray, fps: float, height_m: float) -> np.ndarray:
    """(F, 2) bool, the frames where a standing person's (left, right) ankle is planted: the foot lock's contacts
    (:func:`core.motion_cleanup.contacts.detect_contacts`) on ``joints`` (frame-0 camera axes) taken to the world
    by ``world`` (``world_from_cam0``), smoothed first (:data:`STANDING_FEET_SMOOTH_S`) so that a detector's
    frame-to-frame jitter does not read as steps."""
    joints_world = joints @ world[:3, :3].T + world[:3, 3]
    if STANDING_FEET_SMOOTH_S:
        from scipy.ndimage import gaussian_filter1d

        joints_world = gaussian_filter1d(joints_world, STANDING_FEET_SMOOTH_S * fps, axis=0, mode="nearest")
    return detect_contacts(joints_world, fps, height_m)


def run_solve(film, xy_filled, stance, focal, lengths, *, tracks, height_m, focal_prior, max_iter=None,
              tick=None, x0=None, rotvec=None, camera_prior=None, length_prior=None, span=(0.3, 0.9), static=None,
              bone_cue=None, standing=None):
    """One full solve (initialisation + LM) for a fixed stance labelling.

    ``span``: the part of the overall progress bar this solve fills, one step per LM iteration
    (the solve is most of the run: without this the bar would sit still for seconds).
    """
    prob = slv.Problem(length_prior=length_prior, film=film, mm_per_px=mm_per_pixel(tracks.image_size),
                       sigmas=_sigmas(static),
                       fps=tracks.fps, height_m=height_m,
                       stance=stance, focal_prior_mm=None if focal_prior is None else focal_prior[0],
                       focal_prior_sigma=None if focal_prior is None else focal_prior[1],
                       camera_prior=camera_prior, static=static, bone_cue=bone_cue,
                       standing=standing)
    if x0 is None:
        x0 = initial_state(xy_filled, _fill_stance(stance), focal, lengths, tracks.image_size, rotvec, fps=tracks.fps)
    iters = SOLVE_ITER if max_iter is None else max_iter
    progress = None if tick is None else _lm_progress(tick, span, iters, "joint solve")
    x, rep = slv.solve(prob, x0, max_iter=iters, should_cancel=None if tick is None else tick.should_cancel,
                       progress=progress)
    return x, rep, prob


def estimate_joint(tracks: Tracks, *, focal_mm: float | None = None, height_m: float = 1.75,
                   progress=None, should_cancel=None) -> Estimate:
    """Lengths, camera and 3D motion from all frames at once (see module docstring)."""
    tick = _Ticker(progress, should_cancel)
    _check_input(tracks)
    tick(0.0, "preparing tracks")
    n = tracks.n_frames
    film = pixels_to_film(tracks.xy, tracks.image_size)
    xy_filled = fill_missing(tracks.xy)
    warnings: list[str] = []

    scene = None
    assumed = focal_mm is not None and bool(tracks.meta.get(META_FOCAL_ASSUMED))
    if tracks.static is not None:
        tick(0.01, "camera from the background tracks")
        scene = solve_scene_camera(tracks, **focal_arguments(tracks, focal_mm))
        warnings.extend(_scene_warnings(tracks, scene))
    use_scene = scene is not None and scene.usable

    tick(0.02, "paper method (initialisation)")
    on_the_spot = standing_on_the_spot(tracks)
    paper = paper_initialisation(tracks, focal_mm, height_m, scene if use_scene else None, on_the_spot=on_the_spot)
    if paper is not None:
        if not use_scene:
            # the paper's camera is this method's start and prior, so its warnings about it hold here too
            warnings.extend(w for w in paper["warnings"] if w.startswith("camera:"))
        stance = paper["stance"]
        ratio = paper["focal_ratio"]
        props = paper["proportions"] if paper["proportions"] is not None else DEFAULT_PROPORTIONS
    else:
        warnings.append("paper method failed; initialised from our own 2D stance guess")
        stance = stance_from_2d(xy_filled)
        ratio = np.ones(n)
        props = DEFAULT_PROPORTIONS
    lengths = class_lengths_for_height(props, height_m)

    tick(0.08, "focal length")
    if use_scene:
        # the background's focal length, determined or not, is the best there is: its points carry it into
        # the solve (a looser one is said in the warnings and the diagnostics)
        calib = Calibration(focal_mm=float(scene.focal_mm[0]), determined=scene.focal_determined, warnings=[])
    else:
        calib = self_calibrate(film, xy_filled, _fill_stance(stance), lengths, ratio, tracks=tracks,
                               height_m=height_m, focal_hint=focal_mm, tick=tick)
        if assumed:
            # a phone's main camera (:data:`META_FOCAL_ASSUMED`): held like the default, and not called determined
            calib = dataclasses.replace(calib, determined=False)
    if use_scene:
        ratio = scene.focal_mm / scene.focal_mm[0]
    f0 = calib.focal_mm
    warnings.extend(calib.warnings)
    if focal_mm is not None and not assumed:
        prior = (float(focal_mm), None)              # the hint is a prior with the default sigma
    elif not calib.determined:
        prior = (f0, UNDETERMINED_FOCAL_SIGMA)       # undetermined: keep the assumed value, said in a warning
    else:
        prior = None
    rotvec = paper["rotvec"] if _paper_camera_fits(paper, f0) else None
    static = None
    if use_scene:
        # the scene's camera replaces the paper's as start and prior, and its points join the solve
        rotvec = np.radians(scene.rotvec_deg)
        static = _static_term(tracks, scene)
        if focal_mm is None:
            prior = None

    tick(0.3, "joint solve")
    cue = solve_cue(xy_filled, f0 * ratio, tracks.image_size, seen=np.isfinite(tracks.xy).all(axis=-1),
                    fps=tracks.fps)
    standing = _standing_term(on_the_spot)
    if n > SINGLE_MAX:
        x, rep, prob, stance3 = _solve_windows(film, xy_filled, stance, f0 * ratio, lengths, rotvec, tracks=tracks,
                                               height_m=height_m, prior=prior, tick=tick,
                                               paper=None if use_scene else paper, f0=f0, static=static,
                                               length_paper=paper, bone_cue=cue, standing=standing)
        return _to_estimate(tracks, prob, x, stance if paper is not None else stance3, height_m, calib,
                            warnings, rep, paper, scene, on_the_spot)
    cprior = None if use_scene else _camera_prior(paper, f0)
    lprior = _length_prior(paper, lengths)
    mid, end = (0.6, 0.9) if paper is not None else (0.5, 0.7)
    x, rep, prob = run_solve(film, xy_filled, stance, f0 * ratio, lengths, tracks=tracks, height_m=height_m,
                             focal_prior=prior, tick=tick, rotvec=rotvec,
                             camera_prior=_solve_camera_prior(cprior), length_prior=lprior,
                             span=(0.3, mid), static=static, bone_cue=cue, standing=standing)
    if (paper is not None and STANCE_FROM_FIRST_SOLVE) or standing is not None:
        # the sign rounds hold the feet decided on the first solve's motion (:data:`STANCE_FROM_FIRST_SOLVE`),
        # and a person standing on the spot each foot where that motion has it planted
        joints1 = slv.unpack(x, n)[0]
        world, _, stance1 = _floor_and_stance(joints1, stance, tracks.fps, height_m,
                                              _image_speed(prob, x, use_scene, tracks.fps, height_m))
        if paper is not None and STANCE_FROM_FIRST_SOLVE:
            stance = stance1
        if standing is not None:
            standing = {**standing, "feet": _standing_feet(joints1, world, tracks.fps, height_m)}
        prob = dataclasses.replace(prob, stance=stance, standing=standing)
        rep = dataclasses.replace(rep, cost=float(slv.residuals(prob, x, with_jac=False)))
    polish = end - 0.08 if _polishes(cprior) else end
    x, rep = signs_again(prob, x, rep, tick=tick, span=(mid, polish))
    x, rep, prob = _polish_with_camera_prior(prob, x, rep, cprior, tick, span=(polish, end))
    if paper is not None:
        # measured: the paper's stance beats our 3D decision from ankle speeds alone on the solved joints
        # (15 clips, 1 px: higher or equal on 14, jogging 69 % vs 18 %, side-skip 68 % vs 43 %, the dance 67 %
        # vs 61 %, neutral 100 % vs 95 %; the kick 90.0 % vs 90.8 %), so no second solve on that decision; the
        # slow-and-low decision took over above, and decides the stance reported (``_to_estimate``)
        tick(0.9, "ground and results")
        return _to_estimate(tracks, prob, x, stance, height_m, calib, warnings, rep, paper, scene, on_the_spot)
    tick(0.7, "stance from 3D")
    joints = slv.unpack(x, n)[0]
    stance3 = stance_from_3d(joints, tracks.fps, height_m)
    if np.mean(stance3 != stance) > 0.01:
        x, rep, prob = run_solve(film, xy_filled, stance3, None, None, tracks=tracks, height_m=height_m,
                                 focal_prior=prior, tick=tick, x0=x, max_iter=10, camera_prior=cprior, span=(0.7, 0.9),
                                 static=static, bone_cue=cue, standing=standing)
        joints = slv.unpack(x, n)[0]
        stance3 = stance_from_3d(joints, tracks.fps, height_m)
    tick(0.9, "ground and results")
    return _to_estimate(tracks, prob, x, stance3, height_m, calib, warnings, rep, None, scene, on_the_spot)


def _scene_warnings(tracks: Tracks, scene) -> list[str]:
    """What the joint method says about the background tracks it was given.  "background:" notes inform;
    the scene camera's own "camera:" warnings (a translating camera) are doubts the self-check flags."""
    if scene is None:
        return [f"background: the {tracks.static.n_points} background track(s) are too few or too short to "
                "solve the camera (4 points, 3 in a frame, needed); the camera comes from the person alone"]
    out = list(scene.warnings)
    if not scene.translating and not scene.usable:
        out.append(f"background: the background tracks cover only {100 * scene.solved.mean():.0f} % of the "
                   "frames; the camera comes from the person alone")
    elif scene.usable and not scene.focal_determined:
        out.append(f"focal length not determined by the background tracks: {scene.focal_reason}; their estimate "
                   f"({scene.focal_mm[0]:.1f} mm) is used - give --focal-mm if you know it")
    return out


def _sigmas(static) -> slv.Sigmas:
    """The solve's sigmas: with static points, :data:`SCENE_SIGMAS`."""
    return slv.Sigmas() if static is None else SCENE_SIGMAS


def _static_term(tracks: Tracks, scene) -> dict:
    """The solver's static-point term: film positions of the points kept, their directions."""
    film = pixels_to_film(tracks.static.xy, tracks.image_size)
    film[:, ~scene.used_points] = np.nan
    return {"film": film, "dirs": scene.directions}


def _solve_windows(film, xy_filled, stance, focal, lengths, rotvec, *, tracks, height_m, prior, tick, paper, f0,
                   static=None, length_paper=None, bone_cue=None, standing=None):
    """Windowed solve for long clips (see :data:`SINGLE_MAX`); returns the stitched packed state.

    ``paper`` gives the camera prior (None: none), ``length_paper`` the length prior; ``static`` the
    static-point term, cut per window."""
    n = film.shape[0]
    mm_px = mm_per_pixel(tracks.image_size)
    if rotvec is None:   # one chained camera track for the whole clip, so windows agree on frame 0's axes
        rotvec = rotations_from_stance(xy_filled, _fill_stance(stance), focal, tracks.image_size)
    joints = np.zeros((n, 17, 3))
    w = np.zeros((n, 3))
    g = np.zeros(n)
    fixed = None
    start = 0
    rep = None
    up = offset = None
    while start < n - OVERLAP:
        stop = min(n, start + WINDOW)
        if n - stop < WINDOW // 4:          # do not leave a tiny last window
            stop = n
        sl = slice(start, stop)
        tick(0.3 + 0.6 * start / n, f"joint solve: frames {start}-{stop - 1}")
        cprior = _camera_prior(paper, f0, sl)
        anchors = None
        if start > 0:
            k = np.arange(OVERLAP)
            anchors = {"frames": k, "w": w[start:start + OVERLAP], "g": g[start:start + OVERLAP],
                       "x": joints[start:start + OVERLAP]}
        prob = slv.Problem(film=film[sl], mm_per_px=mm_px, fps=tracks.fps, height_m=height_m, stance=stance[sl],
                           sigmas=_sigmas(static),
                           focal_prior_mm=None if (prior is None or start > 0) else prior[0],
                           focal_prior_sigma=None if prior is None else prior[1], fixed_lengths=fixed,
                           anchors=anchors, camera_prior=_solve_camera_prior(cprior),
                           length_prior=_length_prior(length_paper, lengths) if fixed is None else None,
                           static=None if static is None else {"film": static["film"][sl], "dirs": static["dirs"]},
                           bone_cue=None if bone_cue is None else {**bone_cue, "dirs": bone_cue["dirs"][sl]},
                           standing=standing)
        x0 = initial_state(xy_filled[sl], _fill_stance(stance[sl]), focal[sl], lengths if fixed is None else fixed,
                           tracks.image_size, rotvec[sl], fps=tracks.fps)
        if start > 0:
            # start from the previous window where they overlap (the anchors pin it there)
            j0, w0, g0, _ = slv.unpack(x0, stop - start)
            j0[:OVERLAP], w0[:OVERLAP], g0[:OVERLAP] = anchors["x"], anchors["w"], anchors["g"]
            x0 = slv.pack(j0, w0, g0, fixed, up, offset)
        x, rep = slv.solve(prob, x0, max_iter=SOLVE_ITER, should_cancel=tick.should_cancel)
        if standing is not None:
            # as in a single solve: the sign round and the polish hold each foot where this window stands
            jw = slv.unpack(x, stop - start)[0]
            world = world_from_cam0(jw, stance[sl], height_m)[0]
            prob = dataclasses.replace(prob, standing={**standing, "feet": _standing_feet(jw, world, tracks.fps,
                                                                                          height_m)})
            rep = dataclasses.replace(rep, cost=float(slv.residuals(prob, x, with_jac=False)))
        x, rep = signs_again(prob, x, rep, keep=OVERLAP if start > 0 else 0, tick=tick)
        x, rep, _ = _polish_with_camera_prior(prob, x, rep, cprior, tick)
        jw, ww, gw, lw = slv.unpack(x, stop - start)
        if fixed is None:
            fixed = lw.copy()
        up, offset = slv.unpack_ground(x, stop - start)
        joints[sl], w[sl], g[sl] = jw, ww, gw
        if stop >= n:
            break
        start = stop - OVERLAP
    x_all = slv.pack(joints, w, g, fixed, up, offset)
    prob_all = slv.Problem(film=film, mm_per_px=mm_px, fps=tracks.fps, height_m=height_m, stance=stance,
                           standing=standing)
    stance3 = stance_from_3d(joints, tracks.fps, height_m)
    return x_all, rep, prob_all, stance3


def _image_speed(prob, x: np.ndarray, use_scene: bool, fps: float, height_m: float):
    """The ankles' camera-undone image speeds for the stance (:func:`.stance.undone_ankle_speeds`) when the
    camera comes from background points; None from the person alone (the solve's own camera: no help)."""
    if not use_scene:
        return None
    joints, w, g, _ = slv.unpack(x, prob.film.shape[0])
    return undone_ankle_speeds(prob.film, joints, w, np.exp(g), fps, height_m)


def _floor_and_stance(joints: np.ndarray, stance: np.ndarray, fps: float, height_m: float, image_speed=None,
                      camera_known: bool = False):
    """``world_from_cam0`` fitted with the stance the solve used, its warnings, and the stance decided
    on the motion in those world axes (:func:`.stance.stance_from_world`, the slow and low foot; with
    ``image_speed``, also still in the picture).

    The floor is not fitted again to the new stance: that stance picks the lower ankle *given* this
    floor, and the refit drifts (15 clips, 1 px: angle to the true up median 2.18 -> 2.19 degrees,
    mean 3.65 -> 5.01; side-skip 7.0 -> 17.1, ``131_03`` 5.6 -> 10.3).
    """
    world, warnings = world_from_cam0(joints, stance, height_m, camera_known)
    return world, warnings, stance_from_world(joints @ world[:3, :3].T + world[:3, 3], fps, height_m,
                                              image_speed)


def _to_estimate(tracks, prob, x, stance, height_m, calib, warnings, rep, paper=None, scene=None,
                 on_the_spot: bool | None = None) -> Estimate:
    n = tracks.n_frames
    joints, w, g, L = slv.unpack(x, n)
    R = slv.rot_and_left_jacobian(w)[0]
    rv = rotvec_deg(R)
    focal = np.exp(g)
    # per-frame reprojection error (px) of observed joints
    Y = np.einsum("fab,fjb->fja", R, joints)
    proj = focal[:, None, None] * Y[..., :2] / Y[..., 2:3]
    err = np.linalg.norm(proj - prob.film, axis=-1) / prob.mm_per_px
    seen = np.isfinite(err)
    count = seen.sum(axis=1)
    # a frame where nothing was seen has no error (None below), and must not make numpy warn
    reproj = np.where(count > 0, np.where(seen, err, 0.0).sum(axis=1) / np.maximum(count, 1), np.nan)
    # camera moving: rotation or zoom rate above a small threshold
    rate = np.zeros(n)
    dz = np.zeros(n)
    if n > 1:
        step = np.degrees(np.linalg.norm(np.diff(w, axis=0), axis=1))
        rate[1:] = step
        rate[0] = step[0]
        dzs = np.abs(np.diff(g))
        dz[1:] = dzs
        dz[0] = dzs[0]
    moving = (rate > MOVING_DEG_PER_FRAME) | (dz > MOVING_ZOOM_PER_FRAME)
    use_scene = scene is not None and scene.usable
    if paper is not None and not use_scene:
        # the paper's spell segmentation flags moving frames better than thresholds on our solved
        # camera, whose small frame-to-frame jitter crosses them (measured, 15 clips at 1 px: moving-frame
        # accuracy paper 36-96 %, ours from the rates 37-91 %, lower on 12 of 15 clips, higher on 2)
        moving = paper["moving"]
    scale = joints[0, 0, 2] / joints[:, 0, 2]
    world, ground_warn, stance = _floor_and_stance(joints, stance, tracks.fps, height_m,
                                                   _image_speed(prob, x, use_scene, tracks.fps, height_m),
                                                   camera_known=use_scene)
    warnings = list(warnings) + ground_warn
    frames = []
    for i in range(n):
        frames.append(FrameEstimate(
            stance=None if stance[i] == NONE else ("l" if stance[i] == 0 else "r"),
            camera_moving=bool(moving[i]),
            rotvec_deg=tuple(float(v) for v in rv[i]),
            focal_mm=float(focal[i]),
            scale=float(scale[i]),
            joints_3d=joints[i].tolist(),
            reprojection_px=None if not np.isfinite(reproj[i]) else float(reproj[i]),
        ))
    diagnostics = {
        "world_from_cam0": world.tolist(),
        "focal_determined": bool(calib.determined),
        "focal_curve": calib.curve,
        "warnings": warnings,
        "solver": {"cost": rep.cost, "iterations": rep.iterations, "converged": rep.converged},
        "class_lengths_m": [float(v) for v in L],
        "standing_on_the_spot": standing_on_the_spot(tracks) if on_the_spot is None else on_the_spot,
    }
    if paper is not None and not use_scene:
        # the camera_moving flags above are the paper's spells (see the comment there): say which
        diagnostics["spells"] = paper["spells"]
    if tracks.static is not None:
        diagnostics["scene_camera"] = None if scene is None else scene.summary()
    return Estimate(method="joint", proportions=proportions_dict(L), focal_mm=float(focal[0]), frames=frames,
                    height_m=height_m, diagnostics=diagnostics)
