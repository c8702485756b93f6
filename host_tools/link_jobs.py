"""Requests of a web page for the one thread that owns a link (the service
panel's device session, the online page's debug target): queued with a
bound, each answered through a future, and all failed at once when the
link is lost, so that no page waits on a dead device."""

from __future__ import annotations

import concurrent.futures
import queue
from typing import Callable


class Busy(Exception):
    """Too many requests are already waiting for the link."""


class NotConnected(Exception):
    """The link is not connected now (the message says why)."""


class JobQueue:
    """At most ``size`` jobs waiting for ``what`` (the device, the target)."""

    def __init__(self, size: int, what: str):
        self._jobs: queue.Queue = queue.Queue(maxsize=size)
        self.what = what

    def put(self, job: Callable) -> concurrent.futures.Future:
        """Queue ``job``: its future; Busy when the queue is full."""
        future: concurrent.futures.Future = concurrent.futures.Future()
        try:
            self._jobs.put_nowait((future, job))
        except queue.Full:
            raise Busy(f"{self._jobs.maxsize} requests are already waiting for {self.what}") from None
        return future

    def get(self, timeout: float | None = None) -> tuple[concurrent.futures.Future, Callable]:
        """The next job (queue.Empty when none comes within ``timeout``;
        none waited for at all when it is 0)."""
        if timeout == 0:
            return self._jobs.get_nowait()
        return self._jobs.get(timeout=timeout)

    def waiting(self) -> int:
        """How many jobs wait."""
        return self._jobs.qsize()

    def fail_all(self, err: Exception) -> None:
        """Fail every waiting job with ``err`` (the link is lost)."""
        while True:
            try:
                future, _ = self._jobs.get_nowait()
            except queue.Empty:
                return
            if future.set_running_or_notify_cancel():
                future.set_exception(err)
