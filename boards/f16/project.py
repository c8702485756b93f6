"""The f16 board's generated files for the part (docs/boards.md, "The F16
board"): el_f16_config.h (tick timer, clock, UART1, interrupt levels),
el_f16_devices.h/.c (one constant description per device for its driver,
the external interrupts' handlers), el_f16_vectors.c (the interrupt
vectors, fcc907s's #pragma intvect), hw_map.json, and the Softune project:
a Makefile with the fcc907s / fasm907s / flnk907s / f2ms command lines over
a self-contained copy of every source."""

from __future__ import annotations

import json
import re
import shutil
from easylab.codegen.c_syntax import c_comment
from pathlib import Path

from easylab.board.devices import DeviceView, devices_header
from easylab.board.resources import Resolved, parse_claim
from easylab.board.simtables import item_symbol
from easylab.core.errors import BuildError
from easylab.ir.program import Program

from .part import TIMER_COUNTS_MAX, TIMER_DIVIDERS, Mcu, fine_clock_khz, tick_timer, uart1_rate, usable_rates

_PIN = re.compile(r"^P([0-9A])([0-7])$")
# Interrupt levels (ICR: 0 is the highest, 7 disables): encoder edges
# before the tick before the UART.
LEVEL_EXT_INT, LEVEL_TICK, LEVEL_UART = 2, 3, 4
# The shortest interrupt period the tick timer gets (the dispatcher's and
# the interfaces' work between ticks takes some hundred cycles).
SHORTEST_TICK_ISR_US = 50


def pin_port(pin: str) -> tuple[int, int]:
    """P43 -> (4, 0x08): the port (PDRn) and the bit's mask."""
    m = _PIN.match(pin)
    return int(m.group(1), 16), 1 << int(m.group(2))


def part_tick(program: Program, mcu: Mcu):
    if program.tick_us < SHORTEST_TICK_ISR_US:
        raise BuildError(f"the model's tick of {program.tick_us} us (the gcd of its task periods, offsets and "
                         f"deadlines) is too short for the f16 board: at least {SHORTEST_TICK_ISR_US} us")
    return tick_timer(program.tick_us, mcu.clock_hz, tuple(TIMER_DIVIDERS), TIMER_COUNTS_MAX, SHORTEST_TICK_ISR_US)


def device_views(program: Program, mcu: Mcu) -> list[DeviceView]:
    """The description of every device for the board's drivers (all in
    el_f16_drivers.h)."""
    views = []
    for dev in program.devices:
        claims = [parse_claim(c)[1] for c in dev.claims]
        item = item_symbol(program, dev.items[0])
        d = dev.driver
        c_type, ints = f"el_drv_{d}_t", ()
        if d == "analog_in":
            init, hw = f"{{ {claims[0]}u, &{item} }}", {"adc": claims[0], "pin": mcu.adc[claims[0]]}
        elif d in ("digital_in", "digital_out"):
            port, mask = pin_port(claims[0])
            init, hw = f"{{ {port}u, 0x{mask:02x}u, &{item} }}", {"pin": claims[0]}
        elif d in ("pwm_out", "motor"):
            port, mask = pin_port(claims[0])
            pwm = f"{{ {mcu.pwm[claims[0]]}u, {port}u, 0x{mask:02x}u, "
            hw = {"ppg": mcu.pwm[claims[0]], "pin": claims[0]}
            if d == "pwm_out":
                init = pwm + f"&{item} }}"
            else:
                dport, dmask = pin_port(claims[1])
                init, hw = f"{{ {pwm}(int16_t *)0 }}, {dport}u, 0x{dmask:02x}u, &{item} }}", {**hw, "dir": claims[1]}
        elif d == "encoder":
            (pa, ma), (pb, mb) = pin_port(claims[0]), pin_port(claims[1])
            ints = (mcu.ext_int[claims[0]], mcu.ext_int[claims[1]])
            init = f"{{ {pa}u, 0x{ma:02x}u, {ints[0]}u, {pb}u, 0x{mb:02x}u, {ints[1]}u, &el_dev{dev.id}_state, &{item} }}"
            hw = {"pin_a": claims[0], "pin_b": claims[1], "int": list(ints)}
        else:  # a driver of board.toml the backend does not describe
            raise BuildError(f"{dev.location}: error: the f16 backend cannot describe devices of driver '{d}' yet")
        hw.update({"path": dev.path, "driver": d, "data": [program.items[i].name for i in dev.items]})
        views.append(DeviceView(dev.id, dev.path, d, dev.location, c_type, init, "el_f16_drivers.h", hw, ints=ints))
    return views


def _uart_lines(res: Resolved, mcu: Mcu, release: bool, model: str) -> list[str]:
    lines = []
    for n, use in sorted(res.uarts.items()):
        kind = use["use"]
        if kind == "debug" and release:
            lines.append(f"/* uart{n}: the debug interface, absent from release builds */")
            continue
        rate = uart1_rate(mcu, int(use.get("baud", 115200)), f"{model}: uart{n} ({kind})")
        rx, tx = (192, 255) if kind == "debug" else (260, 260)  # Modbus: a whole ADU (256 bytes) each way
        lines += [f"/* uart{n}: {kind} at {use.get('baud')} baud: clock / {rate.div} / ({208} << {rate.cs}) = "
                  f"{rate.baud:.0f} baud ({rate.error * 100:+.2f} %) */",
                  f"#define EL_F16_UART1_RX {rx}u", f"#define EL_F16_UART1_TX {tx}u",
                  f"#define EL_F16_UART1_DIV {rate.div}u", f"#define EL_F16_UART1_CS {rate.cs}u",
                  f"#define EL_F16_UART1_RX_VECTOR {mcu.vectors['uart1_rx']}u",
                  f"#define EL_F16_UART1_TX_VECTOR {mcu.vectors['uart1_tx']}u",
                  f"#define EL_F16_UART_LEVEL {LEVEL_UART}u",
                  f"#define EL_F16_{'DEBUG' if kind == 'debug' else 'MODBUS'}_UART {n}u"]
    return lines


def _link_uart(mcu: Mcu, res: Resolved) -> int | None:
    """The UART a remote-execution proxy's link takes: the first one the
    board drives that no device claims (the proxy has no interfaces)."""
    return next((n for n in mcu.driven_uarts if n not in res.uarts), None)


def link_rates_message(mcu: Mcu) -> str:
    """What a proxy's link at a rate UART1 does not make is told: the rates
    it makes (usable_rates, the table remote_link writes into the C)."""
    return (f"the proxy's link: UART1 of the {mcu.name} makes these rates within 2 %: "
            f"{', '.join(str(b) for b, _ in usable_rates(mcu))} (easylab proxy --baud)")


def check_link_baud(mcu: Mcu, baud: int) -> None:
    """A proxy's link at ``baud``: one of the rates remote_link gives
    divisors for, else a BuildError listing them (before any compiler
    runs; the generated #error stays for a Makefile run with another
    EL_REMOTE_BAUD)."""
    if baud not in [b for b, _ in usable_rates(mcu)]:
        raise BuildError(f"{baud} baud: {link_rates_message(mcu)}")


def remote_link(mcu: Mcu, res: Resolved) -> list[str]:
    """A remote-execution proxy's link (f16_uart.c) on UART1, its rings
    sized from the device model's frames (el_remote_config.h), its
    divisors those of EL_REMOTE_BAUD (easylab proxy --baud) among the
    standard rates UART1 makes; only a proxy build (-DEL_REMOTE_PROXY=1)
    sees it."""
    lines = ["", "#if defined(EL_REMOTE_PROXY) && EL_REMOTE_PROXY"]
    n = _link_uart(mcu, res)
    if n is None:
        users = ", ".join(f"uart{u} by {res.uarts[u].get('device', 'a device')}" for u in sorted(res.uarts))
        return lines + [f"#error \"a remote-execution proxy needs a UART for its link: the {mcu.name}'s UART the "
                        f"board drives is claimed ({users}); free it for the link\"", "#endif"]
    rates = usable_rates(mcu)
    lines += [f"#define EL_F16_REMOTE_UART {n}u /* the proxy's link: uart{n} (pins {', '.join(mcu.uart[n])}) */",
              '#include "el_remote_config.h"',
              f"#define EL_F16_UART{n}_RX EL_RMT_RX_RING", f"#define EL_F16_UART{n}_TX EL_RMT_TX_RING"]
    for k, (baud, rate) in enumerate(rates):
        lines += [f"#{'if' if k == 0 else 'elif'} EL_REMOTE_BAUD == {baud}UL /* {rate.baud:.0f} baud "
                  f"({rate.error * 100:+.2f} %) */",
                  f"#define EL_F16_UART1_DIV {rate.div}u", f"#define EL_F16_UART1_CS {rate.cs}u"]
    lines += ["#else", f"#error \"{link_rates_message(mcu)}\"", "#endif",
              f"#define EL_F16_UART1_RX_VECTOR {mcu.vectors['uart1_rx']}u",
              f"#define EL_F16_UART1_TX_VECTOR {mcu.vectors['uart1_tx']}u",
              f"#define EL_F16_UART_LEVEL {LEVEL_UART}u"]
    return lines + ["#endif"]


def config_header(program: Program, mcu: Mcu, res: Resolved, release: bool) -> str:
    t = part_tick(program, mcu)
    lines = [f"/* Generated by EasyLab for board \"f16\", part {mcu.name}, model \"{c_comment(program.name)}\". Do not edit. */",
             "#ifndef EL_F16_CONFIG_H", "#define EL_F16_CONFIG_H", "",
             f"#define EL_F16_MCU_NAME \"{mcu.name}\"",
             f"#define EL_F16_PLL_MULT {mcu.pll}u /* {mcu.crystal_hz // 1_000_000} MHz crystal: a "
             f"{mcu.clock_hz // 1_000_000} MHz machine clock */", "",
             f"/* LET tick {program.tick_us} us = {t.isrs} x reload timer 0 period of {t.period} x clock/{t.divider}"
             + (" (exact) */" if t.exact else f" (not exact: drift {t.drift_ppm:+.1f} ppm) */"),
             f"#define EL_F16_TICK_CSL {TIMER_DIVIDERS[t.divider]}u",
             f"#define EL_F16_TICK_RELOAD {t.period - 1}u",
             f"#define EL_F16_TICK_PERIOD {t.period}UL",
             f"#define EL_F16_TICK_ISRS {t.isrs}u",
             f"#define EL_F16_CLOCK_KHZ {fine_clock_khz(mcu.clock_hz, t.divider)}UL /* fine-clock units per ms */",
             f"#define EL_F16_TICK_VECTOR {mcu.vectors['tick']}u",
             f"#define EL_F16_TICK_LEVEL {LEVEL_TICK}u", ""]
    lines += _uart_lines(res, mcu, release, program.name)
    lines += remote_link(mcu, res)
    lines += ["", "#endif /* EL_F16_CONFIG_H */", ""]
    return "\n".join(lines)


def _int_handlers(mcu: Mcu, views: list[DeviceView]) -> dict[int, list[int]]:
    """Vector -> the encoders whose pins interrupt through it."""
    by_vector: dict[int, list[int]] = {}
    for v in views:
        for intn in v.ints:
            ids = by_vector.setdefault(mcu.int_vector(intn), [])
            if v.id not in ids:
                ids.append(v.id)
    return by_vector


def devices_source(program: Program, mcu: Mcu, views: list[DeviceView]) -> str:
    lines = [f"/* Generated by EasyLab for board \"f16\", model \"{c_comment(program.name)}\": the devices' descriptions,",
             " * the encoders' state and external interrupt handlers. Do not edit. */",
             "#include \"el_types.h\"", "#include \"el_board.h\"", "#include \"f16_compiler.h\"",
             "#include \"f16_internal.h\"", "#include \"mb90f543_regs.h\"", ""]
    for v in views:
        if v.driver == "encoder":
            lines.append(f"static el_drv_encoder_state_t el_dev{v.id}_state; /* {v.path} */")
        lines.append(f"const {v.c_type} el_dev{v.id} = {v.init};")
    handlers = _int_handlers(mcu, views)
    lines += ["", "void el_f16_devices_boot(void)", "{"]
    lines += [f"    EL_F16_ICR(EL_F16_ICR_OF_VECTOR({vec}u)) = {LEVEL_EXT_INT}u; /* INT vector #{vec} */"
              for vec in sorted(handlers)]
    lines.append("}")
    for vec, ids in sorted(handlers.items()):
        lines += ["", f"EL_F16_ISR(el_f16_int_{vec}_interrupt)", "{"]
        lines += [f"    el_drv_encoder_update(&el_dev{i});" for i in ids]
        lines.append("}")
    return "\n".join(lines) + "\n"


def vectors_source(program: Program, mcu: Mcu, res: Resolved, views: list[DeviceView], release: bool) -> str:
    """The interrupt vectors: Softune's startup `_start` at reset, then the
    port's and the devices' handlers."""
    handlers = [("el_f16_tick_interrupt", mcu.vectors["tick"])]
    if any(not (u["use"] == "debug" and release) for u in res.uarts.values()):
        handlers += [("el_f16_uart1_rx_interrupt", mcu.vectors["uart1_rx"]),
                     ("el_f16_uart1_tx_interrupt", mcu.vectors["uart1_tx"])]
    handlers += [(f"el_f16_int_{vec}_interrupt", vec) for vec in sorted(_int_handlers(mcu, views))]
    # A proxy build's link (remote_link), unless UART1 has its handlers already.
    link = [] if any(name.startswith("el_f16_uart1") for name, _ in handlers) or _link_uart(mcu, res) is None else [
        ("el_f16_uart1_rx_interrupt", mcu.vectors["uart1_rx"]), ("el_f16_uart1_tx_interrupt", mcu.vectors["uart1_tx"])]
    proxy_only = ["#if defined(EL_REMOTE_PROXY) && EL_REMOTE_PROXY"]
    lines = [f"/* Generated by EasyLab for board \"f16\", part {mcu.name}, model \"{c_comment(program.name)}\": the",
             " * interrupt vectors (fcc907s's #pragma intvect, the only compiler that reads them). Do not edit. */",
             "#include \"el_types.h\"", "#include \"f16_compiler.h\"", ""]
    lines += [f"EL_F16_ISR({name});" for name, _ in handlers]
    if link:
        lines += proxy_only + [f"EL_F16_ISR({name});" for name, _ in link] + ["#endif"]
    lines += ["", "#if defined(EL_F16_FCC907S)", "#pragma section INTVECT, locate=0xfffc00",
              "#pragma intvect _start 8 0 /* reset: Softune's startup, single-chip mode */"]
    lines += [f"#pragma intvect {name} {vec}" for name, vec in handlers]
    if link:
        lines += proxy_only + [f"#pragma intvect {name} {vec}" for name, vec in link] + ["#endif"]
    lines += ["#endif", "", "typedef int el_f16_vectors_t; /* ISO C wants a declaration in every file */", ""]
    return "\n".join(lines)


def hw_map(program: Program, mcu: Mcu, res: Resolved, views: list[DeviceView]) -> dict:
    t = part_tick(program, mcu)
    return {"format": "easylab-f16-hw-map", "version": 1, "model": program.name,
            "program_id": f"0x{program.program_id:08x}", "mcu": mcu.name, "clock_hz": mcu.clock_hz,
            "tick_us": program.tick_us,
            "tick_timer": {"timer": "reload timer 0", "divider": t.divider, "period": t.period,
                           "interrupts_per_tick": t.isrs, "exact": t.exact, "drift_ppm": round(t.drift_ppm, 3)},
            "uarts": {str(n): {**u, "pins": mcu.uart[n]} for n, u in sorted(res.uarts.items())},
            "devices": [v.hw for v in views],
            "pins": {pin: c.text + " by " + c.owner for pin, c in sorted(res.physical.items())}}


def files(program: Program, mcu: Mcu, res: Resolved, release: bool) -> dict[str, str]:
    """The generated files of a build for the part: {name: text}."""
    views = device_views(program, mcu)
    return {"el_f16_config.h": config_header(program, mcu, res, release),
            "el_f16_devices.h": devices_header(program, views, "f16", "drivers/el_f16_drivers.h", ('"el_f16_drivers.h"',),
                                               defined_here=False),
            "el_f16_devices.c": devices_source(program, mcu, views),
            "el_f16_vectors.c": vectors_source(program, mcu, res, views, release),
            "hw_map.json": json.dumps(hw_map(program, mcu, res, views), indent=2) + "\n"}


# ====================================================================== the Softune project

def copy_sources(out_dir: Path, sources: list[Path], headers: list[Path], generated_dir: Path) -> list[str]:
    """Copy what the project compiles into ``out_dir`` (runtime/ and board/
    beside the generated files): the folder builds on a machine with
    Softune and nothing else. Returns the sources' paths in the project."""
    paths = []
    for src in sources + headers:
        if src.parent == generated_dir:
            rel = src.name
        else:
            sub = "runtime" if src.parent.name == "runtime_c" else "board"
            (out_dir / sub).mkdir(exist_ok=True)
            shutil.copyfile(src, out_dir / sub / src.name)
            rel = f"{sub}/{src.name}"
        if src in sources:
            paths.append(rel)
    return paths


def mode_define(release: bool) -> str:
    """EL_RELEASE or EL_DEBUG, as fcc907s takes a define."""
    return "-D EL_RELEASE=1" if release else "-D EL_DEBUG=1"


def fcc_defines(release: bool, defines: tuple[str, ...] = ()) -> str:
    """The build's defines as fcc907s takes them: the mode's and the
    ``-DNAME=VALUE`` flags of ``defines``."""
    return " ".join([mode_define(release)] + [f"-D {d[2:]}" for d in defines if d.startswith("-D")])


def makefile(program: Program, mcu: Mcu, board_toml: dict, sources: list[str], release: bool,
             defines: tuple[str, ...] = ()) -> str:
    """A Makefile (GNU make) running Softune's tools: compile every source,
    link with Softune's startup and C library, convert to Motorola S.
    ``defines``: the build's further ``-DNAME=VALUE`` flags (a proxy's),
    passed to fcc907s too."""
    chain = board_toml["toolchain"]
    cflags = " ".join(f.format(cpu="$(CPU)") for f in chain["cflags"])
    mode = fcc_defines(release, defines)
    objs = " ".join(f"obj/{Path(s).stem}.obj" for s in sources)
    ram_end = mcu.ram_start + mcu.ram - 1
    rules = "\n".join(f"obj/{Path(s).stem}.obj: {s} | obj\n\t$(CC) $(CFLAGS) -o $@ {s}\n" for s in sources)
    return f"""# Generated by EasyLab for board "f16" ({mcu.title}), model "{program.name}".
# Build with Fujitsu's Softune Workbench tools (F2MC-16 family, V30 or later)
# and GNU make:
#
#     make SOFTUNE=C:/Softune
#
# It needs Softune's startup file for the MB90540 series copied here as
# start.asm (Softune's samples have one; it defines _start, sets the stack
# and clears RAM) and writes {program.name}.abs and {program.name}.mhx (Motorola S
# records for Fujitsu's FLASH MCU Programmer). docs/boards.md, "The F16 board".

SOFTUNE ?= C:/Softune
CC = $(SOFTUNE)/BIN/{chain['cc']}
AS = $(SOFTUNE)/BIN/{chain['assembler']}
LD = $(SOFTUNE)/BIN/{chain['linker']}
CONV = $(SOFTUNE)/BIN/{chain['converter']}
CPU = {mcu.cpu}
CFLAGS = {cflags} {mode} -I . -I runtime -I board
LDFLAGS = -cpu $(CPU) -ra _INRAM01=0x{mcu.ram_start:06X}/0x{ram_end:06X} \\
          -ro _INROM01=0x{mcu.flash_start:06X}/0x{mcu.flash_start + mcu.flash - 1:06X} -AL 2 -a \\
          -L $(SOFTUNE)/LIB/907 -l {chain['library']}

OBJS = obj/start.obj {objs}

{program.name}.mhx: {program.name}.abs
\t$(CONV) -S2 -o $@ {program.name}.abs

{program.name}.abs: $(OBJS)
\t$(LD) $(LDFLAGS) -o $@ $(OBJS)

obj:
\tmkdir obj

obj/start.obj: start.asm | obj
\t$(AS) -cpu $(CPU) -o $@ start.asm

start.asm:
\t@echo "copy Softune's startup file for the MB90540 series here as start.asm" && false

{rules}
clean:
\trm -rf obj {program.name}.abs {program.name}.mhx
"""
