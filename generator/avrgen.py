"""The AVR board's backend (boards/avr/, docs/boards.md).

What ``easylab build --board avr [--mcu M] [--sim]`` adds to the portable
C backend, all driven by boards/avr/board.toml:

- ``configure``: the MCU (its memories, resources, avr-gcc flags);
- ``check``: every resource claim against the MCU (a pin used twice through
  different resources, a resource the part lacks, PWM on a pin without a
  timer channel) and every device against the board's drivers, with all
  problems in one error, each at the claiming device's or interface's
  source line;
- ``produce``: el_avr_config.h (the tick timer, UART rings, watchdog,
  interfaces' UARTs), el_avr_devices.h and .c (one ``static const``
  description per device for its driver, the drivers' interrupt handlers)
  and hw_map.json (device data -> pins, ADC channels, UARTs);
- ``compile``: avr-gcc, the .hex (without simavr's .mmcu section) and the
  flash and RAM use against the part's sizes, failing when it does not fit;
- ``build_simulator``: for ``--sim`` builds, the simavr harness of sim/ with
  the model's tables (sim_model.c: item names, types and RAM addresses,
  device data -> hardware), compiled with gcc against libsimavr.

It reads the IR only (and, for the source line of an interface, the model
file the IR names).
"""

from __future__ import annotations

import dataclasses
import json
import math
import re
import shutil
import subprocess
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

from .boards import Board, runtime_dir
from .ir import Program

CONFIG_VERSION = 1
# The shortest LET tick the board takes: the tick interrupt and the
# dispatcher's instant take some hundred cycles.
MIN_TICK_US = 50

# Timer2's clock selects (CS2 bits) by prescaler.
_TIMER2_PRESCALERS = {1: 1, 8: 2, 32: 3, 64: 4, 128: 5, 256: 6, 1024: 7}
_WDTO = {15: "WDTO_15MS", 30: "WDTO_30MS", 60: "WDTO_60MS", 120: "WDTO_120MS", 250: "WDTO_250MS",
         500: "WDTO_500MS", 1000: "WDTO_1S", 2000: "WDTO_2S", 4000: "WDTO_4S", 8000: "WDTO_8S"}
_CLAIM = re.compile(r'^([A-Za-z_]+)\[(?:"([^"]*)"|(\d+))\]$')
_PIN = re.compile(r"^P([A-L])([0-7])$")


def _error(message: str):
    from .build import BuildError  # build imports this module lazily

    return BuildError(message)


# ====================================================================== configuration


@dataclass
class Mcu:
    """One MCU of board.toml."""

    name: str
    title: str
    flash: int
    bootloader: int
    ram: int
    eeprom: int
    avrdude_part: str
    programmer: str
    upload_baud: int
    pins: list[str]
    pcint_groups: list[list[str]]
    ext_int: dict[str, int]
    uart: dict[int, list[str]]
    adc: dict[int, str]
    pwm: dict[str, tuple[int, str]]
    reserved_pwm: dict[str, str]
    wide_timers: list[int]
    unavailable: dict[str, str] = field(default_factory=dict)

    @property
    def small(self) -> bool:
        return self.ram <= 2048


def mcus(board: Board) -> dict[str, Mcu]:
    out = {}
    for name, m in board.raw.get("mcu", {}).items():
        out[name] = Mcu(name, m.get("title", name), int(m["flash"]), int(m.get("bootloader", 0)), int(m["ram"]),
                        int(m["eeprom"]), m["avrdude_part"], m["programmer"], int(m.get("upload_baud", 115200)),
                        list(m["pins"]), [list(g) for g in m.get("pcint_groups", [])],
                        {k: int(v) for k, v in m.get("int", {}).items()},
                        {int(k): list(v) for k, v in m.get("uart", {}).items()},
                        {int(k): str(v) for k, v in m.get("adc", {}).items()},
                        {k: (int(v[0]), str(v[1])) for k, v in m.get("pwm", {}).items()},
                        dict(m.get("reserved_pwm", {})), [int(t) for t in m.get("sixteen_bit_timers", [])],
                        dict(m.get("unavailable", {})))
    return out


def configure(board: Board, mcu: str | None = None, sim: bool = False) -> Board:
    """The board for one MCU: its flags, its EEPROM as the persist store."""
    known = mcus(board)
    name = (mcu or board.raw.get("default_mcu", "")).lower()
    if name not in known:
        raise _error(f"board '{board.name}' has no MCU '{mcu}' (MCUs: {', '.join(sorted(known))})")
    m = known[name]
    raw = dict(board.raw)
    raw["nv_size"] = m.eeprom
    raw["selected_mcu"] = name
    raw["sim"] = bool(sim)
    clock = int(board.raw.get("clock_hz", 16000000))
    cflags = [f"-mmcu={name}", f"-DF_CPU={clock}UL", *board.cflags]
    return dataclasses.replace(board, cflags=cflags, raw=raw)


def selected(board: Board) -> Mcu:
    return mcus(board)[board.raw["selected_mcu"]]


# ====================================================================== claims and drivers


@dataclass
class Claim:
    kind: str
    index: object  # str (pin names) or int
    text: str
    owner: str  # "device 'led'" / "interface 'debug'"
    location: str  # file:line or ""

    def where(self) -> str:
        return f"{self.location}: " if self.location else ""


def parse_claim(text: str) -> tuple[str, object] | None:
    m = _CLAIM.match(text.strip())
    if m is None:
        return None
    return m.group(1), (m.group(2) if m.group(2) is not None else int(m.group(3)))


def _interface_location(program: Program, kind: str) -> str:
    """file:line of an interface's declaration: the IR keeps none, so find
    the line in the model file (a best effort; '' when not found)."""
    word = {"debug": r"debug", "modbus-rtu": r"modbus\s+rtu", "modbus-tcp": r"modbus\s+tcp"}[kind]
    try:
        text = Path(program.source).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return ""
    for n, line in enumerate(text.splitlines(), 1):
        if re.match(rf"\s*{word}\b", line):
            return f"{program.source}:{n}"
    return ""


@dataclass
class Resolved:
    """What the claims of one build come to."""

    problems: list[str] = field(default_factory=list)
    uarts: dict[int, dict] = field(default_factory=dict)  # uart -> {"use": ..., "baud": ..., "parity": ...}
    physical: dict[str, Claim] = field(default_factory=dict)  # pin -> first claim


def _physical_pins(mcu: Mcu, claim: Claim, problems: list[str]) -> list[str] | None:
    """The pins behind a claim, or None (a problem was recorded)."""
    kind, idx = claim.kind, claim.index
    part = mcu.name
    if kind == "pin":
        if not isinstance(idx, str) or idx not in mcu.pins:
            why = (f"the {part}'s {idx} is {mcu.unavailable[idx]}" if idx in mcu.unavailable
                   else f"the {part} has no pin {idx}")
            problems.append(f"{claim.where()}error: {claim.owner} claims {claim.text}, but {why}; pins: "
                            f"{_ranges(mcu.pins)}")
            return None
        return [idx]
    if kind == "pwm":
        if not isinstance(idx, str):
            problems.append(f"{claim.where()}error: {claim.owner} claims {claim.text}: a PWM output is named by "
                            f"its pin, as in pwm[\"{next(iter(mcu.pwm))}\"]")
            return None
        if idx in mcu.reserved_pwm:
            problems.append(f"{claim.where()}error: {claim.owner} claims {claim.text}, but {idx}'s timer output "
                            f"({mcu.reserved_pwm[idx]}) belongs to Timer2, which runs the LET tick on this board; "
                            f"PWM pins of the {part}: {', '.join(sorted(mcu.pwm))}")
            return None
        if idx not in mcu.pwm:
            what = "has no timer output" if idx in mcu.pins else "is not a pin of the " + part
            problems.append(f"{claim.where()}error: {claim.owner} claims {claim.text}, but {idx} {what}; PWM pins "
                            f"of the {part}: {', '.join(sorted(mcu.pwm))}")
            return None
        return [idx]
    if kind == "adc":
        if not isinstance(idx, int) or idx not in mcu.adc:
            problems.append(f"{claim.where()}error: {claim.owner} claims {claim.text}, but the {part} has no ADC "
                            f"channel {idx} (channels 0..{max(mcu.adc)})")
            return None
        return [mcu.adc[idx]]
    if kind == "uart":
        if not isinstance(idx, int) or idx not in mcu.uart:
            have = ", ".join(f"uart{n}" for n in sorted(mcu.uart))
            problems.append(f"{claim.where()}error: {claim.owner} claims {claim.text}, but the {part} has no UART "
                            f"{idx} (it has {have}{' only' if len(mcu.uart) == 1 else ''})")
            return None
        return list(mcu.uart[idx])
    problems.append(f"{claim.where()}error: {claim.owner} claims {claim.text}, but the avr board has no resource "
                    f"kind '{kind}' (kinds: pin, pwm, adc, uart)")
    return None


def _ranges(pins: list[str]) -> str:
    """PB0..PB5, PC0..PC5, ..."""
    groups: dict[str, list[int]] = {}
    for p in pins:
        m = _PIN.match(p)
        if m:
            groups.setdefault(m.group(1), []).append(int(m.group(2)))
    parts = []
    for port, bits in groups.items():
        parts.append(f"P{port}{min(bits)}..P{port}{max(bits)}" if len(bits) > 1 else f"P{port}{bits[0]}")
    return ", ".join(parts)


def _driver_specs(board: Board) -> dict[str, dict]:
    return board.raw.get("drivers", {})


def resolve(program: Program, board: Board) -> Resolved:
    """Check every claim and device of the program against the MCU."""
    mcu = selected(board)
    res = Resolved()
    claims: list[tuple[Claim, object]] = []  # (claim, device or interface)
    for dev in program.devices:
        for text in dev.claims:
            parsed = parse_claim(text)
            if parsed is None:
                res.problems.append(f"{dev.location}: error: device '{dev.path}' claims {text}, which the avr "
                                    f"board cannot read")
                continue
            claims.append((Claim(parsed[0], parsed[1], text, f"device '{dev.path}'", dev.location), dev))
    for iface in program.interfaces:
        loc = _interface_location(program, iface.kind)
        if iface.kind == "modbus-tcp":
            res.problems.append(f"{loc + ': ' if loc else ''}error: the Modbus TCP interface needs a network, and "
                                f"the avr board has none: use 'modbus rtu on uartN'")
            continue
        if iface.resource is None:
            continue
        parsed = parse_claim(iface.resource)
        if parsed is None:
            continue
        claims.append((Claim(parsed[0], parsed[1], iface.resource, f"interface '{iface.kind.replace('-', ' ')}'",
                             loc), iface))
    for claim, _owner in claims:
        pins = _physical_pins(mcu, claim, res.problems)
        if pins is None:
            continue
        for pin in pins:
            if pin in res.physical and res.physical[pin].text != claim.text:
                first = res.physical[pin]
                res.problems.append(
                    f"{claim.where()}error: pin {pin} is claimed twice on the {mcu.name}: as {claim.text} by "
                    f"{claim.owner} and as {first.text} by {first.owner}"
                    + (f" ({first.location})" if first.location else "")
                    + "; each pin has one owner: choose another pin, channel or UART")
            elif pin not in res.physical:
                res.physical[pin] = claim
    # Drivers.
    specs = _driver_specs(board)
    for dev in program.devices:
        spec = specs.get(dev.driver)
        if spec is None:
            res.problems.append(
                f"{dev.location}: error: device '{dev.path}' needs the driver '{dev.driver}', which the avr board "
                f"does not have (drivers: {', '.join(sorted(specs))}); add "
                f"boards/avr/drivers/el_drv_{dev.driver}.h and its [drivers.{dev.driver}] entry in "
                f"boards/avr/board.toml (docs/boards.md, 'Adding a driver')")
            continue
        kinds = [parse_claim(c)[0] if parse_claim(c) else "?" for c in dev.claims]
        if kinds != list(spec.get("claims", [])):
            res.problems.append(f"{dev.location}: error: device '{dev.path}': the avr driver '{dev.driver}' takes "
                                f"the claims {', '.join(k + '[...]' for k in spec['claims'])} in this order, not "
                                f"{', '.join(dev.claims) or 'none'}")
            continue
        data = [f"{'out' if program.items[i].kind == 'dev_out' else 'in'} {program.items[i].type.name}"
                for i in dev.items]
        if data != list(spec.get("data", [])) or any(program.items[i].count != 1 for i in dev.items):
            res.problems.append(f"{dev.location}: error: device '{dev.path}': the avr driver '{dev.driver}' "
                                f"drives the data {', '.join(spec['data'])} (one value each), not "
                                f"{', '.join(data) or 'none'}")
            continue
        if spec.get("interrupt_pins"):
            for c in dev.claims:
                kind, pin = parse_claim(c)
                if kind == "pin" and pin in mcu.pins and pin not in mcu.ext_int and \
                        not any(pin in g for g in mcu.pcint_groups):
                    res.problems.append(f"{dev.location}: error: device '{dev.path}' ({dev.driver}) needs an "
                                        f"interrupt on {pin}, which has neither a pin-change nor an external "
                                        f"interrupt on the {mcu.name}")
    # The UARTs in use.
    for iface in program.interfaces:
        if iface.kind not in ("debug", "modbus-rtu") or iface.resource is None:
            continue
        parsed = parse_claim(iface.resource)
        if parsed and parsed[0] == "uart" and parsed[1] in mcu.uart:
            res.uarts[parsed[1]] = {"use": iface.kind, **iface.settings}
    for dev in program.devices:
        if dev.driver == "line_camera" and dev.driver in specs:
            parsed = parse_claim(dev.claims[0]) if dev.claims else None
            if parsed and parsed[0] == "uart" and parsed[1] in mcu.uart:
                res.uarts[parsed[1]] = {"use": "line_camera", "baud": int(specs["line_camera"].get("baud", 115200)),
                                        "device": dev.path}
    return res


def check(program: Program, board: Board) -> Resolved:
    res = resolve(program, board)
    if res.problems:
        mcu = selected(board)
        count = len(res.problems)
        raise _error(f"the model does not fit the avr board with the {mcu.name} "
                     f"({count} problem{'s' if count != 1 else ''}):\n" + "\n".join(res.problems))
    return res


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


@dataclass
class DeviceView:
    """One device's description for its driver (C) and the harness."""

    id: int
    path: str
    driver: str
    location: str
    c_type: str
    init: str
    header: str
    hw: dict  # for hw_map.json and the harness
    state_type: str | None = None
    irq_fn: str | None = None


def _item_c(program: Program, item_id: int) -> tuple[str, str]:
    from .cgen import ident

    it = program.items[item_id]
    return f"el_i{it.id}_{ident(it.name)}", it.type.c_name


def _pin_regs(pin: str) -> tuple[str, str, int]:
    m = _PIN.match(pin)
    return f"&PIN{m.group(1)}", f"_BV({m.group(2)})", int(m.group(2))


def _pwm_init(mcu: Mcu, pin: str) -> tuple[str, dict]:
    timer, ch = mcu.pwm[pin]
    wide = timer in mcu.wide_timers
    com = {"A": 7, "B": 5, "C": 3}[ch]
    ocr = f"&OCR{timer}{ch}L" if wide else f"&OCR{timer}{ch}"
    pin_reg, mask, _ = _pin_regs(pin)
    init = (f"{{ &TCCR{timer}A, (volatile uint8_t *){ocr}, _BV({com}), {1 if wide else 0}u, {pin_reg}, {mask}, ")
    return init, {"timer": timer, "channel": ch, "pin": pin}


def device_views(program: Program, board: Board) -> list[DeviceView]:
    mcu = selected(board)
    specs = _driver_specs(board)
    views = []
    for dev in program.devices:
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
        else:  # a driver listed in board.toml without generator support
            raise _error(f"{dev.location}: error: the avr backend cannot describe devices of driver '{d}' yet")
        v.hw["data"] = data_names
        v.hw["driver"] = d
        v.hw["path"] = dev.path
        views.append(v)
    return views


def _ring_sizes(mcu: Mcu, use: str) -> tuple[int, int]:
    """(RX, TX) ring bytes of a UART by what it carries (at most 256 each)."""
    if use == "debug":  # a whole encoded frame (163 bytes) must fit in TX
        return (64, 168) if mcu.small else (192, 255)
    if use == "modbus-rtu":  # a whole ADU (256 bytes) arrives while a task may run
        return (128, 64) if mcu.small else (255, 128)
    return (32, 4)  # line camera: frames of 4 bytes, listen only


def config_header(program: Program, board: Board, res: Resolved, release: bool) -> str:
    mcu = selected(board)
    clock = int(board.raw.get("clock_hz", 16000000))
    if program.tick_us < MIN_TICK_US:
        raise _error(f"the model's tick of {program.tick_us} us (the gcd of its task periods, offsets and "
                     f"deadlines) is too short for the avr board: at least {MIN_TICK_US} us")
    t = tick_timer(program.tick_us, clock)
    wd = int(board.raw.get("watchdog_ms", 2000))
    if wd not in _WDTO:
        raise _error(f"boards/avr/board.toml: watchdog_ms = {wd}: choose one of {', '.join(map(str, _WDTO))}")
    lines = [
        f"/* Generated by EasyLab for board \"avr\", MCU {mcu.name}, model \"{program.name}\". Do not edit. */",
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
        rx, tx = _ring_sizes(mcu, u["use"])
        lines.append(f"#define EL_AVR_UART{n}_RX {rx}u /* uart{n}: {u['use']} */")
        lines.append(f"#define EL_AVR_UART{n}_TX {tx}u")
        if u["use"] == "debug":
            lines.append(f"#define EL_AVR_DEBUG_UART {n}u")
            lines.append(f"#define EL_AVR_DEBUG_BAUD {int(u.get('baud', 115200))}UL")
        elif u["use"] == "modbus-rtu":
            lines.append(f"#define EL_AVR_MODBUS_UART {n}u")
            lines.append(f"#define EL_AVR_MODBUS_TX {tx}u")
    if board.raw.get("sim"):
        lines += ["", "#define EL_AVR_SIM 1 /* simulation build: instants reported through GPIOR0 */"]
    lines += ["", "#endif /* EL_AVR_CONFIG_H */", ""]
    return "\n".join(lines)


def devices_header(program: Program, views: list[DeviceView]) -> str:
    headers = sorted({v.header for v in views})
    lines = [f"/* Generated by EasyLab for board \"avr\", model \"{program.name}\": the devices, each a constant",
             " * description for its driver (boards/avr/drivers/). Do not edit. */",
             "#ifndef EL_AVR_DEVICES_H", "#define EL_AVR_DEVICES_H", "",
             "#include \"el_types.h\"", "#include <avr/io.h>"]
    lines += [f"#include \"{h}\"" for h in headers]
    lines.append("")
    seen = set()
    for v in views:
        dev = program.devices[v.id]
        for i in dev.items:
            name, ctype = _item_c(program, i)
            if name not in seen:
                seen.add(name)
                lines.append(f"extern {ctype} {name};")
    lines.append("")
    for v in views:
        if v.state_type:
            lines.append(f"extern {v.state_type} el_dev{v.id}_state;")
        if v.irq_fn:
            lines.append(f"void {v.irq_fn}(void);")
        lines.append(f"static const {v.c_type} el_dev{v.id} = {v.init}; /* {v.path} ({v.location}) */")
    lines += ["", "#endif /* EL_AVR_DEVICES_H */", ""]
    return "\n".join(lines)


def _pcint(mcu: Mcu, pin: str) -> tuple[int, int] | None:
    for g, pins in enumerate(mcu.pcint_groups):
        if pin in pins:
            return g, pins.index(pin)
    return None


def devices_source(program: Program, board: Board, views: list[DeviceView]) -> str:
    mcu = selected(board)
    lines = [f"/* Generated by EasyLab for board \"avr\", model \"{program.name}\": the drivers' state and",
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


def hw_map(program: Program, board: Board, res: Resolved, views: list[DeviceView]) -> dict:
    mcu = selected(board)
    clock = int(board.raw.get("clock_hz", 16000000))
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


def produce(program: Program, board: Board, out_dir: Path, release: bool, res: Resolved) -> list[Path]:
    views = device_views(program, board)
    files = {
        "el_avr_config.h": config_header(program, board, res, release),
        "el_avr_devices.h": devices_header(program, views),
        "el_avr_devices.c": devices_source(program, board, views),
        "hw_map.json": json.dumps(hw_map(program, board, res, views), indent=2) + "\n",
    }
    from .build import write_files  # build imports this module lazily

    return write_files(out_dir, files)


# ====================================================================== the cross build


@dataclass
class SizeReport:
    flash: int  # .text + .data (initialised data is stored in flash)
    ram: int  # .data + .bss + .noinit
    eeprom: int
    flash_max: int
    ram_max: int
    lines: list[str]


def _tool(board: Board, key: str, default: str) -> str:
    return board.raw.get("toolchain", {}).get(key, default)


def _run(cmd: list[str], what: str) -> subprocess.CompletedProcess:
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True)
    except FileNotFoundError:
        raise _error(f"{cmd[0]} is not installed (Debian packages: gcc-avr binutils-avr avr-libc)") from None
    if proc.returncode != 0:
        raise _error(f"{what} failed:\n{proc.stdout}{proc.stderr}".rstrip())
    return proc


def sections(board: Board, elf: Path) -> dict[str, int]:
    """Section sizes of an ELF (avr-size -A)."""
    out = _run([_tool(board, "size", "avr-size"), "-A", str(elf)], "avr-size").stdout
    sizes = {}
    for line in out.splitlines():
        parts = line.split()
        if len(parts) >= 2 and parts[0].startswith(".") and parts[1].isdigit():
            sizes[parts[0]] = int(parts[1])
    return sizes


def size_report(board: Board, elf: Path) -> SizeReport:
    mcu = selected(board)
    s = sections(board, elf)
    flash = s.get(".text", 0) + s.get(".data", 0)
    ram = s.get(".data", 0) + s.get(".bss", 0) + s.get(".noinit", 0)
    eeprom = s.get(".eeprom", 0)
    flash_max = mcu.flash - mcu.bootloader
    lines = [f"{mcu.name}: flash {flash} of {flash_max} bytes ({100.0 * flash / flash_max:.1f} %"
             + (f", {mcu.flash} minus {mcu.bootloader} for the bootloader" if mcu.bootloader else "") + "), "
             f"RAM {ram} of {mcu.ram} bytes ({100.0 * ram / mcu.ram:.1f} %, static data; the stack uses the rest)"]
    return SizeReport(flash, ram, eeprom, flash_max, mcu.ram, lines)


# Bytes of RAM left for the stack at the least: interrupt handlers, the
# dispatcher and the deepest actor call chain.
STACK_RESERVE = 256


def compile(program: Program, board: Board, out_dir: Path, generated: list[Path], extra_cflags: list[str] | None,
            cc: str | None, release: bool, schedule: str | None = None) -> tuple[Path, SizeReport]:
    """Compile and link for the MCU; write NAME.elf and NAME.hex; check
    that it fits."""
    compiler = cc or board.cc
    if shutil.which(compiler) is None:
        raise _error(f"the C compiler '{compiler}' of board 'avr' is not installed (Debian packages: gcc-avr "
                     f"avr-libc binutils-avr)")
    runtime = sorted(p for p in runtime_dir().glob("*.c") if not (release and p.name.startswith("el_debug")))
    sources = [p for p in generated if p.suffix == ".c"] + runtime + [board.path / s for s in board.sources]
    includes = [f"-I{out_dir}", f"-I{runtime_dir()}"] + [f"-I{board.path / d}" for d in board.include_dirs]
    mode = ["-DEL_RELEASE=1"] if release else ["-DEL_DEBUG=1"]
    flags = [*board.cflags, *mode, *(extra_cflags or []), *includes]
    objdir = out_dir / "obj"
    objdir.mkdir(exist_ok=True)

    def one(src: Path) -> tuple[Path, subprocess.CompletedProcess]:
        obj = objdir / (src.stem + ("_gen" if src.parent == out_dir else "") + ".o")
        return obj, subprocess.run([compiler, *flags, "-c", "-o", str(obj), str(src)], capture_output=True,
                                   text=True)

    with ThreadPoolExecutor(max_workers=4) as pool:
        results = list(pool.map(one, sources))
    failed = [p for _, p in results if p.returncode != 0]
    if failed:
        raise _error(f"{compiler} failed:\n" + "".join(p.stdout + p.stderr for p in failed).rstrip())
    elf = out_dir / f"{program.name}.elf"
    keep = []
    if board.raw.get("sim"):
        # Every item and chart stays in a simulation build, even one no code
        # reads: the harness traces it from RAM.
        from .cgen import ident
        keep = [f"-Wl,--undefined=el_i{it.id}_{ident(it.name)}" for it in program.items]
        keep += [f"-Wl,--undefined=el_c{c.id}_active" for c in program.charts]
        keep.append("-Wl,--undefined=el_avr_sim_tick")
    link = [compiler, f"-mmcu={selected(board).name}", "-Os", "-o", str(elf), *[str(o) for o, _ in results],
            *board.ldflags, *keep]
    proc = subprocess.run(link, capture_output=True, text=True)
    measured = elf
    if proc.returncode != 0:
        text = proc.stdout + proc.stderr
        if "not within region" not in text and "overflowed by" not in text:
            raise _error(f"linking with {compiler} failed:\n{text}".rstrip())
        # Too big for the part: link again into memories of any size, only
        # to measure by how much.
        measured = out_dir / f"{program.name}.oversize.elf"
        _run(link[:4] + [str(measured)] + link[5:] + ["-Wl,--defsym=__DATA_REGION_LENGTH__=0xffa0",
                                                      "-Wl,--defsym=__TEXT_REGION_LENGTH__=0x400000"],
             "measuring link")
        if elf.exists():
            elf.unlink()
    report = size_report(board, measured)
    mcu = selected(board)
    problem = None
    if report.flash > report.flash_max:
        problem = _not_fit(program, board, "text", report.flash - report.flash_max, schedule, release)
    elif report.ram + STACK_RESERVE > mcu.ram:
        problem = _not_fit(program, board, "data", report.ram + STACK_RESERVE - mcu.ram, schedule, release)
        problem += "\n" + _ram_users(board, measured, [o for o, _ in results])
    if measured != elf:
        measured.unlink()
    if problem is not None:
        if elf.exists():
            elf.unlink()
        raise _error("\n".join(report.lines) + "\n" + problem)
    hexfile = out_dir / f"{program.name}.hex"
    _run([_tool(board, "objcopy", "avr-objcopy"), "-O", "ihex", "-R", ".eeprom", "-R", ".mmcu", "-R", ".fuse",
          "-R", ".lock", "-R", ".signature", str(elf), str(hexfile)], "avr-objcopy")
    return elf, report


def _ram_users(board: Board, elf: Path, objects: list[Path], top: int = 6) -> str:
    """The biggest variables in RAM, with the file each comes from."""
    nm = _tool(board, "nm", "avr-nm")
    owner: dict[str, str] = {}
    for obj in objects:
        out = subprocess.run([nm, "--defined-only", str(obj)], capture_output=True, text=True).stdout
        for line in out.splitlines():
            parts = line.split()
            if len(parts) == 3 and parts[1] in "bBdDrR":
                owner.setdefault(parts[2], obj.stem.removesuffix("_gen") + ".c")
    syms = sorted(((size, name) for name, (_addr, size) in _symbols(board, elf).items() if size), reverse=True)
    rows = [f"{name} {size} B ({owner.get(name, '?')})" for size, name in syms[:top]]
    return "largest in RAM: " + ", ".join(rows)


def _not_fit(program: Program, board: Board, region: str, over: int, schedule: str | None, release: bool) -> str:
    mcu = selected(board)
    if region == "text":
        msg = (f"error: the program does not fit the {mcu.name}'s flash ({mcu.flash - mcu.bootloader} bytes "
               f"for programs): {over} bytes too many")
    else:
        msg = (f"error: the program does not fit the {mcu.name}'s {mcu.ram} bytes of RAM: {over} bytes too many "
               f"(static data plus {STACK_RESERVE} bytes kept for the stack)")
        buffered = [df for df in program.dataflows if df.buffers]
        if buffered and schedule != "min-buffer":
            def buffer_bytes(df) -> int:
                return sum(b.size * max(1, (getattr(b.type, "bits", 8) or 8) // 8) for b in df.buffers)
            biggest = max(buffered, key=buffer_bytes)
            msg += (f"; dataflow '{biggest.name}' ({biggest.schedule_kind} schedule) keeps {buffer_bytes(biggest)} "
                    f"bytes of tokens: try --schedule min-buffer (smaller buffers, a longer schedule)")
        if not release and any(i.kind == "debug" for i in program.interfaces):
            msg += "; the debug interface's buffers take about 1 KB: a --release build has none"
    bigger = [m for m in mcus(board).values() if (m.ram if region != "text" else m.flash) >
              (mcu.ram if region != "text" else mcu.flash)]
    if bigger:
        msg += f"; or build for --mcu {bigger[0].name}"
    return msg


# ====================================================================== avrdude


def avrdude_command(board: Board, hexfile: str, port: str, programmer: str | None = None,
                    baud: int | None = None) -> str:
    mcu = selected(board)
    template = board.raw.get("flash", {}).get("command",
                                              "avrdude -p {part} -c {programmer} -P {port} -b {baud} -D "
                                              "-U flash:w:{hex}:i")
    return template.format(part=mcu.avrdude_part, programmer=programmer or mcu.programmer, port=port,
                           baud=baud or mcu.upload_baud, hex=hexfile)


# ====================================================================== the simulator


def _symbols(board: Board, elf: Path) -> dict[str, tuple[int, int]]:
    """name -> (data address, size) of the ELF's RAM symbols."""
    out = _run([_tool(board, "nm", "avr-nm"), "-S", "--defined-only", str(elf)], "avr-nm").stdout
    syms = {}
    for line in out.splitlines():
        parts = line.split()
        if len(parts) == 4:
            addr, size, kind, name = parts
            a = int(addr, 16)
            if a >= 0x800000 and a < 0x810000:
                syms[name] = (a - 0x800000, int(size, 16))
    return syms


def _c_str(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


_TYPE_ENUM = {"bool": "EL_T_BOOL", "int8": "EL_T_I8", "uint8": "EL_T_U8", "int16": "EL_T_I16",
              "uint16": "EL_T_U16", "int32": "EL_T_I32", "uint32": "EL_T_U32", "float32": "EL_T_F32",
              "time": "EL_T_TIME"}
_KIND_ENUM = {"param": "EL_K_PARAM", "var": "EL_K_VAR", "dev_out": "EL_K_DEV_OUT", "dev_in": "EL_K_DEV_IN"}
_TYPE_BYTES = {"bool": 1, "int8": 1, "uint8": 1, "int16": 2, "uint16": 2, "int32": 4, "uint32": 4,
               "float32": 4, "time": 4}


def sim_model_source(program: Program, board: Board, elf: Path) -> str:
    """The harness's view of one build: the el_model.h tables (names, types,
    counts) over host-side mirrors, each item's RAM address in the MCU, and
    how device data reach the hardware (sim/sim_model.h)."""
    from .cgen import ident

    mcu = selected(board)
    syms = _symbols(board, elf)
    res = resolve(program, board)
    views = {v.id: v for v in device_views(program, board)}
    lines = [f"/* Generated by EasyLab: the simavr harness's tables for model \"{program.name}\" on the "
             f"{mcu.name}. */", "#include \"sim_model.h\"", ""]
    missing = []
    for it in program.items:
        n = it.count
        lines.append(f"static {it.type.c_name} m_i{it.id}[{n}];")
    for c in program.charts:
        lines.append(f"static uint8_t m_c{c.id}[{max(1, len(c.steps))}];")
        lines.append(f"static const char *const m_c{c.id}_steps[{max(1, len(c.steps))}] = "
                     f"{{ {', '.join(_c_str(s.name) for s in c.steps) or _c_str('')} }};")
    lines.append("")
    lines.append(f"const char el_model_name[] = {_c_str(program.name)};")
    lines.append(f"const uint32_t el_program_id = 0x{program.program_id:08x}UL;")
    lines.append(f"const uint32_t el_tick_us = {program.tick_us}UL;")
    lines.append(f"const uint32_t el_hyperperiod_ticks = {program.hyperperiod}UL;")
    lines.append(f"const el_item_t el_items[{max(1, len(program.items))}] = {{")
    for it in program.items:
        dev = it.device if it.device is not None else "EL_NO_DEVICE"
        lines.append(f"    {{ {_c_str(it.name)}, m_i{it.id}, {_TYPE_ENUM[it.type.name]}, {_KIND_ENUM[it.kind]}, "
                     f"{dev}, {it.count}u }},")
    if not program.items:
        lines.append("    { \"\", 0, 0u, 0u, EL_NO_DEVICE, 0u },")
    lines.append("};")
    lines.append(f"const uint16_t el_item_count = {len(program.items)}u;")
    lines.append(f"const el_device_t el_devices[{max(1, len(program.devices))}] = {{")
    for d in program.devices:
        lines.append(f"    {{ {_c_str(d.path)}, {_c_str(d.driver)} }},")
    if not program.devices:
        lines.append("    { \"\", \"\" },")
    lines.append("};")
    lines.append(f"const uint8_t el_device_count = {len(program.devices)}u;")
    lines.append(f"const el_chart_t el_charts[{max(1, len(program.charts))}] = {{")
    for c in program.charts:
        lines.append(f"    {{ {_c_str(c.name)}, {len(c.steps)}u, m_c{c.id}_steps, m_c{c.id} }},")
    if not program.charts:
        lines.append("    { \"\", 0u, (const char *const *)0, (const uint8_t *)0 },")
    lines.append("};")
    lines.append(f"const uint8_t el_chart_count = {len(program.charts)}u;")
    lines.append("")
    # RAM addresses in the MCU.
    lines.append(f"const sim_addr_t sim_item_addr[{max(1, len(program.items))}] = {{")
    for it in program.items:
        sym = f"el_i{it.id}_{ident(it.name)}"
        addr, _size = syms.get(sym, (0xFFFF, 0))
        if sym not in syms:
            missing.append(sym)
        lines.append(f"    {{ 0x{addr:04x}u, {_TYPE_BYTES[it.type.name] * it.count}u }}, /* {sym} */")
    if not program.items:
        lines.append("    { 0xffffu, 0u },")
    lines.append("};")
    lines.append(f"const sim_addr_t sim_chart_addr[{max(1, len(program.charts))}] = {{")
    for c in program.charts:
        sym = f"el_c{c.id}_active"
        addr, _size = syms.get(sym, (0xFFFF, 0))
        if sym not in syms:
            missing.append(sym)
        lines.append(f"    {{ 0x{addr:04x}u, {len(c.steps)}u }}, /* {sym} */")
    if not program.charts:
        lines.append("    { 0xffffu, 0u },")
    lines.append("};")
    tick_addr = syms.get("el_avr_sim_tick", (0xFFFF, 0))[0]
    if "el_avr_sim_tick" not in syms:
        missing.append("el_avr_sim_tick")
    if missing:
        raise _error(f"{elf}: symbols the simulator needs are missing: {', '.join(missing)}")
    lines.append(f"const uint16_t sim_tick_addr = 0x{tick_addr:04x}u;")
    # Hardware behind device data.
    hw = []
    for it in program.items:
        if it.device is None:
            continue
        v = views[it.device]
        h = v.hw
        kind, a, b, c = "SIM_HW_NONE", 0, 0, 0
        if v.driver == "analog_in":
            kind, a = "SIM_HW_ADC", h["adc"]
        elif v.driver == "digital_in":
            kind, a, b = "SIM_HW_PIN_IN", ord(h["pin"][1]), int(h["pin"][2])
        elif v.driver == "digital_out":
            kind, a, b = "SIM_HW_PIN_OUT", ord(h["pin"][1]), int(h["pin"][2])
        elif v.driver == "line_camera":
            kind, a, c = "SIM_HW_CAMERA", h["uart"], h["baud"]
        elif v.driver == "encoder":
            kind = "SIM_HW_ENCODER"
            a = ord(h["pin_a"][1]) << 8 | int(h["pin_a"][2])
            b = ord(h["pin_b"][1]) << 8 | int(h["pin_b"][2])
        elif v.driver in ("pwm_out", "motor"):
            kind = "SIM_HW_PWM"
        hw.append(f"    {{ {it.id}u, {kind}, {a}u, {b}u, {c}UL }}, /* {it.name} ({v.driver}) */")
    lines.append(f"const sim_hw_t sim_hw[{max(1, len(hw))}] = {{")
    lines += hw or ["    { 0xffffu, SIM_HW_NONE, 0u, 0u, 0UL },"]
    lines.append("};")
    lines.append(f"const uint16_t sim_hw_count = {len(hw)}u;")
    # Pins to trace: every claimed pin, with what it is.
    pins = []
    for v in views.values():
        h = v.hw
        if v.driver in ("digital_in", "digital_out"):
            pins.append((h["pin"], "SIM_PIN_LEVEL", 0, "", v.path))
        elif v.driver in ("pwm_out", "motor"):
            p = h["pwm"]
            pins.append((p["pin"], "SIM_PIN_PWM", p["timer"], p["channel"], v.path))
            if v.driver == "motor":
                pins.append((h["dir"], "SIM_PIN_LEVEL", 0, "", v.path + " (direction)"))
        elif v.driver == "encoder":
            pins.append((h["pin_a"], "SIM_PIN_LEVEL", 0, "", v.path + " (A)"))
            pins.append((h["pin_b"], "SIM_PIN_LEVEL", 0, "", v.path + " (B)"))
    lines.append(f"const sim_pin_t sim_pins[{max(1, len(pins))}] = {{")
    for pin, kind, timer, ch, what in pins:
        ocr = 0
        tccra = 0
        if kind == "SIM_PIN_PWM":
            wide = timer in mcu.wide_timers
            ocr_name = f"OCR{timer}{ch}L" if wide else f"OCR{timer}{ch}"
            ocr = _io_address(mcu, ocr_name)
            tccra = _io_address(mcu, f"TCCR{timer}A")
        com = {"A": 7, "B": 5, "C": 3}.get(ch, 0)
        lines.append(f"    {{ '{pin[1]}', {pin[2]}u, {kind}, 0x{ocr:04x}u, 0x{tccra:04x}u, {com}u, {_c_str(pin)}, "
                     f"{_c_str(what)} }},")
    if not pins:
        lines.append("    { 0, 0u, SIM_PIN_LEVEL, 0u, 0u, 0u, \"\", \"\" },")
    lines.append("};")
    lines.append(f"const uint16_t sim_pin_count = {len(pins)}u;")
    uarts = sorted(mcu.uart)
    lines.append(f"const char sim_uarts[] = {_c_str(''.join(str(u) for u in uarts))};")
    lines.append(f"const char sim_mcu[] = {_c_str(mcu.name)};")
    lines.append(f"const uint32_t sim_clock_hz = {int(board.raw.get('clock_hz', 16000000))}UL;")
    lines.append(f"const char sim_elf_default[] = {_c_str(str(elf.resolve()))};")
    lines.append(f"const uint32_t sim_nv_size = {mcu.eeprom}UL;")
    lines.append("")
    return "\n".join(lines)


# Data-space addresses of the registers the harness watches (avr-libc's
# io headers; the same on both parts where both have the register).
_IO = {
    "atmega328p": {"TCCR0A": 0x44, "OCR0A": 0x47, "OCR0B": 0x48, "TCCR1A": 0x80, "OCR1AL": 0x88, "OCR1BL": 0x8A,
                   "TCCR2A": 0xB0, "OCR2A": 0xB3, "OCR2B": 0xB4},
    "atmega2560": {"TCCR0A": 0x44, "OCR0A": 0x47, "OCR0B": 0x48, "TCCR1A": 0x80, "OCR1AL": 0x88, "OCR1BL": 0x8A,
                   "OCR1CL": 0x8C, "TCCR2A": 0xB0, "OCR2A": 0xB3, "OCR2B": 0xB4, "TCCR3A": 0x90, "OCR3AL": 0x98,
                   "OCR3BL": 0x9A, "OCR3CL": 0x9C, "TCCR4A": 0xA0, "OCR4AL": 0xA8, "OCR4BL": 0xAA, "OCR4CL": 0xAC,
                   "TCCR5A": 0x120, "OCR5AL": 0x128, "OCR5BL": 0x12A, "OCR5CL": 0x12C},
}


def _io_address(mcu: Mcu, reg: str) -> int:
    return _IO[mcu.name][reg]


def simulation_warnings(program: Program, board: Board) -> list[str]:
    """What simavr 1.6 does not simulate of this build."""
    mcu = selected(board)
    notes = []
    for v in device_views(program, board):
        if v.driver == "encoder" and mcu.name == "atmega2560":
            off = [p for p in (v.hw["pin_a"], v.hw["pin_b"]) if p not in mcu.ext_int and not p.startswith("PB")]
            if off:
                notes.append(f"warning: simavr 1.6 simulates the atmega2560's pin-change interrupts on port B "
                             f"only: encoder '{v.path}' on {', '.join(off)} counts nothing in simulation (on a "
                             f"board it does)")
    return notes


def build_simulator(program: Program, board: Board, out_dir: Path, elf: Path) -> tuple[Path, list[str]]:
    """Compile the simavr harness for this build: NAME-sim beside the ELF;
    returns it and warnings about what the simulation cannot show."""
    spec = board.raw.get("simulator", {})
    cc = spec.get("cc", "gcc")
    if shutil.which(cc) is None:
        raise _error(f"the simulator's C compiler '{cc}' is not installed (Debian package: gcc)")
    pc = subprocess.run(["pkg-config", "--cflags", "--libs", spec.get("pkg_config", "simavr")], capture_output=True,
                        text=True)
    if pc.returncode != 0:
        raise _error(f"libsimavr is not installed (Debian packages: {spec.get('debian_packages', 'libsimavr-dev')}):"
                     f" {pc.stderr.strip()}")
    model_c = out_dir / "sim_model.c"
    text = sim_model_source(program, board, elf)
    if not model_c.exists() or model_c.read_text(encoding="utf-8") != text:
        model_c.write_text(text, encoding="utf-8")
    exe = out_dir / f"{program.name}-sim"
    sources = [board.path / s for s in spec.get("sources", [])] + [model_c]
    host = board.path.parent / "host"
    cmd = [cc, *spec.get("cflags", []), f"-I{board.path / 'sim'}", f"-I{host}", f"-I{runtime_dir()}",
           "-o", str(exe), *map(str, sources), *pc.stdout.split(), *spec.get("ldflags", [])]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise _error(f"building the simulator failed:\n{proc.stdout}{proc.stderr}".rstrip())
    return exe, simulation_warnings(program, board)
