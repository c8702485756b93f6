"""The host side of remote execution (docs/remote.md): the interpreter
(interp.Engine) runs the application; the device data it reads come from
the proxy's UP frames, and after the bodies of the tasks released at an
instant their device `in` data go back in a DOWN frame, tagged with that
instant, for the proxy to apply at their deadlines."""

from __future__ import annotations

import ctypes
import sys

from ..interp.engine import Engine
from ..interp.stimulus import Stimulus
from ..ir.program import Program
from ..ir.status import remote_program
from ..interp.plugins import PluginError
from .device_model import DeviceModel, device_model, item_bytes
from .link import Link, RemoteError
from .protocol import K

# In real time the host asks the proxy for its counters at most this often
# (logical time): a COUNTERS answer is 7 + 2 bytes per proxy task more on the link.
COUNTERS_EVERY_US = 100_000

if sys.byteorder != "little":  # device data travel in the C layout of every board, little-endian
    raise ImportError("remote execution needs a little-endian host")


class ProxyDevices:
    """Device reads from the proxy in place of the stimulus's device
    columns; params and vars still come from ``stimulus`` (if any). The
    engine asks it as it asks a Stimulus."""

    def __init__(self, model: DeviceModel, stimulus: Stimulus | None):
        self.model = model
        self.inner = stimulus
        self.payload: dict[str, bytes] = {}  # item name -> bytes read at the current instant (names survive a swap)
        # release instants within the hyperperiod: tick -> proxy tasks released
        self.releases = {i.tick: i.release for i in model.instants if i.release}

    @property
    def unbound(self) -> list[str]:
        return self.inner.unbound if self.inner is not None else []

    def bind(self, program: Program) -> None:
        """A replaced program (same device model, RemoteEngine.replace_model
        checked it): its item and task ids may differ."""
        self.model = device_model(program)
        self.releases = {i.tick: i.release for i in self.model.instants if i.release}
        if self.inner is not None:
            self.inner.bind(program)

    def released_at(self, time_us: int) -> list[int]:
        """The proxy tasks released at ``time_us`` (an UP and a DOWN frame
        then), else []."""
        tick = time_us // self.model.tick_us
        if tick * self.model.tick_us != time_us:
            return []
        return self.releases.get(tick % self.model.hyperperiod, [])

    def quiet_until(self, time_us: int) -> int | None:
        """The next time something has to come from outside: the stimulus's
        next write or the next release instant (stretches of the runner stop
        before it)."""
        tick = -(-time_us // self.model.tick_us)
        hyper = self.model.hyperperiod
        ticks = sorted(self.releases)
        nxt = None
        if ticks:
            base = tick - tick % hyper
            later = [t for t in ticks if base + t >= tick]
            nxt = (base + later[0] if later else base + hyper + ticks[0]) * self.model.tick_us
        quiet = self.inner.quiet_until(time_us) if self.inner is not None else None
        return nxt if quiet is None else quiet if nxt is None else min(nxt, quiet)

    def take(self, released: list[int], payload: bytes) -> None:
        """The UP frame of an instant: its payload split per item."""
        items = self.model.up_items(released)
        if len(payload) != self.model.frame_bytes(items):
            raise ValueError(f"an UP frame of {len(payload)} bytes where the device model has "
                             f"{self.model.frame_bytes(items)}")
        self.payload.clear()
        at = 0
        for item in items:
            size = item_bytes(self.model.item(item))
            self.payload[self.model.item(item).name] = payload[at:at + size]
            at += size

    def read_device(self, device: int, time_us: int, published: list) -> None:
        for item in self.model.devices[device].items:
            data = self.payload.get(self.model.item(item).name)
            if data is not None:
                ctypes.memmove(published[item], data, len(data))

    def apply_inputs(self, time_us: int, published: list) -> None:
        if self.inner is not None:
            self.inner.apply_inputs(time_us, published)


class RemoteEngine(Engine):
    """The interpreter with its devices on a proxy, in lock-step with it:
    at each release instant of the device model, the proxy's UP frame is
    awaited before the instant and the DOWN frame sent after its bodies."""

    command = "remote"

    def __init__(self, program: Program, model: DeviceModel, link: Link, stimulus: Stimulus | None = None,
                 up_timeout: float | None = None, **kwargs):
        self.devices = ProxyDevices(model, stimulus)
        super().__init__(program, stimulus=self.devices, **kwargs)
        self.link = link
        # In real time UP frames come at the proxy's pace: wait for the longest gap, and more.
        self.up_timeout = up_timeout or max(5.0, 2 * model.hyperperiod * model.tick_us / 1e6)
        self.frames = 0
        self.behind = 0  # UP frames the proxy built after their instant's tick (its CPU behind its clock)
        self.proxy_overruns = [0] * len(self.program.status)  # per proxy task, as the proxy last counted them
        self._asked_us: int | None = None  # logical time of the last COUNTERS request
        self._status_io = None  # the interfaces library that holds the counts

    def _prepare(self, program: Program):
        return super()._prepare(remote_program(program))

    def replace_model(self, new_program: Program) -> None:
        """Swap in an edited application; an edit of the device model is
        refused (PluginError): the proxy would have to be rebuilt."""
        old, new = self.devices.model, device_model(new_program)
        if new.id != old.id:
            ours = dict(zip((d.path for d in old.devices), old.device_ids))
            theirs = dict(zip((d.path for d in new.devices), new.device_ids))
            changed = sorted(p for p in ours.keys() | theirs.keys() if ours.get(p) != theirs.get(p))
            what = f"devices {', '.join(changed)}" if changed else "the instants at which tasks read or write devices"
            raise PluginError(f"the edit changes the device model ({what}): the proxy must be rebuilt and flashed "
                              f"(easylab proxy); the running program stays")
        super().replace_model(new_program)

    def step(self) -> None:
        t = self.next_time_us()
        released = self.devices.released_at(t)
        tick = t // self.devices.model.tick_us
        if released:
            up = self.link.up(tick, self.up_timeout)
            if up and up[0] & K.STATE_BEHIND:
                self.behind += 1
            if not up or up[0] & ~K.STATE_BEHIND != K.STATE_RUNNING:
                why = (f"the host's values came late {self.devices.model.overrun_limit} times in a row, or its "
                       "watchdog expired")
                if self.behind:  # the proxy's own CPU made them late: say so first
                    why = f"{self.behind_said()}; so {why}"
                raise RemoteError(f"{self.link.url}: at {t / 1e6:.6f} s the proxy applied its safe values ({why}); "
                                  "the run ends")
            self.devices.take(released, up[1:])
        super().step()
        model = self.devices.model  # the program's (a swap in this step rebinds it)
        if released:
            parts, mask = [], 0
            for k, items in model.down_items(released):
                local = self.state.tasks[model.tasks[k].task].local
                parts += [bytes(local[i]) for i in items]
                mask |= 1 << k
            self.link.down(tick, mask, b"".join(parts))
            self.frames += 1
            if not self.link.lock_step and (self._asked_us is None or t - self._asked_us >= COUNTERS_EVERY_US):
                self.link.ask_counters()  # in real time: the overrun counts (lock-step has none)
                self._asked_us = t
        if self.io is not None and self.io is not self._status_io:  # a program swapped in: its library starts at 0
            self._status_io = self.io
            for status, count in zip(self.program.status, self.proxy_overruns):
                self.io.set_status(status.id, count)
        if self.link.latest_counters is not None:
            self.take_counters(self.link.latest_counters, t)
            self.link.latest_counters = None

    def behind_said(self) -> str:
        """The proxy's own lateness in the words of docs/remote.md."""
        return (f"the proxy was behind its clock at {self.behind} instant{'s' if self.behind != 1 else ''} "
                "(instants processed after their time: its CPU cannot keep the device model's period; "
                "`easylab remote --board B` counts it in the link budget)")

    def take_counters(self, counters: dict, time_us: int) -> None:
        """The proxy's overrun counts into the status items
        ``remote.<task>.overruns`` (debug and service interfaces) and, when
        one grew, into the trace as a status event at ``time_us``."""
        for k, count in enumerate(counters["tasks"][:len(self.proxy_overruns)]):
            if count == self.proxy_overruns[k]:
                continue
            self.proxy_overruns[k] = count
            status = self.program.status[k]
            if self.io is not None:
                self.io.set_status(status.id, count)
            if self.trace is not None:
                self.trace.event(time_us, status.name, count)
