"""Requests of a web page for the one thread that owns a link (the service
panel's device session, the online page's debug target): queued with a
bound, each answered through a future, and all failed at once when the
link is lost, so that no page waits on a dead device."""

from __future__ import annotations

import concurrent.futures
import queue
import threading
import time
from typing import Callable

CONNECTING, CONNECTED, LOST = "connecting", "connected", "lost"


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


class LinkOwner:
    """What the thread that owns a page's link shares with the page's
    server: the link's state (CONNECTING, CONNECTED, LOST or the owner's
    own) with its message and since when, the jobs waiting for it, and the
    event that stops it. ``what`` names the other end (the device, the
    target), ``where`` its address; ``log`` gets each new message."""

    def __init__(self, what: str, where: str, queue_size: int, log: Callable[[str], None] | None,
                 thread_name: str):
        self.connects = 0
        self._log = log or (lambda line: None)
        self._jobs = JobQueue(queue_size, what)
        self._lock = threading.Lock()
        self._state, self._message, self._since = CONNECTING, f"connecting to {where}", time.time()
        self._stopping = threading.Event()
        self._thread = threading.Thread(target=self._run, name=thread_name, daemon=True)

    def start(self) -> None:
        self._thread.start()

    def submit(self, job: Callable) -> concurrent.futures.Future:
        """Queue ``job`` for the link's thread; Busy when the queue is full,
        NotConnected when the other end is away (nothing is queued for it)."""
        with self._lock:
            if self._state != CONNECTED:
                raise NotConnected(self._message)
        return self._jobs.put(job)

    def _run(self) -> None:
        raise NotImplementedError

    def _set_state(self, state: str, message: str) -> None:
        with self._lock:
            changed = (state, message) != (self._state, self._message)
            if state != self._state:
                self._since = time.time()
            self._state, self._message = state, message
        if changed:
            self._log(message)
