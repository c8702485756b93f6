"""The C view of a program's status items (docs/ir.md, "Status items"):
the uint16 counter that holds each, in a firmware or in local execution's
interfaces library."""

from __future__ import annotations

from dataclasses import dataclass

from ..ir.program import Item, Program


@dataclass
class StatusView:
    """A status item (docs/ir.md, "Status items") as C: the uint16 counter
    that holds it and its declaration."""

    item: Item
    c_name: str  # an lvalue of type uint16_t
    c_extern: str

    @property
    def addr(self) -> str:
        return f"&{self.c_name}"


# The counter a firmware keeps for each fault (model.c.j2, link.c.j2).
_FIRMWARE_COUNTERS = {"tardy": ("el_ch{subject}_tardy", "extern uint16_t el_ch{subject}_tardy;"),
                      "unanswered": ("el_round_silent[{subject}]", "extern uint16_t el_round_silent[];")}


def status_views(program: Program, library: bool) -> list[StatusView]:
    """The status items' counters: in local execution's interfaces library
    ``el_interp_status[id]`` (the interpreter keeps them), in a firmware
    the counter its link code keeps."""
    views = []
    for st in program.status:
        if library:
            views.append(StatusView(st, f"el_interp_status[{st.id}]", "extern uint16_t el_interp_status[];"))
        elif st.fault in _FIRMWARE_COUNTERS:
            name, decl = _FIRMWARE_COUNTERS[st.fault]
            views.append(StatusView(st, name.format(subject=st.subject), decl.format(subject=st.subject)))
        else:
            raise ValueError(f"status item {st.name}: counted by the host of remote execution, not by a firmware")
    return views
