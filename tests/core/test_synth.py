"""The synthetic experiment: exact projection at zero noise, honest noise/drop-out/occlusion, sane truth."""

from __future__ import annotations

import numpy as np
import pytest

from core.camera import project_to_pixels, rotation_matrix
from core.errors import InputError
from core.skeleton import (
    CLASS_INDEX,
    JOINT_INDEX,
    class_lengths_for_height,
    proportions,
    segment_lengths,
    segment_lengths_from_classes,
)
from core.synthetic.motion import Motion, load_motion
from core.synthetic.synth import LIMBS, YUP_TO_BLENDER, Spell, place_camera, stance_truth, synthesize

PROPS = np.array([0.05, 0.18, 0.17, 0.06, 0.08, 0.05, 0.09, 0.06, 0.13, 0.13])


def _swing(angle):
    """Unit direction hanging down, swung forward (+x) by ``angle`` radians."""
    return np.array([np.sin(angle), -np.cos(angle), 0.0])


def hand_motion(n: int = 120, fps: float = 30.0, speed: float = 1.2, height: float = 1.75) -> Motion:
    """A rigid figure walking along +x with swinging legs and arms (exact class lengths)."""
    cl = class_lengths_for_height(PROPS, height)
    seg = segment_lengths_from_classes(cl)
    length = {j: seg[j - 1] for j in range(1, 17)}      # segment k ends at joint k + 1
    up = np.array([0.0, 1.0, 0.0])
    left = np.array([0.0, 0.0, -1.0])          # facing +x with y up, the left is -z
    joints = np.zeros((n, 17, 3))

    def put(frame, name, parent, direction):
        d = direction / np.linalg.norm(direction)
        frame[JOINT_INDEX[name]] = frame[JOINT_INDEX[parent]] + length[JOINT_INDEX[name]] * d

    for f in range(n):
        t = f / fps
        phase = 2 * np.pi * 0.9 * t
        swing = 0.35 * np.sin(phase)
        fr = joints[f]
        fr[0] = [speed * t, cl[CLASS_INDEX["thigh"]] + cl[CLASS_INDEX["shank"]] + 0.07 + 0.02 * np.cos(2 * phase), 0]
        put(fr, "spine", "pelvis", up)
        put(fr, "thorax", "spine", up + np.array([0.05, 0, 0]))
        put(fr, "neck", "thorax", up)
        put(fr, "head", "neck", up + np.array([0.1, 0, 0]))
        put(fr, "l_hip", "pelvis", left)
        put(fr, "r_hip", "pelvis", -left)
        put(fr, "l_knee", "l_hip", _swing(swing))
        put(fr, "l_ankle", "l_knee", _swing(swing - 0.2 * (1 + np.sin(phase))))
        put(fr, "r_knee", "r_hip", _swing(-swing))
        put(fr, "r_ankle", "r_knee", _swing(-swing - 0.2 * (1 - np.sin(phase))))
        put(fr, "l_shoulder", "thorax", left - 0.1 * up)
        put(fr, "r_shoulder", "thorax", -left - 0.1 * up)
        put(fr, "l_elbow", "l_shoulder", _swing(-0.6 * swing))
        put(fr, "l_wrist", "l_elbow", _swing(-0.6 * swing + 0.3))
        put(fr, "r_elbow", "r_shoulder", _swing(0.6 * swing))
        put(fr, "r_wrist", "r_elbow", _swing(0.6 * swing + 0.3))
    joints[..., 1] -= joints[..., 1].min()      # floor at y = 0
    period = int(round(fps / 0.9))
    contacts = np.zeros((n, 2), dtype=bool)
    for f in range(n):
        ph = (f % period) / period
        contacts[f, 0] = ph < 0.6
        contacts[f, 1] = ph >= 0.5 or ph < 0.1
    return Motion("hand", fps, joints, cl, contacts)


@pytest.fixture(scope="module")
def motion():
    return hand_motion()


def test_hand_motion_is_rigid(motion):
    seg = segment_lengths(motion.joints)
    assert np.ptp(seg, axis=0).max() < 1e-9


def _world_from_cam0(truth):
    return truth.camera_position_world + truth.joints_3d @ truth.rotation_world_from_cam0.T


@pytest.mark.parametrize("kinds,continuous", [(("pan", "tilt", "zoom"), False),
                                              (("pan_tilt", "rotate_zoom", "roll"), True)])
def test_zero_noise_tracks_reproject_the_rigid_figure_exactly(motion, kinds, continuous):
    tracks, truth = synthesize(motion, kinds=kinds, noise_px=0.0, seed=4, continuous=continuous)
    assert tracks.n_frames == truth.n_frames == motion.n_frames
    assert any(s.moving for s in truth.spells)
    # per-frame camera from the truth alone
    rot = rotation_matrix(truth.rotvec_deg)
    cam = np.einsum("fij,fkj->fki", rot, truth.joints_3d)
    uv = project_to_pixels(cam, truth.focal_mm[:, None], truth.image_size)
    present = tracks.present
    assert present.mean() > 0.95
    assert np.abs(tracks.xy[present] - uv[present]).max() < 1e-6
    # exactly the joints inside the image (and in front of the camera) are present
    w, h = truth.image_size
    inside = (cam[..., 2] > 0) & (uv[..., 0] >= 0) & (uv[..., 0] <= w) & (uv[..., 1] >= 0) & (uv[..., 1] <= h)
    assert np.array_equal(present, inside)
    assert np.all(tracks.conf[present] == 1.0)
    # joints_3d are the world joints seen from the fixed camera position
    assert np.abs(_world_from_cam0(truth) - motion.joints).max() < 1e-9
    r = truth.rotation_world_from_cam0
    assert np.allclose(r.T @ r, np.eye(3)) and np.linalg.det(r) == pytest.approx(1.0)


def test_truth_camera_and_scale_fields_are_consistent(motion):
    tracks, truth = synthesize(motion, noise_px=0.0, seed=1)
    assert np.allclose(truth.rotvec_deg[0], 0.0) and truth.focal_mm[0] == pytest.approx(50.0)
    for s in truth.spells:
        sl = slice(s.start, s.end + 1)
        assert truth.camera_moving[sl].all() == s.moving and truth.camera_moving[sl].any() == s.moving
        if not s.moving:
            assert np.ptp(truth.rotvec_deg[sl], axis=0).max() < 1e-9 and np.ptp(truth.focal_mm[sl]) < 1e-9
    z = truth.joints_3d[:, JOINT_INDEX["pelvis"], 2]
    assert np.allclose(truth.scale, z[0] / z) and truth.scale[0] == 1.0
    # walking along +x is not parallel to the image plane in the chosen oblique view: the scale changes
    assert np.ptp(truth.scale) > 0.05
    assert np.allclose(truth.proportions, proportions(motion.class_lengths))
    assert truth.proportions.sum() == pytest.approx(1.0)
    # world_from_cam0 maps to a Z-up world with the floor at z = 0
    m = truth.world_from_cam0
    homog = np.concatenate([truth.joints_3d, np.ones(truth.joints_3d.shape[:2] + (1,))], axis=-1)
    blender = homog @ m.T
    assert np.allclose(blender[..., :3], motion.joints @ YUP_TO_BLENDER.T)
    assert blender[..., 2].min() == pytest.approx(0.0, abs=1e-9)
    assert np.allclose(blender[..., 2], motion.joints[..., 1])


def test_camera_framing_rules(motion):
    place = place_camera(motion.joints, motion.class_lengths, (720, 480), 50.0)
    assert 1.2 <= place.position_world[1] <= 1.6
    forward = place.rotation_world_from_cam0[:, 2]
    to_target = place.target_world - place.position_world
    assert np.allclose(forward, to_target / np.linalg.norm(to_target))
    assert abs(place.rotation_world_from_cam0[1, 0]) < 1e-12          # camera x axis level: no roll
    uv = project_to_pixels(place.to_cam0(motion.joints), 50.0, (720, 480))
    assert (np.abs(uv - [360, 240]) <= np.array([360, 240]) * 0.8 + 1e-6).all()   # whole motion framed
    # ... and tightly: the figure is not a speck (it touches the 80 % box within 5 %)
    assert (np.abs(uv - [360, 240]) / np.array([360, 240])).max() > 0.75
    # a fixed offset is honoured
    side = place_camera(motion.joints, motion.class_lengths, (720, 480), 50.0, view_offset_deg=0.0)
    assert side.view_offset_deg == 0.0
    path = motion.joints[-1, 0] - motion.joints[0, 0]
    view = side.target_world - side.position_world
    assert abs(np.dot(path[[0, 2]], view[[0, 2]])) < 1e-6 * np.linalg.norm(view)   # side view of the path


def test_noise_statistics_match_sigma(motion):
    clean, _ = synthesize(motion, noise_px=0.0, seed=5)
    noisy, _ = synthesize(motion, noise_px=2.0, seed=5)
    both = clean.present & noisy.present
    resid = (noisy.xy - clean.xy)[both]
    assert resid.shape[0] > 1000
    assert resid.std() == pytest.approx(2.0, rel=0.06)
    assert abs(resid.mean()) < 0.1
    assert np.abs(np.corrcoef(resid[:, 0], resid[:, 1])[0, 1]) < 0.1


def test_dropout_removes_the_asked_fraction(motion):
    base, _ = synthesize(motion, noise_px=0.0, seed=2)
    dropped, _ = synthesize(motion, noise_px=0.0, dropout=0.2, seed=2)
    n = base.present.sum()
    assert (dropped.present & ~base.present).sum() == 0
    assert base.present.sum() - dropped.present.sum() == round(0.2 * n)
    # spread over joints and frames, not a block
    per_joint = 1 - dropped.present.sum(0) / base.present.sum(0)
    assert per_joint.min() > 0.05 and per_joint.max() < 0.4
    # the remaining observations are unchanged
    keep = dropped.present
    assert np.array_equal(dropped.xy[keep], base.xy[keep])


def test_occlusion_hides_a_whole_limb_for_the_duration():
    motion = hand_motion(n=420)  # 14 s -> three events
    base, _ = synthesize(motion, noise_px=0.0, seed=8)
    occl, truth = synthesize(motion, noise_px=0.0, occlusion_s=1.0, seed=8)
    assert len(truth.occlusions) == 3
    expected = base.present.copy()
    for ev in truth.occlusions:
        assert ev["end"] - ev["start"] + 1 == 30 and ev["limb"] in LIMBS
        expected[ev["start"]:ev["end"] + 1, list(LIMBS[ev["limb"]])] = False
        assert not occl.present[ev["start"]:ev["end"] + 1, list(LIMBS[ev["limb"]])].any()
    assert np.array_equal(occl.present, expected)


def test_same_seed_same_data_other_seed_other_data(motion):
    a, ta = synthesize(motion, dropout=0.1, occlusion_s=0.5, seed=3)
    b, tb = synthesize(motion, dropout=0.1, occlusion_s=0.5, seed=3)
    c, _ = synthesize(motion, dropout=0.1, occlusion_s=0.5, seed=4)
    assert np.array_equal(a.xy, b.xy, equal_nan=True) and np.array_equal(a.conf, b.conf)
    assert np.array_equal(ta.rotvec_deg, tb.rotvec_deg) and ta.occlusions == tb.occlusions
    assert not np.array_equal(a.xy, c.xy, equal_nan=True)


def test_given_schedule_is_used_unchanged(motion):
    n = motion.n_frames
    spells = [Spell(0, 29, "still"), Spell(30, 59, "pan", {"pan_deg": 4.0}), Spell(60, 89, "still"),
              Spell(90, 109, "zoom", {"zoom": 1.25}), Spell(110, n - 1, "still")]
    _, truth = synthesize(motion, schedule=spells, noise_px=0.0)
    assert [s.to_dict() for s in truth.spells] == [s.to_dict() for s in spells]
    rv = truth.rotvec_deg[-1]
    assert abs(abs(rv[1]) - 4.0) < 1e-9 and abs(rv[0]) < 1e-9
    assert truth.focal_mm[-1] == pytest.approx(62.5)
    with pytest.raises(InputError, match="covers"):
        synthesize(motion, schedule=spells[:-1])


def test_stance_truth_rule():
    L, R = [True, False], [False, True]
    B, N = [True, True], [False, False]
    contacts = np.array([L, L, B, B, R, R, B, L, N, N, R, B, B, B, B])
    #                    0  1  2  3  4  5  6  7  8  9 10 11 12 13 14
    stance, clear = stance_truth(contacts)
    # double support keeps the foot planted earlier (swap at toe-off); flight is None
    assert stance[:8] == ["l", "l", "l", "l", "r", "r", "r", "l"]
    assert stance[8:11] == [None, None, "r"]
    assert stance[11:] == ["r"] * 4
    assert clear.tolist() == [sum(c) == 1 for c in contacts.tolist()]
    # both feet touching down together: the one that stays planted longer, then left
    stance, _ = stance_truth(np.array([N, B, B, L, L]))
    assert stance == [None, "l", "l", "l", "l"]
    stance, _ = stance_truth(np.array([N, B, B, R]))
    assert stance == [None, "r", "r", "r"]
    stance, _ = stance_truth(np.array([B, B]))
    assert stance == ["l", "l"]


def test_stance_truth_follows_the_motion_contacts(motion):
    _, truth = synthesize(motion, noise_px=0.0)
    for i, s in enumerate(truth.stance):
        c = motion.contacts[i]
        if s is None:
            assert not c.any()
        else:
            assert c[0 if s == "l" else 1]
    assert np.array_equal(truth.stance_clear, motion.contacts.sum(1) == 1)


@pytest.mark.parametrize("kwargs,match", [
    ({"noise_px": -1.0}, "noise"), ({"dropout": 1.0}, "drop-out"), ({"occlusion_s": -0.1}, "occlusion"),
    ({"focal_mm": 0.0}, "focal"), ({"image_size": (720, 0)}, "image size"), ({"kinds": ("swing",)}, "kind"),
])
def test_bad_settings_are_input_errors(motion, kwargs, match):
    with pytest.raises(InputError, match=match):
        synthesize(motion, **kwargs)


def test_bad_motion_is_an_input_error(motion):
    bad = Motion("bad", 30.0, motion.joints[:1], motion.class_lengths, motion.contacts[:1])
    with pytest.raises(InputError, match="frames"):
        synthesize(bad)
    joints = motion.joints.copy()
    joints[3, 2, 1] = np.nan
    with pytest.raises(InputError, match="non-finite"):
        synthesize(Motion("nan", 30.0, joints, motion.class_lengths, motion.contacts))


def test_builtin_walk_through_the_generator():
    motion = load_motion("builtin:walk", max_frames=150)
    tracks, truth = synthesize(motion, noise_px=0.0, seed=0)
    assert tracks.present.mean() > 0.98
    rot = rotation_matrix(truth.rotvec_deg)
    cam = np.einsum("fij,fkj->fki", rot, truth.joints_3d)
    uv = project_to_pixels(cam, truth.focal_mm[:, None], truth.image_size)
    p = tracks.present
    assert np.abs(tracks.xy[p] - uv[p]).max() < 1e-6
    assert np.abs(_world_from_cam0(truth) - motion.joints).max() < 1e-9
    assert truth.stance_clear.mean() > 0.5
    heights = np.nanmax(tracks.xy[..., 1], axis=1) - np.nanmin(tracks.xy[..., 1], axis=1)
    assert np.median(heights) > 0.15 * 480     # the figure is a usable size in the image
    seg = segment_lengths(motion.joints)
    assert np.ptp(seg, axis=0).max() < 1e-6  # rigid figure in, exact proportions out
    assert np.allclose(truth.proportions, proportions(motion.class_lengths))


def test_generated_camera_keeps_the_figure_in_frame_with_realistic_moves():
    motion = hand_motion(n=600, speed=1.0)    # 20 s, 20 m walk: the camera must follow it
    for kinds, continuous in ((("pan", "tilt", "pan_tilt", "zoom"), False),
                              (("pan_tilt", "rotate_zoom", "roll"), True)):
        tracks, truth = synthesize(motion, kinds=kinds, continuous=continuous, noise_px=0.0, seed=6)
        assert tracks.present.mean() > 0.99
        moves = [s for s in truth.spells if s.moving]
        assert len(moves) >= 6
        for s in moves:  # amplitudes at most halved by the keep-in-frame adjustment
            if "pan_deg" in s.params:
                assert 2.5 - 1e-9 <= abs(s.params["pan_deg"]) <= 20 + 1e-9
            if "tilt_deg" in s.params:
                assert 1.5 - 1e-9 <= abs(s.params["tilt_deg"]) <= 8 + 1e-9
            if "zoom" in s.params:
                assert 1.15 ** 0.5 - 1e-9 <= max(s.params["zoom"], 1 / s.params["zoom"]) <= 1.4 + 1e-9
        assert 1 / 1.6 - 1e-9 <= truth.focal_mm.min() / 50 and truth.focal_mm.max() / 50 <= 1.6 + 1e-9


def test_tracks_do_not_leak_the_truth(motion):
    tracks, _ = synthesize(motion)
    assert tracks.meta == {"synthetic": True}


def test_real_bvh_clip_reprojects_exactly(shared_bvh_dir):
    motion = load_motion(str(shared_bvh_dir / "131_03.bvh"), fps=30.0, max_frames=150)
    tracks, truth = synthesize(motion, kinds=("pan_tilt", "zoom"), noise_px=0.0, seed=1)
    assert tracks.present.mean() > 0.98
    cam = np.einsum("fij,fkj->fki", rotation_matrix(truth.rotvec_deg), truth.joints_3d)
    uv = project_to_pixels(cam, truth.focal_mm[:, None], truth.image_size)
    p = tracks.present
    assert np.abs(tracks.xy[p] - uv[p]).max() < 1e-6
    assert np.abs(_world_from_cam0(truth) - motion.joints).max() < 1e-9
