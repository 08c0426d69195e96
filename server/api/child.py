"""Work with a time limit: a calibration's fit is one OpenCV call that no thread can stop, so it runs in
a child process, killed when the limit passes (and a new child started for the next job)."""

from __future__ import annotations

import importlib
import multiprocessing
import threading
from collections.abc import Callable
from multiprocessing.pool import Pool
from typing import Any, TypeVar

T = TypeVar("T")


def _load(module: str) -> None:
    importlib.import_module(module)


class WorkTimedOut(Exception):
    """The job ran past the time limit and was stopped."""


class TimedChild:
    """One job at a time in one child process (spawned when first needed, kept for the next job);
    `run` blocks (call it in a worker thread) and raises `WorkTimedOut` when the job runs past `limit_s`
    (the child's start and imports not counted), the child then killed. `fn` (a module's function) and
    its arguments must pickle; so must what it returns or raises."""

    def __init__(self, limit_s: float) -> None:
        self.limit_s = limit_s
        self._lock = threading.Lock()  # one job at a time; the pool is this lock's
        self._pool: Pool | None = None

    def run(self, fn: Callable[..., T], *args: Any) -> T:
        with self._lock:
            if self._pool is None:
                # spawn: a fresh interpreter, never a fork of a process with threads and OpenCV's pool
                self._pool = multiprocessing.get_context("spawn").Pool(1)
                # the child's imports (seconds on a busy machine) before the clock starts: the limit is the job's
                self._pool.apply(_load, (fn.__module__,))
            pending = self._pool.apply_async(fn, args)
            try:
                return pending.get(self.limit_s)
            except multiprocessing.TimeoutError:
                self._pool.terminate()  # kills the child, stopping the job
                self._pool.join()
                self._pool = None
                raise WorkTimedOut(f"stopped after {self.limit_s:g} s") from None

    def close(self) -> None:
        with self._lock:
            if self._pool is not None:
                self._pool.terminate()
                self._pool.join()
                self._pool = None
