"""The `state` fields of the devices that run the model's own handler
files on a board (docs/language.md, "Device handlers from the model's
folder"): their C type and where they live, for the handlers' code
(board/handlers.py), the debug tables and the trace (read-only items
``DEVICE.FIELD``)."""

from __future__ import annotations

from ..core import types as T
from ..ir.program import Device, Program


def state_type_lines(device: Device) -> list[str]:
    """The C type of a device's state, ``el_mdev<id>_state_t``: its
    ``state`` fields in declaration order (the debug tables and the host
    board's tables declare it again, the same, to reach the firmware's
    ``el_mdev<id>_state``)."""
    fields = [f"{t.c_name} {name}{f'[{size}]' if size else ''};" for name, t, size in device.states]
    return (["typedef struct {"] + [f"    {f}" for f in fields or ["uint8_t el_unused; /* C99 wants a member */"]]
            + [f"}} el_mdev{device.id}_state_t;"])


def state_devices(program: Program, board: str) -> list[Device]:
    """The devices that keep a state on ``board``: those running a handler
    file of the model's there whose type declares ``state`` fields."""
    return [d for d in program.devices if d.states and d.handlers.get(board) is not None]


def state_items(program: Program, board: str) -> list[tuple[Device, str, T.ValueType, int, str]]:
    """(device, field, type, count, C address expression) of every device
    state field on ``board``, named ``DEVICE.FIELD`` (``dev.reads``)
    in the debug map and the trace."""
    out = []
    for dev in state_devices(program, board):
        for name, t, size in dev.states:
            where = f"el_mdev{dev.id}_state.{name}"
            out.append((dev, name, t, size or 1, where if size else f"&{where}"))
    return out
