"""The native skeleton-tracks reader: round trip and one-line errors for hostile files."""

import numpy as np
import pytest

from core.errors import InputError
from core.skeleton import JOINTS
from core.tracks import Tracks, read_tracks_json, write_tracks_json


def _tracks(n=4):
    rng = np.random.default_rng(1)
    xy = rng.uniform(0, 700, (n, 17, 2))
    conf = np.ones((n, 17))
    conf[1, 3] = 0.0
    return Tracks(xy, conf, 25.0, (720, 480))


def test_round_trip_keeps_values_and_missing(tmp_path):
    t = _tracks()
    path = tmp_path / "t.json"
    write_tracks_json(t, path)
    back = read_tracks_json(path)
    assert back.fps == 25.0 and back.image_size == (720.0, 480.0)
    assert np.isnan(back.xy[1, 3]).all() and back.conf[1, 3] == 0
    np.testing.assert_allclose(back.xy[0], t.xy[0], atol=1e-4)


@pytest.mark.parametrize("payload, words", [
    (b"\x80", "not a UTF-8"),
    (b"[" * 100000, "nested too deeply"),
    (b'{"format": "skeleton-tracks", "version": 1, "fps": 1' + b"0" * 400 + b"}", "too large"),
    (b"", "empty"),
    (b"{", "invalid JSON"),
    (b'{"format": "skeleton-tracks", "version": 1, "fps": -3}', "fps"),
])
def test_hostile_files_give_one_line_input_errors(tmp_path, payload, words):
    path = tmp_path / "bad.json"
    path.write_bytes(payload)
    with pytest.raises(InputError) as info:
        read_tracks_json(path)
    assert words in str(info.value) and "\n" not in str(info.value)


def test_ragged_frame_names_the_frame(tmp_path):
    import json
    doc = {"format": "skeleton-tracks", "version": 1, "fps": 30, "image_size": [720, 480],
           "joints": list(JOINTS), "frames": [[None] * 17, [None] * 16]}
    path = tmp_path / "ragged.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(InputError, match="frame 1"):
        read_tracks_json(path)


def test_missing_fps_is_a_named_setting(tmp_path):
    from core.errors import MissingSettingError
    from core.io.formats import read_any

    path = tmp_path / "t.csv"
    path.write_text("frame,joint,x,y\n0,pelvis,10,20\n")
    with pytest.raises(MissingSettingError) as info:
        read_any(path, format="generic_csv", image_size=(720, 480))
    assert info.value.setting == "fps"


def test_source_and_plain_meta_round_trip(tmp_path):
    xy = np.full((2, 17, 2), 10.0)
    conf = np.ones((2, 17))
    meta = {"detector": "BlazePose", "step": 2, "ok": True, "ranks": [1, 2], "array": np.zeros(3),
            "nested": {"a": 1}, "bad": float("nan")}
    write_tracks_json(Tracks(xy, conf, 30.0, (64, 48), source="clip.mp4", meta=meta), tmp_path / "t.json")
    back = read_tracks_json(tmp_path / "t.json")
    assert back.meta == {"detector": "BlazePose", "step": 2, "ok": True, "ranks": [1, 2], "source": "clip.mp4"}
    write_tracks_json(Tracks(xy, conf, 30.0, (64, 48)), tmp_path / "plain.json")
    assert read_tracks_json(tmp_path / "plain.json").meta == {}


def test_a_replaced_copy_leaves_the_original_as_it_was():
    t = _tracks()
    xy = t.xy.copy()
    xy[2, 5] = np.nan                          # missing in the copy only: its confidence becomes 0 there ...
    copy = t.replaced(xy=xy)
    assert copy.conf[2, 5] == 0.0
    assert t.conf[2, 5] == 1.0 and t.present[2, 5]          # ... not in the original, whose array it shared
    conf = t.conf.copy()
    conf[0, 0] = 0.0
    t.replaced(conf=conf)
    assert np.isfinite(t.xy[0, 0]).all()
