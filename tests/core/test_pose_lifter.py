"""The pose lifter: its input ignores the camera's placement, training is deterministic and records its clips,
the shipped file loads and reads depth from a picture, and the depth-sign choices use it."""

from __future__ import annotations

import numpy as np
import pytest

from core import cli
from core.camera import rotation_matrix
from core.errors import InputError
from core.motion_prior import DEFAULT_LIFTER_PATH, PoseLifter, load_default_lifter
from core.motion_prior.evaluation import LIMB_BONES, frame_errors
from core.motion_prior.features import bone_vectors
from core.motion_prior.lifter import N_INPUTS, OUTPUT_BONES, axis_to_z, normalised_view
from core.motion_prior.train import SOURCE
from core.motion_prior.train_lifter import MEMBERS, pose_bank, sample_batch, train
from core.synthetic.motion import load_motion
from core.synthetic.synth import synthesize


def _camera_view(joints: np.ndarray, rotvec_deg, distance: float) -> np.ndarray:
    """Joints (F, 17, 3) of a Y-up world turned by ``rotvec_deg`` and seen level by a camera ``distance``
    metres away (camera axes: x right, y down, z forward)."""
    rel = joints - joints[:, :1]
    cam = (rel @ rotation_matrix(np.asarray(rotvec_deg, dtype=float)).T) * np.array([1.0, -1.0, -1.0])
    cam[..., 2] += distance
    return cam


def test_axis_to_z_turns_a_direction_onto_the_optical_axis():
    rng = np.random.default_rng(3)
    d = rng.normal(size=(50, 3))
    d[:, 2] = np.abs(d[:, 2]) + 0.2
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    R = axis_to_z(d)
    np.testing.assert_allclose(np.einsum("nab,nb->na", R, d), np.tile([0.0, 0.0, 1.0], (50, 1)), atol=1e-9)
    np.testing.assert_allclose(R @ np.transpose(R, (0, 2, 1)), np.broadcast_to(np.eye(3), R.shape), atol=1e-9)
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-9)


def test_input_does_not_depend_on_where_the_person_stands_in_the_frame():
    """Turning the camera (a pan: the person moves across the picture) changes every ray but not the input,
    up to the small roll the turn brings; the person's distance changes it only through perspective."""
    joints = load_motion("builtin:walk", max_frames=5).joints
    cam = _camera_view(joints, [0.0, 0.0, 0.0], 6.0)
    rays = cam / np.linalg.norm(cam, axis=-1, keepdims=True)
    panned = rays @ rotation_matrix(np.array([0.0, 15.0, 0.0])).T
    x0, _, _ = normalised_view(rays)
    x1, _, _ = normalised_view(panned)
    assert x0.shape == (5, N_INPUTS)
    assert np.max(np.abs(x1 - x0)) < 0.05
    far = _camera_view(joints, [0.0, 0.0, 0.0], 60.0)
    x2, _, _ = normalised_view(far / np.linalg.norm(far, axis=-1, keepdims=True))
    assert np.max(np.abs(x2 - x0)) < 0.2


def _tiny_clips():
    return [load_motion("builtin:walk", max_frames=60).joints, load_motion("builtin:run", max_frames=40).joints]


def test_training_batches_and_weights_are_deterministic():
    bank = pose_bank(_tiny_clips())
    a = sample_batch(bank, np.random.default_rng(5), 16)
    b = sample_batch(bank, np.random.default_rng(5), 16)
    np.testing.assert_array_equal(a[0], b[0])
    one = train(_tiny_clips(), steps=30, width=16, layers=1, members=2)
    two = train(_tiny_clips(), steps=30, width=16, layers=1, members=2)
    for w1, w2 in zip(one.weights, two.weights):
        np.testing.assert_array_equal(w1, w2)


def test_a_lifter_of_several_networks_reads_their_mean_and_each_is_trained_from_its_own_seed():
    clips = _tiny_clips()
    both = train(clips, steps=30, width=16, layers=2, members=2, seed=7)
    first = train(clips, steps=30, width=16, layers=2, members=1, seed=7)
    second = train(clips, steps=30, width=16, layers=2, members=1, seed=8)
    assert [m["seed"] for m in both.meta["members"]] == [7, 8]
    assert both.members == 2 and first.members == 1 and both.weights[1].shape == (2, 16, 16)
    x = np.random.default_rng(3).standard_normal((40, N_INPUTS))
    np.testing.assert_allclose(both.forward(x), (first.forward(x) + second.forward(x)) / 2.0, atol=1e-5)
    assert not np.allclose(first.forward(x), second.forward(x), atol=1e-3)
    one = PoseLifter.averaged([first])
    np.testing.assert_array_equal(one.forward(x), first.forward(x))
    four = PoseLifter.averaged([both, PoseLifter.averaged([first, second])])
    assert four.members == 4
    np.testing.assert_allclose(four.forward(x), both.forward(x), atol=1e-5)
    with pytest.raises(ValueError):
        PoseLifter.averaged([first, train(clips, steps=5, width=16, layers=1, members=1)])


def test_recombined_limbs_keep_the_trunk_and_come_from_other_poses():
    """Training poses with limbs from other frames: the trunk stays, and each limb that changed is, in the
    body's own frame, exactly a limb of some pose of the bank."""
    from core.motion_prior.features import body_frame
    from core.motion_prior.train_lifter import _LIMB_SEGMENTS, MIX_LIMB, MIX_RATE, mixed_limbs

    bank = pose_bank(_tiny_clips())
    poses = bank[:150]
    mixed = mixed_limbs(poses, bank, np.random.default_rng(1))
    limb = sorted(s for segs in _LIMB_SEGMENTS for s in segs)
    trunk = [s for s in range(16) if s not in limb]
    np.testing.assert_array_equal(mixed[:, trunk], poses[:, trunk])
    changed = np.abs(mixed - poses).max(axis=(1, 2)) > 1e-9
    expected = MIX_RATE * (1.0 - (1.0 - MIX_LIMB) ** len(_LIMB_SEGMENTS))
    assert abs(changed.mean() - expected) < 0.12
    for segs in _LIMB_SEGMENTS:
        own = np.einsum("nab,nsb->nsa", body_frame(mixed), mixed[:, list(segs)])
        ref = np.einsum("nab,nsb->nsa", body_frame(bank), bank[:, list(segs)])
        nearest = np.min(np.abs(own[:, None] - ref[None]).max(axis=(2, 3)), axis=1)
        assert nearest.max() < 1e-9


def test_training_lowers_the_error_on_its_own_pictures():
    clips = _tiny_clips()
    bank = pose_bank(clips)
    x, t = sample_batch(bank, np.random.default_rng(99), 400)
    short = train(clips, steps=5, width=32, layers=2)
    longer = train(clips, steps=300, width=32, layers=2)
    assert np.mean((longer.forward(x) - t) ** 2) < 0.7 * np.mean((short.forward(x) - t) ** 2)


def test_save_and_load_round_trip(tmp_path):
    lifter = train(_tiny_clips(), steps=5, width=8, layers=1, meta={"source": "test"})
    path = tmp_path / "l.npz"
    lifter.save(path)
    back = PoseLifter.load(path)
    cam = _camera_view(load_motion("builtin:walk", max_frames=4).joints, [0.0, 30.0, 0.0], 5.0)
    rays = cam / np.linalg.norm(cam, axis=-1, keepdims=True)
    np.testing.assert_allclose(back.bone_directions(rays), lifter.bone_directions(rays), atol=1e-6, equal_nan=True)
    assert back.meta["source"] == "test"


def test_shipped_lifter_loads_and_records_its_data():
    assert DEFAULT_LIFTER_PATH.is_file()
    assert DEFAULT_LIFTER_PATH.stat().st_size < 5_000_000
    lifter = load_default_lifter()
    assert lifter.meta["source"] == SOURCE and "licence" in lifter.meta
    assert lifter.members == MEMBERS == len(lifter.meta["members"])
    assert [m["seed"] for m in lifter.meta["members"]] == [lifter.meta["seed"] + k for k in range(MEMBERS)]
    clips = lifter.meta["clips"]
    assert clips and all(len(c["sha256"]) == 64 for c in clips)
    assert not any(c["name"].split("_")[0].lstrip("0") in ("1", "131") for c in clips)


def test_shipped_video_lifter_reads_half_a_second_each_way_and_records_its_data():
    from core.motion_prior import DEFAULT_VIDEO_LIFTER_PATH, load_video_lifter

    assert DEFAULT_VIDEO_LIFTER_PATH.is_file()
    assert DEFAULT_VIDEO_LIFTER_PATH.stat().st_size + DEFAULT_LIFTER_PATH.stat().st_size < 5_000_000
    video = load_video_lifter()
    assert video.temporal and 0.0 in video.taps_s and max(abs(t) for t in video.taps_s) <= 0.5
    assert video.members == MEMBERS and video.meta["source"] == SOURCE and "licence" in video.meta
    assert [c["sha256"] for c in video.meta["clips"]] == [c["sha256"] for c in load_default_lifter().meta["clips"]]


@pytest.mark.parametrize("clip", ["builtin:walk", "builtin:run"])
def test_shipped_video_lifter_reads_which_way_limbs_point_in_depth(clip):
    """The built-in clips (not training data) filmed from eight sides: the limb bones clearly out of the
    picture's plane point the true way in depth far more often than a coin would say, at 30 and 60 fps."""
    from core.motion_prior import load_video_lifter

    right = []
    for fps in (30.0, 60.0):
        joints = load_motion(clip, fps=fps, max_frames=int(3 * fps)).joints
        for heading in range(0, 360, 45):
            cam = _camera_view(joints, [0.0, float(heading), 0.0], 7.0)
            d = load_video_lifter().bone_directions(cam / np.linalg.norm(cam, axis=-1, keepdims=True), fps)
            true = bone_vectors(cam)
            limbs = np.array(LIMB_BONES)
            clear = (np.abs(true[..., 2]) / np.linalg.norm(true, axis=-1))[:, limbs] > 0.3
            right.append((np.sign(d[:, limbs, 2]) == np.sign(true[:, limbs, 2]))[clear])
    right = np.concatenate(right)
    assert right.size > 300
    assert right.mean() > 0.8


@pytest.mark.parametrize("clip", ["builtin:walk", "builtin:run"])
def test_shipped_lifter_reads_which_way_limbs_point_in_depth(clip):
    """Seen from eight sides, the limb bones clearly out of the picture's plane point the true way in
    depth far more often than a coin would say (the built-in clips are not training data)."""
    joints = load_motion(clip, fps=30.0, max_frames=90).joints[::3]
    right = []
    for heading in range(0, 360, 45):
        cam = _camera_view(joints, [0.0, float(heading), 0.0], 7.0)
        rays = cam / np.linalg.norm(cam, axis=-1, keepdims=True)
        d = load_default_lifter().bone_directions(rays)
        true = bone_vectors(cam)
        slant = np.abs(true[..., 2]) / np.linalg.norm(true, axis=-1)
        limbs = np.array(LIMB_BONES)
        clear = slant[:, limbs] > 0.3
        right.append((np.sign(d[:, limbs, 2]) == np.sign(true[:, limbs, 2]))[clear])
    right = np.concatenate(right)
    assert right.size > 100
    assert right.mean() > 0.8
    assert np.isnan(d[:, [s for s in range(16) if s not in OUTPUT_BONES]]).all()


def test_a_depth_cue_steers_the_joint_methods_sign_choice():
    """With everything else true, a cue of the true bone directions leaves fewer mirrored frames than the
    geometric rules alone; a cue of the depth-mirrored directions leaves more."""
    from core.joint_solve.signs_dp import resolve_signs
    from core.joint_solve.taylor import unit_rays

    tracks, truth = synthesize(load_motion("builtin:run", max_frames=120), kinds=(), noise_px=0.0, seed=2,
                               view_offset_deg=50.0)
    R = rotation_matrix(truth.rotvec_deg)
    X = np.einsum("fab,fjb->fja", R, truth.joints_3d)
    rays = unit_rays(tracks.xy, truth.focal_mm[:, None], tracks.image_size)
    true_dirs = bone_vectors(X)
    true_dirs /= np.linalg.norm(true_dirs, axis=-1, keepdims=True)
    mirrored_dirs = true_dirs * np.array([1.0, 1.0, -1.0])
    plain = frame_errors(resolve_signs(rays, truth.class_lengths_m, X[:, 0, 2], R)[1], X)[1].mean()
    good = frame_errors(resolve_signs(rays, truth.class_lengths_m, X[:, 0, 2], R, cue=true_dirs)[1], X)[1].mean()
    bad = frame_errors(resolve_signs(rays, truth.class_lengths_m, X[:, 0, 2], R, cue=mirrored_dirs)[1], X)[1].mean()
    assert good < plain < bad
    assert good < 0.05


def test_single_image_signs_follow_the_lifter():
    """One frame, true lengths: the lifter's cue turns mirrored limbs back on frames of the built-in run."""
    from core.single_image import pose_from_image
    from core.single_image import signs as sign_choice

    tracks, truth = synthesize(load_motion("builtin:run", fps=30.0, max_frames=150), kinds=(), noise_px=0.0,
                               seed=4, view_offset_deg=35.0)
    R = rotation_matrix(truth.rotvec_deg)
    frames = range(0, 150, 10)

    def mirrored(sigma):
        old = sign_choice.LIFTER_SIGMA
        sign_choice.LIFTER_SIGMA = sigma
        try:
            out = []
            for i in frames:
                X = truth.joints_3d[i] @ R[i].T
                pose = pose_from_image(tracks.xy[i], tracks.image_size, truth.class_lengths_m,
                                       focal_mm=float(truth.focal_mm[i]))
                out.append(frame_errors(pose.joints[None], X[None])[1][0])
            return np.mean(out)
        finally:
            sign_choice.LIFTER_SIGMA = old

    assert mirrored(sign_choice.LIFTER_SIGMA) < mirrored(None)


def _clip_folder(tmp_path):
    """A folder of two small training clips named as CMU subject 2's."""
    from tests.core.test_motion_prior import _write_clip

    data = tmp_path / "clips"
    data.mkdir()
    for i in range(2):
        _write_clip(data / f"002_0{i + 1}.bvh", seed=i, n=60)
    return data


def test_train_lifter_command_records_its_clips_and_refuses_evaluation(tmp_path, capsys):
    data = _clip_folder(tmp_path)
    out = tmp_path / "l.npz"
    assert cli.main(["train-lifter", str(data), "--out", str(out), "--steps", "20",
                     "--source", "a repository @ a commit"]) == 0
    lifter = PoseLifter.load(out)
    assert [c["name"] for c in lifter.meta["clips"]] == ["002_01.bvh", "002_02.bvh"]
    assert lifter.meta["sources"] == ["a repository @ a commit"]
    assert "pose lifter: 2 clips" in capsys.readouterr().out
    (data / "131_02.bvh").write_text("HIERARCHY\n")
    assert cli.main(["train-lifter", str(data), "--out", str(tmp_path / "m.npz")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "evaluation" in err[0]
    assert not (tmp_path / "m.npz").exists()
    with pytest.raises(InputError):
        train([np.zeros((3, 17, 3))], steps=1)


def test_the_solves_cue_keeps_or_skips_bones_with_an_unseen_joint(monkeypatch):
    """Where the tracks did not see a joint (filled in time), the lifter read a guess: by default the solve's
    cue keeps it; with ``SOLVE_CUE_SEEN_ONLY`` it drops the bones that end there, in those frames only."""
    from core.joint_solve import pipeline
    from core.skeleton import JOINT_INDEX, SEGMENTS

    tracks, _ = synthesize(load_motion("builtin:walk", max_frames=10), kinds=(), noise_px=0.0, seed=3)
    seen = np.ones((10, 17), dtype=bool)
    seen[4:7, JOINT_INDEX["l_wrist"]] = False
    forearm = next(k for k, (_, c) in enumerate(SEGMENTS) if c == JOINT_INDEX["l_wrist"])
    others = [k for k in OUTPUT_BONES if k != forearm]

    kept = pipeline.solve_cue(tracks.xy, 50.0, tracks.image_size, seen=seen)
    assert np.isfinite(kept["dirs"][:, OUTPUT_BONES]).all()

    monkeypatch.setattr(pipeline, "SOLVE_CUE_SEEN_ONLY", True)
    cue = pipeline.solve_cue(tracks.xy, 50.0, tracks.image_size, seen=seen)
    assert np.isnan(cue["dirs"][4:7, forearm]).all()
    assert np.isfinite(cue["dirs"][[0, 3, 7, 9], forearm]).all()
    assert np.isfinite(cue["dirs"][:, others]).all()
    np.testing.assert_array_equal(cue["dirs"][:, others], kept["dirs"][:, others])


def test_directions_smoothed_over_frames_outvote_one_frames_slip():
    from core.motion_prior.lifter import smoothed_over_frames

    steady = np.tile(np.array([0.6, 0.0, 0.8]), (9, 2, 1))
    np.testing.assert_allclose(smoothed_over_frames(steady, 1.0), steady, atol=1e-12)
    slipped = steady.copy()
    slipped[4, 0, 2] *= -1.0                               # one frame's bone read the other way in depth
    slipped[6, 1] = np.nan                                 # a frame the lifter could not read
    out = smoothed_over_frames(slipped, 1.0)
    assert out[4, 0, 2] > 0.0                              # its neighbours outvote it
    np.testing.assert_allclose(np.linalg.norm(out[:, 0], axis=-1), 1.0, atol=1e-12)
    assert np.isnan(out[6, 1]).all() and np.isfinite(out[[5, 7], 1]).all()
    np.testing.assert_allclose(out[[5, 7], 1], steady[[5, 7], 1], atol=1e-12)
    np.testing.assert_array_equal(smoothed_over_frames(slipped, 0.0), slipped)


def test_the_joint_methods_cue_is_read_once_for_the_same_rays(monkeypatch):
    """The first sign choice and the solve's term read the same rays: the network runs once for both, the
    second read is the first's answer but not the same array (a caller may blank bones in it), and other
    rays are read anew."""
    from core.joint_solve.pipeline import lifter_cue

    lifter = load_default_lifter()
    runs = []
    read = lifter.bone_directions
    monkeypatch.setattr(lifter, "bone_directions", lambda r, fps=None: runs.append(len(r)) or read(r, fps))
    cam = _camera_view(load_motion("builtin:walk", max_frames=30).joints, [0.0, 30.0, 0.0], 6.0)
    rays = cam / np.linalg.norm(cam, axis=-1, keepdims=True)
    first = lifter_cue(rays)
    assert runs == [30]
    first[:] = np.nan
    again = lifter_cue(rays.copy())
    assert np.isfinite(again[:, np.array(OUTPUT_BONES)]).all()
    np.testing.assert_array_equal(again, lifter_cue(rays))
    assert runs == [30]
    other = lifter_cue(rays[::-1].copy())
    assert runs == [30, 30]
    assert not np.allclose(other[:, np.array(OUTPUT_BONES)], again[:, np.array(OUTPUT_BONES)])


def test_a_window_of_frames_is_read_between_frames_held_at_the_ends_and_across_lost_frames():
    from core.motion_prior.lifter import windowed

    x = np.arange(10.0)[:, None] * np.array([[1.0, -2.0]])           # frame f's inputs: (f, -2 f)
    out = windowed(x, (-0.1, 0.0, 0.25), 20.0)                       # 2 frames back, itself, 5 frames on
    assert out.shape == (10, 6)
    np.testing.assert_allclose(out[:, 2:4], x)
    np.testing.assert_allclose(out[4, 0:2], x[2])
    np.testing.assert_allclose(out[4, 4:6], x[9])
    np.testing.assert_allclose(out[0, 0:2], x[0])                    # held at the clip's ends
    np.testing.assert_allclose(out[8, 4:6], x[9])
    half = windowed(x, (0.0, 0.05), 30.0)                            # 1.5 frames on: between frames 1 and 2 ...
    np.testing.assert_allclose(half[0, 2:4], 1.5 * x[1])
    lost = x.copy()
    lost[5] = np.nan
    gap = windowed(lost, (-0.05, 0.0, 0.05), 20.0)
    np.testing.assert_allclose(gap[4, 4:6], x[4])                    # ... a lost frame reads as its nearest
    np.testing.assert_allclose(gap[6, 0:2], x[4])
    np.testing.assert_allclose(gap[3], windowed(x, (-0.05, 0.0, 0.05), 20.0)[3])
    assert np.isnan(windowed(np.full((4, 2), np.nan), (0.0, 0.1), 30.0)).all()


def test_training_windows_stay_in_their_clip_and_film_one_body_from_one_view():
    from core.motion_prior.train_lifter import Sequences, sample_windows

    clips = _tiny_clips()
    seq = Sequences(clips, mirror=False)
    assert len(seq) == 100
    first = bone_vectors(clips[0])
    got = seq.window(np.array([0, 10, 59, 60]), np.ones(4), (-0.1, 0.0, 0.1))   # 3 frames each way at 30 fps
    np.testing.assert_allclose(got[1], first[[7, 10, 13]])
    np.testing.assert_allclose(got[0], first[[0, 0, 3]])             # held at its clip's start ...
    np.testing.assert_allclose(got[2], first[[56, 59, 59]])          # ... and end, never the next clip's
    np.testing.assert_allclose(got[3, 1:], bone_vectors(clips[1])[[0, 3]])
    taps = (-0.2, 0.0, 0.2)
    a = sample_windows(seq, np.random.default_rng(2), 64, taps)
    b = sample_windows(seq, np.random.default_rng(2), 64, taps)
    np.testing.assert_array_equal(a[0], b[0])
    x, target = a
    assert x.shape == (64, 3 * N_INPUTS) and target.shape == (64, len(OUTPUT_BONES) * 3)
    assert np.isfinite(x).all() and np.isfinite(target).all()
    # the taps are pictures of one body in motion: neighbouring taps differ, but by far less than two
    # different windows' pictures do
    step = np.abs(x[:, :N_INPUTS] - x[:, N_INPUTS:2 * N_INPUTS]).mean()
    other = np.abs(x[:, N_INPUTS:2 * N_INPUTS] - x[::-1, N_INPUTS:2 * N_INPUTS]).mean()
    assert 0.0 < step < 0.5 * other


def test_a_temporal_lifter_reads_consecutive_frames_at_their_frame_rate(tmp_path):
    clips = _tiny_clips()
    lifter = train(clips, steps=20, width=16, layers=1, members=2, taps_s=(-0.1, 0.0, 0.1))
    assert lifter.temporal and lifter.taps_s == (-0.1, 0.0, 0.1)
    assert lifter.weights[0].shape == (2, 3 * N_INPUTS, 16)
    path = tmp_path / "t.npz"
    lifter.save(path)
    back = PoseLifter.load(path)
    assert back.temporal and back.taps_s == lifter.taps_s
    cam = _camera_view(load_motion("builtin:walk", max_frames=40).joints, [0.0, 30.0, 0.0], 6.0)
    rays = cam / np.linalg.norm(cam, axis=-1, keepdims=True)
    d = back.bone_directions(rays, 30.0)
    assert d.shape == (40, 16, 3) and np.isfinite(d[:, np.array(OUTPUT_BONES)]).all()
    assert not np.allclose(d[:, np.array(OUTPUT_BONES)], back.bone_directions(rays, 10.0)[:, np.array(OUTPUT_BONES)])
    with pytest.raises(ValueError):
        back.bone_directions(rays)                                   # no frame rate
    with pytest.raises(ValueError):
        back.bone_directions(rays[0], 30.0)                          # one picture
    with pytest.raises(InputError):
        train(clips, steps=1, taps_s=(-0.1, 0.1))                    # no tap on the answered frame


def test_train_lifter_command_trains_a_temporal_lifter_in_half_floats(tmp_path, capsys):
    data = _clip_folder(tmp_path)
    out = tmp_path / "t.npz"
    assert cli.main(["train-lifter", str(data), "--out", str(out), "--steps", "5", "--members", "1",
                     "--taps=-0.2,0,0.2", "--float16"]) == 0
    with np.load(out) as stored:
        assert stored["w0"].dtype == np.float16 and stored["w0"].shape == (3 * N_INPUTS, 256)
    lifter = PoseLifter.load(out)
    assert lifter.temporal and lifter.taps_s == (-0.2, 0.0, 0.2) and lifter.weights[0].dtype == np.float32
    capsys.readouterr()
    assert cli.main(["train-lifter", str(data), "--out", str(tmp_path / "u.npz"), "--taps", "a,b"]) == 2
    assert "--taps" in capsys.readouterr().err
