"""Resource claims against a part's tables: the check that every board
with pins runs (docs/boards.md, "MCUs and resources").

A board describes each of its parts in board.toml: the pins a model may
claim, the pins behind each UART, ADC channel, PWM output and bus (I2C,
SPI), the pins that can interrupt, and the pins the board keeps for
itself. Each claim of the model (devices' ``claims``, interfaces' ``on
uartN``) stands for physical pins; a bus's lines are shared by the devices
on it (``i2c[0] addr 0x48``, ``spi[0] cs "PB2"``), a chip select is its
device's own. A resource the part lacks, a pin claimed twice through
different resources, a bus address I2C does not allow, a bus whose module
(one peripheral serving I2C and SPI) another bus of the model uses, or a device whose
driver the board lacks or drives differently (and whose type brings no
handler file for the board) is a problem, and all problems are reported
together, each at its source line.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from ..core.errors import BuildError
from ..ir.program import Device, Program
from . import handlers
from .claims import parse_claim, parse_select

# The 7-bit addresses I2C leaves to devices (0x00..0x07 and 0x78..0x7F are reserved).
I2C_ADDRESSES = range(0x08, 0x78)
_PIN_NAME = re.compile(r"^(.*?)(\d+)$")


@dataclass
class Part:
    """One MCU's resources, as a board's backend reads them from its
    board.toml. Pin names are the part's own (PB5, RC2, ...)."""

    name: str
    pins: list[str]
    uart: dict[int, list[str]]  # UART n -> its pins (RX, TX)
    adc: dict[int, str]  # channel -> pin (or an analog-only pad's name)
    pwm: dict[str, object]  # pin -> what drives it (the board's own data: timer and channel, CCP module)
    interrupt_pins: set[str] = field(default_factory=set)  # pins that can interrupt (encoders)
    unavailable: dict[str, str] = field(default_factory=dict)  # pin -> what the board uses it for
    reserved_pwm: dict[str, str] = field(default_factory=dict)  # pin -> why its PWM is not offered
    network: bool = False  # Modbus TCP needs one
    pwm_source: str = "PWM output"  # what drives a PWM pin, in messages ("timer output", "CCP output")
    no_interrupt: str = "which cannot interrupt"  # why a pin is no encoder pin, in messages
    i2c: dict[int, list[str]] = field(default_factory=dict)  # I2C bus n -> its pins (SDA, SCL)
    spi: dict[int, list[str]] = field(default_factory=dict)  # SPI bus n -> its pins (SCK, MOSI, MISO, SS)
    aliases: dict[str, str] = field(default_factory=dict)  # another name of a pin -> the part's name for it
    # The peripheral behind a bus, when one serves several: ("i2c", 0) -> "MSSP"
    # and ("spi", 0) -> "MSSP" are one module, which a model uses as one of them.
    bus_modules: dict[tuple[str, int], str] = field(default_factory=dict)
    pin_name: str = r"^(.*?)(\d+)$"  # a pin's port and bit, for pin ranges in messages ("P43": r"^(P.)(\d)$")

    @property
    def kinds(self) -> list[str]:
        """The resource kinds this part has, for messages."""
        return ["pin", "pwm", "adc", "uart"] + (["i2c"] if self.i2c else []) + (["spi"] if self.spi else [])

    def own_pin(self, name: object) -> object:
        """The part's own name of a pin a claim names (an alias resolved)."""
        return self.aliases.get(name, name) if isinstance(name, str) else name


@dataclass
class Claim:
    kind: str
    index: object  # str (a pin's name) or int (a UART, an ADC channel, a bus)
    text: str
    owner: str  # "device 'led'" / "interface 'debug'"
    location: str  # file:line or ""
    select: tuple[str, object] | None = None  # a place on a bus: ("addr", 0x48), ("cs", "PB2")

    def where(self) -> str:
        return f"{self.location}: " if self.location else ""


@dataclass
class Resolved:
    """What the claims of one build come to."""

    problems: list[str] = field(default_factory=list)
    uarts: dict[int, dict] = field(default_factory=dict)  # uart -> {"use": ..., "baud": ..., ...}
    physical: dict[str, Claim] = field(default_factory=dict)  # pin -> its first claim
    buses: dict[tuple[str, int], list[Claim]] = field(default_factory=dict)  # ("i2c", 0) -> the devices on it


def interface_location(program: Program, kind: str) -> str:
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


def pin_ranges(pins: list[str], pattern: str = _PIN_NAME.pattern) -> str:
    """PB0..PB5, PC0..PC2, PC4, PC5: pins grouped by their port (``pattern``'s
    first group) and numbered by their bit (its second), each run of three
    or more consecutive bits as one range."""
    groups: dict[str, list[int]] = {}
    for p in pins:
        m = re.match(pattern, p)
        if m:
            groups.setdefault(m.group(1), []).append(int(m.group(2)))
    runs: list[str] = []
    for port, bits in groups.items():
        bits = sorted(set(bits))
        start = prev = bits[0]
        for bit in bits[1:] + [None]:
            if bit is not None and bit == prev + 1:
                prev = bit
                continue
            runs.append(f"{port}{start}..{port}{prev}" if prev > start + 1 else
                        ", ".join(f"{port}{b}" for b in range(start, prev + 1)))
            if bit is not None:
                start = prev = bit
    return ", ".join(runs)


def _physical_pins(board: str, part: Part, claim: Claim, problems: list[str]) -> list[str] | None:
    """The pins behind a claim, or None (a problem was recorded)."""
    kind, name = claim.kind, part.name
    idx = part.own_pin(claim.index) if kind in ("pin", "pwm") else claim.index
    lead = f"{claim.where()}error: {claim.owner} claims {claim.text}, but"
    if kind == "pin":
        if not isinstance(idx, str) or idx not in part.pins:
            why = f"the {name}'s {idx} is {part.unavailable[idx]}" if idx in part.unavailable \
                else f"the {name} has no pin {idx}"
            problems.append(f"{lead} {why}; pins: {pin_ranges(part.pins, part.pin_name)}")
            return None
        return [idx]
    if kind == "pwm":
        offered = ", ".join(sorted(part.pwm))
        if not isinstance(idx, str):
            problems.append(f"{claim.where()}error: {claim.owner} claims {claim.text}: a PWM output is named by "
                            f"its pin, as in pwm[\"{next(iter(part.pwm), 'P0')}\"]")
            return None
        if idx in part.reserved_pwm:
            problems.append(f"{lead} {idx}'s {part.pwm_source} {part.reserved_pwm[idx]}; PWM pins of the {name}: "
                            f"{offered}")
            return None
        if idx not in part.pwm:
            what = f"has no {part.pwm_source}" if idx in part.pins else f"is not a pin of the {name}"
            problems.append(f"{lead} {idx} {what}; PWM pins of the {name}: {offered or 'none'}")
            return None
        return [idx]
    if kind == "adc":
        if not isinstance(idx, int) or idx not in part.adc:
            channels = f"channels 0..{max(part.adc)}" if part.adc else "no ADC"
            problems.append(f"{lead} the {name} has no ADC channel {idx} ({channels})")
            return None
        return [part.adc[idx]]
    if kind == "uart":
        if not isinstance(idx, int) or idx not in part.uart:
            have = ", ".join(f"uart{n}" for n in sorted(part.uart)) or "none"
            problems.append(f"{lead} the {name} has no UART {idx} (it has {have}"
                            f"{' only' if len(part.uart) == 1 else ''})")
            return None
        return list(part.uart[idx])
    if kind in ("i2c", "spi"):
        return _bus_pins(part, claim, lead, problems)
    problems.append(f"{lead} the {board} board has no resource kind '{kind}' (kinds: {', '.join(part.kinds)})")
    return None


def _bus_pins(part: Part, claim: Claim, lead: str, problems: list[str]) -> list[str] | None:
    """The lines of an I2C or SPI bus (shared by the devices on it) and a
    device's chip select, or None (a problem was recorded)."""
    kind, idx, name = claim.kind, claim.index, part.name
    buses = part.i2c if kind == "i2c" else part.spi
    if not isinstance(idx, int) or idx not in buses:
        have = ", ".join(f"{kind}[{n}]" for n in sorted(buses)) or "none"
        problems.append(f"{lead} the {name} has no {kind.upper()} bus {idx} ({kind.upper()} buses: {have})")
        return None
    lines = list(buses[idx])
    how, where = claim.select if claim.select else (None, None)
    if kind == "i2c" and how not in (None, "addr"):
        problems.append(f"{lead} a device on an I2C bus is named by its address: i2c[{idx}] addr 0x48")
        return None
    if kind == "i2c" and how == "addr" and where not in I2C_ADDRESSES:
        problems.append(f"{lead} I2C leaves addresses 0x08..0x77 to devices (7 bits; the others are reserved)")
        return None
    if kind == "spi" and how not in (None, "cs"):
        problems.append(f"{lead} a device on an SPI bus is named by its chip-select pin: spi[{idx}] cs \"PB2\"")
        return None
    if kind == "spi" and how == "cs":
        where = part.own_pin(where)
        if not isinstance(where, str) or where not in part.pins:
            problems.append(f"{lead} its chip select {where} is not a pin of the {name}; pins: "
                            f"{pin_ranges(part.pins)}")
            return None
        if where in lines[:3]:
            problems.append(f"{lead} {where} is the bus's {('SCK', 'MOSI', 'MISO')[lines.index(where)]}: a chip "
                            f"select is a pin of its own{f' (or the bus SS, {lines[3]})' if len(lines) > 3 else ''}")
            return None
        if where not in lines:
            lines.append(where)
    return lines


def _shared_line(part: Part, claim: Claim, pin: str) -> tuple | None:
    """The bus whose line ``pin`` is for this claim (devices on one bus
    share its lines), or None for a pin the claim holds alone (a chip
    select other than the bus's own SS pin)."""
    buses = {"i2c": part.i2c, "spi": part.spi}.get(claim.kind)
    if buses is None or pin not in buses.get(claim.index, ()):
        return None
    return (claim.kind, claim.index)


def _module_taken(part: Part, claim: Claim, modules: dict[str, Claim], problems: list[str]) -> bool:
    """Whether the claim's bus is on a module (part.bus_modules) that an
    earlier claim uses as another bus (a problem naming both is recorded)."""
    if claim.kind not in ("i2c", "spi"):
        return False
    module = part.bus_modules.get((claim.kind, claim.index))
    if module is None:
        return False
    first = modules.setdefault(module, claim)
    if (first.kind, first.index) == (claim.kind, claim.index):
        return False
    problems.append(f"{claim.where()}error: {claim.owner} claims {claim.text}, but the {part.name}'s "
                    f"{first.kind}[{first.index}] and {claim.kind}[{claim.index}] are one {module}, which "
                    f"{first.owner}{f' ({first.location})' if first.location else ''} uses as {first.text}: "
                    f"a model uses the {module} as one bus, {first.kind}[{first.index}] or "
                    f"{claim.kind}[{claim.index}]")
    return True


def resolve(program: Program, board: str, part: Part, drivers: dict[str, dict]) -> Resolved:
    """Check every claim and device of the program against the part and
    the board's drivers (board.toml ``[drivers.NAME]``: ``claims`` in order,
    ``data`` in order, ``interrupt_pins``, ``baud`` of a driver that owns a
    UART)."""
    res = Resolved()
    claims: list[Claim] = []
    for dev in program.devices:
        for text in dev.claims:
            parsed = parse_claim(text)
            if parsed is None:
                res.problems.append(f"{dev.location}: error: device '{dev.path}' claims {text}, which the {board} "
                                    f"board cannot read")
                continue
            claims.append(Claim(parsed[0], parsed[1], text, f"device '{dev.path}'", dev.location,
                                parse_select(text)))
    for iface in program.interfaces:
        loc = interface_location(program, iface.kind)
        if iface.kind == "modbus-tcp" and not part.network:
            res.problems.append(f"{loc + ': ' if loc else ''}error: the Modbus TCP interface needs a network, and "
                                f"the {board} board has none: use 'modbus rtu on uartN'")
            continue
        parsed = parse_claim(iface.resource) if iface.resource is not None else None
        if parsed is not None:
            claims.append(Claim(parsed[0], parsed[1], iface.resource, f"interface '{iface.kind.replace('-', ' ')}'",
                                loc))
    shared: dict[str, tuple | None] = {}  # pin -> the bus whose line it is
    modules: dict[str, Claim] = {}  # a module serving several buses -> the first claim of one of them
    for claim in claims:
        if _module_taken(part, claim, modules, res.problems):
            continue
        pins = _physical_pins(board, part, claim, res.problems)
        if pins is not None and claim.kind in ("i2c", "spi"):
            res.buses.setdefault((claim.kind, claim.index), []).append(claim)
        for pin in pins or []:
            first = res.physical.get(pin)
            line = _shared_line(part, claim, pin)
            if first is None:
                res.physical[pin] = claim
                shared[pin] = line
            elif line is not None and shared.get(pin) == line:
                continue  # one more device on the bus
            elif first.text != claim.text:
                res.problems.append(
                    f"{claim.where()}error: pin {pin} is claimed twice on the {part.name}: as {claim.text} by "
                    f"{claim.owner} and as {first.text} by {first.owner}"
                    + (f" ({first.location})" if first.location else "")
                    + "; each pin has one owner: choose another pin, channel or UART")
    for dev in program.devices:
        lacking = handlers.lacking(dev, board)
        if lacking is not None and dev.driver not in drivers:
            res.problems.append(lacking)
        elif handlers.handler_file(dev, board) is None:
            _check_driver(program, board, part, drivers, dev, res.problems)
    for iface in program.interfaces:
        parsed = parse_claim(iface.resource) if iface.resource is not None else None
        if iface.kind in ("debug", "modbus-rtu") and parsed and parsed[0] == "uart" and parsed[1] in part.uart:
            res.uarts[parsed[1]] = {"use": iface.kind, **iface.settings}
    for dev in program.devices:  # devices that own a UART (a camera module's link)
        model = handlers.handler_file(dev, board) is not None
        spec = drivers.get(dev.driver) if not model else {}
        for text in dev.claims if spec is not None else ():
            parsed = parse_claim(text)
            if parsed and parsed[0] == "uart" and parsed[1] in part.uart:
                res.uarts[parsed[1]] = {"use": "device" if model else dev.driver,
                                        "baud": int(spec.get("baud", 115200)), "device": dev.path}
    return res


def _check_driver(program: Program, board: str, part: Part, drivers: dict[str, dict], dev: Device,
                  problems: list[str]) -> None:
    spec = drivers.get(dev.driver)
    if spec is None:
        problems.append(
            f"{dev.location}: error: device '{dev.path}' needs the driver '{dev.driver}', which the {board} board "
            f"does not have (drivers: {', '.join(sorted(drivers))}); add boards/{board}/drivers/el_drv_{dev.driver}.h "
            f"and its [drivers.{dev.driver}] entry in boards/{board}/board.toml (docs/boards.md, 'Adding a driver')")
        return
    parsed = [parse_claim(c) for c in dev.claims]
    kinds = [p[0] if p else "?" for p in parsed]
    if kinds != list(spec.get("claims", [])):
        problems.append(f"{dev.location}: error: device '{dev.path}': the {board} driver '{dev.driver}' takes the "
                        f"claims {', '.join(k + '[...]' for k in spec.get('claims', [])) or 'none'} in this order, "
                        f"not {', '.join(dev.claims) or 'none'}")
        return
    data = [f"{'out' if program.items[i].kind == 'dev_out' else 'in'} {program.items[i].type.name}" for i in dev.items]
    rates = bool(spec.get("rates"))  # the driver takes data with a rate (records of several values)
    if data != list(spec.get("data", [])) or (not rates and any(program.items[i].count != 1 for i in dev.items)):
        problems.append(f"{dev.location}: error: device '{dev.path}': the {board} driver '{dev.driver}' drives the "
                        f"data {', '.join(spec.get('data', [])) or 'none'}{'' if rates else ' (one value each)'}, "
                        f"not {', '.join(data) or 'none'}")
        return
    if spec.get("interrupt_pins"):
        for kind, pin in parsed:
            pin = part.own_pin(pin)
            if kind == "pin" and pin in part.pins and pin not in part.interrupt_pins:
                problems.append(f"{dev.location}: error: device '{dev.path}' ({dev.driver}) needs an interrupt on "
                                f"{pin}, {part.no_interrupt} on the {part.name}; pins that can: "
                                f"{pin_ranges(sorted(part.interrupt_pins), part.pin_name) or 'none'}")


def check(program: Program, board: str, part: Part, drivers: dict[str, dict],
          more: Callable[[Program, Resolved], list[str]] | None = None) -> Resolved:
    """:func:`resolve`, raising BuildError with every problem if any; ``more``
    adds a board's own problems (file:line: error: ...) to the same report."""
    res = resolve(program, board, part, drivers)
    if more is not None:
        res.problems += more(program, res)
    if res.problems:
        raise problems_error(f"the {board} board with the {part.name}", res.problems)
    return res


_POSITION = re.compile(r"^(?P<file>.+?):(?P<line>\d+)(?::(?P<column>\d+))?: ")


def by_position(problems: list[str]) -> list[str]:
    """Problems sorted by the position they begin with (``file:line[:col]:``),
    as every error of a run is (docs/language.md, "Errors"); those without a
    position come last, in their order."""
    def key(problem: str) -> tuple:
        """(no position?, file, line, column) of a problem."""
        m = _POSITION.match(problem)
        if m is None:
            return (1, "", 0, 0)
        return (0, m.group("file"), int(m.group("line")), int(m.group("column") or 0))

    return sorted(problems, key=key)


def problems_error(what: str, problems: list[str]) -> BuildError:
    """The error of a model that does not fit ``what`` (a board, with its
    part): the count, then every problem sorted by position."""
    count = len(problems)
    return BuildError(f"the model does not fit {what} ({count} problem{'s' if count != 1 else ''}):\n"
                      + "\n".join(by_position(problems)))
