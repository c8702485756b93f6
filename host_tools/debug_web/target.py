"""The target side of the online mode: one thread owns the debug link.

It refreshes the items the page shows (and only those) as one snapshot
per refresh, runs the page's commands between refreshes, and when the
target stops answering closes the link and opens it again (checking the
program id against the map each time) until it is back. The web server
never speaks the debug protocol itself: it reads the snapshots, or hands
a job to this thread through a small bounded queue and waits for it with
a time limit, so a dead target or a burst of requests never blocks it.

A snapshot is read the way the protocol makes it consistent
(docs/protocol.md, "Transactions"; docs/online.md, "Polling"):

- halted: plain reads (nothing runs between them);
- running, when the items fit in one transaction (``TX_MAX`` elements, one
  frame of values): ``TX_BEGIN``, one ``READ`` of every item, ``TX_COMMIT``,
  ``TX_RESULT`` until applied: the values of one instant;
- otherwise one ``READ`` per frame (each answered between two task
  activations), marked ``split``.

Then ``GET_FLAGS`` gives the state and the logical time; when the program
halted after the values were taken, they are read again (plain reads), so
a halted snapshot always holds the halted state. The refresh
period adapts to the link: never shorter than the time the last refresh
took (so commands always find the link free between two refreshes) nor
than ``min_period``; without a page asking for snapshots nothing is polled.
"""

from __future__ import annotations

import concurrent.futures
import queue
import threading
import time
from collections import deque
from dataclasses import asdict, dataclass, field
from typing import Callable

from ..debug_console import describe_comparison, format_value, no_slots
from ..debug_map import DebugMap, Item
from ..debug_protocol import K, DebugClient, DebugError, decode_value, type_size
from ..link_jobs import CONNECTED, CONNECTING, LOST, LinkOwner, NotConnected
from ..transport import TransportError

WRONG_PROGRAM = "wrong program"  # the link states beside link_jobs's
VIEWER_TIMEOUT = 5.0  # seconds without a page asking: polling stops
FRAME_OVERHEAD = K.HEADER + K.TRAILER + 2  # seq, cmd, CRC, the status byte, APPLIED or the tx state
TX_RESULT_APPLIED = 3  # TX_RESULT's state once the commit applied (docs/protocol.md; the header has no name for it)


def target_url(target: str) -> str:
    """The pyserial URL of a TARGET: ``tcp:HOST:PORT`` -> ``socket://HOST:PORT``;
    a device, pty or URL as it is."""
    if target.startswith("tcp:"):
        return "socket://" + target[4:]
    return target


@dataclass
class Snapshot:
    """The shown items' values at one point of the program, with its state."""

    seq: int
    tick: int
    ms: float | None
    halted: bool
    why: str
    at: str | None  # the halted element, as the console names it
    location: str | None  # its file:line
    element: str | None  # its id in the drawing
    values: dict[int, object]
    consistency: str  # "instant" (a transaction), "halted", "split" (several frames) or "none"
    wire_bytes: int
    round_trips: int
    seconds: float
    wall: float = field(default_factory=time.time)
    guards: dict[str, bool] = field(default_factory=dict)  # the transitions' guards on these values

    def as_json(self) -> dict:
        out = asdict(self)
        out["values"] = {str(k): _json_value(v) for k, v in self.values.items()}
        return out


def _json_value(v):
    if isinstance(v, list):
        return [_json_value(x) for x in v]
    if isinstance(v, float) and v != v:
        return "NaN"
    if isinstance(v, float) and v in (float("inf"), float("-inf")):
        return "Infinity" if v > 0 else "-Infinity"
    return v


def decode_items(items: list[Item], data: bytes) -> dict[int, object]:
    """The values of `items` from a READ answer's bytes (every element of
    each item, in order); an item of several elements gives a list."""
    out: dict[int, object] = {}
    at = 0
    for it in items:
        size = type_size(it.type)
        vals = [decode_value(it.type, data[at + k * size:at + (k + 1) * size]) for k in range(it.count)]
        at += size * it.count
        out[it.id] = vals if it.count > 1 else vals[0]
    return out


def fits_one_transaction(client: DebugClient, items: list[Item]) -> bool:
    """True when one transaction can read every item: its elements within
    TX_MAX, its ids and its values each within one frame."""
    hello = client.hello_info
    tx_max = hello.tx_max if hello else K.TX_MAX
    elements = sum(it.count for it in items)
    values = sum(type_size(it.type) * it.count for it in items)
    room = client.max_frame - FRAME_OVERHEAD
    return 0 < elements <= tx_max and values <= room and 2 * len(items) <= room


def read_in_transaction(client: DebugClient, items: list[Item], wait: float,
                        every: float = 0.001) -> dict[int, object] | None:
    """The items' values read at one instant by a transaction (its result
    asked every `every` seconds until applied); None when it was not applied
    within `wait` seconds (the program halted inside an activation
    meanwhile: the transaction is aborted)."""
    try:
        client.tx_begin()
    except DebugError as err:
        if err.status != K.E_TX_BUSY:
            raise
        client.tx_abort()  # left open by a client that went away
        client.tx_begin()
    client.read_raw([it.id for it in items])
    how, data = client.tx_commit()
    deadline = time.monotonic() + wait
    while how != K.APPLIED:
        state, data = client.tx_result()
        if state == TX_RESULT_APPLIED:
            break
        if time.monotonic() > deadline:
            client.tx_abort()
            return None
        time.sleep(every)
    return decode_items(items, data)


class TargetLink(LinkOwner):
    """The link to one target, its snapshots and its jobs.

    Jobs are functions of the open :class:`DebugClient`; :meth:`submit`
    queues one (at most `queue_size` wait) and returns a future of its result.
    """

    def __init__(self, dmap: DebugMap, target: str, *, elements: dict | None = None, guards=None,
                 timeout: float = 0.5,
                 retry: float = 1.0, min_period: float = 0.05, baud: int = 115200, queue_size: int = 4,
                 history: int = 4000, log: Callable[[str], None] | None = None):
        super().__init__("the target", target, queue_size, log, "easylab-debug-target")
        self.map = dmap
        self.target = target
        self.url = target_url(target)
        self.timeout = timeout
        self.retry = retry
        self.min_period = min_period
        self.baud = baud
        self.guards = guards  # GuardValues, or None
        self.element_of_point = {tuple(e["point"]): el for el, e in (elements or {}).items() if e.get("point")}
        self.status_items = [it for it in dmap.items if it.kind == "status"]
        self.period = min_period
        self.breakpoints: list[dict] = []
        self.forced: list[dict] = []
        self.slots = {"force": 0, "conditions": 0}  # HELLO's: forced elements, conditional breakpoints
        self._history: deque[Snapshot] = deque(maxlen=history)
        self._seq = 0
        self._view: list[Item] = []
        self._last_viewer = 0.0
        self._refresh_now = threading.Event()
        self._client: DebugClient | None = None

    # ------------------------------------------------------------ the server's side

    def stop(self) -> None:
        self._stopping.set()
        self._thread.join(timeout=self.timeout * 8 + self.retry + 1)

    def set_view(self, ids: list[int]) -> list[int]:
        """Poll these items from now on (unknown ids are left out); the ids kept."""
        items = [self.map.by_id[i] for i in dict.fromkeys(ids) if i in self.map.by_id]
        with self._lock:
            self._view = items
            self._last_viewer = time.monotonic()
        self._refresh_now.set()
        return [it.id for it in items]

    def snapshots_after(self, seq: int, limit: int = 500) -> list[Snapshot]:
        """The snapshots newer than `seq`, the newest `limit` of them (a page
        opened late needs no old history); a page asking keeps the polling on."""
        with self._lock:
            self._last_viewer = time.monotonic()
            return [s for s in self._history if s.seq > seq][-limit:]

    def submit(self, job: Callable[[DebugClient], object]) -> concurrent.futures.Future:
        """Queue `job` for the target (LinkOwner.submit), and refresh after it."""
        future = super().submit(job)
        self._refresh_now.set()
        return future

    def link_state(self) -> dict:
        """The link's state for the page: connected or not, why, the period."""
        with self._lock:
            return {"state": self._state, "message": self._message, "since": round(self._since, 3),
                    "where": self.target, "connects": self.connects, "period": round(self.period, 4),
                    "waiting": self._jobs.waiting(), "breakpoints": list(self.breakpoints),
                    "forced": list(self.forced), "slots": dict(self.slots), "no_slots": self.no_slots()}

    def no_slots(self) -> dict[str, str]:
        """Why the connected firmware cannot force or halt on a condition
        (HELLO reports no slots for it): the console's words, by feature."""
        with_none = {"force": ("forcing", "force"), "conditions": ("conditional breakpoints", "conditions")}
        return {key: no_slots(*words) for key, words in with_none.items() if self.slots[key] == 0}

    # ------------------------------------------------------------ the target thread

    def _run(self) -> None:
        next_refresh = time.monotonic()
        while not self._stopping.is_set():
            if self._client is None:
                if not self._connect():
                    self._stopping.wait(self.retry)
                    continue
                next_refresh = time.monotonic()
            self._run_jobs()
            if self._client is None:
                continue
            now = time.monotonic()
            with self._lock:
                watched = now - self._last_viewer < VIEWER_TIMEOUT
            if watched and now >= next_refresh:
                started = time.monotonic()
                self._refresh()
                took = time.monotonic() - started
                self.period = max(self.min_period, took)
                next_refresh = started + self.period
                continue
            self._refresh_now.wait(max(0.0, min(next_refresh - now, 0.1)) if watched else 0.1)
            if self._refresh_now.is_set():
                self._refresh_now.clear()
                next_refresh = min(next_refresh, time.monotonic())
        if self._client is not None:
            self._client.close()
        self._jobs.fail_all(NotConnected("the server is stopping"))

    def _connect(self) -> bool:
        client = None
        try:
            client = DebugClient.open(self.url, self.timeout, self.baud)
            client.retries = 1
            hello = client.hello()
        except TransportError as err:
            if client is not None:
                client.close()
            self._set_state(LOST if self.connects else CONNECTING, f"{self.target}: {err}; trying again")
            return False
        if hello.program_id != self.map.program_id:
            client.close()
            self._set_state(WRONG_PROGRAM, f"{self.target} runs program 0x{hello.program_id:08x}, not the map's "
                                           f"0x{self.map.program_id:08x} ({self.map.model}); trying again")
            return False
        self._client = client
        self.connects += 1
        with self._lock:
            self.slots = {"force": hello.force_slots, "conditions": hello.cond_slots}
        try:
            self._list_breakpoints()
            self._list_forced()
        except (TransportError, DebugError) as err:
            self._lose(err)
            return False
        again = " again" if self.connects > 1 else ""
        self._set_state(CONNECTED, f"connected{again} to {self.target} (model {self.map.model})")
        return True

    def _lose(self, err: Exception) -> None:
        if self._client is not None:
            self._client.close()
        self._client = None
        self._set_state(LOST, f"{self.target}: {err}; reconnecting")
        self._jobs.fail_all(NotConnected(str(err)))

    def _run_jobs(self) -> None:
        while self._client is not None:
            try:
                future, job = self._jobs.get(0)
            except queue.Empty:
                return
            if not future.set_running_or_notify_cancel():
                continue  # the server stopped waiting for it
            try:
                result = job(self._client)
                if getattr(job, "changes_breakpoints", False):
                    self._list_breakpoints()
                if getattr(job, "changes_forced", False):
                    self._list_forced()
            except TransportError as err:
                future.set_exception(err)
                self._lose(err)
            except Exception as err:  # a job's own error (DebugError ...) goes to its waiter
                future.set_exception(err)
            else:
                future.set_result(result)

    def _list_breakpoints(self) -> None:
        listed = []
        for b in self._client.bp_list():
            listed.append({"slot": b.slot, "point": [b.kind, b.a, b.b], "at": self.map.describe(b.kind, b.a, b.b),
                           "element": self.element_of_point.get((b.kind, b.a, b.b)), "hits": b.hits})
            if b.kind == K.P_CONDITION and b.a in self.map.by_id:  # named by its comparison, as the console does
                listed[-1].update(at=f"when {describe_comparison(self.map.by_id[b.a], b)}",
                                  location=self.map.location(b.kind, b.a, b.b))
        with self._lock:
            self.breakpoints = listed

    def _list_forced(self) -> None:
        """The forced elements (FORCE_LIST), when the firmware can force."""
        listed = []
        if self.slots["force"]:
            for f in self._client.forced():
                it = self.map.by_id.get(f.item)
                if it is None:
                    continue
                value = decode_value(it.type, f.value)
                listed.append({"item": it.id, "element": f.elem, "value": _json_value(value),
                               "name": f"{it.name}[{f.elem}]" if it.count > 1 else it.name,
                               "shown": format_value(it, value)})
        with self._lock:
            self.forced = listed

    def _refresh(self) -> None:
        with self._lock:
            items = list(self._view)
        try:
            last_halted = self._history[-1].halted if self._history else None
            snap = self.read_snapshot(self._client, items + [s for s in self.status_items if s not in items],
                                      last_halted)
        except TransportError as err:
            self._lose(err)
            return
        except DebugError as err:
            self._set_state(CONNECTED, f"the target refused a read: {err}")
            return
        previous = self._history[-1] if self._history else None
        try:
            if snap.halted and (previous is None or (previous.halted, previous.tick, previous.at)
                                != (snap.halted, snap.tick, snap.at)):
                self._list_breakpoints()  # a new halt: the breakpoints' hits changed
                self._list_forced()  # and a console may have forced or released meanwhile
        except TransportError as err:
            self._lose(err)
            return
        except DebugError:
            pass
        with self._lock:
            self._history.append(snap)
        if self._state == CONNECTED and self._message.startswith("the target refused"):
            self._set_state(CONNECTED, f"connected to {self.target} (model {self.map.model})")

    def read_snapshot(self, client: DebugClient, items: list[Item], halted: bool | None = None) -> Snapshot:
        """One snapshot of `items` (see the module's docstring for how it is
        kept consistent), numbered after the last one. `halted`: whether the
        program was halted at the last snapshot (None: not known, asked
        first); a guess proved wrong by the flags read after is corrected."""
        started = time.monotonic()
        bytes_before = client.t.bytes_in + client.t.bytes_out
        trips_before = client.round_trips
        values: dict[int, object] = {}
        consistency = "none"
        if halted is None or not items:
            halted = client.flags().halted
        if items and halted:
            values = decode_items_read(client, items)
            consistency = "halted"
        elif items and fits_one_transaction(client, items):
            wait = max(4 * self.map.tick_us / 1e6, 0.2)
            # A commit applies at the next instant: ask for its result a few times a tick, not more.
            got = read_in_transaction(client, items, wait, every=min(max(self.map.tick_us / 4e6, 0.001), 0.005))
            consistency = "instant"
            if got is None:  # halted inside an activation meanwhile: nothing runs now
                got, consistency = decode_items_read(client, items), "halted"
            values = got
        elif items:
            values, consistency = decode_items_read(client, items), "split"
        flags = client.flags()  # the state after the reads, and their logical time
        if items and flags.halted and consistency != "halted":
            # It halted after the values were taken: read them again, so a
            # halted snapshot always shows the halted state (nothing runs now).
            values, consistency = decode_items_read(client, items), "halted"
            flags = client.flags()
        if consistency == "halted" and not flags.halted:
            consistency = "split"  # it ran on meanwhile: plain reads, not one instant
        m = self.map
        loc = flags.location
        halted_at = m.describe(loc.kind, loc.a, loc.b) if flags.halted and loc.kind != K.P_NONE else None
        if flags.halted and loc.kind == K.P_CONDITION:  # `breakpoint N when NAME OP VALUE`, as the console says
            listed = next((b for b in self.breakpoints if b["slot"] == flags.breakpoint), None)
            if listed is not None:
                halted_at = f"breakpoint {flags.breakpoint} {listed['at']}"
        location = m.location(loc.kind, loc.a, loc.b) if flags.halted else None
        if flags.halted and location is None and loc.kind == K.P_INSTANT:
            released = m.released(flags.tick)
            location = released[0].get("location") if released else None
        with self._lock:
            self._seq += 1
            seq = self._seq
        return Snapshot(seq, flags.tick, float(m.ms(flags.tick)) if m.tick_us else None, flags.halted, flags.why,
                        halted_at, location, self.element_of_point.get((loc.kind, loc.a, loc.b)) if flags.halted
                        else None, values, consistency,
                        client.t.bytes_in + client.t.bytes_out - bytes_before, client.round_trips - trips_before,
                        round(time.monotonic() - started, 6),
                        guards=self.guards.evaluate(values) if self.guards is not None else {})


def decode_items_read(client: DebugClient, items: list[Item]) -> dict[int, object]:
    """The items' values by plain READs (several frames when they do not fit in one)."""
    values = client.read([(it.id, it.type, it.count) for it in items])
    return {it.id: v for it, v in zip(items, values)}


def write_job(item: Item, value, element: int = 0):
    """A job writing one element of an item (APPLIED or QUEUED)."""
    def job(client: DebugClient) -> int:
        return client.write(item.id, item.type, value, element, what=item.name)
    return job


def breakpoint_job(point: tuple[int, int, int] | None, slot: int | None):
    """A job setting a breakpoint at `point`, or clearing `slot`."""
    def job(client: DebugClient):
        if point is not None:
            return client.bp_set(*point)
        client.bp_clear(slot)
        return None
    job.changes_breakpoints = True
    return job


def force_job(item: Item, value, element: int = 0):
    """A job forcing one element of an item (APPLIED or QUEUED)."""
    def job(client: DebugClient) -> int:
        return client.force(item.id, item.type, value, element, what=item.name)
    job.changes_forced = True
    return job


def release_job(item: Item | None, element: int = 0):
    """A job releasing one forced element, or every one (`item` None)."""
    def job(client: DebugClient) -> None:
        client.release(None if item is None else item.id, element)
    job.changes_forced = True
    return job


def condition_job(item: Item, op: str, value, element: int = 0):
    """A job setting a conditional breakpoint ``item[element] OP value``; its slot."""
    def job(client: DebugClient) -> int:
        return client.bp_when(item.id, item.type, op, value, element)
    job.changes_breakpoints = True
    return job


def command_job(command: str, unit: str | None = None, program_id: int | None = None):
    """A job for run, break, step UNIT, reset (into a halt)."""
    def job(client: DebugClient):
        if command == "run":
            client.run()
        elif command == "break":
            client.halt()
        elif command == "step":
            client.step(unit or "task")
        elif command == "reset":
            client.reset(halt=True)
            hello = client.hello_again()
            if program_id is not None and hello.program_id != program_id:
                raise TransportError(f"after the reset the target runs program 0x{hello.program_id:08x}")
        return None
    job.changes_breakpoints = job.changes_forced = command == "reset"  # a restarted firmware has none
    return job

