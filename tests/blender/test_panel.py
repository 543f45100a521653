"""The sidebar's draw decisions (ui/state.py) in every state, checked against the real operators' polls.

Headless Blender has no UILayout, so the panels' draw() only renders rows that
ui/state.py computes; these tests run that computation for each state of the
workflow and hold every button's enabled flag and reason against the operator's
own poll() and poll message.
"""

from __future__ import annotations

import threading

import pytest


def _rows_everywhere(scene, has_clip=False):
    from monoskel.ui import state

    return {name: state.section_rows(name, scene.monoskel, has_clip=has_clip) for name in state.SECTIONS}


def _check_consistency(scene, rows_by_section):
    """Every prop exists; every button's enabled/reason equals the operator's poll()/poll message."""
    import bpy

    props = scene.monoskel.bl_rna.properties
    for section, rows in rows_by_section.items():
        for row in rows:
            if row.kind == "prop":
                assert row.attr in props, (section, row.attr)
            elif row.kind == "operator":
                module, name = row.op.split(".")
                op = getattr(getattr(bpy.ops, module), name)
                assert op.poll() == row.enabled, (section, row.op, row.reason)
                assert bool(row.reason) == (not row.enabled), (section, row.op)
                if not row.enabled:
                    with pytest.raises(RuntimeError) as info:
                        op()
                    assert row.reason in str(info.value), (section, row.op)
            elif row.kind == "table":
                widths = {len(r) for r in row.cells}
                assert len(widths) == 1, section
            elif row.kind == "take_list":
                assert "takes" in props and "take_index" in props, section
            elif row.kind == "bone_map":
                assert settings_has_map(scene), section
            else:
                assert row.kind in ("label", "progress"), row.kind


def settings_has_map(scene):
    s = scene.monoskel
    return s.retarget_target is not None and s.retarget_map_rig == s.retarget_target.name and len(s.retarget_map)


def _texts(rows):
    return [r.text for r in rows]


def _store_tracks_and_estimate(scene, *, truth_too=False, n_frames=12):
    import bpy

    from monoskel.blender import scene_data
    from monoskel.blender.test_data import truth_as_estimate
    from monoskel.core.synthetic.motion import load_motion
    from monoskel.core.synthetic.synth import synthesize

    tracks, truth = synthesize(load_motion("builtin:walk", max_frames=n_frames), kinds=("pan",), seed=5,
                               dropout=0.2)
    scene_data.store_tracks(scene, tracks)
    est = truth_as_estimate(truth)
    est.method = "test"
    est.focal_mm = 55.0
    est.proportions = {k: v * (1.1 if k == "thigh" else 1.0) for k, v in est.proportions.items()}
    total = sum(est.proportions.values())
    est.proportions = {k: v / total for k, v in est.proportions.items()}
    est.diagnostics["warnings"] = ["thigh looks long"]
    scene_data.store_estimate(scene, est)
    if truth_too:
        scene_data.store_truth(scene, truth)
    assert bpy.ops.monoskel.refresh() == {"FINISHED"}
    return tracks, truth, est


def test_an_undetermined_focal_length_says_how_to_give_the_lens(empty_scene):
    import bpy

    from monoskel.blender import scene_data

    _, _, est = _store_tracks_and_estimate(empty_scene)
    hint = "Know the lens? Untick Estimate Focal Length, enter it and estimate again"
    assert not any(hint in t for t in _texts(_rows_everywhere(empty_scene)["camera"]))
    est.diagnostics["focal_determined"] = False
    scene_data.store_estimate(empty_scene, est)
    assert bpy.ops.monoskel.refresh() == {"FINISHED"}
    rows = _rows_everywhere(empty_scene)
    _check_consistency(empty_scene, rows)
    texts = _texts(rows["camera"])
    assert any(t.startswith("Focal length not determined") for t in texts)
    assert any(t.startswith("Assumed about 55 mm.") and hint in t for t in texts)
    empty_scene.monoskel.estimate_focal = False          # the lens given: nothing left to advise
    assert not any(hint in t for t in _texts(_rows_everywhere(empty_scene)["camera"]))


def test_state_no_tracks(empty_scene):
    rows = _rows_everywhere(empty_scene)
    _check_consistency(empty_scene, rows)
    assert any("No tracks yet" in t for t in _texts(rows["input"]))
    estimate = [r for r in rows["estimate"] if r.op == "monoskel.estimate"][0]
    assert not estimate.enabled and estimate.reason == "Import tracks first"
    assert _texts(rows["results"]) == ["Import tracks first"]
    assert all(not r.enabled for r in rows["build"] if r.kind == "operator")
    assert all(r.reason for r in rows["export"])


def test_state_tracks(empty_scene, tmp_path):
    import bpy

    from monoskel.core.synthetic.motion import load_motion
    from monoskel.core.synthetic.synth import synthesize
    from monoskel.core.tracks import write_tracks_json

    tracks, _ = synthesize(load_motion("builtin:walk", max_frames=15), kinds=("still",), seed=0, dropout=0.25)
    path = tmp_path / "t.json"
    write_tracks_json(tracks, path)
    bpy.ops.monoskel.import_tracks(filepath=str(path))
    rows = _rows_everywhere(empty_scene)
    _check_consistency(empty_scene, rows)
    texts = _texts(rows["input"])
    assert "Frames: 15 (from scene frame 1)" in texts
    assert f"Missing: {100 * tracks.missing_fraction():.1f}%" in texts
    assert f"Joints present: {int(tracks.present.any(axis=0).sum())}/17" in texts
    assert [r for r in rows["estimate"] if r.op == "monoskel.estimate"][0].enabled
    assert _texts(rows["results"]) == ["Run Estimate first"]
    # Camera: the initial focal is greyed out while "estimate" is on, and editable when off.
    focal = [r for r in rows["camera"] if r.attr == "focal_mm"][0]
    assert not focal.enabled
    empty_scene.monoskel.estimate_focal = False
    focal = [r for r in _rows_everywhere(empty_scene)["camera"] if r.attr == "focal_mm"][0]
    assert focal.enabled


def test_state_estimating(empty_scene):
    from monoskel.blender import estimate_job

    _store_tracks_and_estimate(empty_scene)
    release = threading.Event()
    job = estimate_job.EstimateJob(lambda progress, should_cancel: release.wait(10)).start()
    estimate_job.set_current(job)
    s = empty_scene.monoskel
    s.estimate_running, s.estimate_progress, s.estimate_message = True, 0.4, "stance feet"
    try:
        rows = _rows_everywhere(empty_scene)
        _check_consistency(empty_scene, rows)
        progress = [r for r in rows["estimate"] if r.kind == "progress"]
        assert len(progress) == 1 and progress[0].value == pytest.approx(0.4) and progress[0].text == "stance feet"
        cancel = [r for r in rows["estimate"] if r.op == "monoskel.estimate_cancel"][0]
        assert cancel.enabled
        assert not [r for r in rows["estimate"] if r.op == "monoskel.estimate"]
        for section in ("build", "export"):
            assert all(r.reason == "An estimate is running; wait or cancel it"
                       for r in rows[section] if r.kind == "operator")
        import bpy

        assert bpy.ops.monoskel.estimate_cancel() == {"FINISHED"}
        assert job.cancel_requested
    finally:
        release.set()
        job.wait(10)
        estimate_job.set_current(None)
        s.estimate_running = False


def test_state_result(empty_scene):
    from monoskel.core.skeleton import CLASSES

    _, _, est = _store_tracks_and_estimate(empty_scene)
    rows = _rows_everywhere(empty_scene)
    _check_consistency(empty_scene, rows)
    results = rows["results"]
    assert "Focal length: 55.0 mm (36 mm equivalent)" in _texts(results)
    table = [r for r in results if r.kind == "table"][0]
    assert table.cells[0] == ("Class", "Proportion")
    assert [c[0] for c in table.cells[1:]] == list(CLASSES)
    assert [float(c[1]) for c in table.cells[1:]] == pytest.approx([est.proportions[c] for c in CLASSES], abs=1e-4)
    assert "thigh looks long" in _texts(results)
    spells = [t for t in _texts(rows["camera"]) if t.startswith("  frames ")]
    assert len(spells) == len(est.diagnostics["spells"]) > 0
    assert all(r.enabled for r in rows["build"] if r.kind == "operator")


def test_state_result_with_truth(empty_scene):
    import bpy

    from monoskel.core.skeleton import CLASSES

    _, truth, est = _store_tracks_and_estimate(empty_scene, truth_too=True)
    bpy.ops.monoskel.build_all()
    rows = _rows_everywhere(empty_scene)
    _check_consistency(empty_scene, rows)
    table = [r for r in rows["results"] if r.kind == "table"][0]
    assert table.cells[0] == ("Class", "Estimate", "Truth", "Error")
    for k, name in enumerate(CLASSES):
        row = table.cells[1 + k]
        expected = 100 * (est.proportions[name] - truth.proportions[k]) / truth.proportions[k]
        assert float(row[3].rstrip("%")) == pytest.approx(expected, abs=0.06), name
    thigh = table.cells[1 + CLASSES.index("thigh")]
    assert float(thigh[3].rstrip("%")) > 5  # the thigh was made 10 % longer before renormalising
    assert any(t.startswith("True focal (mean):") for t in _texts(rows["results"]))
    assert any(t.startswith("Armature: ") for t in _texts(rows["build"]))
    assert all(r.enabled for r in rows["export"])


def test_state_with_a_movie_clip(empty_scene, tmp_path):
    import bpy

    image = bpy.data.images.new("frame", 32, 24)
    image.file_format = "PNG"
    image.filepath_raw = str(tmp_path / "c_0001.png")
    image.save()
    empty_scene.active_clip = bpy.data.movieclips.load(str(tmp_path / "c_0001.png"))
    rows = _rows_everywhere(empty_scene, has_clip=True)
    _check_consistency(empty_scene, rows)
    buttons = {r.op: r for r in rows["clip"] if r.kind == "operator"}
    need_tracks = ("monoskel.refine_tracks", "monoskel.track_background")
    assert all(r.enabled for op, r in buttons.items() if op not in need_tracks)
    for op in need_tracks:                                 # refining and the background need tracks too
        assert buttons[op].reason == "Import tracks first"


def test_test_data_section_needs_a_file_for_file_source(empty_scene):
    s = empty_scene.monoskel
    s.test_source = "FILE"
    rows = _rows_everywhere(empty_scene)
    _check_consistency(empty_scene, rows)
    assert "test_bvh_path" in [r.attr for r in rows["test_data"]]
    button = [r for r in rows["test_data"] if r.kind == "operator"][0]
    assert button.reason == "Choose a BVH file first"


def test_panels_are_registered_in_workflow_order(blender):
    import bpy

    from monoskel.ui import panels

    labels = [cls.bl_label for cls in panels.classes if getattr(cls, "bl_parent_id", "") == "MONOSKEL_PT_main"]
    assert labels == ["Input", "Camera", "Estimate", "Results", "Build", "Takes", "Retarget", "Single Image", "Export"]
    for cls in panels.classes:
        assert hasattr(bpy.types, cls.__name__)
        if issubclass(cls, bpy.types.Panel):
            assert cls.bl_category == "MonoSkel"


def test_rows_use_only_real_icons_and_layout_calls(empty_scene):
    """What the renderer passes to UILayout exists in this Blender (checked on its RNA, no layout needed)."""
    import bpy

    from monoskel.ui import state

    functions = bpy.types.UILayout.bl_rna.functions
    icons = set(functions["label"].parameters["icon"].enum_items.keys())
    expected = {"label": ("text", "icon"), "prop": ("data", "property", "text"),
                "operator": ("operator", "text", "icon", "depress"), "progress": ("factor", "type", "text"),
                "row": ("align",), "column": ("align",), "box": (), "separator": ("factor",),
                "prop_search": ("data", "property", "search_data", "search_property", "text"),
                "template_list": ("listtype_name", "list_id", "dataptr", "propname", "active_dataptr",
                                  "active_propname", "rows")}
    for name, params in expected.items():
        assert name in functions, name
        assert set(params) <= set(functions[name].parameters.keys()), name
    assert "BAR" in functions["progress"].parameters["type"].enum_items.keys()
    _store_tracks_and_estimate(empty_scene, truth_too=True)
    used = set()
    for settings_state in (False, True):
        empty_scene.monoskel.estimate_running = settings_state
        for rows in _rows_everywhere(empty_scene, has_clip=True).values():
            used |= {r.icon for r in rows}
    empty_scene.monoskel.estimate_running = False
    used |= {r.icon for r in state.section_rows("input", empty_scene.monoskel)}
    used |= {"RADIOBUT_ON", "RADIOBUT_OFF"}           # the take list's rows (ui/panels.MONOSKEL_UL_takes)
    assert used <= icons, used - icons


def test_opening_a_file_written_without_the_sidebar_fills_the_summary(empty_scene, tmp_path):
    """batch.py stores data but not the sidebar summary; opening its .blend fills the summary in."""
    import bpy

    from monoskel.blender import scene_data
    from monoskel.core.synthetic.motion import load_motion
    from monoskel.core.synthetic.synth import synthesize

    tracks, _ = synthesize(load_motion("builtin:walk", max_frames=11), kinds=("still",), seed=0)
    scene_data.store_tracks(empty_scene, tracks)
    empty_scene.monoskel.estimate_running = True  # a run cannot survive saving and reopening
    path = tmp_path / "batch_like.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    bpy.ops.wm.open_mainfile(filepath=str(path))
    s = bpy.context.scene.monoskel
    assert s.has_tracks and s.tracks_frames == 11 and not s.estimate_running
