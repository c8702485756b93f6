"""Status items: the read-only fault counters of the links a program runs
over (docs/ir.md, "Status items").

They are derived here, from the program's structure, and nowhere else:

- **remote execution** (``remote_program``): one ``remote.<task>.overruns``
  per task that reads a device or drives a device ``in`` datum (the
  proxy's tasks, in task order: the proxy counts their overruns);
- **a node of a distributed model** (``node_status``, called by the
  split): one ``link.<channel>.tardy`` per channel whose producer is on
  another node (the consumer's release counts it), and on the master of a
  Modbus link one ``link.<node>.unanswered`` per slave, in slot order.

Every status item is a uint16 that saturates at 65535 (``STATUS_MAX``),
read-only on the debug and service interfaces, never traced as a column. A
program without links has none: its maps, dump and id are unchanged.
"""

from __future__ import annotations

from dataclasses import replace

from ..core import types as T
from .program import Program, Status, Task

STATUS_MAX = 0xFFFF  # the counters' width: uint16, saturating


def _status(index: int, name: str, fault: str, subject: int, location: str) -> Status:
    return Status(index, name, "status", T.UINT16, 1, 0, location, service="ro", fault=fault, subject=subject)


def device_tasks(program: Program) -> list[tuple[Task, list[int], list[int]]]:
    """The tasks that touch devices, in task order, with the devices they
    read (ids) and the device ``in`` data they write (item ids): the tasks
    a remote-execution proxy runs (docs/remote.md, "The device model")."""
    reads_of: dict[int, list[int]] = {}
    for device in program.devices:
        for task in device.read_by:
            reads_of.setdefault(task, []).append(device.id)
    found = []
    for task in program.tasks:
        writes = sorted(i for i in task.writes if program.items[i].kind == "dev_in")
        reads = sorted(reads_of.get(task.id, []))
        if reads or writes:
            found.append((task, reads, writes))
    return found


def remote_program(program: Program) -> Program:
    """``program`` as remote execution's host runs it: with one overrun
    counter per proxy task (``remote.<task>.overruns``, subject: the task
    id). It keeps the model's program id: the application is the same, and
    the status items come after every id of its maps."""
    status = [_status(k, f"remote.{task.name}.overruns", "overruns", task.id, task.location)
              for k, (task, _, _) in enumerate(device_tasks(program))]
    return replace(program, status=status) if status else program


def node_status(program: Program, inputs: list[tuple[int, str]], slaves: list[str], location: str) -> list[Status]:
    """A node's status items: ``inputs`` are (channel id, name) of the
    channels that cross a link to this node (tardy counters), ``slaves``
    the slaves of the Modbus link this node is master of, in slot order
    (unanswered counters, located in the model's file ``location``)."""
    status = [_status(0, f"link.{name}.tardy", "tardy", channel, program.channels[channel].location)
              for channel, name in inputs]
    status += [_status(0, f"link.{node}.unanswered", "unanswered", slot, location)
               for slot, node in enumerate(slaves)]
    return [replace(s, id=k) for k, s in enumerate(status)]
