"""Every ``python -m core`` command that writes a file refuses an output it cannot write before it starts work.

A mistyped folder should cost the user a second, not the minutes of detection, solving or training that
come before the write: one line, exit 2, no progress printed and nothing written."""

from __future__ import annotations

import os

import pytest

from core.cli import main
from core.estimate import estimate
from core.io.file_io import check_output_file
from core.result import write_estimate_json
from core.synthetic.motion import load_motion
from core.synthetic.synth import synthesize
from core.tracks import write_tracks_json


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    """A tracks file, an estimate of it and a folder holding one BVH file: every command's input."""
    folder = tmp_path_factory.mktemp("inputs")
    tracks, _ = synthesize(load_motion("builtin:walk", fps=30.0, max_frames=60), noise_px=1.0, seed=2)
    write_tracks_json(tracks, folder / "tracks.json")
    write_estimate_json(estimate(tracks, "paper", focal_mm=50.0), folder / "result.json")
    clips = folder / "clips"
    clips.mkdir()
    (clips / "one.bvh").write_text("HIERARCHY\n")
    return folder


def _commands(d, out):
    t, r = str(d / "tracks.json"), str(d / "result.json")
    return {
        "estimate": ["estimate", t, "--out", out],
        "estimate-multiview": ["estimate-multiview", t, t, "--out", out],
        "single-image": ["single-image", t, "--out", out],
        "flip-depth": ["flip-depth", r, "--bone", "l_wrist", "--frames", "10-20", "--out", out],
        "plant-foot": ["plant-foot", r, "--foot", "l", "--frames", "10-20", "--out", out],
        "report": ["report", r, "--out", out],
        # the video does not exist either: the output is checked first
        "detect": ["detect", str(d / "missing.mp4"), "--out", out],
        "train-prior": ["train-prior", str(d / "clips"), "--out", out[:-5] + ".npz"],
        "train-lifter": ["train-lifter", str(d / "clips"), "--out", out[:-5] + ".npz"],
        "evaluate": ["evaluate", "--builtin", "--json", out],
    }


COMMANDS = ["estimate", "estimate-multiview", "single-image", "flip-depth", "plant-foot", "report", "detect",
            "train-prior", "train-lifter", "evaluate"]


@pytest.mark.parametrize("command", COMMANDS)
def test_a_missing_folder_fails_before_any_work(command, inputs, tmp_path, capsys):
    out = str(tmp_path / "no such folder" / "out.json")
    code = main(_commands(inputs, out)[command])
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("error: ") and err.count("\n") == 1, err
    assert "does not exist" in err and "no such folder" in err
    assert "%]" not in err and "iteration" not in err          # no progress: nothing was started
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("command", ["estimate", "report", "flip-depth"])
def test_a_folder_given_as_the_output_fails_before_any_work(command, inputs, tmp_path, capsys):
    code = main(_commands(inputs, str(tmp_path))[command])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "is a folder" in err, err


def test_the_check_passes_a_writable_file_name(tmp_path):
    assert check_output_file(tmp_path / "fine.json") == str(tmp_path / "fine.json")
    assert check_output_file("relative-name.json") == "relative-name.json"   # the working folder


def test_the_message_names_the_setting_or_the_path_alone(tmp_path):
    from core.errors import InputError

    missing = str(tmp_path / "gone" / "x.blend")
    with pytest.raises(InputError) as named:
        check_output_file(missing, "--output")
    assert str(named.value) == f"--output {missing}: folder {tmp_path / 'gone'} does not exist"
    with pytest.raises(InputError) as bare:
        check_output_file(missing, None)
    assert str(bare.value) == f"{missing}: folder {tmp_path / 'gone'} does not exist"
