"""Put BlazePose's two model files into models/blazepose/ from the mediapipe wheel on PyPI.

The pose detector (core/pose_detection) runs Google's BlazePose networks,
which MediaPipe publishes under Apache-2.0 inside its wheel.  This script
downloads that one wheel with pip (a registry package, no other host), takes
``pose_detection.tflite``, ``pose_landmark_full.tflite`` and the licence out
of it, checks their SHA-256 against the pins below and writes them to
``models/blazepose/``.  Nothing else of mediapipe is installed or kept.

    python tools/fetch_pose_models.py          # no-op when the files are there and match

Run by ``make test`` (the detector's tests need it) and ``make package``.
"""

from __future__ import annotations

import hashlib
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TARGET = ROOT / "models" / "blazepose"
WHEEL = "mediapipe==0.10.14"
#: the models are the same in every platform's wheel; this one is fetched from any host
PLATFORM_ARGS = ["--platform", "manylinux_2_17_x86_64", "--python-version", "3.11", "--only-binary=:all:"]
FILES = {
    "mediapipe/modules/pose_detection/pose_detection.tflite":
        ("pose_detection.tflite", "9ba9dd3d42efaaba86b4ff0122b06f29c4122e756b329d89dca1e297fd8f866c"),
    "mediapipe/modules/pose_landmark/pose_landmark_full.tflite":
        ("pose_landmark_full.tflite", "e9a5c5cb17f736fafd4c2ec1da3b3d331d6edbe8a0d32395855aeb2cdfd64b9f"),
}
LICENSE_MEMBER = "mediapipe-0.10.14.dist-info/LICENSE"


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def present() -> bool:
    return all((TARGET / name).is_file() and _sha256(TARGET / name) == digest for name, digest in FILES.values())


def fetch() -> None:
    if present():
        print(f"BlazePose models in {TARGET} are up to date")
        return
    TARGET.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run([sys.executable, "-m", "pip", "download", "--quiet", "--disable-pip-version-check",
                        "--no-deps", "-d", tmp, WHEEL, *PLATFORM_ARGS], check=True)
        wheel = next(Path(tmp).glob("mediapipe-*.whl"))
        with zipfile.ZipFile(wheel) as archive:
            for member, (name, digest) in FILES.items():
                data = archive.read(member)
                if hashlib.sha256(data).hexdigest() != digest:
                    raise SystemExit(f"error: {member} in {wheel.name} does not match its pinned SHA-256")
                (TARGET / name).write_bytes(data)
            (TARGET / "LICENSE-mediapipe.txt").write_bytes(archive.read(LICENSE_MEMBER))
    (TARGET / "SOURCE.txt").write_text(
        f"From the PyPI wheel {WHEEL} (Apache-2.0, Google LLC): {', '.join(FILES)}.\n"
        "Written by tools/fetch_pose_models.py; see docs/pose_detection.md.\n")
    print(f"BlazePose models written to {TARGET}")


if __name__ == "__main__":
    fetch()
