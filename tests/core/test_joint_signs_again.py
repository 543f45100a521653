"""The second depth-sign choice on the solved state (core.joint_solve.pipeline.signs_again).

A wrong depth sign is a minimum the solve cannot leave: the segment would have to turn through the
plane parallel to the image, off its ray.  These tests plant such a mirrored stretch in an otherwise
true state and check that the second choice finds it and that the solve's cost says so.
"""

import numpy as np
import pytest

from core import camera as cam
from core.joint_solve import pipeline as pl
from core.joint_solve import solver as slv
from core.joint_solve.stance import stance_codes
from core.skeleton import JOINT_INDEX, SEGMENTS
from core.synthetic.motion import load_motion
from core.synthetic.synth import synthesize

THIGH = next(k for k, (p, c) in enumerate(SEGMENTS) if c == JOINT_INDEX["l_knee"])


@pytest.fixture(scope="module")
def clip():
    motion = load_motion("builtin:walk", max_frames=90, fps=30.0)
    return synthesize(motion, kinds=("pan", "tilt"), noise_px=0.0, seed=3)


def _below(segment):
    """Joints under a segment's child (they follow it)."""
    out = {SEGMENTS[segment][1]}
    for p, c in SEGMENTS:
        if p in out:
            out.add(c)
    return out - {SEGMENTS[segment][1]}


def _mirror(Y, segment, frames):
    """The segment's other depth root (same ray, same length) in ``frames``; the joints below keep
    their rays and their depth offsets, so the image does not change."""
    p, c = SEGMENTS[segment]
    Y = Y.copy()
    for i in frames:
        t = np.linalg.norm(Y[i, c])
        u = Y[i, c] / t
        new = u * (2 * u @ Y[i, p] - t)
        dz = new[2] - Y[i, c, 2]
        Y[i, c] = new
        for d in _below(segment):
            Y[i, d] *= (Y[i, d, 2] + dz) / Y[i, d, 2]
    return Y


def _state(truth, Y):
    R = truth.rotations()
    joints = np.einsum("fba,fjb->fja", R, Y)
    st = stance_codes(truth.stance)
    return slv.pack(joints, np.radians(truth.rotvec_deg), np.log(truth.focal_mm), truth.class_lengths_m, stance=st)


def _depth_offsets(x, n, segment):
    joints, w = slv.unpack(x, n)[:2]
    Y = np.einsum("fab,fjb->fja", slv.rot_and_left_jacobian(w)[0], joints)
    p, c = SEGMENTS[segment]
    return Y[:, c, 2] - Y[:, p, 2]


def _mirrored_stretch(truth):
    """The longest stretch where the true thigh points clearly in depth (one sign, |dz| > 5 cm)."""
    Y = truth.joints_camera()
    p, c = SEGMENTS[THIGH]
    dz = Y[:, c, 2] - Y[:, p, 2]
    best, run = [], []
    for i in range(len(dz)):
        if abs(dz[i]) > 0.05 and (not run or np.sign(dz[i]) == np.sign(dz[run[-1]])):
            run.append(i)
        else:
            run = [i] if abs(dz[i]) > 0.05 else []
        best = max(best, run, key=len)
    assert len(best) >= 10
    return np.array(best), dz


def test_second_choice_on_the_solved_state_undoes_a_mirrored_stretch(clip):
    tracks, truth = clip
    frames, dz_true = _mirrored_stretch(truth)
    x_bad = _state(truth, _mirror(truth.joints_camera(), THIGH, frames))
    n = tracks.n_frames
    assert np.mean(np.sign(_depth_offsets(x_bad, n, THIGH)[frames]) != np.sign(dz_true[frames])) >= 0.9
    x_new = pl.signs_from_solution(x_bad, n)
    dz_new = _depth_offsets(x_new, n, THIGH)
    assert np.mean(np.sign(dz_new[frames]) == np.sign(dz_true[frames])) >= 0.9
    # ... and it keeps frames it was told to keep (a window's pinned overlap)
    kept = pl.signs_from_solution(x_bad, n, keep=frames[-1] + 1)
    assert np.allclose(slv.unpack(kept, n)[0][:frames[-1] + 1], slv.unpack(x_bad, n)[0][:frames[-1] + 1])


def test_signs_again_lowers_the_cost_of_a_mirror_minimum(clip):
    tracks, truth = clip
    frames, dz_true = _mirrored_stretch(truth)
    n = tracks.n_frames
    st = stance_codes(truth.stance)
    prob = slv.Problem(cam.pixels_to_film(tracks.xy, tracks.image_size), cam.mm_per_pixel(tracks.image_size),
                       tracks.fps, truth.height_m, st, focal_prior_mm=float(truth.focal_mm[0]))
    x1, rep1 = slv.solve(prob, _state(truth, _mirror(truth.joints_camera(), THIGH, frames)), max_iter=5)
    # the solve alone keeps most of the mirrored stretch (the reason for the second choice)
    assert np.mean(np.sign(_depth_offsets(x1, n, THIGH)[frames]) == np.sign(dz_true[frames])) < 0.75
    x2, rep2 = pl.signs_again(prob, x1, rep1)
    assert rep2.cost < rep1.cost
    assert np.mean(np.sign(_depth_offsets(x2, n, THIGH)[frames]) == np.sign(dz_true[frames])) >= 0.9
    # a state the second choice cannot improve comes back unchanged
    x3, rep3 = pl.signs_again(prob, x2, rep2)
    assert rep3.cost <= rep2.cost
