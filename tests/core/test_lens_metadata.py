"""The lens the footage records: the 35 mm-equivalent focal length read from MP4 / MOV atoms
(core/lens/mp4_metadata.py), turned into the core's focal length (core/lens/prior.py), carried in the tracks
by the detector and used by the estimate when the user gives none (the user's focal always wins).

The files are built atom by atom (tests/mp4_headers.py) as phones and cameras write them: QuickTime
``keys``/``ilst`` metadata in the movie, in a track or in ``udta``; an EXIF block in ``udta``; XMP.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from core.lens.mp4_metadata import focal_35mm_equivalent, recording_phone
from core.lens.prior import (
    PHONE_VIDEO_EQUIVALENT_MM,
    Lens,
    focal_from_35mm_equivalent,
    focal_from_sensor,
    lens_from_file,
    lens_prior,
    phone_lens,
)
from tests.mp4_headers import (
    add_to_moov,
    box,
    exif_udta,
    fake_movie,
    quicktime_focal_meta,
    quicktime_text_meta,
    xmp_udta,
)

ANDROID = {"com.android.version": "14", "com.android.manufacturer": "samsung", "com.android.model": "SM-S918B"}

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("kind,value", [("int", 26), ("uint8", 24), ("float", 26.5), ("double", 77.0),
                                        ("text", 13.0)])
def test_the_quicktime_focal_key_is_read_in_every_value_type(tmp_path, kind, value):
    path = fake_movie(tmp_path / "a.mov", quicktime_focal_meta(value, kind, extra_keys=3))
    found = focal_35mm_equivalent(path)
    assert found is not None and found[0] == pytest.approx(value, abs=1e-4)
    assert "com.apple.quicktime.camera.focal_length.35mm_equivalent" in found[1]


@pytest.mark.parametrize("place", ["track", "udta-iso", "exif-II", "exif-MM", "xmp", "moov-first"])
def test_the_lens_is_found_wherever_cameras_put_it(tmp_path, place):
    if place == "track":      # track-level metadata, as Apple documents the key
        path = tmp_path / "t.mov"
        path.write_bytes(b"")
        moov = box(b"moov", box(b"mvhd", bytes(100)) + box(b"trak", box(b"tkhd", bytes(84))
                                                              + quicktime_focal_meta(28, "int")))
        path.write_bytes(box(b"ftyp", b"qt  \0\0\0\0") + box(b"mdat", bytes(100)) + moov)
        path, expected = str(path), 28
    elif place == "udta-iso":
        path, expected = fake_movie(tmp_path / "u.mp4", box(b"udta", quicktime_focal_meta(35, "int", iso=True))), 35
    elif place.startswith("exif"):
        path, expected = fake_movie(tmp_path / "e.mov", exif_udta(31, place[-2:])), 31
    elif place == "xmp":
        path, expected = fake_movie(tmp_path / "x.mp4", xmp_udta(52)), 52
    else:
        path, expected = fake_movie(tmp_path / "f.mp4", quicktime_focal_meta(26, "int"), moov_last=False), 26
    found = focal_35mm_equivalent(path)
    assert found is not None and found[0] == expected, found


def test_a_movie_header_at_the_end_of_a_long_file_is_found(tmp_path):
    path = fake_movie(tmp_path / "long.mp4", quicktime_focal_meta(26, "int"), mdat_bytes=300_000)
    assert focal_35mm_equivalent(path, limit=10_000)[0] == 26        # only the file's two ends are read


def test_files_without_a_lens_or_with_a_broken_one_give_none(tmp_path):
    assert focal_35mm_equivalent(fake_movie(tmp_path / "plain.mp4")) is None
    assert focal_35mm_equivalent(fake_movie(tmp_path / "zero.mp4", quicktime_focal_meta(0, "int"))) is None
    assert focal_35mm_equivalent(fake_movie(tmp_path / "neg.mp4", quicktime_focal_meta(-13, "int"))) is None
    broken = bytearray(Path(fake_movie(tmp_path / "b.mp4", quicktime_focal_meta(26, "int"))).read_bytes())
    at = broken.find(b"keys")
    broken[at + 8:at + 16] = b"\xff" * 8                              # an absurd key count
    (tmp_path / "b.mp4").write_bytes(bytes(broken))
    assert focal_35mm_equivalent(str(tmp_path / "b.mp4")) is None
    (tmp_path / "junk.mp4").write_bytes(b"\0\0\0\x10junkjunkjunk" + bytes(50))
    assert focal_35mm_equivalent(str(tmp_path / "junk.mp4")) is None
    assert focal_35mm_equivalent(str(tmp_path / "missing.mp4")) is None
    assert lens_from_file(str(tmp_path / "plain.mp4"), (1280, 720)) is None


def test_a_35mm_equivalent_is_the_same_diagonal_angle_in_the_cores_focal_length():
    from core.camera import mm_per_pixel

    assert focal_from_35mm_equivalent(26.0, (3000, 2000)) == pytest.approx(26.0)        # 3:2 is the 35 mm frame
    wide = focal_from_35mm_equivalent(26.0, (1920, 1080))
    assert wide == pytest.approx(26.0 * 36 * math.hypot(16, 9) / 16 / math.hypot(36, 24))   # 0.955 x
    # a portrait picture has the same focal length in pixels
    tall = focal_from_35mm_equivalent(26.0, (1080, 1920))
    assert tall / mm_per_pixel((1080, 1920)) == pytest.approx(wide / mm_per_pixel((1920, 1080)))
    # the diagonal angle of view is the 35 mm frame's
    f_px = wide / mm_per_pixel((1920, 1080))
    assert 2 * math.atan(math.hypot(1920, 1080) / 2 / f_px) == pytest.approx(2 * math.atan(math.hypot(36, 24) / 52))
    assert focal_from_sensor(24.0, 36.0, (1920, 1080)) == pytest.approx(24.0)
    assert focal_from_sensor(4.0, 6.0, (1920, 1080)) == pytest.approx(24.0)


def test_the_lens_rides_in_the_tracks_meta_and_through_the_file(tmp_path):
    from core.tracks import Tracks, read_tracks_json, write_tracks_json

    lens = lens_from_file(fake_movie(tmp_path / "p.mov", quicktime_focal_meta(26, "int")), (1920, 1080))
    assert lens.focal_mm == pytest.approx(focal_from_35mm_equivalent(26, (1920, 1080)), abs=1e-9)
    assert "file's metadata: 26 mm 35 mm-equivalent" in lens.source
    t = Tracks(np.ones((3, 17, 2)), np.ones((3, 17)), 30.0, (1920, 1080), meta=lens.meta())
    write_tracks_json(t, tmp_path / "t.json")
    back = lens_prior(read_tracks_json(tmp_path / "t.json").meta)
    assert back == Lens(round(lens.focal_mm, 3), lens.source)
    assert lens_prior({}) is None and lens_prior({"lens_focal_mm": -1.0}) is None
    assert lens_prior({"lens_focal_mm": True}) is None


def test_a_phone_that_states_no_lens_gets_its_main_camera_assumed(tmp_path):
    android = fake_movie(tmp_path / "android.mp4", quicktime_text_meta(ANDROID))
    assert focal_35mm_equivalent(android) is None
    assert recording_phone(android) == "samsung SM-S918B"
    lens = lens_from_file(android, (1920, 1080))
    assert lens.assumed and lens.focal_mm == pytest.approx(focal_from_35mm_equivalent(PHONE_VIDEO_EQUIVALENT_MM,
                                                                                       (1920, 1080)))
    assert "a phone's main camera, assumed: 28 mm 35 mm-equivalent" in lens.source and "SM-S918B" in lens.source
    # older Android versions write the system's version alone; in the video track's metadata too
    old = fake_movie(tmp_path / "old.mp4", box(b"udta", quicktime_text_meta({"com.android.version": "9"})))
    assert recording_phone(old) == "an Android phone"
    iphone = {"com.apple.quicktime.make": "Apple", "com.apple.quicktime.model": "iPhone 12"}
    assert recording_phone(fake_movie(tmp_path / "i.mov", quicktime_text_meta(iphone))) == "Apple iPhone 12"
    # a lens the file states wins over the assumption; a camera that is no phone gets none
    both = fake_movie(tmp_path / "both.mov", quicktime_text_meta(iphone) + quicktime_focal_meta(26, "int"))
    read = lens_from_file(both, (1920, 1080))
    assert not read.assumed and "file's metadata: 26 mm" in read.source
    camera = {"com.apple.quicktime.make": "Canon", "com.apple.quicktime.model": "EOS R6"}
    assert lens_from_file(fake_movie(tmp_path / "c.mov", quicktime_text_meta(camera)), (1920, 1080)) is None
    assert recording_phone(fake_movie(tmp_path / "plain.mp4")) is None
    assert recording_phone(str(tmp_path / "missing.mp4")) is None
    # the assumption rides in the tracks' meta
    back = lens_prior(lens.meta())
    assert back.assumed and back.source == lens.source and back.focal_mm == pytest.approx(lens.focal_mm, abs=1e-3)
    assert "lens_assumed" not in read.meta() and not lens_prior(read.meta()).assumed


@pytest.fixture(scope="module")
def phone_walk():
    """The built-in walk filmed with a phone's 26 mm (35 mm-equivalent) lens at 1920 x 1080."""
    from core.synthetic.motion import load_motion
    from core.synthetic.synth import synthesize

    focal = focal_from_35mm_equivalent(26.0, (1920, 1080))
    tracks, truth = synthesize(load_motion("builtin:walk", fps=30.0, max_frames=120), noise_px=1.0, seed=2,
                               focal_mm=focal, image_size=(1920, 1080))
    return tracks, focal


def test_the_estimate_takes_the_footages_lens_and_says_so(phone_walk):
    from core.estimate import estimate

    tracks, focal = phone_walk
    lens = Lens(focal, "the file's metadata: 26 mm 35 mm-equivalent (test)")
    est = estimate(tracks.replaced(meta={**tracks.meta, **lens.meta()}), "paper")
    assert est.diagnostics["lens"] == {"focal_mm": round(focal, 3), "source": lens.source}
    assert est.focal_mm == pytest.approx(focal, rel=0.05)
    without = estimate(tracks, "paper")
    assert "lens" not in without.diagnostics and abs(without.focal_mm / focal - 1) > 0.3     # 50 mm assumed
    given = estimate(tracks.replaced(meta={**tracks.meta, **lens.meta()}), "paper", focal_mm=35.0)
    assert given.focal_mm == pytest.approx(35.0, rel=0.05)                                  # the user wins
    assert given.diagnostics["lens"]["focal_mm"] == 35.0 and "not used" in given.diagnostics["lens"]["source"]


def test_the_estimate_warns_that_it_assumed_a_phones_lens(phone_walk):
    from core.estimate import estimate

    tracks, focal = phone_walk
    lens = phone_lens("samsung SM-S918B", tracks.image_size)
    est = estimate(tracks.replaced(meta={**tracks.meta, **lens.meta()}), "paper")
    assert est.diagnostics["lens"] == {"focal_mm": round(lens.focal_mm, 3), "source": lens.source, "assumed": True}
    assert est.focal_mm == pytest.approx(lens.focal_mm, rel=0.05)
    said = [w for w in est.diagnostics["warnings"] if w.startswith("lens: a phone's main camera, assumed")]
    assert len(said) == 1 and "give the focal length if known" in said[0]
    given = estimate(tracks.replaced(meta={**tracks.meta, **lens.meta()}), "paper", focal_mm=24.0)
    assert not any(w.startswith("lens: a phone") for w in given.diagnostics["warnings"])
    assert "assumed" not in given.diagnostics["lens"]
    # the joint method holds it as it holds its default, and does not call it determined
    joint = estimate(tracks.replaced(meta={**tracks.meta, **lens.meta()}), "joint")
    assert joint.focal_mm == pytest.approx(lens.focal_mm, rel=0.01) and joint.diagnostics["focal_determined"] is False
    assert estimate(tracks.replaced(meta={**tracks.meta, **lens.meta()}), "joint",
                    focal_mm=24.0).diagnostics["focal_determined"] is True


def test_detect_keeps_the_videos_lens_and_estimate_says_where_it_came_from(tmp_path):
    import imageio_ffmpeg

    from core.pose_detection import runtime

    if not runtime.available()[0]:
        pytest.fail("the detector must be installed for the tests (make models does it)")
    img = np.load(ROOT / "tests" / "core" / "data" / "person_photos.npz")["astronaut"]
    video = tmp_path / "phone.mp4"
    writer = imageio_ffmpeg.write_frames(str(video), (1280, 720), fps=24, macro_block_size=1)
    writer.send(None)
    for i in range(3):
        writer.send(np.ascontiguousarray(np.pad(img, ((100, 108), (300 + 4 * i, 468 - 4 * i), (0, 0)), mode="edge")))
    writer.close()
    add_to_moov(video, quicktime_focal_meta(26, "int"), into_track=True)
    assert focal_35mm_equivalent(str(video))[0] == 26
    out = tmp_path / "tracks.json"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.run([sys.executable, "-m", "core", "detect", str(video), "--out", str(out), "--quiet"],
                          capture_output=True, text=True, cwd=ROOT, env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "lens: 24.8 mm (36 mm film) from the file's metadata: 26 mm 35 mm-equivalent" in proc.stdout
    from core.tracks import read_tracks_json

    tracks = read_tracks_json(out)
    assert tracks.n_frames == 3          # the atoms added after the pictures leave them readable
    assert tracks.meta["lens_focal_mm"] == pytest.approx(focal_from_35mm_equivalent(26, (1280, 720)), abs=1e-3)


def test_background_tracks_overrule_an_assumed_lens_but_heed_a_stated_one():
    """A phone's assumed main camera is only where the background's own estimate of the lens starts; a lens the
    file states stays a hint it may move a little."""
    from core.estimate import estimate
    from core.synthetic.motion import load_motion
    from core.synthetic.synth import synthesize

    tracks, truth = synthesize(load_motion("builtin:walk", fps=30.0, max_frames=150), noise_px=1.0, seed=3,
                               focal_mm=70.0, static_points=12)
    assumed = phone_lens("samsung SM-S918B", tracks.image_size)
    stated = Lens(assumed.focal_mm, "the file's metadata (test)")
    for method in ("paper", "joint"):
        alone = estimate(tracks, method).focal_mm
        assert alone == pytest.approx(70.0, rel=0.02)
        told = estimate(tracks.replaced(meta={**tracks.meta, **assumed.meta()}), method)
        assert told.focal_mm == pytest.approx(alone, abs=0.05)
        assert told.diagnostics["lens"]["assumed"]
        heeded = estimate(tracks.replaced(meta={**tracks.meta, **stated.meta()}), method).focal_mm
        assert heeded < alone - 2.0                                  # pulled towards the stated 28 mm
