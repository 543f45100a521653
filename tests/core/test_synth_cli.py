"""``python -m core synth``: writes tracks + truth, or fails with one line, exit 2 and no files."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from core import cli
from core.synthetic.truth import read_truth_json
from core.tracks import read_tracks_json

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture
def synth_main(monkeypatch):
    """core.cli.main with only the synth command registered (other commands may not exist yet)."""
    monkeypatch.setattr(cli, "COMMANDS", {"synth": cli.COMMANDS["synth"]})
    return lambda argv: cli.main(["synth", *argv])


def test_writes_tracks_and_truth(synth_main, tmp_path, capsys):
    out, truth_path = tmp_path / "t.json", tmp_path / "truth.json"
    code = synth_main(["--builtin", "walk", "--out", str(out), "--truth", str(truth_path), "--max-frames", "120",
                       "--kinds", "pan,zoom", "--noise-px", "0.5", "--dropout", "0.1", "--seed", "3"])
    assert code == 0
    printed = capsys.readouterr().out
    assert "120 frames" in printed and "visible" in printed and printed.count("\n") == 1
    tracks = read_tracks_json(out)
    truth = read_truth_json(truth_path)
    assert tracks.n_frames == truth.n_frames == 120
    assert tracks.image_size == (720.0, 480.0) and truth.image_size == (720.0, 480.0)
    assert truth.generator["noise_px"] == 0.5 and truth.generator["seed"] == 3
    assert {s.kind for s in truth.spells} <= {"still", "pan", "zoom"}
    assert 0.85 < tracks.present.mean() < 0.95        # 10 % dropped on top of what the frame cuts
    assert not list(tmp_path.glob("*.tmp"))


def test_continuous_and_options_reach_the_generator(synth_main, tmp_path):
    out, truth_path = tmp_path / "t.json", tmp_path / "truth.json"
    code = synth_main(["--builtin", "walk", "--out", str(out), "--truth", str(truth_path), "--max-frames", "150",
                       "--kinds", "pan_tilt,rotate_zoom", "--continuous", "--focal-mm", "35", "--image-size",
                       "640x480", "--fps", "25", "--height-m", "1.6", "--noise-px", "0", "--view-offset-deg", "-20"])
    assert code == 0
    truth = read_truth_json(truth_path)
    tracks = read_tracks_json(out)
    assert truth.fps == 25.0 and tracks.fps == 25.0 and tracks.image_size == (640.0, 480.0)
    assert truth.focal_mm[0] == pytest.approx(35.0)
    assert truth.height_m == pytest.approx(1.6, rel=1e-6)
    assert all(s.moving for s in truth.spells[1:])
    assert truth.generator["view_offset_deg"] == -20.0


BAD = [
    (["--builtin", "walk", "--noise-px", "-1"], "--noise-px"),
    (["--builtin", "walk", "--noise-px", "lots"], "--noise-px"),
    (["--builtin", "walk", "--dropout", "1.5"], "--dropout"),
    (["--builtin", "walk", "--occlusion-s", "nan"], "--occlusion-s"),
    (["--builtin", "walk", "--focal-mm", "0"], "--focal-mm"),
    (["--builtin", "walk", "--image-size", "720by480"], "--image-size"),
    (["--builtin", "walk", "--kinds", "pan,dolly"], "dolly"),
    (["--builtin", "walk", "--max-frames", "1"], "--max-frames"),
    (["--builtin", "walk", "--seed", "x"], "--seed"),
    (["--builtin", "walk", "--view-offset-deg", "95"], "--view-offset-deg"),
    (["--builtin", "moonwalk"], "moonwalk"),
    (["missing.bvh"], "missing.bvh"),
    (["x.bvh", "--builtin", "walk"], "exactly one"),
    ([], "exactly one"),
]


@pytest.mark.parametrize("argv,match", BAD)
def test_bad_arguments_fail_cleanly(synth_main, tmp_path, capsys, argv, match, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code = synth_main([*argv, "--out", "t.json", "--truth", "truth.json"])
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("error: ") and err.count("\n") == 1 and match in err
    assert sorted(os.listdir(tmp_path)) == []


def test_missing_output_folder_fails_cleanly(synth_main, tmp_path, capsys):
    code = synth_main(["--builtin", "walk", "--out", str(tmp_path / "no" / "t.json"),
                       "--truth", str(tmp_path / "truth.json")])
    assert code == 2 and "does not exist" in capsys.readouterr().err
    assert os.listdir(tmp_path) == []


def test_reads_a_real_bvh(synth_main, tmp_path, shared_bvh_dir):
    bvh = shared_bvh_dir / "bandai_dataset-1_walk_normal_001.bvh"
    out, truth_path = tmp_path / "t.json", tmp_path / "truth.json"
    assert synth_main([str(bvh), "--out", str(out), "--truth", str(truth_path), "--max-frames", "120",
                       "--noise-px", "0"]) == 0
    truth = read_truth_json(truth_path)
    tracks = read_tracks_json(out)
    assert tracks.present.mean() > 0.95
    assert np.isclose(truth.proportions.sum(), 1.0)


def test_module_entry_point_runs_synth(tmp_path):
    """The real ``python -m core synth``; every command module of core/cli/__init__.py imports."""
    import importlib

    for module, _ in cli.COMMANDS.values():
        assert hasattr(importlib.import_module(module, "core"), "run"), module
    out, truth_path = tmp_path / "t.json", tmp_path / "truth.json"
    run = subprocess.run([sys.executable, "-m", "core", "synth", "--builtin", "walk", "--out", str(out),
                          "--truth", str(truth_path), "--max-frames", "60"], cwd=REPO, capture_output=True,
                         text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    assert out.exists() and truth_path.exists()
    bad = subprocess.run([sys.executable, "-m", "core", "synth", "--builtin", "walk", "--out", str(out) + "2",
                          "--truth", str(truth_path) + "2", "--noise-px", "-1"], cwd=REPO, capture_output=True,
                         text=True, timeout=120)
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1
    assert not Path(str(out) + "2").exists()
