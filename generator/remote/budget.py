"""The link budget of remote execution (docs/remote.md, "Link budget"): at
each release instant the proxy's CPU must do the instant's work (its
devices, its frames) and the UP frame and the DOWN frame must cross the
link before the earliest deadline of the tasks released then, and the CPU
must be done before the next release instant. Computed before a real-time
run, which is refused with the numbers when it cannot fit.

The CPU's share comes from the board's measured coefficients (board.toml,
[remote_cpu]: cycles per release instant, per further task, per device by
its driver, and the share of its clock's interrupts; measured in the
board's simulator by tools/proxy_cpu.py). A board without them (the host
board: a PC; the F16 board, never run) counts the wire alone."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from ..ir.program import Program
from .device_model import DeviceModel
from .protocol import wire_bytes

BITS_PER_BYTE = 10  # 8N1: a start and a stop bit
DEFAULT_BAUD = 115200  # the link's baud rate unless `easylab proxy --baud` and `easylab remote --baud` say otherwise


@dataclass
class CpuShare:
    """The proxy's CPU at one release instant: its cycles by what takes
    them (the instant's fixed work, each further task, each device), the
    share of every cycle its clock's interrupts take, and the time (µs)."""

    cycles: int
    parts: list[tuple[str, int]]  # (what, cycles)
    clock_share: float
    cycle_hz: int
    part: str  # "PIC18F4520"
    clock_hz: int

    @property
    def us(self) -> float:
        return self.cycles * 1e6 / (self.cycle_hz * (1.0 - self.clock_share))

    def explain(self) -> str:
        def ms(cycles: int) -> str:
            return f"{cycles * 1e3 / self.cycle_hz:.2f} ms"
        parts = ", ".join(f"{what} {ms(c)}" for what, c in self.parts)
        return (f"the {self.part} proxy needs {self.us / 1000:.2f} ms of CPU per instant ({parts}; "
                f"its clock's interrupts {100 * self.clock_share:.1f} % of the CPU) at {self.clock_hz / 1e6:g} MHz")


@dataclass
class InstantBudget:
    """One release instant: its frames' bytes on the wire, their time at the
    baud rate, the proxy's CPU (None: not counted on this board), the
    deadline they must meet and the time until the next release instant
    (µs)."""

    tick: int
    tasks: list[str]
    up_bytes: int
    down_bytes: int
    wire_us: float
    deadline_us: int
    cpu: CpuShare | None = None
    gap_us: int = 0

    @property
    def need_us(self) -> float:
        """The CPU's time and the wire's, one after the other: the UP frame
        leaves once the CPU built it and the DOWN frame's last byte is
        decoded after it came; the CPU's work while bytes are on the wire
        (the UART's interrupts) is not counted on to overlap."""
        return self.wire_us + (self.cpu.us if self.cpu else 0.0)

    @property
    def fits(self) -> bool:
        return self.need_us <= self.deadline_us and (self.cpu is None or self.cpu.us <= self.gap_us)

    @property
    def shortest_period_ms(self) -> int:
        """The shortest period in whole ms (with its deadline) at which this
        instant would fit, its work the same."""
        return max(1, math.ceil(max(self.need_us, self.cpu.us if self.cpu else 0.0) / 1000))

    def explain(self, baud: int) -> str:
        return (f"{', '.join(self.tasks)} at tick {self.tick}: {self.up_bytes + self.down_bytes} bytes per instant "
                f"(UP {self.up_bytes}, DOWN {self.down_bytes}) take {self.wire_us / 1000:.3f} ms at {baud} baud; "
                f"the deadline is {self.deadline_us / 1000:g} ms")


@dataclass
class CpuCoefficients:
    """A board's [remote_cpu] (board.toml) at one baud rate: cycles of its
    CPU per release instant (one task reading one device), per further task
    released then, per device by its driver, as measured with the link at
    ``baud``; the share of the cycles its clock's interrupts take at a 1 ms
    tick; the CPU's cycles per second."""

    cycle_hz: int
    instant: int
    task: int
    clock_share: float
    drivers: dict[str, int] = field(default_factory=dict)
    baud: int = DEFAULT_BAUD

    def driver(self, name: str) -> int:
        """A driver's cycles; one not measured counts as the dearest measured."""
        return self.drivers.get(name, max(self.drivers.values(), default=0))


CALIBRATION_PREFIX = "at_"  # [remote_cpu.at_115200]: the figures measured at 115200 baud


def cpu_coefficients(board, baud: int = DEFAULT_BAUD) -> CpuCoefficients | None:
    """The configured ``board``'s coefficients for a link at ``baud``, or
    None when it has none. A board measures them at a few rates
    ([remote_cpu.at_BAUD]); the link's code costs less per instant the
    faster its bytes come (several per pass through it), so the figures of
    the fastest rate not above ``baud`` count (those of the slowest for a
    slower link: below it every byte comes alone, as at that rate)."""
    table = board.description.table("remote_cpu") if board is not None else {}
    rates = {int(k[len(CALIBRATION_PREFIX):]): v for k, v in table.items()
             if k.startswith(CALIBRATION_PREFIX) and isinstance(v, dict)}
    if not rates:
        return None
    at = max((r for r in rates if r <= baud), default=min(rates))
    chosen = rates[at]
    return CpuCoefficients(int(table["cycle_hz"]), int(chosen["instant"]), int(chosen["task"]),
                           float(table["clock_share"]), {k: int(v) for k, v in chosen.get("drivers", {}).items()},
                           at)


def cpu_share(model: DeviceModel, coefficients: CpuCoefficients, released: list[int], part: str,
              clock_hz: int) -> CpuShare:
    """The proxy's CPU for a release instant of the proxy tasks ``released``:
    the instant, each further task, each device read by them or driven by
    them (its driver's read or write, its data's bytes in the frames)."""
    parts = [("instant", coefficients.instant)]
    if len(released) > 1:
        parts.append((f"{len(released) - 1} more task{'s' if len(released) > 2 else ''}",
                      coefficients.task * (len(released) - 1)))
    read = {d for k in released for d in model.tasks[k].reads}
    written = {i for k in released for i in model.tasks[k].writes}
    for d in model.devices:
        if d.id in read or any(i in written for i in d.items):
            parts.append((f"{d.path} ({d.driver})", coefficients.driver(d.driver)))
    # The clock's interrupts come once per tick at most every 1 ms: a
    # shorter tick brings them more often.
    share = coefficients.clock_share * max(1.0, 1000 / model.tick_us)
    return CpuShare(sum(c for _, c in parts), parts, min(share, 0.99), coefficients.cycle_hz, part, clock_hz)


def _part_name(board) -> str:
    """The MCU as its maker writes it ("ATmega328P": board.toml's title up
    to its parenthesis), else the board's name."""
    if board is None:
        return ""
    title = getattr(board.part, "title", None) or board.mcu or board.name
    return title.split(" (")[0]


def link_budget(program: Program, model: DeviceModel, baud: int, board=None) -> list[InstantBudget]:
    """The budget of every release instant of the device model's table, the
    proxy's CPU counted when ``board`` (configured: its MCU chosen) has
    coefficients."""
    coefficients = cpu_coefficients(board, baud)
    part = _part_name(board)
    clock_hz = int(board.description.raw.get("clock_hz", 0)) if board is not None else 0
    releases = [i for i in model.instants if i.release]
    budgets = []
    for n, instant in enumerate(releases):
        up = wire_bytes(model.up_payload(instant.release))
        down = wire_bytes(model.down_payload(instant.release))
        deadline = min(model.tasks[k].deadline for k in instant.release) * model.tick_us
        following = releases[(n + 1) % len(releases)].tick + (model.hyperperiod if n + 1 == len(releases) else 0)
        cpu = (cpu_share(model, coefficients, instant.release, part, clock_hz)
               if coefficients is not None else None)
        budgets.append(InstantBudget(instant.tick, [program.tasks[model.tasks[k].task].name for k in instant.release],
                                     up, down, (up + down) * BITS_PER_BYTE * 1e6 / baud, deadline, cpu,
                                     (following - instant.tick) * model.tick_us))
    return budgets


def refusal(program: Program, model: DeviceModel, baud: int, board=None) -> str | None:
    """Why a real-time run at ``baud`` cannot fit (the worst instant, with
    its numbers), or None when every instant fits; the proxy's CPU counted
    when ``board`` (configured) has coefficients. The one rule that
    `easylab remote` and `easylab proxy` apply."""
    over = [b for b in link_budget(program, model, baud, board) if not b.fits]
    if not over:
        return None
    count = f"{len(over)} instant{'s' if len(over) > 1 else ''} over"
    worst = max(over, key=lambda b: max(b.need_us / b.deadline_us, (b.cpu.us / b.gap_us) if b.cpu else 0.0))
    if worst.cpu is None:
        return (f"the link cannot carry the device data in time: {worst.explain(baud)} "
                f"({count}; a faster link or longer deadlines)")
    tasks = ", ".join(worst.tasks)
    if worst.need_us > worst.deadline_us:
        late = (f"with its frames' {worst.up_bytes + worst.down_bytes} bytes on the wire "
                f"({worst.wire_us / 1000:.3f} ms at {baud} baud) {worst.need_us / 1000:.2f} ms, but the deadline is "
                f"{worst.deadline_us / 1000:g} ms")
    else:
        late = f"but the next release instant comes {worst.gap_us / 1000:g} ms after it"
    return (f"the proxy cannot keep up: {tasks} at tick {worst.tick}: {worst.cpu.explain()}; {late} "
            f"({count}; a period and deadline of at least {worst.shortest_period_ms} ms fit, or fewer devices "
            f"per task)")
