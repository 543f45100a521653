"""The learnt pose prior: training is deterministic, the shipped file loads, it prefers true poses, it
helps the depth signs, training refuses evaluation clips, and the self-check flags implausible frames."""

from __future__ import annotations

import numpy as np
import pytest

from core import cli
from core.camera import rotation_matrix
from core.errors import InputError
from core.io.bvh import format_bvh, make_bvh
from core.motion_prior import DEFAULT_PATH, PosePrior, load_default
from core.motion_prior.evaluation import frame_errors
from core.motion_prior.features import bone_vectors, joints_from_bones, mirrored_left_right, pose_features
from core.motion_prior.train import LICENCE, MIXED_SOURCE, SOURCE, refuse_evaluation, train
from core.skeleton import JOINT_INDEX
from core.synthetic.motion import load_motion
from core.synthetic.synth import synthesize


def _tiny_set():
    """Two short built-in clips, a few dozen frames: a synthetic training set."""
    return [load_motion("builtin:walk", max_frames=60).joints, load_motion("builtin:run", max_frames=40).joints]


def test_training_is_deterministic():
    a = train(_tiny_set(), components=3, iterations=10)
    b = train(_tiny_set(), components=3, iterations=10)
    np.testing.assert_array_equal(a.means, b.means)
    np.testing.assert_array_equal(a.covariances, b.covariances)
    np.testing.assert_array_equal(a.weights, b.weights)


def test_save_and_load_round_trip(tmp_path):
    prior = train(_tiny_set(), components=2, iterations=5, meta={"source": "test"})
    path = tmp_path / "p.npz"
    prior.save(path)
    back = PosePrior.load(path)
    poses = load_motion("builtin:walk", max_frames=20).joints
    np.testing.assert_allclose(back.log_likelihood(poses), prior.log_likelihood(poses), rtol=1e-4, atol=1e-3)
    assert back.meta["source"] == "test"


def test_shipped_prior_loads_and_records_its_data():
    assert DEFAULT_PATH.is_file()
    assert DEFAULT_PATH.stat().st_size < 5_000_000
    prior = load_default()
    assert prior.meta["source"] == SOURCE
    clips = prior.meta["clips"]
    assert clips and all(len(c["sha256"]) == 64 for c in clips)
    assert not any(c["name"].split("_")[0].lstrip("0") in ("1", "131") for c in clips)


def test_features_ignore_heading_and_place():
    poses = load_motion("builtin:walk", max_frames=10).joints
    turn = rotation_matrix(np.array([10.0, 70.0, -20.0]))
    moved = poses @ turn.T + np.array([3.0, -1.0, 8.0])
    np.testing.assert_allclose(pose_features(moved), pose_features(poses), atol=1e-9)


def test_bones_round_trip():
    poses = load_motion("builtin:run", max_frames=5).joints
    np.testing.assert_allclose(joints_from_bones(bone_vectors(poses), poses[:, 0]), poses, atol=1e-12)


def test_left_right_mirror_is_a_pose_not_a_depth_mirror():
    """Mirrored and relabelled, a walk stays as likely; mirrored in depth (names kept), it does not."""
    prior = load_default()
    poses = load_motion("builtin:walk", max_frames=90).joints
    relabelled = mirrored_left_right(poses)
    reflected = poses * np.array([1.0, 1.0, -1.0])
    assert np.median(prior.log_likelihood(relabelled)) > np.median(prior.log_likelihood(reflected)) + 5.0


@pytest.mark.parametrize("clip", ["builtin:walk", "builtin:run"])
def test_prior_prefers_true_limbs_over_depth_flipped_ones(clip):
    """Seen from the side, each limb bone flipped in depth alone: the true pose scores higher on most."""
    prior = load_default()
    poses = load_motion(clip, max_frames=150).joints
    view = rotation_matrix(np.array([0.0, 90.0, 0.0]))
    cam = poses @ view.T
    gains = prior.flip_gains(cam)
    b = bone_vectors(cam)
    clear = np.abs(b[..., 2]) / np.linalg.norm(b, axis=-1) > 0.3
    limbs = [JOINT_INDEX[n] - 1 for n in ("l_knee", "l_ankle", "r_knee", "r_ankle")]
    right = (gains < 0)[:, limbs][clear[:, limbs]]
    assert right.size > 50
    assert right.mean() > 0.8


def test_prior_improves_the_depth_signs_of_a_real_clip(shared_bvh_dir):
    """The joint method's sign choice with everything else true (camera, pelvis depth, lengths; 0 px) on a
    real walk seen from five sides: a lower mean error with the prior than with the geometric rules alone."""
    from core.joint_solve.signs_dp import resolve_signs
    from core.joint_solve.taylor import unit_rays

    motion = load_motion(str(shared_bvh_dir / "131_01.bvh"), max_frames=150)
    plain, learnt = [], []
    for view in (0.0, 40.0, 80.0, 120.0, -60.0):
        tracks, truth = synthesize(motion, kinds=(), noise_px=0.0, seed=1, view_offset_deg=view)
        R = rotation_matrix(truth.rotvec_deg)
        X = np.einsum("fab,fjb->fja", R, truth.joints_3d)
        rays = unit_rays(tracks.xy, truth.focal_mm[:, None], tracks.image_size)
        plain.append(frame_errors(resolve_signs(rays, truth.class_lengths_m, X[:, 0, 2], R)[1], X)[0].mean())
        learnt.append(frame_errors(resolve_signs(rays, truth.class_lengths_m, X[:, 0, 2], R,
                                                 prior=load_default())[1], X)[0].mean())
    assert np.mean(learnt) < 0.9 * np.mean(plain)


def test_frame_errors_sees_a_mirrored_limb():
    X = load_motion("builtin:walk", max_frames=3).joints
    bad = X.copy()
    knee, ankle = JOINT_INDEX["l_knee"], JOINT_INDEX["l_ankle"]
    bad[:, ankle] = 2 * bad[:, knee] - bad[:, ankle]          # the shank pointing up from the knee
    err, mirrored = frame_errors(bad, X)
    assert mirrored.all()
    assert not frame_errors(X, X)[1].any()
    assert np.allclose(frame_errors(X, X)[0], 0.0, atol=1e-9)


def test_training_refuses_evaluation_clips(tmp_path):
    for name in ("01_01.bvh", "131_03.bvh", "0131_01.bvh"):
        with pytest.raises(InputError, match="evaluation"):
            refuse_evaluation(tmp_path / name)
    with pytest.raises(InputError, match="evaluation"):
        refuse_evaluation(tmp_path / "shared" / "data" / "bvh" / "walk.bvh")
    refuse_evaluation(tmp_path / "002_01.bvh")          # a training subject passes


def test_training_refuses_a_renamed_copy_of_an_evaluation_clip(tmp_path, shared_bvh_dir):
    copy = tmp_path / "002_09.bvh"
    copy.write_bytes((shared_bvh_dir / "acrnn_martial_04.bvh").read_bytes())
    with pytest.raises(InputError, match="evaluation"):
        refuse_evaluation(copy)


def _cc_tree():
    """A Character Creator style skeleton (``CC_Base_L_Thigh`` names), Y up, facing +Z, left = +X, cm."""
    t = [("CC_Base_Hip", None, (0, 95, 0))]
    for side, sx in (("L", 1), ("R", -1)):
        t += [(f"CC_Base_{side}_Thigh", "CC_Base_Hip", (sx * 9, -5, 0)),
              (f"CC_Base_{side}_Calf", f"CC_Base_{side}_Thigh", (0, -43, 0)),
              (f"CC_Base_{side}_Foot", f"CC_Base_{side}_Calf", (0, -41, 0)),
              (f"CC_Base_{side}_ToeBase", f"CC_Base_{side}_Foot", (0, -5, 13)),
              (f"CC_Base_{side}_ToeBase_End", f"CC_Base_{side}_ToeBase", (0, 0, 5))]
    t += [("CC_Base_Waist", "CC_Base_Hip", (0, 10, 0)), ("CC_Base_Spine01", "CC_Base_Waist", (0, 12, 0)),
          ("CC_Base_Spine02", "CC_Base_Spine01", (0, 12, 0)), ("CC_Base_NeckTwist01", "CC_Base_Spine02", (0, 16, 0)),
          ("CC_Base_Head", "CC_Base_NeckTwist01", (0, 9, 0)), ("CC_Base_Head_End", "CC_Base_Head", (0, 18, 0))]
    for side, sx in (("L", 1), ("R", -1)):
        t += [(f"CC_Base_{side}_Clavicle", "CC_Base_Spine02", (sx * 4, 12, 0)),
              (f"CC_Base_{side}_Upperarm", f"CC_Base_{side}_Clavicle", (sx * 14, 0, 0)),
              (f"CC_Base_{side}_Forearm", f"CC_Base_{side}_Upperarm", (sx * 28, 0, 0)),
              (f"CC_Base_{side}_Hand", f"CC_Base_{side}_Forearm", (sx * 25, 0, 0)),
              (f"CC_Base_{side}_Hand_End", f"CC_Base_{side}_Hand", (sx * 9, 0, 0))]
    return t


def _write_clip(path, seed, n=40):
    tree = _cc_tree()
    bvh = make_bvh(tree)
    rng = np.random.default_rng(seed)
    t = np.arange(n)[:, None] / 30.0
    k = bvh.motion.shape[1]
    motion = 10.0 * np.sin(2 * np.pi * rng.uniform(0.5, 1.5, k) * t + rng.uniform(0, 6, k))
    motion[:, :3] = np.asarray(tree[0][2]) + np.array([0, 0, 120.0]) * t
    path.write_text(format_bvh(make_bvh(tree, motion=motion)))


def test_train_prior_command_is_deterministic_and_records_its_clips(tmp_path, capsys):
    data = tmp_path / "clips"
    data.mkdir()
    for i in range(3):
        _write_clip(data / f"002_0{i + 1}.bvh", seed=i)
    outs = []
    for name in ("a.npz", "b.npz"):
        assert cli.main(["train-prior", str(data), "--out", str(tmp_path / name), "--components", "2"]) == 0
        outs.append(PosePrior.load(tmp_path / name))
    np.testing.assert_array_equal(outs[0].means, outs[1].means)
    np.testing.assert_array_equal(outs[0].covariances, outs[1].covariances)
    assert [c["name"] for c in outs[0].meta["clips"]] == ["002_01.bvh", "002_02.bvh", "002_03.bvh"]
    assert outs[0].meta["source"] == SOURCE and "licence" in outs[0].meta
    assert "2 components" in capsys.readouterr().out


def test_train_prior_records_the_licences_it_is_given(tmp_path):
    data = tmp_path / "clips"
    data.mkdir()
    for i in range(2):
        _write_clip(data / f"002_0{i + 1}.bvh", seed=i)
    assert cli.main(["train-prior", str(data), "--out", str(tmp_path / "cmu.npz"), "--components", "2"]) == 0
    assert PosePrior.load(tmp_path / "cmu.npz").meta["licence"] == LICENCE
    assert cli.main(["train-prior", str(data), "--out", str(tmp_path / "mixed.npz"), "--components", "2",
                     "--licence", "CMU clips: the CMU terms", "--licence", "idle clips: MIT"]) == 0
    mixed = PosePrior.load(tmp_path / "mixed.npz").meta
    assert mixed["licence"] == "CMU clips: the CMU terms; idle clips: MIT"
    assert mixed["source"] == MIXED_SOURCE                 # no longer the CMU database's name alone
    assert cli.main(["train-prior", str(data), "--out", str(tmp_path / "named.npz"), "--components", "2",
                     "--licence", "CMU clips: the CMU terms", "--licence", "idle clips: MIT",
                     "--source", "cmu: a repository", "--source", "idle: another"]) == 0
    assert PosePrior.load(tmp_path / "named.npz").meta["source"] == "cmu: a repository; idle: another"


def test_train_prior_command_refuses_an_evaluation_name(tmp_path, capsys):
    clip = tmp_path / "131_01.bvh"
    clip.write_text("HIERARCHY\n")
    code = cli.main(["train-prior", str(tmp_path), "--out", str(tmp_path / "p.npz")])
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "evaluation" in err[0]
    assert not (tmp_path / "p.npz").exists()


def test_single_image_signs_keep_the_users_choice_with_the_prior():
    """The prior picks the default signs; a sign the user holds stays, and its flip cost is infinite."""
    from core.single_image.signs import choose_signs

    X = load_motion("builtin:walk", max_frames=40).joints[30]
    view = rotation_matrix(np.array([0.0, 60.0, 0.0]))
    cam = X @ view.T
    uv = cam[:, :2] * 100.0
    seg = np.linalg.norm(bone_vectors(cam), axis=-1)
    free = choose_signs(uv, seg, 100.0)
    knee = JOINT_INDEX["l_knee"] - 1
    held = choose_signs(uv, seg, 100.0, fixed={knee: -free.signs[knee]})
    assert held.signs[knee] == -free.signs[knee]
    assert np.isinf(held.flip_cost[knee]) and np.isfinite(free.flip_cost[knee])
    assert held.cost >= free.cost


def test_rate_term_prefers_smooth_motion():
    """The change-over-time term scores a clip above the same frames in a shuffled order."""
    prior = load_default()
    poses = load_motion("builtin:walk", max_frames=120).joints
    shuffled = poses[np.random.default_rng(0).permutation(len(poses))]
    assert prior.rate_log_likelihood(poses, 30.0).mean() > prior.rate_log_likelihood(shuffled, 30.0).mean()


def test_the_arms_prior_cap_bounds_its_say(monkeypatch):
    """The arms' signs move away from their geometric choice (the prior capped at nothing) less with a small
    cap on the prior than without one, and without one they move."""
    from core.joint_solve import signs_dp
    from core.joint_solve.taylor import unit_rays

    tracks, truth = synthesize(load_motion("builtin:run", max_frames=90), kinds=(), noise_px=1.0, seed=1,
                               view_offset_deg=40.0)
    R = rotation_matrix(truth.rotvec_deg)
    X = np.einsum("fab,fjb->fja", R, truth.joints_3d)
    rays = unit_rays(tracks.xy, truth.focal_mm[:, None], tracks.image_size)
    arms = [JOINT_INDEX[n] - 1 for n in ("l_shoulder", "l_elbow", "l_wrist", "r_shoulder", "r_elbow", "r_wrist")]

    def arm_signs(factor, cap):
        monkeypatch.setattr(signs_dp, "PRIOR_ARM_FACTOR", factor)
        monkeypatch.setattr(signs_dp, "PRIOR_ARM_CAP", cap)
        signs, _ = signs_dp.resolve_signs(rays, truth.class_lengths_m, X[:, 0, 2], R, prior=load_default(),
                                          prior_weight=30.0)
        return signs[:, arms]

    geometric = arm_signs(1.0, 0.0)
    free = np.sum(arm_signs(1.0, None) != geometric)
    capped = np.sum(arm_signs(1.0, 1.0) != geometric)
    assert free > 0
    assert capped < free


def test_the_mixtures_density_is_the_sum_of_its_components():
    """The fast scoring (every component's whitening in one product) against the components one by one."""
    from scipy.special import logsumexp

    from core.motion_prior.model import component_log_densities

    prior = load_default()
    x = prior.means[0] + np.random.default_rng(8).normal(0.0, 0.3, (5000, prior.means.shape[1]))
    direct = logsumexp(component_log_densities(x, prior.weights, prior.means, prior.covariances), axis=1)
    np.testing.assert_allclose(prior.log_likelihood_features(x), direct, rtol=1e-10, atol=1e-8)
