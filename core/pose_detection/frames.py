"""Frames for the detector, as (H, W, 3) uint8 RGB arrays, from files the core can read itself.

The core reads without any image library:

* a folder of ``.bmp`` images (uncompressed 24/32-bit, what Blender writes
  when it decodes a movie for :mod:`blender.pose_detection`) or ``.npy``
  frames, in name order;
* one ``.npy`` stack (F, H, W, 3) or a single ``.bmp``/``.npy`` frame;
* a video file (mp4, mov, avi, mkv, webm ...) or a folder of PNG/JPEG images,
  only through ``imageio-ffmpeg`` when it is installed (a PyPI package that
  ships its own ffmpeg, which also applies a phone's rotation flag).
  Otherwise the message says how to decode it: ``batch.py --video`` decodes
  with Blender's own ffmpeg.

A :class:`FrameSource` knows its frame count (when cheap to know), size and
frame rate and yields frames lazily, so a long clip never sits in memory.
"""

from __future__ import annotations

import importlib
import os
from collections.abc import Callable, Iterator
from dataclasses import dataclass

import numpy as np

from ..errors import InputError

NATIVE_IMAGES = (".bmp", ".npy")
FFMPEG_IMAGES = (".png", ".jpg", ".jpeg", ".tif", ".tiff", ".webp")
VIDEOS = (".mp4", ".mov", ".m4v", ".avi", ".mkv", ".webm", ".mpg", ".mpeg", ".mts", ".gif")


def read_bmp(path: str) -> np.ndarray:
    """An uncompressed 24- or 32-bit BMP as (H, W, 3) uint8 RGB."""
    raw = np.fromfile(path, dtype=np.uint8)
    if raw.size < 54 or raw[:2].tobytes() != b"BM":
        raise InputError(f"{path}: not a BMP image")

    def field(start, size, signed=False):
        return int.from_bytes(raw[start:start + size].tobytes(), "little", signed=signed)

    offset, width, height = field(10, 4), field(18, 4, True), field(22, 4, True)
    bpp, compression = field(28, 2), field(30, 4)
    if bpp not in (24, 32) or compression not in (0, 3) or width <= 0 or height == 0:
        raise InputError(f"{path}: only uncompressed 24/32-bit BMP images are read (this one: {bpp}-bit, "
                         f"compression {compression})")
    channels = bpp // 8
    stride = (width * channels + 3) // 4 * 4
    rows = abs(height)
    if raw.size < offset + stride * rows:
        raise InputError(f"{path}: BMP image is cut short")
    pixels = raw[offset:offset + stride * rows].reshape(rows, stride)[:, :width * channels]
    pixels = pixels.reshape(rows, width, channels)[..., 2::-1]  # BGR(A) -> RGB
    return np.ascontiguousarray(pixels[::-1] if height > 0 else pixels)  # positive height: bottom-up


def read_frame(path: str) -> np.ndarray:
    """One image file the core reads natively (.bmp or .npy) as (H, W, 3) uint8."""
    ext = os.path.splitext(path)[1].lower()
    if ext == ".bmp":
        return read_bmp(path)
    if ext == ".npy":
        return _as_rgb(np.load(path, allow_pickle=False), path)
    raise InputError(f"{path}: the core reads .bmp and .npy frames itself; for {ext} install imageio-ffmpeg")


def _as_rgb(frame: np.ndarray, where: str) -> np.ndarray:
    if frame.ndim == 2:
        frame = np.repeat(frame[..., None], 3, axis=2)
    if frame.ndim != 3 or frame.shape[2] not in (3, 4):
        raise InputError(f"{where}: a frame must be H x W x 3 (RGB), got shape {frame.shape}")
    if frame.dtype != np.uint8:
        frame = np.clip(frame * (255.0 if np.issubdtype(frame.dtype, np.floating) and frame.max() <= 1.0 else 1.0),
                        0, 255).astype(np.uint8)
    return frame[..., :3]


@dataclass
class FrameSource:
    """Frames to detect in: ``read(i)`` is not offered, only ordered iteration from ``start``."""

    description: str
    width: int
    height: int
    fps: float | None
    count: int | None
    _iterate: Callable[[int], Iterator[np.ndarray]]

    def frames(self, start: int = 0) -> Iterator[np.ndarray]:
        return self._iterate(start)


def _folder_source(folder: str) -> FrameSource:
    names = sorted(n for n in os.listdir(folder) if os.path.splitext(n)[1].lower() in NATIVE_IMAGES + FFMPEG_IMAGES)
    native = [n for n in names if os.path.splitext(n)[1].lower() in NATIVE_IMAGES]
    if not names:
        raise InputError(f"{folder}: no image files (.bmp, .npy, .png, .jpg) in this folder")
    if len(native) < len(names):
        return _ffmpeg_folder_source(folder, names)
    paths = [os.path.join(folder, n) for n in native]
    first = read_frame(paths[0])

    def iterate(start):
        for p in paths[start:]:
            frame = read_frame(p)
            if frame.shape != first.shape:
                raise InputError(f"{p}: frame size {frame.shape[1]}x{frame.shape[0]} differs from the first "
                                 f"frame's {first.shape[1]}x{first.shape[0]}")
            yield frame

    return FrameSource(folder, first.shape[1], first.shape[0], None, len(paths), iterate)


def _npy_source(path: str) -> FrameSource:
    stack = np.load(path, mmap_mode="r", allow_pickle=False)
    if stack.ndim in (2, 3) and (stack.ndim == 2 or stack.shape[2] in (3, 4)):
        stack = stack[None]
    if stack.ndim != 4:
        raise InputError(f"{path}: a frame stack must be shaped (frames, H, W, 3), got {stack.shape}")

    def iterate(start):
        for i in range(start, stack.shape[0]):
            yield _as_rgb(np.asarray(stack[i]), f"{path} frame {i}")

    return FrameSource(path, stack.shape[2], stack.shape[1], None, stack.shape[0], iterate)


def _imageio_ffmpeg():
    try:
        return importlib.import_module("imageio_ffmpeg")
    except ImportError:
        return None


def _ffmpeg_needed(what: str) -> InputError:
    return InputError(f"{what}: decoding it needs imageio-ffmpeg (pip install imageio-ffmpeg), or run it through "
                      f"Blender, which decodes video itself: batch.py --video FILE")


def _video_source(path: str) -> FrameSource:
    iio = _imageio_ffmpeg()
    if iio is None:
        raise _ffmpeg_needed(path)
    try:
        reader = iio.read_frames(path)
        meta = next(reader)
    except (OSError, RuntimeError, StopIteration) as exc:
        raise InputError(f"{path}: not a video ffmpeg can read ({str(exc).splitlines()[0] if str(exc) else exc})") \
            from None
    reader.close()
    width, height = (int(v) for v in meta["size"])
    fps = float(meta.get("fps") or 0) or None
    count = None
    try:
        count = int(iio.count_frames_and_secs(path)[0])
    except (OSError, RuntimeError):
        pass

    def iterate(start):
        frames = iio.read_frames(path)
        next(frames)
        for i, buf in enumerate(frames):
            if i >= start:
                yield np.frombuffer(buf, dtype=np.uint8).reshape(height, width, 3)

    return FrameSource(path, width, height, fps, count, iterate)


def _ffmpeg_folder_source(folder: str, names: list[str]) -> FrameSource:
    iio = _imageio_ffmpeg()
    if iio is None:
        raise _ffmpeg_needed(folder)
    # ffmpeg has no name-ordered list input; decode each image on its own (still frames are small)
    paths = [os.path.join(folder, n) for n in names]

    def one(p):
        gen = iio.read_frames(p)
        meta = next(gen)
        w, h = meta["size"]
        return np.frombuffer(next(gen), dtype=np.uint8).reshape(h, w, 3)

    first = one(paths[0])

    def iterate(start):
        for p in paths[start:]:
            yield one(p)

    return FrameSource(folder, first.shape[1], first.shape[0], None, len(paths), iterate)


def open_frames(source: str) -> FrameSource:
    """A :class:`FrameSource` for a video file, an image folder, a ``.npy`` stack or one image."""
    if os.path.isdir(source):
        return _folder_source(source)
    if not os.path.exists(source):
        raise InputError(f"{source}: no such file or folder")
    ext = os.path.splitext(source)[1].lower()
    if ext == ".npy":
        return _npy_source(source)
    if ext == ".bmp":
        frame = read_bmp(source)
        return FrameSource(source, frame.shape[1], frame.shape[0], None, 1, lambda start: iter([frame][start:]))
    if ext in VIDEOS or ext in FFMPEG_IMAGES:
        return _video_source(source)
    raise InputError(f"{source}: not a video or image this reader knows ({', '.join(VIDEOS + NATIVE_IMAGES)})")
