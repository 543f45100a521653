"""Build shots N at a time, each by its own process running the single-shot batch.

Nothing is shared between shots but the read-only inputs: each process writes only into its shot's folder
(its log, its outputs, its own TMPDIR), and the status record is written when it has ended, so a crash,
a kill or a bad file is one failed shot and the others go on.  Each finished shot is reported through
``progress`` as it ends.  The peak memory of each process is measured by the kernel (``wait4``).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import threading
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field

from .discover import Shot
from .outputs import FAILED, OK, ShotOutputs, write_status

#: Thread pools of numeric libraries (numpy's BLAS, OpenMP); each worker gets its share of the cores.
THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


@dataclass
class ShotJob:
    """One shot to build: its command line and where its files go."""

    shot: Shot
    outputs: ShotOutputs
    args: list[str]           # the single-shot batch's arguments (recorded, compared for up-to-date)
    command: list[str]        # the whole command line
    expected: list[str] = field(default_factory=list)


@dataclass
class ShotResult:
    name: str
    status: str               # OK or FAILED
    seconds: float
    exit_code: int
    error: str = ""           # one line when FAILED
    peak_rss_mb: float | None = None


def default_workers() -> int:
    """One worker per core this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:          # not Linux
        return max(1, os.cpu_count() or 1)


def _worker_env(outs: ShotOutputs, threads: int) -> dict:
    env = dict(os.environ)
    for name in ("TMPDIR", "TEMP", "TMP"):
        env[name] = outs.temp
    for name in THREAD_VARIABLES:
        env.setdefault(name, str(threads))
    return env


def error_line(log_text: str, exit_code: int) -> str:
    """The one line that says why a shot failed: the batch's own error line, else the log's last line."""
    lines = [ln.strip() for ln in log_text.splitlines() if ln.strip()]
    for ln in reversed(lines):
        if ln.startswith("batch.py: ") or ln.startswith("[monoskel] ERROR"):
            return ln
    if exit_code < 0:
        return f"killed by signal {-exit_code}"
    return lines[-1] if lines else f"exit status {exit_code} and nothing in its log"


def _wait(proc: subprocess.Popen) -> tuple[int, float | None]:
    """(exit code, peak memory in MB) of ``proc``, reaped with wait4 where there is one."""
    if hasattr(os, "wait4"):
        _, status, usage = os.wait4(proc.pid, 0)
        proc.returncode = os.waitstatus_to_exitcode(status)   # reaped here: Popen must not wait again
        return proc.returncode, usage.ru_maxrss / 1024.0      # Linux: kilobytes
    return proc.wait(), None


class ShotRunner:
    """Runs :class:`ShotJob` s with at most ``workers`` processes at once; ``cancel`` ends the running ones."""

    def __init__(self, workers: int, cwd: str | None = None):
        self.workers = max(1, int(workers))
        self.cwd = cwd
        self._running: dict[int, subprocess.Popen] = {}
        self._lock = threading.Lock()
        self._cancelled = False

    def _run_one(self, job: ShotJob) -> ShotResult:
        outs = job.outputs
        os.makedirs(outs.folder, exist_ok=True)
        shutil.rmtree(outs.temp, ignore_errors=True)
        os.makedirs(outs.temp)
        threads = max(1, default_workers() // self.workers)
        started = time.perf_counter()
        with open(outs.log, "w", encoding="utf-8") as log:
            log.write(" ".join(job.command) + "\n")
            log.flush()
            with self._lock:
                if self._cancelled:
                    return ShotResult(job.shot.name, FAILED, 0.0, -1, "cancelled")
                proc = subprocess.Popen(job.command, stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT,
                                        cwd=self.cwd, env=_worker_env(outs, threads))
                self._running[proc.pid] = proc
            try:
                code, peak = _wait(proc)
            finally:
                with self._lock:
                    self._running.pop(proc.pid, None)
        seconds = time.perf_counter() - started
        shutil.rmtree(outs.temp, ignore_errors=True)
        missing = [p for p in job.expected if not os.path.isfile(p)]
        if code == 0 and not missing:
            result = ShotResult(job.shot.name, OK, seconds, code, peak_rss_mb=peak)
        else:
            with open(outs.log, encoding="utf-8", errors="replace") as fh:
                text = fh.read()
            why = error_line(text, code) if code != 0 else f"finished but wrote no {os.path.basename(missing[0])}"
            result = ShotResult(job.shot.name, FAILED, seconds, code, why, peak)
        write_status(outs, {"shot": job.shot.name, "input": job.shot.path, "kind": job.shot.kind,
                            "status": result.status, "error": result.error, "exit_code": code,
                            "seconds": round(seconds, 2), "peak_rss_mb": None if peak is None else round(peak, 1),
                            "args": job.args, "command": job.command,
                            "finished": time.strftime("%Y-%m-%d %H:%M:%S")})
        return result

    def run(self, jobs: list[ShotJob], progress=None) -> list[ShotResult]:
        """Run ``jobs``; ``progress(result, done, total)`` as each ends.  Ctrl-C ends the running shots."""
        results = []
        pool = ThreadPoolExecutor(max_workers=self.workers)
        try:
            futures = [pool.submit(self._run_one, job) for job in jobs]
            for future in as_completed(futures):
                results.append(future.result())
                if progress:
                    progress(results[-1], len(results), len(jobs))
        except BaseException:
            self.cancel()
            raise
        finally:
            pool.shutdown(wait=True, cancel_futures=True)
        return results

    def cancel(self) -> None:
        """End every shot process this runner started (each by its own id) and start no more."""
        with self._lock:
            self._cancelled = True
            running = list(self._running.values())
        for proc in running:
            try:
                proc.terminate()
            except OSError:
                pass

