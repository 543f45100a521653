"""A Movie Clip's frames as RGB arrays, decoded by Blender itself.

Blender's Python API gives an image's pixels for one frame of a movie only,
so the frames are rendered through the sequencer of a temporary scene (a
movie or image-sequence strip, the Standard view transform so that pixels
pass unchanged) into uncompressed BMP files in a temporary folder, a chunk at
a time, read back with the core's BMP reader and deleted.  Blender's own
ffmpeg decodes, so every format Blender plays works, with no extra package.
:meth:`ClipFrames.close` removes the scene and the folder, whatever happened.
"""

from __future__ import annotations

import os
import re
import shutil
import tempfile

import bpy

from ...core.errors import InputError
from ...core.pose_detection.frames import read_bmp
from ..compat import sequencer_strips, set_output_format

SCENE_NAME = "MonoSkel Decode (temporary)"
#: A chunk's BMP files never take more than this on disk (24 frames of 4K would be 600 MB).
CHUNK_BYTES = 256 * 1024 * 1024


def _sequence_files(path: str) -> list[str]:
    """The files of an image sequence that starts at ``path``: same name but for the last number, in order."""
    folder, name = os.path.split(path)
    match = re.match(r"^(.*?)(\d+)(\D*)$", name)
    if match is None:
        return [name]
    head, digits, tail = match.groups()
    pattern = re.compile(re.escape(head) + r"(\d+)" + re.escape(tail) + "$")
    numbered = []
    for other in os.listdir(folder or "."):
        m = pattern.match(other)
        if m and int(m.group(1)) >= int(digits):
            numbered.append((int(m.group(1)), other))
    numbered.sort()
    for (a, _), (b, _) in zip(numbered, numbered[1:]):
        if b != a + 1:   # the strip would slide every later image onto the wrong frame
            raise InputError(f"image sequence {name}: no image numbered {a + 1} (the next is {b}); fill the gap "
                             f"or rename the images so the numbers run on")
    return [n for _, n in numbered]


class ClipFrames:
    """Frames ``first``..``last`` (clip frames, 1-based, every ``step``-th) of ``clip``, ``chunk`` at a time."""

    def __init__(self, clip, first: int, last: int, step: int = 1, chunk: int = 24):
        if clip.source not in {"MOVIE", "SEQUENCE"}:
            raise InputError(f"clip '{clip.name}': only movies and image sequences can be decoded")
        path = bpy.path.abspath(clip.filepath)
        if not os.path.exists(path):
            raise InputError(f"clip '{clip.name}': its file {path} is missing")
        width, height = (int(v) for v in clip.size)
        if width <= 0 or height <= 0:
            raise InputError(f"clip '{clip.name}': Blender cannot read its frames ({path})")
        self.clip_name, self.width, self.height = clip.name, width, height
        self.first, self.last, self.step = int(first), int(last), max(1, int(step))
        self.chunk = max(1, min(int(chunk), CHUNK_BYTES // (3 * width * height)))
        self.next_frame = self.first
        self.folder = tempfile.mkdtemp(prefix="monoskel_decode_")
        self.scene = None
        try:
            self._make_scene(clip, path)
        except BaseException:
            self.close()
            raise

    def _make_scene(self, clip, path: str) -> None:
        scene = self.scene = bpy.data.scenes.new(SCENE_NAME)   # held at once: close() removes it on any failure
        editor = scene.sequence_editor_create()
        if clip.source == "MOVIE":
            sequencer_strips(editor).new_movie(name="clip", filepath=path, channel=1, frame_start=1)
        else:
            files = _sequence_files(path)
            first = os.path.join(os.path.dirname(path), files[0])
            strip = sequencer_strips(editor).new_image(name="clip", filepath=first, channel=1, frame_start=1)
            for name in files[1:]:
                strip.elements.append(name)
        render = scene.render
        render.resolution_x, render.resolution_y, render.resolution_percentage = self.width, self.height, 100
        render.pixel_aspect_x = render.pixel_aspect_y = 1.0
        render.fps, render.fps_base = max(1, round(clip.fps or 30)), 1.0
        render.use_sequencer, render.use_compositing = True, False
        render.dither_intensity = 0.0
        render.use_file_extension, render.use_overwrite, render.use_placeholder = True, True, False
        set_output_format(render.image_settings, "BMP")
        render.image_settings.color_mode = "RGB"
        view = scene.view_settings
        view.view_transform, view.look, view.exposure, view.gamma = "Standard", "None", 0.0, 1.0
        render.filepath = os.path.join(self.folder, "f_")

    @property
    def done(self) -> bool:
        return self.next_frame > self.last

    @property
    def total(self) -> int:
        return (self.last - self.first) // self.step + 1

    def next_chunk(self) -> list[tuple[int, object]]:
        """[(clip frame, (H, W, 3) uint8 RGB), ...] for the next chunk; [] when done."""
        if self.done:
            return []
        start = self.next_frame
        end = min(self.last, start + self.step * (self.chunk - 1))
        scene = self.scene
        scene.frame_start, scene.frame_end, scene.frame_step = start, end, self.step
        with bpy.context.temp_override(scene=scene):
            bpy.ops.render.render(animation=True, scene=scene.name)
        frames = []
        for number in range(start, end + 1, self.step):
            path = os.path.join(self.folder, f"f_{number:04d}.bmp")
            if not os.path.exists(path):
                raise InputError(f"clip '{self.clip_name}': Blender could not decode frame {number}")
            frames.append((number, read_bmp(path)))
            os.remove(path)
        self.next_frame = end + self.step
        return frames

    def frame(self, number: int):
        """Clip frame ``number`` (within ``first``..``last``) alone, as (H, W, 3) uint8 RGB (for a few chosen
        frames; :meth:`next_chunk` reads runs of them faster)."""
        scene = self.scene
        scene.frame_start = scene.frame_end = int(number)
        scene.frame_step = 1
        with bpy.context.temp_override(scene=scene):
            bpy.ops.render.render(animation=True, scene=scene.name)
        path = os.path.join(self.folder, f"f_{int(number):04d}.bmp")
        if not os.path.exists(path):
            raise InputError(f"clip '{self.clip_name}': Blender could not decode frame {number}")
        try:
            return read_bmp(path)
        finally:
            os.remove(path)

    def close(self) -> None:
        if self.scene is not None:
            try:
                bpy.data.scenes.remove(self.scene)
            except ReferenceError:
                pass
            self.scene = None
        shutil.rmtree(self.folder, ignore_errors=True)
