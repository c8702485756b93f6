"""The checker's distribution rules: nodes, links, placement, channels over
links, exports; each error's position and the ends it names."""

from __future__ import annotations

import pytest

from easylab.pipeline import check_file
from distribution_testlib import ROBOT, position, variant


def diagnostics(text: str) -> list[tuple[int, int, str, str | None]]:
    result = check_file("/tmp/arm.elab", text=text)
    return [(d.span.line, d.span.column, d.message, d.hint) for d in result.diagnostics.sorted()]


def only_error(text: str) -> tuple[int, int, str, str | None]:
    found = diagnostics(text)
    assert len(found) == 1, found
    return found[0]


def test_the_robot_checks_and_keeps_its_placement():
    result = check_file("/tmp/arm.elab", text=ROBOT)
    assert result.model is not None, result.report()
    m = result.model
    assert {n: (i.board, i.mcu) for n, i in m.nodes.items()} == {
        "pc": ("host", None), "j1": ("avr", "atmega328p"), "j2": ("avr", "atmega328p")}
    assert m.task_nodes == {"plan": "pc", "c1": "j1", "c2": "j2"}
    assert m.device_nodes == {"m1": "j1", "m2": "j2", "e1": "j1"}
    bus = m.links["bus"]
    assert bus.settings == {"baud": 115200, "parity": "even", "round": 20000, "turnaround": 1000, "jitter": 0}
    assert [(x.node.name, x.role, x.unit, str(x.uart) if x.uart else None) for x in bus.members] == [
        ("pc", "master", None, None), ("j1", "slave", 2, "uart[0]"), ("j2", "slave", 3, "uart[0]")]
    assert m.links["lan"].settings["domain"] == 7
    assert {c.name: c.link.name for c in m.channels.values()} == {"goal1": "bus", "goal2": "bus", "pos1": "bus"}
    assert [(e.target.name, e.link.name, e.node.name) for e in m.exports] == [("pos1", "lan", "pc")]


def test_the_same_pins_on_two_nodes_are_two_resources():
    # m1 and m2 claim PD6 and PD7 each, on different boards: no conflict
    assert diagnostics(ROBOT) == []


def test_the_same_pin_twice_on_one_node_is_still_an_error():
    text = variant('device m2: Motor(pwm = "PD6", dir = "PD7") on j2', 'device m2: Motor(pwm = "PD6", dir = "PD7") on j1')
    text = variant("g.y -> m2.speed", "g.y -> m1.speed", text)
    found = diagnostics(text)
    assert any("pwm[\"PD6\"] is claimed by device 'm2' and by device 'm1'" in d[2] for d in found), found


def test_a_channel_between_nodes_without_a_link_names_both_ends():
    text = variant("channel goal1: int16 delay 2 over bus", "channel goal1: int16 delay 2")
    line, col, message, hint = only_error(text)
    assert (line, col) == position(text, "goal1")
    assert message == ("channel 'goal1' goes from task 'plan' on node 'pc' to task 'c1' on node 'j1' "
                       "but names no link")
    assert hint == "add: over bus"


def test_a_link_that_does_not_reach_a_node_names_it():
    text = variant("    slave j2 on uart0 unit 3\n", "")
    found = diagnostics(text)
    assert (*position(text, "bus\nchannel pos1"), "channel 'goal2' goes from task 'plan' on node 'pc' to task 'c2' on node 'j2' over link "
                    "'bus', which does not reach node 'j2'",
            "add node 'j2' to link 'bus', or choose another link") in found


def test_a_channel_within_one_node_needs_no_link():
    text = variant("task c2 on j2 period", "task c2 on pc period")
    text = variant('device m2: Motor(pwm = "PD6", dir = "PD7") on j2', 'device m2: Motor(pwm = "PD6", dir = "PD7") on pc',
                   text)
    found = diagnostics(text)
    assert any(d[2].startswith("channel 'goal2' goes from task 'plan' on node 'pc' to task 'c2' on node 'pc': "
                               "both ends are on one node") for d in found), found


def test_every_task_and_device_is_on_a_node():
    text = variant("task c1 on j1 period", "task c1 period")
    line, col, message, hint = only_error(text)
    assert (line, col, message) == (*position(text, "c1 period"), "task 'c1' is on no node: a model with nodes places every task and device")


def test_an_unknown_node_is_reported_with_a_suggestion():
    text = variant("task c1 on j1 period", "task c1 on j1x period")
    line, col, message, hint = only_error(text)
    assert (line, col, message, hint) == (*position(text, "j1x"), "unknown node 'j1x'", "did you mean 'j1'?")


def test_a_var_used_on_two_nodes_is_an_error():
    text = variant("dataflow J2 {\n    g = Gain<int16>(k = 1000)\n    goal2 -> g.x",
                   "dataflow J2 {\n    g = Gain<int16>(k = 1000)\n    s = Cast<int32, int16>()\n"
                   "    seen -> s.x\n    s.y -> m2.speed\n    goal2 -> g.x", ROBOT)
    text = variant("    g.y -> m2.speed\n", "", text)
    found = diagnostics(text)
    assert any(d[2] == "var 'seen' is on node 'pc' but used here on node 'j2'" for d in found), found


def test_a_device_used_on_another_node_is_an_error():
    text = variant("    g.y -> m2.speed\n", "    g.y -> m2.speed\n    e1 -> seen2\n")
    text = variant("var seen: int32\n", "var seen: int32\nvar seen2: int32\n", text)
    found = diagnostics(text)
    assert any(d[2] == "device datum 'e1.count' is on node 'j1' but used here on node 'j2'" for d in found), found


@pytest.mark.parametrize("old, new, message", [
    ("    master pc\n", "", "Modbus link 'bus' needs exactly one master, not 0"),
    ("slave j2 on uart0 unit 3", "slave j2 on uart0 unit 2", "unit id 2 is used twice on link 'bus'"),
    ("slave j2 on uart0 unit 3", "slave j2 unit 3", "slave 'j2' of link 'bus' needs the UART it is on: 'on uart0'"),
    ("slave j2 on uart0 unit 3", "slave j2 on adc0 unit 3", "a Modbus link runs on a UART, not on 'adc[0]'"),
    (" round 20 ms", "", "Modbus link 'bus' has no round period"),
    (" round 20 ms", " round 20", "the round is a 'time': write a duration such as '20 ms'"),
    ("turnaround 1 ms", "turnaround 1.5 us", "the turnaround is a non-negative whole number of microseconds"),
    ("slave j1 on uart0 unit 2", "slave j1 on uart0", "slave 'j1' of link 'bus' has no unit id"),
    ("peer pc", "peer pc on uart1", "a DDS peer runs on its node's network, not 'on' a resource"),
    ("domain 7", "domain 300", "the domain 300 is outside 0..232"),
    ("baud 115200", "baud 100", "the baud 100 is outside 300..4000000"),
    ("baud 115200", "domain 3", "'domain' is not a setting of link 'bus'"),
    ("peer pc", "master pc", "a DDS link has no 'master'"),
    ("export pos1 over lan", "export pos1 over bus", "link 'bus' is a Modbus bus: exports go over a DDS link"),
    ("export pos1 over lan", "export goal1 over lan",
     "'goal1' is on node 'j1', which is no peer of DDS link 'lan'"),
    ("node j2 board avr", "node j1 board avr", "'j1' is already declared as a node"),
])
def test_link_errors(old, new, message):
    found = diagnostics(variant(old, new))
    assert message in [d[2] for d in found], found


def test_interfaces_wait_for_their_nodes():
    found = diagnostics(ROBOT + "debug on uart0\n")
    assert [d[2] for d in found] == ["a model with nodes has no model-wide interface: each node's debug and "
                                     "service interfaces are not placed yet (docs/distribution.md)"]


def test_a_model_without_nodes_cannot_use_links():
    text = "model m\nimport std\nchannel c: int16 over bus\n"
    found = diagnostics(text)
    assert (*position(text, "over"), "channel 'c' goes over a link, but the model has no nodes", None) in found


def test_a_device_on_the_uart_of_a_link_names_the_link():
    text = variant('device e1: Encoder(pin_a = "PD2", pin_b = "PD4") on j1',
                   'device e1: Encoder(pin_a = "PD2", pin_b = "PD4") on j1\ndevice cam: LineCam() on j1')
    text = variant("var seen: int32\n", "var seen: int32\ndevice type LineCam() {\n    claims uart[0]\n"
                   "    out offset: int16\n    driver \"line_camera\"\n}\n", text)
    found = diagnostics(text)
    assert [d[2] for d in found] == ["resource uart[0] is claimed by device 'cam' and by link 'bus'"]


def test_a_device_on_a_node_declares_its_safe_values_after_the_node():
    """`device d: T(...) on NODE safe datum = value`: both the placement and
    the safe value are kept (the two optional parts in their order)."""
    text = ROBOT
    line = next(ln for ln in text.splitlines() if ln.startswith("device m1:"))
    text = text.replace(line, line + " safe speed = 7")
    result = check_file("/tmp/arm.elab", text=text)
    assert result.model is not None, result.report()
    assert result.model.device_nodes["m1"] == "j1"
    datum = next(d for path, d in result.model.device_data.items() if str(path).endswith("m1.speed"))
    assert datum.safe == 7
