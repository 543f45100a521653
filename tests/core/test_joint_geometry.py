"""Perspective Taylor construction, the sign DP and the floor plane (core.joint_solve)."""

import itertools

import numpy as np
import pytest

from core.joint_solve import ground, signs_dp, taylor
from core.joint_solve.stance import stance_codes
from core.skeleton import FEET, JOINT_INDEX, SEGMENT_CLASS, SEGMENTS, segment_lengths_from_classes
from core.synthetic.motion import load_motion
from core.synthetic.synth import synthesize


@pytest.fixture(scope="module")
def clip():
    motion = load_motion("builtin:walk", max_frames=60, fps=30.0)
    tracks, truth = synthesize(motion, kinds=("pan", "tilt", "zoom"), noise_px=0.0, seed=3, continuous=True)
    return tracks, truth


def _true_signs(rays, joints_cam, lengths):
    seg_len = np.asarray(lengths)[list(SEGMENT_CLASS)]
    signs = np.zeros((rays.shape[0], len(SEGMENTS)))
    for s, (p, c) in enumerate(SEGMENTS):
        near, far, _ = taylor.child_candidates(joints_cam[:, p], rays[:, c], seg_len[s])
        d_far = np.linalg.norm(far - joints_cam[:, c], axis=-1)
        d_near = np.linalg.norm(near - joints_cam[:, c], axis=-1)
        signs[:, s] = np.where(d_far < d_near, 1.0, -1.0)
    return signs


def test_both_roots_lie_on_the_ray_at_the_segment_length():
    rng = np.random.default_rng(0)
    parent = rng.normal(size=(50, 3)) + np.array([0, 0, 6.0])
    ray = rng.normal(size=(50, 3)) * 0.05 + np.array([0, 0, 1.0])
    ray /= np.linalg.norm(ray, axis=-1, keepdims=True)
    length = 5.0
    near, far, short = taylor.child_candidates(parent, ray, length)
    ok = short == 0
    assert ok.sum() > 10
    for cand in (near, far):
        assert np.allclose(np.linalg.norm(cand[ok] - parent[ok], axis=-1), length)
        assert np.allclose(np.cross(cand, ray), 0.0, atol=1e-9)
    assert np.all(far[ok, 2] >= near[ok, 2])


def test_reconstruct_with_true_signs_is_exact(clip):
    tracks, truth = clip
    cam = truth.joints_camera()
    rays = taylor.unit_rays(tracks.xy, truth.focal_mm[:, None], tracks.image_size)
    signs = _true_signs(rays, cam, truth.class_lengths_m)
    rec = taylor.reconstruct(rays, truth.class_lengths_m, cam[:, 0, 2], signs)
    assert np.abs(rec - cam).max() < 1e-6


def test_viterbi_matches_brute_force():
    rng = np.random.default_rng(1)
    n, s = 6, 4
    for _ in range(5):
        unary = rng.random((n, s)) * 3
        pair = rng.random((n - 1, s, s)) * 3
        path = signs_dp.viterbi(unary, pair)

        def cost(seq, unary=unary, pair=pair):
            return unary[np.arange(n), seq].sum() + sum(pair[i, seq[i], seq[i + 1]] for i in range(n - 1))

        best = min(itertools.product(range(s), repeat=n), key=lambda q: cost(np.array(q)))
        assert cost(path) == pytest.approx(cost(np.array(best)))


def test_second_order_viterbi_matches_brute_force():
    rng = np.random.default_rng(2)
    sigma = 0.7
    for n, s in ((3, 3), (5, 3), (6, 2), (4, 4)):
        unary = rng.random((n, s)) * 3
        pair = rng.random((n - 1, s, s)) * 3
        vecs = rng.normal(size=(s, n, 2))

        def cost(seq, unary=unary, pair=pair, vecs=vecs, n=n):
            c = unary[np.arange(n), seq].sum() + sum(pair[i, seq[i], seq[i + 1]] for i in range(n - 1))
            acc = [vecs[seq[i - 1], i - 1] - 2 * vecs[seq[i], i] + vecs[seq[i + 1], i + 1] for i in range(1, n - 1)]
            return c + sum(float(a @ a) for a in acc) / sigma ** 2

        path = signs_dp.viterbi2(unary, pair, vecs, sigma)
        best = min(itertools.product(range(s), repeat=n), key=lambda q: cost(np.array(q)))
        assert cost(path) == pytest.approx(cost(np.array(best)), rel=1e-5)


def test_second_order_continuity_lets_a_swing_pass_through_the_image_plane():
    # a segment turning at constant speed through the plane parallel to the image: its depth offset
    # is L sin(t), so the two depth candidates are +-|L sin(t)| and meet at t = 0.  First-order
    # continuity cannot tell "passes through" from "bounces back" there; the second difference can.
    t = np.linspace(-0.6, 0.6, 25)
    depth = 0.4 * np.sin(t)
    cand = np.stack([-np.abs(depth), np.abs(depth)])                    # state 0 near, 1 far
    vecs = np.stack([np.stack([0.4 * np.cos(t), c], -1) for c in cand])  # (2, F, 2)
    truth = (depth > 0).astype(int)
    n = t.size
    diff = vecs[:, None, 1:] - vecs[None, :, :-1]                        # (from, to, F-1, 2)
    pair = np.transpose(np.sum(diff ** 2, -1), (2, 0, 1)) / 0.05 ** 2
    unary = np.zeros((n, 2))
    unary[0, 1] = 1.0                                                    # the first frame is known: near
    second = signs_dp.viterbi2(unary, pair, vecs, 0.05)
    away = np.abs(depth) > 0.02
    assert np.array_equal(second[away], truth[away])
    first = signs_dp.viterbi(unary, pair)
    assert not np.array_equal(first[away], truth[away])                 # it bounces back: the tie goes wrong


def test_dp_signs_recover_the_pose_without_noise(clip):
    tracks, truth = clip
    cam = truth.joints_camera()
    rays = taylor.unit_rays(tracks.xy, truth.focal_mm[:, None], tracks.image_size)
    _, joints = signs_dp.resolve_signs(rays, truth.class_lengths_m, cam[:, 0, 2], truth.rotations())
    err = np.linalg.norm(joints - cam, axis=-1)
    legs = [FEET["l"], FEET["r"], FEET["l"] - 1, FEET["r"] - 1]
    # legs decide facing; the knees' bending direction must get them right
    assert np.median(err[:, legs]) < 0.02
    assert np.median(err) < 0.05


def test_pruned_prior_scores_the_cheapest_states_and_gives_the_rest_the_frames_worst(clip):
    from core.motion_prior import load_default

    tracks, truth = clip
    cam = truth.joints_camera()[:40]
    prior = load_default()
    children = [JOINT_INDEX[name] for name in signs_dp.GROUPS[1]]            # hips and legs: 64 states
    rng = np.random.default_rng(3)
    parents = [SEGMENTS[c - 1][0] for c in children]
    vecs = (cam[:, children] - cam[:, parents])[None] * rng.choice([-1.0, 1.0], (64, 1, len(children), 1))
    unary = rng.random((40, 64))
    full = signs_dp._prior_cost(prior, cam, children, vecs)
    pruned = signs_dp._pruned_prior_cost(prior, cam, children, vecs, unary, 16)
    kept = np.argsort(unary, axis=1)[:, :16]
    rows = np.arange(40)[:, None]
    # the kept states' costs are the prior's, each frame's minimum of them taken off
    assert np.allclose(pruned[rows, kept], full[rows, kept] - full[rows, kept].min(axis=1, keepdims=True))
    others = np.ones((40, 64), bool)
    others[rows, kept] = False
    assert np.allclose(pruned[others].reshape(40, 48), pruned[rows, kept].max(axis=1, keepdims=True))
    assert not np.allclose(full[others].reshape(40, 48), pruned[others].reshape(40, 48))


def test_knee_hinge_violation_sign():
    left = np.array([[1.0, 0, 0]])
    up = np.array([[0, -1.0, 0]])               # camera axes: y down
    fwd = np.cross(left, up)
    thigh = -up * 0.45
    shank_back = -up * 0.4 - fwd * 0.2
    shank_front = -up * 0.4 + fwd * 0.2
    assert signs_dp.hinge_violation(thigh, shank_back, left, 1.0)[0] == 0.0
    assert signs_dp.hinge_violation(thigh, shank_front, left, 1.0)[0] > 0.1


def test_ground_from_planted_feet_matches_truth(clip):
    _, truth = clip
    stance = stance_codes(truth.stance)
    m, _ = ground.world_from_cam0(truth.joints_3d, stance, truth.height_m)
    up_est = m[2, :3]
    up_true = np.asarray(truth.world_from_cam0)[2, :3]
    angle = np.degrees(np.arccos(np.clip(up_est @ up_true / np.linalg.norm(up_true), -1, 1)))
    assert angle < 3.0
    # planted ankles sit at ankle height above the floor
    world = truth.joints_3d @ m[:3, :3].T + m[:3, 3]
    planted = np.concatenate([world[stance == 0, FEET["l"], 2], world[stance == 1, FEET["r"], 2]])
    assert np.median(planted) == pytest.approx(0.039 * truth.height_m, abs=0.02)
    assert np.allclose(m[:3, :3] @ m[:3, :3].T, np.eye(3), atol=1e-9)


def _standing_figure(n: int, floor_tilt_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """Joints (n, 17, 3) in camera-like axes (y down) of an upright figure whose planted ankles, frame by
    frame, step across a plane tilted ``floor_tilt_deg`` about the x axis, and its stance (all left)."""
    rng = np.random.default_rng(0)
    joints = np.zeros((n, 17, 3))
    t = np.radians(floor_tilt_deg)
    tilted_x, tilted_z = np.array([1.0, 0.0, 0.0]), np.array([0.0, np.sin(t), np.cos(t)])
    for i in range(n):
        foot = rng.uniform(-1, 1) * tilted_x + rng.uniform(-1, 1) * tilted_z + np.array([0.0, 0.0, 8.0])
        joints[i] = foot
        joints[i, JOINT_INDEX["neck"]] = foot + np.array([0.0, -1.4, 0.0])     # upright: y is down
        joints[i, JOINT_INDEX["pelvis"]] = foot + np.array([0.0, -0.9, 0.0])
    return joints, np.zeros(n, dtype=int)


@pytest.mark.parametrize("tilt, falls_back", [(5.0, False), (25.0, True)])
def test_floor_tilted_far_from_the_body_vertical_falls_back_to_the_body(tilt, falls_back):
    joints, stance = _standing_figure(40, tilt)
    m, warnings = ground.world_from_cam0(joints, stance, 1.75)
    up = m[2, :3]
    body = np.array([0.0, -1.0, 0.0])
    angle = np.degrees(np.arccos(np.clip(up @ body, -1, 1)))
    if not falls_back:                         # believable: the footprints' plane wins, no warning
        assert angle == pytest.approx(tilt, abs=0.5)
        assert not any(w.startswith("floor:") for w in warnings)
    else:                                      # not believable: the body's vertical, and a warning
        assert angle < 0.5
        assert any(w.startswith("floor:") and f"{tilt:.0f} degrees" in w and "check the camera" in w
                   for w in warnings)
        known = ground.world_from_cam0(joints, stance, 1.75, camera_known=True)[1]
        assert any(w.startswith("floor:") and "check the stance" in w for w in known)
    assert np.allclose(m[:3, :3] @ m[:3, :3].T, np.eye(3), atol=1e-9)


@pytest.fixture(scope="module")
def placed(clip):
    """The clip's true joints in camera axes, its rays and its segments' lengths: what a group's states are
    built from."""
    tracks, truth = clip
    rays = taylor.unit_rays(tracks.xy, truth.focal_mm[:, None], tracks.image_size)
    return truth.joints_camera(), rays, segment_lengths_from_classes(truth.class_lengths_m)


def test_legs_terms_worked_out_per_dependency_equal_those_of_every_state(placed):
    # the sign choice works each term out on the states of the bits it depends on (a knee on its hip's bit
    # and its own, the hips' symmetry on two bits) and spreads it to the 64: the numbers of every state's own
    cam, rays, seg_len = placed
    group = signs_dp.GROUPS[1]
    children = [JOINT_INDEX[name] for name in group]
    n, k = cam.shape[0], len(children)
    pos = {c: np.empty((2 ** k, n, 3)) for c in children}
    vecs = np.empty((2 ** k, n, k, 3))
    for state in range(2 ** k):                          # each state built on its own, parent by parent
        placed = {}
        for b, c in enumerate(children):
            p = SEGMENTS[c - 1][0]
            parent = placed.get(p, cam[:, p])
            near, far, _ = taylor.child_candidates(parent, rays[:, c], seg_len[c - 1])
            placed[c] = far if (state >> b) & 1 else near
            pos[c][state], vecs[state, :, b] = placed[c], placed[c] - parent
    _, deps = signs_dp._state_bits(group)
    every = signs_dp._group_prior(group, cam, pos)
    assert np.array_equal(signs_dp._group_prior(group, cam, pos, deps), every)
    assert np.ptp(every, axis=0).min() > 0                 # the states' costs differ in every frame
    rng = np.random.default_rng(2)
    cue = rng.normal(size=(n, 16, 3))
    cue /= np.linalg.norm(cue, axis=-1, keepdims=True)
    cue[rng.random((n, 16)) < 0.2] = np.nan
    assert np.array_equal(signs_dp._cue_cost(cue, children, vecs, deps), signs_dp._cue_cost(cue, children, vecs))
    # a dependency left out is caught: the left ankle's place without its knee's bit
    wrong = list(deps)
    wrong[group.index("l_ankle")] &= ~(1 << group.index("l_knee"))
    assert not np.array_equal(signs_dp._cue_cost(cue, children, vecs, wrong), signs_dp._cue_cost(cue, children, vecs))


@pytest.mark.parametrize("group", signs_dp.GROUPS, ids=lambda g: g[0])
def test_a_groups_own_costs_read_only_the_joints_it_names(clip, placed, group):
    # the prior's rounds reuse a group's states and costs while the joints it reads stand; every other
    # joint may change (another group chosen again) without changing them
    truth = clip[1]
    cam, rays, seg_len = placed
    rng = np.random.default_rng(5)
    cue = rng.normal(size=(cam.shape[0], 16, 3))
    cue /= np.linalg.norm(cue, axis=-1, keepdims=True)

    def build(joints):
        return signs_dp._group_states(group, rays, seg_len, joints, truth.rotations().transpose(0, 2, 1), 0.08, cue)

    own = build(cam)
    reads = signs_dp._reads(group)
    others = [j for j in range(17) if j not in reads and j not in [JOINT_INDEX[name] for name in group]]
    moved = cam.copy()
    moved[:, others] += rng.normal(0.0, 0.1, moved[:, others].shape)
    for a, b in zip(own, build(moved)):
        assert np.array_equal(a, b)
    moved = cam.copy()
    moved[:, reads] += rng.normal(0.0, 0.1, moved[:, reads].shape)
    assert not all(np.array_equal(a, b) for a, b in zip(own, build(moved)))


def test_a_missing_joint_is_filled_at_its_parent_plus_the_offset_over_time():
    """A wrist lost while the body walks on stays at the end of its forearm (the elbow plus the
    elbow-to-wrist offset interpolated between the frames where both were seen, held beyond the ends);
    the root is interpolated itself, and a joint never observed sits on its parent."""
    tracks, _ = synthesize(load_motion("builtin:walk", max_frames=40), kinds=(), noise_px=0.0, seed=2)
    xy = np.array(tracks.xy, dtype=float)
    wrist, elbow, pelvis = JOINT_INDEX["l_wrist"], JOINT_INDEX["l_elbow"], JOINT_INDEX["pelvis"]
    lost = xy.copy()
    lost[10:20, wrist] = np.nan                            # inside the clip
    lost[30:, wrist] = np.nan                              # to its end
    lost[5:8, pelvis] = np.nan
    lost[:, JOINT_INDEX["head"]] = np.nan                  # never seen
    out = taylor.fill_missing(lost)
    assert np.isfinite(out).all()
    np.testing.assert_array_equal(out[~np.isnan(lost)], lost[~np.isnan(lost)])   # what was seen stays

    offset = xy[:, wrist] - xy[:, elbow]
    w = (np.arange(10, 20) - 9) / 11.0
    expected = xy[10:20, elbow] + (1 - w)[:, None] * offset[9] + w[:, None] * offset[20]
    np.testing.assert_allclose(out[10:20, wrist], expected, atol=1e-9)
    np.testing.assert_allclose(out[30:, wrist], xy[30:, elbow] + offset[29], atol=1e-9)
    # the body walks: the wrist's own place held at the end would fall behind the elbow
    assert np.linalg.norm(xy[-1, elbow] - xy[29, elbow]) > 5.0
    w = (np.arange(5, 8) - 4) / 4.0
    np.testing.assert_allclose(out[5:8, pelvis], (1 - w)[:, None] * xy[4, pelvis] + w[:, None] * xy[8, pelvis],
                               atol=1e-9)
    np.testing.assert_array_equal(out[:, JOINT_INDEX["head"]], out[:, JOINT_INDEX["neck"]])
