"""The link budget of remote execution (docs/remote.md, "Timing"): at each
release instant the UP frame and the DOWN frame must cross the link before
the earliest deadline of the tasks released then. Computed before a
real-time run, which is refused with the numbers when it cannot fit."""

from __future__ import annotations

from dataclasses import dataclass

from ..ir.program import Program
from .device_model import DeviceModel
from .protocol import wire_bytes

BITS_PER_BYTE = 10  # 8N1: a start and a stop bit
DEFAULT_BAUD = 115200  # the link's baud rate unless `easylab proxy --baud` and `easylab remote --baud` say otherwise


@dataclass
class InstantBudget:
    """One release instant: its frames' bytes on the wire, their time at the
    baud rate, and the deadline they must meet (µs)."""

    tick: int
    tasks: list[str]
    up_bytes: int
    down_bytes: int
    wire_us: float
    deadline_us: int

    @property
    def fits(self) -> bool:
        return self.wire_us <= self.deadline_us

    def explain(self, baud: int) -> str:
        return (f"{', '.join(self.tasks)} at tick {self.tick}: {self.up_bytes + self.down_bytes} bytes per instant "
                f"(UP {self.up_bytes}, DOWN {self.down_bytes}) take {self.wire_us / 1000:.3f} ms at {baud} baud; "
                f"the deadline is {self.deadline_us / 1000:g} ms")


def link_budget(program: Program, model: DeviceModel, baud: int) -> list[InstantBudget]:
    """The budget of every release instant of the device model's table."""
    budgets = []
    for instant in model.instants:
        if not instant.release:
            continue
        up = wire_bytes(model.up_payload(instant.release))
        down = wire_bytes(model.down_payload(instant.release))
        deadline = min(model.tasks[k].deadline for k in instant.release) * model.tick_us
        budgets.append(InstantBudget(instant.tick, [program.tasks[model.tasks[k].task].name for k in instant.release],
                                     up, down, (up + down) * BITS_PER_BYTE * 1e6 / baud, deadline))
    return budgets


def refusal(program: Program, model: DeviceModel, baud: int) -> str | None:
    """Why a real-time run at ``baud`` cannot fit (the worst instant, with
    its numbers), or None when every instant fits."""
    over = [b for b in link_budget(program, model, baud) if not b.fits]
    if not over:
        return None
    worst = max(over, key=lambda b: b.wire_us / b.deadline_us)
    return (f"the link cannot carry the device data in time: {worst.explain(baud)} "
            f"({len(over)} instant{'s' if len(over) > 1 else ''} over; a faster link or longer deadlines)")
