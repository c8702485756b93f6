"""The f16 board's part (board.toml's [mcu.*]) and the settings the backend
computes for it: the LET tick's reload timer, UART1's baud rate divisors
(docs/boards.md, "The F16 board")."""

from __future__ import annotations

from dataclasses import dataclass, field

from easylab.board.resources import Part
from easylab.core.errors import BuildError

# Reload timer 0's count clock: the machine clock divided by 2, 8 or 32
# (TMCSR's CSL 0, 1, 2); it counts reload + 1 clocks per period.
TIMER_DIVIDERS = {2: 0, 8: 1, 32: 2}
TIMER_COUNTS_MAX = 65536
# UART1's dedicated baud rate generator: clock / div / (208 << cs).
UART_DIVS = range(1, 9)
UART_CS = range(0, 4)
UART_BASE = 208
BAUD_TOLERANCE = 0.02


@dataclass
class Mcu:
    """One part of board.toml."""

    name: str
    title: str
    cpu: str  # fcc907s -cpu
    flash: int
    flash_start: int
    ram: int
    ram_start: int
    clock_hz: int
    crystal_hz: int
    pll: int
    pins: list[str]
    uart: dict[int, list[str]]
    driven_uarts: list[int]
    adc: dict[int, str]
    pwm: dict[str, int]  # pin -> PPG channel
    ext_int: dict[str, int]  # pin -> INTn
    vectors: dict[str, int]
    unavailable: dict[str, str] = field(default_factory=dict)

    def part(self) -> Part:
        """The resources for the shared claim check."""
        return Part(self.name, self.pins, self.uart, self.adc, dict(self.pwm), set(self.ext_int), self.unavailable,
                    {}, network=False, pwm_source="PPG output", no_interrupt="which is no external interrupt (INTn)",
                    pin_name=r"^(P[0-9A])([0-7])$")

    def int_vector(self, intn: int) -> int:
        """The vector of INTn (INT0/1, INT2/3, ... share one each)."""
        pair = 2 * (intn // 2)
        return self.vectors[f"int{pair}{pair + 1}"]


def read_mcus(table: dict) -> dict[str, Mcu]:
    """board.toml's [mcu.*] tables by name."""
    return {name: Mcu(name, m.get("title", name), m["cpu"], int(m["flash"]), int(m["flash_start"]), int(m["ram"]),
                      int(m["ram_start"]), int(m["clock_hz"]), int(m["crystal_hz"]), int(m["pll"]), list(m["pins"]),
                      {int(k): list(v) for k, v in m["uart"].items()}, [int(u) for u in m["driven_uarts"]],
                      {int(k): str(v) for k, v in m["adc"].items()}, {k: int(v) for k, v in m["pwm"].items()},
                      {k: int(v) for k, v in m["int"].items()}, {k: int(v) for k, v in m["vectors"].items()},
                      dict(m.get("unavailable", {})))
            for name, m in table.items()}


@dataclass(frozen=True)
class TickTimer:
    """The LET tick on a periodic timer: an interrupt every ``period``
    counts of clock / ``divider`` (count clock = the fine clock), ``isrs``
    interrupts per tick."""

    divider: int
    period: int
    isrs: int
    exact: bool
    drift_ppm: float


def tick_timer(tick_us: int, clock_hz: int, dividers: tuple[int, ...], counts_max: int,
               shortest_us: int) -> TickTimer:
    """Timer settings whose product is the tick exactly when some exist:
    the fewest interrupts per tick, then the finest count clock, with no
    interrupt closer than ``shortest_us``. Otherwise the nearest setting,
    with its drift against the clock."""
    best = None
    for divider in dividers:
        if (tick_us * clock_hz) % (1_000_000 * divider):
            continue
        counts = tick_us * clock_hz // (1_000_000 * divider)
        isrs = max(1, -(-counts // counts_max))
        while isrs <= 65535 and counts % isrs:
            isrs += 1
        period = counts // isrs if isrs <= 65535 else 0
        if period and period * divider * 1_000_000 >= shortest_us * clock_hz:
            key = (isrs, divider)
            if best is None or key < best[0]:
                best = (key, TickTimer(divider, period, isrs, True, 0.0))
    if best is not None:
        return best[1]
    want = tick_us * clock_hz / 1_000_000
    divider = dividers[-1]
    isrs = max(1, -(-int(want / divider) // counts_max))
    period = max(1, min(counts_max, round(want / divider / isrs)))
    return TickTimer(divider, period, isrs, False, (period * divider * isrs - want) / want * 1e6)


def fine_clock_khz(clock_hz: int, divider: int) -> int:
    """Fine-clock units (counts of clock / divider) per ms, rounded up."""
    return -(-clock_hz // (divider * 1000))


@dataclass(frozen=True)
class UartRate:
    div: int
    cs: int
    baud: float  # the rate the part gives
    error: float  # relative to the one asked


def uart1_rates(clock_hz: int) -> list[UartRate]:
    """Every rate UART1's generator makes from the machine clock."""
    return sorted((UartRate(d, cs, clock_hz / d / (UART_BASE << cs), 0.0) for d in UART_DIVS for cs in UART_CS),
                  key=lambda r: -r.baud)


# The standard rates a serial link is asked for.
STANDARD_BAUDS = (300, 600, 1200, 2400, 4800, 9600, 14400, 19200, 38400, 57600, 76800, 115200, 230400, 250000,
                  500000, 1000000)


def usable_rates(mcu: Mcu) -> list[tuple[int, UartRate]]:
    """(baud, divisors) of every standard rate UART1 makes within 2 %."""
    rates = uart1_rates(mcu.clock_hz)
    out = []
    for baud in STANDARD_BAUDS:
        best = min(rates, key=lambda r: (abs(r.baud - baud), r.div))
        if abs(best.baud / baud - 1.0) <= BAUD_TOLERANCE:
            out.append((baud, UartRate(best.div, best.cs, best.baud, best.baud / baud - 1.0)))
    return out


def uart1_rate(mcu: Mcu, baud: int, what: str) -> UartRate:
    """The divisors nearest to ``baud``; BuildError when more than 2 % off,
    listing the standard rates that work."""
    rates = uart1_rates(mcu.clock_hz)
    best = min(rates, key=lambda r: (abs(r.baud - baud), r.div))
    error = best.baud / baud - 1.0
    if abs(error) > BAUD_TOLERANCE:
        usable = [b for b, _ in usable_rates(mcu)]
        raise BuildError(f"{what}: {baud} baud is {error * 100:+.1f} % off on UART1 of the {mcu.name} (its nearest "
                         f"rate from the {mcu.clock_hz // 1_000_000} MHz machine clock is {best.baud:.0f}); rates "
                         f"within 2 %: {', '.join(map(str, usable))}")
    return UartRate(best.div, best.cs, best.baud, error)
