"""``python -m core estimate``: success writes a valid result, bad input exits 2 with no file."""

from __future__ import annotations

import json

import numpy as np
import pytest

from core.cli import main
from core.result import read_estimate_json
from core.skeleton import CLASSES
from core.synthetic.motion import load_motion
from core.synthetic.synth import synthesize
from core.tracks import Tracks, write_tracks_json


@pytest.fixture(scope="module")
def tracks_file(tmp_path_factory):
    tracks, _ = synthesize(load_motion("builtin:walk", fps=30.0, max_frames=150), noise_px=1.0, seed=1)
    path = tmp_path_factory.mktemp("cli") / "walk.json"
    write_tracks_json(tracks, path)
    return path


def test_estimate_writes_the_result(tracks_file, tmp_path, capsys):
    out = tmp_path / "result.json"
    assert main(["estimate", str(tracks_file), "--out", str(out), "--method", "paper", "--focal-mm", "50"]) == 0
    est = read_estimate_json(out)
    assert est.method == "paper" and len(est.frames) == 150 and est.focal_mm == 50.0
    doc = json.loads(out.read_text())
    assert sorted(doc["proportions"]) == sorted(CLASSES)
    assert abs(sum(doc["proportions"].values()) - 1.0) < 1e-6
    assert {"stance", "camera_moving", "rotvec_deg", "focal_mm", "scale", "joints_3d"} <= set(doc["frames"][0])
    assert "%]" in capsys.readouterr().err        # progress on stderr


def test_estimate_prints_the_warnings(tracks_file, tmp_path, capsys):
    # the joint method with no focal hint assumes 50 mm and says so: a CLI user must see it too
    out = tmp_path / "result.json"
    assert main(["estimate", str(tracks_file), "--out", str(out), "--method", "joint"]) == 0
    warned = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("warning: ")]
    assert any("focal length not determined" in ln for ln in warned)
    assert warned == [f"warning: {w}" for w in read_estimate_json(out).diagnostics["warnings"]]


def _write_bad(path, n, feet=True):
    xy = np.full((n, 17, 2), 300.0)
    conf = np.ones((n, 17))
    if not feet:
        xy[:, [7, 10]] = np.nan
        conf[:, [7, 10]] = 0.0
    write_tracks_json(Tracks(xy, conf, 30.0, (720, 480)), path)


@pytest.mark.parametrize("case", ["too_few", "no_feet", "missing_file", "bad_format", "not_json"])
def test_bad_input_exits_2_without_a_result(case, tmp_path, capsys):
    src = tmp_path / "in.json"
    extra = []
    if case == "too_few":
        _write_bad(src, 4)
    elif case == "no_feet":
        _write_bad(src, 60, feet=False)
    elif case == "bad_format":
        _write_bad(src, 60)
        extra = ["--format", "no-such-format"]
    elif case == "not_json":
        src.write_text("{ not json")
    out = tmp_path / "result.json"
    assert main(["estimate", str(src), "--out", str(out), "--method", "paper", *extra]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err and err[-1].startswith("error: ")
    assert not out.exists() and not (tmp_path / "result.json.tmp").exists()


def test_bad_image_size_option(tracks_file, tmp_path):
    out = tmp_path / "r.json"
    assert main(["estimate", str(tracks_file), "--out", str(out), "--image-size", "abc"]) == 2
    assert not out.exists()


def test_a_frame_range_estimates_that_stretch_alone(tracks_file, tmp_path, capsys):
    from core.tracks import read_tracks_json

    whole = read_tracks_json(tracks_file)
    part = whole.frames_between(5, 24)
    assert part.n_frames == 20 and part.meta["frame_offset"] == 5
    assert np.array_equal(part.xy, whole.xy[5:25], equal_nan=True)
    assert part.frames_between(2, 3).meta["frame_offset"] == 7          # offsets add up
    out = tmp_path / "r.json"
    assert main(["estimate", str(tracks_file), "--out", str(out), "--method", "paper", "--frames", "5-64"]) == 0
    assert len(read_estimate_json(out).frames) == 60 and "60 frames 5-64" in capsys.readouterr().err
    for bad in ("24-5", "x-3", "5", f"0-{whole.n_frames}"):
        assert main(["estimate", str(tracks_file), "--out", str(tmp_path / "no.json"), "--frames", bad]) == 2
        assert not (tmp_path / "no.json").exists()


def test_no_foot_lock_keeps_the_solved_motion(tracks_file, tmp_path):
    held, raw = tmp_path / "held.json", tmp_path / "raw.json"
    assert main(["estimate", str(tracks_file), "--out", str(held), "--method", "joint"]) == 0
    assert main(["estimate", str(tracks_file), "--out", str(raw), "--method", "joint", "--no-foot-lock"]) == 0
    a, b = read_estimate_json(held), read_estimate_json(raw)
    assert "motion_cleanup" in a.diagnostics and "motion_cleanup" not in b.diagnostics
    ja = np.array([f.joints_3d for f in a.frames])
    jb = np.array([f.joints_3d for f in b.frames])
    legs = [7, 10, 6, 9]      # ankles and knees: the lock moves these alone
    rest = [k for k in range(17) if k not in legs]
    assert np.abs(ja[:, legs] - jb[:, legs]).max() > 0.005
    assert np.abs(ja[:, rest] - jb[:, rest]).max() < 1e-4
