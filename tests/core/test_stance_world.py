"""The stance reported by the joint method: the slow, low foot of the solved motion (stance_from_world)."""

import numpy as np

from core.joint_solve.stance import stance_codes, stance_from_world
from core.skeleton import FEET, N_JOINTS
from core.synthetic.motion import load_motion
from core.synthetic.synth import synthesize


def _world(truth) -> np.ndarray:
    m = np.asarray(truth.world_from_cam0, dtype=float)
    return truth.joints_3d @ m[:3, :3].T + m[:3, 3]


def test_true_motion_gives_the_true_stance_and_swapped_feet_do_not():
    motion = load_motion("builtin:walk", max_frames=240, fps=30.0)
    _, truth = synthesize(motion, noise_px=0.0, seed=0)
    world = _world(truth)
    clear = np.asarray(truth.stance_clear, dtype=bool)
    true = stance_codes(truth.stance)
    got = stance_from_world(world, 30.0, truth.height_m)
    assert set(np.unique(got)) <= {0, 1}
    assert np.mean(got[clear] == true[clear]) >= 0.97
    swapped = world.copy()
    swapped[:, [FEET["l"], FEET["r"]]] = world[:, [FEET["r"], FEET["l"]]]
    assert np.mean(stance_from_world(swapped, 30.0, truth.height_m)[clear] == true[clear]) <= 0.03


def test_the_low_foot_wins_over_a_still_raised_one():
    """Standing on the left foot, whose ankle creeps 10 cm/s (a heel lifting), with the right ankle held
    still 10 cm up: the stiller foot is the raised one, so speed alone would pick it."""
    n = 30
    joints = np.zeros((n, N_JOINTS, 3))
    joints[:, FEET["l"]] = [0.0, 0.1, 0.08]
    joints[:, FEET["l"], 0] = np.arange(n) * 0.1 / 30.0
    joints[:, FEET["r"]] = [0.0, -0.1, 0.18]
    assert np.all(stance_from_world(joints, 30.0, 1.75) == 0)
    swapped = joints.copy()
    swapped[:, [FEET["l"], FEET["r"]]] = joints[:, [FEET["r"], FEET["l"]]]
    assert np.all(stance_from_world(swapped, 30.0, 1.75) == 1)


def test_a_moving_foot_is_not_planted_even_when_lower():
    """The right ankle sweeps along the floor 1 cm below the left, which stands: the left is planted."""
    n = 30
    joints = np.zeros((n, N_JOINTS, 3))
    joints[:, FEET["l"]] = [0.0, 0.1, 0.09]
    joints[:, FEET["r"], 0] = np.linspace(-0.5, 0.5, n)     # 1.5 m/s
    joints[:, FEET["r"], 2] = 0.08
    assert np.all(stance_from_world(joints, 30.0, 1.75) == 0)


def test_short_clips():
    assert stance_from_world(np.zeros((2, N_JOINTS, 3)), 30.0, 1.75).tolist() == [0, 0]


def test_with_the_camera_undone_a_planted_ankle_stands_still_in_the_picture():
    """undone_ankle_speeds: on a handheld walk's exact tracks, the true camera undone leaves the planted ankle
    still (the stance term the joint method adds when background points give the camera); taking the camera
    for still instead mixes the feet up on a sixth of the frames."""
    from core.camera import pixels_to_film
    from core.joint_solve.stance import undone_ankle_speeds
    from core.synthetic.footage_sim import HandheldOperator

    motion = load_motion("builtin:walk", max_frames=240, fps=30.0)
    tracks, truth = synthesize(motion, noise_px=0.0, seed=3, focal_mm=35.0, operator=HandheldOperator())
    film = pixels_to_film(tracks.xy, tracks.image_size)
    idx = np.flatnonzero(np.asarray(truth.stance_clear, dtype=bool))
    true = stance_codes(truth.stance)[idx]

    def planted_and_swing(rotvec_rad, focal_mm):
        sp = undone_ankle_speeds(film, truth.joints_3d, rotvec_rad, focal_mm, 30.0, truth.height_m)
        return sp[idx, true], sp[idx, 1 - true]

    planted, swing = planted_and_swing(np.radians(truth.rotvec_deg), truth.focal_mm)
    assert np.percentile(planted, 90) < 0.02 and np.median(swing) > 0.3       # body heights per second
    assert np.mean(planted < swing) > 0.98
    planted, swing = planted_and_swing(np.zeros((len(film), 3)), np.full(len(film), truth.focal_mm[0]))
    assert np.mean(planted < swing) < 0.9
