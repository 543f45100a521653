"""``bench/camera_oracle.py``'s footprint column says how far the planted feet alone pin a handheld camera; that
claim rests on its least squares recovering the camera when the footprints are exact."""


import numpy as np
import pytest

from core.camera import pixels_to_film
from core.evaluation import metrics
from core.joint_solve.stance import stance_codes  # noqa: E402
from core.skeleton import FEET
from core.synthetic.footage_sim import HandheldOperator
from core.synthetic.motion import load_motion
from core.synthetic.synth import synthesize


@pytest.fixture(scope="module")
def bench(load_bench):
    return load_bench("camera_oracle.py")


def _walk(noise_px):
    tracks, truth = synthesize(load_motion("builtin:walk", max_frames=240, fps=30.0), noise_px=noise_px, seed=3,
                               focal_mm=35.0, operator=HandheldOperator())
    film = pixels_to_film(tracks.xy, tracks.image_size)
    feet = np.stack([film[:, FEET["l"]], film[:, FEET["r"]]], axis=1)
    stance = stance_codes(truth.stance)
    return feet, stance, truth, tracks.fps


def test_exact_footprints_give_the_handheld_camera(bench):
    feet, stance, truth, fps = _walk(0.0)
    assert np.ptp(truth.rotvec_deg[:, 1]) > 2.0            # the operator did turn the camera
    rv = bench.footprint_rotvec_deg(feet, stance, truth.focal_mm, fps)
    err = metrics.rotation_error_deg(rv, truth.rotvec_deg)
    # a still camera, or the pan's sign turned round, is degrees off (6 and 11.5 here); the shake between
    # contacts, which the acceleration prior smooths over, keeps it from zero (0.6)
    still = metrics.rotation_error_deg(np.zeros_like(rv), truth.rotvec_deg)
    assert err < 1.0 and still > 4 * err
    assert metrics.rotation_error_deg(-rv, truth.rotvec_deg) > 4 * err
