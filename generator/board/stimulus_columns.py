"""Which stimulus columns something reads, per board: the one rule both
stimulus readers apply (boards/host/README.md, "Stimulus CSV"; the C reader
boards/host/host_stimulus.c through the table ``el_host_unread`` emitted
here, easylab run's generator/interp/stimulus.py by calling
:func:`unread_items`), and the "did you mean" both give for an unknown
column.

A param's or var's column is always read (the stimulus writes the item).
A device `out` datum's column is read when

- a task reads its device (``Device.read_by``): a device no task reads is
  never read, on any board; and
- the run puts the value where the device's read finds it. The host board,
  local and remote execution and the F16 proxy simulate every device (a
  device with host handlers starts its read from the stimulus's value); a
  simulator harness (AVR in simavr, PIC18 in gpsim) only drives the
  hardware of its ``sim_hw`` table's rows of :data:`DRIVEN_KINDS`: an ADC
  channel, an input pin, a line camera's UART, an encoder's pins, a sensor
  chip on an I2C bus, the chip model a device type brings (`sim "FILE.c"`).
  A device whose data reach no such hardware (one with the model's own
  handlers and no chip model, a driver the harness has no hardware for)
  reads nothing of the stimulus.
"""

from __future__ import annotations

from ..codegen.c_syntax import c_string
from ..ir.program import Program
from .handlers import handler_file

# The sim_hw kinds (sim/sim_harness.h) whose hardware a harness
# drives from a device `out` datum's stimulus value.
DRIVEN_KINDS = frozenset({"SIM_HW_ADC", "SIM_HW_PIN_IN", "SIM_HW_CAMERA", "SIM_HW_ENCODER",
                          "SIM_HW_CHIP"})

# Names longer than this are not compared for "did you mean" (the C reader
# keeps its edit-distance rows in fixed arrays of this size plus one).
SUGGEST_MAX = 64


def unread_items(program: Program, driven: set[int] | None = None, simulator: str = "",
                 board: str = "") -> dict[int, str]:
    """item id -> why nothing reads a stimulus column of it, for every item
    a stimulus may name (device `out` data, params, vars) that nothing
    reads. ``driven`` is None where every device is simulated (host board,
    local and remote execution, the F16 proxy), else the item ids of the
    device data whose hardware the ``simulator`` harness of ``board``
    drives."""
    unread = {}
    for it in program.items:
        if it.kind != "dev_out":
            continue
        dev = program.devices[it.device]
        if not dev.read_by:
            unread[it.id] = f"no task reads device {dev.path}"
        elif driven is not None and it.id not in driven:
            own = "the model's handlers, " if handler_file(dev, board) is not None else ""
            unread[it.id] = (f"the {simulator} simulator has no hardware behind device {dev.path} ({own}driver "
                             f"{dev.driver})")
    return unread


def driven_items(rows: list[tuple[int, str]]) -> set[int]:
    """The item ids of a harness's ``sim_hw`` rows (item, kind) whose
    hardware it drives."""
    return {item for item, kind in rows if kind in DRIVEN_KINDS}


def unread_table(program: Program, driven: set[int] | None = None, simulator: str = "",
                 board: str = "") -> list[str]:
    """``el_host_unread`` and its count (boards/host/host_internal.h): the
    items of :func:`unread_items` with the reason the C reader prints."""
    rows = [f"    {{ {item}u, {c_string(why)} }}, /* {program.items[item].name} */"
            for item, why in sorted(unread_items(program, driven, simulator, board).items())]
    return [f"const uint16_t el_host_unread_count = {len(rows)}u;",
            f"const el_host_unread_t el_host_unread[{max(len(rows), 1)}] = {{"] \
        + (rows or ["    { 0xffffu, \"\" },"]) + ["};", ""]


def edit_distance(a: bytes, b: bytes) -> int:
    """The optimal string alignment distance of two byte strings (inserts,
    deletes, substitutions and swaps of neighbours), as host_stimulus.c's
    edit_distance computes it."""
    prev2: list[int] = []
    prev = list(range(len(b) + 1))
    for i in range(1, len(a) + 1):
        row = [i] + [0] * len(b)
        for j in range(1, len(b) + 1):
            cost = 0 if a[i - 1] == b[j - 1] else 1
            row[j] = min(prev[j] + 1, row[j - 1] + 1, prev[j - 1] + cost)
            if i > 1 and j > 1 and a[i - 1] == b[j - 2] and a[i - 2] == b[j - 1]:
                row[j] = min(row[j], prev2[j - 2] + 1)
        prev2, prev = prev, row
    return prev[len(b)]


def suggestion(name: bytes, candidates: list[bytes]) -> bytes | None:
    """The candidate closest to ``name`` (the first of the closest), if at
    most a third of ``name``'s length (at least 1) of edits away; none for
    names longer than SUGGEST_MAX bytes."""
    if not name or len(name) > SUGGEST_MAX:
        return None
    best, best_d = None, max(1, len(name) // 3) + 1
    for cand in candidates:
        if len(cand) > SUGGEST_MAX:
            continue
        d = edit_distance(name, cand)
        if d < best_d:
            best, best_d = cand, d
    return best
