"""Single photographs of real people with motion-capture truth: the detector and the single-image pose.

The only real pictures with 3D truth within reach are the eight frames mmpose keeps for its tests
(github.com/open-mmlab/mmpose, ``tests/data``, commit 759b39c1): four Human3.6M frames (subjects 1, 5,
7, 8; a studio, 1000 x 1000) and four MPI-INF-3DHP frames (two of its training set, two of its test
set; studio frames, 2048 x 2048), each with its camera's focal length and the capture's 17 joints in
camera axes. Both datasets allow research use only and Human3.6M forbids passing its data on, so they are read where
they lie and never copied into this repository. Fetch mmpose and point this at its ``tests/data``:

    python bench/real_frames_bench.py MMPOSE/tests/data

Every frame is posed (the single-image scenario of ``bench/single_image_bench.py``: perspective, the
camera's focal length told) from the capture's joints projected into the picture (the datasets' 2D
truth) and from BlazePose's joints found in the photograph, both with the capture's own bone lengths,
and from BlazePose's joints with the built-in adult figure's lengths (what ``python -m core
single-image`` uses when told nothing else). Per frame: P-MPJPE (a similarity of its own) and whether
a limb points more than 45 degrees off (a mirrored limb). Then, over the limb bones clearly out of the
picture's plane, how often each reading of depth gets a bone's depth sign right: the pose lifter (from
the 2D truth and from BlazePose's joints), BlazePose's own 3D joints (the tracks' ``landmarks_3d``) and
the single-image pose. Eight frames say whether the method works on real pictures, not how well to a
millimetre.
"""

from __future__ import annotations

import argparse
import os
import pickle
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import numpy as np  # noqa: E402

from bench.single_image_bench import frame_scores  # noqa: E402
from core.camera import mm_per_pixel  # noqa: E402
from core.motion_prior.features import bone_vectors  # noqa: E402
from core.single_image import pose_from_image  # noqa: E402
from core.skeleton import class_lengths_from_segments, segment_lengths  # noqa: E402
from core.synthetic.procedural import adult_class_lengths  # noqa: E402

#: A limb bone whose true depth change is above this share of its length counts in the depth-sign table.
CLEAR_SLANT = 0.3
#: The canonical joints (pelvis, spine, thorax, neck, head, left leg, right leg, left arm, right arm)
#: as each dataset's 17 joints, by index.
H36M_ORDER = [0, 7, 8, 9, 10, 4, 5, 6, 1, 2, 3, 11, 12, 13, 14, 15, 16]
MPI_INF_3DHP_ORDER = [14, 15, 1, 16, 0, 11, 12, 13, 8, 9, 10, 5, 6, 7, 2, 3, 4]


def frames(root: str):
    """(name, image path, truth (17, 3) camera axes in metres, 2D truth (17, 2) px, focal px, (w, h))."""
    h36m = os.path.join(root, "h36m")
    with open(os.path.join(h36m, "cameras.pkl"), "rb") as fh:
        cams = pickle.load(fh)
    data = np.load(os.path.join(h36m, "test_h36m_body3d.npz"))
    for name, S, part in zip(data["imgname"], data["S"], data["part"], strict=True):
        subject, rest = str(name).split("/", 1)
        cam = cams[(subject, rest.split(".")[1].split("/")[0])]
        size = (int(np.ravel(cam["w"])[0]), int(np.ravel(cam["h"])[0]))
        yield (os.path.basename(str(name)), os.path.join(h36m, str(name)), S[H36M_ORDER, :3],
               part[H36M_ORDER, :2], float(np.mean(cam["f"])), size)
    hp = os.path.join(root, "mpi_inf_3dhp")
    for split in ("test", "train"):
        with open(os.path.join(hp, f"cameras_{split}.pkl"), "rb") as fh:
            cams = pickle.load(fh)
        data = np.load(os.path.join(hp, f"test_3dhp_{split}.npz"))
        for name, S, part in zip(data["imgname"], data["S"], data["part"], strict=True):
            key = str(name).rsplit("_", 1)[0]
            cam = cams[key]
            yield (str(name), os.path.join(hp, str(name)), S[MPI_INF_3DHP_ORDER, :3], part[MPI_INF_3DHP_ORDER, :2],
                   float(np.mean(cam["f"])), (2048, 2048))


def detected_joints(path: str) -> tuple[np.ndarray | None, tuple[int, int], np.ndarray | None]:
    """BlazePose's 17 joints (px, NaN where not found) in the photograph at ``path`` (None: nobody found),
    its size, and the detector's own 3D joints (17, 3) (camera axes, NaN where it gives none)."""
    from core.errors import InputError
    from core.pose_detection.detect import detect_frames
    from core.pose_detection.frames import open_frames

    source = open_frames(path)
    try:
        found = detect_frames(source.frames(), fps=None, image_size=(source.width, source.height),
                              mode="per-frame")
    except InputError:
        return None, (source.width, source.height), None
    world = found.tracks.landmarks_3d
    return found.tracks.xy[0], (source.width, source.height), None if world is None else world[0]


def limb_depth_signs(truth: np.ndarray, guesses: dict) -> dict:
    """For the limb bones clearly out of the picture's plane in ``truth`` (depth change over length above
    :data:`CLEAR_SLANT`): per guess (name -> (16, 3) bone vectors in camera axes, or None where it has no
    answer, which counts as wrong), how many of those bones it gives the true depth sign (child nearer or
    farther than its parent), and how many there were."""
    from bench.single_image_bench import LIMB_SEGMENTS
    from core.skeleton import SEGMENTS

    out = {}
    for name, bones in guesses.items():
        right = judged = 0
        for k in LIMB_SEGMENTS:
            p, c = SEGMENTS[k]
            true = truth[c] - truth[p]
            if abs(true[2]) <= CLEAR_SLANT * np.linalg.norm(true):
                continue
            judged += 1
            if bones is not None and np.isfinite(bones[k]).all() and np.sign(bones[k][2]) == np.sign(true[2]):
                right += 1
        out[name] = (right, judged)
    return out


def lifter_bones(xy: np.ndarray, size: tuple[int, int], f_px: float) -> np.ndarray | None:
    """The shipped one-picture lifter's bone directions for 2D joints ``xy`` (px) seen with ``f_px``: the
    single-image pose's own reading (:func:`core.single_image.signs.lifter_cue`)."""
    from core.single_image.signs import lifter_cue

    if xy is None:
        return None
    return lifter_cue(xy - np.array(size, dtype=float) / 2.0, f_px)


def mirrored_bones(est: np.ndarray, truth: np.ndarray) -> list[str]:
    """The limb bones (named by their lower joint) more than :data:`core.evaluation.metrics.MIRROR_ANGLE_DEG`
    off the truth after the frame's similarity alignment (:func:`core.evaluation.metrics.limb_angles_deg`)."""
    from core.evaluation import metrics
    from core.skeleton import JOINTS

    angles = metrics.limb_angles_deg(est[None], truth[None])[0]
    return [JOINTS[c] for (_, c), a in zip(metrics.LIMB_BONES, angles, strict=True) if a > metrics.MIRROR_ANGLE_DEG]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("root", help="mmpose's tests/data folder (h36m/ and mpi_inf_3dhp/ in it)")
    args = ap.parse_args(argv)
    rows = {"2D truth": [], "BlazePose": [], "BlazePose, built-in figure": []}
    missed = dict.fromkeys(rows, 0)
    signs: dict[str, list[int]] = {}
    for name, image, truth, xy_true, f_px, size in frames(args.root):
        captured = class_lengths_from_segments(segment_lengths(truth[None])[0])
        xy_found, found_size, world = detected_joints(image)
        line = [name]
        f_found = f_px * size[0] / found_size[0]
        guesses = {"the lifter, from the 2D truth": lifter_bones(xy_true, size, f_px),
                   "the lifter, from BlazePose's joints": lifter_bones(xy_found, found_size, f_found),
                   "BlazePose's own 3D joints": None if world is None else bone_vectors(world),
                   "the single-image pose, BlazePose's joints, built-in figure": None}
        for label, xy, sz, lengths in (("2D truth", xy_true, size, captured),
                                       ("BlazePose", xy_found, found_size, captured),
                                       ("BlazePose, built-in figure", xy_found, found_size, adult_class_lengths(1.75))):
            if xy is None:
                missed[label] += 1
                line.append(f"{label}: nobody found")
                continue
            focal_mm = f_px * size[0] / sz[0] * mm_per_pixel(sz)
            pose = pose_from_image(xy, sz, lengths, focal_mm=focal_mm, perspective=True)
            err, mirrored = frame_scores(pose.joints, truth)
            rows[label].append((err, mirrored))
            if label == "BlazePose, built-in figure":
                guesses["the single-image pose, BlazePose's joints, built-in figure"] = bone_vectors(pose.joints)
            bones = mirrored_bones(pose.joints, truth)
            line.append(f"{label}: {err * 1000:.0f} mm{' (mirrored: ' + ', '.join(bones) + ')' if mirrored else ''}")
        print("; ".join(line), flush=True)
        for guess, (right, judged) in limb_depth_signs(truth, guesses).items():
            tally = signs.setdefault(guess, [0, 0])
            tally[0] += right
            tally[1] += judged
    print("\n| 2D joints from | frames posed | P-MPJPE mm median / mean | frames with a mirrored limb | nobody found |")
    print("|---|---|---|---|---|")
    for label, vals in rows.items():
        e = np.array([v[0] for v in vals]) * 1000
        m = sum(v[1] for v in vals)
        print(f"| {label} | {len(vals)} | {np.median(e):.1f} / {e.mean():.1f} | {m} of {len(vals)} | {missed[label]} |")
    print(f"\n| limb bones out of the picture's plane (depth over length above {CLEAR_SLANT}) | depth sign right |")
    print("|---|---|")
    for guess, (right, judged) in signs.items():
        print(f"| {guess} | {right} of {judged} ({100.0 * right / max(judged, 1):.0f} %) |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
