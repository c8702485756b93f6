"""Device handlers from the model's folder (docs/language.md, "Device
handlers"; docs/boards.md, "Writing a device driver"): the mechanism every
board uses for a device whose type names a C file for it
(``driver "tmp102" impl avr "drivers/tmp102_avr.c"``).

A handler file is file-scope code and up to six blocks, ``EL_OPEN``,
``EL_START``, ``EL_READ``, ``EL_WRITE``, ``EL_STOP`` and ``EL_CLOSE``, each
followed by ``{ ... }``; a block it lacks does nothing. For a build, every
device with a file for the board becomes six functions
``el_mdev<id>_<handler>`` in the generated ``el_handlers.c``, in whose
bodies the device's parameters, data ports and state are in scope under
their own names (macros). model.c calls them where it calls a board's
driver otherwise (:func:`call`). The same rendering, with the data and the
state reached through pointers, makes the plug-ins of local execution
(:func:`device_block`).
"""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from ..codegen.c_syntax import c_comment, c_literal, c_string
from ..codegen.device_state import state_devices, state_items, state_symbol, state_type_lines  # noqa: F401 (re-exported: the boards use them through this module)
from ..core.impl_files import DEVICE_BLOCKS, split_impl
from ..core import types as T
from ..core.errors import BuildError
from ..ir.program import Device, Item, Program
from .claims import parse_select
from .simtables import item_symbol

HANDLERS = DEVICE_BLOCKS  # open, start, read, write, stop, close
SOURCE_FILE = "el_handlers.c"
# After a block's body: a #line back into the generated file, whose number
# only the whole file knows (resolve_lines).
LINE_BACK = "#line @generated@"


@dataclass
class HandlerCode:
    """One handler file, split: its file-scope code and its blocks' bodies."""

    file: str
    prelude: str
    bodies: dict[str, str]
    lines: dict[str, int]  # the line of the file each body starts on


@functools.lru_cache(maxsize=64)
def _split_cached(file: str, mtime_ns: int, size: int) -> HandlerCode:
    text = Path(file).read_text(encoding="utf-8")
    spans: dict[str, tuple[int, int, int]] = {}
    prelude, bodies = split_impl(text, file, HANDLERS, spans)
    return HandlerCode(file, prelude, bodies, {k: text.count("\n", 0, v[1]) + 1 for k, v in spans.items()})


def read_handlers(file: str) -> HandlerCode:
    """A handler file, split (cached while the file is unchanged); a file
    that cannot be read or split is a BuildError naming it."""
    try:
        st = os.stat(file)
        return _split_cached(file, st.st_mtime_ns, st.st_size)
    except OSError as err:
        raise BuildError(f"cannot read the handler file {file}: {err.strerror or err}") from None
    except (UnicodeDecodeError, ValueError) as err:
        raise BuildError(f"handler file {err}" if isinstance(err, ValueError) else
                         f"handler file {file} is not UTF-8 text") from None


def handler_file(device: Device, board: str) -> str | None:
    """The file that implements the device's handlers on ``board``, if its
    type brings one."""
    return device.handlers.get(board)


def function_name(device: Device, handler: str) -> str:
    return f"el_mdev{device.id}_{handler}"


def call(device: Device, handler: str, board: str) -> str | None:
    """The C statement model.c runs for one handler of a device whose type
    brings a file for ``board`` ('' when the file has no such block); None
    when it brings none (the board's own driver runs). The statement
    declares the function it calls, so model.c needs no header."""
    file = handler_file(device, board)
    if file is None:
        return None
    if handler not in read_handlers(file).bodies:
        return ""
    fn = function_name(device, handler)
    return f"{{ void {fn}(void); {fn}(); }}"


def lacking(device: Device, board: str) -> str | None:
    """The problem of a device whose type brings handler files, but none
    for ``board`` (at its source line, saying what to write); None when it
    brings one for the board or none at all (the board's own drivers
    decide then)."""
    if not device.handlers or handler_file(device, board) is not None:
        return None
    return (f"{device.location}: error: device '{device.path}' ({device.type_name}, driver '{device.driver}') has "
            f"no handlers for the {board} board: its type brings them for {', '.join(sorted(device.handlers))} "
            f"only; write a C file with its EL_OPEN ... EL_CLOSE blocks for the {board} board and name it after "
            f"the driver: driver \"{device.driver}\" impl {board} \"FILE.c\" (docs/boards.md, 'Writing a device "
            f"driver')")


def check_files(program: Program, board: str) -> None:
    """Read and split every handler file the build uses (a BuildError names
    the first one that cannot be)."""
    for dev in program.devices:
        file = handler_file(dev, board)
        if file is not None:
            read_handlers(file)


# ====================================================================== C


@dataclass
class Binding:
    """How a device block reaches its data and state: C expressions for an
    item's storage (an lvalue, or an array) and for the state struct."""

    datum: Callable[[Item], str]
    state: str


def firmware_binding(program: Program, device: Device) -> Binding:
    """Firmware: the items of model.c and a static state per device."""
    return Binding(lambda item: item_symbol(program, item.id), state_symbol(device))


def device_block(program: Program, device: Device, code: HandlerCode, binding: Binding,
                 firmware: bool = True, chip_select: Callable[[str], str] | None = None) -> list[str]:
    """The C of one device's handlers: its state type, the names its code
    sees (macros, undefined at the end) and its six functions ``void
    el_mdev<id>_<handler>(void)`` (a block the file lacks is an empty
    function). For ``firmware`` the functions are global (model.c calls
    them), the items extern and the state a static variable; otherwise
    (a plug-in) the functions are static and ``binding`` reaches the data
    and the state through pointers. ``chip_select`` gives the board's C
    initializer of a pin (struct el_pin) for a device on an SPI bus: its
    handlers get their chip select as ``EL_CS``."""
    state_type = f"el_mdev{device.id}_state_t"
    storage = "" if firmware else "static "
    lines = ["/* " + c_comment(f"device {device.path}: {device.type_name}("
                               + ", ".join(f"{k} = {_show(t, v)}" for k, (t, v) in device.params.items())
                               + f"), {device.location}; handlers {Path(code.file).name}") + " */"]
    items = [program.items[i] for i in device.items]
    if firmware:
        for item in items:
            dims = f"[{item.count}]" if item.count > 1 else ""
            lines.append(f"extern {item.type.c_name} {item_symbol(program, item.id)}{dims};")
    lines += state_type_lines(device)
    if firmware and device.states:
        # Global: the debug tables and the host board's trace reach it (docs/language.md, "Device handlers").
        lines.append(f"extern {state_type} {binding.state};")
        lines.append(f"{state_type} {binding.state}; /* zero at boot */")
    defines = [("EL_DEVICE", f"{device.id}u"), ("EL_DEVICE_PATH", c_literal(T.STRING, device.path))]
    cs = next((where for how, where in filter(None, map(parse_select, device.claims)) if how == "cs"), None)
    if cs is not None and chip_select is not None:
        lines.append(f"static const el_pin_t el_mdev{device.id}_cs = {chip_select(str(cs))}; /* cs {cs} */")
        defines.append(("EL_CS", f"(&el_mdev{device.id}_cs)"))
    defines += [(name, c_literal(t, v)) for name, (t, v) in device.params.items()]
    for item in items:
        array = item.port in device.array_ports or item.count > 1
        ctype = item.type.c_name
        where = binding.datum(item)
        if item.kind == "dev_out":
            defines.append((item.port, f"({where})"))
        elif array:
            defines.append((item.port, f"((const {ctype} *){where})"))
        else:
            defines.append((item.port, f"(*(const {ctype} *)&{where})"))
    defines += [(name, f"(({binding.state}).{name})") for name, _t, _s in device.states]
    lines += [f"#define {name} {value}" for name, value in defines]
    for handler in HANDLERS:
        fn = function_name(device, handler)
        lines.append(f"{storage}void {fn}(void);")
        lines.append(f"{storage}void {fn}(void)")
        lines.append("{")
        if handler in code.bodies:
            # the compiler names the user's file and line in the body
            lines += ["    {", f"#line {code.lines[handler]} {c_string(code.file)}", code.bodies[handler].rstrip(" \t"),
                      LINE_BACK, "    }"]
        if handler == "close" and firmware and device.states:
            lines.append(f"    (void)&{binding.state}; /* a state its file does not use is no error */")
        lines.append("}")
    lines += [f"#undef {name}" for name, _v in defines]
    return lines


def _show(t: T.ValueType, value) -> str:
    return f'"{value}"' if t is T.STRING else str(value)


def prelude_block(code: HandlerCode) -> list[str]:
    """A handler file's file-scope code, with where it comes from."""
    return [f"/* ---- file-scope code of {code.file} ---- */", code.prelude.strip("\n"), "/* ---- end ---- */"]


def source(program: Program, board: str, includes: tuple[str, ...] = (),
           chip_select: Callable[[str], str] | None = None) -> dict[str, str]:
    """{``el_handlers.c``: its text} for the devices with a handler file for
    ``board``, or {} when there are none. ``includes`` are the board's
    headers the files may use beyond the runtime's and el_board.h (its bus
    interface); ``chip_select`` the board's C for a chip select (see
    :func:`device_block`)."""
    devices = [d for d in program.devices if handler_file(d, board) is not None]
    if not devices:
        return {}
    lines = [f"/* Generated by EasyLab from {c_comment(program.source)} for board \"{board}\": the handlers of the devices "
             "whose types", " * bring their C from the model's folder (docs/language.md, \"Device handlers\"). "
             "Do not edit. */", '#include "el_types.h"', '#include "el_model.h"', '#include "el_board.h"']
    lines += [f'#include "{h}"' for h in includes]
    lines.append("")
    done: set[str] = set()
    for dev in devices:
        code = read_handlers(handler_file(dev, board))
        if code.file not in done:  # one copy of a file's own code, whatever uses it
            done.add(code.file)
            lines += prelude_block(code) + [""]
        lines += device_block(program, dev, code, firmware_binding(program, dev), chip_select=chip_select) + [""]
    return {SOURCE_FILE: resolve_lines("\n".join(lines) + "\n", SOURCE_FILE)}


def resolve_lines(text: str, name: str) -> str:
    """``text`` with each LINE_BACK made the ``#line`` that numbers the
    lines after it as ``name``'s own."""
    out = text.split("\n")
    for k, line in enumerate(out):
        if line == LINE_BACK:
            out[k] = f"#line {k + 2} {c_string(name)}"
    return "\n".join(out)
