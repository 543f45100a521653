"""Ground truth of a synthetic clip and its ``skeleton-truth`` JSON.

The generator (:mod:`core.synthetic.synth`) writes one truth file beside every tracks
file, so that the evaluation, the Blender test-data operator and the tests can
hold an estimate against what really happened.  Per-frame quantities mirror the
``skeleton-estimate`` frames (same conventions, :mod:`core.camera`), so a
comparison is field by field.

File shape (world = the motion's Y-up world, metres)::

    {"format": "skeleton-truth", "version": 1, "source": "...", "fps": 30.0, "image_size": [720, 480],
     "proportions": {10 classes}, "class_lengths_m": {10 classes}, "height_m": 1.75,
     "camera": {"position_world": [x,y,z], "rotation_world_from_cam0": 3x3},
     "world_from_cam0": 4x4,            # frame-0 camera coords -> Blender world (Z up, floor z = 0)
     "spells": [{"start": 0, "end": 44, "kind": "still", "params": {}}, ...],   # end inclusive
     "occlusions": [{"start": 10, "end": 39, "limb": "l_arm"}, ...],           # end inclusive
     "generator": {...settings...},
     "frames": [{"stance": "l"|"r"|null, "stance_clear": bool, "camera_moving": bool,
                 "rotvec_deg": [3], "focal_mm": f, "scale": s, "joints_3d": 17 x [x,y,z]}, ...]}
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field

import numpy as np

from ..camera import rotation_matrix
from ..errors import InputError
from ..io.file_io import check_header, read_json_file, write_json_atomic
from ..skeleton import CLASSES, N_JOINTS, proportions_array
from .synth_camera import Spell

FORMAT_NAME = "skeleton-truth"
FORMAT_VERSION = 1


@dataclass
class Truth:
    """What a synthetic clip really shows.

    Per-frame arrays: ``stance`` list of "l"/"r"/None; ``stance_clear`` (F,)
    bool (exactly one foot planted); ``camera_moving`` (F,) bool;
    ``rotvec_deg`` (F, 3) (``X_i = R_i X_0``); ``focal_mm`` (F,); ``scale``
    (F,) Peng & Li's ``s'_i = Z_0 / Z_i`` of the pelvis in frame-0 camera axes;
    ``joints_3d`` (F, 17, 3) metres in frame-0 camera coordinates.
    ``proportions`` and ``class_lengths_m`` are (10,) in :data:`CLASSES` order.
    """

    source: str
    fps: float
    image_size: tuple[float, float]
    proportions: np.ndarray
    class_lengths_m: np.ndarray
    height_m: float
    camera_position_world: np.ndarray
    rotation_world_from_cam0: np.ndarray
    world_from_cam0: np.ndarray
    spells: list[Spell]
    stance: list
    stance_clear: np.ndarray
    camera_moving: np.ndarray
    rotvec_deg: np.ndarray
    focal_mm: np.ndarray
    scale: np.ndarray
    joints_3d: np.ndarray
    occlusions: list[dict] = field(default_factory=list)
    generator: dict = field(default_factory=dict)

    @property
    def n_frames(self) -> int:
        return int(self.joints_3d.shape[0])

    def rotations(self) -> np.ndarray:
        """(F, 3, 3) camera rotations ``R_i`` with ``X_i = R_i X_0``."""
        return rotation_matrix(self.rotvec_deg)

    def joints_camera(self) -> np.ndarray:
        """(F, 17, 3) joints in each frame's own camera coordinates."""
        return np.einsum("fij,fkj->fki", self.rotations(), self.joints_3d)

    def proportions_dict(self) -> dict[str, float]:
        return {name: float(self.proportions[i]) for i, name in enumerate(CLASSES)}


def _r(v, digits: int = 8) -> float:
    return round(float(v), digits)


def truth_to_dict(truth: Truth) -> dict:
    frames = []
    for i in range(truth.n_frames):
        frames.append({
            "stance": truth.stance[i],
            "stance_clear": bool(truth.stance_clear[i]),
            "camera_moving": bool(truth.camera_moving[i]),
            "rotvec_deg": [_r(v) for v in truth.rotvec_deg[i]],
            "focal_mm": _r(truth.focal_mm[i]),
            "scale": _r(truth.scale[i]),
            "joints_3d": [[_r(c, 7) for c in p] for p in truth.joints_3d[i]],
        })
    return {
        "format": FORMAT_NAME,
        "version": FORMAT_VERSION,
        "source": truth.source,
        "fps": float(truth.fps),
        "image_size": [float(truth.image_size[0]), float(truth.image_size[1])],
        "proportions": {name: _r(truth.proportions[i], 10) for i, name in enumerate(CLASSES)},
        "class_lengths_m": {name: _r(truth.class_lengths_m[i], 10) for i, name in enumerate(CLASSES)},
        "height_m": _r(truth.height_m),
        "camera": {
            "position_world": [_r(v) for v in truth.camera_position_world],
            "rotation_world_from_cam0": [[_r(v, 10) for v in row] for row in truth.rotation_world_from_cam0],
        },
        "world_from_cam0": [[_r(v, 10) for v in row] for row in truth.world_from_cam0],
        "spells": [s.to_dict() for s in truth.spells],
        "occlusions": [dict(o) for o in truth.occlusions],
        "generator": dict(truth.generator),
        "frames": frames,
    }


def write_truth_json(truth: Truth, path: str | os.PathLike) -> None:
    """Write ``truth`` as a ``skeleton-truth`` file (atomically: temp file + rename)."""
    write_json_atomic(truth_to_dict(truth), path, what="truth file")


def _number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _array(value, shape: tuple, what: str, where: str) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{where}{what} must be numbers shaped {shape}") from None
    if arr.shape != shape or not np.isfinite(arr).all():
        raise InputError(f"{where}{what} must be finite numbers shaped {shape}, got shape {arr.shape}")
    return arr


def _classes(value, what: str, where: str) -> np.ndarray:
    if not isinstance(value, dict) or set(value) != set(CLASSES) or not all(_number(v) for v in value.values()):
        raise InputError(f"{where}\"{what}\" must map the 10 classes {list(CLASSES)} to numbers")
    return proportions_array(value)


def truth_from_dict(doc, source: str = "") -> Truth:
    """Validate a parsed ``skeleton-truth`` document; InputError naming the problem."""
    where = f"{source}: " if source else ""
    check_header(doc, FORMAT_NAME, FORMAT_VERSION, where)
    fps = doc.get("fps")
    if not _number(fps) or fps <= 0:
        raise InputError(f"{where}\"fps\" must be a positive number, got {fps!r}")
    size = doc.get("image_size")
    if not isinstance(size, list) or len(size) != 2 or not all(_number(v) and v > 0 for v in size):
        raise InputError(f"{where}\"image_size\" must be [width, height] in pixels, got {size!r}")
    height = doc.get("height_m")
    if not _number(height) or height <= 0:
        raise InputError(f"{where}\"height_m\" must be a positive number, got {height!r}")
    cam = doc.get("camera")
    if not isinstance(cam, dict):
        raise InputError(f"{where}\"camera\" must be an object with position_world and rotation_world_from_cam0")
    position = _array(cam.get("position_world"), (3,), "camera.position_world", where)
    rot = _array(cam.get("rotation_world_from_cam0"), (3, 3), "camera.rotation_world_from_cam0", where)
    world = _array(doc.get("world_from_cam0"), (4, 4), "\"world_from_cam0\"", where)
    spells_doc = doc.get("spells")
    if not isinstance(spells_doc, list):
        raise InputError(f"{where}\"spells\" must be a list")
    spells = [Spell.from_dict(s, f"{where}spell {k}: ") for k, s in enumerate(spells_doc)]
    occlusions = doc.get("occlusions", [])
    if not isinstance(occlusions, list) or not all(isinstance(o, dict) for o in occlusions):
        raise InputError(f"{where}\"occlusions\" must be a list of objects")
    generator = doc.get("generator", {})
    if not isinstance(generator, dict):
        raise InputError(f"{where}\"generator\" must be an object")
    frames = doc.get("frames")
    if not isinstance(frames, list) or not frames:
        raise InputError(f"{where}\"frames\" is empty or not a list")
    n = len(frames)
    stance: list = []
    clear = np.zeros(n, dtype=bool)
    moving = np.zeros(n, dtype=bool)
    rotvec = np.zeros((n, 3))
    focal = np.zeros(n)
    scale = np.zeros(n)
    joints = np.zeros((n, N_JOINTS, 3))
    for i, fr in enumerate(frames):
        at = f"{where}frame {i}: "
        if not isinstance(fr, dict):
            raise InputError(f"{at}expected an object, got {type(fr).__name__}")
        st = fr.get("stance")
        if st not in ("l", "r", None):
            raise InputError(f"{at}\"stance\" must be \"l\", \"r\" or null, got {st!r}")
        stance.append(st)
        for key, arr in (("stance_clear", clear), ("camera_moving", moving)):
            if not isinstance(fr.get(key), bool):
                raise InputError(f"{at}\"{key}\" must be true or false, got {fr.get(key)!r}")
            arr[i] = fr[key]
        rotvec[i] = _array(fr.get("rotvec_deg"), (3,), "\"rotvec_deg\"", at)
        for key, arr in (("focal_mm", focal), ("scale", scale)):
            v = fr.get(key)
            if not _number(v) or v <= 0:
                raise InputError(f"{at}\"{key}\" must be a positive number, got {v!r}")
            arr[i] = v
        joints[i] = _array(fr.get("joints_3d"), (N_JOINTS, 3), "\"joints_3d\"", at)
    return Truth(
        source=str(doc.get("source", "")), fps=float(fps), image_size=(float(size[0]), float(size[1])),
        proportions=_classes(doc.get("proportions"), "proportions", where),
        class_lengths_m=_classes(doc.get("class_lengths_m"), "class_lengths_m", where),
        height_m=float(height), camera_position_world=position, rotation_world_from_cam0=rot,
        world_from_cam0=world, spells=spells, stance=stance, stance_clear=clear, camera_moving=moving,
        rotvec_deg=rotvec, focal_mm=focal, scale=scale, joints_3d=joints,
        occlusions=[dict(o) for o in occlusions], generator=dict(generator))


def read_truth_json(path: str | os.PathLike) -> Truth:
    """Read a ``skeleton-truth`` file, with one-line errors on bad input."""
    return truth_from_dict(read_json_file(path), os.fspath(path))


def truth_as_estimate(truth: Truth, method: str = "truth"):
    """The ground truth dressed as an Estimate: previews, demos, and the builders' tests, which then build
    the truth with the estimate's own rig."""
    from ..result import Estimate, FrameEstimate

    frames = [FrameEstimate(stance=truth.stance[i] if i < len(truth.stance) else None,
                            camera_moving=bool(truth.camera_moving[i]),
                            rotvec_deg=tuple(float(v) for v in truth.rotvec_deg[i]),
                            focal_mm=float(truth.focal_mm[i]), scale=float(truth.scale[i]),
                            joints_3d=np.asarray(truth.joints_3d[i], dtype=float).tolist())
              for i in range(truth.n_frames)]
    spells = [{"start": int(s.start), "end": int(s.end), "kind": str(s.kind)} for s in truth.spells]
    props = np.asarray(truth.proportions, dtype=float)
    return Estimate(method=method, proportions={name: float(props[k]) for k, name in enumerate(CLASSES)},
                    focal_mm=float(truth.focal_mm[0]), frames=frames, height_m=float(truth.height_m),
                    diagnostics={"world_from_cam0": np.asarray(truth.world_from_cam0, dtype=float).tolist(),
                                 "spells": spells, "image_size": [float(v) for v in truth.image_size],
                                 "fps": float(truth.fps)})
