"""A small robot model for the distribution tests, with the pieces the
tests change: a planner PC and two joints on a Modbus RTU bus."""

from __future__ import annotations

ROBOT = """\
model arm
import std
node pc board host
node j1 board avr mcu atmega328p
node j2 board avr mcu atmega328p
link bus modbus rtu baud 115200 round 20 ms turnaround 1 ms {
    master pc
    slave j1 on uart0 unit 2
    slave j2 on uart0 unit 3
}
link lan dds domain 7 {
    peer pc
}
device m1: Motor(pwm = "PD6", dir = "PD7") on j1
device m2: Motor(pwm = "PD6", dir = "PD7") on j2
device e1: Encoder(pin_a = "PD2", pin_b = "PD4") on j1
channel goal1: int16 delay 2 over bus
channel goal2: int16 delay 2 over bus
channel pos1: int32 delay 2 over bus
var seen: int32
export pos1 over lan
dataflow Plan {
    r = Ramp<int16>(slope = 1)
    r.y -> goal1
    r.y -> goal2
    pos1 -> seen
}
dataflow J1 {
    g = Gain<int16>(k = 1000)
    goal1 -> g.x
    g.y -> m1.speed
    e1 -> pos1
}
dataflow J2 {
    g = Gain<int16>(k = 1000)
    goal2 -> g.x
    g.y -> m2.speed
}
task plan on pc period 20 ms { run Plan }
task c1 on j1 period 20 ms { run J1 }
task c2 on j2 period 20 ms offset 5 ms deadline 5 ms { run J2 }
"""


def variant(old: str, new: str, text: str = ROBOT) -> str:
    """The robot model with one piece of text replaced (which must be there)."""
    assert old in text, old
    return text.replace(old, new, 1)


def position(text: str, fragment: str, skip: int = 0) -> tuple[int, int]:
    """(line, column), 1-based, of ``skip`` characters into ``fragment``'s first occurrence."""
    at = text.index(fragment) + skip
    line = text.count("\n", 0, at) + 1
    return line, at - (text.rfind("\n", 0, at) + 1) + 1
