"""Devices whose types bring their handlers from the model's folder, in
local execution (docs/local.md, "Devices"): local execution runs on the
host, so a device runs its type's host handlers (``impl host "file.c"``),
compiled into a plug-in like an actor's code, with the same rules as on
the host board: before its ``read()`` every ``out`` datum takes the
stimulus value due at the instant (or its initial value), and the handler
computes from there. A device without host handlers is simulated
(stimulus in, nothing out), as on the host board.

A device plug-in is the firmware's rendering of the device's handlers
(easylab.board.handlers.device_block) with its data and state reached
through pointers, behind a fixed ABI:

.. code-block:: c

    uint32_t el_device_abi_version(void);   /* DEVICE_ABI_VERSION */
    size_t   el_device_state_size(void);    /* bytes of the device's state */
    void     el_device_call(uint8_t handler, void *state, void *const *data);

``handler`` is 0..5 for open, start, read, write, stop, close; ``data[i]``
points at the i-th datum of the device (port order) in its C type.
"""

from __future__ import annotations

import ctypes
import dataclasses
from dataclasses import dataclass

from ..board import handlers as H
from ..core.errors import BuildError
from ..ir.program import Device, Program
from . import values as V
from .plugins import RUNTIME_HEADERS, PluginCache, PluginError

DEVICE_ABI_VERSION = 1
BOARD = "host"  # local execution runs on the host: its handlers are the host board's
_HANDLER = {name: index for index, name in enumerate(H.HANDLERS)}


def plugin_source(program: Program, device: Device) -> str:
    """The C source of the plug-in of one device's host handlers. Its
    location keeps only the file: the source, hence its digest and its
    identity across live replacements, depends on what the code is, not on
    the line the device is declared at."""
    device = dataclasses.replace(device, location=device.location.rsplit(":", 1)[0])
    code = H.read_handlers(H.handler_file(device, BOARD))
    items = [program.items[i] for i in device.items]
    slot = {item.id: k for k, item in enumerate(items)}

    def datum(item) -> str:
        ctype = item.type.c_name
        if item.port in device.array_ports or item.count > 1:
            return f"(({ctype} *)el_data[{slot[item.id]}])"
        return f"*({ctype} *)el_data[{slot[item.id]}]"

    state_type = f"el_mdev{device.id}_state_t"
    binding = H.Binding(datum, f"*({state_type} *)el_state")
    calls = "\n".join(f"    case {k}u: {H.function_name(device, h)}(); break;" for h, k in _HANDLER.items())
    return H.resolve_lines("\n".join([
        f"/* EasyLab device plug-in: {device.path} ({device.type_name}), its host handlers for local execution",
        " * (docs/local.md). Generated from the same rendering as firmware; do not edit. */",
        *(f'#include "{h}"' for h in RUNTIME_HEADERS), "#include <stddef.h>", "",
        "static void *el_state;", "static void *const *el_data;", "",
        *H.prelude_block(code), "",
        *H.device_block(program, device, code, binding, firmware=False), "",
        f"/* ---- EasyLab device plug-in ABI {DEVICE_ABI_VERSION} (docs/local.md) ---- */",
        '#define EL_PLUGIN_EXPORT __attribute__((visibility("default")))',
        "EL_PLUGIN_EXPORT uint32_t el_device_abi_version(void);",
        "EL_PLUGIN_EXPORT size_t el_device_state_size(void);",
        "EL_PLUGIN_EXPORT void el_device_call(uint8_t handler, void *state, void *const *data);",
        f"uint32_t el_device_abi_version(void) {{ return {DEVICE_ABI_VERSION}u; }}",
        f"size_t el_device_state_size(void) {{ return sizeof({state_type}); }}",
        "void el_device_call(uint8_t handler, void *state, void *const *data)", "{",
        "    el_state = state;", "    el_data = data;", "    switch (handler) {", calls,
        "    default: break;", "    }", "}", ""]), f"plug-in of device {device.path} (generated)")


@dataclass
class DevicePlugin:
    """A loaded device plug-in."""

    digest: str
    state_size: int
    call: ctypes._CFuncPtr
    library: ctypes.CDLL


def load_plugin(cache: PluginCache, program: Program, device: Device) -> DevicePlugin:
    """The plug-in of a device's host handlers, built if the cache lacks it."""
    what = f"device '{device.path}' ({device.type_name}, {device.location})"
    try:
        source = plugin_source(program, device)
    except BuildError as err:  # an unreadable or malformed handler file
        raise PluginError(f"{what}: {err}") from None
    digest = cache.digest(source)

    def open_library(path) -> DevicePlugin:
        try:
            lib = ctypes.CDLL(str(path))
            version, size, call = lib.el_device_abi_version, lib.el_device_state_size, lib.el_device_call
        except (OSError, AttributeError) as err:
            raise PluginError(f"{what}: cannot load its plug-in {path}: {err}") from None
        version.restype = ctypes.c_uint32
        size.restype = ctypes.c_size_t
        call.restype = None
        call.argtypes = [ctypes.c_uint8, ctypes.c_void_p, ctypes.c_void_p]
        if version() != DEVICE_ABI_VERSION:
            raise PluginError(f"{what}: plug-in {path} has ABI {version()}, expected {DEVICE_ABI_VERSION}")
        return DevicePlugin(digest, size(), call, lib)
    return cache.load_library(what, source, open_library)


class ModelDevice:
    """One device running its host handlers: its plug-in, its state and the
    C cells its data go through at each call."""

    def __init__(self, program: Program, device: Device, plugin: DevicePlugin):
        self.device = device
        self.plugin = plugin
        self.state = (ctypes.c_uint64 * max(1, (plugin.state_size + 7) // 8))()  # zeroed, 8-byte aligned
        self.items = [program.items[i] for i in device.items]
        self.cells = [(V.ctype(it.type) * it.count)() for it in self.items]
        self.pointers = (ctypes.c_void_p * max(1, len(self.cells)))(*(ctypes.addressof(c) for c in self.cells))
        self.outs = [k for k, it in enumerate(self.items) if it.kind == "dev_out"]

    def state_fields(self) -> dict[str, ctypes.Array]:
        """Each `state` field by name, as an array (one element for a
        scalar) over the state's memory, laid out as the C struct is."""
        fields = [(name, V.ctype(t) * (size or 1)) for name, t, size in self.device.states]
        if not fields:
            return {}
        layout = type("State", (ctypes.Structure,), {"_fields_": fields}).from_address(ctypes.addressof(self.state))
        return {name: getattr(layout, name) for name, _t in fields}

    def call(self, handler: str, published: list[ctypes.Array]) -> None:
        """One handler, on the published data (C arrays of the data's
        types): in, then its out data back."""
        for cell, it in zip(self.cells, self.items):
            ctypes.memmove(cell, published[it.id], ctypes.sizeof(cell))
        self.plugin.call(_HANDLER[handler], ctypes.addressof(self.state), self.pointers)
        for k in self.outs:
            ctypes.memmove(published[self.items[k].id], self.cells[k], ctypes.sizeof(self.cells[k]))

    def sample(self, published: list[ctypes.Array], stimulus, time_us: int) -> None:
        """``el_sim_sample``: every out datum takes the stimulus value due
        now, or its initial value."""
        for k in self.outs:
            it = self.items[k]
            published[it.id][:] = [V.literal(it.type, it.initial)] * it.count
        if stimulus is not None:
            stimulus.read_device(self.device.id, time_us, published)


class ModelDevices:
    """The devices of a program that run host handlers, by device id."""

    def __init__(self, program: Program, cache: PluginCache):
        self.devices: dict[int, ModelDevice] = {}
        for dev in program.devices:
            if H.handler_file(dev, BOARD) is not None:
                self.devices[dev.id] = ModelDevice(program, dev, load_plugin(cache, program, dev))
        self.running: set[int] = set()  # opened and started

    def state_fields(self) -> dict[str, tuple]:
        """``DEVICE.FIELD`` -> (type, array over the state's memory) of every
        device's `state` fields (what ``--trace-state`` records)."""
        out = {}
        for dev in self.devices.values():
            types = {name: t for name, t, _size in dev.device.states}
            for name, array in dev.state_fields().items():
                out[f"{dev.device.path}.{name}"] = (types[name], array)
        return out

    def boot(self, published: list[ctypes.Array], only: set[int] | None = None) -> None:
        """open() of every device, then start(), as model.c does."""
        chosen = [d for i, d in self.devices.items() if only is None or i in only]
        for dev in chosen:
            dev.call("open", published)
        for dev in chosen:
            dev.call("start", published)
            self.running.add(dev.device.id)

    def shutdown(self, published: list[ctypes.Array], only: set[int] | None = None) -> None:
        """stop() of every device, then close()."""
        chosen = [d for i, d in self.devices.items() if i in self.running and (only is None or i in only)]
        for dev in chosen:
            dev.call("stop", published)
        for dev in chosen:
            dev.call("close", published)
            self.running.discard(dev.device.id)

    def read(self, device: int, published: list[ctypes.Array], stimulus, time_us: int) -> bool:
        """The device's read() if it runs host handlers (True), else False
        (a simulated device: the caller applies the stimulus)."""
        dev = self.devices.get(device)
        if dev is None:
            return False
        dev.sample(published, stimulus, time_us)
        dev.call("read", published)
        return True

    def write(self, device: int, published: list[ctypes.Array]) -> None:
        dev = self.devices.get(device)
        if dev is not None:
            dev.call("write", published)

    def take_over(self, old: "ModelDevices", old_published: list[ctypes.Array], published: list[ctypes.Array]) -> list[str]:
        """At a live replacement: a device with the same path and plug-in
        keeps its state and goes on without open(); the old program's other
        devices stop and close (on the old program's data), the new
        program's other devices open and start. Returns the paths kept."""
        kept, fresh = [], set()
        old_by_path = {d.device.path: d for i, d in old.devices.items() if i in old.running}
        for i, dev in self.devices.items():
            previous = old_by_path.pop(dev.device.path, None)
            if previous is not None and previous.plugin.digest == dev.plugin.digest:
                ctypes.memmove(dev.state, previous.state, dev.plugin.state_size)
                self.running.add(i)
                kept.append(dev.device.path)
            else:
                fresh.add(i)
        old.shutdown(old_published, {d.device.id for d in old_by_path.values()})
        self.boot(published, fresh)
        return kept
