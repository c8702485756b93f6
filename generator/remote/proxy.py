"""The remote-execution proxy firmware (``easylab proxy``, docs/remote.md):
generated from the device model alone and built through the board
contract like any firmware."""

from __future__ import annotations

import shlex
import struct
from dataclasses import dataclass
from pathlib import Path

from ..core.errors import BuildError
from ..board.cbuild import write_files
from ..board.contract import CompileOptions
from ..board.registry import load_board
from ..board.simtables import item_symbol
from ..build import BuildResult
from ..codegen.c_syntax import C_KIND_ENUM, C_TYPE_ENUM, c_literal
from ..codegen.render import environment
from ..ir.program import Program
from .budget import DEFAULT_BAUD
from .device_model import DeviceModel, device_model, item_bytes, proxy_program, safe_value, watchdog_problem
from .protocol import K

# The flag every C file of a proxy build sees (runtime_c/el_remote.c, the
# board's link).
PROXY_CFLAGS = ("-DEL_REMOTE_PROXY=1",)


def proxy_cflags(baud: int) -> tuple[str, ...]:
    """The proxy build's flags: PROXY_CFLAGS and the link's baud rate
    (EL_REMOTE_BAUD: a board whose link is a serial port sets it up so)."""
    return PROXY_CFLAGS + (f"-DEL_REMOTE_BAUD={int(baud)}UL",)


_PACK = {"bool": "<B", "int8": "<b", "uint8": "<B", "int16": "<h", "uint16": "<H", "int32": "<i", "uint32": "<I",
         "float32": "<f", "time": "<I"}


def encode_values(type_name: str, values) -> bytes:
    """Values as they travel on the link: little-endian, in the C type's
    size (bool: one byte, 0 or 1)."""
    fmt = _PACK[type_name]
    return b"".join(struct.pack(fmt, float(v) if type_name == "float32" else int(v)) for v in values)


@dataclass
class _View:
    """What templates/proxy.c.j2 renders."""

    name: str
    id: int
    watchdog_ticks: int
    overrun_limit: int
    tick_us: int
    hyperperiod: int
    items: list
    devices: list
    out_fields: list
    in_fields: list
    safe: list
    tasks: list
    instants: list


def _mask(tasks: list[int]) -> int:
    return sum(1 << t for t in tasks)


def view(program: Program, model: DeviceModel, board) -> _View:
    """The template's view of the proxy of ``program`` for ``board``."""
    proxy = proxy_program(program, model)
    # The names the boards' device tables and simulators give items (as in any firmware).
    sym = {i.id: item_symbol(proxy, i.id) for i in proxy.items}
    items = [dict(name=i.name, sym=sym[i.id], c_type=i.type.c_name, count=i.count, kind=i.kind,
                  location=i.location, type_enum=C_TYPE_ENUM[i.type.name], kind_enum=C_KIND_ENUM[i.kind],
                  device=i.device, init=", ".join([c_literal(i.type, i.initial)] * i.count)) for i in proxy.items]
    devices = []
    for d, dev_hash in zip(proxy.devices, model.device_ids):
        has_in = any(proxy.items[i].kind == "dev_in" for i in d.items)
        devices.append(dict(path=d.path, driver=d.driver, hash=dev_hash, readers=_mask([t for t in d.read_by]),
                            read=board.device_call(d, "read"), open=board.device_call(d, "open"),
                            start=board.device_call(d, "start"), stop=board.device_call(d, "stop"),
                            close=board.device_call(d, "close"),
                            write=board.device_call(d, "write") if has_in else None))
    out_fields = [dict(sym=sym[i], size=item_bytes(proxy.items[i]), owner=d.id, name=proxy.items[i].name)
                  for d in proxy.devices for i in d.items if proxy.items[i].kind == "dev_out"]
    in_fields, safe = [], []
    for t in proxy.tasks:
        for i in t.writes:
            item = proxy.items[i]
            in_fields.append(dict(sym=sym[i], size=item_bytes(item), owner=t.id, name=item.name, task=t.name))
            safe += [f"0x{b:02x}u" for b in encode_values(item.type.name, [safe_value(item)] * item.count)]
    tasks = [dict(index=t.id, name=t.name, deadline=t.deadline,
                  write_calls=[board.device_call(proxy.devices[d], "write") for d in
                               sorted({proxy.items[i].device for i in t.writes})]) for t in proxy.tasks]
    instants = [dict(tick=i.tick, publish=_mask(i.publish), release=_mask(i.release)) for i in proxy.instants]
    if not instants:  # no task uses a device: one empty instant per hyperperiod keeps the clock
        instants = [dict(tick=0, publish=0, release=0)]
    return _View(proxy.name, model.id, model.watchdog_ticks, model.overrun_limit, model.tick_us, model.hyperperiod,
                 items, devices, out_fields, in_fields, safe, tasks, instants)


def check_frames(program: Program, model: DeviceModel) -> None:
    """Every UP and DOWN payload of the device model within MAX_PAYLOAD."""
    for instant in model.instants:
        if not instant.release:
            continue
        up, down = model.up_payload(instant.release), model.down_payload(instant.release)
        if max(up, down) > K.MAX_PAYLOAD:
            tasks = ", ".join(program.tasks[model.tasks[k].task].name for k in instant.release)
            raise BuildError(f"{program.name}: the device data of the tasks released at tick {instant.tick} "
                             f"({tasks}) take {max(up, down)} bytes in one frame, more than the link's "
                             f"{K.MAX_PAYLOAD}: release those tasks at different instants, or read fewer data")


def check_watchdog(program: Program, model: DeviceModel) -> None:
    """The watchdog time the model declares (device_model.watchdog_problem,
    the rule `easylab check` applies too); BuildError when it is wrong."""
    problem = watchdog_problem(program, model)
    if problem is not None:
        raise BuildError(f"{program.remote.watchdog_location}: {problem}")


def render_proxy(program: Program, board, model: DeviceModel | None = None) -> dict[str, str]:
    """The proxy's generated files: {file name: text}."""
    model = model or device_model(program)
    text = environment().get_template("proxy.c.j2").render(p=view(program, model, board))
    # A debug build without a debug server: the runtime's framing (el_debug_cobs.c) is compiled, no server.
    config = ("/* Generated by EasyLab: a remote-execution proxy has no debug server (docs/remote.md). */\n"
              "#ifndef EL_DEBUG_CONFIG_H\n#define EL_DEBUG_CONFIG_H\n#define EL_DEBUG_SERVER 0\n#endif\n")
    return {"proxy.c": text, "el_debug_config.h": config, "el_remote_config.h": remote_config(model)}


def remote_config(model: DeviceModel) -> str:
    """el_remote_config.h: the proxy's frame buffers sized from its device
    model (DeviceModel.frame_sizes), for runtime_c/el_remote.c and the
    board's link (its UART rings), and its count of proxy tasks."""
    sizes = model.frame_sizes()
    return "\n".join([
        f"/* Generated by EasyLab: the frame sizes of the proxy of device model 0x{model.id:08x} "
        "(docs/remote.md, \"Frames\"). Do not edit. */",
        "#ifndef EL_REMOTE_CONFIG_H", "#define EL_REMOTE_CONFIG_H",
        f"#define EL_RMT_RX_FRAME {sizes.rx}u /* the largest decoded frame the host sends */",
        f"#define EL_RMT_TX_FRAME {sizes.tx}u /* the largest decoded frame the proxy sends */",
        f"#define EL_RMT_RX_WIRE {sizes.rx_wire}u /* the same on the wire (COBS, delimiter) */",
        f"#define EL_RMT_TX_WIRE {sizes.tx_wire}u",
        "/* A board's UART rings for the link (a ring of n bytes holds n - 1): the largest frame the proxy sends",
        " * whole, two of the largest it receives (a DOWN may arrive while an instant runs). */",
        "#define EL_RMT_TX_RING (EL_RMT_TX_WIRE + 1u)",
        "#define EL_RMT_RX_RING (2u * EL_RMT_RX_WIRE + 1u)",
        f"#define EL_RMT_TASKS {max(1, len(model.tasks))}u /* proxy tasks: the runtime's per-task tables */",
        "#endif", ""])


def build_proxy(program: Program, board_name: str, out_dir: Path, mcu: str | None = None, sim: bool = False,
                board_path: list[str] | tuple[str, ...] = (), extra_cflags: tuple[str, ...] = (),
                baud: int = DEFAULT_BAUD, check: bool = False) -> BuildResult:
    """Generate and compile the proxy of ``program`` for a board (as
    build.build does for firmware), its link at ``baud`` where the board's
    link is a serial port; ``check``: the board's further checks of the C
    (``easylab build --check``). BuildError when a frame of its device
    model would not fit the protocol's largest frame, when its declared
    watchdog time is wrong (device_model.watchdog_problem), or when the
    board's link cannot run at ``baud`` (the board's ``check_link_baud``,
    before anything is generated)."""
    model = device_model(program)
    check_frames(program, model)
    check_watchdog(program, model)
    proxy = proxy_program(program, model)
    board = load_board(board_name, board_path).configure(mcu, sim)
    check_link = getattr(board, "check_link_baud", None)  # BoardBase's; any rate for a board without it
    if check_link is not None:
        check_link(int(baud))
    checked = board.check(proxy)
    files = render_proxy(program, board, model)
    files.update(board.produce(proxy, checked, False))
    generated = write_files(out_dir, files)
    compiled = board.compile(proxy, checked, out_dir, generated,
                             CompileOptions(False, proxy_cflags(baud) + tuple(extra_cflags), check=check))
    result = BuildResult(out_dir, board, compiled, generated, list(compiled.size.lines if compiled.size else []))
    result.notes += compiled.notes + [f"device model 0x{model.id:08x}"]
    if sim:
        simulator = board.build_simulator(proxy, checked, out_dir, compiled)
        result.simulator = simulator.program
        # Its serial links on ptys in out_dir: `easylab remote --target` opens the link's.
        run_it = shlex.join(board.simulator_command(out_dir, proxy))
        result.notes += simulator.notes + [f"simulator: {simulator.program}", f"run: {run_it}"]
    else:
        try:  # what `easylab flash --proxy` runs
            result.notes.append("flash: " + shlex.join(board.flash_command(out_dir, proxy, "PORT")))
        except BuildError:
            pass  # a process (the host board's proxy) runs where it is built
    return result
