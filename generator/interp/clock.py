"""The clocks of a run: real time, paced virtual time, flat out."""

from __future__ import annotations

import time
from typing import Callable




# ====================================================================== clocks


class Clock:
    """Virtual time (``pace`` None: instants follow each other at once) or
    paced real time: logical time runs ``pace`` times as fast as
    ``time.monotonic`` (1 = real time), anchored at the first instant.
    ``stop()`` (e.g. from a signal handler) ends waiting."""

    def __init__(self, pace: float | None = None):
        self.pace = pace
        self.stopped = False
        self._start: float | None = None
        self._first_us = 0

    def stop(self) -> None:
        self.stopped = True

    def wait_until(self, time_us: int, idle: Callable[[float], None] | None = None) -> bool:
        """Wait for logical time ``time_us``; False when stopped. ``idle(s)``
        waits at most s seconds (serving the interfaces' links)."""
        if self.pace is None:
            return not self.stopped
        while not self.stopped:
            left = self.remaining_s(time_us)
            if left <= 0:
                break
            (idle or time.sleep)(min(left, 0.05))
        return not self.stopped

    def remaining_s(self, time_us: int) -> float:
        """Real seconds until logical time ``time_us`` is due (the first
        time asked for is due at once: it anchors the clock)."""
        if self._start is None:
            self._start, self._first_us = time.monotonic(), time_us
        return self._start + (time_us - self._first_us) / 1e6 / self.pace - time.monotonic()

    def resync(self, time_us: int) -> None:
        """Logical time ``time_us`` is due now: after a halt, real time
        resumes from here instead of catching up."""
        if self.pace is not None:
            self._start, self._first_us = time.monotonic(), time_us

    def late_us(self, time_us: int) -> int:
        """How far (logical µs) real time is past ``time_us``."""
        if self.pace is None or self._start is None:
            return 0
        return int((time.monotonic() - self._start) * 1e6 * self.pace) - (time_us - self._first_us)


