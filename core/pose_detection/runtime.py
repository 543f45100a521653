"""Where the BlazePose model files are and what runs them: the detector's optional part.

The estimator needs nothing from here.  Detection needs two things that are
not Python source and are installed apart from it:

* the model files ``pose_detection.tflite`` and ``pose_landmark_full.tflite``
  (Google's BlazePose, Apache-2.0), looked for in ``$MONOSKEL_POSE_MODELS``,
  then in ``models/blazepose/`` of the extension (``tools/fetch_pose_models.py``
  puts them there from the ``mediapipe`` wheel on PyPI), then in an installed
  ``mediapipe`` package;
* a TensorFlow Lite interpreter: ``ai_edge_litert`` (LiteRT), else
  ``tflite_runtime``, else ``tensorflow.lite``.

Nothing is ever downloaded at run time.  When either part is missing,
:class:`DetectorUnavailable` says which and how to get it, in one line.
"""

from __future__ import annotations

import importlib
import importlib.util
import os

import numpy as np

from ..errors import InputError

DETECTOR_FILE = "pose_detection.tflite"
LANDMARK_FILE = "pose_landmark_full.tflite"
ENV_VAR = "MONOSKEL_POSE_MODELS"
_EXTENSION_ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUNDLED_DIR = os.path.join(_EXTENSION_ROOT, "models", "blazepose")
RUNTIME_HINT = "pip install ai-edge-litert into Blender's Python (docs/pose_detection.md)"
MODELS_HINT = "run tools/fetch_pose_models.py (docs/pose_detection.md)"


class DetectorUnavailable(InputError):
    """The detector's optional part (models or interpreter) is not installed."""


def _candidate_dirs() -> list[str]:
    dirs = []
    if os.environ.get(ENV_VAR):
        dirs.append(os.environ[ENV_VAR])
    dirs.append(BUNDLED_DIR)
    try:
        spec = importlib.util.find_spec("mediapipe")
    except (ImportError, ValueError):
        spec = None
    if spec is not None and spec.submodule_search_locations:
        base = list(spec.submodule_search_locations)[0]
        dirs += [os.path.join(base, "modules", "pose_detection"), os.path.join(base, "modules", "pose_landmark")]
    return dirs


def find_model(name: str) -> str:
    """Path of the model file ``name``; :class:`DetectorUnavailable` when none is installed."""
    for folder in _candidate_dirs():
        path = os.path.join(folder, name)
        if os.path.isfile(path):
            return path
    raise DetectorUnavailable(f"pose detector model {name} not found (looked in ${ENV_VAR}, {BUNDLED_DIR} and "
                              f"an installed mediapipe): {MODELS_HINT}")


INTERPRETERS = (("ai_edge_litert.interpreter", "Interpreter"), ("tflite_runtime.interpreter", "Interpreter"),
                ("tensorflow.lite", "Interpreter"))


def interpreter_class():
    """The first TensorFlow Lite interpreter class that imports."""
    for module, attr in INTERPRETERS:
        try:
            return getattr(importlib.import_module(module), attr)
        except (ImportError, AttributeError):
            continue
    raise DetectorUnavailable(f"no TensorFlow Lite interpreter is installed: {RUNTIME_HINT}")


def _interpreter_installed() -> bool:
    """Whether an interpreter package is there, without importing it (LiteRT takes ~0.1 s to import)."""
    for module, _ in INTERPRETERS:
        try:
            if importlib.util.find_spec(module.split(".")[0]) is not None:
                return True
        except (ImportError, ValueError):
            continue
    return False


def available() -> tuple[bool, str]:
    """(True, "") when detection can likely run here, else (False, why), cheaply and without raising:
    for a sidebar.  (A package that is there but fails to import is reported when detection starts.)"""
    if not _interpreter_installed():
        return False, f"Pose detector runtime missing: {RUNTIME_HINT}"
    try:
        find_model(DETECTOR_FILE)
        find_model(LANDMARK_FILE)
    except DetectorUnavailable:
        return False, f"Pose detector models missing: {MODELS_HINT}"
    return True, ""


class _Model:
    """One loaded network: ``run(tensor) -> {output name: array}``."""

    def __init__(self, path: str, threads: int):
        cls = interpreter_class()
        try:
            self._it = cls(model_path=path, num_threads=threads)
            self._it.allocate_tensors()
        except (ValueError, RuntimeError) as exc:
            raise DetectorUnavailable(f"{path}: cannot be loaded as a TensorFlow Lite model ({exc})") from None
        self._input = self._it.get_input_details()[0]["index"]
        self._outputs = {d["name"]: d["index"] for d in self._it.get_output_details()}

    def run(self, tensor: np.ndarray) -> dict[str, np.ndarray]:
        self._it.set_tensor(self._input, np.ascontiguousarray(tensor, dtype=np.float32))
        self._it.invoke()
        return {name: self._it.get_tensor(idx) for name, idx in self._outputs.items()}


class Networks:
    """BlazePose's detector and full landmark network, loaded once.

    Output names are the models' own: the detector's ``Identity`` (boxes) and
    ``Identity_1`` (scores); the landmark model's ``Identity`` (39 x 5
    landmarks), ``Identity_1`` (pose score), ``Identity_3`` (heatmap) and
    ``Identity_4`` (39 x 3 world landmarks, metres).
    """

    def __init__(self, threads: int | None = None):
        threads = threads or min(4, os.cpu_count() or 1)
        self.detector = _Model(find_model(DETECTOR_FILE), threads)
        self.landmarks = _Model(find_model(LANDMARK_FILE), threads)

    def detect(self, tensor: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        out = self.detector.run(tensor)
        return out["Identity"], out["Identity_1"]

    def landmark(self, tensor: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
        out = self.landmarks.run(tensor)
        return out["Identity"], out["Identity_1"], out["Identity_3"], out.get("Identity_4")
