"""The AVR board's generated files (docs/boards.md, "The AVR board"):
el_avr_config.h (the LET tick's timer, UART rings, watchdog, the
interfaces' UARTs), el_avr_devices.h and .c (one ``static const``
description per device for its driver, the drivers' interrupt handlers)
and hw_map.json (device data -> pins, ADC channels, UARTs)."""

from __future__ import annotations

import json
import math
import re
from easylab.codegen.c_syntax import c_comment
from dataclasses import dataclass

from easylab.board import handlers
from easylab.board.devices import DeviceView, devices_header
from easylab.board.resources import Resolved, parse_claim, parse_select
from easylab.board.simtables import item_symbol
from easylab.core.errors import BuildError
from easylab.ir.program import Program

from .parts import Mcu

CONFIG_VERSION = 1
# The shortest LET tick the board takes: the tick interrupt and the
# dispatcher's instant take some hundred cycles.
MIN_TICK_US = 50

# Timer2's clock selects (CS2 bits) by prescaler.
_TIMER2_PRESCALERS = {1: 1, 8: 2, 32: 3, 64: 4, 128: 5, 256: 6, 1024: 7}
_WDTO = {15: "WDTO_15MS", 30: "WDTO_30MS", 60: "WDTO_60MS", 120: "WDTO_120MS", 250: "WDTO_250MS",
         500: "WDTO_500MS", 1000: "WDTO_1S", 2000: "WDTO_2S", 4000: "WDTO_4S", 8000: "WDTO_8S"}
_PIN = re.compile(r"^P([A-L])([0-7])$")


# ====================================================================== the tick


@dataclass
class TickTimer:
    prescale: int
    cs: int
    ocr: int  # TOP: period ocr + 1 timer clocks
    isrs: int  # interrupts per tick
    exact: bool
    drift_ppm: float

    @property
    def isr_cycles(self) -> int:
        return self.prescale * (self.ocr + 1)


def tick_timer(tick_us: int, clock_hz: int) -> TickTimer:
    """Timer2 settings for a LET tick of ``tick_us``: an interrupt every
    prescale * (ocr + 1) cycles, ``isrs`` of them per tick; exact (no drift
    against the crystal) whenever some setting divides the tick with
    interrupts no closer than 50 us, preferring the longest interrupt
    period up to 1 ms, then the smallest prescaler."""
    if (tick_us * clock_hz) % 1_000_000:
        cycles = None
    else:
        cycles = tick_us * clock_hz // 1_000_000
    ms = clock_hz // 1000
    shortest = ms // 20  # interrupts at most every 50 us
    best = None
    if cycles:
        for p, cs in _TIMER2_PRESCALERS.items():
            for c in range(2, 257):
                period = p * c
                if cycles % period or cycles // period > 65535 or (period < shortest and period != cycles):
                    continue
                n = cycles // period
                key = (period <= ms, period if period <= ms else -period, -c)
                if best is None or key > best[0]:
                    best = (key, TickTimer(p, cs, c - 1, n, True, 0.0))
    if best is not None:
        return best[1]
    # No exact setting: the nearest product, with interrupts no more often
    # than every 50 us; it drifts by its rounding error against the crystal.
    want = tick_us * clock_hz / 1_000_000
    near = None
    for p, cs in _TIMER2_PRESCALERS.items():
        for c in range(2, 257):
            period = p * c
            if period < shortest:
                continue
            n = max(1, min(65535, round(want / period)))
            key = (abs(n * period - want), abs(period - ms))
            if near is None or key < near[0]:
                near = (key, TickTimer(p, cs, c - 1, n, False, (n * period - want) / want * 1e6))
    return near[1]


# ====================================================================== generated files


def _item_c(program: Program, item_id: int) -> tuple[str, str]:
    return item_symbol(program, item_id), program.items[item_id].type.c_name


def _pin_regs(pin: str) -> tuple[str, str, int]:
    m = _PIN.match(pin)
    return f"&PIN{m.group(1)}", f"_BV({m.group(2)})", int(m.group(2))


def chip_select(pin: str) -> str:
    """A pin as the buses take a chip select: ``struct el_pin`` (el_board.h)."""
    reg, mask, _ = _pin_regs(pin)
    return f"{{ {reg}, {mask} }}"


def _pwm_init(mcu: Mcu, pin: str) -> tuple[str, dict]:
    timer, ch = mcu.pwm[pin]
    wide = timer in mcu.wide_timers
    com = {"A": 7, "B": 5, "C": 3}[ch]
    ocr = f"&OCR{timer}{ch}L" if wide else f"&OCR{timer}{ch}"
    pin_reg, mask, _ = _pin_regs(pin)
    init = (f"{{ &TCCR{timer}A, (volatile uint8_t *){ocr}, _BV({com}), {1 if wide else 0}u, {pin_reg}, {mask}, ")
    return init, {"timer": timer, "channel": ch, "pin": pin}


def _eeprom_log_slot(dev, values: int) -> int:
    """Bytes per slot of an EEPROM log: the smallest power of two that
    holds a record (a sequence number and the values) and divides the page."""
    page, size = int(dev.params["page"][1]), int(dev.params["bytes"][1])
    slot = 4
    while slot < 2 + 2 * values:
        slot *= 2
    if slot > min(page, 64) or page % slot or size % page or size > 0x10000 or size & (size - 1):
        raise BuildError(f"{dev.location}: error: device '{dev.path}': a record of {values} values takes a slot "
                         f"of {slot} bytes, which must divide its page of {page} bytes (64 at the most) in a "
                         f"memory of whole pages whose size is a power of two up to 65536 bytes ({size}): fewer "
                         f"values, or another page or size")
    return slot


def device_views(program: Program, board) -> list[DeviceView]:
    """The descriptions of the devices that run the board's drivers (those
    whose types bring handler files for the board run those instead)."""
    mcu = board.part
    specs = board.drivers
    views = []
    for dev in program.devices:
        if handlers.handler_file(dev, board.name) is not None:
            continue
        spec = specs[dev.driver]
        claims = [parse_claim(c) for c in dev.claims]
        items = [_item_c(program, i)[0] for i in dev.items]
        comment = f"{dev.path} ({dev.location})"
        d = dev.driver
        data_names = [program.items[i].name for i in dev.items]
        if d == "analog_in":
            ch = claims[0][1]
            v = DeviceView(dev.id, dev.path, d, dev.location, "el_drv_analog_in_t", f"{{ {ch}u, &{items[0]} }}",
                           spec["header"], {"adc": ch, "pin": mcu.adc[ch]})
        elif d in ("digital_in", "digital_out"):
            pin = claims[0][1]
            reg, mask, _ = _pin_regs(pin)
            v = DeviceView(dev.id, dev.path, d, dev.location, f"el_drv_{d}_t", f"{{ {reg}, {mask}, &{items[0]} }}",
                           spec["header"], {"pin": pin})
        elif d == "pwm_out":
            pin = claims[0][1]
            init, hw = _pwm_init(mcu, pin)
            v = DeviceView(dev.id, dev.path, d, dev.location, "el_drv_pwm_out_t", init + f"&{items[0]} }}",
                           spec["header"], {"pwm": hw})
        elif d == "motor":
            pin = claims[0][1]
            dir_pin = claims[1][1]
            init, hw = _pwm_init(mcu, pin)
            reg, mask, _ = _pin_regs(dir_pin)
            v = DeviceView(dev.id, dev.path, d, dev.location, "el_drv_motor_t",
                           f"{{ {init}(int16_t *)0 }}, {reg}, {mask}, &{items[0]} }}", spec["header"],
                           {"pwm": hw, "dir": dir_pin})
        elif d == "encoder":
            a, b = claims[0][1], claims[1][1]
            ra, ma, _ = _pin_regs(a)
            rb, mb, _ = _pin_regs(b)
            v = DeviceView(dev.id, dev.path, d, dev.location, "el_drv_encoder_t",
                           f"{{ {ra}, {ma}, {rb}, {mb}, &el_dev{dev.id}_state, el_dev{dev.id}_irq_on, &{items[0]} }}",
                           spec["header"], {"pin_a": a, "pin_b": b}, "el_drv_encoder_state_t",
                           f"el_dev{dev.id}_irq_on")
        elif d == "line_camera":
            n = claims[0][1]
            v = DeviceView(dev.id, dev.path, d, dev.location, "el_drv_line_camera_t",
                           f"{{ {n}u, &el_dev{dev.id}_state, &{items[0]} }}", spec["header"],
                           {"uart": n, "baud": int(spec.get("baud", 115200))}, "el_drv_line_camera_state_t")
        elif d == "i2c_temperature":
            bus, addr = claims[0][1], parse_select(dev.claims[0])[1]
            v = DeviceView(dev.id, dev.path, d, dev.location, "el_drv_i2c_temperature_t",
                           f"{{ {bus}u, 0x{addr:02x}u, &{items[0]} }}", spec["header"], {"i2c": bus, "addr": addr})
        elif d in ("i2c_eeprom_log", "spi_eeprom_log"):
            bus, (how, where) = claims[0][1], parse_select(dev.claims[0])
            values = program.items[dev.items[0]].count
            slot = _eeprom_log_slot(dev, values)
            slots = int(dev.params["bytes"][1]) // slot
            record = items[0] if values > 1 else f"&{items[0]}"
            place = f"0x{where:02x}u" if how == "addr" else chip_select(where)
            v = DeviceView(dev.id, dev.path, d, dev.location, f"el_drv_{d}_t",
                           f"{{ {bus}u, {place}, {{ {values}u, {slot}u, {slots}u, {record} }}, "
                           f"&el_dev{dev.id}_state }}", spec["header"], {d[:3]: bus, how: where, "slot": slot},
                           f"el_drv_{d}_state_t")
        else:  # a driver listed in board.toml without generator support
            raise BuildError(f"{dev.location}: error: the avr backend cannot describe devices of driver '{d}' yet")
        v.hw["data"] = data_names
        v.hw["driver"] = d
        v.hw["path"] = dev.path
        views.append(v)
    return views


def _ring_sizes(mcu: Mcu, use: str) -> tuple[int, int]:
    """(RX, TX) ring bytes of a UART by what it carries (at most 256 each)."""
    if use == "modbus-rtu":  # a whole ADU (256 bytes) arrives while a task may run
        return (128, 64) if mcu.small else (255, 128)
    return (32, 4)  # line camera: frames of 4 bytes, listen only


def remote_link(board, res: Resolved) -> list[str]:
    """A remote-execution proxy's link (avr_remote.c), on the first UART no
    device claims; only a proxy build (-DEL_REMOTE_PROXY=1, easylab proxy)
    sees it. A part whose every UART a device claims has no link."""
    mcu = board.part
    free = [n for n in sorted(mcu.uart) if n not in res.uarts]
    lines = ["", "#if defined(EL_REMOTE_PROXY) && EL_REMOTE_PROXY"]
    if not free:
        users = ", ".join(f"uart{n} by {res.uarts[n].get('device', 'a device')}" for n in sorted(res.uarts))
        lines.append(f"#error \"a remote-execution proxy needs a UART for its link: every UART of the {mcu.name} "
                     f"is claimed ({users}); build for another --mcu\"")
    else:
        n = free[0]
        # Rings of the device model's frames (el_remote_config.h), at most 255 bytes.
        lines += [f"#define EL_AVR_REMOTE_UART {n}u /* the proxy's link: uart{n} (pins {', '.join(mcu.uart[n])}) */",
                  '#include "el_remote_config.h"',
                  f"#define EL_AVR_UART{n}_RX (EL_RMT_RX_RING < 255u ? EL_RMT_RX_RING : 255u)",
                  f"#define EL_AVR_UART{n}_TX EL_RMT_TX_RING",
                  f"#define EL_AVR_REMOTE_TX EL_AVR_UART{n}_TX"]
    return lines + ["#endif"]


def config_header(program: Program, board, res: Resolved, release: bool) -> str:
    mcu = board.part
    clock = board.clock_hz
    if program.tick_us < MIN_TICK_US:
        raise BuildError(f"the model's tick of {program.tick_us} us (the gcd of its task periods, offsets and "
                     f"deadlines) is too short for the avr board: at least {MIN_TICK_US} us")
    t = tick_timer(program.tick_us, clock)
    wd = board.watchdog_ms
    if wd not in _WDTO:
        raise BuildError(f"boards/avr/board.toml: watchdog_ms = {wd}: choose one of {', '.join(map(str, _WDTO))}")
    lines = [
        f"/* Generated by EasyLab for board \"avr\", MCU {mcu.name}, model \"{c_comment(program.name)}\". Do not edit. */",
        "#ifndef EL_AVR_CONFIG_H", "#define EL_AVR_CONFIG_H", "",
        f"#define EL_AVR_CONFIG_VERSION {CONFIG_VERSION}",
        f"#define EL_AVR_MCU_NAME \"{mcu.name}\"",
        f"#define EL_AVR_NV_SIZE {mcu.eeprom}u /* EEPROM bytes */", "",
        f"/* LET tick {program.tick_us} us = {t.isrs} x Timer2 period of {t.ocr + 1} x clk/{t.prescale}"
        + (" (exact) */" if t.exact else f" (not exact: drift {t.drift_ppm:+.1f} ppm) */"),
        f"#define EL_AVR_TICK_PRESCALE {t.prescale}u",
        f"#define EL_AVR_TICK_CS {t.cs}u",
        f"#define EL_AVR_TICK_OCR {t.ocr}u",
        f"#define EL_AVR_TICK_ISRS {t.isrs}u",
        f"#define EL_AVR_CLOCK_KHZ {math.ceil(clock / t.prescale / 1000)}u /* fine-clock periods per ms (rounded up) */",
        "", f"#define EL_AVR_WDTO {_WDTO[wd]} /* watchdog: {wd} ms */", ""]
    for n in sorted(res.uarts):
        u = res.uarts[n]
        if u["use"] == "debug" and release:
            lines.append(f"/* uart{n}: the debug interface, absent from release builds */")
            continue
        if u["use"] == "debug":
            # RX: an encoded request (COBS and its delimiter) of the model's largest frame
            # (el_debug_config.h) or the protocol's, which waits there while the response goes out
            # (the host sends one request at a time: WINDOW 1); a ring of n bytes holds n - 1.
            # No TX ring: responses go out straight from the debug server's buffer (avr_interfaces.c).
            frame = "EL_DBG_FRAME" if board.model_sized_debug_buffers else "EL_DBG_MAX_FRAME"
            header = "el_debug_config.h" if board.model_sized_debug_buffers else "el_debug_protocol.h"
            lines.append(f'#include "{header}" /* uart{n}: debug; {frame} */')
            lines.append(f"#define EL_AVR_UART{n}_RX ({frame} + {frame} / 254u + 3u)")
            lines.append(f"#define EL_AVR_UART{n}_TX 0u")
            lines.append(f"#define EL_AVR_DEBUG_UART {n}u")
            lines.append(f"#define EL_AVR_DEBUG_BAUD {int(u.get('baud', 115200))}UL")
            continue
        rx, tx = _ring_sizes(mcu, u["use"])
        lines.append(f"#define EL_AVR_UART{n}_RX {rx}u /* uart{n}: {u['use']} */")
        lines.append(f"#define EL_AVR_UART{n}_TX {tx}u")
        if u["use"] == "modbus-rtu":
            lines.append(f"#define EL_AVR_MODBUS_UART {n}u")
            lines.append(f"#define EL_AVR_MODBUS_TX {tx}u")
    lines += _i2c_config(board, res) + _spi_config(board, res) + remote_link(board, res)
    if board.sim:
        lines += ["", "#define EL_AVR_SIM 1 /* simulation build: instants reported through GPIOR0 */"]
    lines += ["", "#endif /* EL_AVR_CONFIG_H */", ""]
    return "\n".join(lines)


def _i2c_config(board, res: Resolved) -> list[str]:
    """The TWI's settings when a device is on the I2C bus (avr_twi.c)."""
    if ("i2c", 0) not in res.buses:
        return []
    i2c = board.description.table("i2c")
    sda, scl = board.part.i2c[0]
    port = sda[1]
    return ["", f"/* i2c[0] on the TWI: {', '.join(c.owner for c in res.buses[('i2c', 0)])} */",
            "#define EL_AVR_I2C 1", f"#define EL_AVR_I2C_HZ {int(i2c.get('clock_hz', 400000))}UL",
            f"#define EL_I2C_WAIT_US {int(i2c.get('wait_us', 2000))}UL /* the longest wait for a job */",
            f"#define EL_I2C_BUSY_US {int(i2c.get('busy_us', 10000))}UL /* a busy chip is tried again this long */",
            f"#define EL_AVR_I2C_PORT PORT{port} /* SDA {sda}, SCL {scl}: internal pull-ups */",
            f"#define EL_AVR_I2C_PULLUPS (_BV({sda[2]}) | _BV({scl[2]}))"]


_SPI_DIVIDERS = {2: (0, 1), 4: (0, 0), 8: (1, 1), 16: (1, 0), 32: (2, 1), 64: (2, 0), 128: (3, 0)}  # SPR, SPI2X


def _spi_config(board, res: Resolved) -> list[str]:
    """The SPI's settings when a device is on the SPI bus (avr_spi.c): the
    fastest clock F_CPU / 2^k at most the board's."""
    if ("spi", 0) not in res.buses:
        return []
    hz = int(board.description.table("spi").get("clock_hz", 4000000))
    divider = next((k for k in sorted(_SPI_DIVIDERS) if board.clock_hz // k <= hz), 128)
    spr, x2 = _SPI_DIVIDERS[divider]
    sck, mosi, _miso, ss = board.part.spi[0]
    port = sck[1]
    return ["", f"/* spi[0], master: {', '.join(c.owner for c in res.buses[('spi', 0)])} */",
            "#define EL_AVR_SPI 1", f"#define EL_AVR_SPI_HZ {board.clock_hz // divider}UL /* F_CPU / {divider} */",
            f"#define EL_AVR_SPI_SPR {spr}u", f"#define EL_AVR_SPI_2X {x2}u",
            f"#define EL_AVR_SPI_DDR DDR{port} /* SCK {sck}, MOSI {mosi}, SS {ss}: outputs */",
            f"#define EL_AVR_SPI_PORT PORT{port}",
            f"#define EL_AVR_SPI_OUTPUTS (_BV({sck[2]}) | _BV({mosi[2]}) | _BV({ss[2]}))",
            f"#define EL_AVR_SPI_SS _BV({ss[2]})"]


def _pcint(mcu: Mcu, pin: str) -> tuple[int, int] | None:
    for g, pins in enumerate(mcu.pcint_groups):
        if pin in pins:
            return g, pins.index(pin)
    return None


def devices_source(program: Program, board, views: list[DeviceView]) -> str:
    mcu = board.part
    lines = [f"/* Generated by EasyLab for board \"avr\", model \"{c_comment(program.name)}\": the drivers' state and",
             " * interrupt handlers. Do not edit. */",
             "#include \"el_types.h\"", "#include \"el_board.h\"", "#include <avr/interrupt.h>", ""]
    pc_groups: dict[int, list[int]] = {}
    ext: dict[int, list[int]] = {}
    for v in views:
        if v.state_type:
            lines.append(f"{v.state_type} el_dev{v.id}_state; /* {v.path} */")
        if v.driver == "encoder":
            body = []
            for pin in (v.hw["pin_a"], v.hw["pin_b"]):
                if pin in mcu.ext_int:
                    n = mcu.ext_int[pin]
                    reg = "EICRA" if n < 4 else "EICRB"
                    body.append(f"    {reg} = (uint8_t)(({reg} & (uint8_t)~(3u << {2 * (n % 4)})) | "
                                f"(1u << {2 * (n % 4)})); /* INT{n}: any edge */")
                    body.append(f"    EIFR = _BV({n});")
                    body.append(f"    EIMSK |= _BV({n}); /* {pin} */")
                    ext.setdefault(n, []).append(v.id)
                else:
                    g, bit = _pcint(mcu, pin)
                    body.append(f"    PCMSK{g} |= _BV({bit}); /* {pin} */")
                    body.append(f"    PCIFR = _BV(PCIF{g});")
                    body.append(f"    PCICR |= _BV(PCIE{g});")
                    pc_groups.setdefault(g, []).append(v.id)
            lines.append(f"void {v.irq_fn}(void)")
            lines.append("{")
            lines += body
            lines.append("}")
    lines.append("")
    for g in sorted(pc_groups):
        ids = sorted(set(pc_groups[g]))
        lines.append(f"ISR(PCINT{g}_vect)")
        lines.append("{")
        lines += [f"    el_drv_encoder_update(&el_dev{i});" for i in ids]
        lines.append("}")
    for n in sorted(ext):
        ids = sorted(set(ext[n]))
        lines.append(f"ISR(INT{n}_vect)")
        lines.append("{")
        lines += [f"    el_drv_encoder_update(&el_dev{i});" for i in ids]
        lines.append("}")
    if len(lines) and not any(v.state_type for v in views) and not pc_groups and not ext:
        lines.append("typedef int el_avr_devices_empty_t; /* ISO C wants something here */")
    lines.append("")
    return "\n".join(lines)


def hw_map(program: Program, board, res: Resolved, views: list[DeviceView]) -> dict:
    mcu = board.part
    clock = board.clock_hz
    t = tick_timer(program.tick_us, clock)
    return {
        "format": "easylab-avr-hw-map", "version": 1,
        "model": program.name, "program_id": f"0x{program.program_id:08x}", "mcu": mcu.name, "clock_hz": clock,
        "tick_us": program.tick_us,
        "tick_timer": {"timer": 2, "prescale": t.prescale, "ocr": t.ocr, "interrupts_per_tick": t.isrs,
                       "exact": t.exact, "drift_ppm": round(t.drift_ppm, 3)},
        "uarts": {str(n): {**u, "pins": mcu.uart[n]} for n, u in sorted(res.uarts.items())},
        "devices": [v.hw for v in views],
        "pins": {pin: c.text + " by " + c.owner for pin, c in sorted(res.physical.items())},
    }


def files(program: Program, board, res: Resolved, release: bool) -> dict[str, str]:
    """The board's generated files: {file name: text}."""
    views = device_views(program, board)
    return {
        "el_avr_config.h": config_header(program, board, res, release),
        "el_avr_devices.h": devices_header(program, views, "avr", "boards/avr/drivers/", ("<avr/io.h>",)),
        "el_avr_devices.c": devices_source(program, board, views),
        "hw_map.json": json.dumps(hw_map(program, board, res, views), indent=2) + "\n",
    }
