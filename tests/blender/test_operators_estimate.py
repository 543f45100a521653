"""Estimate operator (synchronous path used headless) and the background job behind the modal path."""

from __future__ import annotations

import threading

import numpy as np
import pytest


def _import_walk(tmp_path, n_frames=30):
    import bpy

    from monoskel.core.synthetic.motion import load_motion
    from monoskel.core.synthetic.synth import synthesize
    from monoskel.core.tracks import write_tracks_json

    tracks, truth = synthesize(load_motion("builtin:walk", max_frames=n_frames), kinds=("still",), seed=1)
    path = tmp_path / "walk.json"
    write_tracks_json(tracks, path)
    assert bpy.ops.monoskel.import_tracks(filepath=str(path)) == {"FINISHED"}
    return tracks, truth


def test_estimate_stores_a_result_on_the_scene(empty_scene, tmp_path):
    import bpy

    from monoskel.blender import scene_data
    from monoskel.core.estimate import DEFAULT_METHOD
    from monoskel.core.skeleton import CLASSES

    tracks, _ = _import_walk(tmp_path)
    s = empty_scene.monoskel
    s.estimate_focal, s.focal_mm, s.method = False, 50.0, DEFAULT_METHOD

    assert bpy.ops.monoskel.estimate() == {"FINISHED"}

    est = scene_data.load_estimate(empty_scene)
    assert est is not None and est.method == DEFAULT_METHOD
    assert len(est.frames) == tracks.n_frames
    assert s.has_estimate and s.est_method == DEFAULT_METHOD
    assert s.est_focal_mm == pytest.approx(est.focal_mm, rel=1e-5)
    np.testing.assert_allclose(list(s.est_proportions), [est.proportions[c] for c in CLASSES], rtol=1e-5)
    assert sum(s.est_proportions) == pytest.approx(1.0, abs=1e-4)
    assert not s.estimate_running
    assert bpy.ops.monoskel.build_all.poll()  # the next step is now available


def test_estimate_failure_is_one_line_and_stores_nothing(empty_scene, tmp_path):
    import bpy

    from monoskel.blender import scene_data

    _import_walk(tmp_path, n_frames=5)  # far too short for any method
    empty_scene.monoskel.estimate_focal = False
    with pytest.raises(RuntimeError) as info:
        bpy.ops.monoskel.estimate()
    message = str(info.value).strip()
    assert len(message.splitlines()) == 1 and "Traceback" not in message
    assert scene_data.load_estimate(empty_scene) is None
    assert not empty_scene.monoskel.has_estimate and not empty_scene.monoskel.estimate_running


def test_estimate_poll_says_why(empty_scene, tmp_path):
    import bpy

    with pytest.raises(RuntimeError, match="Import tracks first"):
        bpy.ops.monoskel.estimate()
    _import_walk(tmp_path, n_frames=6)
    empty_scene.monoskel.estimate_running = True
    with pytest.raises(RuntimeError, match="An estimate is running"):
        bpy.ops.monoskel.estimate()
    with pytest.raises(RuntimeError, match="An estimate is running"):
        bpy.ops.monoskel.import_tracks(filepath="x.json")
    with pytest.raises(RuntimeError, match="No estimate is running"):
        bpy.ops.monoskel.estimate_cancel()


# ----------------------------------------------------------------------------- the background job

def test_job_reports_progress_and_result(blender):
    from monoskel.blender.estimate_job import EstimateJob

    release = threading.Event()

    def run(progress, should_cancel):
        progress(0.25, "first step")
        release.wait(5)
        progress(0.1, "")  # progress never goes backwards
        return "the estimate"

    job = EstimateJob(run).start()
    snap = None
    for _ in range(500):  # wait for the first progress call (no timing assert: bounded polling)
        snap = job.snapshot()
        if snap.fraction > 0:
            break
        threading.Event().wait(0.01)
    assert snap.fraction == pytest.approx(0.25) and snap.message == "first step" and not snap.done
    release.set()
    final = job.wait(10)
    assert final.done and final.result == "the estimate" and final.fraction == 1.0
    assert final.error is None and not final.cancelled


def test_job_hands_errors_to_the_main_thread(blender):
    from monoskel.blender.estimate_job import EstimateJob
    from monoskel.core.errors import InputError

    def run(progress, should_cancel):
        raise InputError("clip.json: frame 3 is broken")

    state = EstimateJob(run).start().wait(10)
    assert state.done and isinstance(state.error, InputError) and state.result is None


def test_cancel_stops_the_real_estimator(blender):
    from monoskel.blender.estimate_job import EstimateJob
    from monoskel.core.estimate import estimate
    from monoskel.core.synthetic.motion import load_motion
    from monoskel.core.synthetic.synth import synthesize

    tracks, _ = synthesize(load_motion("builtin:walk", max_frames=40), kinds=("pan",), seed=0)

    def run(progress, should_cancel):
        return estimate(tracks, progress=progress, should_cancel=should_cancel)

    job = EstimateJob(run)
    job.cancel()
    state = job.start().wait(60)
    assert state.done and state.cancelled and state.result is None and state.error is None
