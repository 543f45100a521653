"""Run an estimator in a background thread, with progress and cancel, without touching bpy.

Blender's data may only be touched from the main thread, so the worker gets plain
core objects (``Tracks``) and hands back a plain ``Estimate``; the modal operator
polls :meth:`EstimateJob.snapshot` from a timer on the main thread and stores the
result there.  Everything here is ordinary Python, so it is tested without a window.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass

from ..core.errors import Cancelled


@dataclass
class JobState:
    fraction: float = 0.0
    message: str = "Starting"
    done: bool = False
    cancelled: bool = False
    result: object = None
    error: BaseException | None = None


class EstimateJob:
    """One estimate run.  ``run`` is any callable ``run(progress=..., should_cancel=...) -> Estimate``."""

    def __init__(self, run):
        self._run = run
        self._lock = threading.Lock()
        self._cancel = threading.Event()
        self._state = JobState()
        self._thread = threading.Thread(target=self._main, name="monoskel-estimate", daemon=True)

    # --- called from the worker thread ---
    def _progress(self, fraction, message="") -> None:
        with self._lock:
            self._state.fraction = min(1.0, max(self._state.fraction, float(fraction)))
            if message:
                self._state.message = str(message)

    def _main(self) -> None:
        try:
            result = self._run(progress=self._progress, should_cancel=self._cancel.is_set)
        except Cancelled:
            with self._lock:
                self._state.cancelled = True
                self._state.message = "Cancelled"
        except BaseException as exc:  # noqa: BLE001 - handed to the main thread and reported there
            with self._lock:
                self._state.error = exc
        else:
            with self._lock:
                if self._cancel.is_set():  # cancelled after the last check: the result is not wanted
                    self._state.cancelled = True
                    self._state.message = "Cancelled"
                else:
                    self._state.result = result
                    self._state.fraction = 1.0
        finally:
            with self._lock:
                self._state.done = True

    # --- called from the main thread ---
    def start(self) -> EstimateJob:
        self._thread.start()
        return self

    def cancel(self) -> None:
        self._cancel.set()

    @property
    def cancel_requested(self) -> bool:
        return self._cancel.is_set()

    def snapshot(self) -> JobState:
        """A copy of the state, safe to read while the worker runs."""
        with self._lock:
            s = self._state
            return JobState(s.fraction, s.message, s.done, s.cancelled, s.result, s.error)

    def wait(self, timeout: float | None = None) -> JobState:
        self._thread.join(timeout)
        return self.snapshot()


#: The job the modal operator is running (one at a time per Blender process), for the Cancel button.
_current: EstimateJob | None = None


def current() -> EstimateJob | None:
    return _current


def set_current(job: EstimateJob | None) -> None:
    global _current
    _current = job
