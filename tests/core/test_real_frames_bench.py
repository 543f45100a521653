"""The real-photograph bench's own arithmetic: joint orders, the depth-sign tally and the mirrored limbs
(the photographs themselves are research data that stays outside the repository)."""

import numpy as np

from bench.real_frames_bench import (
    CLEAR_SLANT,
    H36M_ORDER,
    MPI_INF_3DHP_ORDER,
    limb_depth_signs,
    mirrored_bones,
)
from core.motion_prior.features import bone_vectors
from core.skeleton import JOINT_INDEX, SEGMENTS
from core.synthetic.motion import load_motion


def _pose():
    joints = load_motion("builtin:walk", fps=30.0).joints[10]
    return joints - joints[0] + np.array([0.0, 0.0, 4.0])


def test_joint_orders_take_every_joint_once():
    assert sorted(H36M_ORDER) == list(range(17))
    assert sorted(MPI_INF_3DHP_ORDER) == list(range(17))


def test_the_depth_sign_tally_counts_clear_bones_and_wrong_answers():
    truth = _pose()
    k = next(i for i, (p, c) in enumerate(SEGMENTS) if c == JOINT_INDEX["l_elbow"])
    p, c = SEGMENTS[k]
    truth[c] = truth[p] + np.array([0.1, 0.1, 0.25])          # the upper arm clearly towards the back
    bones = bone_vectors(truth)
    clear = sum(abs(b[2]) > CLEAR_SLANT * np.linalg.norm(b) for i, b in enumerate(bones)
                if SEGMENTS[i][1] in [JOINT_INDEX[n] for n in ("l_elbow", "l_wrist", "r_elbow", "r_wrist",
                                                                 "l_knee", "l_ankle", "r_knee", "r_ankle")])
    flipped = bones.copy()
    flipped[k, 2] *= -1.0
    tally = limb_depth_signs(truth, {"right": bones, "one flipped": flipped, "no answer": None})
    assert tally["right"] == (clear, clear)
    assert tally["one flipped"] == (clear - 1, clear)
    assert tally["no answer"] == (0, clear)


def test_a_forearm_mirrored_in_depth_is_named():
    truth = _pose()
    e, w = JOINT_INDEX["r_elbow"], JOINT_INDEX["r_wrist"]
    truth[w] = truth[e] + np.array([0.05, 0.0, -0.24])        # the forearm pointing at the camera
    est = truth.copy()
    est[w] = truth[e] + np.array([0.05, 0.0, 0.24])           # and away from it
    assert mirrored_bones(est, truth) == ["r_wrist"]
    assert mirrored_bones(truth, truth) == []
