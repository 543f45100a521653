"""``bench/motion_bench.py``'s ``--half all`` and ``--no-builtins``: a corpus kept for evaluation alone is
measured as one group, with only the clips given, and its means are printed beside the medians; its phone
cases and its clips played backwards keep their draws."""

import json

import numpy as np
import pytest


@pytest.fixture(scope="module")
def bench(load_bench):
    return load_bench("motion_bench.py")


def test_all_takes_every_clip_whatever_its_half(bench):
    clips = ["builtin:walk", "builtin:run", "builtin:stand"]
    halves = {bench.half_of(c) for c in clips}
    assert len(halves) == 2                                  # the built-ins fall in both halves
    for half in halves:
        assert len(bench.cases(clips, ["paper"], half, 1, None)) < len(clips)
    assert [c["clip"] for c in bench.cases(clips, ["paper"], "all", 1, None)] == clips


def test_a_corpus_alone_as_one_group(bench, tmp_path, capsys):
    out = tmp_path / "rows.json"
    assert bench.main(["builtin:stand", "--scenario", "still", "--half", "all", "--no-builtins", "--max-s", "2",
                       "--json", str(out)]) == 0
    rows = json.loads(out.read_text())
    assert [(r["clip"], r["half"]) for r in rows] == [("builtin:stand", "all")]
    text = capsys.readouterr().out
    assert "| still | all | on | 1 |" in text
    assert "still / all / on: means over cases: mirrored frames" in text


def test_phone_cases_keep_their_draws_but_the_lens_and_carry_the_assumed_lens(bench, tmp_path):
    from core.lens.prior import focal_from_35mm_equivalent

    c = bench.draw_case("builtin:walk", "paper", 0)
    phone = bench.phone_case(c)
    assert {k: v for k, v in phone.items() if k != "focal_mm"} == {k: v for k, v in c.items() if k != "focal_mm"}
    lo, hi = (focal_from_35mm_equivalent(v, bench.IMAGE_SIZE) for v in bench.PHONE_EQUIVALENT_MM)
    assert lo <= phone["focal_mm"] <= hi and phone == bench.phone_case(c)        # drawn, and the same each time
    told, plain = (bench.run_case(c, 2.0, ["on"], phone=p)[0] for p in ("assumed", "none"))
    assert told["focal_mm"] == plain["focal_mm"] == phone["focal_mm"] and told["phone"] == "assumed"
    assert any(w.startswith("lens: a phone's main camera, assumed") for w in told["warnings"])
    assert not any(w.startswith("lens: a phone") for w in plain["warnings"])


def test_backwards_films_the_clip_played_backwards_with_the_cases_own_draws(bench):
    c = bench.draw_case("builtin:walk", "still", 0)
    tracks, truth = bench.film(c, 2.0)
    back_tracks, back = bench.film({**c, "backwards": True}, 2.0)
    assert back_tracks.fps == tracks.fps and back.focal_mm[0] == truth.focal_mm[0]

    def shape(joints):                      # each frame's pose, wherever the camera puts the figure
        return np.linalg.norm(joints[:, :, None] - joints[:, None, :], axis=-1)

    np.testing.assert_allclose(shape(back.joints_3d), shape(truth.joints_3d)[::-1], atol=1e-9)
    assert not np.allclose(shape(back.joints_3d), shape(truth.joints_3d), atol=1e-3)


def test_the_oracle_cue_reads_the_cases_truth(bench, monkeypatch):
    from core.joint_solve import pipeline

    monkeypatch.setattr(pipeline, "lifter_cue", pipeline.lifter_cue)          # put back after the test
    monkeypatch.setitem(bench._oracle, "kind", None)
    c = bench.draw_case("builtin:walk", "still", 0)
    plain = bench.run_case(c, 2.0, ["on"])[0]
    bench.use_oracle_cue("directions")
    told = bench.run_case(c, 2.0, ["on"])[0]
    _, truth = bench.film(c, 2.0)
    dirs = bench.true_bone_directions(truth)
    np.testing.assert_allclose(np.linalg.norm(dirs, axis=-1), 1.0)
    # the solve reads those directions at its working rate, every frame of it
    rays = np.ones((truth.n_frames // 2, 17, 3))
    np.testing.assert_array_equal(pipeline.lifter_cue(rays, truth.fps), dirs[::2][: len(rays)])
    assert told["mpjpe_frame_mm"] < plain["mpjpe_frame_mm"]
    assert told["mirrored_pct"] == 0.0
