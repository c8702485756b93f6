"""The PIC18 board's generated files: the tick timer's settings, the
configuration header (el_pic18_config.h), the device descriptions
(el_pic18_devices.h), the linker script and hw_map.json; and the checks
only this part needs (ADCON1's analog pins)."""

from __future__ import annotations

import json
from easylab.codegen.c_syntax import c_comment
from dataclasses import dataclass

from easylab.board import handlers
from easylab.board.devices import DeviceView, devices_header
from easylab.board.resources import Resolved, parse_claim
from easylab.board.simtables import item_symbol
from easylab.core.errors import BuildError
from easylab.ir.program import Program

from .linkmap import SFR_START
from .parts import Mcu, pin_code

CONFIG_VERSION = 1
# The shortest LET tick the board takes: the tick interrupt and the
# dispatcher's instant take some hundred cycles.
MIN_TICK_US = 50
_PRESCALERS = {1: 0, 4: 1, 16: 2}  # Timer2's T2CKPS by prescaler
PWM_PERIOD = 1000  # preferred Timer2 period in cycles: 10 kHz PWM, 10-bit duty


# ====================================================================== the tick


@dataclass
class TickTimer:
    prescale: int
    pr2: int  # the period is pr2 + 1 timer clocks
    postscale: int  # 1..16
    isrs: int  # interrupts per tick
    exact: bool
    drift_ppm: float

    @property
    def period(self) -> int:
        """Cycles of one Timer2 period (the PWM period)."""
        return self.prescale * (self.pr2 + 1)

    @property
    def isr_cycles(self) -> int:
        return self.period * self.postscale

    @property
    def t2con(self) -> int:
        return (self.postscale - 1) << 3 | _PRESCALERS[self.prescale]


def tick_timer(tick_us: int, fcy: int) -> TickTimer:
    """Timer2's settings for a LET tick of ``tick_us``: an interrupt every
    prescale x (PR2 + 1) x postscale cycles, ``isrs`` of them per tick.
    Exact (no drift against the crystal) whenever some setting divides the
    tick with interrupts 50 us to 1 ms apart; among those the one whose
    period is 1000 cycles (a 10 kHz PWM), then the longest interrupt period,
    then the finest PWM resolution."""
    ms = fcy // 1000
    shortest = ms // 20
    want = tick_us * fcy / 1_000_000
    best = None
    for p in _PRESCALERS:
        for period in range(1, 257):
            for q in range(1, 17):
                isr = p * period * q
                if isr > ms or (isr < shortest and isr < want):
                    continue
                n = max(1, min(65535, round(want / isr)))
                error = abs(n * isr - want)
                key = (error, period * p != PWM_PERIOD, -isr, -period)
                if best is None or key < best[0]:
                    drift = (n * isr - want) / want * 1e6
                    best = (key, TickTimer(p, period - 1, q, n, error == 0, drift))
    if best is None:
        raise BuildError(f"no Timer2 setting gives a tick of {tick_us} us")
    return best[1]


# ====================================================================== devices


def _claims(mcu: Mcu, texts: list[str]) -> list[tuple[str, object]]:
    part = mcu.part()
    out = []
    for text in texts:
        kind, idx = parse_claim(text)
        out.append((kind, part.own_pin(idx) if kind in ("pin", "pwm") else idx))
    return out


def chip_select(mcu: Mcu, pin: str) -> str:
    """The C initializer of a chip select (struct el_pin of el_board.h):
    the hardware layer's pin number."""
    pin = mcu.part().own_pin(pin)
    return f"{{ 0x{pin_code(pin):02X}u }}"


def device_views(program: Program, mcu: Mcu, drivers: dict) -> list[DeviceView]:
    """The board's drivers' devices (those whose types bring handler files
    for the board run those instead)."""
    views = []
    encoder_slot = 0
    for dev in program.devices:
        if handlers.handler_file(dev, "pic18") is not None:
            continue
        claims = _claims(mcu, dev.claims)
        items = [item_symbol(program, i) for i in dev.items]
        d = dev.driver
        header = drivers[d]["header"]
        if d == "analog_in":
            ch = claims[0][1]
            init, hw = f"{{ {ch}u, &{items[0]} }}", {"adc": ch, "pin": mcu.adc[ch]}
        elif d in ("digital_in", "digital_out"):
            pin = claims[0][1]
            init, hw = f"{{ 0x{pin_code(pin):02X}u, &{items[0]} }}", {"pin": pin}
        elif d == "pwm_out":
            pin = claims[0][1]
            init, hw = f"{{ {mcu.pwm[pin]}u, &{items[0]} }}", {"pwm": {"pin": pin, "ccp": mcu.pwm[pin]}}
        elif d == "motor":
            pin, direction = claims[0][1], claims[1][1]
            init = f"{{ {mcu.pwm[pin]}u, 0x{pin_code(direction):02X}u, &{items[0]} }}"
            hw = {"pwm": {"pin": pin, "ccp": mcu.pwm[pin]}, "dir": direction}
        elif d == "encoder":
            a, b = claims[0][1], claims[1][1]
            init = f"{{ {encoder_slot}u, 0x{pin_code(a):02X}u, 0x{pin_code(b):02X}u, &{items[0]} }}"
            hw = {"pin_a": a, "pin_b": b, "slot": encoder_slot}
            encoder_slot += 1
        else:  # a driver listed in board.toml without generator support
            raise BuildError(f"{dev.location}: error: the pic18 backend cannot describe devices of driver '{d}' yet")
        hw.update({"data": [program.items[i].name for i in dev.items], "driver": d, "path": dev.path})
        views.append(DeviceView(dev.id, dev.path, d, dev.location, f"el_drv_{d}_t", init, header, hw))
    return views


def analog_problems(program: Program, mcu: Mcu) -> list[str]:
    """ADCON1 makes AN0..ANn analog together, and an analog pin reads 0 as
    a digital input: refuse digital inputs on the pins a claimed channel
    turns analog."""
    claimed = [(dev, kind, idx) for dev in program.devices for kind, idx in _claims(mcu, dev.claims)]
    channels = [(idx, dev) for dev, kind, idx in claimed if kind == "adc" and idx in mcu.adc]
    if not channels:
        return []
    top, owner = max(channels, key=lambda c: c[0])
    analog = {mcu.adc[ch]: ch for ch in range(top + 1) if ch in mcu.adc}
    problems = []
    for dev, kind, pin in claimed:
        if kind == "pin" and pin in analog and dev.driver in ("digital_in", "encoder"):
            problems.append(
                f"{dev.location}: error: device '{dev.path}' reads {pin} as a digital input, but on the {mcu.name} "
                f"adc[{top}] (device '{owner.path}') makes AN0..AN{top} analog together (ADCON1) and {pin} is "
                f"AN{analog[pin]}, which then reads 0; choose a pin that is none of AN0..AN{top}, or a lower ADC "
                f"channel")
    return problems


# ====================================================================== generated files


def _ring_sizes(mcu: Mcu) -> tuple[int, int]:
    """(RX, TX) ring bytes of the EUSART carrying Modbus RTU (at most 255)."""
    small = mcu.ram <= 2048
    return (128, 64) if small else (255, 128)  # Modbus: a whole ADU arrives while a task may run


def remote_link(mcu: Mcu, res: Resolved) -> list[str]:
    """A remote-execution proxy's link (pic18_remote.c) on the EUSART, its
    rings sized from the device model's frames (el_remote_config.h, at most
    255 bytes); only a proxy build (-DEL_REMOTE_PROXY=1, easylab proxy) sees it. A
    model whose devices claim the EUSART has no link."""
    lines = ["", "#if defined(EL_REMOTE_PROXY) && EL_REMOTE_PROXY"]
    free = [n for n in sorted(mcu.uart) if n not in res.uarts]
    if not free:
        users = ", ".join(f"uart{n} by {res.uarts[n].get('device', 'a device')}" for n in sorted(res.uarts))
        lines.append(f"#error \"a remote-execution proxy needs a UART for its link: the {mcu.name}'s only UART is "
                     f"claimed ({users}); free it for the link\"")
    else:
        lines += [f"#define EL_PIC18_REMOTE_UART {free[0]}u /* the proxy's link: uart{free[0]} "
                  f"(pins {', '.join(mcu.uart[free[0]])}) */",
                  '#include "el_remote_config.h"',
                  "#define EL_PIC18_UART_RX (EL_RMT_RX_RING < 255u ? EL_RMT_RX_RING : 255u)",
                  "#define EL_PIC18_UART_TX EL_RMT_TX_RING"]
    return lines + ["#endif"]


def config_header(program: Program, board, res: Resolved, release: bool) -> str:
    mcu: Mcu = board.part
    if program.tick_us < MIN_TICK_US:
        raise BuildError(f"the model's tick of {program.tick_us} us (the gcd of its task periods, offsets and "
                         f"deadlines) is too short for the pic18 board: at least {MIN_TICK_US} us")
    t = tick_timer(program.tick_us, board.fcy)
    channels = [idx for dev in program.devices for kind, idx in _claims(mcu, dev.claims) if kind == "adc"]
    encoders = sum(1 for dev in program.devices if dev.driver == "encoder")
    lines = [
        f"/* Generated by EasyLab for board \"pic18\", MCU {mcu.name}, model \"{c_comment(program.name)}\". Do not edit. */",
        "#ifndef EL_PIC18_CONFIG_H", "#define EL_PIC18_CONFIG_H", "",
        f"#define EL_PIC18_CONFIG_VERSION {CONFIG_VERSION}",
        f"#define EL_PIC18_MCU_NAME \"{mcu.name}\"",
        f"#define EL_PIC18_FCY {board.fcy}UL /* instruction cycles per second */",
        f"#define EL_PIC18_RAM_LAST 0x{mcu.ram_last:03X} /* start-up clears RAM up to here */",
        f"#define EL_PIC18_RAM_TOP 0x{mcu.ram_last + 1:03X} /* el_pic18_kept */",
        f"#define EL_PIC18_NV_SIZE {mcu.eeprom}u /* data EEPROM bytes */", "",
        f"/* LET tick {program.tick_us} us = {t.isrs} x Timer2 interrupts of {t.isr_cycles} cycles "
        f"({t.prescale} x {t.pr2 + 1} x {t.postscale})"
        + (" (exact) */" if t.exact else f" (not exact: drift {t.drift_ppm:+.1f} ppm) */"),
        f"#define EL_PIC18_TICK_T2CON 0x{t.t2con:02X}u",
        f"#define EL_PIC18_TICK_PR2 {t.pr2}u",
        f"#define EL_PIC18_TICK_ISRS {t.isrs}u", "",
        f"#define EL_PIC18_ADC_CHANNELS {max(channels) + 1 if channels else 0}u /* AN0.. analog (ADCON1) */",
        f"#define EL_PIC18_ENCODERS {encoders}u", ""]
    for n, u in sorted(res.uarts.items()):
        if u["use"] == "debug" and release:
            lines.append(f"/* uart{n}: the debug interface, absent from release builds */")
            continue
        if u["use"] == "debug":
            # RX: an encoded request of the model's largest frame (el_debug_config.h) or the
            # protocol's, its COBS code and delimiter (a ring of n bytes holds n - 1), which waits
            # there while the response goes out; no TX ring: responses go out straight from the
            # debug server's buffer (pic18_uart.c)
            frame = "EL_DBG_FRAME" if board.model_sized_debug_buffers else "EL_DBG_MAX_FRAME"
            header = "el_debug_config.h" if board.model_sized_debug_buffers else "el_debug_protocol.h"
            lines += [f'#include "{header}" /* uart{n}: debug; {frame} */',
                      f"#define EL_PIC18_UART_RX ({frame} + 3u)",
                      "#define EL_PIC18_UART_TX 0u"]
        else:
            rx, tx = _ring_sizes(mcu)
            lines += [f"#define EL_PIC18_UART_RX {rx}u /* uart{n}: {u['use']} */", f"#define EL_PIC18_UART_TX {tx}u"]
        if u["use"] == "debug":
            lines.append(f"#define EL_PIC18_DEBUG_BAUD {int(u.get('baud', 115200))}UL")
        elif u["use"] == "modbus-rtu":
            lines.append("#define EL_PIC18_MODBUS 1")
    lines += mssp_config(board, res) + remote_link(mcu, res)
    if board.sim:
        lines += ["", "#define EL_PIC18_SIM 1 /* simulation build: instants reported to the gpsim harness */"]
    lines += ["", "#endif /* EL_PIC18_CONFIG_H */", ""]
    return "\n".join(lines)


_SPI_DIVIDERS = {4: 0, 16: 1, 64: 2}  # Fosc / n: SSPCON1's SSPM


def mssp_config(board, res: Resolved) -> list[str]:
    """The MSSP's settings when a device is on its I2C or SPI bus
    (pic18_mssp.c): SSPADD for the I2C clock, SSPM for the SPI's."""
    lines = []
    if ("i2c", 0) in res.buses:
        i2c = board.description.table("i2c")
        hz = int(i2c.get("clock_hz", 400000))
        sspadd = max(3, -(-board.fcy // hz) - 1)  # Fosc / (4 (SSPADD + 1)), at most hz
        if sspadd > 255:
            raise BuildError(f"board.toml's [i2c] clock_hz {hz} is too slow for the MSSP at {board.clock_hz} Hz")
        lines += ["", f"/* i2c[0] on the MSSP: {', '.join(c.owner for c in res.buses[('i2c', 0)])} */",
                  "#define EL_PIC18_I2C 1", f"#define EL_PIC18_I2C_SSPADD {sspadd}u /* {board.fcy // (sspadd + 1)} Hz */",
                  # SMP clear: slew-rate control, for the 400 kHz mode only
                  f"#define EL_PIC18_I2C_SSPSTAT 0x{0x00 if 100000 < hz < 1000000 else 0x80:02X}u",
                  f"#define EL_I2C_WAIT_US {int(i2c.get('wait_us', 2000))}UL /* the longest wait for a job */",
                  f"#define EL_I2C_BUSY_US {int(i2c.get('busy_us', 10000))}UL /* a busy chip is tried again this long */"]
    if ("spi", 0) in res.buses:
        hz = int(board.description.table("spi").get("clock_hz", 4000000))
        divider = next((k for k in sorted(_SPI_DIVIDERS) if board.clock_hz // k <= hz), 64)
        lines += ["", f"/* spi[0], master on the MSSP: {', '.join(c.owner for c in res.buses[('spi', 0)])} */",
                  "#define EL_PIC18_SPI 1", f"#define EL_PIC18_SPI_SSPM {_SPI_DIVIDERS[divider]}u "
                  f"/* Fosc / {divider}: {board.clock_hz // divider} Hz */"]
    return lines


def linker_script(mcu: Mcu, big_start: int | None = None, measure: bool = False) -> str:
    """gplink's memory map: program memory, the configuration words, the
    RAM banks, then at the top of RAM the objects larger than a bank (from
    ``big_start``: sdcc_quirks.place_big_objects), sdcc's software stack
    (el_pic18_stack.c puts it there) and el_pic18_kept alone at the last
    byte; the special function registers. ``measure``: the same map with the
    PIC18's whole 2 MB of program memory and RAM up to the registers, to
    measure a program too big for the part."""
    below_stack = mcu.stack_bottom - 1
    last = below_stack if big_start is None or big_start > below_stack else big_start - 1
    big = [] if last == below_stack else [
        f"DATABANK   NAME=big     START=0x{big_start:03X}  END=0x{below_stack:03X}  PROTECTED"]
    starts = [0x80] + list(range(0x100, last + 1, 0x100))
    banks = [f"DATABANK   NAME=gpr{start >> 8}  START=0x{start:03X}  END=0x{min((start | 0xFF), last):03X}"
             for start in starts]
    beyond = mcu.ram_last + 2  # past the kept byte
    extra = [] if not measure else [
        f"DATABANK   NAME=more{start >> 8}  START=0x{start:03X}  END=0x{min(start | 0xFF, SFR_START - 1):03X}"
        for start in [beyond] + list(range((beyond | 0xFF) + 1, SFR_START, 0x100)) if start < SFR_START]
    return "\n".join([
        f"// gplink's memory map of the {mcu.name} for EasyLab's pic18 board (devices.py). Do not edit.",
        "LIBPATH .",
        f"CODEPAGE   NAME=page    START=0x0        END=0x{(0x200000 if measure else mcu.flash) - 1:X}",
        "CODEPAGE   NAME=idlocs  START=0x200000   END=0x200007   PROTECTED",
        "CODEPAGE   NAME=config  START=0x300000   END=0x30000D   PROTECTED",
        "CODEPAGE   NAME=devid   START=0x3FFFFE   END=0x3FFFFF   PROTECTED",
        f"CODEPAGE   NAME=eedata  START=0xF00000   END=0x{0xF00000 + mcu.eeprom - 1:X}   PROTECTED",
        "ACCESSBANK NAME=accessram START=0x0      END=0x7F",
        *banks, *big,
        f"DATABANK   NAME=stack   START=0x{mcu.stack_bottom:03X}  END=0x{mcu.ram_last:03X}  PROTECTED",
        f"DATABANK   NAME=kept    START=0x{mcu.ram_last + 1:03X}  END=0x{mcu.ram_last + 1:03X}  PROTECTED",
        *extra,
        f"ACCESSBANK NAME=accesssfr START=0x{SFR_START:03X}    END=0xFFF      PROTECTED",
        "SECTION    NAME=CONFIG  ROM=config", ""])


def stack_source(mcu: Mcu) -> str:
    """el_pic18_stack.c: sdcc's software stack at the top of RAM (below
    el_pic18_kept), larger than a bank: the large stack model carries
    the stack pointer's high byte (sdcc's --pstack-model=large)."""
    return "\n".join([
        f"/* The software stack of the {mcu.name} (boards/pic18/devices.py). Do not edit. */",
        f"#pragma stack 0x{mcu.stack_bottom:03X} {mcu.stack}",
        "typedef int el_pic18_stack_unit_t; /* a translation unit declares something */", ""])


def hw_map(program: Program, board, res: Resolved, views: list[DeviceView]) -> dict:
    mcu: Mcu = board.part
    t = tick_timer(program.tick_us, board.fcy)
    return {
        "format": "easylab-pic18-hw-map", "version": 1,
        "model": program.name, "program_id": f"0x{program.program_id:08x}", "mcu": mcu.name,
        "clock_hz": board.clock_hz, "instruction_hz": board.fcy, "tick_us": program.tick_us,
        "tick_timer": {"timer": 2, "prescale": t.prescale, "pr2": t.pr2, "postscale": t.postscale,
                       "interrupts_per_tick": t.isrs, "exact": t.exact, "drift_ppm": round(t.drift_ppm, 3),
                       "pwm_hz": board.fcy / t.period},
        "uarts": {str(n): {**u, "pins": mcu.uart[n]} for n, u in sorted(res.uarts.items())},
        "devices": [v.hw for v in views],
        "pins": {pin: c.text + " by " + c.owner for pin, c in sorted(res.physical.items())},
    }


def handler_declarations(program: Program) -> list[str]:
    """The functions of the devices that run handler files (el_handlers.c),
    declared at file scope: sdcc takes a function declared inside a block
    (the generic call's form) for an uninitialised variable."""
    lines = []
    for dev in program.devices:
        if handlers.handler_file(dev, "pic18") is not None:
            lines.append(f"/* {dev.path}: handlers {handlers.handler_file(dev, 'pic18')} */")
            lines += [f"void {handlers.function_name(dev, h)}(void);" for h in handlers.HANDLERS]
    return lines


def files(program: Program, board, res: Resolved, release: bool) -> dict[str, str]:
    """The board's generated files: {file name: text}."""
    views = device_views(program, board.part, board.drivers)
    header = devices_header(program, views, "pic18", "boards/pic18/drivers/")
    declared = handler_declarations(program)
    if declared:
        end = "#endif /* EL_PIC18_DEVICES_H */"
        header = header.replace(end, "\n".join(declared) + "\n\n" + end)
    return {
        "el_pic18_config.h": config_header(program, board, res, release),
        "el_pic18_devices.h": header,
        "hw_map.json": json.dumps(hw_map(program, board, res, views), indent=2) + "\n",
    }
