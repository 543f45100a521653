"""core.review: residual lines and colours, problem frames, take comparison, the headless HTML report."""

from __future__ import annotations

import copy
import re

import numpy as np
import pytest

from core.camera import pan_tilt_roll_matrix, rotvec_deg
from core.result import Estimate, FrameEstimate
from core.review import compare_takes, reprojected_pixels, residual_colours, residual_lines
from core.review.problems import POOR_FIT, REJECTED, SWAPPED, poor_fit_limit_px, problem_starts
from core.review.report import pan_tilt_roll_deg, proportion_rows, review_html, write_review_html
from core.review.residuals import BAD, FAIR, GOOD
from core.review.svg_plot import line_plot
from core.review.take_compare import TakeComparison
from core.self_check import SelfCheckSettings
from core.synthetic.motion import load_motion
from core.synthetic.synth import synthesize
from core.synthetic.truth import truth_as_estimate


@pytest.fixture(scope="module")
def clip():
    tracks, truth = synthesize(load_motion("builtin:walk", max_frames=40), kinds=("pan", "zoom"), seed=6,
                               noise_px=0.0)
    return tracks, truth_as_estimate(truth)


def test_reprojection_of_the_truth_lands_on_noise_free_tracks(clip):
    tracks, est = clip
    uv = reprojected_pixels(est, tracks.image_size)
    _, _, residual, drawn = residual_lines(tracks.xy, tracks.present, uv)
    assert drawn.sum() == tracks.present.sum()
    assert np.nanmax(residual) < 1e-6


def test_frames_without_joints_and_missing_tracks_draw_no_line(clip):
    tracks, est = clip
    est = Estimate(est.method, est.proportions, est.focal_mm, [FrameEstimate(**vars(f)) for f in est.frames])
    est.frames[3].joints_3d = None
    present = tracks.present.copy()
    present[5, 2] = False
    _, _, residual, drawn = residual_lines(tracks.xy, present, reprojected_pixels(est, tracks.image_size))
    assert not drawn[3].any() and not drawn[5, 2] and drawn[5].sum() == 16
    assert np.isnan(residual[3]).all()


def test_residual_colours_ramp_green_yellow_red():
    c = residual_colours(np.array([0.0, 4.0, 8.0, 50.0, np.nan]), limit_px=4.0)
    np.testing.assert_allclose(c[0], GOOD)
    np.testing.assert_allclose(c[1], FAIR)
    np.testing.assert_allclose(c[2], BAD)
    np.testing.assert_allclose(c[3], BAD)
    assert c[4, 0] == c[4, 1] == c[4, 2]                       # grey where unknown
    mid = residual_colours(np.array([2.0]), limit_px=4.0)[0]
    np.testing.assert_allclose(mid, (np.array(GOOD) + np.array(FAIR)) / 2)


def _est(n=30, rep=1.0):
    frames = [FrameEstimate(reprojection_px=rep) for _ in range(n)]
    props = {"hip": 0.05, "thigh": 0.25, "shank": 0.24, "lower_spine": 0.07, "upper_spine": 0.16,
             "neck": 0.065, "head": 0.12, "clavicle": 0.1, "upper_arm": 0.17, "forearm": 0.15}
    return Estimate("test", props, 50.0, frames)


def test_problem_runs_start_where_each_run_starts():
    est = _est()
    for i in (3, 4, 5, 20):
        est.frames[i].rejected = ["l_wrist"]
    est.frames[10].swapped = ["legs"]
    est.frames[25].reprojection_px = 20.0
    s = SelfCheckSettings()
    limit = max(s.fit_floor_px, s.poor_frame_ratio * 1.0)       # over a 1 px median
    assert poor_fit_limit_px(est) == pytest.approx(limit)
    assert sorted(problem_starts(est)) == sorted([(REJECTED, 3), (REJECTED, 20), (SWAPPED, 10), (POOR_FIT, 25)])
    est.frames[25].reprojection_px = 0.99 * limit
    assert (POOR_FIT, 25) not in problem_starts(est)


def test_take_comparison_finds_the_frame_and_joint_that_moved():
    rng = np.random.default_rng(0)
    joints = rng.normal(size=(10, 17, 3))
    moved = joints.copy()
    moved[4, 7] += [0.0, 0.03, 0.04]                              # 50 mm at one joint of one frame
    la = np.linspace(0.1, 0.5, 10)
    lb = la.copy()
    lb[2] += 0.012
    result = compare_takes(la, np.arange(10), joints, lb, np.arange(2, 12), moved[:10] * 1.0)
    # take B's frames are 2..11: common frames 2..9, compared frame by frame number
    assert list(result.frames) == list(range(2, 10))
    result = compare_takes(la, np.arange(10), joints, lb, np.arange(10), moved)
    assert result.worst_frames(1) == [(4, pytest.approx(50.0 / 17))]
    assert result.max_mm == pytest.approx(50.0 / 17) and result.mean_mm == pytest.approx(5.0 / 17)
    assert result.worst_joints(1)[0][1] == pytest.approx(5.0)
    np.testing.assert_allclose(result.length_diff_mm, [0, 0, 12.0] + [0] * 7, atol=1e-9)
    again = TakeComparison.from_dict(result.to_dict())
    np.testing.assert_allclose(again.frame_mm, result.frame_mm)
    rows = result.summary_rows()
    assert rows[0] == ["Bone", "A cm", "B cm", "B-A"] and rows[3][3] == "+1.2"
    summary = result.summary()
    assert summary["frames"] == 10 and summary["worst_frames"][0][0] == 4 and summary["rows"] == rows
    none = compare_takes(la, [0, 1], joints[:2], lb, [5, 6], joints[5:7])
    assert none.frames.size == 0 and np.isnan(none.mean_mm) and none.worst_frames() == []
    assert none.summary() == {"frames": 0}


def test_pan_tilt_roll_undo_the_camera_model():
    est = _est(n=3)
    angles = np.array([[10.0, -5.0, 2.0], [-30.0, 12.0, -1.0], [0.0, 0.0, 0.0]])
    r = pan_tilt_roll_matrix(angles[:, 0], angles[:, 1], angles[:, 2])
    for fr, rv in zip(est.frames, rotvec_deg(r)):
        fr.rotvec_deg = tuple(rv)
    np.testing.assert_allclose(pan_tilt_roll_deg(est), angles, atol=1e-9)


def test_proportions_read_against_the_adult():
    est = _est()
    rows = {name: verdict for name, _, _, _, verdict in proportion_rows(est)}
    assert set(rows.values()) <= {"typical", "unusual"}
    est.proportions["head"] = 0.6
    assert dict((r[0], r[4]) for r in proportion_rows(est))["head"] == "implausible"


def test_report_says_warnings_problems_and_plots(clip, tmp_path):
    tracks, est = clip[0], copy.deepcopy(clip[1])
    est.diagnostics = {"warnings": ["focal length not determined"], "spells": [{"start": 0, "end": 19, "kind": "pan"}],
                       "self_check": {"flags": [{"code": "fit", "message": "fit: 12 % of frames fit poorly"}]}}
    for i, fr in enumerate(est.frames):
        fr.reprojection_px = 9.0 if i == 30 else 1.0
    est.frames[7].rejected = ["r_knee"]
    path = write_review_html(str(tmp_path / "r.html"), est, title="walk <test>", fps=tracks.fps,
                             image_size=tracks.image_size, first_frame=1)
    page = open(path, encoding="utf-8").read()
    assert "<title>walk &lt;test&gt;</title>" in page
    assert "focal length not determined" in page and "fit: 12 % of frames fit poorly" in page
    assert "fit: poor: 1 frame (30)" in page and "input: rejected joints: 1 frame (7)" in page
    assert len(re.findall(r"<svg ", page)) == 3 and f"poor fit &gt; {poor_fit_limit_px(est):.1f} px" in page
    assert "Proportions against the average adult" in page and page.count("typical") >= 5
    clean = _est()
    assert "No warnings" in review_html(clean)


def test_report_lists_the_bones_flipped_by_hand(clip):
    from core.motion_cleanup.depth_flip import flip_depth

    est = clip[1]
    assert "Corrected by hand" not in review_html(est)
    fixed, report = flip_depth(est, "l_wrist", 10, 19)
    page = review_html(fixed, first_frame=1)
    assert "Corrected by hand" in page
    assert f"l_wrist turned to its other side in depth on frames 11-20 ({report['frames']} flipped)" in page


def test_report_lists_the_feet_planted_by_hand(clip):
    from core.motion_cleanup.foot_plant import plant_foot

    fixed, report = plant_foot(clip[1], "r", 20, 29)
    page = review_html(fixed, first_frame=1)
    assert "Corrected by hand" in page
    assert f"the right foot held still on frames 21-30 (it had strayed up to {100 * report['slide_m']:.0f} cm)" in page


def test_line_plot_breaks_at_nan_and_survives_constant_series():
    svg = line_plot([("a", np.arange(6), np.array([1, 2, np.nan, 3, 4, 5.0]), "#000")],
                    title="t", x_label="x", y_label="y")
    assert svg.count("<polyline") == 2
    flat = line_plot([("a", np.arange(4), np.zeros(4), "#000")], title="t", x_label="x", y_label="y")
    assert "<polyline" in flat and "nan" not in flat
    empty = line_plot([("a", np.arange(3), np.full(3, np.nan), "#000")], title="t", x_label="x", y_label="y")
    assert "<polyline" not in empty and empty.endswith("</svg>")


def test_report_command_writes_the_page_beside_the_estimate(clip, tmp_path, capsys):
    from core.cli import main
    from core.result import write_estimate_json

    tracks, est = clip
    path = tmp_path / "walk_result.json"
    write_estimate_json(est, path)
    assert main(["report", str(path)]) == 0
    page = (tmp_path / "walk_result.review.html").read_text(encoding="utf-8")
    assert "MonoSkel review: walk_result.json" in page and f"{int(tracks.image_size[0])} x" in page
    assert main(["report", str(tmp_path / "missing.json")]) == 2
    assert "missing.json" in capsys.readouterr().err


def test_estimates_carry_the_clips_picture_and_clock():
    from core.estimate import estimate

    tracks, _ = synthesize(load_motion("builtin:walk", max_frames=30), kinds=("still",), seed=1, image_size=(640, 360))
    est = estimate(tracks, "paper", focal_mm=50.0)
    assert est.diagnostics["image_size"] == [640.0, 360.0] and est.diagnostics["fps"] == tracks.fps
