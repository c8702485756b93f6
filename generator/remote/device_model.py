"""The device model: the part of the IR a remote-execution proxy is built
from (docs/remote.md), its identity and the layout of its frames.

It is computed here, once, from the IR: the devices with their data, the
LET tick and the instants at which the tasks that use device data are
released (devices read) and publish (device `in` data written). The proxy
firmware is generated from it (as an IR ``Program`` of its own,
:func:`proxy_program`), and the host side of ``easylab remote`` frames its
device data with the same layouts, so the two cannot disagree.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field, replace

from ..core import types as T
from ..ir.program import Device, Instant, Item, Program, Task, to_json
from ..ir.status import device_tasks
from .protocol import K, wire_bytes


# The proxy applies the safe values after this many consecutive overruns, and
# when no valid frame came for twice the longest gap between two release
# instants, but never sooner than WATCHDOG_MIN_US (docs/remote.md); a model
# may set either (`remote watchdog T overruns K`).
OVERRUN_LIMIT = 3
WATCHDOG_MIN_US = 100_000


def longest_gap(hyperperiod: int, release_ticks: list[int]) -> int:
    """The longest time in ticks between two release instants (frames come
    at each), cyclically over the hyperperiod."""
    ticks = sorted(set(release_ticks))
    gaps = [b - a for a, b in zip(ticks, ticks[1:])] + ([ticks[0] + hyperperiod - ticks[-1]] if ticks else [])
    return max(gaps, default=hyperperiod)


def watchdog_ticks(tick_us: int, hyperperiod: int, release_ticks: list[int], declared_us: int | None = None) -> int:
    """The proxy's watchdog time in ticks: the model's (rounded up to whole
    ticks), else twice the longest gap between two release instants, at
    least WATCHDOG_MIN_US."""
    if declared_us is not None:
        return -(-declared_us // tick_us)
    return max(2 * longest_gap(hyperperiod, release_ticks), -(-WATCHDOG_MIN_US // tick_us))


def value_size(t: T.ValueType) -> int:
    """Bytes of one value on the link (the C type's size; bool is 1 byte)."""
    return max(1, t.bits // 8)


def item_bytes(item: Item) -> int:
    return value_size(item.type) * item.count


@dataclass(frozen=True)
class FrameSizes:
    """The largest decoded frame (header, payload, CRC) a proxy receives
    (``rx``) and sends (``tx``): its buffers' sizes, at most MAX_FRAME."""

    rx: int
    tx: int

    @property
    def rx_wire(self) -> int:
        """Bytes of the largest received frame on the wire (COBS, delimiter)."""
        return wire_bytes(self.rx - K.HEADER - K.TRAILER)

    @property
    def tx_wire(self) -> int:
        """Bytes of the largest sent frame on the wire (COBS, delimiter)."""
        return wire_bytes(self.tx - K.HEADER - K.TRAILER)


@dataclass
class ProxyTask:
    """A task that uses device data, as the proxy sees it: its timing, the
    devices read at its release and the device `in` data it publishes at
    its deadline (item ids of the application's IR, in id order)."""

    task: int  # id in the application's IR
    period: int
    offset: int
    deadline: int
    reads: list[int]  # device ids
    writes: list[int]  # item ids (dev_in)


@dataclass
class DeviceModel:
    """The device part of a program. Proxy task ``k`` is ``tasks[k]``;
    ``instants`` carry proxy task ids."""

    name: str
    tick_us: int
    hyperperiod: int
    devices: list[Device]
    items: list[Item]  # every device datum, in the application's item order
    tasks: list[ProxyTask]
    instants: list[Instant]
    watchdog_ticks: int = 0  # no valid frame for this long: the safe values
    overrun_limit: int = OVERRUN_LIMIT  # this many overruns in a row: the safe values
    device_ids: list[int] = field(default_factory=list)  # per device: a 32-bit hash of its description
    id: int = 0

    def proxy_task_of(self, task: int) -> int | None:
        return next((k for k, t in enumerate(self.tasks) if t.task == task), None)

    def up_items(self, released: list[int]) -> list[int]:
        """Item ids of an UP frame's payload when the proxy tasks
        ``released`` are released: the `out` data of every device one of
        them reads (device order, port order), as the proxy reads them."""
        read = {d for k in released for d in self.tasks[k].reads}
        return [i for d in self.devices if d.id in read for i in d.items if self.item_kind(i) == "dev_out"]

    def down_items(self, released: list[int]) -> list[tuple[int, list[int]]]:
        """(proxy task, item ids) of a DOWN frame's payload for the proxy
        tasks ``released``: each one's written device data, task order."""
        return [(k, self.tasks[k].writes) for k in sorted(released) if self.tasks[k].writes]

    def up_payload(self, released: list[int]) -> int:
        """Bytes of the UP payload when the proxy tasks ``released`` are
        released: the state byte and the device data read."""
        return K.UP_STATE + self.frame_bytes(self.up_items(released))

    def down_payload(self, released: list[int]) -> int:
        """Bytes of the DOWN payload for the proxy tasks ``released``: the
        task mask and the device data they publish."""
        return K.DOWN_MASK + sum(self.frame_bytes(items) for _, items in self.down_items(released))

    def frame_sizes(self) -> FrameSizes:
        """The proxy's buffer sizes: the largest decoded frame each way
        (docs/remote.md, "Frames"), from the fixed frames of the protocol
        and the largest UP and DOWN of this device model. A DEVICE answer's
        path is cut at MAX_PAYLOAD, as the proxy cuts it."""
        released = [i.release for i in self.instants if i.release]
        path = max((len(d.path.encode()) for d in self.devices), default=0)
        down = max((self.down_payload(r) for r in released), default=K.DOWN_MASK)
        up = max((self.up_payload(r) for r in released), default=K.UP_STATE)
        received = max(1, down)  # DEVICE and START carry one byte, HELLO, STOP and COUNTERS none
        counters = 1 + 2 * (K.COUNTER_COUNT + max(1, len(self.tasks)))  # the link's, then each task's overruns
        sent = max(K.HELLO_ANSWER, min(K.MAX_PAYLOAD, K.DEVICE_ANSWER + path), counters, up)
        return FrameSizes(K.HEADER + received + K.TRAILER, K.HEADER + sent + K.TRAILER)

    def release_ticks(self) -> list[int]:
        """The ticks of the instants at which a proxy task is released (an
        UP and a DOWN frame each)."""
        return [i.tick for i in self.instants if i.release]

    def item_kind(self, item_id: int) -> str:
        return self._by_id[item_id].kind

    def item(self, item_id: int) -> Item:
        return self._by_id[item_id]

    def frame_bytes(self, item_ids: list[int]) -> int:
        return sum(item_bytes(self._by_id[i]) for i in item_ids)

    def __post_init__(self) -> None:
        self._by_id = {i.id: i for i in self.items}


def _device_json(program: Program, device: Device) -> dict:
    dump = to_json(device)
    for key in ("id", "location", "read_by", "written_by", "claims"):
        dump.pop(key, None)
    dump["claims"] = sorted(device.claims)
    dump["items"] = [{"name": program.items[i].name, "kind": program.items[i].kind,
                      "type": program.items[i].type.name, "count": program.items[i].count,
                      "safe": safe_value(program.items[i])} for i in device.items]
    return dump


def safe_value(item: Item):
    """The value the proxy applies to a device `in` datum when the host is
    not driving it (boot, stop, watchdog, repeated overruns): the model's
    `safe` value, zero or false by default, which is also the datum's
    initial value in the IR (docs/remote.md, "Safe values")."""
    return item.initial


def _hash32(dump) -> int:
    return int.from_bytes(hashlib.sha256(json.dumps(dump, sort_keys=True).encode()).digest()[:4], "big")


def device_model(program: Program) -> DeviceModel:
    """The device model of ``program``: the one place it is decided."""
    device_items = [i for i in program.items if i.kind in ("dev_out", "dev_in")]
    tasks = [ProxyTask(task.id, task.period, task.offset, task.deadline, reads, writes)
             for task, reads, writes in device_tasks(program)]
    proxy_of = {t.task: k for k, t in enumerate(tasks)}
    instants = []
    for instant in program.instants:
        publish = [proxy_of[t] for t in instant.publish if t in proxy_of]
        release = [proxy_of[t] for t in instant.release if t in proxy_of]
        if publish or release:
            instants.append(Instant(instant.tick, publish, release))
    model = DeviceModel(program.name, program.tick_us, program.hyperperiod, list(program.devices), device_items,
                        tasks, instants)
    settings = program.remote
    model.watchdog_ticks = watchdog_ticks(program.tick_us, program.hyperperiod, model.release_ticks(),
                                          settings.watchdog_us if settings else None)
    if settings and settings.overrun_limit is not None:
        model.overrun_limit = settings.overrun_limit
    model.device_ids = [_hash32(_device_json(program, d)) for d in program.devices]
    model.id = _hash32({
        "version": K.PROTOCOL_VERSION, "tick_us": program.tick_us, "hyperperiod": program.hyperperiod,
        "watchdog_ticks": model.watchdog_ticks, "overrun_limit": model.overrun_limit,
        "devices": [_device_json(program, d) for d in program.devices],
        "tasks": [{"period": t.period, "offset": t.offset, "deadline": t.deadline, "reads": t.reads,
                   "writes": [program.items[i].name for i in t.writes]} for t in tasks],
        "instants": [[i.tick, i.publish, i.release] for i in instants],
    })
    return model


def watchdog_problem(program: Program, model: DeviceModel | None = None) -> str | None:
    """What is wrong with the watchdog time the model declares (``remote
    watchdog T``; its place is ``program.remote.watchdog_location``), or
    None: it must be longer than the longest gap between two release
    instants (frames come only at those, so a shorter one would apply the
    safe values in a run that keeps up) and at most 2^32 - 1 ticks. The one
    rule of `easylab check` and `easylab proxy`."""
    settings = program.remote
    if settings is None or settings.watchdog_us is None:
        return None
    model = model or device_model(program)
    gap = longest_gap(model.hyperperiod, model.release_ticks())
    if model.watchdog_ticks <= gap:
        return (f"the watchdog time ({_ms(settings.watchdog_us)}) must be longer than the longest time between two "
                f"frames of the device model ({_ms(gap * model.tick_us)})")
    if model.watchdog_ticks > 0xFFFFFFFF:
        return f"the watchdog time ({_ms(settings.watchdog_us)}) is more than 2^32 - 1 ticks of {model.tick_us} us"
    return None


def _ms(us: int) -> str:
    return f"{us / 1000:g} ms"


def proxy_program(program: Program, model: DeviceModel | None = None) -> Program:
    """The proxy as an IR program of its own: the device data as its items
    (renumbered), the devices, the proxy tasks (no bodies; reading their
    devices and writing their device data) and the device model's
    instants; its program id is the device-model id. The board contract
    checks, and compiles, it as it does any program."""
    model = model or device_model(program)
    new_id = {item.id: k for k, item in enumerate(model.items)}
    items = [Item(new_id[i.id], i.name, i.kind, i.type, i.count, safe_value(i) if i.kind == "dev_in" else i.initial,
                  i.location, device=i.device, port=i.port) for i in model.items]
    for task_k, task in enumerate(model.tasks):
        for i in task.writes:
            items[new_id[i]].writer_task = task_k
    # Everything else of a device (its parameters, handler files, state) is the application's.
    devices = [replace(d, items=[new_id[i] for i in d.items], read_by=[model.proxy_task_of(t) for t in d.read_by],
                       written_by=model.proxy_task_of(d.written_by) if d.written_by is not None else None)
               for d in model.devices]
    tasks = []
    for k, t in enumerate(model.tasks):
        app = program.tasks[t.task]
        reads = [new_id[i] for d in t.reads for i in program.devices[d].items if program.items[i].kind == "dev_out"]
        tasks.append(Task(k, app.name, t.period, t.offset, t.deadline, None, [], reads,
                          [new_id[i] for i in t.writes], [], [], app.location))
    return Program(f"{program.name}_proxy", program.title, program.source, model.id, model.tick_us,
                   model.hyperperiod, items, devices, [], [], [], [], [], tasks, list(model.instants), [])
