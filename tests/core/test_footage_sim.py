"""The generator's handheld operator and detector errors, and their command-line options."""

from __future__ import annotations

import json

import numpy as np

from core.cli import main
from core.synthetic.footage_sim import DetectorErrors, HandheldOperator
from core.synthetic.motion import load_motion
from core.synthetic.synth import synthesize


def test_the_handheld_operator_moves_whenever_and_keeps_the_person_in_the_picture():
    motion = load_motion("builtin:walk", fps=30.0)
    tracks, truth = synthesize(motion, operator=HandheldOperator(), seed=4, focal_mm=35.0)
    assert truth.generator["operator"] == "handheld"
    assert tracks.present.mean() > 0.9
    steps = np.linalg.norm(np.diff(truth.rotvec_deg, axis=0), axis=1)
    assert (steps > 0).all()                                   # shake: never exactly still
    assert truth.camera_moving.mean() > 0.2
    again = synthesize(motion, operator=HandheldOperator(), seed=4, focal_mm=35.0)[1]
    other = synthesize(motion, operator=HandheldOperator(), seed=5, focal_mm=35.0)[1]
    assert np.array_equal(again.rotvec_deg, truth.rotvec_deg)
    assert not np.allclose(other.rotvec_deg, truth.rotvec_deg)


def test_detector_errors_follow_their_rates_and_leave_the_plain_noise_alone():
    motion = load_motion("builtin:walk", fps=30.0)
    plain, _ = synthesize(motion, seed=2)
    same, _ = synthesize(motion, seed=2, detector=DetectorErrors())
    assert np.array_equal(np.isnan(plain.xy), np.isnan(same.xy))
    assert np.allclose(plain.xy[np.isfinite(plain.xy)], same.xy[np.isfinite(same.xy)])
    tracks, truth = synthesize(motion, seed=2, detector=DetectorErrors(outliers=0.02, swaps=0.05, confidence=True))
    log = truth.generator["detector_log"]
    assert abs(len(log["outliers"]) - 0.02 * plain.present.sum()) <= 3
    swapped = sum(e["end"] - e["start"] + 1 for e in log["swaps"])
    assert 0.05 * tracks.n_frames <= swapped <= 0.05 * tracks.n_frames + 8
    f, j = log["outliers"][0]
    assert tracks.conf[f, j] <= 0.6 and np.median(tracks.conf[tracks.present]) > 0.8


def test_synth_command_line_options(tmp_path, capsys):
    out, truth = tmp_path / "t.json", tmp_path / "truth.json"
    assert main(["synth", "--builtin", "walk", "--out", str(out), "--truth", str(truth), "--operator", "handheld",
                 "--detector-errors", "--swaps", "0.1", "--seed", "1"]) == 0
    gen = json.loads(truth.read_text())["generator"]
    assert gen["operator"] == "handheld" and gen["detector"]["swaps"] == 0.1 and gen["detector"]["outliers"] == 0.01
    assert "handheld operator" in capsys.readouterr().out
    assert main(["synth", "--builtin", "walk", "--out", str(out), "--truth", str(truth), "--detector-errors",
                 "--outliers", "0"]) == 0
    assert json.loads(truth.read_text())["generator"]["detector"]["outliers"] == 0.0
    capsys.readouterr()
    assert main(["synth", "--builtin", "walk", "--out", str(out), "--truth", str(truth), "--outliers", "x"]) == 2
    assert "--outliers must be a number" in capsys.readouterr().err


def test_missing_joints_as_measured_on_real_footage(tmp_path, capsys):
    from core.pose_detection.quality import track_quality
    from core.synthetic.footage_sim.detector import MEASURED_MISSING

    for fps in (30.0, 120.0):
        tracks, _ = synthesize(load_motion("builtin:walk", fps=fps), noise_px=1.0, seed=3,
                               detector=DetectorErrors(missing_as_measured=True))
        drop = track_quality(tracks)["dropouts"]
        for name, got in drop.items():
            key = name[2:] if name[:2] in ("l_", "r_") else name
            share, longest = MEASURED_MISSING.get(key, (0.0, 0.0))
            assert abs(got["share"] - share) < 0.03, (fps, name, got)     # the arms far more than the legs
            assert got["longest_s"] <= 2 * longest + 1.0 / fps, (fps, name, got)   # two runs may touch
    out, truth = tmp_path / "t.json", tmp_path / "truth.json"
    assert main(["synth", "--builtin", "walk", "--out", str(out), "--truth", str(truth),
                 "--missing-as-measured"]) == 0
    assert json.loads(truth.read_text())["generator"]["detector"]["missing_as_measured"] is True
    assert "missing as measured" in capsys.readouterr().out
