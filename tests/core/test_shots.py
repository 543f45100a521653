"""core.shots without Blender: which shots a folder holds, the shared options, up-to-date checks, the index
page and the Open Job Description template (checked by the openjd-model parser when it is installed)."""

from __future__ import annotations

import argparse
import json
import os
import time

import pytest

from core.errors import InputError
from core.shots import yaml_text
from core.shots.command import BLENDER, PYTHON, Runner, current_runner, given_options, option_arguments, shot_arguments
from core.shots.discover import TRACKS, VIDEO, discover_shots, find_shot
from core.shots.index_page import write_index
from core.shots.openjd import asset_references, job_template, parameter_values, write_bundle
from core.shots.outputs import FAILED, OK, expected_files, shot_outputs, up_to_date, write_status


def _touch(path, text="{}"):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


def test_a_folder_gives_one_shot_per_tracks_file_and_video(tmp_path):
    for name in ("b.json", "a.csv", "c.mp4", "c.json", "d.MOV", "walk.json", "walk.csv", "notes.txt", ".hidden.json",
                 "x_000000000000_keypoints.json"):
        _touch(tmp_path / name)
    _touch(tmp_path / "op" / "run_000000000000_keypoints.json")
    _touch(tmp_path / "other" / "readme.json")
    shots = {s.name: s for s in discover_shots(tmp_path)}
    assert sorted(shots) == ["a", "b", "c", "d", "op", "walk_csv", "walk_json"]
    assert shots["c"].kind == TRACKS and shots["c"].footage == str(tmp_path / "c.mp4")   # the tracks' footage
    assert shots["d"].kind == VIDEO and shots["op"].kind == TRACKS and os.path.isdir(shots["op"].path)
    assert shots["c"].input_files() == [str(tmp_path / "c.json"), str(tmp_path / "c.mp4")]
    assert find_shot(tmp_path, "walk_csv").path == str(tmp_path / "walk.csv")
    with pytest.raises(InputError, match="no shot 'nope'"):
        find_shot(tmp_path, "nope")
    with pytest.raises(InputError, match="no such folder"):
        discover_shots(tmp_path / "missing")


def _parser():
    p = argparse.ArgumentParser()
    p.add_argument("input", nargs="?")
    p.add_argument("--output", "-o")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--kinds", type=lambda t: tuple(t.split(",")), default=("pan",))
    p.add_argument("--no-report", dest="review", action="store_false")
    p.add_argument("--views", nargs="+", default=())
    p.add_argument("--folder")
    return p


def test_the_options_given_come_back_as_typed_without_the_left_out_ones():
    argv = ["--fold", "shots", "--seed", "-3", "--kinds=pan,zoom", "--no-rep", "-o", "x.blend", "--views", "a", "b"]
    given = given_options(_parser(), argv)
    assert given["seed"] == ("--seed", ["-3"]) and given["kinds"] == ("--kinds", ["pan,zoom"])
    assert given["review"] == ("--no-report", None) and given["output"] == ("--output", ["x.blend"])
    args = option_arguments(given, {"seed", "kinds", "review", "views"})
    assert args == ["--seed=-3", "--kinds=pan,zoom", "--no-report", "--views", "a", "b"]
    back = _parser().parse_args(args)           # the shot's batch reads the same values
    assert (back.seed, back.kinds, back.review, back.views) == (-3, ("pan", "zoom"), False, ["a", "b"])


def test_a_shot_command_names_its_input_and_its_own_files(tmp_path):
    _touch(tmp_path / "s" / "clip.mp4")
    _touch(tmp_path / "s" / "t.json")
    _touch(tmp_path / "s" / "t.avi")
    shots = {s.name: s for s in discover_shots(tmp_path / "s")}
    video, tracks = shots["clip"], shots["t"]
    outs = shot_outputs(tmp_path / "out", video)
    args = shot_arguments(video, outs, ["--seed=1"], exports=("fbx",))
    assert args[:3] == ["--video", video.path, "--seed=1"]
    assert outs.blend in args and outs.tracks in args and args[-2:] == ["--fbx", outs.export("fbx")]
    assert all(a.startswith(str(tmp_path / "out" / "clip")) for a in (outs.blend, outs.result, outs.log))
    t_args = shot_arguments(tracks, shot_outputs(tmp_path / "out", tracks), [], track_background=True)
    assert t_args[0] == tracks.path and t_args[-2:] == ["--footage", tracks.footage]
    assert "--footage" not in shot_arguments(tracks, shot_outputs(tmp_path / "out", tracks), [])
    assert Runner(PYTHON, "/py").command("/b.py", ["x"]) == ["/py", "/b.py", "--", "x"]
    blender = Runner(BLENDER, "/blender").command("/b.py", ["x"])
    assert blender[0] == "/blender" and blender[1] == "-b" and blender[-4:] == ["--python", "/b.py", "--", "x"]

    class FakeApp:                    # what Blender's own bpy.app says about itself
        binary_path = "/opt/blender/blender"

    class FakeBpy:
        app = FakeApp

    assert current_runner(FakeBpy) == Runner(BLENDER, "/opt/blender/blender")
    assert current_runner(None).kind == PYTHON


def test_up_to_date_needs_success_the_same_arguments_and_outputs_newer_than_inputs(tmp_path):
    _touch(tmp_path / "s" / "a.json")
    shot = discover_shots(tmp_path / "s")[0]
    outs = shot_outputs(tmp_path / "out", shot)
    expected = expected_files(shot, outs)
    assert expected == [outs.blend, outs.result, outs.review]
    assert not up_to_date(shot, outs, ["a"], expected)                       # never run
    for path in expected:
        _touch(tmp_path / path)
    write_status(outs, {"status": OK, "args": ["a"]})
    assert up_to_date(shot, outs, ["a"], expected)
    assert not up_to_date(shot, outs, ["a", "--seed=2"], expected)           # other options
    later = time.time() + 10
    os.utime(shot.path, (later, later))                                      # the input changed
    assert not up_to_date(shot, outs, ["a"], expected)
    os.utime(shot.path, (later - 100, later - 100))
    os.remove(outs.review)
    assert not up_to_date(shot, outs, ["a"], expected)                       # an output is missing
    _touch(tmp_path / outs.review)
    write_status(outs, {"status": FAILED, "args": ["a"]})
    assert not up_to_date(shot, outs, ["a"], expected)


def test_the_index_lists_built_failed_and_unrun_shots_with_figures_and_links(tmp_path):
    for name in ("good", "bad", "later"):
        _touch(tmp_path / "s" / f"{name}.json")
    shots = discover_shots(tmp_path / "s")
    out = tmp_path / "out"
    bad, good = (shot_outputs(out, s) for s in shots[:2])           # in name order: bad, good, later
    os.makedirs(bad.folder)
    frames = [{"reprojection_px": v} for v in (1.0, 2.0, 4.0)]
    _touch(tmp_path / good.result, json.dumps({"method": "joint", "frames": frames, "focal_mm": 35.0,
                                               "height_m": 1.8, "diagnostics": {"warnings": ["focal & guessed"]}}))
    _touch(tmp_path / good.review, "<html>")
    write_status(good, {"status": OK, "seconds": 3.25})
    write_status(bad, {"status": FAILED, "error": "batch.py: error: bad.json: <broken>"})
    rows = {r["shot"]: r for r in write_index(out, shots)}
    assert rows["good"]["status"] == OK and rows["good"]["median_fit_px"] == 2.0 and rows["good"]["frames"] == 3
    assert rows["bad"]["status"] == FAILED and rows["later"]["status"] == "not run"
    page = (out / "index.html").read_text()
    assert "3 shots: 1 built, 1 failed, 1 not run" in page
    assert "href='good/good.review.html'" in page and "focal &amp; guessed" in page
    assert "batch.py: error: bad.json: &lt;broken&gt;" in page and "35.0" in page
    assert json.loads((out / "index.json").read_text())["shots"][0]["shot"] == "bad"


def test_yaml_text_reads_back_as_written():
    yaml = pytest.importorskip("yaml")
    doc = {"a": 1, "b": "x: y", "c": [{"n": "yes", "v": ["--x=2", "{{Param.A}}", "", "1.5"]}, {"n": "r"}],
           "d": {"e": [[1, 2], []], "f": {}}, "g": True, "h": None, "i": "ünï \"q\"\n2"}
    assert yaml.safe_load(yaml_text.dump(doc, "a comment")) == doc


def test_the_job_template_is_valid_open_job_description(tmp_path):
    template = job_template(["a", "b"], Runner(BLENDER, "/opt/blender"), "/x/batch.py", str(tmp_path / "s"),
                            str(tmp_path / "o"), ["--seed=1"], "MonoSkel s")
    shots_step, index_step = template["steps"]
    assert shots_step["parameterSpace"]["taskParameterDefinitions"][0]["range"] == ["a", "b"]
    args = shots_step["script"]["actions"]["onRun"]["args"]
    assert args[:5] == ["-b", "--factory-startup", "--python-exit-code", "1", "--python"]
    assert "{{Task.Param.Shot}}" in args and args[-1] == "--seed=1"
    assert index_step["dependencies"] == [{"dependsOn": "Shots"}]
    assert parameter_values(template)["parameterValues"][0] == {"name": "Executable", "value": "/opt/blender"}
    assert asset_references(template)["assetReferences"]["outputs"]["directories"] == [str(tmp_path / "o")]
    written = write_bundle(str(tmp_path / "bundle"), template, "a test")
    assert [os.path.basename(p) for p in written] == ["template.yaml", "parameter_values.yaml",
                                                      "asset_references.yaml"]
    with pytest.raises(InputError, match="at most 1024"):
        job_template([f"s{i}" for i in range(1025)], Runner(PYTHON, "/py"), "/b.py", "/s", "/o", [], "x")
    model = pytest.importorskip("openjd.model")
    yaml = pytest.importorskip("yaml")
    doc = yaml.safe_load((tmp_path / "bundle" / "template.yaml").read_text())
    assert doc == template
    model.decode_job_template(template=doc)          # raises on anything the specification does not allow
