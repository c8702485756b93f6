"""The device side of the service panel: one thread owns the Modbus link.

It samples every item of the map once per period into a bounded history,
runs the panel's writes, backups and restores between samples, and when
the device stops answering closes the link and opens it again (checking
the device's program each time) until it is back. The web server never
talks Modbus itself: it reads the history, or hands a job to this thread
through a small bounded queue and waits for it with a time limit, so a
dead device or a burst of requests never blocks it or piles up traffic.
"""

from __future__ import annotations

import concurrent.futures
import math
import queue
import time
from collections import deque
from dataclasses import dataclass
from typing import Callable

from ..link_jobs import CONNECTED, CONNECTING, LOST, LinkOwner, NotConnected
from ..modbus_link import DeviceException, LinkError, LinkStats, ModbusLink
from ..service_cli import DeviceAddress, read_values
from ..service_map import ServiceMap



@dataclass(frozen=True)
class Sample:
    seq: int
    time: float  # seconds since the epoch
    values: list  # one per map item, in map order
    gap: bool = False  # the first sample of a connection: the device was away before it

    def as_json(self) -> dict:
        doc = {"seq": self.seq, "t": round(self.time, 3), "v": [json_value(v) for v in self.values]}
        return {**doc, "gap": True} if self.gap else doc


def json_value(value):
    """A value for JSON: non-finite float32 values as text ("NaN", ...)."""
    if isinstance(value, float) and not math.isfinite(value):
        return "NaN" if math.isnan(value) else ("Infinity" if value > 0 else "-Infinity")
    return value


class DeviceSession(LinkOwner):
    """The link to one device, sampled every `period` seconds.

    Jobs are functions of the open :class:`ModbusLink`; :meth:`submit` queues
    one (at most `queue_size` wait) and returns a future of its result.
    """

    def __init__(self, smap: ServiceMap, address: DeviceAddress, period: float, *, retry: float = 1.0,
                 queue_size: int = 4, history: int = 1200, log: Callable[[str], None] | None = None):
        super().__init__("the device", address.where, queue_size, log, "easylab-device")
        self.smap = smap
        self.address = address
        self.period = period
        self.retry = retry
        self.stats = LinkStats()
        self._history: deque[Sample] = deque(maxlen=history)
        self._seq = 0
        self._link: ModbusLink | None = None
        self._connected_message = ""
        self._gap = False  # the next sample follows an outage

    # ------------------------------------------------------------ the server's side

    def stop(self) -> None:
        self._stopping.set()
        self._thread.join(timeout=self.address.timeout * 4 + self.period + 1)

    def link_state(self) -> dict:
        """The link's state for the page: connected or not, why, and counts."""
        with self._lock:
            return {"state": self._state, "message": self._message, "since": round(self._since, 3),
                    "where": self.address.where, "connects": self.connects, "stats": self.stats.as_dict(),
                    "waiting": self._jobs.waiting(), "period": self.period}

    def last_seq(self) -> int:
        """The newest sample's number: a write done now shows from the next."""
        with self._lock:
            return self._seq

    def samples_after(self, seq: int) -> list[Sample]:
        """The samples in the history newer than `seq`."""
        with self._lock:
            return [s for s in self._history if s.seq > seq]

    # ------------------------------------------------------------ the device thread

    def _run(self) -> None:
        next_sample = time.monotonic()
        while not self._stopping.is_set():
            if self._link is None:
                if not self._connect():
                    self._stopping.wait(self.retry)
                    continue
                next_sample = time.monotonic()
            now = time.monotonic()
            if now >= next_sample:
                self._sample()
                # No catching up after a slow read: the next sample is a period away.
                next_sample = max(next_sample + self.period, time.monotonic())
                continue
            try:
                future, job = self._jobs.get(next_sample - now)
            except queue.Empty:
                continue
            self._execute(future, job)
        if self._link is not None:
            self._link.close()
        self._jobs.fail_all(NotConnected("the panel is stopping"))

    def _connect(self) -> bool:
        try:
            self._link = self.address.connect(self.stats)
        except LinkError as err:
            self._set_state(LOST if self.connects else CONNECTING, f"{err}; trying again")
            return False
        self.connects += 1
        self._gap = True
        again = " again" if self.connects > 1 else ""
        self._connected_message = f"connected{again} to {self.address.where} (model {self.smap.model})"
        self._set_state(CONNECTED, self._connected_message)
        return True

    def _lose(self, err: LinkError) -> None:
        if self._link is not None:
            self._link.close()
        self._link = None
        self._set_state(LOST, f"{err}; reconnecting")
        self._jobs.fail_all(NotConnected(str(err)))

    def _sample(self) -> None:
        try:
            values = read_values(self._link, self.smap.items)
        except DeviceException as err:
            self._set_state(CONNECTED, f"the device refused a read: {err}")
            return
        except LinkError as err:
            self._lose(err)
            return
        self._set_state(CONNECTED, self._connected_message)  # after a refused read, if one came
        with self._lock:
            self._seq += 1
            self._history.append(Sample(self._seq, time.time(), [values[it.name] for it in self.smap.items],
                                        self._gap))
            self._gap = False

    def _execute(self, future: concurrent.futures.Future, job) -> None:
        if not future.set_running_or_notify_cancel():
            return  # the server stopped waiting for it
        try:
            result = job(self._link)
        except LinkError as err:
            future.set_exception(err)
            if not isinstance(err, DeviceException):
                self._lose(err)
        except Exception as err:  # a job's own error goes to its waiter, the thread goes on
            future.set_exception(err)
        else:
            future.set_result(result)
