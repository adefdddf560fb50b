"""Work that grows with an input (a path of 100 000 poses, a map of 10⁸ cells) done beside the control loop.

Source: the node's real-time contract: ``cmd_vel`` keeps its rate whatever arrives. The control loop
(the executor's thread) hands a decoding job to :class:`Background` and goes on with the last good
path or map; at each cycle it takes what is finished and applies it (an assignment).

What we chose:
* One worker thread, one pending job per kind: a newer path supersedes an older one that has not
  started (only the newest matters; a path re-sent at 1 Hz never queues up). A running job is not
  interrupted; its result is kept only if no newer job of its kind was submitted meanwhile.
* Jobs are plain callables; an exception in one is its result (the caller refuses the input and
  says why), never the end of the worker.
* The worker is a daemon thread: it never keeps the process alive.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any


@dataclass
class Outcome:
    """A finished job: its ``value``, or the ``error`` it raised."""

    value: Any = None
    error: Exception | None = None


class Background:
    def __init__(self) -> None:
        self._lock = threading.Condition()
        self._pending: dict[str, tuple[int, Callable[[], Any]]] = {}
        self._done: dict[str, tuple[int, Outcome]] = {}
        self._latest: dict[str, int] = {}
        self._running: str | None = None
        self._serial = 0
        self._closed = False
        self._thread: threading.Thread | None = None

    def submit(self, kind: str, job: Callable[[], Any]) -> None:
        """Run ``job`` in the worker; it replaces a job of the same kind not yet started."""
        with self._lock:
            self._serial += 1
            self._latest[kind] = self._serial
            self._pending[kind] = (self._serial, job)
            self._done.pop(kind, None)
            if self._thread is None:
                self._thread = threading.Thread(target=self._work, name="viapath-background", daemon=True)
                self._thread.start()
            self._lock.notify()

    def take(self, kind: str) -> Outcome | None:
        """The newest finished job of ``kind`` (once), or None while none is ready."""
        with self._lock:
            item = self._done.pop(kind, None)
        return None if item is None else item[1]

    def busy(self, kind: str) -> bool:
        with self._lock:
            return kind in self._pending or self._running == kind

    def cancel(self, kind: str) -> None:
        """Forget a job of ``kind``: pending, running (its result is dropped) or finished."""
        with self._lock:
            self._serial += 1
            self._latest[kind] = self._serial
            self._pending.pop(kind, None)
            self._done.pop(kind, None)

    def close(self) -> None:
        with self._lock:
            self._closed = True
            self._pending.clear()
            self._lock.notify()

    def _work(self) -> None:
        while True:
            with self._lock:
                while not self._pending and not self._closed:
                    self._lock.wait()
                if self._closed:
                    return
                kind = next(iter(self._pending))
                serial, job = self._pending.pop(kind)
                self._running = kind
            try:
                outcome = Outcome(value=job())
            except Exception as error:  # the job's input is refused with this; the worker goes on
                outcome = Outcome(error=error)
            with self._lock:
                self._running = None
                if self._latest.get(kind) == serial:
                    self._done[kind] = (serial, outcome)
