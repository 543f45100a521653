"""Static background tracks: the format, the generator, the scene camera and its use in the solve."""

from __future__ import annotations

import json

import numpy as np
import pytest

from core import camera as cam
from core import cli
from core.errors import InputError
from core.estimate import estimate
from core.evaluation.evaluate import score
from core.evaluation.metrics import rotation_errors_deg
from core.io.formats.generic_csv import read_generic_csv, write_generic_csv
from core.joint_solve import solver as slv
from core.joint_solve.stance import stance_codes
from core.scene_camera import solve_scene_camera
from core.synthetic.footage_sim import HandheldOperator
from core.synthetic.motion import load_motion
from core.synthetic.synth import synthesize
from core.timebase import to_working_rate
from core.tracks import StaticTracks, Tracks, read_tracks_json, tracks_from_dict, tracks_to_dict, write_tracks_json


@pytest.fixture(scope="module")
def walk():
    return load_motion("builtin:walk", max_frames=300)


@pytest.fixture(scope="module")
def handheld(walk):
    """A handheld walk, 35 mm (not told), 12 static points, 1 px."""
    return synthesize(walk, focal_mm=35.0, operator=HandheldOperator(), seed=1, static_points=12)


# --- format ------------------------------------------------------------------------------------------


def test_static_block_round_trips_through_json_and_csv(handheld, tmp_path):
    tracks, _ = handheld
    path = tmp_path / "t.json"
    write_tracks_json(tracks, path)
    back = read_tracks_json(path)
    assert back.static.names == tracks.static.names
    assert np.array_equal(back.static.present, tracks.static.present)
    assert np.nanmax(np.abs(back.static.xy - tracks.static.xy)) < 1e-3
    csv = tmp_path / "t.csv"
    write_generic_csv(tracks, csv)
    again = read_generic_csv(str(csv))
    assert again.static.names == tracks.static.names
    assert np.nanmax(np.abs(again.static.xy - tracks.static.xy)) < 1e-3
    assert np.nanmax(np.abs(again.xy - tracks.xy)) < 1e-3
    # a file without the block reads as before
    plain = tracks.replaced(static=None)
    assert tracks_from_dict(json.loads(json.dumps(tracks_to_dict(plain)))).static is None


def test_csv_ignore_and_typo(tmp_path):
    head = "# fps: 30\n# image_size: 720 480\nframe,joint,x,y\n"
    body = "".join(f"{f},pelvis,{100 + f},200\n{f},corner_a,{300 + f},50\n{f},corner_b,400,60\n" for f in range(3))
    p = tmp_path / "a.csv"
    p.write_text(head + body)
    assert read_generic_csv(str(p)).static.names == ("corner_a", "corner_b")
    p.write_text("# ignore: corner_b\n" + head + body)
    assert read_generic_csv(str(p)).static.names == ("corner_a",)
    p.write_text(head + body + "0,l_kne,1,2\n")
    with pytest.raises(InputError, match="did you mean 'l_knee'"):
        read_generic_csv(str(p))


@pytest.mark.parametrize("block, message", [
    ({"names": ["a"], "frames": [[None]]}, "one entry per frame"),
    ({"names": ["head"], "frames": [[None]] * 3}, "joint names"),
    ({"names": ["a", "a"], "frames": [[None, None]] * 3}, "listed twice"),
    ({"names": ["a"], "frames": [[[1, 2]]] * 3}, r"static: frame 0, point 'a'"),
    ("x", "must be an object"),
])
def test_bad_static_block(block, message):
    doc = {"format": "skeleton-tracks", "version": 1, "fps": 30, "image_size": [720, 480],
           "joints": list(tracks_to_dict(Tracks(np.zeros((3, 17, 2)), np.ones((3, 17)), 30, (720, 480)))["joints"]),
           "frames": [[[1, 1, 1]] * 17] * 3, "static": block}
    with pytest.raises(InputError, match=message):
        tracks_from_dict(doc, "f.json")


def test_working_rate_averages_static_tracks_too():
    n = 12
    xy = np.zeros((n, 17, 2))
    st = StaticTracks(["p"], np.arange(n, dtype=float)[:, None, None].repeat(2, axis=2), np.ones((n, 1)))
    t = to_working_rate(Tracks(xy, np.ones((n, 17)), 120.0, (720, 480), static=st), 4)
    assert t.static.xy.shape == (3, 1, 2)
    # frame 4 averages 2..6 with the ends at half weight: 4
    assert t.static.xy[1, 0, 0] == pytest.approx(4.0)


# --- generator ---------------------------------------------------------------------------------------


def test_static_points_are_seen_only_inside_the_picture(handheld):
    tracks, truth = handheld
    st = tracks.static
    assert st.n_points == 12 and len(truth.generator["static_points_cam0"]) == 12
    inside = st.xy[st.present]
    assert (inside[:, 0] >= -5).all() and (inside[:, 0] <= 725).all()
    assert (inside[:, 1] >= -5).all() and (inside[:, 1] <= 485).all()
    # each point projects where the true camera puts its frame-0 direction
    pts = np.array(truth.generator["static_points_cam0"])
    R = cam.rotation_matrix(truth.rotvec_deg)
    uv = cam.project_to_pixels(np.einsum("fij,kj->fki", R, pts), truth.focal_mm[:, None], tracks.image_size)
    err = np.linalg.norm(uv - st.xy, axis=-1)[st.present]
    assert np.median(err) < 2.0
    assert np.allclose(truth.rotvec_deg[0], 0.0, atol=1e-9)


def test_synth_cli_static_points(tmp_path, capsys):
    out, tr = tmp_path / "t.json", tmp_path / "truth.json"
    assert cli.main(["synth", "--builtin", "walk", "--max-frames", "60", "--static-points", "6", "--operator",
                     "handheld", "--out", str(out), "--truth", str(tr)]) == 0
    assert read_tracks_json(out).static.n_points == 6 and "6 static points" in capsys.readouterr().out
    for argv, match in ((["--static-points", "2.5"], "whole number"), (["--operator-walk", "1"], "needs --operator")):
        assert cli.main(["synth", "--builtin", "walk", *argv, "--out", str(out), "--truth", str(tr)]) == 2
        assert match in capsys.readouterr().err


# --- the scene camera --------------------------------------------------------------------------------


def test_scene_camera_recovers_rotation_and_focal(handheld):
    tracks, truth = handheld
    sc = solve_scene_camera(tracks)
    assert sc.usable and sc.focal_determined and sc.turn_deg > 10
    assert abs(sc.focal_mm[0] / truth.focal_mm[0] - 1) < 0.02
    assert np.median(np.abs(sc.focal_mm / truth.focal_mm - 1)) < 0.01
    assert np.median(rotation_errors_deg(sc.rotvec_deg, truth.rotvec_deg)) < 0.3
    assert np.allclose(sc.rotvec_deg[0], 0.0)
    assert not sc.translating and sc.parallax_px < 0.5


def test_scene_camera_exact_without_noise(walk):
    tracks, truth = synthesize(walk, focal_mm=28.0, operator=HandheldOperator(), seed=2, static_points=10,
                               noise_px=0.0)
    sc = solve_scene_camera(tracks)
    assert np.max(rotation_errors_deg(sc.rotvec_deg, truth.rotvec_deg)) < 1e-3
    assert np.max(np.abs(sc.focal_mm / truth.focal_mm - 1)) < 1e-4


def test_a_short_lens_far_from_the_assumed_one_is_reached(walk):
    """Starting at the assumed 50 mm, the adjustment follows the focal length's long flat valley to 22 mm
    (it stopped at 29 mm after 30 iterations, its turn 10 degrees instead of 13 and frames 3 degrees off)."""
    tracks, truth = synthesize(walk, focal_mm=22.0, operator=HandheldOperator(moves_per_s=0.2), seed=0,
                               static_points=12)
    sc = solve_scene_camera(tracks)
    assert abs(sc.focal_mm[0] / truth.focal_mm[0] - 1) < 0.03
    assert np.max(rotation_errors_deg(sc.rotvec_deg, truth.rotvec_deg)) < 1.0


def test_small_turn_leaves_the_focal_length_undetermined(walk):
    op = HandheldOperator(moves_per_s=0.01, shake_deg=0.1)
    tracks, _ = synthesize(walk, focal_mm=35.0, operator=op, seed=3, static_points=12)
    sc = solve_scene_camera(tracks)
    assert sc.turn_deg < 10
    assert not sc.focal_determined and "turns only" in sc.focal_reason


def test_an_undetermined_lens_is_as_uncertain_as_its_prior(walk):
    """A still camera says nothing of the lens (the background's sigma of log f is over 1); the lens is then
    held at the assumed 50 mm, and how far it may be off is the lens prior's spread, not the data's."""
    tracks, _ = synthesize(walk, focal_mm=30.0, kinds="still", seed=3, static_points=12)
    sc = solve_scene_camera(tracks)
    assert sc.log_focal_sigma > 1.0 and sc.focal_mm[0] == pytest.approx(50.0, rel=1e-3)
    assert 0.5 < sc.log_focal_sigma_with_prior < min(sc.log_focal_sigma, 1.0)
    hinted = solve_scene_camera(tracks, focal_hint_mm=30.0)
    assert hinted.log_focal_sigma_with_prior <= 0.05
    assert hinted.summary()["log_focal_sigma_with_prior"] == hinted.log_focal_sigma_with_prior


def test_translating_camera_is_reported_not_absorbed(walk):
    tracks, truth = synthesize(walk, focal_mm=35.0, operator=HandheldOperator(walk_m_s=0.5), seed=1,
                               static_points=12)
    sc = solve_scene_camera(tracks)
    assert sc.translating and not sc.usable and sc.parallax_px > 2.0
    est = estimate(tracks)
    assert est.diagnostics["scene_camera"]["translating"] is True
    assert any("parallax" in w for w in est.diagnostics["warnings"])
    assert "camera_track" in {f["code"] for f in est.diagnostics["self_check"]["flags"]}


def test_slipping_track_is_left_out(handheld):
    tracks, truth = handheld
    st = tracks.static
    xy = st.xy.copy()
    k = int(np.argmax(st.present.sum(axis=0)))
    xy[:, k, 0] += np.linspace(0, 40, tracks.n_frames)          # a tracker sliding 40 px along the clip
    slipped = tracks.replaced(static=StaticTracks(st.names, xy, st.conf))
    sc = solve_scene_camera(slipped)
    assert not sc.used_points[k] and sc.used_points.sum() == st.n_points - 1
    assert any(st.names[k] in w for w in sc.warnings)
    assert abs(sc.focal_mm[0] / truth.focal_mm[0] - 1) < 0.02


def test_too_few_points_give_no_scene_camera(handheld):
    tracks, _ = handheld
    st = tracks.static
    few = tracks.replaced(static=StaticTracks(st.names[:3], st.xy[:, :3], st.conf[:, :3]))
    assert solve_scene_camera(few) is None
    est = estimate(few)
    assert any(w.startswith("background:") for w in est.diagnostics["warnings"])
    assert est.diagnostics["scene_camera"] is None


# --- the joint solve with the scene --------------------------------------------------------------------


def test_static_term_gradient_matches_finite_differences(handheld, check_cost_gradient):
    tracks, truth = handheld
    sc = solve_scene_camera(tracks)
    film = cam.pixels_to_film(tracks.xy, tracks.image_size)
    st = stance_codes(truth.stance)
    sig = slv.Sigmas(knee=1e9, head_align=1e9, spine_straight=1e9, symmetry_m=1e9)
    static = {"film": cam.pixels_to_film(tracks.static.xy, tracks.image_size), "dirs": sc.directions}
    prob = slv.Problem(film[:20], cam.mm_per_pixel(tracks.image_size), tracks.fps, 1.75, st[:20], sigmas=sig,
                       static={"film": static["film"][:20], "dirs": static["dirs"]})
    rng = np.random.default_rng(0)
    x = slv.pack(truth.joints_3d[:20], np.radians(truth.rotvec_deg[:20]) + 0.002, np.log(truth.focal_mm[:20]) + 0.01,
                 truth.class_lengths_m, stance=st[:20])
    parts = {}
    slv.residuals(prob, x, with_jac=False, parts=parts)
    assert parts["static"] > 0
    cam_cols = [f * slv.BLOCK + slv.W_OFF + k for f in rng.choice(20, 8, replace=False) for k in range(4)]
    check_cost_gradient(prob, x, cam_cols, eps=1e-6, rel=2e-3, abs_scale=2e-2)


def test_estimate_with_background_beats_the_person_alone(handheld):
    tracks, truth = handheld
    with_bg = estimate(tracks)
    alone = estimate(tracks.replaced(static=None))
    s_bg, s_alone = score(with_bg, truth), score(alone, truth)
    assert with_bg.diagnostics["focal_determined"] is True
    assert abs(with_bg.focal_mm / truth.focal_mm[0] - 1) < 0.02
    assert s_bg["rotation_error_deg"] < 0.3 < s_alone["rotation_error_deg"]
    assert s_bg["proportions"]["mean_abs"] < 0.6
    assert s_bg["mpjpe_clip_mm"] < s_alone["mpjpe_clip_mm"]
    assert with_bg.diagnostics["scene_camera"]["used"] is True
    assert with_bg.diagnostics["trusted"] is True
    assert "scene_camera" not in alone.diagnostics


def test_estimate_cli_background_switch(handheld, tmp_path, capsys):
    from core.result import read_estimate_json

    tracks, _ = handheld
    path = tmp_path / "t.json"
    write_tracks_json(tracks, path)
    assert cli.main(["estimate", str(path), "--out", str(tmp_path / "a.json")]) == 0
    assert "background points" in capsys.readouterr().err
    assert read_estimate_json(tmp_path / "a.json").diagnostics["scene_camera"]["used"] is True
    assert cli.main(["estimate", str(path), "--out", str(tmp_path / "b.json"), "--no-background"]) == 0
    assert "scene_camera" not in read_estimate_json(tmp_path / "b.json").diagnostics


def test_paper_method_undoes_the_scene_camera(handheld):
    """The paper method with background tracks takes the scene camera (and marks its moving frames)."""
    tracks, truth = handheld
    est = estimate(tracks, "paper")
    assert est.diagnostics["scene_camera"]["used"] is True
    assert score(est, truth)["rotation_error_deg"] < 0.3
    assert any(f.camera_moving for f in est.frames) and est.diagnostics["spells"]
