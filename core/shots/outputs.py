"""Where one shot's files go (``OUT/<shot>/``), its status record, and whether it needs building again.

Every file of a shot lives in its own folder, so two workers never write the same file.  The status record
(``<shot>.status.json``) is written by the folder runner after the shot's process ends, whatever happened,
so the index page can be rebuilt from the output folder alone (``--index-only``, a farm's last step).
A shot is up to date when its last run succeeded with the same command line and every output it made is
newer than every input file.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass

from ..io.file_io import write_atomic
from .discover import VIDEO, Shot

STATUS_FORMAT = "monoskel-shot-status"
OK, FAILED = "ok", "failed"


@dataclass(frozen=True)
class ShotOutputs:
    """The paths of one shot's files under the output folder."""

    folder: str
    name: str

    def _file(self, suffix: str) -> str:
        return os.path.join(self.folder, self.name + suffix)

    @property
    def blend(self) -> str:
        return self._file(".blend")

    @property
    def result(self) -> str:
        return self._file("_result.json")

    @property
    def review(self) -> str:
        """Beside the .blend, where the single-shot batch writes it (blender.worker.report_path)."""
        return self._file(".review.html")

    @property
    def tracks(self) -> str:
        """A video shot's detected tracks (kept, so the shot can be estimated again without detecting)."""
        return self._file("_tracks.json")

    @property
    def log(self) -> str:
        return self._file(".log")

    @property
    def status(self) -> str:
        return self._file(".status.json")

    @property
    def temp(self) -> str:
        """The shot's own temporary folder (TMPDIR of its process), removed when it ends."""
        return os.path.join(self.folder, ".tmp")

    def export(self, ext: str) -> str:
        return self._file("." + ext)


def shot_outputs(out_dir: str, shot: Shot) -> ShotOutputs:
    return ShotOutputs(os.path.join(os.path.abspath(out_dir), shot.name), shot.name)


def expected_files(shot: Shot, outs: ShotOutputs, *, review: bool = True, exports=()) -> list[str]:
    """The files a successful run of ``shot`` leaves."""
    files = [outs.blend, outs.result]
    if review:
        files.append(outs.review)
    if shot.kind == VIDEO:
        files.append(outs.tracks)
    return files + [outs.export(ext) for ext in exports]


def write_status(outs: ShotOutputs, record: dict) -> None:
    write_atomic(outs.status, json.dumps({"format": STATUS_FORMAT, **record}, indent=1), what="shot status")


def read_status(outs: ShotOutputs) -> dict | None:
    """The shot's last status record, or None when it has none (never run, or unreadable)."""
    try:
        with open(outs.status, encoding="utf-8") as fh:
            doc = json.load(fh)
    except (OSError, ValueError):
        return None
    return doc if isinstance(doc, dict) and doc.get("format") == STATUS_FORMAT else None


def _mtime(path: str) -> float | None:
    try:
        return os.stat(path).st_mtime
    except OSError:
        return None


def up_to_date(shot: Shot, outs: ShotOutputs, args: list[str], expected: list[str]) -> bool:
    """True when the last run of ``shot`` succeeded with ``args`` and its outputs are newer than its inputs."""
    status = read_status(outs)
    if not status or status.get("status") != OK or status.get("args") != list(args):
        return False
    made = [_mtime(p) for p in expected]
    used = [_mtime(p) for p in shot.input_files()]
    if any(t is None for t in made) or any(t is None for t in used):
        return False
    return min(made) >= max(used, default=0.0)
