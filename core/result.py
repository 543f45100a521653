"""The estimate every method returns, and its ``skeleton-estimate`` JSON.

One :class:`Estimate` per run; ``frames`` holds one :class:`FrameEstimate` per
input frame.  Conventions (camera axes, rotation direction, film) are those of
:mod:`core.camera`; ``joints_3d`` are metres in frame 0's camera coordinates
for a person of ``height_m`` (None until a method produces 3D).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field

import numpy as np

from .errors import InputError
from .io.file_io import check_header, read_json_file, write_json_atomic
from .skeleton import CLASSES, N_JOINTS, proportions_array

FORMAT_NAME = "skeleton-estimate"
FORMAT_VERSION = 1


@dataclass
class FrameEstimate:
    stance: str | None = None            # "l", "r" or None
    camera_moving: bool = False
    rotvec_deg: tuple[float, float, float] = (0.0, 0.0, 0.0)
    focal_mm: float = 50.0
    scale: float = 1.0                    # Peng & Li's virtual scale parameter s'
    joints_3d: list | None = None        # 17 x [x, y, z] metres, canonical order
    reprojection_px: float | None = None  # mean reprojection error of this frame
    rejected: list[str] | None = None     # joints the input cleaning set aside in this frame (outliers)
    swapped: list[str] | None = None      # left/right exchanges the input cleaning undid in this frame


@dataclass
class Estimate:
    method: str
    proportions: dict[str, float]
    focal_mm: float
    frames: list[FrameEstimate]
    height_m: float | None = None
    diagnostics: dict = field(default_factory=dict)

    def proportions_vector(self) -> np.ndarray:
        return proportions_array(self.proportions)


def _num(v: float, digits: int = 6) -> float:
    return round(float(v), digits)


def estimate_to_dict(est: Estimate) -> dict:
    frames = []
    for fr in est.frames:
        d = {
            "stance": fr.stance,
            "camera_moving": bool(fr.camera_moving),
            "rotvec_deg": [_num(v) for v in fr.rotvec_deg],
            "focal_mm": _num(fr.focal_mm),
            "scale": _num(fr.scale),
            "joints_3d": None if fr.joints_3d is None else [[_num(c, 5) for c in p] for p in fr.joints_3d],
        }
        if fr.reprojection_px is not None:
            d["reprojection_px"] = _num(fr.reprojection_px, 4)
        if fr.rejected:
            d["rejected"] = list(fr.rejected)
        if fr.swapped:
            d["swapped"] = list(fr.swapped)
        frames.append(d)
    doc = {
        "format": FORMAT_NAME,
        "version": FORMAT_VERSION,
        "method": est.method,
        "proportions": {k: _num(est.proportions[k], 8) for k in CLASSES},
        "focal_mm": _num(est.focal_mm),
        "frames": frames,
    }
    if est.height_m is not None:
        doc["height_m"] = _num(est.height_m)
    if est.diagnostics:
        doc["diagnostics"] = est.diagnostics
    return doc


def write_estimate_json(est: Estimate, path: str | os.PathLike) -> None:
    """Write atomically, so a failed run never leaves a partial RESULT file."""
    write_json_atomic(estimate_to_dict(est), path, what="result file", indent=1)


def estimate_from_dict(doc, source: str = "") -> Estimate:
    where = f"{source}: " if source else ""
    check_header(doc, FORMAT_NAME, FORMAT_VERSION, where)
    props = doc.get("proportions")
    if not isinstance(props, dict) or sorted(props) != sorted(CLASSES):
        raise InputError(f"{where}\"proportions\" must name exactly the classes {list(CLASSES)}")
    frames = []
    for i, d in enumerate(doc.get("frames") or []):
        j3 = d.get("joints_3d")
        if j3 is not None and (len(j3) != N_JOINTS or any(len(p) != 3 for p in j3)):
            raise InputError(f"{where}frame {i}: joints_3d must be 17 x [x, y, z]")
        frames.append(FrameEstimate(
            stance=d.get("stance"),
            camera_moving=bool(d.get("camera_moving", False)),
            rotvec_deg=tuple(float(v) for v in d.get("rotvec_deg", (0, 0, 0))),
            focal_mm=float(d.get("focal_mm", doc.get("focal_mm", 50.0))),
            scale=float(d.get("scale", 1.0)),
            joints_3d=j3,
            reprojection_px=d.get("reprojection_px"),
            rejected=_names(d.get("rejected"), where, i, "rejected"),
            swapped=_names(d.get("swapped"), where, i, "swapped"),
        ))
    if not frames:
        raise InputError(f"{where}no frames")
    focal = doc.get("focal_mm")
    if not isinstance(focal, (int, float)) or not math.isfinite(focal) or focal <= 0:
        raise InputError(f"{where}\"focal_mm\" must be a positive number")
    return Estimate(method=str(doc.get("method", "")), proportions={k: float(props[k]) for k in CLASSES},
                    focal_mm=float(focal), frames=frames, height_m=doc.get("height_m"),
                    diagnostics=doc.get("diagnostics") or {})


def _names(value, where: str, frame: int, key: str) -> list[str] | None:
    if value is None:
        return None
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise InputError(f"{where}frame {frame}: \"{key}\" must be a list of names")
    return list(value)


def read_estimate_json(path: str | os.PathLike) -> Estimate:
    """Read a ``skeleton-estimate`` file, with one-line errors on bad input."""
    return estimate_from_dict(read_json_file(path), os.fspath(path))
