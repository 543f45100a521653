"""A small network that lifts one picture's joints to 3D: which way each bone points in depth.

Why: every bone seen in a picture has two depths (towards or away from the camera), and the depth-sign
choices of :mod:`core.joint_solve.signs_dp` and :mod:`core.single_image` score each candidate pose on
its own (knees bend backwards, the pose prior's likelihood).  A network that sees the *whole* picture
of the body at once reads what those terms cannot: how foreshortened every other bone is, where the
hands are against the hips, the turn of the shoulders.  Its answer is not used as the pose (its
lengths and placement are guesses); it is a soft per-frame cue for the depth order of each bone, added
where the signs are chosen.

The input is camera- and lens-free: the viewing rays of the 17 joints, turned so that the pelvis's ray
is the optical axis (a virtual camera looking straight at the person, so where the person stands in
the frame and the focal length drop out), projected, and divided by their spread.  The output is the
bone vectors (child minus parent) in those axes, divided by the pelvis depth times the same spread
(image units, so a bone's depth offset is on the scale of its image length); bones rather than joints,
so that one bone's error does not carry down its limb.

A lifter may read a window of frames around the one it answers (``taps_s``, seconds; :func:`windowed`):
how a foreshortened bone moves over half a second says more about its depth than one picture of it, and
a slip of one frame's joints counts for less.  The joint solve reads video with such a lifter
(``data/pose_lifter_video.npz``); a single image with the one-picture lifter (``data/pose_lifter.npz``).

Loaded and run with numpy alone: a multilayer perceptron (ReLU), or the mean of several trained alike
(:meth:`PoseLifter.averaged`; the shipped files hold four), stored as a compressed ``.npz`` with its
training record (clips, licence, the networks' seeds, the taps) as JSON text.  Trained by :mod:`.train_lifter`.
"""

from __future__ import annotations

import json
import os

import numpy as np

from ..skeleton import JOINT_INDEX, N_SEGMENTS, SEGMENTS
from ..timebase.frames import frames_between, nearest_marked
from .features import _unit

#: The joints the network reads besides the pelvis: all but the neck and head, whose places are a
#: capture rig's convention (the CMU rig's head joint sits below its neck joint) and, in footage, a
#: detector's (nose and ears).
INPUT_JOINTS: tuple[int, ...] = tuple(j for j in range(1, 17) if j not in (JOINT_INDEX["neck"], JOINT_INDEX["head"]))
#: The bones it answers (segment indices, :data:`core.skeleton.SEGMENTS` order): the same, without the
#: neck's and head's.
OUTPUT_BONES: tuple[int, ...] = tuple(s for s, (_, c) in enumerate(SEGMENTS) if c in INPUT_JOINTS)
N_INPUTS = 2 * len(INPUT_JOINTS)
N_OUTPUTS = 3 * len(OUTPUT_BONES)
_IN = np.array(INPUT_JOINTS)


def axis_to_z(direction: np.ndarray) -> np.ndarray:
    """(..., 3, 3) the smallest rotations taking the unit vectors ``direction`` (..., 3) to +z.

    The rotation turns about ``direction x z``, so the picture's up stays up when the person is off
    the optical axis; a direction pointing away (z < 0) is not expected (joints are in front)."""
    d = _unit(np.asarray(direction, dtype=float))
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    k = 1.0 / np.maximum(1.0 + z, 1e-9)
    out = np.empty(d.shape[:-1] + (3, 3))
    out[..., 0, 0] = 1.0 - x * x * k
    out[..., 0, 1] = -x * y * k
    out[..., 0, 2] = -x
    out[..., 1, 0] = -x * y * k
    out[..., 1, 1] = 1.0 - y * y * k
    out[..., 1, 2] = -y
    out[..., 2, 0] = x
    out[..., 2, 1] = y
    out[..., 2, 2] = z
    return out


def normalised_view(rays: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The network's input from viewing rays (..., 17, 3) in camera axes.

    Returns (inputs (..., 2 x len(INPUT_JOINTS)), turn (..., 3, 3) the rotation to the virtual camera's
    axes, spread (...,)): the :data:`INPUT_JOINTS`' projections in the virtual camera looking along the
    pelvis's ray, divided by their root-mean-square distance from the pelvis."""
    rays = np.asarray(rays, dtype=float)
    turn = axis_to_z(rays[..., 0, :])
    v = np.einsum("...ab,...jb->...ja", turn, rays[..., _IN, :])
    uv = v[..., :2] / v[..., 2:3]
    spread = np.sqrt(np.mean(np.sum(uv * uv, axis=-1), axis=-1))
    spread = np.maximum(spread, 1e-9)
    x = (uv / spread[..., None, None]).reshape(uv.shape[:-2] + (N_INPUTS,))
    return x, turn, spread


class PoseLifter:
    """A ReLU perceptron from :func:`normalised_view` inputs to the :data:`OUTPUT_BONES` (image units).

    It may hold several networks of one shape (members, trained alike from their own seeds), stacked on a
    leading axis of every weight and bias; it then answers their mean (:meth:`averaged`)."""

    def __init__(self, weights: list[np.ndarray], biases: list[np.ndarray], meta: dict | None = None):
        if len(weights) != len(biases) or not weights:
            raise ValueError("a lifter needs as many bias vectors as weight matrices, at least one")
        self.weights = [np.asarray(w, dtype=np.float32) for w in weights]
        self.biases = [np.asarray(b, dtype=np.float32) for b in biases]
        stacked = {w.ndim == 3 for w in self.weights} | {b.ndim == 2 for b in self.biases}
        if len(stacked) != 1 or any(w.ndim not in (2, 3) for w in self.weights):
            raise ValueError("a lifter's layers are all single networks' or all stacked members'")
        self.meta = dict(meta or {})
        self.taps_s = tuple(float(t) for t in self.meta.get("taps_s", (0.0,)))
        if 0.0 not in self.taps_s:
            raise ValueError("a lifter's taps include the frame it answers (0 s)")
        if self.weights[0].shape[-2] != N_INPUTS * len(self.taps_s) or self.weights[-1].shape[-1] != N_OUTPUTS:
            raise ValueError(f"a lifter maps {N_INPUTS} inputs per tap ({len(self.taps_s)}) to {N_OUTPUTS} outputs")

    @property
    def temporal(self) -> bool:
        """Whether it reads a window of frames around the one it answers (:data:`taps_s`), not one picture."""
        return len(self.taps_s) > 1

    @property
    def members(self) -> int:
        """How many networks it averages."""
        return self.weights[0].shape[0] if self.weights[0].ndim == 3 else 1

    def forward(self, x: np.ndarray) -> np.ndarray:
        """(N, N_OUTPUTS) outputs for inputs (N, N_INPUTS): the members' mean."""
        h = np.asarray(x, dtype=np.float32)
        last = len(self.weights) - 1
        for i, (w, b) in enumerate(zip(self.weights, self.biases)):
            h = h @ w + (b[:, None, :] if b.ndim == 2 else b)
            if i < last:
                np.maximum(h, 0.0, out=h)
        return h.mean(axis=0) if h.ndim == 3 else h

    @classmethod
    def averaged(cls, members: list[PoseLifter], meta: dict | None = None) -> PoseLifter:
        """One lifter holding ``members`` (networks of one shape, or lifters that hold several already),
        which answers the mean of their outputs: each network's sign errors are partly its own."""
        if not members:
            raise ValueError("averaging needs at least one lifter")
        shapes = {tuple(w.shape[-2:] for w in m.weights) for m in members}
        if len(shapes) != 1:
            raise ValueError("averaged lifters must have layers of one shape")

        def stack(arrays, ndim):
            return np.concatenate([a if a.ndim == ndim + 1 else a[None] for a in arrays])

        weights = [stack([m.weights[i] for m in members], 2) for i in range(len(members[0].weights))]
        biases = [stack([m.biases[i] for m in members], 1) for i in range(len(members[0].biases))]
        return cls(weights, biases, meta)

    def bone_directions(self, rays: np.ndarray, fps: float | None = None) -> np.ndarray:
        """(..., 16, 3) unit bone vectors (child minus parent, :data:`core.skeleton.SEGMENTS` order) the
        network sees in rays (..., 17, 3), in the rays' camera axes; NaN for the bones it does not answer
        (the neck's and head's) and for frames with a missing ray.

        A :attr:`temporal` lifter reads consecutive frames, rays (F, 17, 3) filmed at ``fps``."""
        rays = np.asarray(rays, dtype=float)
        lead = rays.shape[:-2]
        x, turn, _ = normalised_view(rays.reshape((-1,) + rays.shape[-2:]))
        ok = np.isfinite(x).all(axis=1)
        if self.temporal and ok.any():
            if rays.ndim != 3 or not fps or fps <= 0:
                raise ValueError("a temporal lifter reads consecutive frames (F, 17, 3) at a known frame rate")
            x = windowed(x, self.taps_s, fps)
        out = np.full((x.shape[0], N_SEGMENTS, 3), np.nan)
        if ok.any():
            y = self.forward(x[ok]).astype(float).reshape(-1, len(OUTPUT_BONES), 3)
            out[np.ix_(ok, OUTPUT_BONES)] = _unit(np.einsum("fba,fjb->fja", turn[ok], y))   # turn^T: camera axes
        return out.reshape(lead + (N_SEGMENTS, 3))

    def save(self, path: str | os.PathLike, half: bool = False) -> None:
        """Write the networks and the training record; ``half`` stores the weights as 16-bit floats (half
        the file, read back as 32-bit; the answers move by about a thousandth of a bone's direction)."""
        kind = np.float16 if half else np.float32
        arrays = {f"w{i}": w.astype(kind) for i, w in enumerate(self.weights)}
        arrays.update({f"b{i}": b for i, b in enumerate(self.biases)})
        np.savez_compressed(path, meta=np.array(json.dumps(self.meta, sort_keys=True)), **arrays)

    @classmethod
    def load(cls, path: str | os.PathLike) -> PoseLifter:
        with np.load(path, allow_pickle=False) as data:
            n = sum(1 for k in data.files if k.startswith("w"))
            weights = [data[f"w{i}"] for i in range(n)]
            biases = [data[f"b{i}"] for i in range(n)]
            meta = json.loads(str(data["meta"])) if "meta" in data.files else {}
        return cls(weights, biases, meta)


def windowed(x: np.ndarray, taps_s, fps: float) -> np.ndarray:
    """(F, len(taps_s) x D) each frame's inputs at the times ``taps_s`` (seconds) around it, from per-frame
    inputs ``x`` (F, D) of consecutive frames at ``fps``: linear between frames, held at the clip's ends.
    Frames without inputs (NaN rows) take their nearest read frame's, so a lost frame does not blank
    its neighbours' windows; with no read frame at all the result is NaN."""
    x = np.asarray(x, dtype=float)
    n = x.shape[0]
    ok = np.isfinite(x).all(axis=1)
    if not ok.any():
        return np.full((n, len(taps_s) * x.shape[1]), np.nan)
    if not ok.all():
        have = np.flatnonzero(ok)
        x = x[have[nearest_marked(have, np.arange(n))]]
    i0, i1, w = frames_between(np.arange(n)[:, None] + np.asarray(taps_s, dtype=float)[None, :] * fps, 0, n - 1)
    w = w[..., None]
    return (x[i0] * (1.0 - w) + x[i1] * w).reshape(n, -1)


def smoothed_over_frames(directions: np.ndarray, sigma_frames: float) -> np.ndarray:
    """Unit directions (F, B, 3) of consecutive frames, each the normalised Gaussian-weighted sum of its
    neighbours' within 3 ``sigma_frames`` (NaN ones left out; a NaN stays NaN).

    Why: the network reads each picture alone, so its slips are one frame's, while a bone turns
    smoothly; a slip then counts for less against the frames around it."""
    from scipy.ndimage import gaussian_filter1d

    d = np.asarray(directions, dtype=float)
    if sigma_frames <= 0 or d.shape[0] < 2:
        return d.copy()
    ok = np.isfinite(d).all(axis=-1)
    # zeros for the unread frames and beyond the clip's ends: they add nothing to the sum
    total = gaussian_filter1d(np.where(ok[..., None], d, 0.0), sigma_frames, axis=0, mode="constant", truncate=3.0)
    out = total / np.maximum(np.linalg.norm(total, axis=-1, keepdims=True), 1e-12)
    out[~ok] = np.nan
    return out
