"""Several synchronized views (core.multiview): triangulation with given cameras, cameras calibrated
from the person alone, a view's outliers outvoted, constant bone lengths, the calibration file and the
command line."""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest

from core.cli import main
from core.errors import InputError
from core.evaluation.metrics import mpjpe_per_frame_m
from core.multiview import estimate_multiview, read_calibration, write_calibration
from core.multiview.synth import film_views, ring_cameras
from core.result import read_estimate_json
from core.skeleton import proportions, segment_lengths
from core.synthetic.motion import load_motion
from core.tracks import write_tracks_json


@pytest.fixture(scope="module")
def walk():
    motion = load_motion("builtin:walk", max_frames=150)
    cams = ring_cameras(motion, 3, seed=1)
    return motion, cams, film_views(motion, cams, noise_px=1.0, seed=1)


def _errors(est, motion, cam0):
    joints = np.array([f.joints_3d for f in est.frames])
    pp = 100 * np.abs(est.proportions_vector() - proportions(motion.class_lengths))
    return 1000 * mpjpe_per_frame_m(joints, cam0.to_camera(motion.joints)), pp, joints


def test_known_cameras_triangulate_the_person_with_constant_bones(walk):
    motion, cams, views = walk
    est = estimate_multiview(views, cameras=cams)
    mm, pp, joints = _errors(est, motion, cams[0])
    assert mm < 25 and pp.max() < 0.3, (mm, pp.max())
    bones = segment_lengths(joints)
    assert np.abs(bones - bones[0]).max() < 1e-9                      # constant by construction
    assert max(est.diagnostics["view_reprojection_px"]) < 3.0
    assert est.diagnostics["calibration"] == "given" and len(est.diagnostics["cameras"]) == 3


def test_cameras_from_the_person_alone(walk):
    motion, cams, views = walk
    est = estimate_multiview(views)
    mm, pp, _ = _errors(est, motion, cams[0])
    assert mm < 60 and pp.max() < 0.8, (mm, pp.max())
    # metric: the person is as tall as said, so the cameras stand where they stood
    c = est.diagnostics["cameras"]
    baseline = np.linalg.norm(np.array(c[1]["position"]) - np.array(c[0]["position"]))
    assert baseline == pytest.approx(np.linalg.norm(cams[1].position - cams[0].position), rel=0.15)
    assert est.diagnostics["calibration"]["bundle_frames"] > 0
    # the lenses are well pinned by a walk seen from three sides: no doubt said
    from core.multiview.pipeline import LENS_DOUBT_PCT

    assert max(est.diagnostics["calibration"]["focal_sigma_pct"]) < LENS_DOUBT_PCT
    assert not any("loosely pinned" in w for w in est.diagnostics["warnings"])


def test_a_lens_the_take_barely_pins_is_said(walk):
    """One second of the walk from two views: the bones change depth too little to pin the lenses, and
    the estimate says so (the bundle adjustment's own uncertainty) instead of handing over a lens
    several percent off in silence."""
    from core.multiview.pipeline import LENS_DOUBT_PCT

    motion, cams, views = walk
    est = estimate_multiview([v.frames_between(0, 29) for v in views[:2]])
    sigma = est.diagnostics["calibration"]["focal_sigma_pct"]
    assert len(sigma) == 2 and max(sigma) > LENS_DOUBT_PCT
    doubts = [w for w in est.diagnostics["warnings"] if "loosely pinned" in w]
    assert doubts and "Save / Load View Cameras" in doubts[0]
    assert not any("detector's tracks" in w for w in est.diagnostics["warnings"])     # clean tracks


def test_two_views_calibrated_from_a_detectors_tracks_are_said():
    """Two views of a detector's tracks (outliers, exchanged limbs) and cameras from the person: no third
    view outvotes the mistakes, and the estimate says so; with the cameras given it does not."""
    from core.synthetic.footage_sim.detector import TYPICAL

    motion = load_motion("builtin:walk", max_frames=120)
    cams = ring_cameras(motion, 2, seed=2)
    views = film_views(motion, cams, noise_px=1.0, detector=TYPICAL, seed=2)
    found = estimate_multiview(views).diagnostics
    said = [w for w in found["warnings"] if "detector's tracks" in w]
    assert len(said) == 1 and "Load View Cameras" in said[0]
    # joints missing in both views (the detector's runs) leave the lenses' uncertainty computable
    sigma = found["calibration"]["focal_sigma_pct"]
    assert sigma is not None and np.all(np.isfinite(sigma)) and min(sigma) > 0
    given = estimate_multiview(views, cameras=cams).diagnostics["warnings"]
    assert not any("detector's tracks" in w for w in given)


def test_one_view_thrown_off_is_outvoted(walk):
    from core.multiview.triangulate import triangulate

    motion, cams, views = walk
    rng = np.random.default_rng(4)
    pixels = np.stack([np.where(v.present[..., None], v.xy, np.nan) for v in views])
    hit = rng.random(pixels.shape[1:3]) < 0.05
    pixels[2][hit] += rng.choice([-1, 1], size=(int(hit.sum()), 2)) * 30.0    # near the body: 2D cleaning keeps them
    plain, _ = triangulate(pixels, cams, robust=False)
    robust, used = triangulate(pixels, cams)

    def err(points):
        return 1000 * np.linalg.norm(points - motion.joints, axis=-1)

    assert np.nanmedian(err(robust)[hit]) < 0.3 * np.nanmedian(err(plain)[hit])
    assert (~used[2][hit]).mean() > 0.8                       # the thrown points were the ones dropped
    assert (~used[:, ~hit]).mean() < 0.01                     # and hardly any good one
    thrown = views[:2] + [views[2].replaced(xy=np.where(np.isfinite(pixels[2]), pixels[2], np.nan))]
    clean_mm = _errors(estimate_multiview(views, cameras=cams), motion, cams[0])[0]
    assert _errors(estimate_multiview(thrown, cameras=cams), motion, cams[0])[0] < clean_mm + 4.0


def test_bad_input_is_refused_in_one_line(walk, tmp_path):
    motion, cams, views = walk
    with pytest.raises(InputError, match="2 to 8 views"):
        estimate_multiview(views[:1])
    with pytest.raises(InputError, match="frame rates"):
        estimate_multiview([views[0], views[1].replaced(fps=60.0)])
    with pytest.raises(InputError, match="2 cameras for 3 views"):
        estimate_multiview(views, cameras=cams[:2])
    path = tmp_path / "cal.json"
    path.write_text(json.dumps({"format": "skeleton-tracks"}))
    with pytest.raises(InputError, match="not a multiview-calibration file"):
        read_calibration(path)
    write_calibration(cams, path)
    back = read_calibration(path)
    assert np.allclose(back[2].rotation, cams[2].rotation) and back[1].focal_px == pytest.approx(cams[1].focal_px)


def test_command_line_calibrates_then_reuses_the_cameras(walk, tmp_path):
    motion, cams, views = walk
    paths = []
    for k, v in enumerate(views[:2]):
        paths.append(str(tmp_path / f"view{k}.json"))
        write_tracks_json(v, paths[-1])
    out, cal, again = (str(tmp_path / n) for n in ("a.json", "cal.json", "b.json"))
    assert main(["estimate-multiview", *paths, "--out", out, "--cameras-out", cal]) == 0
    assert main(["estimate-multiview", *paths, "--out", again, "--calibration", cal, "--offsets", "0,0"]) == 0
    a, b = read_estimate_json(out), read_estimate_json(again)
    assert np.abs(a.proportions_vector() - b.proportions_vector()).max() < 1e-3
    assert len(a.frames) == len(motion.joints)
    assert main(["estimate-multiview", paths[0], "--out", out]) == 2                  # one view: refused
    assert main(["estimate-multiview", *paths, "--out", out, "--offsets", "0,x"]) == 2
    assert read_estimate_json(again).diagnostics["sync"] == "given"


def test_views_started_at_different_moments_are_synchronised():
    from core.multiview.sync import frame_offset

    motion = load_motion("builtin:walk", max_frames=160)
    cams = ring_cameras(motion, 3, seed=3)
    full = film_views(motion, cams, noise_px=1.0, seed=3)

    def cut(view, a, b):
        return view.replaced(xy=view.xy[a:b], conf=view.conf[a:b])

    views = [cut(full[0], 5, 155), cut(full[1], 12, 160), cut(full[2], 1, 140)]
    d, report = frame_offset(views[0], views[1])
    assert d == -7 and report["error_px"] < 1.0 < report["tried"]
    est = estimate_multiview(views, cameras=cams)
    assert est.diagnostics["frame_offsets"] == [0, -7, 4] and len(est.frames) == 150
    joints = np.array([f.joints_3d for f in est.frames])
    mm = 1000 * mpjpe_per_frame_m(joints, cams[0].to_camera(motion.joints[5:155]))
    assert mm < 25, mm
    given = estimate_multiview(views, cameras=cams, offsets=[0, -7, 4])
    assert given.diagnostics["sync"] == "given"
    with pytest.raises(InputError, match="one frame offset per view"):
        estimate_multiview(views, cameras=cams, offsets=[0, 1])


def test_bundle_adjustment_finds_the_lenses_from_a_wrong_start(walk):
    """From lenses 15 % off, the Schur-complement bundle adjustment reaches the optimum it reaches
    from the true cameras (the bones' constancy pins the lenses)."""
    from core.multiview.bundle import bundle_adjust
    from core.multiview.cameras import ViewCamera
    from core.multiview.triangulate import triangulate

    motion, cams, views = walk
    r0, c0 = cams[0].rotation, cams[0].position
    true = [ViewCamera(c.name, c.image_size, c.focal_px, c.rotation @ r0.T, r0 @ (c.position - c0)) for c in cams]
    pixels = np.stack([np.where(v.present[..., None], v.xy, np.nan) for v in views])[:, ::3]

    def adjust(start):
        pts, _ = triangulate(pixels, start)
        pts = np.where(np.isfinite(pts), pts, np.nanmean(pts.reshape(-1, 3), axis=0))
        lengths = np.nanmedian(segment_lengths(pts), axis=0)        # the 16 bones
        for slack in (0.2, 0.05, 0.01):
            start, pts, lengths, report = bundle_adjust(start, pixels, pts, lengths, slack=slack)
        return start, report

    wrong = [ViewCamera(c.name, c.image_size, c.focal_px * s, c.rotation, c.position)
             for c, s in zip(true, (1.15, 0.85, 1.1))]
    from_truth, _ = adjust(true)
    found, report = adjust(wrong)
    assert report["cost"] < report["cost_start"]
    for a, b, t in zip(found, from_truth, true):
        assert a.focal_px == pytest.approx(b.focal_px, rel=2e-3)
        assert a.focal_px == pytest.approx(t.focal_px, rel=0.02)
        assert np.degrees(np.linalg.norm(a.rotation - t.rotation)) < 0.5    # chord, ~ the angle in radians


def test_a_cancel_stops_between_stages(walk):
    from core.errors import Cancelled

    _, cams, views = walk
    asked = []

    def cancel_at_the_cameras():
        asked.append(1)
        return len(asked) >= 3          # cleaning, synchronising, then stop before the cameras

    with pytest.raises(Cancelled):
        estimate_multiview(views, should_cancel=cancel_at_the_cameras)
    assert len(asked) == 3


def test_joints_one_view_sees_are_placed_on_its_ray_by_the_pose_prior(walk, monkeypatch):
    """A leg's knee and ankle and an arm's elbow and wrist hidden from every view but the first for 90 frames:
    placed on the first view's rays with the depth the pose prior picks, they come out nearer the truth than
    filled in time, and nearer than with the candidate closest to that time fill."""
    import core.motion_prior as motion_prior
    from core.multiview import pipeline as mv
    from core.skeleton import JOINT_INDEX

    motion, cams, views = walk
    hidden = [JOINT_INDEX[n] for n in ("l_knee", "l_ankle", "r_elbow", "r_wrist")]
    blocked = [copy.deepcopy(v) for v in views]
    for v in blocked[1:]:
        v.xy[30:120, hidden] = np.nan
    truth = cams[0].to_camera(motion.joints)[30:120][:, hidden]

    def hidden_error():
        est = estimate_multiview(blocked, cameras=cams)
        joints = np.array([f.joints_3d for f in est.frames])[30:120][:, hidden]
        return float(np.mean(np.linalg.norm(joints - truth, axis=-1)))

    with_prior = hidden_error()
    monkeypatch.setattr(mv, "USE_ONE_VIEW", False)
    time_fill = hidden_error()
    monkeypatch.setattr(mv, "USE_ONE_VIEW", True)
    monkeypatch.setattr(motion_prior, "load_default", lambda: None)
    nearest = hidden_error()
    assert with_prior < nearest < time_fill, (with_prior, nearest, time_fill)
